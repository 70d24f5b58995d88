"""The oracle's rotational springs and dampers, from their potential or dissipation function
differentiated on Jets (:mod:`inerter.oracle.jets`), in 2D (:class:`OracleRotational`) and in 3D
(:class:`OracleSpatialRotational`). Neither reads :mod:`inerter.elements` or the engine: the
laws V = ½k(φ − φ0)² and R = ½d φ̇² are written here, and in 3D the angle, the rate and the
generalised force are derived from quaternions and the rotation's definition.
"""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from inerter.common.errors import SceneError
from inerter.oracle.jets import Jet, angular_velocity, point_position, seed

_COEFFICIENT_NAME = {"rotational_spring": "k", "rotational_damper": "d"}


def _law(kind, coefficient, free_angle, x):
    """V(φ) of a spring, R(φ̇) of a damper, on a Jet (or a float)."""
    if kind == "rotational_spring":
        d = x - free_angle
        return 0.5 * coefficient * (d * d)
    return 0.5 * coefficient * (x * x)


def _slope(kind, coefficient, free_angle, x):
    """dV/dφ or ∂R/∂φ̇ at the float x, by differentiating the law on a Jet seeded dx = 1."""
    return _law(kind, coefficient, free_angle, Jet(x, 1.0, 0.0, np.zeros(0))).d1


class OracleRotational:
    """A planar rotational spring or damper between two bodies' angles (or a body and the ground),
    from its potential or its dissipation function, differentiated on Jets.

    φ(q) = θ_b − θ_a is a Jet with its gradient ∇φ over the angles and φ̇ = ∇φ·q̇ along the motion.
    Spring: V(φ) = ½k(φ − φ0)²; the generalised force is −∇V (chain rule on the Jets: V.g), the
    torque dV/dφ (V on a Jet seeded dφ = 1). Damper: R(φ̇) = ½d φ̇² (Rayleigh); the generalised
    force is −(∂R/∂φ̇)∇φ, since ∂φ̇/∂q̇ = ∇φ, the torque ∂R/∂φ̇ (R on a Jet seeded dφ̇ = 1). Neither
    law is read from :mod:`inerter.elements`: these two functions are the definitions.

    The mechanism builds these through ``OracleElement.rotational`` in planar scenes; in 3D it
    builds :class:`OracleSpatialRotational`."""

    def __init__(self, spec, index_a, index_b, free_angle):
        self.name = spec.name
        self.kind = spec.type
        self.coefficient = float(spec.coefficient)
        self.coefficient_name = _COEFFICIENT_NAME[spec.type]
        self.free_angle = float(free_angle)
        self.ia, self.ib = index_a, index_b
        self.dofs = [i for i in (index_a, index_b) if i >= 0]

    def _definition(self, x):
        """V(φ) of a spring, R(φ̇) of a damper, on a Jet (or a float)."""
        return _law(self.kind, self.coefficient, self.free_angle, x)

    def angle(self, q, v):
        """φ as a Jet over the velocity coordinates in `dofs` (gradient ∇φ, first derivative φ̇)."""
        n = len(self.dofs)
        phi = Jet.constant(0.0, n)
        for sign, i in ((1.0, self.ib), (-1.0, self.ia)):
            if i >= 0:
                g = np.zeros(n)
                g[self.dofs.index(i)] = 1.0
                phi = phi + sign * Jet(float(q[i]), float(v[i]), 0.0, g)
        return phi

    def _torque(self, phi):
        """dV/dφ (spring) or ∂R/∂φ̇ (damper), by differentiation of the definition."""
        return _slope(self.kind, self.coefficient, self.free_angle, phi.v if self.kind == "rotational_spring" else phi.d1)

    def geometry(self, q, v):
        return self.angle(q, v)

    def add_force(self, q, v, Q, geo=None):
        phi = geo or self.angle(q, v)
        if self.kind == "rotational_spring":
            Q[self.dofs] -= self._definition(phi).g               # −∇V
        else:
            Q[self.dofs] -= self._torque(phi) * phi.g             # −(∂R/∂φ̇) ∇φ

    def add_mass(self, q, v, M, geo=None):
        pass

    def outputs(self, q, v, a):
        phi = self.angle(q, v)
        return phi.v, phi.d1, self._torque(phi)

    def kinetic(self, q, v):
        return 0.0

    def potential(self, q):
        if self.kind != "rotational_spring":
            return 0.0
        return self._definition(self.angle(q, np.zeros_like(q)).v)


def _qmul(a, b):
    """The quaternion product a ⊗ b, (w, x, y, z)."""
    return np.array((a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
                     a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
                     a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
                     a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]))


def _conjugate(p):
    return np.array((p[0], -p[1], -p[2], -p[3]))


