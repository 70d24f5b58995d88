"""The reference oracle's translational elements: forces from the definitions, by differentiation.

Every translational element is a function of its terminal distance L(q) only. The oracle computes
L(q) from the bodies' poses and differentiates it with forward-mode automatic differentiation
(:class:`Jet`), never using the closed forms of Eqs. (15–20):

* the gradient ∇L (exact), so that L̇ = ∇L·q̇ and the generalised force is −F ∇L,
* the second derivative along the motion, q̇ᵀ∇²L q̇ (exact, Taylor mode), so that
  L̈ = ∇L·q̈ + q̇ᵀ∇²L q̇.

Inerter with the centripetal term: F = b L̈ (Eq. 9). Without it (Eq. 8): F = b r̈·r̂, which the
oracle obtains as b(L̈ − |ṙ⊥|²/L) with ṙ from the Jacobian of r(q), again by differentiation.
Under the small-displacement law: F = b s̈ with s(q) = ê0·r(q), ê0 the initial r̂, acting along
ê0 (generalised force −F ∇s), s differentiated on Jets as L is.
An inerter's device (:class:`OracleDevice`) takes its inertance from the kinetic energy of its
flywheel or channel fluid, its friction and channel damping from their dissipation function, its
end stops from their potential and Hunt-Crossley dissipation function.
An error in either the fast path or this module shows up as a disagreement between the two.

Planar rotational elements (:class:`OracleRotational`) are derived in the same way from the relative
angle φ(q) = θ_b − θ_a: a rotational spring from its potential V = ½k(φ − φ0)² (generalised force
−∇V, torque dV/dφ), a rotational damper from its dissipation function R = ½d φ̇² (generalised force
−(∂R/∂φ̇)∇φ, torque ∂R/∂φ̇), each derivative taken on Jets. 3D rotational elements stay with the
numpy evaluators (see :class:`OracleRotational`).
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.errors import MIN_LENGTH, TerminalsMeet


class Jet:
    """A number with its gradient g (w.r.t. n chosen coordinates) and its first and second
    derivatives d1, d2 along a curve q(t) = q + q̇ t (so d2 = q̇ᵀ∇²f q̇)."""

    __slots__ = ("v", "d1", "d2", "g")

    def __init__(self, v, d1, d2, g):
        self.v, self.d1, self.d2, self.g = v, d1, d2, g

    @staticmethod
    def constant(value, n):
        return Jet(float(value), 0.0, 0.0, np.zeros(n))

    def __add__(self, o):
        if not isinstance(o, Jet):
            return Jet(self.v + o, self.d1, self.d2, self.g)
        return Jet(self.v + o.v, self.d1 + o.d1, self.d2 + o.d2, self.g + o.g)

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.v, -self.d1, -self.d2, -self.g)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, Jet):
            return Jet(self.v * o, self.d1 * o, self.d2 * o, self.g * o)
        return Jet(self.v * o.v,
                   self.d1 * o.v + self.v * o.d1,
                   self.d2 * o.v + 2.0 * self.d1 * o.d1 + self.v * o.d2,
                   self.g * o.v + self.v * o.g)

    __rmul__ = __mul__

    def reciprocal(self):
        return self._chain(1.0 / self.v, -1.0 / self.v ** 2, 2.0 / self.v ** 3)

    def __truediv__(self, o):
        return self * (o.reciprocal() if isinstance(o, Jet) else 1.0 / o)

    def __rtruediv__(self, o):
        return self.reciprocal() * o

    def _chain(self, f0, f1, f2):
        """Apply a scalar function with value f0 and derivatives f1, f2 at self.v."""
        return Jet(f0, f1 * self.d1, f1 * self.d2 + f2 * self.d1 * self.d1, f1 * self.g)


def jsqrt(x: Jet) -> Jet:
    s = math.sqrt(x.v)
    return x._chain(s, 0.5 / s, -0.25 / (s * x.v))


def jsin(x: Jet) -> Jet:
    s, c = math.sin(x.v), math.cos(x.v)
    return x._chain(s, c, -s)


def jcos(x: Jet) -> Jet:
    s, c = math.sin(x.v), math.cos(x.v)
    return x._chain(c, -s, -c)


def jpow(x: Jet, p: float) -> Jet:
    """x**p for x > 0."""
    return x._chain(x.v ** p, p * x.v ** (p - 1.0), p * (p - 1.0) * x.v ** (p - 2.0))


def jabs(x: Jet) -> Jet:
    return x._chain(abs(x.v), math.copysign(1.0, x.v), 0.0)


def jlogcosh(x: Jet) -> Jet:
    """ln cosh x, written |x| + ln(1 + e^{−2|x|}) − ln 2 so that it does not overflow."""
    a = abs(x.v)
    t = math.tanh(x.v)
    return x._chain(a + math.log1p(math.exp(-2.0 * a)) - math.log(2.0), t, 1.0 - t * t)


def point_position(point, coords):
    """r = R + A ū written out from the rotation's definition, on Jets (or floats): in 2D from
    the angle, in 3D from the (not necessarily unit) quaternion p, A = I + 2/|p|² (w[v]× + [v]×²)."""
    if point.body < 0:
        return list(point.local)
    if len(coords) == 3:
        x, y, th = coords
        ux, uy = point.local
        c, s = jcos(th), jsin(th)
        return [x + c * ux - s * uy, y + s * ux + c * uy]
    X, Y, Z, w, a, b, c = coords
    u = point.local
    k = 2.0 / (w * w + a * a + b * b + c * c)
    vec = (a, b, c)
    t = [vec[1] * u[2] - vec[2] * u[1], vec[2] * u[0] - vec[0] * u[2], vec[0] * u[1] - vec[1] * u[0]]  # v × u
    tt = [vec[1] * t[2] - vec[2] * t[1], vec[2] * t[0] - vec[0] * t[2], vec[0] * t[1] - vec[1] * t[0]]  # v × (v × u)
    return [P + u[i] + k * (w * t[i] + tt[i]) for i, P in enumerate((X, Y, Z))]


def _plain(q, point):
    """A point's body coordinates as constant Jets (None for the ground): (x, y, θ) or (R, p)."""
    if point.body < 0:
        return None
    return [Jet.constant(x, 1) for x in q[point.qi:point.qi + (3 if len(point.local) == 2 else 7)]]


