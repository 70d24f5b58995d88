"""The compiled mechanism: a validated scene turned into flat arrays, index maps and term objects.

Only what the scene declares is compiled in: a scene without gravity has no gravity term, a scene
without inerters no inerter term, and so on. :meth:`Mechanism.terms` lists what was compiled.

Coordinates q (positions and orientations, `nq` of them) and velocity coordinates v (`n` of them:
Ṙ and θ̇ per planar body, Ṙ and the body-frame ω per spatial body). The equations of motion are
the augmented form of Eq. (33),

    [M + M_I  C_vᵀ] [v̇]   [Q_e + Q_Iv]
    [C_v      0   ] [λ] = [γ − 2α Ċ − α² C]

with Baumgarte stabilisation of the constraints (α in 1/s; α = 0 gives the plain Eq. 33), and
q̇ = B(q) v (the identity in 2D; the quaternion or Euler-angle rates in 3D).
"""
from __future__ import annotations

import contextlib
import copy
import math

import numpy as np

from inerter.model import evaluators as el
from inerter import elements
from inerter.elements import kinematics, layout, terminals
from inerter.elements import winding
from inerter.elements.device import MODE_SOLVES
from inerter.common.errors import SceneError, SimulationError
from inerter.model.joints import make_joint
from inerter.model.planar import PointKinematics, PointPair
from inerter.scene.reader import GROUND, Scene
from inerter.scene.units import for_reading
from inerter.model.spatial import EULER_SINGULARITY, Orientation, RotationCache, SpatialPoint

# the kernels' laws, run uncompiled
_gyroscopic = kinematics.gyroscopic.py_func
_pd_magnitude = kinematics.pd_magnitude.py_func
_frame_force = kinematics.frame_force.py_func
_planar_body_energy = kinematics.planar_body_energy.py_func
_spatial_body_energy = kinematics.spatial_body_energy.py_func
_chord_approach = terminals.chord_approach.py_func
_carried = winding.carried.py_func


def _in_3d(r):
    """A 2D or 3D vector as three floats (z = 0 in 2D)."""
    return (float(r[0]), float(r[1]), float(r[2]) if len(r) > 2 else 0.0)


#: How far an initial pose may violate a joint before it is rejected rather than assembled (m or rad).
ASSEMBLY_TOLERANCE = 1e-6

#: The augmented matrix [[M + M_I, C_vᵀ], [C_v, 0]] counts as singular at t = 0 when its smallest
#: singular value is below this fraction of its largest.
SINGULAR_RATIO = 1e-14
#: A body's principal moment of inertia at or below this fraction of its largest counts as zero
#: (:meth:`Mechanism.check_free_spins`).
FREE_SPIN_RATIO = 1e-12
#: A body's spin counts as held by its joints where it moves their constraint rows C_v by more
#: than this fraction of ‖C_v‖ (a joint's point off the spin axis by more than that, relative).
HELD_RATIO = 1e-9
#: A run that stops where the joints' C_v has a smallest singular value below this fraction of its largest
#: names them as nearly dependent (:meth:`Mechanism.diagnose`).
DEPENDENT_RATIO = 1e-4

#: A device's Hooke mount (inerter.elements.device_inertia, "The mount") is refused at t = 0 where
#: the sine of the angle between its first axis a₁ and the device's axis is below this: its spin
#: divides by that sine, and the housing's frame is undefined where it is 0.
MOUNT_SINGULAR = 1e-6

#: A run that stops names a device mount whose axis is within this sine (about 3°) of the device's:
#: its spin and the mass-matrix block grow as 1/sine² there, which the integrator cannot follow.
MOUNT_NEAR = 0.05

#: A translational element's terminals count as meeting when, within an integrator step, they come
#: closer than this fraction of the element's initial length (or MIN_LENGTH, whichever is larger):
#: its direction is then lost in round-off, and an adaptive integrator would shrink its step there
#: without end.
MEET_RELATIVE = 1e-6


#: What a state whose accelerations cannot be evaluated says (the system solve not finite, or the
#: elements' geometry overflowing to NaN on a huge but finite state), as the kernels' NOT_FINITE.
_NOT_FINITE = "accelerations are not finite (the system matrix is near-singular or a force is unbounded)"


class TimeFunction:
    """A point force's magnitude as a function of time (constant, sine, step) or a held input."""

    def __init__(self, force):
        self.force = force

    def static_value(self) -> float:
        """The load's static part (for the static equilibrium): constant, sine offset, step start."""
        f = self.force
        return {"constant": f.value, "sine": f.offset, "step": f.initial}.get(f.function, 0.0)

    def __call__(self, t: float) -> float:
        f = self.force
        if f.function == "constant":
            return f.value
        if f.function == "sine":
            return f.offset + f.amplitude * math.sin(2.0 * math.pi * f.frequency * t + f.phase)
        if f.function == "step":
            return f.value if t >= f.time else f.initial
        raise AssertionError(f.function)


class BodyFrame:
    """A body's rotation matrix and body-frame angular velocity (identity and zero for the ground)."""

    __slots__ = ("body", "qi", "vi", "orientation", "dim")

    def __init__(self, body, qi, vi, orientation, dim):
        self.body, self.qi, self.vi, self.orientation, self.dim = body, qi, vi, orientation, dim

    def evaluate(self, q, v):
        if self.body < 0:
            return np.eye(self.dim), np.zeros(3)
        o = self.orientation
        return o.matrix(q[self.qi + 3:self.qi + 3 + o.size]), v[self.vi + 3:self.vi + 6]


@contextlib.contextmanager
def wound_from(holder, start=None):
    """`holder.windings` (the φ_ref of its 3D rotational elements: a :class:`Mechanism`'s evaluators,
    the engine kernel's table column) at 0, their value at t = 0, or at `start` (the angles where a
    history starts), while a history is evaluated sample after sample from there, each sample
    winding on; as they were afterwards."""
    held = np.array(holder.windings, dtype=float)
    if not held.size:                  # none (2D, or no 3D rotational element): nothing to wind
        yield
        return
    holder.windings = np.zeros(len(held)) if start is None else start
    try:
        yield
    finally:
        holder.windings = held


def rank_kept(rows) -> bool:
    """Whether the joints' constraint rows `rows` (C_v) keep full rank: the smallest singular value
    above DEPENDENT_RATIO of the largest (below it, a change point: :meth:`Mechanism._dependent_joints`
    names the joints, ``simulation.StepMonitor`` stops a run there)."""
    sv = np.linalg.svd(rows, compute_uv=False)
    return bool(sv[-1] > DEPENDENT_RATIO * sv[0])


