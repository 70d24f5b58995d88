"""Output signals, named and united as a Modelica user expects (the FMU uses the same names).

Points: ``P.r[i]`` (m), ``P.v[i]`` (m/s). Translational elements: ``E.s_rel`` (m, terminal
distance), ``E.v_rel`` (m/s, its rate), ``E.f`` (N, axial force, tension positive), ``E.power``
(W, f·v_rel: what it absorbs from the mechanism), ``E.energy`` (J, what it stores: its terms of
``energy``); an inerter's
device adds ``E.w_flywheel`` (rad/s), ``E.f_friction``, ``E.f_fluid``, ``E.f_stop`` (N),
``E.p_loss`` (W), ``E.s_series`` (m), ``E.engaged`` (1) and ``E.e_loss`` (J), those of its effects
(:mod:`inerter.elements.device`; the last three read the element's internal states). Rotational
elements: ``E.phi_rel`` (rad), ``E.w_rel`` (rad/s), ``E.tau`` (N.m), ``E.power`` (W, τ·ω_rel),
``E.energy`` (J). 3D bodies: ``B.q[i]`` (unit
quaternion w, x, y, z), ``B.euler[i]`` (rad, the scene's ``euler_sequence``), ``B.w[i]`` (rad/s,
angular velocity in the global frame). Mechanism: ``energy`` (J), ``constraint_residual`` (largest
|C_i| of the joint constraints, m or rad). Derived outputs (the scene's ``[outputs.derived]``):
expressions over the others, evaluated from their values (:meth:`Signals.complete`), after them.
"""
from __future__ import annotations

import numpy as np

from inerter import elements
from inerter.common.rotations import EULER_SEQUENCES, euler_angles9, quat_from_matrix


#: The units of an element family's outputs that are coordinates or rates (s_rel, v_rel, phi_rel, w_rel).
MOTION_UNITS = ("m", "m/s", "rad", "rad/s")


