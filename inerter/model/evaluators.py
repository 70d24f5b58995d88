"""The readable evaluators of the elements: each element's geometry in numpy, its law from
:mod:`inerter.elements` run uncompiled (the same definition the kernels inline, ``.py_func``).

An element adds to the system mass matrix M (the factor of gᵀq̈ in its law, b for an inerter: M_I
of Eq. 33) and to the generalised force vector Q, and reports its outputs (Modelica names:
``s_rel``, ``v_rel``, ``f`` for translational elements, tension positive; ``phi_rel``, ``w_rel``,
``tau`` for rotational ones; then ``power``, the force times the rate, and ``energy``, what the
element adds to :meth:`Mechanism.energy`: :data:`inerter.elements.FAMILY_OUTPUTS`).

Translational elements act along the line between their terminals (uniaxial, Sec. 2.2) and enter
the equations through the generalised force of Eq. (29), Q = −F Hᵀ r̂.
"""
from __future__ import annotations

import math

import numpy as np

from inerter import elements
from inerter.common.errors import MIN_LENGTH, TerminalsMeet  # noqa: F401  (re-exported)
from inerter.common.rotations import matrix9_apply, planar_matrix9
from inerter.elements import device, device_inertia, layout, terminals, twist
from inerter.elements.base import axial_scalars as _compiled_axial_scalars
from inerter.model.planar import PointPair


axial_scalars = _compiled_axial_scalars.py_func     # the kernels' definition, run uncompiled
_planar_relative = twist.planar_relative.py_func
_spatial_twist = twist.spatial_twist.py_func


acting_line = terminals.acting_line.py_func         # the element's geometry, as the kernels inline it
turning_axis = terminals.turning_axis.py_func
reported_distance = terminals.reported_distance.py_func


def rotation(point, q):
    """The rotation of the body carrying `point` as a row-major 9-tuple (the ground's: the identity),
    what :mod:`inerter.elements.terminals` takes: 2D A(θ) about the normal, 3D the body's matrix."""
    if point.body < 0:
        return terminals.IDENTITY
    if len(point.local) == 2:
        return planar_matrix9.py_func(q[point.qi + 2])
    return point.rotation9(q)


def slider_direction(point, axis, q) -> np.ndarray:
    """A prismatic joint's axis in the global frame, ê = A n̄, n̄ fixed in the body of `point` (the
    joint's first point; the ground's axis is global)."""
    n = np.zeros(3)
    n[:len(axis)] = axis
    return np.array(matrix9_apply.py_func(rotation(point, q), *n)[:len(axis)])


