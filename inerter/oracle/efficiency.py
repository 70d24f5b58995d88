"""The reference oracle's screw efficiency: the definition of :mod:`inerter.elements.device`'s
docstring ("Efficiency"), written here from it (not read from the element laws), and the
resolution of its mode by trying every sign assignment.

A ball screw passes η_f of the terminals' force to the flywheel when they drive it and η_b of the
flywheel's to the terminals when it drives them. With the flywheel's kinetic energy kept at
T = ½ b ẋ² (ẋ the screw's stroke rate: L̇ rigid, the inerter's own u̇ = L̇ − ṡ in series), the force
on the stroke is b_eff ẍ instead of b ẍ,

    b_eff = b (1 + λ(τ)),   λ(τ) = τ ((α+β)/2 + τ (α−β)/2),   α = 1/η_f − 1,   β = 1 − η_b,
    τ = σ tanh(ẋ/v_s)  (v_s > 0),   τ = σ sgn(ẋ), +1 at ẋ = 0  (v_s = 0),   σ = sign(ẍ),

so λ(1) = α (b/η_f, driven) and λ(−1) = −β (b η_b, back-driving). In the oracle's Lagrange
equations this is the ideal inerter's term (from T, Eq. 9: b ∇ẋ ∇ẋᵀ in the mass matrix, −b ẍ₀ ∇ẋ
in the forces, ẍ₀ = ẍ at zero accelerations) scaled by 1 + λ(τ); the power the screw loses, the
terminals' b_eff ẍ ẋ less dT/dt = b ẍ ẋ, is b λ(τ) ẍ ẋ ≥ 0 (sign λ = sign τ = sign(ẋ ẍ)).

The mode σ = sign(ẍ) holds the unknown accelerations. The oracle resolves it by trying every
assignment σ ∈ {±1}ⁿ of its n efficient elements (:func:`resolve`): it solves its system once per
assignment and keeps the one whose solved ẍ agree in sign with it (where ẍ = 0 either sign does:
b_eff ẍ = 0 in both, and the solutions are the same). One exists and it is unique: with
y_i = b_eff,i ẍ_i, a strictly increasing function of ẍ_i (b_eff > 0 in either mode), the system
reads ẍ(y) + S y = r with S = Gᵀ K₀⁻¹ G positive semidefinite (G the elements' gradients, K₀ the
system without them), a strictly monotone equation in y. The engine's way (solve in the stored
mode, flip where the solved sign disagrees, solve again) is not used here.
"""
from __future__ import annotations

import itertools
import math

import numpy as np

from inerter.common.errors import SimulationError

#: Round-off of a solved stroke acceleration, relative to the sum of its terms' sizes (Σ|∇ẋ_i q̈_i|
#: and the rest): an ẍ that small is 0, a tie agreeing with either mode (measured: 1e-16 of them
#: inside a backlash gap, where the series force and the drag are 0 and so ẍ = 0 exactly). The
#: solve's own round-off grows with the condition of its system, hence the margin; either mode's
#: force b_eff ẍ there is within 1e-10 of the terms' size of the other's.
ROUND_OFF = 1e-10

#: Two solutions of a tie (ẍ = 0 to ROUND_OFF, either mode) differ by the round-off of two systems
#: with different b_eff (measured 1.2e-13 of the largest component); a second solution of the
#: equations, were there one, would differ at order one. Relative to each part's largest component.
SAME = 1e-9

#: The largest number of efficient elements whose 2ⁿ assignments the oracle tries.
MAX_ELEMENTS = 8


class ScrewEfficiency:
    """η_f, η_b and v_s of one device (``device.efficiency``) and the law of the module docstring."""

    def __init__(self, values: dict):
        self.forward = float(values["forward"])
        self.backward = float(values["backward"])
        self.scale = float(values.get("velocity_scale") or 0.0)
        self.alpha = 1.0 / self.forward - 1.0
        self.beta = 1.0 - self.backward

    def direction(self, mode: float, rate: float) -> float:
        """τ: σ tanh(ẋ/v_s), or σ sgn(ẋ) with +1 at ẋ = 0 where v_s = 0."""
        if self.scale > 0.0:
            return mode * math.tanh(rate / self.scale)
        if rate == 0.0:
            return 1.0
        return mode * math.copysign(1.0, rate)

    def excess(self, tau: float) -> float:
        """λ(τ) = τ ((α+β)/2 + τ (α−β)/2): b_eff = b (1 + λ)."""
        return tau * (0.5 * (self.alpha + self.beta) + tau * 0.5 * (self.alpha - self.beta))

    def factor(self, mode: float, rate: float) -> float:
        """b_eff / b = 1 + λ(τ) in mode σ at the stroke rate ẋ."""
        return 1.0 + self.excess(self.direction(mode, rate))

    def loss(self, b: float, mode: float, rate: float, accel: float) -> float:
        """The power the screw loses, b λ(τ) ẍ ẋ (W)."""
        return b * self.excess(self.direction(mode, rate)) * accel * rate


def _agreement(modes, accels):
    """The largest disagreement of the solved ẍ with the assignment, −σ ẍ relative to the terms of
    each (accels: (ẍ, scale) per element): ≤ ROUND_OFF where every sign agrees (a tie, ẍ = 0 to
    round-off, agreeing with both)."""
    worst = -math.inf
    for mode, (x, scale) in zip(modes, accels):
        worst = max(worst, -mode * x / scale if scale > 0.0 else 0.0)
    return worst


def resolve(elements, solve, names, t):
    """Try every assignment of the modes σ ∈ {±1}ⁿ of `elements` (each with a settable ``mode``):
    `solve()` solves the system in the modes set and returns (solution, [(ẍ, scale) per element]).
    Returns the solution of the assignment whose signs agree, leaving its modes set: at a tie the
    first in the order tried, σ = +1 (driven, as at rest) before −1. Where none agrees, or two agree
    whose solutions differ (beyond ROUND_OFF), a SimulationError naming `names` (neither happens but
    by a fault: the assignment is unique, module docstring)."""
    if len(elements) > MAX_ELEMENTS:
        raise SimulationError(f"the oracle tries every mode of its screw efficiencies, 2^n solves, and this "
                              f"scene has {len(elements)} (elements {', '.join(names)}): at most {MAX_ELEMENTS}",
                              t)
    tried = []
    for modes in itertools.product((1.0, -1.0), repeat=len(elements)):
        for e, mode in zip(elements, modes):
            e.mode = mode
        solution, accels = solve()
        tried.append((_agreement(modes, accels), modes, solution))
    agree = [x for x in tried if x[0] <= ROUND_OFF]
    if not agree:
        raise SimulationError(f"the oracle finds no modes of the screw efficiencies of {', '.join(names)} that "
                              f"agree with the signs of their solved stroke accelerations", t)
    first = agree[0]
    for other in agree[1:]:
        if not _same(first[2], other[2]):
            raise SimulationError(f"the oracle finds two sets of modes of the screw efficiencies of "
                                  f"{', '.join(names)} that agree with their solutions, and the solutions differ", t)
    for e, mode in zip(elements, first[1]):
        e.mode = mode
    return first[2]


def _same(a, b):
    """Whether two solutions (tuples of arrays) are equal to round-off."""
    for x, y in zip(a, b):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        scale = max(float(np.max(np.abs(x), initial=0.0)), float(np.max(np.abs(y), initial=0.0)), 1e-300)
        if float(np.max(np.abs(x - y), initial=0.0)) > SAME * scale:
            return False
    return True