def _position(q, point):
    """r of a point at pose q, as floats."""
    return [c.v if isinstance(c, Jet) else float(c) for c in point_position(point, _plain(q, point))]


def _seed(q, v, qi, vi, dim, n, k):
    """Jets for one body's coordinates along the motion, with gradients w.r.t. its velocity
    coordinates (placed at columns k...). 2D: q = (x, y, θ), q̇ = v, q̈|v̇=0 = 0. 3D: R with
    Ṙ = v; quaternion p with ṗ = ½ p⊗(0, ω) and p̈|ω̇=0 = ½ ṗ⊗(0, ω) = −¼|ω|² p."""
    if dim == 2:
        jets = []
        for j in range(3):
            g = np.zeros(n)
            g[k + j] = 1.0
            jets.append(Jet(float(q[qi + j]), float(v[vi + j]), 0.0, g))
        return jets
    jets = []
    for j in range(3):
        g = np.zeros(n)
        g[k + j] = 1.0
        jets.append(Jet(float(q[qi + j]), float(v[vi + j]), 0.0, g))
    p = np.asarray(q[qi + 3:qi + 7], dtype=float)
    w = np.asarray(v[vi + 3:vi + 6], dtype=float)

    def rate(pp, ww):                                          # ½ p ⊗ (0, ω)
        a, b, c = ww
        return 0.5 * np.array((-pp[1] * a - pp[2] * b - pp[3] * c, pp[0] * a + pp[2] * c - pp[3] * b,
                               pp[0] * b + pp[3] * a - pp[1] * c, pp[0] * c + pp[1] * b - pp[2] * a))
    pdot = rate(p, w)
    pddot = rate(pdot, w)
    basis = [rate(p, e) for e in np.eye(3)]
    for i in range(4):
        g = np.zeros(n)
        for j in range(3):
            g[k + 3 + j] = basis[j][i]
        jets.append(Jet(float(p[i]), float(pdot[i]), float(pddot[i]), g))
    return jets


