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
end stops from their potential and Hunt-Crossley dissipation function. With series compliance
(and backlash) the inerter strokes with u = L − s, s one more coordinate of the element
(:mod:`.series`, :meth:`OracleElement.extended`); its flywheel, friction and channel then act on u̇.
A screw efficiency (:mod:`.efficiency`) scales the inerter's term, b ∇ẋ∇ẋᵀ in the mass matrix and
−b ẍ₀ ∇ẋ in the forces (ẋ = L̇, or u̇ in series), by 1 + λ(τ) in the element's mode σ
(:attr:`OracleElement.mode`), which the mechanism's solve sets by trying every assignment; the screw's
loss b λ ẍ ẋ joins p_loss.
An error in either the fast path or this module shows up as a disagreement between the two.

Rotational elements (:mod:`inerter.oracle.rotational`) are derived in the same way from their angle
φ(q): a rotational spring from its potential V = ½k(φ − φ0)² (generalised force −∇V, torque
dV/dφ), a rotational damper from its dissipation function R = ½d φ̇² (generalised force
−(∂R/∂φ̇)∇φ, torque ∂R/∂φ̇), each derivative taken on Jets; φ = θ_b − θ_a in 2D, in 3D the twist
about an axis fixed in body a, from the relative rotation's quaternion.

Only the kinds written here and in :mod:`.rotational` are derived: a scene with an element of any
other kind (one added to :mod:`inerter.elements` since) is refused (:func:`require_definitions`)
until its definition is written here, from the kind's potential or dissipation function, for the
oracle to check the engine's law against.
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.errors import MIN_LENGTH, SceneError, TerminalsMeet
from inerter.oracle.jets import (
    Jet, angular_velocity, cross, dot, jabs, jcos, jlogcosh, jpow, jsin, jsqrt, parts, point_position, position, rotation,
    seed, times)
from inerter.oracle.rotational import COEFFICIENT_NAME as _ROTATIONAL_KINDS
from inerter.oracle.rotational import OracleRotational, OracleSpatialRotational
from inerter.oracle.efficiency import ScrewEfficiency
from inerter.oracle.series import SeriesConnection

#: The translational kinds :class:`OracleElement` derives, each with its coefficient's key; with
#: the rotational ones of :mod:`.rotational`, the kinds the oracle has a definition of.
_TRANSLATIONAL_KINDS = {"spring": "k", "damper": "c", "inerter": "b"}

#: Where a family's definitions are written: where a new kind's goes.
_DEFINED_IN = {"translational": "inerter/oracle/derivation.py (OracleElement)",
               "rotational": "inerter/oracle/rotational.py (_law)"}


def undefined_kind(spec, source):
    """None where the oracle has a definition of scene element `spec`'s kind; else the
    :class:`SceneError` that refuses it, naming the element, its kind and where its definition goes.
    (A translational element is one between two points, as the scene reader builds it.)"""
    family = "translational" if spec.point_a is not None else "rotational"
    defined = _TRANSLATIONAL_KINDS if family == "translational" else _ROTATIONAL_KINDS
    if spec.type in defined:
        return None
    return SceneError(
        source, f"elements.{spec.name}.type", spec.type,
        f"a kind the oracle defines ({', '.join(sorted(defined))}), or this kind's definition written "
        f"in {_DEFINED_IN[family]} from its potential or dissipation function",
        f"the oracle has no independent definition of the {family} kind {spec.type!r} of element "
        f"{spec.name!r} yet")


def require_definitions(scene):
    """Refuse `scene` (:class:`SceneError`, the first such element) where one of its elements is of
    a kind the oracle has no definition of: the oracle writes each kind's law itself, never reading
    :mod:`inerter.elements`, which is what makes it a check of the engine, so a kind added there has
    none until one is written here (:func:`undefined_kind`)."""
    for spec in scene.elements.values():
        error = undefined_kind(spec, scene.source)
        if error is not None:
            raise error


class _BodyPoint:
    """A point of a body given by its body-frame coordinates (what :func:`point_position` reads)."""

    def __init__(self, body, qi, local):
        self.body, self.qi, self.local = body, qi, local