class TranslationalElement:
    """A two-terminal uniaxial element between points a and b, of any translational kind."""

    def __init__(self, name: str, kind: str, pair: PointPair, coefficient: float, labels: tuple[str, str],
                 free_length: float | None = None, centripetal: bool = True, device=None,
                 fixed_direction=None, slider_axis=None):
        self.name = name
        self.kind = kind
        self.pair = pair
        self.labels = labels
        self.coefficient = float(coefficient)
        self.coefficient_name = elements.KINDS[kind].coefficient.key
        self.free_length = None if free_length is None else float(free_length)
        self.centripetal = bool(centripetal)
        law = elements.MODULE[kind]
        self._force, self._inertance, self._energy = law.force.py_func, law.inertance.py_func, law.energy.py_func
        self.device = device
        row = np.zeros(layout.ELEMENT_REAL_COLUMNS)
        row[layout.COEFFICIENT] = self.coefficient
        row[layout.FREE_LENGTH] = self.free_length or 0.0
        row[layout.CENTRIPETAL] = 1.0 if self.centripetal else 0.0
        if device is not None:
            for column, value in device.columns().items():     # DEVICE ... FLUID_QUADRATIC, SERIES ... LOSS
                row[column] = value
        #: The small-displacement law: the element acts along this initial direction (not r̂).
        self.fixed_direction = None if fixed_direction is None else np.asarray(fixed_direction, dtype=float)
        if self.fixed_direction is not None:
            row[layout.CENTRIPETAL] = 0.0
            row[layout.FIXED_DIRECTION] = 1.0
            row[layout.DIRECTION:layout.DIRECTION + len(self.fixed_direction)] = self.fixed_direction
        #: A prismatic joint's spring or damper: along the joint's axis, fixed in a's body; L the signed slide.
        self.slider_axis = None if slider_axis is None else np.asarray(slider_axis, dtype=float)
        if self.slider_axis is not None:
            row[layout.SLIDER] = 1.0
            row[layout.DIRECTION:layout.DIRECTION + len(self.slider_axis)] = self.slider_axis
        self.row = row
        self.turns = bool(terminals.turns_with_a.py_func(row))     # its line turns with a's body
        # the kind's outputs beyond its family's (a device's), by its law extra_outputs
        self.extra = len(device.outputs()) if device is not None else 0
        self._extra = getattr(law, "extra_outputs", None)
        self._extra = self._extra.py_func if self._extra is not None and self.extra else None
        #: Its internal states' place in z (y = [q, v, z]; an inerter device's: Mechanism sets it),
        #: and their laws (:mod:`inerter.elements`, uncompiled).
        self.states = slice(0, 0)
        self.n_states = len(device.states()) if device is not None else 0
        if self.n_states:
            self._state_force, self._state_energy, self._state_rates = (
                law.state_force.py_func, law.state_energy.py_func, law.state_rates.py_func)

    def inertance(self, Ldot: float) -> float:
        """The factor of gᵀq̈ in its law at the stroke rate L̇ (b; a screw efficiency's b_eff in its
        current mode, inerter.elements.device)."""
        return self._inertance(self.row, Ldot)

    def efficient(self) -> bool:
        """Whether it has a screw efficiency whose mode the solve settles (:meth:`settle`): a rigid one
        (in series the mode is a law of the state, inerter.elements.device.series_drive)."""
        return bool(device.mode_solved.py_func(self.row))

    def _scalars(self, geo, a=None):
        """(L, L̇, a_n·r̂, |ṙ⊥|², gᵀq̈) of the geometry `geo` at accelerations `a` (gᵀq̈ = 0 without)."""
        r, rdot, a_n, H, L, rhat = geo
        rd, an, e = np.zeros(3), np.zeros(3), np.zeros(3)       # 2D vectors padded with z = 0
        rd[:len(rdot)], an[:len(a_n)], e[:len(rhat)] = rdot, a_n, rhat
        Ldot, an_r, perp2 = axial_scalars(*rd, *an, *e)
        gq = 0.0 if a is None else float((H @ a[self.pair.dofs]) @ rhat)
        return L, Ldot, an_r, perp2, gq

    def settle(self, q, v, a) -> int:
        """Set its efficiency's mode from the solved accelerations `a` (inerter.elements.inerter.settle,
        uncompiled); 1 where it changed."""
        return elements.MODULE[self.kind].settle.py_func(self.row, *self._scalars(self.geometry(q, v), a))

    def geometry(self, q, v):
        """(r, ṙ, a_n, H, L, ê): the terminals' kinematics (:class:`PointPair`) and the element's
        geometry, L and the direction ê it acts along (:mod:`inerter.elements.terminals`, uncompiled;
        ṙ and H with a turning axis' terms)."""
        r, rdot, a_n, H = self.pair.evaluate(q, v)
        dim = len(r)
        rx, ry, rz = (r.tolist() + [0.0])[:3]                   # 2D: z = 0
        A = rotation(self.pair.a, q) if self.turns else terminals.IDENTITY
        distance = math.sqrt(float(r @ r))
        L, *e, meets = acting_line(self.row, A, rx, ry, rz, distance)
        if meets:
            raise TerminalsMeet(
                f"element '{self.name}': its terminals {self.labels[0]} and {self.labels[1]} meet "
                f"(distance {distance:.3g} m < {MIN_LENGTH:g} m), so its direction is undefined", recoverable=True)
        axis = np.array(e[:dim])
        if self.turns and self.pair.a.dofs is not None:
            H, rdot = self._turning_axis(v, (rx, ry, rz), rdot, H, A, e)
        return r, rdot, a_n, H, L, axis

    def _turning_axis(self, v, r, rdot, H, A, e):
        """A prismatic joint's spring or damper, ê = A_a n̄ turning with a's body: H's columns of a's
        rotation (2D θ_a, 3D ω̄_a) gain ê c̄ᵀ and ṙ gains (ω̄_a·c̄) ê (terminals.turning_axis)."""
        a = self.pair.a
        dim = len(rdot)
        cols = [2] if dim == 2 else [3, 4, 5]
        w = np.zeros(3)
        w[3 - len(cols):] = v[a.dofs[cols]]
        rd = np.zeros(3)
        rd[:dim] = rdot
        c0, c1, c2, *rd = turning_axis(A, *e, *r, *w, *rd)
        H = np.array(H, dtype=float)
        H[:, cols] += np.outer(e[:dim], (c0, c1, c2)[3 - len(cols):])
        return H, np.array(rd[:dim])

    def length(self, q):
        return self.geometry(q, np.zeros_like(q))[4]

    def _law_force(self, geo):
        """The law's force without the inertance part (:mod:`inerter.elements`), and L̇."""
        L, Ldot, an_r, perp2, _ = self._scalars(geo)
        return self._force(self.row, L, Ldot, an_r, perp2), Ldot

    def _x(self, z):
        """Its internal states in z (zero where z is not given)."""
        return np.zeros(self.n_states) if z is None else np.asarray(z[self.states], dtype=float)

    def force(self, q, v, a=None, geo=None, z=None):
        """The axial force at accelerations `a` (needed only where the kind has an inertance) and
        internal states z."""
        geo = geo or self.geometry(q, v)
        F, Ldot = self._law_force(geo)
        b = self.inertance(Ldot)
        if b != 0.0:
            F += b * float((geo[3] @ a[self.pair.dofs]) @ geo[5])   # b gᵀq̈, Eq. (9)
        if self.n_states:
            F += self._state_force(self.row, geo[4], Ldot, self._x(z))
        return F

    def outputs(self, q, v, a, z=None):
        """(s_rel, v_rel, f, power f·v_rel, stored energy) at accelerations `a` (and internal states
        z), then the kind's extra outputs (a device's)."""
        geo = self.geometry(q, v)
        L, Ldot = geo[4], float(geo[1] @ geo[5])
        distance = reported_distance(self.row, L, math.sqrt(float(geo[0] @ geo[0])))
        F = self.force(q, v, a, geo, z)
        values = (distance, Ldot, F, F * Ldot, self.stored(q, v, z))
        if self._extra is None:
            return values
        extra = np.zeros(self.extra)
        _, _, an_r, perp2, gq = self._scalars(geo, a)
        self._extra(self.row, L, Ldot, an_r, perp2, gq, self._x(z), extra, 0)
        return values + tuple(float(x) for x in extra)

    def block(self, q, v, frame_acc=None):
        """A device's kinetic block (inerter.elements.device_inertia, run uncompiled) over the pair's
        dofs: (M, Q, T, V: its kinetic and gravitational energy), or None without one; frame_acc: the
        ground's acceleration, which its parts feel (default none). The terminals' kinematics are the points' own; the
        mount's axis a₁ = A_a a̅₁ is the point a̅₁ on a's body less its origin."""
        if self.device is None or not self.device.inertia():
            return None
        dim = len(self.pair.a.local)
        width = 3 if dim == 2 else 6
        n = 2 * width
        Ha, Hb, kin = np.zeros((3, n)), np.zeros((3, n)), []
        for p, H, col in ((self.pair.a, Ha, 0), (self.pair.b, Hb, width)):
            r, rdot, Hp, acc = p.evaluate(q, v)
            if Hp is not None:
                H[:dim, col:col + width] = Hp
            kin.append([np.pad(np.asarray(x, dtype=float), (0, 3 - dim)) for x in (r, rdot, acc)])
        (ra, va, acc_a), (rb, vb, acc_b) = kin
        a1, a1d, a1dd, Ga1 = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros((3, n))
        if self.row[layout.MOUNT] != 0.0:
            (rt, vt, Ht, at), (ro, vo, Ho, ao) = self._mount_points(q, v)
            a1, a1d, a1dd = rt - ro, vt - vo, at - ao
            if Ht is not None:
                Ga1[:, :width] = Ht - Ho
        M, Q = np.zeros((n, n)), np.zeros(n)
        frame = np.zeros(3)
        if frame_acc is not None:
            frame[:dim] = frame_acc
        T, V = device_inertia.block.py_func(self.row, Ha, Hb, ra, rb, va, vb, acc_a, acc_b, frame, a1, a1d, a1dd,
                                            Ga1, M, Q)
        keep = [i for i, p in enumerate((self.pair.a,) * width + (self.pair.b,) * width) if p.dofs is not None]
        return M[np.ix_(keep, keep)], Q[keep], T, V

    def _mount_points(self, q, v):
        """The kinematics of the mount's axis tip a̅₁ and of the origin of terminal a's body (the
        axis a₁ is their difference, a direction fixed in that body)."""
        a = self.pair.a
        axis = self.row[layout.MOUNT_AXIS:layout.MOUNT_AXIS + 3]
        return tuple(type(a)(a.body, local, a.qi, a.dofs[0] if a.dofs is not None else 0, a.orientation,
                             a.cache).evaluate(q, v) for local in (axis, np.zeros(3)))

    def mount_sine(self, q) -> float | None:
        """|a₁ × u| at q, the sine of the angle between the device's axis u and its Hooke mount's
        first axis a₁ (None without a mount): the mount is singular where it is 0
        (inerter.elements.device_inertia, "The mount")."""
        if self.device is None or self.row[layout.MOUNT] == 0.0:
            return None
        z = np.zeros(len(q))                    # at rest: only the positions are read (len(v) ≤ len(q))
        (rt, *_), (ro, *_) = self._mount_points(q, z)
        a1 = np.asarray(rt - ro, dtype=float)
        r = np.asarray(self.pair.evaluate(q, z)[0], dtype=float)
        u = r / np.linalg.norm(r)
        return float(np.linalg.norm(np.cross(a1 / np.linalg.norm(a1), u)))

    def add_state_force(self, q, v, Q, z, geo=None):
        """Q −= F g for the force its internal states carry (a series connection's)."""
        geo = geo or self.geometry(q, v)
        _, Ldot = self._law_force(geo)
        F = self._state_force(self.row, geo[4], Ldot, self._x(z))
        Q[self.pair.dofs] -= F * (geo[3].T @ geo[5])

    def state_rates(self, q, v, a, z, dz):
        """dz[its states] = their rates at accelerations a (the kind's ``state_rates``, gᵀq̈ from H)."""
        r, rdot, a_n, H, L, rhat = geo = self.geometry(q, v)
        rd, an, e = np.zeros(3), np.zeros(3), np.zeros(3)
        rd[:len(rdot)], an[:len(a_n)], e[:len(rhat)] = rdot, a_n, rhat
        Ldot, an_r, perp2 = axial_scalars(*rd, *an, *e)
        gq = float((H @ a[self.pair.dofs]) @ rhat)
        out = np.zeros(self.n_states)
        self._state_rates(self.row, L, Ldot, an_r, perp2, gq, self._x(z), out)
        dz[self.states] = out
        return geo

    def state_energy(self, q, v, z) -> float:
        geo = self.geometry(q, v)
        return self._state_energy(self.row, geo[4], float(geo[1] @ geo[5]), self._x(z))

    def add_mass(self, q, v, M, geo=None):
        block = self.block(q, v)
        if block is not None:
            M[np.ix_(self.pair.dofs, self.pair.dofs)] += block[0]
        if self.inertance(0.0) == 0.0:       # none at any L̇ (a screw efficiency's b_eff is > 0 at every L̇)
            return
        geo = geo or self.geometry(q, v)
        b = self.inertance(self._scalars(geo)[1])
        g = geo[3].T @ geo[5]                                     # Hᵀ r̂
        idx = self.pair.dofs
        M[np.ix_(idx, idx)] += b * np.outer(g, g)                # M_I, Eq. (33)

    def add_force(self, q, v, Q, geo=None):
        geo = geo or self.geometry(q, v)
        F, _ = self._law_force(geo)
        Q[self.pair.dofs] -= F * (geo[3].T @ geo[5])              # Eq. (29); Q_Iv, Eq. (31)
        block = self.block(q, v)
        if block is not None:
            Q[self.pair.dofs] += block[1]

    def add_frame_force(self, q, v, Q, frame_acc):
        """Q += the inertial force −Σ m G_cᵀ a_g of a device's parts under a ground motion (its
        block's right side with the ground's acceleration less without), like the bodies' −m a_g."""
        if self.device is not None and self.device.inertia():
            Q[self.pair.dofs] += self.block(q, v, frame_acc)[1] - self.block(q, v)[1]

    def energy(self, q, v) -> float:
        geo = self.geometry(q, v)
        return self._energy(self.row, geo[4], float(geo[1] @ geo[5]))

    def stored(self, q, v, z=None) -> float:
        """The energy it adds to :meth:`Mechanism.energy` (its ``energy`` output): its law's, its
        device block's kinetic and gravitational energy, its internal states' (z None: zero)."""
        E = self.kinetic(q, v) + self.potential(q)
        return E + self.state_energy(q, v, z) if self.n_states else E

    def potential(self, q):
        """The part of :meth:`energy` that does not depend on the velocities."""
        return self._energy(self.row, self.length(q), 0.0)

    def kinetic(self, q, v):
        """The kinetic energy beyond the bodies', and (a device's masses) their weight's potential."""
        block = self.block(q, v)
        return self.energy(q, v) - self.potential(q) + (block[2] + block[3] if block is not None else 0.0)


