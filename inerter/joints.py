"""Joint constraints C(q) = 0 with their Jacobian C_q and the right side γ of C_q q̈ = γ (Eq. 26's Q_d).

Each joint reports its rows as (C, C_q over its own coordinates, γ). Formulas follow the standard
planar forms (Nikravesh 1988, Shabana 2009 as cited by the paper).
"""
from __future__ import annotations

import math

import numpy as np

from .planar import PointPair


class Revolute:
    """Pin joint: the two points coincide, C = r_b − r_a = 0 (2 rows).

    C_q = H and γ = −a_n from Eqs. (18–19), since r̈ = H q̈ + a_n = 0.
    """

    kind = "revolute"
    rows = 2

    def __init__(self, name: str, pair: PointPair):
        self.name = name
        self.pair = pair
        self.dofs = pair.dofs

    def evaluate(self, q, v):
        r, rdot, a_n, H = self.pair.evaluate(q, v)
        return r, H, -a_n


class Prismatic:
    """Slider: no relative rotation, and point b stays on the line through point a along `axis`
    (fixed in a's body). Rows: θ_b − θ_a − φ0 = 0 and n·(r_b − r_a) = 0, n = A_a n̄, n̄ ⊥ axis."""

    kind = "prismatic"
    rows = 2

    def __init__(self, name: str, pair: PointPair, axis, angle_index_a: int, angle_index_b: int, phi0: float):
        self.name = name
        self.pair = pair
        self.dofs = pair.dofs
        self.normal = np.array((-axis[1], axis[0]), dtype=float)
        self.phi0 = float(phi0)
        self.ia, self.ib = angle_index_a, angle_index_b

    def evaluate(self, q, v):
        pair = self.pair
        d, ddot, a_n, H = pair.evaluate(q, v)
        has_a = pair.a.dofs is not None
        k = len(self.dofs)
        Cq = np.zeros((2, k))
        # Row 1: relative angle.
        th_a = q[self.ia] if self.ia >= 0 else 0.0
        th_b = q[self.ib] if self.ib >= 0 else 0.0
        c1 = th_b - th_a - self.phi0
        if has_a:
            Cq[0, 2] = -1.0
        if pair.b.dofs is not None:
            Cq[0, k - 1] = 1.0
        # Row 2: n·d with n turning with body a.
        if has_a:
            c, s = math.cos(th_a), math.sin(th_a)
            n = np.array((c * self.normal[0] - s * self.normal[1], s * self.normal[0] + c * self.normal[1]))
            wa = v[self.ia]
        else:
            n, wa = self.normal, 0.0
        n_perp = np.array((-n[1], n[0]))                       # dn/dθ_a
        c2 = float(n @ d)
        Cq[1] = n @ H                                           # ∂(n·d)/∂q through d
        if has_a:
            Cq[1, 2] += float(n_perp @ d)                       # ... and through n
        # C̈ = n·(H q̈ + a_n) + θ̈_a n⊥·d − θ̇_a² n·d + 2 θ̇_a n⊥·ḋ
        gamma2 = -(float(n @ a_n) - wa * wa * c2 + 2.0 * wa * float(n_perp @ ddot))
        return np.array((c1, c2)), Cq, np.array((0.0, gamma2))