class DistanceProbe:
    """L(q) between two points, with ∇L, L̇, q̇ᵀ∇²Lq̇ and the terminal velocity ṙ, by Jets."""

    def __init__(self, pair, labels, name, mech, direction=None):
        self.pair = pair
        self.direction = direction          # ê0: evaluate s = ê0·r instead of L (small-displacement law)
        self.dofs = pair.dofs
        self.labels = labels
        self.name = name
        self.dim = mech.dim
        if mech.dim == 3 and mech.orientation.kind != "quaternion":
            from inerter.common.errors import SceneError
            raise SceneError(mech.scene.source, "scene.orientation", mech.orientation.kind,
                             "orientation = \"quaternion\" for the oracle", "the oracle differentiates "
                             "quaternion kinematics only")

    def evaluate(self, q, v):
        n = len(self.dofs)
        coords, k = {}, 0
        nvb = 3 if self.dim == 2 else 6
        for p in (self.pair.a, self.pair.b):
            if p.body >= 0 and p.body not in coords:
                coords[p.body] = _seed(q, v, p.qi, p.dofs[0], self.dim, n, k)
                k += nvb
        ra = point_position(self.pair.a, coords.get(self.pair.a.body))
        rb = point_position(self.pair.b, coords.get(self.pair.b.body))
        r = [b - a for a, b in zip(ra, rb)]
        r = [c if isinstance(c, Jet) else Jet.constant(c, n) for c in r]
        L2 = r[0] * r[0]
        for c in r[1:]:
            L2 = L2 + c * c
        if not math.sqrt(L2.v) > MIN_LENGTH:
            raise TerminalsMeet(
                f"element '{self.name}': its terminals {self.labels[0]} and {self.labels[1]} meet "
                f"(distance {math.sqrt(L2.v):.3g} m < {MIN_LENGTH:g} m), so its direction is undefined")
        rdot = np.array([c.d1 for c in r])                      # ṙ = J_r q̇
        if self.direction is not None:
            s = r[0] * float(self.direction[0])
            for c, e in zip(r[1:], self.direction[1:]):
                s = s + c * float(e)
            return s, rdot
        return jsqrt(L2), rdot

    def distance(self, q):
        """|r(q)|, whatever the probe differentiates."""
        ra, rb = _position(q, self.pair.a), _position(q, self.pair.b)
        return math.sqrt(sum((b - a) ** 2 for a, b in zip(ra, rb)))


