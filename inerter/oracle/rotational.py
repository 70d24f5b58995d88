"""The oracle's rotational springs and dampers, from their potential or dissipation function
differentiated on Jets (:mod:`inerter.oracle.jets`), in 2D (:class:`OracleRotational`) and in 3D
(:class:`OracleSpatialRotational`). Neither reads :mod:`inerter.elements` or the engine: the
laws V = ½k(φ − φ0)² and R = ½d φ̇² are written here, and in 3D the angle is the twist about the
axis, from the relative rotation's quaternion on Jets.
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.errors import SceneError
from inerter.oracle.jets import Jet, jatan2, jsqrt, seed

#: The rotational kinds the oracle defines (:func:`_law`), each with its coefficient's key.
COEFFICIENT_NAME = {"rotational_spring": "k", "rotational_damper": "d"}


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
        self.coefficient_name = COEFFICIENT_NAME[spec.type]
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
        """(φ, φ̇, torque, power torque·φ̇, stored energy V: a damper's 0)."""
        phi = self.angle(q, v)
        tau = self._torque(phi)
        return phi.v, phi.d1, tau, tau * phi.d1, self.kinetic(q, v) + self.potential(q)

    def kinetic(self, q, v):
        return 0.0

    def potential(self, q):
        if self.kind != "rotational_spring":
            return 0.0
        return self._definition(self.angle(q, np.zeros_like(q)).v)


def _qmul(a, b):
    """The quaternion product a ⊗ b, (w, x, y, z), of Jets or floats."""
    return [a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]]


def _conjugate(p):
    return [p[0], -p[1], -p[2], -p[3]]


class OracleSpatialRotational(OracleRotational):
    """A 3D rotational spring or damper about an axis n̄ fixed in body a (in the ground's frame for
    the ground), from its potential or dissipation function on the angle's Jet, as the planar one:

    * its angle φ(q): the twist about n̄ of the relative rotation since t = 0, from the swing-twist
      decomposition of its quaternion d = p̄_a ⊗ p_b ⊗ p̄_ab(0) (p_ab(0) = p̄_a ⊗ p_b at t = 0, each p
      normalised): d = d_swing ⊗ d_twist with d_twist = (cos φ/2, sin φ/2 n̄), so
      φ = 2 atan2(n̄·d⃗, d₀), taken on the turn nearest φ_ref (its angle at the last accepted step,
      0 at t = 0), so that it winds on past half a turn. On Jets of the bodies' coordinates along the
      motion (the quaternions' rates ṗ = ½ p ⊗ (0, ω)) it carries its gradient ∇φ over the velocity
      coordinates and its rate φ̇ = ∇φ·v;
    * spring: V(φ) = ½k(φ − φ0)², generalised force −∇V; damper: R(φ̇) = ½d φ̇², generalised force
      −(∂R/∂φ̇)∇φ; torque dV/dφ or ∂R/∂φ̇ (:class:`OracleRotational`).

    On a revolute joint about n̄, ∇φ·v = n·(ω_b − ω_a) with n = A_a n̄. Near a relative rotation that
    swings half a turn away from n̄ (d₀ = n̄·d⃗ = 0) the twist is undefined and its gradient grows
    without bound."""

    def __init__(self, spec, frame_a, frame_b, q0):
        for frame in (frame_a, frame_b):
            if frame.body >= 0 and frame.orientation.kind != "quaternion":
                raise SceneError("the oracle", "scene.orientation", frame.orientation.kind,
                                 "orientation = \"quaternion\" for the oracle",
                                 "the oracle differentiates quaternion kinematics only")
        super().__init__(spec, -1, -1, float(spec.free_length or 0.0))
        self.axis = np.asarray(spec.axis, dtype=float)
        self.frames = [f for f in (frame_a, frame_b) if f.body >= 0]
        self.fa, self.fb = frame_a, frame_b
        self.dofs = [f.vi + j for f in self.frames for j in range(6)]
        z = np.zeros(max(f.vi for f in (frame_a, frame_b)) + 6)
        self.initial = [x.v for x in self._relative(q0, z)]
        #: φ_ref: the angle at the last accepted step (0 at t = 0), moved on by :meth:`wind`.
        self.reference = 0.0

    def _relative(self, q, v):
        """p̄_a ⊗ p_b, each normalised, as Jets over :attr:`dofs`."""
        n = len(self.dofs)
        quats, k = {}, 0
        for frame in self.frames:
            p = seed(q, v, frame.qi, frame.vi, 3, n, k)[3:]
            norm = jsqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] + p[3] * p[3])
            quats[frame.body] = [c / norm for c in p]
            k += 6
        identity = [Jet.constant(x, n) for x in (1.0, 0.0, 0.0, 0.0)]
        pa, pb = (quats.get(f.body, identity) if f.body >= 0 else identity for f in (self.fa, self.fb))
        return _qmul(_conjugate(pa), pb)

    def angle(self, q, v):
        """φ as a Jet over :attr:`dofs` (gradient ∇φ, first derivative φ̇), on the turn nearest φ_ref."""
        d = _qmul(self._relative(q, v), _conjugate(self.initial))
        x = d[1] * self.axis[0] + d[2] * self.axis[1] + d[3] * self.axis[2]
        reading = 2.0 * jatan2(x, d[0])
        return reading + (self.reference + math.remainder(reading.v - self.reference, 2.0 * math.pi) - reading.v)

    def wind(self, q):
        """After an accepted step to q: the next angles are read on the turn of this one."""
        self.reference = self.angle(q, np.zeros(max(f.vi for f in (self.fa, self.fb)) + 6)).v

    def rate(self, q, v):
        """φ̇ = ∇φ·v at (q, v) (Mechanism.wind's prediction of the angle at a step's end)."""
        return self.angle(q, v).d1

    def potential(self, q):
        if self.kind != "rotational_spring":
            return 0.0
        return self._definition(self.angle(q, np.zeros(max(f.vi for f in (self.fa, self.fb)) + 6)).v)
