"""Force elements of the fast path, each behind one small interface.

An element adds to the system mass matrix M (only the inerter does: M_I of Eq. 33) and to the
generalised force vector Q, and reports its outputs (Modelica names: ``s_rel``, ``v_rel``, ``f`` for
translational elements, tension positive; ``phi_rel``, ``w_rel``, ``tau`` for rotational ones).

Translational elements act along the line between their terminals (uniaxial, Sec. 2.2) and enter
the equations through the generalised force of Eq. (29), Q = −F Hᵀ r̂.
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.errors import MIN_LENGTH, TerminalsMeet  # noqa: F401  (re-exported)
from inerter.model.planar import PointPair

class TranslationalElement:
    """Common geometry of a two-terminal uniaxial element between points a and b."""

    kind = "element"
    coefficient_name = "k"

    def __init__(self, name: str, pair: PointPair, coefficient: float, labels: tuple[str, str]):
        self.name = name
        self.pair = pair
        self.coefficient = float(coefficient)
        self.labels = labels

    def geometry(self, q, v):
        r, rdot, a_n, H = self.pair.evaluate(q, v)
        length = math.sqrt(float(r @ r))
        if not length > MIN_LENGTH:
            raise TerminalsMeet(
                f"element '{self.name}': its terminals {self.labels[0]} and {self.labels[1]} meet "
                f"(distance {length:.3g} m < {MIN_LENGTH:g} m), so its direction is undefined")
        rhat = r / length
        return r, rdot, a_n, H, length, rhat

    def length(self, q):
        return self.geometry(q, np.zeros_like(q))[4]

    def outputs(self, q, v, a):
        """(s_rel, v_rel, f) at accelerations `a`."""
        r, rdot, a_n, H, L, rhat = self.geometry(q, v)
        return L, float(rdot @ rhat), self.force(q, v, a, (r, rdot, a_n, H, L, rhat))

    def add_mass(self, q, v, M, geo=None):
        pass

    def potential(self, q):
        return 0.0

    def kinetic(self, q, v):
        return 0.0


class Spring(TranslationalElement):
    """Linear spring, F = k(L − L0) (Eq. 5)."""

    kind = "spring"

    def __init__(self, name, pair, k, free_length, labels):
        super().__init__(name, pair, k, labels)
        self.free_length = float(free_length)

    def force(self, q, v, a=None, geo=None):
        L = (geo or self.geometry(q, v))[4]
        return self.coefficient * (L - self.free_length)

    def add_force(self, q, v, Q, geo=None):
        geo = geo or self.geometry(q, v)
        H, L, rhat = geo[3], geo[4], geo[5]
        F = self.coefficient * (L - self.free_length)
        Q[self.pair.dofs] -= F * (H.T @ rhat)                      # Eq. (29)

    def potential(self, q):
        return 0.5 * self.coefficient * (self.length(q) - self.free_length) ** 2


class Damper(TranslationalElement):
    """Linear viscous damper, F = c ṙ·r̂ (Eq. 7)."""

    kind = "damper"
    coefficient_name = "c"

    def force(self, q, v, a=None, geo=None):
        geo = geo or self.geometry(q, v)
        return self.coefficient * float(geo[1] @ geo[5])

    def add_force(self, q, v, Q, geo=None):
        geo = geo or self.geometry(q, v)
        H, rhat = geo[3], geo[5]
        F = self.coefficient * float(geo[1] @ rhat)
        Q[self.pair.dofs] -= F * (H.T @ rhat)                      # Eq. (29)


class Inerter(TranslationalElement):
    """Ideal inerter in the augmented form of Eq. (33).

    With the centripetal term (Eq. 9/20): F = b[(H q̈ + a_n)·r̂ + (ṙ·ṙ − (ṙ·r̂)²)/L].
    Without it (Eq. 8): F = b (H q̈ + a_n)·r̂.
    The q̈ part moves to the mass matrix, M_I = b Hᵀ r̂ r̂ᵀ H, the rest to the right side as Q_Iv
    (Eq. 31).
    """

    kind = "inerter"
    coefficient_name = "b"

    def __init__(self, name, pair, b, centripetal: bool, labels):
        super().__init__(name, pair, b, labels)
        self.centripetal = bool(centripetal)

    def _velocity_term(self, geo):
        """The part of F/b not multiplying q̈: r̂·a_n (+ the centripetal term of Eq. 9)."""
        r, rdot, a_n, H, L, rhat = geo
        term = float(a_n @ rhat)
        if self.centripetal:
            along = float(rdot @ rhat)
            term += (float(rdot @ rdot) - along * along) / L     # |ṙ⊥|²/L, Eq. (9)/(20)
        return term

    def add_mass(self, q, v, M, geo=None):
        geo = geo or self.geometry(q, v)
        g = geo[3].T @ geo[5]                                     # Hᵀ r̂
        idx = self.pair.dofs
        M[np.ix_(idx, idx)] += self.coefficient * np.outer(g, g)   # M_I, Eq. (33)

    def add_force(self, q, v, Q, geo=None):
        geo = geo or self.geometry(q, v)
        g = geo[3].T @ geo[5]
        Q[self.pair.dofs] -= self.coefficient * self._velocity_term(geo) * g   # Q_Iv, Eq. (31)

    def force(self, q, v, a, geo=None):
        geo = geo or self.geometry(q, v)
        r, rdot, a_n, H, L, rhat = geo
        return self.coefficient * (float((H @ a[self.pair.dofs]) @ rhat) + self._velocity_term(geo))

    def kinetic(self, q, v):
        geo = self.geometry(q, v)
        return 0.5 * self.coefficient * float(geo[1] @ geo[5]) ** 2   # ½ b L̇²


class RotationalElement:
    """Rotational spring or damper between two bodies' angles (or a body and the ground)."""

    kind = "rotational"

    def __init__(self, name: str, index_a: int, index_b: int, coefficient: float, free_angle: float = 0.0):
        self.name = name
        self.ia, self.ib = index_a, index_b     # coordinate indices of the angles, −1 for the ground
        self.coefficient = float(coefficient)
        self.free_angle = float(free_angle)

    def relative(self, q, v):
        phi = (q[self.ib] if self.ib >= 0 else 0.0) - (q[self.ia] if self.ia >= 0 else 0.0)
        w = (v[self.ib] if self.ib >= 0 else 0.0) - (v[self.ia] if self.ia >= 0 else 0.0)
        return phi, w

    def add_force(self, q, v, Q, geo=None):
        tau = self.torque(q, v)
        if self.ib >= 0:
            Q[self.ib] -= tau
        if self.ia >= 0:
            Q[self.ia] += tau

    def add_mass(self, q, v, M, geo=None):
        pass

    def geometry(self, q, v):
        return None

    def outputs(self, q, v, a):
        phi, w = self.relative(q, v)
        return phi, w, self.torque(q, v)

    def kinetic(self, q, v):
        return 0.0