class OracleRotational:
    """A planar rotational spring or damper between two bodies' angles (or a body and the ground),
    from its potential or its dissipation function, differentiated on Jets.

    φ(q) = θ_b − θ_a is a Jet with its gradient ∇φ over the angles and φ̇ = ∇φ·q̇ along the motion.
    Spring: V(φ) = ½k(φ − φ0)²; the generalised force is −∇V (chain rule on the Jets: V.g), the
    torque dV/dφ (V on a Jet seeded dφ = 1). Damper: R(φ̇) = ½d φ̇² (Rayleigh); the generalised
    force is −(∂R/∂φ̇)∇φ, since ∂φ̇/∂q̇ = ∇φ, the torque ∂R/∂φ̇ (R on a Jet seeded dφ̇ = 1). Neither
    law is read from :mod:`inerter.elements`: these two functions are the definitions.

    The mechanism builds these through ``OracleElement.rotational`` for planar scenes only. In 3D
    the evaluators' φ (rotation about an axis fixed in body a) equals an exact derivation only
    while the relative rotation stays about that axis, so an oracle there would disagree off the
    revolute joint's manifold by construction, not by a mistake."""

    def __init__(self, spec, index_a, index_b, free_angle):
        self.name = spec.name
        self.kind = spec.type
        self.coefficient = float(spec.coefficient)
        self.coefficient_name = {"rotational_spring": "k", "rotational_damper": "d"}[spec.type]
        self.free_angle = float(free_angle)
        self.ia, self.ib = index_a, index_b
        self.dofs = [i for i in (index_a, index_b) if i >= 0]

    def _definition(self, x):
        """V(φ) of a spring, R(φ̇) of a damper, on a Jet (or a float)."""
        if self.kind == "rotational_spring":
            d = x - self.free_angle
            return 0.5 * self.coefficient * (d * d)
        return 0.5 * self.coefficient * (x * x)

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
        x = phi.v if self.kind == "rotational_spring" else phi.d1
        return self._definition(Jet(x, 1.0, 0.0, np.zeros(0))).d1

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


