"""Spatial rigid-body kinematics (paper Sec. 3.2, Appendix B).

A 3D body has the position R of its centre of mass and an orientation; its velocity coordinates
are (Ṙ, ω) with ω the angular velocity in the body frame, so that its mass matrix is the constant
diag(m I, J) and only the gyroscopic term −ω × Jω appears in the forces.

A point with body coordinates ū is at r = R + A ū (Eq. 15); ṙ = Ṙ − A ũ ω (the 3D H of Eq. 22,
written with body-frame ω instead of Euler-angle rates); r̈ = R̈ − A ũ ω̇ + A(ω × (ω × ū)), whose
last term is the 3D a_n of Eq. (25).

Orientations:
* ``quaternion`` (default): a unit quaternion p = (w, x, y, z); ṗ = ½ p ⊗ (0, ω). No singularity.
* ``euler_zxz``: the paper's Euler angles (φ, θ, ψ), A = R_z(φ) R_x(θ) R_z(ψ) (Eq. B.1). Their
  rates follow from ω through the inverse of G (Eq. 23), which does not exist where sin θ = 0
  (gimbal lock): there the solver stops with an error naming the body and the time.
"""
from __future__ import annotations

import numpy as np

from inerter.common.rotations import (  # noqa: F401  (re-exported for the model's users)
    EULER_SINGULARITY, cross, skew, quat_matrix, quat_rate, quat_from_matrix, axis_angle_matrix, euler_matrix, euler_from_matrix, euler_rate)
from inerter.elements import kinematics


class Orientation:
    """How a 3D body's orientation is stored: ``quaternion`` (4 numbers) or ``euler_zxz`` (3)."""

    def __init__(self, kind: str):
        self.kind = kind
        self.size = 4 if kind == "quaternion" else 3

    def matrix(self, o):
        return quat_matrix(o) if self.kind == "quaternion" else euler_matrix(o)

    def from_matrix(self, A):
        return quat_from_matrix(A) if self.kind == "quaternion" else euler_from_matrix(A)

    def rate(self, o, omega, body_name="", t=None):
        return quat_rate(o, omega) if self.kind == "quaternion" else euler_rate(o, omega, body_name, t)

    def retract(self, o, dtheta):
        """The orientation turned by the small body-frame rotation vector dθ."""
        A = self.matrix(o) @ axis_angle_matrix(dtheta, np.linalg.norm(dtheta)) if np.any(dtheta) else self.matrix(o)
        new = self.from_matrix(A)
        if self.kind == "quaternion" and float(np.dot(new, o)) < 0:
            new = -new          # stay on the same sheet as before
        return new

    def normalise(self, o):
        return o / np.linalg.norm(o) if self.kind == "quaternion" else o


class RotationCache:
    """The last rotation matrix computed for one body: points of a body share it, so that an
    evaluation of the mechanism computes each body's A once (also as the row-major 9-tuple of
    floats the laws take)."""

    __slots__ = ("key", "A", "A9")

    def __init__(self):
        self.key, self.A, self.A9 = None, None, None

    def matrix(self, orientation, o):
        key = o.tobytes()
        if key != self.key:
            self.key, self.A = key, orientation.matrix(o)
            self.A9 = tuple(self.A.ravel().tolist())
        return self.A

    def matrix9(self, orientation, o):
        self.matrix(orientation, o)
        return self.A9


# the kernels' laws, run uncompiled
_spatial_point = kinematics.spatial_point.py_func
_turn_row = kinematics.spatial_turn_row.py_func
_spatial_point_force = kinematics.spatial_point_force.py_func


class SpatialPoint:
    """A point on a 3D body (or the ground, body −1): r, ṙ, its H block and acceleration term."""

    __slots__ = ("body", "local", "dofs", "qi", "orientation", "_l", "cache")

    def __init__(self, body: int, local, q_index: int, v_index: int, orientation: Orientation | None,
                 cache: RotationCache | None = None):
        self.body = body
        self.local = np.asarray(local, dtype=float)
        self._l = tuple(self.local.tolist())
        self.qi = q_index
        self.orientation = orientation
        self.dofs = np.arange(v_index, v_index + 6) if body >= 0 else None
        self.cache = cache or RotationCache()

    def rotation9(self, q):
        """The body's rotation as a row-major 9-tuple (cached per body and state)."""
        k, o = self.qi, self.orientation
        return self.cache.matrix9(o, q[k + 3:k + 3 + o.size])

    def evaluate(self, q, v):
        """(r, ṙ, H_b, acc): ṙ = H_b v_body, r̈ = H_b v̇_body + acc (kinematics.spatial_point; H_b's
        ω̄-block row by row from kinematics.spatial_turn_row, its rows eᵢᵀH)."""
        if self.body < 0:
            z = np.zeros(3)
            return self.local, z, None, z
        k, j = self.qi, self.dofs[0]
        A = self.rotation9(q)
        lx, ly, lz = self._l
        x = _spatial_point(A, q[k], q[k + 1], q[k + 2], v[j], v[j + 1], v[j + 2], v[j + 3], v[j + 4], v[j + 5],
                           lx, ly, lz)
        H = np.empty((3, 6))
        H[:, :3] = np.eye(3)
        H[0, 3:] = _turn_row(A, lx, ly, lz, 1.0, 0.0, 0.0)
        H[1, 3:] = _turn_row(A, lx, ly, lz, 0.0, 1.0, 0.0)
        H[2, 3:] = _turn_row(A, lx, ly, lz, 0.0, 0.0, 1.0)
        return np.array(x[:3]), np.array(x[3:6]), H, np.array(x[6:])

    def generalised_force(self, q, F):
        """Hᵀ F of a force F at the point, over the body's six velocity coordinates
        (kinematics.spatial_point_force)."""
        lx, ly, lz = self._l
        return _spatial_point_force(self.rotation9(q), lx, ly, lz, F[0], F[1], F[2])
