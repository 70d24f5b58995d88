"""The reference oracle's series connection: an inerter device's compliance and backlash, written
from their definitions as one more generalised coordinate of the element (Wang & Su 2008, Veh.
Syst. Dyn. 46(7) 575-595, Sec. 3; the definitions of :mod:`inerter.elements.device`'s docstring,
not its laws).

Terminal a — spring k_c, damper c_c — massless node — inerter b — terminal b. The node's
deflection s (the spring's extension) is a coordinate beside the bodies' q, so the inerter's own
stroke is u(q, s) = L(q) − s. The element's extended Lagrangian and dissipation function are

    T_I = ½ b u̇²,   V = ½ k_c d(s)²,   R = ½ c_c ṡ² + D(u̇),

d = s without backlash; with a gap Δ, d = s − sgn(s) Δ/2 beyond it and no spring inside it
(V = 0, and R's c_c part acts only engaged); D(u̇) the device's friction and channel dissipation
on the inerter's own stroke rate (:class:`~.derivation.OracleDevice`). Lagrange's equations on the
coordinates (q, s), with the velocities (v, ṡ) and u̇ = gᵀv − ṡ (g = ∇L), give the mass block
b γγᵀ, γ = ∂u̇/∂(v, ṡ) = [g; −1], that is [[b g gᵀ, −b g], [−b gᵀ, b]], and the generalised forces
−b ü₀ γ (ü₀ = ü at v̇ = 0, s̈ = 0: q̇ᵀ∇²Lq̇, less |ṙ⊥|²/L under Eq. 8), −∂R/∂(v, ṡ) and
−∂V/∂s: :meth:`~.derivation.OracleElement.extended` writes them on Jets of u over (v, ṡ), and the
oracle's mechanism solves them with the bodies' and the joints' rows in one system
(:meth:`~.mechanism.OracleMechanism.extended_accelerations`).

Backlash's contact is unilateral: the force F = ∂V/∂s + ∂R/∂ṡ through the engaged sides only
pushes them together, so where it would pull them apart (F·d < 0) it is 0, as an end stop's
contact force (Marhefka & Orin 1999); the spring's energy V is then released into nothing (lost).
The dissipated power is what the connection's force does on ṡ less what V stores, (F − ∂V/∂s) ṡ:
c_c ṡ² engaged, −(∂V/∂s) ṡ ≥ 0 while the clip holds.
"""
from __future__ import annotations

import numpy as np

from inerter.oracle.jets import Jet


def _coordinate(x):
    """x as a Jet over itself (gradient 1): derivatives by x read off its gradient."""
    return Jet(float(x), 0.0, 0.0, np.ones(1))


class SeriesConnection:
    """A series spring and damper, with an optional backlash gap (module docstring)."""

    def __init__(self, compliance: dict, gap: float | None):
        self.stiffness = float(compliance["stiffness"])
        self.damping = float(compliance.get("damping") or 0.0)
        self.gap = gap

    def deflection(self, s: Jet):
        """d(s) on the Jet s: s, or s ∓ Δ/2 beyond the gap; None inside it (no spring there)."""
        if self.gap is None:
            return s
        half = 0.5 * self.gap
        if s.v > half:
            return s - half
        if s.v < -half:
            return s + half
        return None

    def potential(self, s: float) -> float:
        """V = ½ k_c d² (J)."""
        d = self.deflection(_coordinate(s))
        return 0.0 if d is None else 0.5 * self.stiffness * (d.v * d.v)

    def force(self, s: float, sdot: float):
        """(F, engaged, ∂V/∂s): the force through the connection F = ∂V/∂s + ∂R/∂ṡ (tension
        positive), clipped to 0 where a backlash contact would pull (F·d < 0), and 1.0 engaged."""
        d = self.deflection(_coordinate(s))
        if d is None:
            return 0.0, 0.0, 0.0
        elastic = (0.5 * self.stiffness * (d * d)).g[0]                     # ∂V/∂s
        w = _coordinate(sdot)
        F = elastic + (0.5 * self.damping * (w * w)).g[0]                   # + ∂R/∂ṡ
        if self.gap is not None and F * d.v < 0.0:      # a contact only pushes the engaged sides together
            return 0.0, 1.0, elastic
        return F, 1.0, elastic

    def loss(self, s: float, sdot: float) -> float:
        """The power the connection dissipates, (F − ∂V/∂s) ṡ (W, ≥ 0)."""
        F, _, elastic = self.force(s, sdot)
        return (F - elastic) * sdot
