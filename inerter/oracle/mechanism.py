"""The oracle's mechanism: the compiled :class:`~inerter.model.mechanism.Mechanism` with its joints,
point forces, gravity and ground motion derived here on Jets (:mod:`.jets`) from their definitions,
and its elements from :class:`~.derivation.OracleElement`.

* Joints (:mod:`.joints`): C(q) written from each joint's definition, C_v = ∂Ċ/∂v and
  γ = −C̈|v̇=0 by differentiation.
* Point forces, by virtual work: a force F at a point r(q) does δW = F·δr = F·(∂ṙ/∂v) δv, so its
  generalised force is (∂ṙ/∂v)ᵀ F, ∂ṙ/∂v the gradient of r's Jets (Kane & Levinson 1985, partial
  velocities). A PD actuator along the fixed unit d: F = −[k_p(d·r − ref) + k_d d·ṙ] d, with r and
  ṙ the Jet's value and first derivative.
* Gravity: the potential V = −Σ m g·r_c of the bodies' centres r_c (the coordinates R), Q = −∂V/∂v
  (V on Jets of the coordinates, its gradient over the velocity coordinates). V is linear in R,
  whose rates Ṙ are velocity coordinates, so Q is the same at every pose: derived once, at the
  scene's pose.
* Ground motion: the bodies' coordinates are relative to the ground, which accelerates by a_g; in
  that frame each body's centre carries the d'Alembert force −m a_g (Shabana 2009, moving frames),
  whose generalised force is −m (∂Ṙ/∂v)ᵀ a_g by virtual work (∂Ṙ/∂v read off the centres' Jets,
  the same at every pose). An inerter device's housing, rod and flywheel take theirs from
  :meth:`~.derivation.OracleElement.add_frame_force`.

* Internal states (an inerter device's series deflection s, its rate, its dissipated energy; the
  engine's z layout, each element's slice ``states``): each series connection's s is one more
  coordinate (:mod:`.series`); Lagrange's equations on (v, ṡ) with the joints' rows give one system
  for (v̇, s̈, λ) (:meth:`OracleMechanism.extended_accelerations`), ż = (ṡ, s̈, p_loss).

* Screw efficiencies (:mod:`.efficiency`): the system is assembled once with each efficient
  element's ideal inerter term and solved once per assignment of their modes σ ∈ {±1}ⁿ, each
  adding λ(τ) times those terms; the assignment its solution agrees with is kept
  (:meth:`OracleMechanism.accelerations`).

* The bodies' mass matrix, velocity forces and energy (:mod:`.bodies`): from each body's kinetic
  energy T on Jets, M's columns as ∂T/∂v at unit velocities, −ω̄ × ∂T/∂ω̄ on a 3D body's ω̄
  (Boltzmann–Hamel), and T itself with the weight's V in the mechanism's energy.

What stays the Mechanism's is the formulation: the coordinates, the assembly of Eq. (33) from the
terms above and its solution."""
from __future__ import annotations

import numpy as np

from inerter.common.errors import SceneError
from inerter.model.mechanism import Mechanism
from inerter.oracle import bodies
from inerter.oracle.derivation import OracleElement
from inerter.oracle.efficiency import resolve
from inerter.oracle.jets import Jet
from inerter.oracle.joints import BodyJets, OracleJoint


def centre_jets(mech, q, v):
    """The bodies' centres R as Jets over all velocity coordinates (Ṙ = v, R̈|v̇=0 = 0)."""
    out = []
    for qi, vi in zip(mech.q_index, mech.v_index):
        jets = []
        for j in range(mech.dim):
            g = np.zeros(mech.n)
            g[vi + j] = 1.0
            jets.append(Jet(float(q[qi + j]), float(v[vi + j]), 0.0, g))
        out.append(jets)
    return out


def _virtual_work(F, r):
    """(∂ṙ/∂v)ᵀ F of a force F at the point whose position's Jets are r (δW = F·δr)."""
    return sum(float(fi) * c.g for fi, c in zip(F, r))


def _pd_law(f, r, static=False):
    """A PD actuator's force along its fixed unit d, F = −[k_p(d·r − ref) + k_d d·ṙ] d, with r and ṙ
    the value and first derivative of its point's Jets r (`static`: without the rate term, for the
    static equilibrium)."""
    d = np.asarray(f.direction, dtype=float)
    along = sum(float(di) * c.v for di, c in zip(d, r)) - f.reference
    rate = 0.0 if static else sum(float(di) * c.d1 for di, c in zip(d, r))
    return -(f.kp * along + f.kd * rate) * d


