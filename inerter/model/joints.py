"""Joint constraints C(q) = 0 with their Jacobian C_v (over velocity coordinates) and the right
side γ of C_v v̇ = γ (Eq. 26's Q_d). Standard forms (Nikravesh 1988; Shabana 2009, as cited by
the paper): points that coincide, and the dot-1 / dot-2 conditions on body-fixed vectors.

Each row's C, coefficients and γ are :mod:`inerter.elements.joint_rows`' laws, the definitions the
engine's kernels compile in, run here as written; this module places their coefficients into
the joint's rows over the bodies' velocity coordinates (a translational coefficient t as tᵀH on
the points' Jacobian H, Eq. 22).
"""
from __future__ import annotations

import math

import numpy as np

from inerter.elements.joint_rows import dot1_row, dot2_row, screw_row, screw_turn_2d, slider_rows_2d


class Coincident:
    """Two points coincide, C = r_b − r_a = 0: the planar revolute joint (2 rows) and the spatial
    spherical joint (3 rows). C_v = H and γ = −a_n by Eqs. (18–19), since r̈ = H v̇ + a_n = 0."""

    def __init__(self, name: str, kind: str, pair):
        self.name, self.kind, self.pair = name, kind, pair
        self.dofs = pair.dofs
        self.rows = len(pair.a.local)

    def evaluate(self, q, v):
        r, rdot, a_n, H = self.pair.evaluate(q, v)
        return r, H, -a_n


class Prismatic2D:
    """Planar slider: no relative rotation, and point b stays on the line through point a along
    `axis` (fixed in a's body). Rows: θ_b − θ_a − φ0 = 0 and n·(r_b − r_a) = 0, n = A_a n̄
    (:func:`~inerter.elements.joint_rows.slider_rows_2d`)."""

    kind = "prismatic"
    rows = 2

    def __init__(self, name: str, pair, axis, angle_index_a: int, angle_index_b: int, phi0: float,
                 lead: float = 0.0, advance0: float = 0.0):
        self.name = name
        self.pair = pair
        self.dofs = pair.dofs
        self.normal = np.array((-axis[1], axis[0]), dtype=float)
        self.phi0 = float(phi0)
        self.ia, self.ib = angle_index_a, angle_index_b
        # A 2D screw (rack and pinion): b turns by ρ = 2π/p per unit of its advance t·d along the axis
        # t = A_a t̄ since the initial advance x₀; the first row becomes θ_b − θ_a − φ0 − ρ(t·d − x₀)
        # (joint_rows.screw_turn_2d).
        self.ratio = 2.0 * math.pi / lead if lead else 0.0
        self.advance0 = float(advance0)
        if lead:
            self.kind = "screw"

    def evaluate(self, q, v):
        pair = self.pair
        d, ddot, a_n, H = pair.evaluate(q, v)
        has_a = pair.a.dofs is not None
        k = len(self.dofs)
        th_a, wa = (q[self.ia], v[self.ia]) if self.ia >= 0 else (0.0, 0.0)
        th_b, wb = (q[self.ib], v[self.ib]) if self.ib >= 0 else (0.0, 0.0)
        c1, _, c2, nx, ny, turn, gamma2 = slider_rows_2d(has_a, th_a, th_b, wa, wb, self.phi0, self.normal[0],
                                                         self.normal[1], d[0], d[1], ddot[0], ddot[1], a_n[0], a_n[1])
        Cq = np.zeros((2, k))
        if has_a:
            Cq[0, 2] = -1.0
        if pair.b.dofs is not None:
            Cq[0, k - 1] = 1.0
        Cq[1] = nx * H[0] + ny * H[1]                           # ∂(n·d)/∂q through d
        if has_a:
            Cq[1, 2] += turn                                    # ... and through n
        gamma1 = 0.0
        if self.ratio:
            c1, tx, ty, turn, gamma1 = screw_turn_2d(self.ratio, self.advance0, c1, nx, ny, wa, d[0], d[1],
                                                     ddot[0], ddot[1], a_n[0], a_n[1])
            Cq[0] -= self.ratio * (tx * H[0] + ty * H[1])
            if has_a:
                Cq[0, 2] -= self.ratio * turn
        return np.array((c1, c2)), Cq, np.array((gamma1, gamma2))


def _rotation9(frame, q, v):
    """A body frame's rotation as the laws take it (a row-major 9-tuple) and its body-frame ω̄."""
    A, w = frame.evaluate(q, v)
    return tuple(float(x) for x in A.ravel()), w


