"""Planar rigid-body kinematics (paper Sec. 3.1).

Each body i has the three coordinates q^i = [x^i, y^i, θ^i]: its centre of mass R^i and its angle.
A point with body-frame coordinates ū has the global position R + A(θ)ū (Eq. 15) and the velocity
Ṙ + θ̇ A_θ ū (Eq. 16); its acceleration is R̈ + θ̈ A_θ ū − θ̇² A ū (Eq. 17). In 2D, A_θ ū is the
vector A ū turned by +90°.
"""
from __future__ import annotations

import numpy as np

from inerter.elements import kinematics

DOF_PER_BODY = 3

# the kernels' laws, run uncompiled
_planar_point = kinematics.planar_point.py_func
_planar_point_force = kinematics.planar_point_force.py_func


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
        H_b = [I, A_θ ū] (Eq. 16) and acc = −θ̇² A ū (Eq. 17), from kinematics.planar_point."""
        if self.body < 0:
            z = np.zeros(2)
            return self.local, z, None, z
        k = self.qi
        rx, ry, vx, vy, ax, ay, cx, cy = _planar_point(q[k], q[k + 1], q[k + 2], v[k], v[k + 1], v[k + 2],
                                                       self._lx, self._ly)
        H = np.array(((1.0, 0.0, -ay), (0.0, 1.0, ax)))         # A_θ ū = (−ay, ax)
        return np.array((rx, ry)), np.array((vx, vy)), H, np.array((cx, cy))

    def generalised_force(self, q, F):
        """Hᵀ F of a force F at the point, over the body's three coordinates (kinematics.planar_point_force)."""
        return _planar_point_force(q[self.qi + 2], self._lx, self._ly, F[0], F[1])


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