class OracleDevice:
    """An inerter's device from its energies, written here from the device literature's
    definitions (not read from :mod:`inerter.elements`), each derivative taken on Jets.

    * Inertance from the kinetic energy T(L̇) of what the stroke drives: a flywheel of inertia J
      turned at ω = n L̇ (n = 2π/p for a ball screw of lead p, or the gear ratio), T = ½ J ω²; the
      fluid in a helical channel of length ℓ and area A_c, driven by a piston of area A_p at
      u = (A_p/A_c) L̇, T = ½ ρ ℓ A_c u². b = d²T/dL̇².
    * Friction and channel damping from their dissipation function D(L̇) = F_c v_s ln cosh(L̇/v_s)
      + ½ c_f L̇² + ½ c₁ L̇² + ⅓ c₂ |L̇|³: the generalised force is −∂D/∂q̇ (D on the Jet of L̇,
      whose gradient is ∂L̇/∂q̇ = ∇L), the axial force ∂D/∂L̇.
    * End stops: penetration δ = L_min − L or L − L_max, the potential V = k_s δⁿ⁺¹/(n+1) and
      the Hunt-Crossley dissipation R = ½ c_s δⁿ δ̇²; a contact pushes only, so its normal force is
      N = max(0, dV/dδ + ∂R/∂δ̇), acting as −N (lower stop) or +N (upper) along the element.
    """

    def __init__(self, device):
        self.spec = device
        states = [n for n in ("compliance", "backlash", "dissipated_energy") if device.has(n)]
        if states:
            from inerter.common.errors import InerterError
            raise InerterError(f"the oracle derives an inerter device from L(q) and its rate only; "
                               f"device.{states[0]} has internal states (series deflection, dissipated "
                               f"energy), which it does not derive: check such a scene against closed forms")
        self.flywheel = device.values("flywheel") if device.has("flywheel") else None
        self.friction = device.values("friction") if device.has("friction") else None
        self.stops = device.values("end_stops") if device.has("end_stops") else None
        self.fluid = device.values("fluid") if device.has("fluid") else None
        if self.flywheel is not None:
            lead = self.flywheel.get("lead")
            self.ratio = 2.0 * math.pi / lead if lead is not None else self.flywheel["ratio"]

    def kinetic_energy(self, rate):
        """T(L̇) of the flywheel or the channel's fluid (None: the scene gives b)."""
        if self.flywheel is not None:
            w = rate * self.ratio
            return 0.5 * self.flywheel["inertia"] * (w * w)
        if self.fluid is not None:
            f = self.fluid
            u = rate * (f["piston_area"] / f["channel_area"])
            return 0.5 * f["density"] * f["channel_length"] * f["channel_area"] * (u * u)
        return None

    def inertance(self):
        T = self.kinetic_energy(Jet(0.0, 1.0, 0.0, np.zeros(0)))
        return None if T is None else T.d2

    def _parts(self, rate):
        """(friction, channel) dissipation functions of L̇ (a Jet or a float)."""
        friction = channel = 0.0
        if self.friction is not None:
            fr = self.friction
            if fr["coulomb"] is not None:
                vs = fr["velocity_scale"]
                friction = fr["coulomb"] * vs * jlogcosh(rate * (1.0 / vs))
            friction = friction + 0.5 * (fr["viscous"] or 0.0) * (rate * rate)
        if self.fluid is not None:
            f = self.fluid
            channel = (0.5 * f["linear_damping"] * (rate * rate)
                       + (f["quadratic_damping"] / 3.0) * (rate * rate * jabs(rate)))
        return friction, channel

    def dissipation(self, rate):
        friction, channel = self._parts(rate)
        return friction + channel

    def _slope(self, fn, x):
        """dfn/dx at the float x, on a Jet."""
        y = fn(Jet(x, 1.0, 0.0, np.zeros(0)))
        return y.d1 if isinstance(y, Jet) else 0.0

    def _penetration(self, L, rate):
        """(δ, δ̇, sign of the axial force) past a stop, or None within the stroke."""
        st = self.stops
        if st["min"] is not None and st["min"] - L > 0.0:
            return st["min"] - L, -rate, -1.0
        if st["max"] is not None and L - st["max"] > 0.0:
            return L - st["max"], rate, 1.0
        return None

    def _stop_potential(self, d):
        n = self.stops["exponent"]
        return self.stops["stiffness"] * jpow(d, n + 1.0) * (1.0 / (n + 1.0))

    def contact(self, L, rate):
        """(axial force, dissipated power) of the end stops at L, L̇ (floats)."""
        hit = self._penetration(L, rate) if self.stops is not None else None
        if hit is None:
            return 0.0, 0.0
        d, ddot, sign = hit
        elastic = self._slope(self._stop_potential, d)                               # dV/dδ
        n, c = self.stops["exponent"], self.stops["damping"]

        def rayleigh(x):
            return 0.5 * c * d ** n * (x * x)
        damping = self._slope(rayleigh, ddot)                                         # ∂R/∂δ̇
        N = elastic + damping
        if not N > 0.0:                    # a contact only pushes: released, its energy V is lost
            return 0.0, -elastic * ddot
        return sign * N, 2.0 * rayleigh(ddot)                                         # R quadratic in δ̇

    def potential(self, L):
        """The end stops' elastic energy at the terminal distance L (a float)."""
        hit = self._penetration(L, 0.0) if self.stops is not None else None
        return 0.0 if hit is None else self._stop_potential(Jet(hit[0], 0.0, 0.0, np.zeros(0))).v

    def add_force(self, L, Q, dofs):
        """Q −= ∂D/∂q̇ (D on the Jet of L̇ with gradient ∇L) and the contact's −F∇L."""
        rate = Jet(L.d1, 0.0, 0.0, L.g)
        D = self.dissipation(rate)
        if isinstance(D, Jet):
            Q[dofs] -= D.g
        F, _ = self.contact(L.v, L.d1)
        Q[dofs] -= F * L.g

    def force(self, L, rate):
        """The device's axial force ∂D/∂L̇ + the contact's (floats)."""
        return self._slope(self.dissipation, rate) + self.contact(L, rate)[0]

    def outputs(self, L, rate):
        """The device's outputs, in the order its scene element names them."""
        friction = self._slope(lambda x: self._parts(x)[0], rate)
        channel = self._slope(lambda x: self._parts(x)[1], rate)
        stop, stop_loss = self.contact(L, rate)
        values = {"w_flywheel": self.ratio * rate if self.flywheel is not None else 0.0,
                  "f_friction": friction, "f_fluid": channel, "f_stop": stop,
                  "p_loss": (friction + channel) * rate + stop_loss}
        return tuple(values[suffix] for suffix, _, _ in self.spec.outputs())