class RotationalElement:
    """A rotational element between two planar bodies' angles (or a body and the ground), of any
    rotational kind: φ = θ_b − θ_a."""

    def __init__(self, name: str, kind: str, index_a: int, index_b: int, coefficient: float,
                 free_angle: float = 0.0):
        self.name = name
        self.kind = kind
        self.ia, self.ib = index_a, index_b     # coordinate indices of the angles, −1 for the ground
        self.coefficient = float(coefficient)
        self.coefficient_name = elements.KINDS[kind].coefficient.key
        self.free_angle = float(free_angle)
        law = elements.MODULE[kind]
        self._torque, self._energy = law.torque.py_func, law.energy.py_func
        self.row = np.array([self.coefficient, self.free_angle])

    def relative(self, q, v):
        """(φ, φ̇), twist.planar_relative."""
        return _planar_relative(q, v, self.ia, self.ib)

    def torque(self, q, v):
        return self._torque(self.row, *self.relative(q, v))

    def add_force(self, q, v, Q, geo=None):
        tau = self.torque(q, v)
        if self.ib >= 0:
            Q[self.ib] -= tau
        if self.ia >= 0:
            Q[self.ia] += tau

    def add_mass(self, q, v, M, geo=None):
        pass

    def geometry(self, q, v):
        return None

    def outputs(self, q, v, a):
        """(φ_rel, ω_rel, τ, power τ ω_rel, stored energy)."""
        phi, w = self.relative(q, v)
        tau = self._torque(self.row, phi, w)
        return phi, w, tau, tau * w, self._energy(self.row, phi, w)

    def kinetic(self, q, v):
        return 0.0

    def potential(self, q):
        return self._energy(self.row, self.relative(q, q * 0)[0], 0.0)