class DistanceProbe:
    """L(q) between two points, with ∇L, L̇, q̇ᵀ∇²Lq̇ and the terminal velocity ṙ, by Jets."""

    def __init__(self, pair, labels, name, mech, direction=None, slider_axis=None):
        self.pair = pair
        self.direction = direction          # ê0: evaluate s = ê0·r instead of L (small-displacement law)
        # a prismatic joint's spring or damper: s = ê(q)·r with ê = A_a n̄, the joint's axis in a's body,
        # written as the difference of two points of a's body (n̄ apart), so that it is differentiated too
        self.axis_end = None if slider_axis is None else _BodyPoint(
            pair.a.body, pair.a.qi, np.asarray(pair.a.local, dtype=float) + np.asarray(slider_axis, dtype=float))
        self.dofs = pair.dofs
        self.labels = labels
        self.name = name
        self.dim = mech.dim
        self._last = None                   # (state, evaluation) of the last call
        if mech.dim == 3 and mech.orientation.kind != "quaternion":
            raise SceneError(mech.scene.source, "scene.orientation", mech.orientation.kind,
                             "orientation = \"quaternion\" for the oracle", "the oracle differentiates "
                             "quaternion kinematics only")

    def terminals(self, q, v):
        """(the bodies' coordinates as Jets by body, r_a, r_b as Jets), over this probe's dofs."""
        n = len(self.dofs)
        coords, k = {}, 0
        nvb = 3 if self.dim == 2 else 6
        for p in (self.pair.a, self.pair.b):
            if p.body >= 0 and p.body not in coords:
                coords[p.body] = seed(q, v, p.qi, p.dofs[0], self.dim, n, k)
                k += nvb
        ra = point_position(self.pair.a, coords.get(self.pair.a.body))
        rb = point_position(self.pair.b, coords.get(self.pair.b.body))
        as_jet = [c if isinstance(c, Jet) else Jet.constant(c, n) for c in ra + rb]
        return coords, as_jet[:len(ra)], as_jet[len(ra):]

    def evaluate(self, q, v):
        """(L as a Jet, ṙ) at (q, v) (s = ê·r for a fixed direction or a joint's axis), kept for the
        next call at the same state: a screw efficiency's modes are tried by solving the same state's
        system once per assignment (:func:`.efficiency.resolve`)."""
        key = (np.asarray(q, dtype=float).tobytes(), np.asarray(v, dtype=float).tobytes())
        if self._last is None or self._last[0] != key:
            self._last = (key, self._evaluate(q, v))
        return self._last[1]

    def _evaluate(self, q, v):
        n = len(self.dofs)
        coords, ra, rb = self.terminals(q, v)
        r = [b - a for a, b in zip(ra, rb)]
        rdot = np.array([c.d1 for c in r])                      # ṙ = J_r q̇
        if self.axis_end is not None:
            tip = point_position(self.axis_end, coords.get(self.pair.a.body))
            s = Jet.constant(0.0, n)
            for c, a, t in zip(r, ra, tip):
                s = s + c * (t - a)
            return s, rdot
        L2 = r[0] * r[0]
        for c in r[1:]:
            L2 = L2 + c * c
        if not math.sqrt(L2.v) > MIN_LENGTH:
            raise TerminalsMeet(
                f"element '{self.name}': its terminals {self.labels[0]} and {self.labels[1]} meet "
                f"(distance {math.sqrt(L2.v):.3g} m < {MIN_LENGTH:g} m), so its direction is undefined")
        if self.direction is not None:
            s = r[0] * float(self.direction[0])
            for c, e in zip(r[1:], self.direction[1:]):
                s = s + c * float(e)
            return s, rdot
        return jsqrt(L2), rdot

    def distance(self, q):
        """|r(q)|, whatever the probe differentiates."""
        ra, rb = position(q, self.pair.a), position(q, self.pair.b)
        return math.sqrt(sum((b - a) ** 2 for a, b in zip(ra, rb)))


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
    * Series compliance and backlash (:mod:`.series`): the inerter strokes with u = L − s, s one
      more coordinate; T(u̇), D(u̇) on the inerter's own stroke rate, the stops still on L.
    * Dissipated energy: ż = p_loss, the power of D, of the contacts and of the series connection
      (:meth:`loss`).
    * Screw efficiency (:mod:`.efficiency`): the inerter's term scaled by 1 + λ(τ) on the stroke
      the screw turns with (L, or u in series), its loss b λ ẍ ẋ part of the dissipated power.
    A mount beside a compliance or beside an efficiency is refused.
    """

    def __init__(self, device, source: str = "the oracle", element: str = "inerter"):
        """`source` (the scene file) and `element` (the element's name) name what is refused."""
        self.spec = device
        field = f"elements.{element}.device"
        if device.has("efficiency") and device.has("mount"):
            raise SceneError(source, f"{field}.efficiency", device.values("efficiency"),
                             "a device with a screw efficiency or a mount for the oracle, not both",
                             "the mount's gyroscopic terms spin the flywheel with b; the efficiency scales the "
                             "inerter's term to b_eff: no derivation of both together")
        if device.has("compliance") and device.has("mount"):
            raise SceneError(source, f"{field}.mount", device.values("mount"),
                             "a device with a mount or a compliance for the oracle, not both",
                             "the oracle's series connection spins the flywheel with the inerter's own stroke u; "
                             "device.mount's gyroscopic terms take it from L: no derivation of both together")
        #: The series connection (:mod:`.series`), or None: the inerter then strokes with L itself.
        self.series = (SeriesConnection(device.values("compliance"),
                                        device.values("backlash")["gap"] if device.has("backlash") else None)
                       if device.has("compliance") else None)
        #: The dissipated energy as a state (ż = p_loss), after the series' (s, ṡ) in z.
        self.keeps_loss = device.has("dissipated_energy")
        self.n_states = (2 if self.series is not None else 0) + (1 if self.keeps_loss else 0)
        self.flywheel = device.values("flywheel") if device.has("flywheel") else None
        self.friction = device.values("friction") if device.has("friction") else None
        self.stops = device.values("end_stops") if device.has("end_stops") else None
        self.fluid = device.values("fluid") if device.has("fluid") else None
        #: The screw efficiency (:class:`.efficiency.ScrewEfficiency`), or None.
        self.efficiency = ScrewEfficiency(device.values("efficiency")) if device.has("efficiency") else None
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
        """Q −= ∂D/∂q̇ (D on the Jet of L̇ with gradient ∇L) and the contact's −F∇L. In series D acts
        on the inerter's own stroke rate u̇ (:meth:`OracleElement.extended`): only the contact here."""
        if self.series is None:
            D = self.dissipation(Jet(L.d1, 0.0, 0.0, L.g))
            if isinstance(D, Jet):
                Q[dofs] -= D.g
        F, _ = self.contact(L.v, L.d1)
        Q[dofs] -= F * L.g

    def stroke_rate(self, rate, x):
        """The inerter's own stroke rate: u̇ = L̇ − ṡ in series (x = the element's states), L̇ without."""
        return rate - x[1] if self.series is not None else rate

    def force(self, L, rate, x=None):
        """The device's axial force on the terminals beyond b L̈ (floats): ∂D/∂L̇ and the contact's;
        in series the connection's force (:class:`.series.SeriesConnection`) and the contact's."""
        if self.series is not None:
            return self.series.force(x[0], x[1])[0] + self.contact(L, rate)[0]
        return self._slope(self.dissipation, rate) + self.contact(L, rate)[0]

    def loss(self, L, rate, x, screw=0.0):
        """The dissipated power (W): ∂D/∂u̇ · u̇ (D's power on the stroke it resists), the contact's,
        the series connection's (:meth:`.series.SeriesConnection.loss`) and `screw`, the screw
        efficiency's b λ ẍ ẋ (:meth:`OracleElement.screw`)."""
        ud = self.stroke_rate(rate, x)
        p = self._slope(self.dissipation, ud) * ud + self.contact(L, rate)[1] + screw
        return p + (self.series.loss(x[0], x[1]) if self.series is not None else 0.0)

    def outputs(self, L, rate, x, screw=(0.0, 1.0)):
        """The device's outputs, in the order its scene element names them (x: the element's states;
        `screw`: the screw efficiency's loss and direction τ, :meth:`OracleElement.screw`)."""
        ud = self.stroke_rate(rate, x)
        values = {"mode": 0.5 * (1.0 + screw[1]),
                  "w_flywheel": self.ratio * ud if self.flywheel is not None else 0.0,
                  "f_friction": self._slope(lambda y: self._parts(y)[0], ud),
                  "f_fluid": self._slope(lambda y: self._parts(y)[1], ud),
                  "f_stop": self.contact(L, rate)[0], "p_loss": self.loss(L, rate, x, screw[0]),
                  "e_loss": x[-1] if self.keeps_loss else 0.0}
        if self.series is not None:
            values.update(s_series=x[0], engaged=self.series.force(x[0], x[1])[1])
        return tuple(values[suffix] for suffix, _, _ in self.spec.outputs())


class DeviceBodies:
    """An inerter device's housing, rod and flywheel as rigid bodies whose poses are functions of
    the pose q, and their kinetic energy's terms in Eq. (33), written from the definitions.

    Each part is a rigid body of mass m, centre c(q) on the device's line (housing
    r_a + h_h u, flywheel r_a + h_f u, rod r_b − h_r u, u = r/|r|) and rotation R(q) (columns: two
    normals, then u), with inertia diag(I_t, I_t, J) in that frame: T = ½ m |ċ|² + ½ ωᵀ I ω,
    ω̃ = Ṙ Rᵀ. The housing's frame is the mount's definition: in 3D a Hooke joint at terminal a,
    first axis a₁ = A_a a̅₁ fixed in body a, second axis ŵ = a₁ × u/|a₁ × u| fixed in the housing,
    R_h = [ŵ, u × ŵ, u]; in 2D R_h = [ẑ, u × ẑ, u] (no spin about u). The rod is keyed to the
    housing (R_r = R_h); the flywheel turns on the screw, R_f = R_h R_z(n L). In 3D without a mount
    the device's spin is not modelled: only T = ½ m |ċ|² + ½ I_t |u̇|² (u(q) like a position). In a
    scene with gravity g each part has the potential −m g·c: Q += m c.gᵀ g.
    Every velocity is (Jet gradient)·v, so Kane's equations (Kane & Levinson 1985) give, with the
    partial velocities ∂ċ/∂v = c.g, ∂ω/∂v from Rg Rᵀ and the accelerations at v̇ = 0 (c.d2,
    α₀ = vee(R̈Rᵀ + ṘṘᵀ)): M += m c.gᵀc.g + ω_vᵀ I ω_v and Q −= m c.gᵀ c̈₀ + ω_vᵀ(I α₀ + ω × Iω). The
    ideal inerter's ½ b L̇² (b = J n², in the element already) is taken off, T_block = T − ½ b L̇²."""

    def __init__(self, device, dim, gravity=None):
        self.dim = dim
        self.gravity = np.zeros(3)
        if gravity is not None:
            self.gravity[:len(gravity)] = gravity
        fly, h, rod = (device.values(n) if device.has(n) else {} for n in ("flywheel", "housing", "rod"))
        self.mount = np.asarray(device.values("mount")["axis"], dtype=float) if device.has("mount") else None
        self.ratio = 0.0
        if fly:
            self.ratio = 2.0 * math.pi / fly["lead"] if fly.get("lead") is not None else fly["ratio"]
        self.b = (fly.get("inertia") or 0.0) * self.ratio ** 2
        spin = dim == 2 or self.mount is not None
        # (mass, end, signed distance, I_t, J, turns with the screw)
        self.bodies = [(h.get("mass") or 0.0, "a", h.get("centre") or 0.0, h.get("transverse_inertia") or 0.0,
                        h.get("axial_inertia") or 0.0, False),
                       (rod.get("mass") or 0.0, "b", -(rod.get("centre") or 0.0),
                        rod.get("transverse_inertia") or 0.0, rod.get("axial_inertia") or 0.0, False),
                       (fly.get("mass") or 0.0, "a", fly.get("centre") or 0.0, fly.get("transverse_inertia") or 0.0,
                        fly.get("inertia") or 0.0, True)]
        if not spin:                      # 3D without a mount: no spin, the ideal inerter's flywheel
            self.bodies = [(m, end, x, It, 0.0, False) for m, end, x, It, _, _ in self.bodies]
        self.spin = spin

    def _frame(self, coords, body_a, u, n):
        """R_h as 3 × 3 Jets (columns ŵ or ẑ, u × that, u)."""
        if self.dim == 2:
            e1 = [Jet.constant(0.0, n), Jet.constant(0.0, n), Jet.constant(1.0, n)]
        else:
            a1 = self._axis(coords, body_a, n)
            w = cross(a1, u)
            wn = jsqrt(dot(w, w))
            e1 = [c / wn for c in w]
        e2 = cross(u, e1)
        return [[e1[i], e2[i], u[i]] for i in range(3)]

    def _axis(self, coords, point_a, n):
        """a₁ = A_a a̅₁ on Jets (:func:`~inerter.oracle.jets.rotation` of body a)."""
        if point_a.body < 0:
            return [Jet.constant(x, n) for x in self.mount]
        return times(rotation(coords[point_a.body]), self.mount)

    def terms(self, probe, q, v, frame_acc=None):
        """(M block, Q block, energy: kinetic T − ½ b L̇² and the parts' weight's potential −Σ m g·c)
        over the probe's dofs; frame_acc: the ground's acceleration a_g, under which each part's
        absolute acceleration is c̈ + a_g (coordinates relative to the ground)."""
        field = self.gravity.copy()
        if frame_acc is not None:
            field[:len(frame_acc)] -= frame_acc
        coords, ra, rb = probe.terminals(q, v)
        n = len(probe.dofs)
        if self.dim == 2:
            ra, rb = ra + [Jet.constant(0.0, n)], rb + [Jet.constant(0.0, n)]
        r = [b - a for a, b in zip(ra, rb)]
        L = jsqrt(dot(r, r))
        u = [c / L for c in r]
        M, Q, T = np.zeros((n, n)), np.zeros(n), 0.0
        R = self._frame(coords, probe.pair.a, u, n) if self.spin else None
        for m, end, x, It, J, turns in self.bodies:
            c = [p + x * e for p, e in zip(ra if end == "a" else rb, u)]
            cv, cd, cdd, cg = parts(c)
            M += m * cg.T @ cg
            Q -= m * cg.T @ (cdd - field)                       # inertia (absolute) and weight
            T += 0.5 * m * float(cd @ cd) - m * float(self.gravity @ cv)
            if self.spin:
                Rb = R
                if turns:
                    psi = L * self.ratio
                    cz, sz = jcos(psi), jsin(psi)
                    Rb = [[row[0] * cz + row[1] * sz, row[1] * cz - row[0] * sz, row[2]] for row in R]
                dM, dQ, dT = self._rotation(Rb, np.diag((It, It, J)))
            else:
                dM, dQ, dT = self._transverse(u, It)
            M, Q, T = M + dM, Q + dQ, T + dT
        if not self.spin:
            return M, Q, T
        M -= self.b * np.outer(L.g, L.g)            # the ideal inerter's ½ b L̇², in the element already
        Q += self.b * L.d2 * L.g
        return M, Q, T - 0.5 * self.b * L.d1 ** 2

    @staticmethod
    def _rotation(R, inertia):
        Rv, w, wg, alpha0 = angular_velocity(R)
        I = Rv @ inertia @ Rv.T
        M = wg.T @ I @ wg
        Q = -wg.T @ (I @ alpha0 + np.cross(w, I @ w))
        return M, Q, 0.5 * float(w @ I @ w)

    @staticmethod
    def _transverse(u, It):
        _, ud, udd, ug = parts(u)
        return It * ug.T @ ug, -It * ug.T @ udd, 0.5 * It * float(ud @ ud)


class OracleElement:
    """Spring, damper or inerter (with its device, :class:`OracleDevice`) through L(q) and its
    derivatives. As the mechanism's element factory it builds the rotational elements too, planar
    (:attr:`rotational`) and 3D (:attr:`spatial_rotational`)."""

    #: The factory of planar rotational elements, ``rotational(spec, index_a, index_b, free_angle)``.
    rotational = OracleRotational
    #: The factory of 3D rotational elements, ``spatial_rotational(spec, frame_a, frame_b, q0)``.
    spatial_rotational = OracleSpatialRotational

    def __init__(self, spec, pair, centripetal, free_length, labels, mech):
        error = undefined_kind(spec, mech.scene.source)
        if error is not None:
            raise error
        self.name = spec.name
        self.kind = spec.type
        self.device = (OracleDevice(spec.device, mech.scene.source, spec.name)
                       if getattr(spec, "device", None) is not None else None)
        from_device = self.device.inertance() if self.device is not None else None
        self.coefficient = float(spec.coefficient) if from_device is None else from_device
        self.coefficient_name = _TRANSLATIONAL_KINDS[spec.type]
        self.centripetal = bool(centripetal)
        self.free_length = free_length
        direction = None
        if spec.type == "inerter" and mech.scene.small_displacement:
            # the small-displacement law: s = ê0·r, ê0 the direction at the scene's pose; F = b s̈
            r0 = np.subtract(position(mech.initial_q, pair.b), position(mech.initial_q, pair.a))
            direction = r0 / np.linalg.norm(r0)
            self.centripetal = True                     # F = b s̈ as it is: no |ṙ⊥|²/L to remove
        self.fixed_direction = direction
        self.probe = DistanceProbe(pair, labels, spec.name, mech, direction, getattr(spec, "slider_axis", None))
        self.pair = pair
        dev = getattr(spec, "device", None)
        self.bodies = (DeviceBodies(dev, mech.dim, mech.scene.effects.get("gravity"))
                       if dev is not None and dev.inertia() else None)
        #: The series connection (in the device), or None; the count of the element's states in z
        #: (the mechanism sets its slice, ``states``): (s, ṡ) in series, then the dissipated energy.
        self.series = self.device.series if self.device is not None else None
        self.n_states = self.device.n_states if self.device is not None else 0
        self.states = slice(0, 0)
        #: The screw efficiency (:mod:`.efficiency`), or None, and its mode σ = sign of the screw's
        #: stroke acceleration (L̈, or ü in series), which the mechanism's solve sets
        #: (:func:`.efficiency.resolve`).
        self.efficiency = self.device.efficiency if self.device is not None else None
        self.mode = 1.0

    def efficient(self) -> bool:
        """Whether it has a screw efficiency on its terminal distance (rigid: its b_eff is in the mass
        matrix; in series the efficiency acts on the inerter's own stroke, a coordinate of its own)."""
        return self.efficiency is not None and self.series is None

    def b_eff(self, rate):
        """b_eff = b (1 + λ(τ)) at the screw's stroke rate in the mode set; b without an efficiency,
        or with no mode set (None: the ideal inerter's term, which each mode scales)."""
        if self.efficiency is None or self.mode is None:
            return self.coefficient
        return self.coefficient * self.efficiency.factor(self.mode, rate)

    def _rest(self, L, rdot):
        """L̈ at q̈ = 0 under the scene's law: q̇ᵀ∇²Lq̇ (Eq. 9), less |ṙ⊥|²/L without the
        centripetal term (F = b r̈·r̂, Eq. 8)."""
        rest = L.d2                                             # q̇ᵀ∇²Lq̇: L̈ = ∇L·q̈ + this
        if not self.centripetal:
            rest -= (float(rdot @ rdot) - L.d1 * L.d1) / L.v    # remove |ṙ⊥|²/L: F = b r̈·r̂ (Eq. 8)
        return rest

    def _force_parts(self, L, rdot):
        """F = a·q̈ part (gradient factor) + the rest: returns (mass factor, rest). In series the
        inerter acts through the connection (:meth:`extended`): none here."""
        b = self.coefficient
        if self.kind == "spring":
            return 0.0, b * (L.v - self.free_length)            # Eq. (5)
        if self.kind == "damper":
            return 0.0, b * L.d1                                # c dL/dt, Eq. (6)
        if self.series is not None:
            return 0.0, 0.0
        b = self.b_eff(L.d1)                                    # b_eff with a screw efficiency
        return b, b * self._rest(L, rdot)

    def _x(self, z):
        """Its internal states in z (zero where z is not given)."""
        return np.zeros(self.n_states) if z is None else np.asarray(z[self.states], dtype=float)

    def stroke(self, q, v, z):
        """The inerter's own stroke u = L − s as a Jet over (its dofs, ṡ): u̇ = gᵀv − ṡ, its
        gradient γ = [g; −1], its second derivative at v̇ = 0, s̈ = 0 that of L under the law."""
        L, rdot = self.probe.evaluate(q, v)
        s, sdot = self._x(z)[:2]
        return Jet(L.v - s, L.d1 - sdot, self._rest(L, rdot), np.append(L.g, -1.0))

    def extended(self, q, v, z):
        """(mass block, generalised force) of the series connection over (its dofs, s), from the
        extended Lagrangian of :mod:`.series`: T_I = ½ b u̇² gives b γγᵀ and −b ü₀ γ; R's D(u̇)
        −∂D/∂(v, ṡ) (D on the Jet of u̇, gradient γ); V and R's c_c ṡ² the −F on s. A screw
        efficiency scales T_I's terms by 1 + λ(τ) (τ of u̇ and the mode set)."""
        u = self.stroke(q, v, z)
        b = self.b_eff(u.d1)                                    # b_eff on u̇ with a screw efficiency
        M = b * np.outer(u.g, u.g)
        Q = -b * u.d2 * u.g
        D = self.device.dissipation(Jet(u.d1, 0.0, 0.0, u.g))
        if isinstance(D, Jet):
            Q -= D.g
        x = self._x(z)
        Q[-1] -= self.series.force(x[0], x[1])[0]              # −∂V/∂s − ∂R/∂ṡ, clipped (unilateral)
        return M, Q

    def series_acceleration(self, q, v, z, a):
        """s̈ at the accelerations `a` from the s row of its extended system (:meth:`extended`),
        (b_eff) s̈ − (b_eff) gᵀv̇ = Q_s, in the mode set."""
        Me, Qe = self.extended(q, v, z)
        return (Qe[-1] - Me[-1, :-1] @ a[self.probe.dofs]) / Me[-1, -1]

    def stroke_acceleration(self, q, v, z, a, sdd=0.0):
        """The screw's stroke acceleration at the accelerations `a` (and s̈ = `sdd` in series):
        L̈ = ∇L·q̈ + q̇ᵀ∇²Lq̇ (Eq. 9; Eq. 8's less |ṙ⊥|²/L), or ü = L̈ − s̈."""
        G, x0, _ = self.screw_term(q, v, z)
        accel = float(G[:len(self.probe.dofs)] @ a[self.probe.dofs]) + x0
        return accel - sdd if self.series is not None else accel

    def screw_term(self, q, v, z):
        """(G, ẍ₀, ẋ): the gradient of the screw's stroke rate ẋ over the velocities it touches (∇L,
        or γ = [∇L; −1] over (its dofs, ṡ) in series), its stroke acceleration at zero accelerations
        (:meth:`_rest`, or ü₀), and ẋ: its ideal inerter's term is b G Gᵀ in the mass matrix and
        −b ẍ₀ G in the forces, the term a screw efficiency scales by 1 + λ(τ)."""
        if self.series is not None:
            u = self.stroke(q, v, z)
            return u.g, u.d2, u.d1
        L, rdot = self.probe.evaluate(q, v)
        return L.g, self._rest(L, rdot), L.d1

    def screw(self, q, v, z, a, sdd=0.0):
        """(b λ(τ) ẍ ẋ, τ): the screw efficiency's lost power and direction in the mode set, at the
        accelerations `a` (s̈ = `sdd` in series); (0, 1) without an efficiency."""
        if self.efficiency is None:
            return 0.0, 1.0
        rate, accel = self.screw_term(q, v, z)[2], self.stroke_acceleration(q, v, z, a, sdd)
        return (self.efficiency.loss(self.coefficient, self.mode, rate, accel),
                self.efficiency.direction(self.mode, rate))

    def state_rates(self, q, v, z, a, sdd, dz):
        """dz[its states]: (ṡ, s̈) in series (s̈ from the extended system, `sdd`), then ż = p_loss
        (with the screw efficiency's loss at the accelerations `a`)."""
        x = self._x(z)
        out = []
        if self.series is not None:
            out += [x[1], sdd]
        if self.device.keeps_loss:
            L, _ = self.probe.evaluate(q, v)
            out.append(self.device.loss(L.v, L.d1, x, self.screw(q, v, z, a, sdd)[0]))
        dz[self.states] = out

    def state_energy(self, q, v, z):
        """In series: ½ b u̇² and the connection's V (the element's ½ b L̇² is then left out)."""
        if self.series is None:
            return 0.0
        u = self.stroke(q, v, z)
        return 0.5 * self.coefficient * u.d1 ** 2 + self.series.potential(self._x(z)[0])

    def geometry(self, q, v):
        return self.probe.evaluate(q, v)

    def add_mass(self, q, v, M, geo=None):
        if self.kind != "inerter":
            return
        L, _ = geo or self.probe.evaluate(q, v)
        idx = self.probe.dofs
        if self.series is None:
            M[np.ix_(idx, idx)] += self.b_eff(L.d1) * np.outer(L.g, L.g)
        if self.bodies is not None:
            M[np.ix_(idx, idx)] += self.bodies.terms(self.probe, q, v)[0]

    def add_force(self, q, v, Q, geo=None):
        L, rdot = geo or self.probe.evaluate(q, v)
        _, rest = self._force_parts(L, rdot)
        Q[self.probe.dofs] -= rest * L.g                        # Q = −F ∇L
        if self.device is not None:
            self.device.add_force(L, Q, self.probe.dofs)
        if self.bodies is not None:
            Q[self.probe.dofs] += self.bodies.terms(self.probe, q, v)[1]

    def outputs(self, q, v, a, z=None):
        """(distance, dL/dt, F, power, stored energy), then a device's outputs. The power is the
        force times dL/dt, the rate of the work it takes from the bodies (−Q·q̇ with Q = −F∇L);
        the stored energy is this element's T + V (:meth:`kinetic`, :meth:`potential`, and its
        internal states' :meth:`state_energy`). In series F is the connection's force."""
        L, rdot = self.probe.evaluate(q, v)
        mass, rest = self._force_parts(L, rdot)
        F = rest + (mass * float(L.g @ a[self.probe.dofs]) if mass else 0.0)   # (no q̈ where no inerter)
        distance = L.v if self.fixed_direction is None else self.probe.distance(q)
        stored = self.kinetic(q, v) + self.potential(q) + (self.state_energy(q, v, z) if self.n_states else 0.0)
        if self.device is None:
            return distance, L.d1, F, F * L.d1, stored
        x = self._x(z)
        F += self.device.force(L.v, L.d1, x)
        screw = (0.0, 1.0)
        if self.efficiency is not None:
            sdd = self.series_acceleration(q, v, z, a) if self.series is not None else 0.0
            screw = self.screw(q, v, z, a, sdd)
        return (distance, L.d1, F, F * L.d1, stored) + self.device.outputs(L.v, L.d1, x, screw)

    def length(self, q):
        return self.probe.evaluate(q, np.zeros_like(q))[0].v

    def add_frame_force(self, q, v, Q, frame_acc):
        """Q += the device parts' inertial force under a ground motion, −Σ m (∂c/∂q)ᵀ a_g."""
        if self.bodies is not None:
            Q[self.probe.dofs] += (self.bodies.terms(self.probe, q, v, frame_acc)[1]
                                   - self.bodies.terms(self.probe, q, v)[1])

    def kinetic(self, q, v):
        """½ b L̇² (none in series: the inerter's ½ b u̇² is in :meth:`state_energy`) and a
        device's parts' kinetic and gravitational energy."""
        if self.kind != "inerter":
            return 0.0
        T = 0.0 if self.series is not None else 0.5 * self.coefficient * self.probe.evaluate(q, v)[0].d1 ** 2
        return T if self.bodies is None else T + self.bodies.terms(self.probe, q, v)[2]

    def potential(self, q):
        if self.device is not None:
            return self.device.potential(self.length(q))
        if self.kind != "spring":
            return 0.0
        return 0.5 * self.coefficient * (self.length(q) - self.free_length) ** 2