class Signals:
    def __init__(self, mech):
        self.mech = mech
        self.names, self.units, self.descriptions = [], [], []
        # Groups of signals computed together: (needs_accelerations, f(t, q, v, a) -> values), in the
        # order of `names`; a point's position and velocity, an element's three outputs come from
        # one evaluation.
        self._groups = []
        self._where = {}      # name -> (group, position in it)
        self._reads = {}      # name -> whether that signal itself reads q̈
        #: the coordinates and rates of the motion: points' and bodies' outputs, an element's s_rel,
        #: v_rel, phi_rel, w_rel (functions of q and v alone, continuous in time; not a force, power,
        #: energy or device output, which may pulse: inerter.api.metric_grid_rtol)
        self.kinematic: set[str] = set()
        element_outputs = []
        for pname in mech.point_names:
            point = mech.points[pname]
            d = mech.dim
            self._group([(f"{pname}.r[{i + 1}]", "m", f"position of point {pname}, global axis {i + 1}")
                         for i in range(d)]
                        + [(f"{pname}.v[{i + 1}]", "m/s", f"velocity of point {pname}, global axis {i + 1}")
                           for i in range(d)],
                        False, lambda t, q, v, a, z, p=point: np.concatenate(p.evaluate(q, v)[:2]), kinematic=True)
        for e in mech.elements:
            spec = elements.outputs(mech.scene.elements[e.name])
            family = len(elements.KINDS[e.kind].outputs)
            # an element whose law has an inertance reports a force that depends on q̈
            needs_a = e.kind == "inerter" or (hasattr(e, "inertance") and e.inertance(0.0) != 0.0)
            # of its family's outputs, only the force and the power read q̈ (the distance, its rate and
            # the stored energy do not); a screw efficiency's mode and loss are those of the solved L̈
            # (inerter.elements.device)
            efficient = e in mech.efficient
            element_outputs += [f"{e.name}.{suffix}" for suffix, _, _ in spec]
            self._group([(f"{e.name}.{suffix}", unit, f"{e.kind} {e.name}: {text}") for suffix, unit, text in spec],
                        needs_a, lambda t, q, v, a, z, e=e, k=len(spec): (
                            e.outputs(q, v, a, z) if getattr(e, "n_states", 0) else e.outputs(q, v, a))[:k],
                        reads=tuple(needs_a and suffix in elements.FORCE_OUTPUTS for suffix, _, _ in spec[:family])
                        + tuple(efficient and suffix in ("p_loss", "mode") for suffix, _, _ in spec[family:]),
                        kinematic=tuple(k < family and unit in MOTION_UNITS for k, (_, unit, _) in enumerate(spec)))
        if mech.dim == 3:
            for bname in mech.body_names:
                self._body(mech, bname)
        self._group([("energy", "J", "kinetic + potential energy: the bodies' and every element's E.energy "
                                "(½·b·(dL/dt)² per inerter)")], False,
                    lambda t, q, v, a, z: (mech.energy(q, v, z) if len(mech.z0) else mech.energy(q, v),))
        self._group([("constraint_residual", "m", "largest |C_i(q)| of the joint constraints (m or rad)")], False,
                    lambda t, q, v, a, z: (mech.constraint_residual(q),))
        self.needs_accelerations = any(needs_a for needs_a, _ in self._groups)
        #: the outputs that hold no pulse narrower than the integrator's steps resolve, which a periodic
        #: metric may sample only as finely as its rule needs (inerter.api.metric_grid_rtol): the motion's
        #: and, in a scene without an inerter device (whose end stops and backlash pulse, and carry the
        #: pulse through q̈ into every force that reads it), every element's outputs and the energy,
        #: functions of the state and of forcing that is smooth between the kinks and jumps a grid's
        #: refinement sees. Not a derived output (an expression may pulse: max(0, x − 0.99)), nor the
        #: constraint residual.
        devices = any(getattr(mech.scene.elements[e.name], "device", None) is not None for e in mech.elements)
        self.pulse_free: set[str] = set(self.kinematic) if devices else self.kinematic | set(element_outputs) | {"energy"}
        #: the signals before the derived outputs: those the groups (and the kernels) evaluate
        self.base_count = len(self.names)
        self.derived = tuple(mech.scene.derived)
        self._derived = {d.name: d for d in self.derived}
        for d in self.derived:
            # it reads q̈ (and then depends on the inputs at the same instant) where an output it reads does
            self._reads[d.name] = any(self._reads[x] for x in d.expression.reads)
            self.names.append(d.name)
            self.units.append(d.unit)
            self.descriptions.append(d.description)
        self.index = {n: i for i, n in enumerate(self.names)}

    def for_run(self, mech) -> "Signals":
        """These signals on `mech`, a run's copy of the mechanism they were built on
        (``Mechanism.for_run``), whose run state (the 3D rotational elements' φ_ref, the screw
        efficiencies' modes) they then read; themselves where `mech` is theirs."""
        return self if mech is self.mech else Signals(mech)

    def _body(self, mech, bname):
        """A 3D body's orientation (unit quaternion, Euler angles) and global angular velocity."""
        frame = mech.frames[bname]
        sequence = mech.scene.euler_sequence
        axes = EULER_SEQUENCES[sequence]
        quaternion_state = mech.orientation.kind == "quaternion"

        def values(t, q, v, a, z):
            A, w = frame.evaluate(q, v)
            if quaternion_state:
                p = q[frame.qi + 3:frame.qi + 7]
                p = p / np.linalg.norm(p)
            else:
                p = quat_from_matrix(A)
            return (*p, *euler_angles9.py_func(tuple(A.ravel()), *axes), *(A @ w))
        self._group([(f"{bname}.q[{i + 1}]", "1", f"body {bname}: unit quaternion, component {c}")
                     for i, c in enumerate("wxyz")]
                    + [(f"{bname}.euler[{i + 1}]", "rad", f"body {bname}: Euler angle {i + 1} of the {sequence} "
                                                         "sequence (intrinsic)") for i in range(3)]
                    + [(f"{bname}.w[{i + 1}]", "rad/s", f"body {bname}: angular velocity, global axis {i + 1}")
                       for i in range(3)], False, values, kinematic=True)

    def _group(self, signals, needs_a, fn, reads=None, kinematic=False):
        for k, (name, unit, description) in enumerate(signals):
            self._where[name] = (len(self._groups), k)
            self._reads[name] = needs_a if reads is None else reads[k]
            if kinematic is True or (kinematic and kinematic[k]):
                self.kinematic.add(name)
            self.names.append(name)
            self.units.append(unit)
            self.descriptions.append(description)
        self._groups.append((needs_a, fn))

    def info(self):
        """Name, unit, description of each signal, and whether it reads the accelerations (then it
        depends on the inputs at the same instant: an FMU declares that feedthrough)."""
        return [dict(name=n, unit=u, description=d, reads_accelerations=self.reads_accelerations(n))
                for n, u, d in zip(self.names, self.units, self.descriptions)]

    def reads_accelerations(self, name) -> bool:
        """Whether signal `name` is computed from q̈ (an inerter's force), not from (t, q, v) alone."""
        return self._reads[name]

    def evaluate(self, t, q, v, inputs=None, alpha=0.0, accelerations=None, z=None) -> np.ndarray:
        """Every signal at one state, `z` the internal states (None: their initial values).
        `accelerations`: the function giving (q̈, λ) of Eq. (33) (default the mechanism's; the
        compiled path passes its kernel's, with z bound where there are internal states)."""
        a = None
        if self.needs_accelerations:
            if accelerations is None and z is not None and len(z):
                a = self.mech.accelerations(t, q, v, inputs, alpha, z=z)[0]
            else:
                a = (accelerations or self.mech.accelerations)(t, q, v, inputs, alpha)[0]
        return self.values(t, q, v, a, z)

    def values(self, t, q, v, a, z=None) -> np.ndarray:
        """Every signal at one state with the accelerations `a` (None when no signal needs them)
        and the internal states `z` (None: their initial values)."""
        out = []
        for _, fn in self._groups:
            out.extend(fn(t, q, v, a, z))
        return self.complete(np.array(out, dtype=float))

    def is_derived(self, name) -> bool:
        return name in self._derived

    def derived_reads(self, name) -> tuple[str, ...]:
        """The outputs derived output `name` reads."""
        return self._derived[name].expression.reads

    def complete(self, base) -> np.ndarray:
        """Every signal from the values of the first `base_count` (the last axis of `base`: one
        state, or a history's samples × signals): the derived outputs appended, each evaluated
        element by element from the values of the outputs it reads (:meth:`derive`)."""
        base = np.asarray(base, dtype=float)
        if not self.derived:
            return base
        columns = {n: base[..., i] for i, n in enumerate(self.names[:self.base_count])}
        for d in self.derived:
            columns[d.name] = self.derive(d.name, columns)
        return np.concatenate((base, np.stack([columns[d.name] for d in self.derived], axis=-1)), axis=-1)

    def derive(self, name, columns) -> np.ndarray:
        """Derived output `name` from `columns`, the values of the outputs it reads by name (arrays
        of one shape, or floats)."""
        expression = self._derived[name].expression
        values = [np.asarray(columns[x], dtype=float) for x in expression.reads]
        return np.broadcast_to(expression.evaluate(values), np.broadcast_shapes(*(v.shape for v in values)))

    def function(self, name):
        """f(t, q, v, inputs) → value of one signal."""
        if name in self._derived:
            reads = {x: self.function(x) for x in self._derived[name].expression.reads}

            def derived(t, q, v, inputs=None, alpha=0.0, z=None):
                return float(self.derive(name, {x: f(t, q, v, inputs, alpha, z=z) for x, f in reads.items()}))
            return derived
        g, k = self._where[name]
        needs_a, fn = self._groups[g]
        mech = self.mech

        def signal(t, q, v, inputs=None, alpha=0.0, z=None):
            a = None
            if needs_a:
                a = (mech.accelerations(t, q, v, inputs, alpha, z=z) if z is not None and len(z)
                     else mech.accelerations(t, q, v, inputs, alpha))[0]
            return float(fn(t, q, v, a, z)[k])
        return signal