class SpatialRotationalElement:
    """A rotational element about an axis between two 3D bodies (or a body and the ground), of any
    rotational kind. φ is the rotation about the axis (fixed in body a; global for the ground)
    measured from the initial relative orientation, so φ(0) = 0: where the relative rotation also
    swings off the axis, the twist about it (swing-twist decomposition). Its torque acts along φ's
    gradient g (the axis on a revolute joint about it), so that a spring's force is −∇V and the
    rate is φ̇. It winds on past half a turn from :attr:`reference`, its angle at the last accepted
    step (inerter.elements.winding)."""

    def __init__(self, spec, frame_a, frame_b, q0):
        self.name = spec.name
        self.kind = spec.type
        self.coefficient_name = elements.KINDS[spec.type].coefficient.key
        self.coefficient = float(spec.coefficient)
        self.free_angle = float(spec.free_length or 0.0)
        law = elements.MODULE[spec.type]
        self._torque, self._energy = law.torque.py_func, law.energy.py_func
        self.row = np.array([self.coefficient, self.free_angle])
        self.fa, self.fb = frame_a, frame_b
        self.axis = np.asarray(spec.axis, dtype=float)
        z = np.zeros(max(frame_a.vi, frame_b.vi) + 6)
        Aa, _ = frame_a.evaluate(q0, z)
        Ab, _ = frame_b.evaluate(q0, z)
        self.rel0 = Aa.T @ Ab
        self._rel0 = tuple(self.rel0.ravel().tolist())
        #: φ_ref: the angle at the last accepted step (0 at t = 0), moved on by :meth:`wind`.
        self.reference = 0.0

    def wind(self, q):
        """After an accepted step to q: the next angles are read on the branch of this one."""
        self.reference = self.geometry(q, np.zeros(len(q)))[0]

    def rate(self, q, v):
        """φ̇ at (q, v) (Mechanism.wind's prediction of the angle at a step's end)."""
        return self.geometry(q, v)[1]

    def geometry(self, q, v):
        """(φ, φ̇, g, A_a, A_b): twist.spatial_twist."""
        Aa, wa = self.fa.evaluate(q, v)
        Ab, wb = self.fb.evaluate(q, v)
        n = self.axis
        phi, w, gx, gy, gz = _spatial_twist(tuple(Aa.ravel().tolist()), tuple(Ab.ravel().tolist()), self._rel0, 0,
                                            n[0], n[1], n[2], self.reference, *wa.tolist(), *wb.tolist())
        return phi, w, np.array((gx, gy, gz)), Aa, Ab

    def torque(self, q, v, geo=None):
        phi, w, *_ = geo or self.geometry(q, v)
        return self._torque(self.row, phi, w)

    def add_force(self, q, v, Q, geo=None):
        geo = geo or self.geometry(q, v)
        tau = self.torque(q, v, geo)
        _, _, g, Aa, Ab = geo
        if self.fb.body >= 0:
            Q[self.fb.vi + 3:self.fb.vi + 6] -= tau * (Ab.T @ g)
        if self.fa.body >= 0:
            Q[self.fa.vi + 3:self.fa.vi + 6] += tau * (Aa.T @ g)

    def add_mass(self, q, v, M, geo=None):
        pass

    def outputs(self, q, v, a):
        """(φ_rel, ω_rel, τ, power τ ω_rel, stored energy)."""
        geo = self.geometry(q, v)
        tau = self.torque(q, v, geo)
        return geo[0], geo[1], tau, tau * geo[1], self._energy(self.row, geo[0], geo[1])

    def kinetic(self, q, v):
        return 0.0

    def potential(self, q):
        return self._energy(self.row, self.geometry(q, np.zeros(len(q)))[0], 0.0)