class Screw:
    """The screw (helical) row (:func:`~inerter.elements.joint_rows.screw_row`): b turns relative to
    a about the axis s = A_a s̄ by ρ = 2π/p per unit of its advance along it,
    C = φ − ρ(s·(r_b − r_a) − x₀) = 0 (mod 2π: φ, the relative turn since the initial pose, is an
    angle), with its Jacobian taken where the relative rotation is about the axis (the cylindrical
    rows, or the mechanism's other joints, keep it so)."""

    def __init__(self, axis, rel0, lead, advance0):
        self.axis = np.asarray(axis, dtype=float)
        self.rel0 = np.asarray(rel0, dtype=float)
        self._rel0 = self.rel0.ravel()
        self.ratio = 2.0 * math.pi / lead
        self.advance0 = float(advance0)

    def evaluate(self, Aa, wa, Ab, wb, d, ddot, a_n, H, wa_cols, wb_cols):
        """(C, its row over the joint's dofs, γ) from the bodies' rotations (9-tuples) and ω̄ and
        the points' relative kinematics; wa_cols, wb_cols: the bodies' ω̄ columns (None: ground)."""
        c, tx, ty, tz, ax, ay, az, nx, ny, nz, bx, by, bz, gamma = screw_row(
            Aa, *wa, Ab, *wb, *self.axis, self._rel0, self.ratio, self.advance0, *d, *ddot, *a_n)
        row = tx * H[0] + ty * H[1] + tz * H[2]
        if wa_cols is not None:
            row[wa_cols] += (ax + nx, ay + ny, az + nz)
        if wb_cols is not None:
            row[wb_cols] += (bx, by, bz)
        return c, row, gamma


class SpatialJoint:
    """A 3D joint as rows of three kinds over the two bodies' velocity coordinates:
    coincident points (3 rows), dot-1 rows s_a·s_b = 0, dot-2 rows s_a·(r_b − r_a) = 0
    (:func:`~inerter.elements.joint_rows.dot1_row`, :func:`~inerter.elements.joint_rows.dot2_row`;
    `dot1`: pairs (s̄_a, s̄_b) in a's and b's frames, `dot2`: s̄_a)."""

    def __init__(self, name, kind, pair, frame_a, frame_b, dot1=(), dot2=(), coincident=True, screw=None):
        self.name, self.kind, self.pair = name, kind, pair
        self.dofs = pair.dofs
        self.has_a = pair.a.dofs is not None
        self.has_b = pair.b.dofs is not None
        self.coincident = coincident
        self.frame_a, self.frame_b = frame_a, frame_b
        self.dot1 = [(np.asarray(sa, dtype=float), np.asarray(sb, dtype=float)) for sa, sb in dot1]
        self.dot2 = [np.asarray(sa, dtype=float) for sa in dot2]
        self.screw = screw                                       # a Screw row, last
        self.rows = (3 if coincident else 0) + len(self.dot1) + len(self.dot2) + (screw is not None)
        self._wa = slice(3, 6)                                  # a's ω columns within dofs
        self._wb = slice(9, 12) if self.has_a else slice(3, 6)  # b's ω columns within dofs

    def evaluate(self, q, v):
        d, ddot, a_n, H = self.pair.evaluate(q, v)
        Aa, wa = _rotation9(self.frame_a, q, v)
        Ab, wb = _rotation9(self.frame_b, q, v)
        k = len(self.dofs)
        C, rows, gamma = [], [], []
        if self.coincident:
            C.extend(d)
            rows.extend(H)
            gamma.extend(-a_n)
        for sa, sb in self.dot1:
            c, ax, ay, az, bx, by, bz, g = dot1_row(Aa, *wa, *sa, Ab, *wb, *sb)
            row = np.zeros(k)
            if self.has_a:
                row[self._wa] = (ax, ay, az)
            if self.has_b:
                row[self._wb] = (bx, by, bz)
            C.append(c)
            rows.append(row)
            gamma.append(g)
        for sa in self.dot2:
            c, sx, sy, sz, ax, ay, az, g = dot2_row(Aa, *wa, *sa, *d, *ddot, *a_n)
            row = sx * H[0] + sy * H[1] + sz * H[2]
            if self.has_a:
                row[self._wa] += (ax, ay, az)
            C.append(c)
            rows.append(row)
            gamma.append(g)
        if self.screw is not None:
            c, row, g = self.screw.evaluate(Aa, wa, Ab, wb, d, ddot, a_n, H, self._wa if self.has_a else None,
                                            self._wb if self.has_b else None)
            C.append(c)
            rows.append(row)
            gamma.append(g)
        return np.array(C), np.array(rows), np.array(gamma)