class OracleMechanism(Mechanism):
    """A scene compiled with the oracle's elements, joints, point forces, gravity, ground motion and
    bodies' inertia (module docstring); the coordinates and the solution of Eq. 33 are the
    Mechanism's."""

    def __init__(self, scene):
        super().__init__(scene, element_factory=OracleElement)
        #: The elements with a series connection, each with one more coordinate s (:mod:`.series`),
        #: numbered after the n velocity coordinates in the extended system.
        self.series = [e for e in self.stateful if getattr(e, "series", None) is not None]
        self._solved = None                 # (state, s̈) of the last extended solve
        #: The elements with a screw efficiency, rigid or in series, whose modes each evaluation
        #: resolves by trying every assignment (:meth:`accelerations`, :mod:`.efficiency`).
        self.screws = [e for e in self.elements if getattr(e, "efficiency", None) is not None]

    # -- the bodies' inertia ---------------------------------------------------------------------
    def _bodies(self, scene):
        """As the Mechanism's, with the mass matrix derived from the bodies' T (:mod:`.bodies`)."""
        start = super()._bodies(scene)
        nvb = self.n // max(len(self.body_names), 1)
        self._blocks = [bodies.mass_block(b, self.dim) for b in scene.bodies.values()]
        self.M0 = np.zeros((self.n, self.n))
        for k, block in zip(self.v_index, self._blocks):
            self.M0[k:k + nvb, k:k + nvb] = block
        return start

    def body_forces(self, v):
        """−ω̄ × ∂T/∂ω̄ on each 3D body's ω̄ (:func:`.bodies.velocity_force`)."""
        Q = np.zeros(self.n)
        for k, block in zip(self.v_index, self._blocks):
            Q[k:k + 6] += bodies.velocity_force(block, v[k:k + 6])
        return Q

    def body_energy(self, i, q, v) -> float:
        """Body i's T (:func:`.bodies.kinetic_energy`) and its weight's potential V = −m g·R, both
        written from the scene's body."""
        body = list(self.scene.bodies.values())[i]
        k, j, nvb = self.q_index[i], self.v_index[i], 3 if self.dim == 2 else 6
        T = bodies.kinetic_energy(body, self.dim, v[j:j + nvb]).v
        g = self.scene.effects.get("gravity")
        V = 0.0 if self.gravity is None else -float(body.mass) * float(np.dot(g, q[k:k + self.dim]))
        return T + V

    def terms(self) -> list[str]:
        """The Mechanism's description, its first line naming what the oracle derives."""
        lines = super().terms()
        lines[0] = lines[0].replace("oracle: element forces from d²L/dt² by automatic differentiation",
                                    "oracle: element forces, joints, point forces, weight, ground motion and the "
                                    "bodies' inertia by automatic differentiation")
        return lines

    # -- joints ----------------------------------------------------------------------------------
    @property
    def derived_joints(self):
        """The joints as :class:`.joints.OracleJoint`, built at the scene's pose on first use (the
        Mechanism assembles its initial pose with :meth:`constraints` while it is being built)."""
        if "_derived" not in self.__dict__:
            self._derived = [OracleJoint(j, self, self.initial_q) for j in self.scene.joints.values()]
        return self._derived

    def body_jets(self, q, v):
        """The Jets of the bodies that joints and point forces touch, over all velocity coordinates,
        at (q, v): kept for the next call at the same state (Eq. 33 asks for the forces and the
        constraints at one state), so that each body's rotation is written once per state."""
        key = (np.asarray(q, dtype=float).tobytes(), np.asarray(v, dtype=float).tobytes())
        cached = self.__dict__.get("_jets")
        if cached is None or cached[0] != key:
            points = [p for j in self.derived_joints for p in (j.a, j.b)]
            points += [p for _, p, _ in self.applied] + [p for _, p in self.feedback + self.input_forces]
            cached = self._jets = (key, BodyJets(self, points, q, v, full=True))
        return cached[1]

    def constraints(self, q, v):
        """(C, C_v, γ) stacked over the joints: C, its gradient and −C̈|v̇=0 of each row's Jet, on
        one set of the bodies' Jets (each body's rotation written once per call)."""
        joints = self.derived_joints
        if not joints:
            return np.zeros(0), np.zeros((0, self.n)), np.zeros(0)
        jets = self.body_jets(q, v)
        rows = [r for j in joints for r in j.residuals(jets)]
        return (np.array([r.v for r in rows]), np.array([r.g for r in rows]),
                np.array([-r.d2 for r in rows]))

    # -- point forces ----------------------------------------------------------------------------
    def _forces(self, scene):
        """As the Mechanism's; refused in a 3D scene in Z-X-Z Euler angles, where the Jets of a
        body's pose, written on its quaternion, do not apply."""
        super()._forces(scene)
        if self.dim == 3 and self.orientation.kind != "quaternion" and scene.forces:
            name = next(iter(scene.forces))
            raise SceneError(scene.source, "scene.orientation", self.orientation.kind,
                             "orientation = \"quaternion\" for the oracle's point forces",
                             f"the oracle differentiates quaternion kinematics only (force {name!r})")

    def _add_point_force(self, Q, point, q, F):
        """Q += (∂ṙ/∂v)ᵀ F over the point's body (virtual work; nothing for a ground point)."""
        if point.body < 0:
            return
        jets = BodyJets(self, (point,), q, np.zeros(self.n))
        dofs = slice(self.v_index[point.body], self.v_index[point.body] + jets.n)
        Q[dofs] += _virtual_work(F, jets.point(point))

    def _pd_force(self, f, point, q, v, static=False):
        """The PD actuator's force (:func:`_pd_law`) at (q, v), for the static equilibrium too."""
        return _pd_law(f, BodyJets(self, (point,), q, v).point(point), static)

    def point_forces(self, t, q, v, inputs=None):
        """Σ (∂ṙ/∂v)ᵀ F over the applied, PD and input forces, on one set of the bodies' Jets
        (∂ṙ/∂v does not depend on v; the PD law reads r and ṙ from the same Jets)."""
        forces = [(point, fn(t) * np.asarray(f.direction, dtype=float)) for f, point, fn in self.applied]
        if inputs is not None and len(inputs):
            forces += [(point, np.asarray(inputs[k * self.dim:(k + 1) * self.dim], dtype=float))
                       for k, (f, point) in enumerate(self.input_forces)]
        Q = np.zeros(self.n)
        if not forces and not self.feedback:
            return Q
        jets = self.body_jets(q, v)
        forces += [(point, _pd_law(f, jets.point(point))) for f, point in self.feedback]
        for point, F in forces:
            if point.body >= 0:
                Q += _virtual_work(F, jets.point(point))
        return Q

    # -- gravity and the ground motion -----------------------------------------------------------
    def _effects(self, scene):
        """As the Mechanism's, with the weight −∂V/∂v derived (V = −Σ m g·R on Jets)."""
        super()._effects(scene)
        centres = centre_jets(self, self.initial_q, np.zeros(self.n))
        #: ∂Ṙ/∂v of each body's centre, dim × n: the same at every pose (Ṙ are velocity coordinates).
        self.centre_rates = [np.array([x.g for x in R]) for R in centres]
        g = scene.effects.get("gravity")
        if self.gravity is None:
            return
        V = Jet.constant(0.0, self.n)
        for m, R in zip(self.masses, centres):
            for gi, x in zip(g, R):
                V = V - float(m * gi) * x
        self.gravity = -V.g

    def frame_force(self, q, a_g):
        """The bodies' d'Alembert forces −m a_g at their centres, as generalised forces
        −m (∂Ṙ/∂v)ᵀ a_g (virtual work)."""
        Q = np.zeros(self.n)
        a_g = np.asarray(a_g, dtype=float)
        for m, G in zip(self.masses, self.centre_rates):
            Q -= m * (G.T @ a_g)
        return Q

    def add_state_forces(self, q, v, Q, z):
        """Nothing: a series connection's forces are terms of its extended system
        (:meth:`extended_accelerations`), not forces at given states."""

    # -- internal states and the screw efficiencies' modes ---------------------------------------
    def accelerations(self, t, q, v, inputs=None, alpha=0.0, z=None):
        """(v̇, λ) of Eq. (33), extended by the series connections' coordinates; with screw
        efficiencies, in the modes of the one assignment σ ∈ {±1}ⁿ whose solution's stroke
        accelerations agree with it in sign (:func:`.efficiency.resolve`), those modes left set for
        the outputs and the state rates at this state. The system is assembled once with each
        screw's ideal inerter term b G Gᵀ, −b ẍ₀ G (G = ∇ẋ over its dofs, and its s in series); each
        assignment adds λ(τ) times that term (b_eff = b (1 + λ)) and is solved."""
        if not self.screws:
            return self._accelerations(t, q, v, inputs, alpha, z)
        z = self.z0 if z is None else np.asarray(z, dtype=float)
        for e in self.screws:
            e.mode = None                   # the ideal inerter's term, b
        K, rhs = self._system(t, q, v, inputs, alpha, z)
        series = {id(e): self.n + k for k, e in enumerate(self.series)}
        terms = [(e, np.append(e.probe.dofs, series[id(e)]) if id(e) in series else np.asarray(e.probe.dofs))
                 + e.screw_term(q, v, z) for e in self.screws]

        def solve():
            Km, r = K.copy(), rhs.copy()
            for e, idx, G, x0, rate in terms:
                extra = e.b_eff(rate) - e.coefficient           # b λ(τ) in the mode set
                Km[np.ix_(idx, idx)] += extra * np.outer(G, G)
                r[idx] -= extra * x0 * G
            x = self._solve(Km, r, t)
            return x, [(float(G @ x[idx]) + x0, float(np.abs(G) @ np.abs(x[idx])) + abs(x0))
                       for _, idx, G, x0, _ in terms]
        x = resolve(self.screws, solve, [e.name for e in self.screws], t)
        n, N = self.n, self.n + len(self.series)
        self._solved = (self._state_key(q, v, z, x[:n]), x[n:N].copy())
        return x[:n], x[N:]

    def _accelerations(self, t, q, v, inputs, alpha, z):
        """(v̇, λ): Eq. (33), extended by the series connections' coordinates where there are some."""
        if not self.series:
            return super()._accelerations(t, q, v, inputs, alpha, z)
        a, sdd, lam = self.extended_accelerations(t, q, v, inputs, alpha, z)
        return a, lam

    def _system(self, t, q, v, inputs, alpha, z):
        """(K, rhs) of the extended system in (v̇, s̈, λ): the bodies' and elements' M and Q
        (:meth:`assemble`), each series element's block over (its dofs, its s)
        (:meth:`~.derivation.OracleElement.extended`: [[b g gᵀ, −b g], [−b gᵀ, b]] and its forces) and
        the joints' rows, padded with zeros in the s columns (a joint does not touch the series node),
        with Baumgarte's α as Eq. (33)."""
        n, N, m = self.n, self.n + len(self.series), self.m
        M, Q = self.assemble(t, q, v, inputs, z=z)
        K, rhs = np.zeros((N + m, N + m)), np.zeros(N + m)
        K[:n, :n], rhs[:n] = M, Q
        for k, e in enumerate(self.series):
            idx = np.append(e.probe.dofs, n + k)
            Me, Qe = e.extended(q, v, z)
            K[np.ix_(idx, idx)] += Me
            rhs[idx] += Qe
        if m:
            C, Cq, gamma = self.constraints(q, v)
            K[:n, N:], K[N:, :n] = Cq.T, Cq
            rhs[N:] = gamma - 2.0 * alpha * (Cq @ v) - alpha * alpha * C     # Baumgarte
        return K, rhs

    def extended_accelerations(self, t, q, v, inputs=None, alpha=0.0, z=None):
        """(v̇, s̈, λ) from one system (:meth:`_system`), in the screw efficiencies' modes set."""
        z = self.z0 if z is None else np.asarray(z, dtype=float)
        n, N = self.n, self.n + len(self.series)
        x = self._solve(*self._system(t, q, v, inputs, alpha, z), t)
        self._solved = (self._state_key(q, v, z, x[:n]), x[n:N].copy())
        return x[:n], x[n:N], x[N:]

    @staticmethod
    def _state_key(q, v, z, a):
        return b"".join(np.asarray(y, dtype=float).tobytes() for y in (q, v, z, a))

    def _series_accelerations(self, q, v, z, a):
        """s̈ at the accelerations a: the last extended solve's at this state, else each series
        coordinate's own row of that system, b s̈ − b gᵀv̇ = Q_s, solved for s̈ (the s rows couple
        to nothing but their element's dofs)."""
        if self._solved is not None and self._solved[0] == self._state_key(q, v, z, a):
            return self._solved[1]
        return np.array([e.series_acceleration(q, v, z, a) for e in self.series])

    def state_rates(self, q, v, z, a) -> np.ndarray:
        """ż at (q, v, z) and the accelerations a: (ṡ, s̈) of each series connection, then the
        dissipated energy's rate p_loss, in each element's slice of z (the engine's layout)."""
        z = np.asarray(z, dtype=float)
        dz = np.zeros(len(z))
        sdd = dict(zip(map(id, self.series), self._series_accelerations(q, v, z, a))) if self.series else {}
        for e in self.stateful:
            e.state_rates(q, v, z, a, sdd.get(id(e), 0.0), dz)
        return dz