class OracleSpatialRotational:
    """A 3D rotational spring or damper about an axis n̄ fixed in body a (in the ground's frame for
    the ground), between body a and body b, derived from its definitions:

    * **angle** φ: the twist about n̄ of the relative rotation since t = 0, from the swing-twist
      decomposition of its quaternion d = p̄_a ⊗ p_b ⊗ p̄_ab(0) (p_ab(0) = p̄_a ⊗ p_b at t = 0, each
      p normalised): d = d_swing ⊗ d_twist with d_twist = (cos φ/2, sin φ/2 n̄), so
      φ = 2 atan2(n̄·d⃗, d₀), taken on the turn nearest φ_ref (its angle at the last accepted step,
      0 at t = 0), so that it winds on past half a turn;
    * **rate** ω_n = n·(ω_b − ω_a), n = A_a n̄, each ω a body's angular velocity from its definition
      ω̃ = Ṙ Rᵀ, R(q) the body's rotation on Jets (the images of the unit vectors under
      :func:`point_position`), so that ∂ω_n/∂v comes from the Jets' gradients;
    * **torque** τ = dV/dφ, V = ½k(φ − φ0)² (spring), or ∂R/∂ω_n, R = ½d ω_n² (damper), acting as −τn
      on body b and +τn on body a: its virtual power is −τ δω_n, so its generalised force is
      −τ ∂ω_n/∂v.

    Where the relative rotation stays about n̄ (a revolute joint about n̄) φ̇ = ω_n and the spring's
    generalised force is −∇V; off that manifold (a violated joint, another joint) the torque still
    acts about n, as docs/scene_format.md defines the element."""

    def __init__(self, spec, frame_a, frame_b, q0):
        for frame in (frame_a, frame_b):
            if frame.body >= 0 and frame.orientation.kind != "quaternion":
                raise SceneError("the oracle", "scene.orientation", frame.orientation.kind,
                                 "orientation = \"quaternion\" for the oracle",
                                 "the oracle differentiates quaternion kinematics only")
        self.name = spec.name
        self.kind = spec.type
        self.coefficient = float(spec.coefficient)
        self.coefficient_name = _COEFFICIENT_NAME[spec.type]
        self.free_angle = float(spec.free_length or 0.0)
        self.axis = np.asarray(spec.axis, dtype=float)
        self.frames = [f for f in (frame_a, frame_b) if f.body >= 0]
        self.a_moves, self.b_moves = frame_a.body >= 0, frame_b.body >= 0
        self.fa, self.fb = frame_a, frame_b
        self.dofs = [f.vi + j for f in self.frames for j in range(6)]
        self.initial = _qmul(_conjugate(self._quaternion(frame_a, q0)), self._quaternion(frame_b, q0))
        #: φ_ref: the angle at the last accepted step (0 at t = 0), moved on by :meth:`wind`.
        self.reference = 0.0

    @staticmethod
    def _quaternion(frame, q):
        if frame.body < 0:
            return np.array((1.0, 0.0, 0.0, 0.0))
        p = np.asarray(q[frame.qi + 3:frame.qi + 7], dtype=float)
        return p / np.linalg.norm(p)

    def angle(self, q):
        """φ: the twist about n̄ of the rotation since t = 0, on the turn nearest φ_ref."""
        rel = _qmul(_conjugate(self._quaternion(self.fa, q)), self._quaternion(self.fb, q))
        d = _qmul(rel, _conjugate(self.initial))
        reading = 2.0 * math.atan2(float(self.axis @ d[1:]), float(d[0]))
        return self.reference + math.remainder(reading - self.reference, 2.0 * math.pi)

    def rate(self, q, v):
        """(ω_n, ∂ω_n/∂v over :attr:`dofs`): the relative angular velocity about n = A_a n̄."""
        n = len(self.dofs)
        omegas, k = [], 0
        for frame in self.frames:
            coords = seed(q, v, frame.qi, frame.vi, 3, n, k)
            origin = point_position(SimpleNamespace(body=frame.body, local=np.zeros(3)), coords)
            columns = [point_position(SimpleNamespace(body=frame.body, local=e), coords) for e in np.eye(3)]
            R = [[columns[j][i] - origin[i] for j in range(3)] for i in range(3)]
            omegas.append(angular_velocity(R))
            k += 6
        axis = omegas[0][0] @ self.axis if self.a_moves else self.axis        # n = A_a n̄
        w, grad = 0.0, np.zeros(n)
        signs = ([-1.0] if self.a_moves else []) + ([1.0] if self.b_moves else [])
        for (_, omega, d_omega, _), sign in zip(omegas, signs):
            w += sign * float(axis @ omega)
            grad += sign * (axis @ d_omega)
        return w, grad

    def geometry(self, q, v):
        return (self.angle(q), *self.rate(q, v))

    def torque(self, phi, w):
        x = phi if self.kind == "rotational_spring" else w
        return _slope(self.kind, self.coefficient, self.free_angle, x)

    def add_force(self, q, v, Q, geo=None):
        phi, w, grad = geo or self.geometry(q, v)
        Q[self.dofs] -= self.torque(phi, w) * grad

    def add_mass(self, q, v, M, geo=None):
        pass

    def wind(self, q):
        """After an accepted step to q: the next angles are read on the turn of this one."""
        self.reference = self.angle(q)

    def outputs(self, q, v, a):
        phi, w, _ = self.geometry(q, v)
        return phi, w, self.torque(phi, w)

    def kinetic(self, q, v):
        return 0.0

    def potential(self, q):
        if self.kind != "rotational_spring":
            return 0.0
        return _law(self.kind, self.coefficient, self.free_angle, self.angle(q))