class OracleElement:
    """Spring, damper or inerter (with its device, :class:`OracleDevice`) through L(q) and its
    derivatives. As the mechanism's element factory it builds the planar rotational elements too
    (:attr:`rotational`)."""

    #: The factory of planar rotational elements, ``rotational(spec, index_a, index_b, free_angle)``.
    rotational = OracleRotational

    def __init__(self, spec, pair, centripetal, free_length, labels, mech):
        self.name = spec.name
        self.kind = spec.type
        self.device = OracleDevice(spec.device) if getattr(spec, "device", None) is not None else None
        from_device = self.device.inertance() if self.device is not None else None
        self.coefficient = float(spec.coefficient) if from_device is None else from_device
        self.coefficient_name = {"spring": "k", "damper": "c", "inerter": "b"}[spec.type]
        self.centripetal = bool(centripetal)
        self.free_length = free_length
        direction = None
        if spec.type == "inerter" and mech.scene.small_displacement:
            # the small-displacement law: s = ê0·r, ê0 the direction at the scene's pose; F = b s̈
            r0 = np.subtract(_position(mech.initial_q, pair.b), _position(mech.initial_q, pair.a))
            direction = r0 / np.linalg.norm(r0)
            self.centripetal = True                     # F = b s̈ as it is: no |ṙ⊥|²/L to remove
        self.fixed_direction = direction
        self.probe = DistanceProbe(pair, labels, spec.name, mech, direction)
        self.pair = pair

    def _force_parts(self, L, rdot):
        """F = a·q̈ part (gradient factor) + the rest: returns (mass factor, rest)."""
        b = self.coefficient
        if self.kind == "spring":
            return 0.0, b * (L.v - self.free_length)            # Eq. (5)
        if self.kind == "damper":
            return 0.0, b * L.d1                                # c dL/dt, Eq. (6)
        rest = L.d2                                             # q̇ᵀ∇²Lq̇: L̈ = ∇L·q̈ + this
        if not self.centripetal:
            rest -= (float(rdot @ rdot) - L.d1 * L.d1) / L.v    # remove |ṙ⊥|²/L: F = b r̈·r̂ (Eq. 8)
        return b, b * rest

    def geometry(self, q, v):
        return self.probe.evaluate(q, v)

    def add_mass(self, q, v, M, geo=None):
        if self.kind != "inerter":
            return
        L, _ = geo or self.probe.evaluate(q, v)
        idx = self.probe.dofs
        M[np.ix_(idx, idx)] += self.coefficient * np.outer(L.g, L.g)

    def add_force(self, q, v, Q, geo=None):
        L, rdot = geo or self.probe.evaluate(q, v)
        _, rest = self._force_parts(L, rdot)
        Q[self.probe.dofs] -= rest * L.g                        # Q = −F ∇L
        if self.device is not None:
            self.device.add_force(L, Q, self.probe.dofs)

    def outputs(self, q, v, a):
        L, rdot = self.probe.evaluate(q, v)
        mass, rest = self._force_parts(L, rdot)
        F = rest + mass * float(L.g @ a[self.probe.dofs])
        distance = L.v if self.fixed_direction is None else self.probe.distance(q)
        if self.device is None:
            return distance, L.d1, F
        F += self.device.force(L.v, L.d1)
        return (distance, L.d1, F) + self.device.outputs(L.v, L.d1)

    def length(self, q):
        return self.probe.evaluate(q, np.zeros_like(q))[0].v

    def kinetic(self, q, v):
        if self.kind != "inerter":
            return 0.0
        return 0.5 * self.coefficient * self.probe.evaluate(q, v)[0].d1 ** 2

    def potential(self, q):
        if self.device is not None:
            return self.device.potential(self.length(q))
        if self.kind != "spring":
            return 0.0
        return 0.5 * self.coefficient * (self.length(q) - self.free_length) ** 2