class RotationalSpring(RotationalElement):
    """τ = k (φ_rel − φ0), restoring."""

    kind = "rotational_spring"

    def torque(self, q, v):
        return self.coefficient * (self.relative(q, v)[0] - self.free_angle)

    def potential(self, q):
        return 0.5 * self.coefficient * (self.relative(q, q * 0)[0] - self.free_angle) ** 2


class RotationalDamper(RotationalElement):
    """τ = d ω_rel."""

    kind = "rotational_damper"

    def torque(self, q, v):
        return self.coefficient * self.relative(q, v)[1]

    def potential(self, q):
        return 0.0


class SpatialRotationalElement:
    """Rotational spring (τ = k(φ − φ0)) or damper (τ = d φ̇) about an axis between two 3D bodies
    (or a body and the ground). φ is the rotation about the axis (fixed in body a; global for the
    ground) measured from the initial relative orientation, so φ(0) = 0; exact while the relative
    rotation is about that axis (as a revolute joint keeps it)."""

    def __init__(self, spec, frame_a, frame_b, q0):
        self.name = spec.name
        self.kind = spec.type
        self.coefficient_name = "k" if spec.type == "rotational_spring" else "d"
        self.coefficient = float(spec.coefficient)
        self.free_angle = float(spec.free_length or 0.0)
        self.fa, self.fb = frame_a, frame_b
        self.axis = np.asarray(spec.axis, dtype=float)
        z = np.zeros(max(frame_a.vi, frame_b.vi) + 6)
        Aa, _ = frame_a.evaluate(q0, z)
        Ab, _ = frame_b.evaluate(q0, z)
        self.rel0 = Aa.T @ Ab

    def geometry(self, q, v):
        Aa, wa = self.fa.evaluate(q, v)
        Ab, wb = self.fb.evaluate(q, v)
        D = (Aa.T @ Ab) @ self.rel0.T                  # rotation since t = 0, in a's frame
        n = self.axis
        s = 0.5 * (n[0] * (D[2, 1] - D[1, 2]) + n[1] * (D[0, 2] - D[2, 0]) + n[2] * (D[1, 0] - D[0, 1]))
        c = 0.5 * (np.trace(D) - n @ D @ n)
        n_w = Aa @ n
        return math.atan2(s, c), float(n_w @ (Ab @ wb - Aa @ wa)), n_w, Aa, Ab

    def torque(self, q, v, geo=None):
        phi, w, *_ = geo or self.geometry(q, v)
        if self.kind == "rotational_spring":
            return self.coefficient * (phi - self.free_angle)
        return self.coefficient * w

    def add_force(self, q, v, Q, geo=None):
        geo = geo or self.geometry(q, v)
        tau = self.torque(q, v, geo)
        _, _, n_w, Aa, Ab = geo
        if self.fb.body >= 0:
            Q[self.fb.vi + 3:self.fb.vi + 6] -= tau * (Ab.T @ n_w)
        if self.fa.body >= 0:
            Q[self.fa.vi + 3:self.fa.vi + 6] += tau * (Aa.T @ n_w)

    def add_mass(self, q, v, M, geo=None):
        pass

    def outputs(self, q, v, a):
        geo = self.geometry(q, v)
        return geo[0], geo[1], self.torque(q, v, geo)

    def kinetic(self, q, v):
        return 0.0

    def potential(self, q):
        if self.kind != "rotational_spring":
            return 0.0
        return 0.5 * self.coefficient * (self.geometry(q, np.zeros(len(q)))[0] - self.free_angle) ** 2
