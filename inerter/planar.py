"""Planar rigid-body kinematics (paper Sec. 3.1).

Each body i has the three coordinates q^i = [x^i, y^i, θ^i]: its centre of mass R^i and its angle.
A point with body-frame coordinates ū has the global position R + A(θ)ū (Eq. 15) and the velocity
Ṙ + θ̇ A_θ ū (Eq. 16); its acceleration is R̈ + θ̈ A_θ ū − θ̇² A ū (Eq. 17). In 2D, A_θ ū is the
vector A ū turned by +90°.
"""
from __future__ import annotations

import math

import numpy as np

DOF_PER_BODY = 3


class PointKinematics:
    """Where a point sits: a body index (−1 for the ground) and its body-frame coordinates."""

    __slots__ = ("body", "local", "dofs", "_lx", "_ly")

    def __init__(self, body: int, local):
        self.body = body
        self.local = np.asarray(local, dtype=float)
        self._lx, self._ly = float(self.local[0]), float(self.local[1])
        self.dofs = np.arange(DOF_PER_BODY * body, DOF_PER_BODY * body + DOF_PER_BODY) if body >= 0 else None

    def evaluate(self, q, v):
        """Return (r, ṙ, u, u_θ, ω): position, velocity, A ū, A_θ ū and the body's angular velocity."""
        if self.body < 0:
            z = np.zeros(2)
            return self.local, z, z, z, 0.0
        k = DOF_PER_BODY * self.body
        th = q[k + 2]
        c, s = math.cos(th), math.sin(th)
        ux, uy = self._lx, self._ly
        ax, ay = c * ux - s * uy, s * ux + c * uy               # A ū
        w = float(v[k + 2])
        u = np.array((ax, ay))
        u_t = np.array((-ay, ax))                                # A_θ ū
        r = np.array((q[k] + ax, q[k + 1] + ay))
        rdot = np.array((v[k] - w * ay, v[k + 1] + w * ax))
        return r, rdot, u, u_t, w


class PointPair:
    """The relative kinematics of two points a → b: r = r_b − r_a (Eq. 15), ṙ = H q̇ (Eq. 18),
    r̈ = H q̈ + a_n (Eq. 19), with H and a_n over the two bodies' coordinates only."""

    __slots__ = ("a", "b", "dofs", "_cols")

    def __init__(self, a: PointKinematics, b: PointKinematics):
        self.a, self.b = a, b
        parts = [p.dofs for p in (a, b) if p.dofs is not None]
        self.dofs = np.concatenate(parts) if parts else np.zeros(0, dtype=int)

    def evaluate(self, q, v):
        """Return (r, ṙ, a_n, H) where H has one column per entry of `self.dofs`."""
        ra, va, ua, uta, wa = self.a.evaluate(q, v)
        rb, vb, ub, utb, wb = self.b.evaluate(q, v)
        r = rb - ra
        rdot = vb - va
        a_n = wa * wa * ua - wb * wb * ub                        # Eq. (19): (θ̇ⁱ)² Aⁱūⁱ − (θ̇ʲ)² Aʲūʲ
        cols = []
        if self.a.dofs is not None:                               # H = [−I, −A_θⁱūⁱ, I, A_θʲūʲ]
            cols.append(np.array([[-1.0, 0.0, -uta[0]], [0.0, -1.0, -uta[1]]]))
        if self.b.dofs is not None:
            cols.append(np.array([[1.0, 0.0, utb[0]], [0.0, 1.0, utb[1]]]))
        H = np.hstack(cols)
        return r, rdot, a_n, H
