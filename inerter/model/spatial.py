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

import math

import numpy as np

from inerter.common.rotations import (  # noqa: F401  (re-exported for the model's users)
    EULER_SINGULARITY, cross, skew, quat_matrix, quat_rate, quat_from_matrix, axis_angle_matrix, euler_matrix, euler_from_matrix, euler_rate)


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
    evaluation of the mechanism computes each body's A once."""

    __slots__ = ("key", "A")

    def __init__(self):
        self.key, self.A = None, None

    def matrix(self, orientation, o):
        key = o.tobytes()
        if key != self.key:
            self.key, self.A = key, orientation.matrix(o)
        return self.A


class SpatialPoint:
    """A point on a 3D body (or the ground, body −1): r, ṙ, its H block and acceleration term."""

    __slots__ = ("body", "local", "dofs", "qi", "orientation", "_skew", "cache")

    def __init__(self, body: int, local, q_index: int, v_index: int, orientation: Orientation | None,
                 cache: RotationCache | None = None):
        self.body = body
        self.local = np.asarray(local, dtype=float)
        self.qi = q_index
        self.orientation = orientation
        self.dofs = np.arange(v_index, v_index + 6) if body >= 0 else None
        self._skew = skew(self.local)
        self.cache = cache or RotationCache()

    def evaluate(self, q, v):
        """(r, ṙ, H_b, acc): ṙ = H_b v_body, r̈ = H_b v̇_body + acc."""
        if self.body < 0:
            z = np.zeros(3)
            return self.local, z, None, z
        k, o = self.qi, self.orientation
        A = self.cache.matrix(o, q[k + 3:k + 3 + o.size])
        vb = v[self.dofs[0]:self.dofs[0] + 6]
        w = vb[3:]
        u = A @ self.local
        Au = -A @ self._skew                                     # ∂ṙ/∂ω: −A ũ
        H = np.empty((3, 6))
        H[:, :3] = np.eye(3)
        H[:, 3:] = Au
        wxu = cross(w, self.local)
        r = q[k:k + 3] + u
        rdot = vb[:3] + A @ wxu
        acc = A @ cross(w, wxu)                               # A(ω × (ω × ū)), Eq. (25)
        return r, rdot, H, acc