def perpendiculars(axis):
    """Two unit vectors completing `axis` to a right-handed orthonormal frame: n̂ × h normalised,
    h the x axis (the y axis where n̂ is within about 26° of x), then n̂ × that. A convention, not
    physics: it picks which rows a joint's axis condition is written as (and so what its
    multipliers λ mean), and the oracle's joints take the same (inerter.oracle.joints)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    helper = np.array((1.0, 0.0, 0.0)) if abs(a[0]) < 0.9 else np.array((0.0, 1.0, 0.0))
    p1 = np.cross(a, helper)
    p1 /= np.linalg.norm(p1)
    return p1, np.cross(a, p1)


def make_joint(spec, mech, q0):
    """The joint object for a scene joint, on the mechanism's points and body frames."""
    pair = mech.pair(spec.point_a, spec.point_b)
    if mech.dim == 2:
        if spec.type == "revolute":
            return Coincident(spec.name, "revolute", pair)
        body_a = mech.scene.points[spec.point_a].body
        body_b = mech.scene.points[spec.point_b].body
        ia, ib = mech.angle_index(body_a), mech.angle_index(body_b)
        phi0 = (q0[ib] if ib >= 0 else 0.0) - (q0[ia] if ia >= 0 else 0.0)
        if spec.type == "screw":
            d0 = pair.evaluate(q0, np.zeros(mech.n))[0]
            th = q0[ia] if ia >= 0 else 0.0
            t = np.array((math.cos(th) * spec.axis[0] - math.sin(th) * spec.axis[1],
                          math.sin(th) * spec.axis[0] + math.cos(th) * spec.axis[1]))
            return Prismatic2D(spec.name, pair, spec.axis, ia, ib, phi0, spec.lead, float(t @ d0))
        return Prismatic2D(spec.name, pair, spec.axis, ia, ib, phi0)

    if spec.type == "spherical":
        return Coincident(spec.name, "spherical", pair)
    fa = mech.frames[mech.scene.points[spec.point_a].body]
    fb = mech.frames[mech.scene.points[spec.point_b].body]
    z = np.zeros(mech.n)
    Aa, _ = fa.evaluate(q0, z)
    Ab, _ = fb.evaluate(q0, z)

    def in_b(vec_a):
        """A vector fixed in a's frame, expressed in b's frame at the initial pose."""
        return Ab.T @ (Aa @ vec_a)

    if spec.type == "fixed":
        ex, ey, ez = np.eye(3)
        dot1 = [(ex, in_b(ey)), (ey, in_b(ez)), (ez, in_b(ex))]
        return SpatialJoint(spec.name, "fixed", pair, fa, fb, dot1=dot1)
    axis = np.asarray(spec.axis, dtype=float)
    p1, p2 = perpendiculars(axis)
    if spec.type == "screw":
        rows = dict(coincident=False) if spec.coupling_only else _cylindrical_rows(axis, p1, p2, in_b, spec)
        d0 = pair.evaluate(q0, z)[0]
        screw = Screw(axis, Aa.T @ Ab, spec.lead, float((Aa @ axis) @ d0))
        return SpatialJoint(spec.name, "screw", pair, fa, fb, screw=screw, **rows)
    rows = _SPATIAL_ROWS[spec.type](axis, p1, p2, in_b, spec)
    return SpatialJoint(spec.name, spec.type, pair, fa, fb, **rows)


def _revolute_rows(axis, p1, p2, in_b, spec):
    """Points coincide; b's copy of the axis stays perpendicular to a's two normals (1 DOF)."""
    return dict(dot1=[(p1, in_b(axis)), (p2, in_b(axis))])


def _prismatic_rows(axis, p1, p2, in_b, spec):
    """Axes parallel, no twist about them, and b's point on a's line through its point (1 DOF)."""
    return dict(dot1=[(p1, in_b(axis)), (p2, in_b(axis)), (p1, in_b(p2))], dot2=[p1, p2], coincident=False)


def _cylindrical_rows(axis, p1, p2, in_b, spec):
    """The prismatic joint without its twist row: b slides along and turns about a's axis (2 DOF)."""
    return dict(dot1=[(p1, in_b(axis)), (p2, in_b(axis))], dot2=[p1, p2], coincident=False)


def _universal_rows(axis, p1, p2, in_b, spec):
    """Points coincide, and b's axis (`axis2`, fixed in b) stays perpendicular to a's `axis`: the
    Cardan (Hooke) joint, two rotations and no twist (2 DOF)."""
    return dict(dot1=[(axis, in_b(np.asarray(spec.axis2, dtype=float)))])


def _planar_rows(axis, p1, p2, in_b, spec):
    """b's copy of the normal `axis` stays parallel to a's, and b's point in the plane through a's
    point normal to it: two slides in the plane and a turn about the normal (3 DOF)."""
    return dict(dot1=[(p1, in_b(axis)), (p2, in_b(axis))], dot2=[axis], coincident=False)


#: The rows of each 3D joint kind with an axis (Shabana 2009's dot-1/dot-2 conditions), from the
#: axis in a's frame, two perpendiculars completing it, and a's vectors carried into b's frame.
_SPATIAL_ROWS = {"revolute": _revolute_rows, "prismatic": _prismatic_rows, "cylindrical": _cylindrical_rows,
                 "universal": _universal_rows, "planar": _planar_rows}