class Mechanism:
    """A scene compiled for simulation. `element_factory`, where given, builds the translational
    elements instead of :mod:`inerter.model.evaluators`: the oracle (:mod:`inerter.oracle`) passes
    its own, which differentiates each element's terminal distance L(q) instead of Eqs. (15–20),
    with the signature ``factory(spec, pair, centripetal, free_length, labels, mechanism)``. Where
    the factory has an attribute ``rotational``, the planar rotational elements are built by it,
    ``factory.rotational(spec, angle_index_a, angle_index_b, free_angle)``, and where it has
    ``spatial_rotational``, the 3D ones, ``factory.spatial_rotational(spec, frame_a, frame_b, q0)``
    (each with the evaluators' ``reference`` and ``wind``)."""

    def __init__(self, scene: Scene, element_factory=None):
        self.scene = scene
        self.element_factory = element_factory
        self.oracle = element_factory is not None
        self.dim = scene.dimension
        self.body_names = list(scene.bodies)
        self.body_index = {n: i for i, n in enumerate(self.body_names)}
        self.orientation = Orientation(scene.orientation) if self.dim == 3 else None
        q0, v0 = self._bodies(scene)
        self.point_names = list(scene.points)
        self._rotation_caches = [RotationCache() for _ in self.body_names]
        self.points = {p.name: self._point(p) for p in scene.points.values()}
        self.joints = [make_joint(j, self, q0) for j in scene.joints.values()]
        self.m = sum(j.rows for j in self.joints)
        #: The scene's pose the elements are built at (an element factory reads initial directions here).
        self.initial_q = np.array(q0, dtype=float)
        self.elements = [self._element(e, q0) for e in scene.elements.values()]
        self.inerters = [e for e in self.elements if e.kind == "inerter"]
        #: The 3D rotational elements, whose angles wind on from the last accepted step (:meth:`wind`).
        self.winding = [e for e in self.elements if hasattr(e, "wind")]
        #: The elements with a screw efficiency, whose modes each solve settles (:meth:`accelerations`).
        self.efficient = [e for e in self.inerters if getattr(e, "efficient", None) is not None and e.efficient()]
        # Elements on the same pair of terminals share one evaluation of the pair's geometry (one
        # acting along a fixed direction has geometry of its own).
        groups = {}
        for spec, e in zip(scene.elements.values(), self.elements):
            fixed = getattr(e, "fixed_direction", None) is not None
            if spec.slider_axis is not None:        # along a joint's axis: geometry of its own, no meeting
                key = (None, spec.name)
            else:
                key = (spec.point_a, spec.point_b, fixed) if spec.point_a else ("rotational", spec.name)
            groups.setdefault(key, []).append(e)
        self.groups = list(groups.values())
        self._forces(scene)
        self._effects(scene)
        self.q0, self.v0 = self.assemble_initial(q0, v0)
        #: The elements' internal states at t = 0 (an inerter device's series deflection and its rate,
        #: its dissipated energy; :meth:`inerter.elements.device.Device.states`), all zero: the
        #: compiled engine integrates them (y = [q, v, z]); empty for most scenes.
        self.z0 = np.zeros(sum(len(e.device.states()) for e in scene.elements.values()
                               if getattr(e, "device", None) is not None))
        self.stateful = []                  # the elements with internal states, each its slice of z
        offset = 0
        for e in self.elements:
            count = getattr(e, "n_states", 0)
            if count:
                e.states = slice(offset, offset + count)
                self.stateful.append(e)
                offset += count
        if offset != len(self.z0):          # an element factory (the oracle) without internal states
            raise SceneError(scene.source, "elements", None, "elements whose internal states this model "
                             "derives", "internal states not derived")
        self._meet_limits(groups)
        self.check_mounts(self.q0)
        self.check_free_spins(self.q0)
        self.check_mass_matrix(self.q0, self.v0)

    def _bodies(self, scene):
        """The coordinate layout (per body q = [R, θ] in 2D or [R, orientation] in 3D; v = [Ṙ, θ̇]
        or [Ṙ, ω]), the constant mass matrix M0, the body frames and the initial (q0, v0) as the
        scene gives them (before assembly)."""
        dim = self.dim
        nqb = 3 if dim == 2 else 3 + self.orientation.size
        nvb = 3 if dim == 2 else 6
        self.q_index = [nqb * i for i in range(len(self.body_names))]
        self.v_index = [nvb * i for i in range(len(self.body_names))]
        self.nq = nqb * len(self.body_names)
        self.n = nvb * len(self.body_names)
        self.M0 = np.zeros((self.n, self.n))
        q0, v0 = [], []
        self.inertia_body = []
        self._inertia9 = []
        for i, b in enumerate(scene.bodies.values()):
            k = self.v_index[i]
            self.M0[k:k + dim, k:k + dim] = b.mass * np.eye(dim)
            if dim == 2:
                self.M0[k + 2, k + 2] = b.inertia
                q0 += [*b.position, b.angle]
                v0 += [*b.velocity, b.angular_velocity]
            else:
                J = np.array(b.inertia)
                self.M0[k + 3:k + 6, k + 3:k + 6] = J
                self.inertia_body.append(J)
                self._inertia9.append(tuple(J.ravel().tolist()))
                A = np.array(b.rotation)
                q0 += [*b.position, *self.orientation.from_matrix(A)]
                v0 += [*b.velocity, *(A.T @ np.array(b.angular_velocity))]   # ω to the body frame
        self.frames = {GROUND: BodyFrame(-1, 0, 0, None, dim)}
        for name in self.body_names:
            i = self.body_index[name]
            self.frames[name] = BodyFrame(i, self.q_index[i], self.v_index[i], self.orientation, dim)
        return np.array(q0, dtype=float), np.array(v0, dtype=float)

    def _forces(self, scene):
        """Point forces: applied with a time function, PD actuators, and held inputs."""
        self.applied = [(f, self.points[f.point], TimeFunction(f)) for f in scene.forces.values()
                        if f.function not in ("input", "pd")]
        self.feedback = [(f, self.points[f.point]) for f in scene.forces.values() if f.function == "pd"]
        self.input_forces = [(f, self.points[f.point]) for f in scene.forces.values() if f.function == "input"]
        self.input_names = [f"{f.point}.f[{i + 1}]" for f, _ in self.input_forces for i in range(self.dim)]

    def _effects(self, scene):
        """Gravity and the ground motion where declared, and the times where the right-hand side is
        not smooth."""
        dim = self.dim
        switches = {f.time for f in scene.forces.values() if f.function == "step" and f.time > 0}
        g = scene.effects.get("gravity")
        self.gravity = None
        if g is not None and any(g):
            self.gravity = np.zeros(self.n)
            for i, b in enumerate(scene.bodies.values()):
                self.gravity[self.v_index[i]:self.v_index[i] + dim] = b.mass * np.asarray(g)
        self.masses = np.array([b.mass for b in scene.bodies.values()])
        self.ground_motion = scene.effects.get("ground_acceleration")
        kinks, record_jumps = self.ground_motion.breaks() if self.ground_motion is not None else ([], [])
        switches.update(record_jumps)
        #: Times where the right-hand side jumps (a step force switches; a ground record ends on a
        #: value other than zero, the motion being zero outside it): the integrators restart there
        #: (module simulation), with the forces of the segment before up to it.
        self.discontinuities = sorted(switches)
        #: Times where the right-hand side is continuous but its slope jumps (a ground record's
        #: samples: it is interpolated linearly). No step may straddle one, or the methods lose
        #: their order; but the state, its derivative and the step size the error control
        #: proposes are still valid there, so the explicit Runge-Kutta methods run on through a
        #: kink, their step clipped to end on it, and the others restart there as at a jump
        #: (:func:`inerter.engine.simulation.jumps`). A time here that is also in
        #: ``discontinuities`` is a jump.
        self.kinks = sorted(set(kinks) - switches)
        if self.ground_motion is not None and self.ground_motion.input:
            self.input_names += [f"ground.a[{i + 1}]" for i in range(dim)]

    def _meet_limits(self, groups):
        """Translational elements by terminal pair, with the distance below which the terminals
        meet (also by element name, for the compiled kernels: meet_limit)."""
        self._meet = []
        self.meet_limit = {}
        checked = {}
        for spec, group in zip(groups, self.groups):
            if not elements.translational(group[0].kind) or spec[0] is None:
                continue
            terminals = spec[:2]
            if terminals in checked:              # the same terminals, in a group of its own
                checked[terminals][1].extend(e.name for e in group)
                self.meet_limit.update((e.name, checked[terminals][3]) for e in group)
                continue
            pair = self.pair(*terminals)
            r0 = pair.evaluate(self.q0, np.zeros(self.n))[0]
            limit = max(el.MIN_LENGTH, MEET_RELATIVE * math.sqrt(float(r0 @ r0)))
            checked[terminals] = (pair, [e.name for e in group], terminals, limit)
            self._meet.append(checked[terminals])
            self.meet_limit.update((e.name, limit) for e in group)

    # -- compilation helpers ---------------------------------------------------------------
    def _body(self, name):
        return -1 if name == GROUND else self.body_index[name]

    def _point(self, p):
        i = self._body(p.body)
        if self.dim == 2:
            return PointKinematics(i, p.local, self.q_index[i] if i >= 0 else 0, self.v_index[i] if i >= 0 else 0)
        return SpatialPoint(i, p.local, self.q_index[i] if i >= 0 else 0, self.v_index[i] if i >= 0 else 0,
                            self.orientation, self._rotation_caches[i] if i >= 0 else None)

    def angle_index(self, body_name):
        """Velocity index of a planar body's angle (−1 for the ground)."""
        i = self._body(body_name)
        return self.v_index[i] + 2 if i >= 0 else -1

    def pair(self, a, b):
        return PointPair(self.points[a], self.points[b])

    def _element(self, e, q0):
        """The evaluator of scene element `e`. A kind with a free length (or angle) that the scene
        leaves out takes the distance (or relative angle) at t = 0."""
        has_free = elements.KINDS[e.type].free is not None
        if not elements.translational(e.type):
            if self.dim == 3:
                build = getattr(self.element_factory, "spatial_rotational", el.SpatialRotationalElement)
                return build(e, self.frames[e.body_a], self.frames[e.body_b], q0)
            ia, ib = self.angle_index(e.body_a), self.angle_index(e.body_b)
            phi0 = e.free_length if has_free else 0.0
            if phi0 is None:
                phi0 = (q0[ib] if ib >= 0 else 0.0) - (q0[ia] if ia >= 0 else 0.0)
            rotational = getattr(self.element_factory, "rotational", None)
            if rotational is not None:
                return rotational(e, ia, ib, phi0)
            return el.RotationalElement(e.name, e.type, ia, ib, e.coefficient, phi0)
        pair = self.pair(e.point_a, e.point_b)
        labels = (e.point_a, e.point_b)
        if e.slider_axis is not None:       # a prismatic joint's: L is the slide, its free value the initial one
            r0 = pair.evaluate(q0, np.zeros(self.n))[0]
            L_initial = float(r0 @ el.slider_direction(pair.a, np.asarray(e.slider_axis, dtype=float), q0))
        else:
            L_initial = self._initial_length(e, pair, q0)
        free = (e.free_length if e.free_length is not None else L_initial) if has_free else None
        if self.element_factory is not None:
            return self.element_factory(e, pair, self.scene.centripetal, free, labels, self)
        fixed = None
        if e.type == "inerter" and self.scene.small_displacement:     # along r̂ at t = 0
            r0 = pair.evaluate(q0, np.zeros(self.n))[0]
            fixed = r0 / L_initial
        out = el.TranslationalElement(e.name, e.type, pair, e.coefficient, labels, free, self.scene.centripetal,
                                      device=e.device, fixed_direction=fixed, slider_axis=e.slider_axis)
        g = self.scene.effects.get("gravity")
        if e.device is not None and e.device.inertia() and g is not None:     # the weight of its masses
            out.row[layout.DEVICE_GRAVITY:layout.DEVICE_GRAVITY + len(g)] = g
        return out

    def _initial_length(self, e, pair, q0):
        r, _, _, _ = pair.evaluate(q0, np.zeros(self.n))
        length = math.sqrt(float(r @ r))
        if not length > el.MIN_LENGTH:
            raise SceneError(self.scene.source, f"elements.{e.name}.between", [e.point_a, e.point_b],
                             f"terminals at least {el.MIN_LENGTH:g} m apart at t = 0",
                             f"coincident terminals at t = 0 (distance {length:.3g} m): the element's "
                             "direction is undefined")
        return length

    # -- coordinates -------------------------------------------------------------------------
    def qdot(self, q, v, t=None):
        """q̇ = B(q) v."""
        if self.dim == 2:
            return v
        out = np.empty(self.nq)
        o = self.orientation
        for i, name in enumerate(self.body_names):
            k, j = self.q_index[i], self.v_index[i]
            out[k:k + 3] = v[j:j + 3]
            out[k + 3:k + 3 + o.size] = o.rate(q[k + 3:k + 3 + o.size], v[j + 3:j + 6], name, t)
        return out

    def retract(self, q, dv):
        """The coordinates moved by a small displacement dv given in velocity coordinates."""
        if self.dim == 2:
            return q + dv
        q = q.copy()
        o = self.orientation
        for i in range(len(self.body_names)):
            k, j = self.q_index[i], self.v_index[i]
            q[k:k + 3] += dv[j:j + 3]
            q[k + 3:k + 3 + o.size] = o.retract(q[k + 3:k + 3 + o.size], dv[j + 3:j + 6])
        return q

    def check_step(self, q_old, q_new, t, t_old=None):
        """After each accepted step: Z-X-Z Euler angles must not pass through their singularity
        (sin θ = 0) within a step: the rates there are undefined and the result past it would be
        garbage. (Terminals that meet within a step: :meth:`chord_margin`, which the integrator's
        watch reads first, to stop at the meeting, ``simulation.StepMonitor``.)"""
        if self.dim != 3 or self.orientation.kind != "euler_zxz":
            return
        for i, name in enumerate(self.body_names):
            k = self.q_index[i] + 4                              # θ of (φ, θ, ψ)
            s0, s1 = math.sin(q_old[k]), math.sin(q_new[k])
            if s0 * s1 <= 0.0 or abs(s1) < EULER_SINGULARITY:
                raise SimulationError(
                    f"body '{name}': its Z-X-Z Euler angles pass through their singularity (gimbal lock: "
                    f"sin θ goes from {s0:.3g} to {s1:.3g} in the step"
                    + (f" from t = {t_old:.6g} s" if t_old is not None else "") + "), where the angle rates are "
                    "undefined; use orientation = \"quaternion\" (the default)", t)

    def wind(self, y, y_old=None, h=0.0):
        """After an accepted step of length h from y_old to the state y = [q, v, z] (or at each
        sample of a history, in time order from t = 0, without y_old): each 3D rotational element's
        φ_ref moves on to its angle there, so that its angle winds on past half a turn
        (inerter.elements.winding); nothing in 2D. After a step, the angle is read on the branch
        nearest φ_ref + h (φ̇(y_old) + φ̇(y))/2, where the rates carry it, so that a step turning it
        by more than half a turn winds it on too (kernels.wind3_step)."""
        n, nv = self.nq, self.nq + self.n
        for e in self.winding:
            if y_old is not None:
                e.reference = _carried(e.reference, h, e.rate(y_old[:n], y_old[n:nv]), e.rate(y[:n], y[n:nv]))
            e.wind(y[:n])

    def angles_between(self, times0, states0, windings0, times, states) -> np.ndarray:
        """(rows × elements) each 3D rotational element's angle at each row of `states` (at `times`),
        on the branch its integration followed, from the row of `states0` (at `times0`: an end of
        the step that gives the time) where the integrator held φ_ref = `windings0`: the branch
        the rates at both carry the angle to (:meth:`wind`); φ_ref as it was afterwards."""
        out = np.empty((len(states), len(self.winding)))
        with self.wound_from_start():
            for i in range(len(states)):
                self.windings = windings0[i]
                self.wind(states[i], states0[i], times[i] - times0[i])
                out[i] = self.windings
        return out

    @property
    def windings(self) -> np.ndarray:
        """The 3D rotational elements' φ_ref (0 at t = 0), in the order of :attr:`winding`."""
        return np.array([e.reference for e in self.winding], dtype=float)

    @windings.setter
    def windings(self, values):
        for e, value in zip(self.winding, values, strict=True):
            e.reference = float(value)

    def reset_windings(self):
        """φ_ref at 0, its value at t = 0 (a run's start)."""
        for e in self.winding:
            e.reference = 0.0

    def wound_from_start(self, start=None):
        """φ_ref at 0, its value at t = 0 (or at `start`), while a history is evaluated from there
        (:func:`wound_from`)."""
        return wound_from(self, start)

    def for_run(self) -> "Mechanism":
        """A copy of this mechanism that owns what a run or a co-simulation stepper changes as it
        goes, at its value at t = 0: the 3D rotational elements' φ_ref (:meth:`wind`: 0), the screw
        efficiencies' modes (:meth:`accelerations`: +1, as loaded), and the caches keyed on the
        state (each body's rotation matrix; the oracle's derivatives). The mechanism itself is left
        as it was, so that two runs or steppers of one model (two FMU instances of one scene in a
        process) do not change each other's. The scene, its ground motion and the compiled kernel
        are shared, not copied (``Kernel.for_run`` copies the kernel's own run state)."""
        shared = (self.scene, self.ground_motion, self.element_factory, getattr(self, "_compiled_kernel", None),
                  getattr(self, "model_mechanism", None))
        run = copy.deepcopy(self, {id(x): x for x in shared if x is not None})
        run.model_mechanism = getattr(self, "model_mechanism", self)
        run.reset_windings()
        for e in run.efficient:
            if getattr(e, "row", None) is not None:
                e.row[layout.EFFICIENCY_MODE] = 1.0
            else:                                   # the oracle's element: its own mode
                e.mode = 1.0
        return run

    @property
    def watches_terminals(self) -> bool:
        """Whether some translational element's terminals can meet (:meth:`chord_margin`)."""
        return bool(self._meet)

    def chord_margin(self, y0, y1) -> float:
        """Terminals meet within a step from the state y0 to y1 (or their q) where this is at most
        1: the smallest, over the pairs of terminals of translational elements, of the closest
        approach of the chord from r(q0) to r(q1) (which catches a pass through each other between
        two accepted steps too) over the pair's limit (see MEET_RELATIVE); inf without such pairs.
        The compiled loops' test is the same (``kernels.terminals_meet``, ``kernels.chord_margin``)."""
        z = np.zeros(self.n)
        worst = math.inf
        for pair, names, (a, b), limit in self._meet:
            r0 = _in_3d(pair.evaluate(y0[:self.nq], z)[0])
            r1 = _in_3d(pair.evaluate(y1[:self.nq], z)[0])
            worst = min(worst, _chord_approach(*r0, *r1) / limit)
        return worst

    def meeting_message(self, y, t) -> str:
        """Why a run stops at the state y (or its q), at time t, where an integrator located a
        meeting of terminals (:meth:`chord_margin`): the elements of the pair nearest its limit
        there, its terminals, the time, their distance and the limit."""
        z = np.zeros(self.n)
        q = np.asarray(y, dtype=float)[:self.nq]
        pairs = [(math.sqrt(float(r @ r)), entry) for entry in self._meet
                 for r in (entry[0].evaluate(q, z)[0],)]
        dist, (_, names, (a, b), limit) = min(pairs, key=lambda p: p[0] / p[1][3])
        label = ", ".join(f"'{n}'" for n in names)
        return (f"element{'s' if len(names) > 1 else ''} {label}: terminals {a} and {b} meet at t = {t:.9g} s "
                f"({dist:.3g} m apart there; their limit is {limit:.3g} m, {MEET_RELATIVE:g} of the initial "
                f"length), so the direction is undefined; the run stops at the meeting")

    def mount_sines(self, q) -> list[tuple[str, float]]:
        """(element, |a₁ × u|) for each inerter device with a Hooke mount, at q."""
        sines = ((e.name, getattr(e, "mount_sine", lambda q: None)(q)) for e in self.inerters)
        return [(name, sine) for name, sine in sines if sine is not None]

    def check_mounts(self, q):
        """At t = 0: no device's mount axis a₁ may lie along the device's axis (MOUNT_SINGULAR)."""
        for name, sine in self.mount_sines(q):
            if sine < MOUNT_SINGULAR:
                field = f"elements.{name}.device.mount.axis"
                raise SceneError(self.scene.source, field, self.scene.elements[name].device.values("mount")["axis"],
                                 "an axis at an angle to the device's axis at t = 0 (the Hooke mount is singular "
                                 "where they are parallel: the housing's spin is undefined)",
                                 f"along the device's axis at t = 0 (sine of the angle {sine:.2g})")

    def diagnose(self, q) -> str:
        """Why a run may have stalled at q (or a state starting with q): the translational elements
        that are nearly closed, the device mounts near their singularity, and joint constraints that
        are nearly dependent."""
        q = np.asarray(q, dtype=float)[:self.nq]
        z = np.zeros(self.n)
        short = []
        for pair, names, (a, b), limit in self._meet:
            r = pair.evaluate(q, z)[0]
            L = math.sqrt(float(r @ r))
            if L < 1e3 * limit:
                short.append(f"{'/'.join(names)} ({a}-{b}: {L:.3g} m)")
        text = ("; terminals nearly meeting: " + ", ".join(short)) if short else ""
        near = [f"{name} (its axis {math.degrees(math.asin(min(1.0, s))):.3g}° from mount.axis)"
                for name, s in self.mount_sines(q) if s < MOUNT_NEAR]
        if near:
            text += ("; device mount near its singularity, the device's axis along the Hooke joint's first "
                     "axis (the housing's spin is undefined there; declare mount.axis away from the "
                     "device's path): " + ", ".join(near))
        return text + self._dependent_joints(q)

    def stiffest(self) -> str:
        """What sets the scene's fastest time scale, for a run whose step size collapsed: the
        devices' series modes ω = √(k_c/(b η_b)) (the node between the compliance and the inerter
        has no mass, so the mode's inertia is the inerter's own, at its smallest, back-driven: Wang &
        Su 2008, Sec. 3; the efficiency, Wen et al. 2017), the fastest named with its values, and the
        narrowest tanh switch, a friction's or a screw efficiency's velocity_scale v_s (a switch the
        steps must resolve: Pennestrì et al. 2016)."""
        modes, switches = [], []
        for spec in self.scene.elements.values():
            dev = spec.device
            if dev is None:
                continue
            if dev.has("compliance"):
                kc = dev.values("compliance")["stiffness"]
                eta = dev.values("efficiency")["backward"] if dev.has("efficiency") else 1.0
                mass = (dev.inertance() or spec.coefficient) * eta
                if kc > 0.0 and mass > 0.0:
                    w = math.sqrt(kc / mass)
                    modes.append((w, f"element '{spec.name}': series compliance k_c = {kc:g} N/m on b η_b = "
                                     f"{mass:.3g} kg (η_b = {eta:g}): its mode √(k_c/(b η_b)) = {w:.3g} rad/s, a "
                                     f"period of {2.0 * math.pi / w:.3g} s"))
            for effect in ("friction", "efficiency"):
                scale = dev.values(effect).get("velocity_scale")
                if scale:
                    switches.append((scale, f"element '{spec.name}': {effect}.velocity_scale = {scale:g} m/s"))
        parts = ([f"the stiffest effect, {max(modes)[1]}"] if modes else []) + \
            ([f"the narrowest switch, {min(switches)[1]}"] if switches else [])
        return "; likely cause: " + "; ".join(parts) if parts else ""

    def closed_loops(self) -> int:
        """How many independent closed loops the joints form: the cyclomatic number E − V + c of
        the graph whose nodes are the bodies and the ground and whose edges are the joints (each
        edge joins two components or closes a loop). A tree of joints (0) keeps C_v of full rank at
        every pose: ordered from the ground out, each joint's rows act on the body it carries
        through a block of full row rank (a revolute joint's on the point's translation, a
        prismatic's on its perpendicular and its angle, the dot-1 rows held at right angles), so
        C_v is block-triangular with full-rank diagonal blocks. Only a mechanism with a closed loop
        can reach a change point, where the rows become dependent (:meth:`_dependent_joints`), and
        only such a mechanism is watched for one (inerter.engine.kernels.loop_watch)."""
        root = {}

        def find(node):
            while root.get(node, node) != node:
                node = root[node]
            return node
        loops = 0
        for joint in self.scene.joints.values():
            a = find(self.scene.points[joint.point_a].body)
            b = find(self.scene.points[joint.point_b].body)
            if a == b:
                loops += 1
            else:
                root[a] = b
        return loops

    def _dependent_joints(self, q) -> str:
        """The joints whose constraint rows are nearly dependent at q (the smallest singular value of
        C_v below DEPENDENT_RATIO of the largest), named by their share of the left singular vector:
        a change point (a parallelogram's four pivots in a line), where the mechanism may go on in
        more than one way and Eq. (33) has no unique solution (Nikravesh 1988)."""
        if not self.m:
            return ""
        Cq = self.constraints(q, np.zeros(self.n))[1]
        if not np.all(np.isfinite(Cq)) or rank_kept(Cq):
            return ""
        U, sv, _ = np.linalg.svd(Cq, full_matrices=False)
        share, row = np.abs(U[:, -1]), 0
        names = []
        for j in self.joints:
            if np.max(share[row:row + j.rows]) > 0.1 * np.max(share):
                names.append(j.name)
            row += j.rows
        return (f"; the joints' constraints are nearly dependent there (joints {', '.join(names)}: smallest/largest "
                f"singular value {sv[-1] / sv[0]:.2g}): a change point, where the mechanism may move on in more "
                f"than one way and its accelerations are not determined")

    def check_free_spins(self, q):
        """At t = 0: a body with mass (not ``massless = true``) has a moment of inertia > 0 about
        every axis its joints leave it free to turn about, its centre of mass at rest. Such a spin
        has no mass; an inerter that carries it at one pose (a terminal off the axis) does not at
        others, where the run stops with the step size collapsing. A point mass whose rotation a
        joint holds (a prismatic joint, a revolute one about another axis) is fine."""
        spins = []                                   # (body, unit axis in the body frame, moment, Δv)
        size = 1 if self.dim == 2 else 3
        for i, name in enumerate(self.body_names):
            if self.scene.bodies[name].massless:
                continue
            k = self.v_index[i] + self.dim
            moments, axes = np.linalg.eigh(self.M0[k:k + size, k:k + size])
            for moment, axis in zip(moments, axes.T):
                if moment <= FREE_SPIN_RATIO * max(moments[-1], 0.0):
                    column = np.zeros(self.n)
                    column[k:k + size] = axis
                    spins.append((name, axis, float(moment), column))
        if not spins:
            return
        Z = np.column_stack([spin[3] for spin in spins])
        null = np.zeros(len(spins))
        null[0] = 1.0
        if self.m:
            Cq = self.constraints(q, np.zeros(self.n))[1]
            _, sv, Vt = np.linalg.svd(Cq @ Z)
            rank = int(np.sum(sv > HELD_RATIO * max(1.0, np.linalg.norm(Cq, 2))))
            if rank == len(spins):
                return
            null = Vt[-1]
        name, axis, moment, _ = spins[int(np.argmax(np.abs(null)))]
        raise self._free_spin_error(name, axis, moment)

    def _free_spin_error(self, name, axis, moment):
        """The error of :meth:`check_free_spins` for body `name`'s spin about `axis` (body frame)."""
        spec = self.scene.bodies[name]
        J = np.asarray(spec.inertia, dtype=float)
        value = float(J) if J.ndim == 0 else ([float(x) for x in np.diag(J)]
                                              if np.count_nonzero(J - np.diag(np.diag(J))) == 0
                                              else [[float(x) for x in row] for row in J])
        joints = [f"{j.name}: {j.type}" for j in self.scene.joints.values()
                  if name in (self.scene.points[j.point_a].body, self.scene.points[j.point_b].body)]
        held = f"which its joints ({', '.join(joints)}) leave free" if joints else "and no joint holds it"
        about = "" if self.dim == 2 else \
            f" about its axis [{', '.join(f'{x + 0.0:.6g}' for x in axis * np.sign(axis[np.argmax(np.abs(axis))]))}]"
        return SceneError(self.scene.source, f"bodies.{name}.inertia", value,
                          "a moment of inertia > 0 about every axis its joints leave free (a point mass where a "
                          "joint holds its rotation), or massless = true where inerters carry that rotation",
                          f"body '{name}' turns freely with no inertia: moment {moment:.3g} kg.m2{about}, {held}")

    def check_mass_matrix(self, q, v):
        """At t = 0: the augmented matrix [[M + M_I, C_vᵀ], [C_v, 0]] must be non-singular, or some
        coordinate has no mass (a massless body not carried by an inerter, a zero inertia not held
        by a joint, an inerter at right angles to the only direction it could carry)."""
        M = self.mass_matrix(q, v)
        if self.m:
            Cq = self.constraints(q, np.zeros(self.n))[1]
            # Scaled by the congruence diag(√s I, I/√s), s = ‖C_v‖/‖M‖, which keeps the rank: the
            # singular values of [[M, C_vᵀ], [C_v, 0]] span about ‖M‖ to ‖C_v‖²/‖M‖, so heavy bodies
            # on joints (a 1e6 kg storey) would otherwise read as singular.
            norm_m, norm_c = np.linalg.norm(M, 2), np.linalg.norm(Cq, 2)
            s = norm_c / norm_m if norm_m > 0.0 and norm_c > 0.0 else 1.0
            K = np.block([[s * M, Cq.T], [Cq, np.zeros((self.m, self.m))]])
        else:
            K = M
        U, sv, Vt = np.linalg.svd(K)
        if sv[-1] > SINGULAR_RATIO * sv[0]:
            return
        null = Vt[-1, :self.n]
        i = int(np.argmax([np.linalg.norm(null[j:j + (3 if self.dim == 2 else 6)]) for j in self.v_index]))
        body = self.body_names[i]
        spec = self.scene.bodies[body]
        j = self.v_index[i]
        block = np.abs(null[j:j + (3 if self.dim == 2 else 6)])
        rotational = int(np.argmax(block)) >= self.dim
        fld = f"bodies.{body}.{'inertia' if rotational else 'mass'}"
        value = spec.inertia if rotational else spec.mass
        carried = ("its rotation" if rotational else "its translation") + " has no mass"
        raise SceneError(self.scene.source, fld, value,
                         "a mass matrix M + M_I that, with the joints, is non-singular at t = 0: give the body "
                         "mass/inertia, hold the coordinate with a joint, or connect an inerter along it",
                         f"the system matrix is singular at t = 0 (smallest/largest singular value "
                         f"{sv[-1] / sv[0]:.2g}): body '{body}': {carried}"
                         + (" (massless = true, and no inerter or joint supplies it)" if spec.massless else ""))

    def normalise(self, q):
        if self.dim == 2 or self.orientation.kind != "quaternion":
            return q
        q = q.copy()
        for k in self.q_index:
            q[k + 3:k + 7] /= np.linalg.norm(q[k + 3:k + 7])
        return q

    # -- constraints -----------------------------------------------------------------------
    def constraints(self, q, v):
        """(C, C_v, γ) stacked over all joints."""
        C = np.empty(self.m)
        Cq = np.zeros((self.m, self.n))
        gamma = np.empty(self.m)
        row = 0
        for j in self.joints:
            c, jac, g = j.evaluate(q, v)
            k = j.rows
            C[row:row + k] = c
            Cq[row:row + k, j.dofs] = jac
            gamma[row:row + k] = g
            row += k
        return C, Cq, gamma

    def constraint_residual(self, q) -> float:
        if not self.m:
            return 0.0
        return float(np.max(np.abs(self.constraints(q, np.zeros(self.n))[0])))

    def project(self, q, v, tol=1e-13, max_iter=20):
        """Move (q, v) onto the constraint manifold: Newton on C(q) = 0, then C_v v = 0
        (minimum-norm corrections)."""
        q = self.normalise(q)
        if not self.m:
            return q, v
        z = np.zeros(self.n)
        for _ in range(max_iter):
            C, Cq, _ = self.constraints(q, z)
            if np.max(np.abs(C)) <= tol:
                break
            q = self.retract(q, -Cq.T @ np.linalg.solve(Cq @ Cq.T, C))
        _, Cq, _ = self.constraints(q, z)
        v = v - Cq.T @ np.linalg.solve(Cq @ Cq.T, Cq @ v)
        return q, v

    def assemble_initial(self, q, v):
        """Check the scene's initial pose against its joints; fix round-off, reject real violations."""
        if not self.m:
            return q, v
        C, Cq, _ = self.constraints(q, np.zeros(self.n))
        row = 0
        for j in self.joints:
            worst = float(np.max(np.abs(C[row:row + j.rows])))
            if worst > ASSEMBLY_TOLERANCE:
                raise SceneError(self.scene.source, f"joints.{j.name}", f"violated by {worst:.3g}",
                                 f"an initial pose (bodies' position and angle) that satisfies the joint "
                                 f"to {ASSEMBLY_TOLERANCE:g}", "initial pose violates the joint")
            row += j.rows
        if np.linalg.matrix_rank(Cq) < self.m:
            raise SceneError(self.scene.source, "joints", [j.name for j in self.joints],
                             "independent joint constraints", "redundant or singular constraints at t = 0")
        return self.project(q, v)

    # -- forces and dynamics -----------------------------------------------------------------
    def assemble(self, t, q, v, inputs=None, with_mass=True, z=None):
        """M + M_I (Eq. 33) and Q_e + Q_Iv: every force except the inerters' acceleration term; `z`:
        the internal states (default z0), whose forces an element with some adds. The weight,
        the point forces and the ground motion's forces are methods of their own
        (:meth:`point_forces`, :meth:`frame_force`), which the oracle's mechanism derives anew."""
        M = self.M0.copy() if with_mass else None
        Q = np.zeros(self.n) if self.gravity is None else self.gravity.copy()
        if self.dim == 3:
            Q += self.body_forces(v)
        for group in self.groups:
            geo = group[0].geometry(q, v)
            for e in group:
                e.add_force(q, v, Q, geo)
                if with_mass:
                    e.add_mass(q, v, M, geo)
        self.add_state_forces(q, v, Q, self.z0 if z is None else z)
        Q += self.point_forces(t, q, v, inputs)
        if self.ground_motion is not None:
            a_g = self.ground_motion.acceleration(t, inputs, len(self.input_forces) * self.dim)
            Q += self.frame_force(q, a_g)
            for e in self.inerters:                         # a device's housing, rod, flywheel move too
                e.add_frame_force(q, v, Q, a_g)
        return M, Q

    def body_forces(self, v):
        """The 3D bodies' velocity forces: −ω̄ × Jω̄ on each body's ω̄ (Euler's equations in the body
        frame, kinematics.gyroscopic). The oracle's mechanism derives them from T."""
        Q = np.zeros(self.n)
        for i, J in enumerate(self._inertia9):
            k = self.v_index[i] + 3
            Q[k:k + 3] -= _gyroscopic(J, 0, v[k], v[k + 1], v[k + 2])
        return Q

    def add_state_forces(self, q, v, Q, z):
        """The forces of the elements with internal states, at those states z."""
        for e in self.stateful:
            e.add_state_force(q, v, Q, z)

    def point_forces(self, t, q, v, inputs=None):
        """Σ Hᵀ F over the applied, feedback (PD) and input forces."""
        Q = np.zeros(self.n)
        for f, point, fn in self.applied:
            self._add_point_force(Q, point, q, fn(t) * np.asarray(f.direction))
        for f, point in self.feedback:
            self._add_point_force(Q, point, q, self._pd_force(f, point, q, v))
        if inputs is not None and len(inputs):
            for k, (f, point) in enumerate(self.input_forces):
                self._add_point_force(Q, point, q, inputs[k * self.dim:(k + 1) * self.dim])
        return Q

    def frame_force(self, q, a_g):
        """The bodies' −m a_g: their coordinates are relative to the ground frame, which accelerates
        by a_g (kinematics.frame_force)."""
        Q = np.zeros(self.n)
        a3 = np.zeros(3)
        a3[:self.dim] = a_g
        for i, m in enumerate(self.masses):
            Q[self.v_index[i]:self.v_index[i] + self.dim] -= _frame_force(m, *a3)[:self.dim]
        return Q

    def generalized_forces(self, t, q, v, inputs=None):
        return self.assemble(t, q, v, inputs, with_mass=False)[1]

    @staticmethod
    def _pd_force(f, point, q, v, static=False):
        """A grounded actuator along the fixed direction d: F = −[kp(d·r − ref) + kd d·v] d
        (kinematics.pd_magnitude; `static`: kd's term left out)."""
        r, rdot, _, _ = point.evaluate(q, v)
        d = np.zeros(3)
        d[:len(r)] = f.direction
        rr, vv = np.zeros(3), np.zeros(3)
        rr[:len(r)] = r
        if not static:
            vv[:len(r)] = rdot
        return _pd_magnitude(*d, f.reference, f.kp, f.kd, *rr, *vv) * np.asarray(f.direction)

    def _add_point_force(self, Q, point, q, F):
        """Hᵀ F into the point's body's coordinates (virtual work, δr = H δq)."""
        if point.dofs is not None:
            Q[point.dofs] += point.generalised_force(q, F)

    def mass_matrix(self, q, v):
        M = self.M0.copy()
        for e in self.elements:                   # a kind whose law has no inertance adds nothing
            e.add_mass(q, v, M)                                    # M + M_I, Eq. (33)
        return M

    def accelerations(self, t, q, v, inputs=None, alpha=0.0, z=None):
        """Solve Eq. (33) for (v̇, λ) at (t, q, v) and the internal states z (default z0); with screw
        efficiencies, solved again until their modes agree with the solved L̈, as the kernels do
        (inerter.elements.device, ``kernels.accelerations``; after MODE_SOLVES checks, once more in
        the modes last set)."""
        for _ in range(MODE_SOLVES):
            a, lam = self._accelerations(t, q, v, inputs, alpha, z)
            if not sum(e.settle(q, v, a) for e in self.efficient):
                return a, lam
        return self._accelerations(t, q, v, inputs, alpha, z)       # unsettled: the modes last set

    def _accelerations(self, t, q, v, inputs, alpha, z):
        try:
            M, Q = self.assemble(t, q, v, inputs, z=z)
        except (ValueError, OverflowError) as exc:     # a finite state whose geometry overflowed
            if "NaN" not in str(exc) and "infinity" not in str(exc):
                raise
            raise SimulationError(_NOT_FINITE, t, recoverable=True) from None
        if not self.m:
            return self._solve(M, Q, t), np.zeros(0)
        C, Cq, gamma = self.constraints(q, v)
        rhs_c = gamma - 2.0 * alpha * (Cq @ v) - alpha * alpha * C     # Baumgarte
        K = np.zeros((self.n + self.m, self.n + self.m))
        K[:self.n, :self.n] = M
        K[:self.n, self.n:] = Cq.T
        K[self.n:, :self.n] = Cq
        x = self._solve(K, np.concatenate((Q, rhs_c)), t)
        return x[:self.n], x[self.n:]

    def _solve(self, K, rhs, t):
        try:
            x = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:
            raise SimulationError("the mass matrix M + M_I with the joint constraints is singular: some "
                                  "coordinate has no mass (check zero masses/inertias and the inerters)", t,
                                  recoverable=True)
        if not np.all(np.isfinite(x)):
            raise SimulationError(_NOT_FINITE, t, recoverable=True)
        return x

    def state_rates(self, q, v, z, a) -> np.ndarray:
        """ż at (q, v, z) and the accelerations a (each stateful element's ``state_rates``)."""
        dz = np.zeros(len(z))
        for e in self.stateful:
            e.state_rates(q, v, a, z, dz)
        return dz

    # -- energy ----------------------------------------------------------------------------
    def energy(self, q, v, z=None) -> float:
        """T + V: ½vᵀM v + Σ ½bL̇² (inerters) + elastic and gravity potential. Conserved by the
        corrected model without damping and forcing (the inerter adds ½bL̇² to T, Sec. 2.2)."""
        return self.energy_held(q, v, z)[0]

    def energy_held(self, q, v, z=None) -> tuple[float, float]:
        """(:meth:`energy`, what the scene holds: the sum of its parts' magnitudes, each body's T + V
        and each element's stored energy; as the kernels' ``scene_energy2``, RK4's energy watch)."""
        parts = [self.body_energy(i, q, v) for i in range(len(self.body_names))]
        parts += [e.kinetic(q, v) + e.potential(q) for e in self.elements]
        z = self.z0 if z is None else z
        for e in self.stateful:                 # a series connection's ½ b u̇² + ½ k_c d², its element's
            parts[len(self.body_names) + self.elements.index(e)] += e.state_energy(q, v, z)
        return float(sum(parts)), float(sum(abs(p) for p in parts))

    #: The element kinds that store energy and give it back, and those that only take it out (linear
    #: dampers, c ≥ 0 and d ≥ 0: their power c L̇², d ω_rel² leaves the motion).
    STORING_KINDS = frozenset({"spring", "inerter", "rotational_spring"})
    DISSIPATING_KINDS = frozenset({"damper", "rotational_damper"})

    def conserves_energy(self) -> bool:
        """Whether the scene conserves :meth:`energy`: no applied forces or inputs, no ground
        motion, springs, ideal inerters and rotational springs only (no damper, no device: its
        friction, efficiency or end stops take energy out), every inerter with its centripetal
        term (Eq. 9: F = b d²L/dt² stores ½bL̇²; the uncorrected Eq. 8 and the small-displacement
        law do work of their own, Sec. 2.2). RK4's energy watch holds such a scene to it."""
        return self._energy_only_through(self.STORING_KINDS)

    def only_loses_energy(self) -> bool:
        """Whether :meth:`energy` can only fall: as :meth:`conserves_energy`, with linear dampers
        and rotational dampers too, dE/dt = −Σ c L̇² − Σ d ω_rel² ≤ 0. RK4's energy watch holds
        such a scene to it (a device stays out: that its model's energy, with its friction,
        efficiency, compliance and end stops, can only fall is not shown here)."""
        return self._energy_only_through(self.STORING_KINDS | self.DISSIPATING_KINDS)

    def _energy_only_through(self, kinds) -> bool:
        """No forcing, ground motion, input or device, elements of `kinds` only, every inerter with
        its centripetal term."""
        s = self.scene
        present = {e.type for e in s.elements.values()}
        return (not s.forces and self.ground_motion is None and not self.input_names
                and present <= kinds
                and all(e.device is None for e in s.elements.values())
                and ("inerter" not in present or (s.centripetal and not s.small_displacement)))

    def body_energy(self, i, q, v) -> float:
        """Body i's ½ vᵀ M0 v over its block and its weight's potential −m g·R
        (kinematics.planar_body_energy, spatial_body_energy, as the kernels' energy output)."""
        k, j, dim = self.q_index[i], self.v_index[i], self.dim
        weight = self.gravity[j:j + dim] if self.gravity is not None else (0.0,) * dim
        if dim == 2:
            return _planar_body_energy(self.masses[i], self.M0[j + 2, j + 2], *v[j:j + 3], *weight, *q[k:k + 2])
        return _spatial_body_energy(self.masses[i], self._inertia9[i], 0, *v[j:j + 6], *weight, *q[k:k + 3])

    # -- description -----------------------------------------------------------------------
    def terms(self) -> list[str]:
        """What this compiled model computes: one line per term."""
        s = self.scene
        path = ("oracle: element forces from d²L/dt² by automatic differentiation" if self.oracle
                else "fast path: Eqs. (15-20), (33)")
        orient = f", orientation {self.orientation.kind}" if self.dim == 3 else ""
        lines = [f"{s.dimension}D, {len(self.body_names)} bodies, {self.nq} coordinates, {self.n} velocity "
                 f"coordinates, {self.m} constraint rows{orient} ({path})"]
        for j in self.joints:
            lines.append(f"joint {j.name}: {j.kind}, {j.rows} rows")
        for e in self.elements:
            extra = ""
            if e.kind == "inerter":
                extra = f" {s.inerter_law}"
            slider = getattr(s.elements.get(e.name), "slider_axis", None)
            if slider is not None:
                extra = f" along the prismatic joint's axis {list(slider)} (in the first point's body frame)"
            lines.append(f"element {e.name}: {e.kind}, {getattr(e, 'coefficient_name', 'k')} = {e.coefficient:g}{extra}")
            device = getattr(s.elements.get(e.name), "device", None)
            if device is not None:
                lines.append(f"element {e.name}: device: {device.describe()}")
        for f, _, _ in self.applied:
            lines.append(f"force {f.name}: {f.function} at {f.point} along {list(f.direction)}")
        for f, _ in self.feedback:
            lines.append(f"force {f.name}: pd actuator at {f.point} along {list(f.direction)}, kp = {f.kp:g}, "
                         f"kd = {f.kd:g}")
        for f, _ in self.input_forces:
            lines.append(f"force {f.name}: input at {f.point} ({', '.join(n for n in self.input_names if n.startswith(f.point + '.'))})")
        lines.append("gravity: " + (f"{list(s.effects['gravity'])} m/s²" if self.gravity is not None else "not declared, not computed"))
        if self.dim == 3:
            lines.append("gyroscopic terms: ω × Jω per body")
        if self.ground_motion is not None:
            lines.append(f"ground motion: {self.ground_motion.describe()} (coordinates relative to the ground)")
        if not self.inerters:
            lines.append("inerters: none, no inerter term computed")
        for d in s.derived:
            unit = for_reading(d.unit)
            lines.append(f"derived output {d.name}{f' ({unit})' if unit else ''} = {d.expression.text}")
        return lines
