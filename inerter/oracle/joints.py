"""The oracle's joints: each joint's constraint C(q) = 0 written from its definition in the scene
(kind, points, axis) on Jets of the two bodies' coordinates (:mod:`.jets`), and differentiated
there, never read from :mod:`inerter.model.joints`.

The rows are the standard conditions (Nikravesh 1988; Shabana 2009, as the paper cites them):
coincident points r_b − r_a = 0, dot-1 rows s_a·s_b = 0 between a vector fixed in a and one fixed
in b, dot-2 rows s_a·(r_b − r_a) = 0; a body-fixed vector is s = A s̄ and a point r = R + A ū,
the body's rotation A written on Jets from its angle (2D) or its quaternion (3D, :func:`rotation`).
With one Jet per row, carrying the velocity coordinates' gradient and the derivatives along the
motion (q̇ = B(q) v, and q̈ at v̇ = 0),

    C = C.v,   C_v = ∂Ċ/∂v = C.g,   γ = −C̈|v̇=0 = −C.d2,

since Ċ = C_v v is linear in v, so C̈ = C_v v̇ + C̈|v̇=0 and C̈ = 0 reads C_v v̇ = γ (Eq. 26's Q_d).
The bodies' Jets are evaluated once per state and give all the rows (:class:`BodyJets`).

The rows are chosen as the model's joints choose theirs (the same perpendiculars completing the
axis, :func:`inerter.model.joints.perpendiculars`, a convention the two share; b's copies of a's
vectors taken at the initial pose), so that C, C_v, γ and the multipliers λ are comparable row by
row: the rows define the manifold and what λ means, the derivation here is
the oracle's own. A screw joint's row is the relative turn φ about the axis since the initial pose
minus ρ = 2π/p times the advance along it, φ from D = A_aᵀA_b R₀ᵀ (R₀ = A_aᵀA_b at t = 0) as
φ = atan2(½ n̄·vee(D − Dᵀ), ½(tr D − n̄ᵀDn̄)) (the rotation's axis-angle, Shabana 2009), taken
modulo 2π, and its rate is the relative angular velocity about the axis, s·(ω_b − ω_a) (a screw
turns with the relative spin about its axis), ω from ω̃ = ȦAᵀ on Jets: C_v and γ are that rate's
gradient and derivative along the motion. On the joint's manifold (the relative rotation about the
axis) it is φ's own derivative, which the oracle also takes (:attr:`OracleJoint.exact_turn`, used by
the tests to check it); off the manifold the two differ (by 0.02 to 0.1 in C_v at the random poses
of tests/test_oracle_joints.py).
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.errors import SceneError
from inerter.model.joints import perpendiculars
from inerter.oracle.jets import Jet, angular_velocity, dot, jatan2, placed, rotation, seed, times


class BodyJets:
    """The Jets of the bodies a joint or a force touches, over their velocity coordinates (each
    body's 3 or 6 in turn): each body's centre R and rotation A, once, and from them positions of
    points r = R + A ū and body-fixed vectors A s̄ (Eq. 15)."""

    def __init__(self, mech, points, q, v, full=False):
        """`full`: gradients over all the mechanism's velocity coordinates, in its order."""
        self.dim = mech.dim
        bodies = []
        for p in points:
            if p.body >= 0 and p.body not in bodies:
                bodies.append(p.body)
        nvb = 3 if self.dim == 2 else 6
        self.n = mech.n if full else nvb * len(bodies)
        self.coords = {b: seed(q, v, mech.q_index[b], mech.v_index[b], self.dim, self.n,
                               mech.v_index[b] if full else nvb * k) for k, b in enumerate(bodies)}
        self.frames = {b: (c[:self.dim], rotation(c)) for b, c in self.coords.items()}

    def point(self, p, local=None):
        """r of point p (or of the point at `local` on p's body), as Jets."""
        local = p.local if local is None else local
        if p.body < 0:
            return [Jet.constant(x, self.n) for x in local]
        return placed(*self.frames[p.body], local)

    def vector(self, p, local):
        """A s̄: the vector `local` fixed in p's body (in the ground's frame for the ground)."""
        if p.body < 0:
            return [Jet.constant(x, self.n) for x in local]
        return times(self.frames[p.body][1], local)

    def rotation(self, p):
        """A of p's body as rows of Jets (the identity for the ground)."""
        if p.body < 0:
            return [[Jet.constant(float(i == j), self.n) for j in range(self.dim)] for i in range(self.dim)]
        return self.frames[p.body][1]

    def angle(self, p):
        """θ of p's planar body (0 for the ground)."""
        return self.coords[p.body][2] if p.body >= 0 else Jet.constant(0.0, self.n)


class OracleJoint:
    """One scene joint's rows on Jets. Built from the scene's joint (its kind, points, axis, second
    axis, lead) and the mechanism's initial pose q0, where the references are read: the 2D relative
    angle φ₀, the initial advance x₀ of a screw, b's copies of a's vectors, a 3D screw's R₀."""

    def __init__(self, spec, mech, q0):
        self.name, self.kind = spec.name, spec.type
        self.mech = mech
        #: A 3D screw's turn differentiated as the angle φ itself (True) instead of by its
        #: definition's rate, the relative angular velocity about the axis (module docstring).
        self.exact_turn = False
        self.a, self.b = mech.points[spec.point_a], mech.points[spec.point_b]
        bodies = []
        for p in (self.a, self.b):
            if p.body >= 0 and p.body not in bodies:
                bodies.append(p.body)
        nvb = 3 if mech.dim == 2 else 6
        self.dofs = np.array([mech.v_index[b] + j for b in bodies for j in range(nvb)], dtype=int)
        if mech.dim == 3 and mech.orientation.kind != "quaternion":
            raise SceneError(mech.scene.source, "scene.orientation", mech.orientation.kind,
                             "orientation = \"quaternion\" for the oracle's joints",
                             f"the oracle differentiates quaternion kinematics only (joint {spec.name!r})")
        zero = np.zeros(mech.n)
        self.ratio = 2.0 * math.pi / spec.lead if spec.type == "screw" else 0.0
        if mech.dim == 2:
            self._planar(spec, BodyJets(mech, (self.a, self.b), q0, zero))
        else:
            self._spatial(spec, BodyJets(mech, (self.a, self.b), q0, zero))
        self.rows = len(self.residuals(BodyJets(mech, (self.a, self.b), q0, zero)))

    # -- definitions ---------------------------------------------------------------------------
    def _planar(self, spec, jets):
        if spec.type == "revolute":
            return
        # slider: no relative turn, b's point on the line through a's point along the axis t = A_a t̄;
        # n = A_a n̄, n̄ = t̄ turned by +90°. Screw (rack and pinion): the turn is ρ(t·d − x₀).
        self.axis = np.asarray(spec.axis, dtype=float)
        self.normal = np.array((-self.axis[1], self.axis[0]))
        self.phi0 = (jets.angle(self.b) - jets.angle(self.a)).v
        if self.ratio:
            self.advance0 = self._advance(jets).v

    def _advance(self, jets):
        """t·(r_b − r_a): the advance along the axis."""
        ra, rb = jets.point(self.a), jets.point(self.b)
        t = jets.vector(self.a, self.axis)
        return sum((ti * (y - x) for ti, x, y in zip(t, ra, rb)), Jet.constant(0.0, jets.n))

    def _spatial(self, spec, jets):
        kind = spec.type
        self.coincident = kind in ("spherical", "revolute", "universal", "fixed")
        self.dot1, self.dot2 = [], []
        if kind == "spherical":
            return
        Aa = np.array([[c.v for c in row] for row in jets.rotation(self.a)])
        Ab = np.array([[c.v for c in row] for row in jets.rotation(self.b)])

        def in_b(vec_a):                          # a's vector in b's frame at the initial pose
            return Ab.T @ (Aa @ vec_a)
        if kind == "fixed":
            ex, ey, ez = np.eye(3)
            self.dot1 = [(ex, in_b(ey)), (ey, in_b(ez)), (ez, in_b(ex))]
            return
        axis = np.asarray(spec.axis, dtype=float)
        self.axis = axis
        p1, p2 = perpendiculars(axis)
        parallel = [(p1, in_b(axis)), (p2, in_b(axis))]           # b's axis along a's
        if kind == "revolute":
            self.dot1 = parallel
        elif kind == "universal":                                  # b's axis2 at right angles to a's axis
            self.dot1 = [(axis, in_b(np.asarray(spec.axis2, dtype=float)))]
        elif kind == "planar":
            self.dot1, self.dot2 = parallel, [axis]
        elif kind in ("prismatic", "cylindrical", "screw"):
            self.dot1, self.dot2 = list(parallel), [p1, p2]        # b's point on a's line
            if kind == "prismatic":                                # and no twist about it
                self.dot1.append((p1, in_b(p2)))
            if kind == "screw" and spec.coupling_only:
                self.dot1, self.dot2 = [], []
        else:
            raise SceneError(self.mech.scene.source, f"joints.{spec.name}.type", kind,
                             "a joint kind the oracle defines (spherical, revolute, prismatic, cylindrical, "
                             "universal, planar, fixed, screw)", "the oracle has no definition of this joint kind")
        if kind == "screw":
            self.rel0 = Aa.T @ Ab
            self.advance0 = self._advance(jets).v

    def residuals(self, jets):
        """C(q) as Jets, one per row, in the model's row order."""
        ra, rb = jets.point(self.a), jets.point(self.b)
        d = [y - x for x, y in zip(ra, rb)]
        if self.mech.dim == 2:
            if self.kind == "revolute":
                return d
            turn = jets.angle(self.b) - jets.angle(self.a) - self.phi0
            if self.ratio:
                turn = turn - self.ratio * (self._advance(jets) - self.advance0)
            n = jets.vector(self.a, self.normal)
            return [turn, n[0] * d[0] + n[1] * d[1]]
        rows = list(d) if self.coincident else []
        for sa, sb in self.dot1:
            rows.append(dot(jets.vector(self.a, sa), jets.vector(self.b, sb)))
        for sa in self.dot2:
            rows.append(dot(jets.vector(self.a, sa), d))
        if self.kind == "screw":
            rows.append(self._screw(jets, d))
        return rows

    def _screw(self, jets, d):
        """φ − ρ(s·d − x₀), modulo 2π (φ: the relative turn about the axis since the initial pose),
        its rate the relative angular velocity about the axis (:meth:`_turn_rate`) or, with
        :attr:`exact_turn`, φ's own derivatives."""
        Aa, Ab = jets.rotation(self.a), jets.rotation(self.b)
        rel = [[sum((Aa[k][i] * Ab[k][j] for k in range(3)), Jet.constant(0.0, jets.n)) for j in range(3)]
               for i in range(3)]                                              # A_aᵀ A_b
        D = [[sum((rel[i][k] * float(self.rel0[j, k]) for k in range(3)), Jet.constant(0.0, jets.n))
              for j in range(3)] for i in range(3)]                            # (A_aᵀ A_b) R₀ᵀ
        n = self.axis
        sine = 0.5 * (n[0] * (D[2][1] - D[1][2]) + n[1] * (D[0][2] - D[2][0]) + n[2] * (D[1][0] - D[0][1]))
        nDn = sum((D[i][j] * float(n[i] * n[j]) for i in range(3) for j in range(3)), Jet.constant(0.0, jets.n))
        cosine = 0.5 * (D[0][0] + D[1][1] + D[2][2] - nDn)
        s = jets.vector(self.a, self.axis)
        turn = jatan2(sine, cosine) if self.exact_turn else self._turn_rate(jatan2(sine, cosine).v, Aa, Ab, s)
        c = turn - self.ratio * (dot(s, d) - self.advance0)
        return c + (math.remainder(c.v, 2.0 * math.pi) - c.v)

    @staticmethod
    def _turn_rate(phi, Aa, Ab, s):
        """The turn φ as a Jet whose rate is the relative angular velocity about the axis,
        φ̇ := s·(ω_b − ω_a), ω̃ = ȦAᵀ of each body's rotation on Jets (:func:`.jets.angular_velocity`):
        gradient s·∂(ω_b − ω_a)/∂v, and d/dt at v̇ = 0 ṡ·(ω_b − ω_a) + s·(α_b − α_a) with α the
        angular accelerations at v̇ = 0. On the joint's manifold (the relative rotation about the
        axis) this is φ's derivative; off it, the rate the joint is defined by (a screw turns with
        the relative spin about its axis, Shabana 2009)."""
        _, wa, dwa, alpha_a = angular_velocity(Aa)
        _, wb, dwb, alpha_b = angular_velocity(Ab)
        sv, sd = np.array([c.v for c in s]), np.array([c.d1 for c in s])
        return Jet(phi, float(sv @ (wb - wa)), float(sd @ (wb - wa) + sv @ (alpha_b - alpha_a)), sv @ (dwb - dwa))

    def evaluate(self, q, v):
        """(C, C_v over :attr:`dofs`, γ) at (q, v), from one evaluation of the joint's Jets."""
        rows = self.residuals(BodyJets(self.mech, (self.a, self.b), q, v))
        return (np.array([r.v for r in rows]), np.array([r.g for r in rows]).reshape(len(rows), -1),
                np.array([-r.d2 for r in rows]))

