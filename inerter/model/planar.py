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

    __slots__ = ("body", "local", "dofs", "qi", "_lx", "_ly")

    def __init__(self, body: int, local, q_index: int | None = None, v_index: int | None = None):
        self.body = body
        self.local = np.asarray(local, dtype=float)
        self._lx, self._ly = float(self.local[0]), float(self.local[1])
        self.qi = DOF_PER_BODY * body if q_index is None else q_index
        start = self.qi if v_index is None else v_index
        self.dofs = np.arange(start, start + DOF_PER_BODY) if body >= 0 else None

    def evaluate(self, q, v):
        """(r, ṙ, H_b, acc): ṙ = H_b q̇_body and r̈ = H_b q̈_body + acc, with
        H_b = [I, A_θ ū] (Eq. 16) and acc = −θ̇² A ū (Eq. 17)."""
        if self.body < 0:
            z = np.zeros(2)
            return self.local, z, None, z
        k = self.qi
        th = q[k + 2]
        c, s = math.cos(th), math.sin(th)
        ux, uy = self._lx, self._ly
        ax, ay = c * ux - s * uy, s * ux + c * uy               # A ū
        w = float(v[k + 2])
        r = np.array((q[k] + ax, q[k + 1] + ay))
        rdot = np.array((v[k] - w * ay, v[k + 1] + w * ax))
        H = np.array(((1.0, 0.0, -ay), (0.0, 1.0, ax)))         # A_θ ū = (−ay, ax)
        acc = np.array((-w * w * ax, -w * w * ay))
        return r, rdot, H, acc


class PointPair:
    """The relative kinematics of two points a → b: r = r_b − r_a (Eq. 15), ṙ = H q̇ (Eq. 18),
    r̈ = H q̈ + a_n (Eq. 19), with H and a_n over the two bodies' velocity coordinates only.
    Works for planar and spatial points alike."""

    __slots__ = ("a", "b", "dofs")

    def __init__(self, a, b):
        self.a, self.b = a, b
        parts = [p.dofs for p in (a, b) if p.dofs is not None]
        self.dofs = np.concatenate(parts) if parts else np.zeros(0, dtype=int)

    def evaluate(self, q, v):
        """Return (r, ṙ, a_n, H) where H has one column per entry of `self.dofs`."""
        ra, va, Ha, acc_a = self.a.evaluate(q, v)
        rb, vb, Hb, acc_b = self.b.evaluate(q, v)
        blocks = []
        if Ha is not None:
            blocks.append(-Ha)                                    # H = [−Hⁱ, Hʲ] (Eq. 18, 22)
        if Hb is not None:
            blocks.append(Hb)
        # a_n = (θ̇ⁱ)² Aⁱūⁱ − (θ̇ʲ)² Aʲūʲ in 2D (Eq. 19), its 3D form Eq. (25)
        return rb - ra, vb - va, acc_b - acc_a, np.hstack(blocks)
