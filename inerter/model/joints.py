"""Joint constraints C(q) = 0 with their Jacobian C_v (over velocity coordinates) and the right
side γ of C_v v̇ = γ (Eq. 26's Q_d). Standard forms (Nikravesh 1988; Shabana 2009, as cited by
the paper): points that coincide, and the dot-1 / dot-2 conditions on body-fixed vectors.
"""
from __future__ import annotations

import math

import numpy as np

from inerter.model.spatial import cross, skew


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
    `axis` (fixed in a's body). Rows: θ_b − θ_a − φ0 = 0 and n·(r_b − r_a) = 0, n = A_a n̄."""

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
        # t = A_a t̄ since the initial advance x₀; the first row becomes θ_b − θ_a − φ0 − ρ(t·d − x₀).
        self.ratio = 2.0 * math.pi / lead if lead else 0.0
        self.advance0 = float(advance0)
        if lead:
            self.kind = "screw"

    def evaluate(self, q, v):
        pair = self.pair
        d, ddot, a_n, H = pair.evaluate(q, v)
        has_a = pair.a.dofs is not None
        k = len(self.dofs)
        Cq = np.zeros((2, k))
        th_a = q[self.ia] if self.ia >= 0 else 0.0
        th_b = q[self.ib] if self.ib >= 0 else 0.0
        c1 = th_b - th_a - self.phi0
        if has_a:
            Cq[0, 2] = -1.0
        if pair.b.dofs is not None:
            Cq[0, k - 1] = 1.0
        if has_a:
            c, s = math.cos(th_a), math.sin(th_a)
            n = np.array((c * self.normal[0] - s * self.normal[1], s * self.normal[0] + c * self.normal[1]))
            wa = v[self.ia]
        else:
            n, wa = self.normal, 0.0
        n_perp = np.array((-n[1], n[0]))                       # dn/dθ_a
        c2 = float(n @ d)
        Cq[1] = n @ H                                           # ∂(n·d)/∂q through d
        if has_a:
            Cq[1, 2] += float(n_perp @ d)                       # ... and through n
        # C̈ = n·(H q̈ + a_n) + θ̈_a n⊥·d − θ̇_a² n·d + 2 θ̇_a n⊥·ḋ
        gamma2 = -(float(n @ a_n) - wa * wa * c2 + 2.0 * wa * float(n_perp @ ddot))
        gamma1 = 0.0
        if self.ratio:
            t = -n_perp                                         # the axis; dt/dθ_a = n
            c1 -= self.ratio * (float(t @ d) - self.advance0)
            Cq[0] -= self.ratio * (t @ H)
            if has_a:
                Cq[0, 2] -= self.ratio * float(n @ d)
            # (t·d)¨ = t·(H q̈ + a_n) + θ̈_a n·d − θ̇_a² t·d + 2 θ̇_a n·ḋ
            gamma1 = self.ratio * (float(t @ a_n) - wa * wa * float(t @ d) + 2.0 * wa * float(n @ ddot))
        return np.array((c1, c2)), Cq, np.array((gamma1, gamma2))


class _Vector:
    """A body-fixed unit vector s = A s̄: its value, rate and ∂ṡ/∂ω (body-frame ω)."""

    def __init__(self, frame, local):
        self.frame = frame
        self.local = np.asarray(local, dtype=float)
        self._skew = skew(self.local)

    def evaluate(self, q, v):
        A, w = self.frame.evaluate(q, v)
        s = A @ self.local
        wxs = cross(w, self.local)
        sdot = A @ wxs
        s_acc = A @ cross(w, wxs)                            # s̈ at ω̇ = 0
        return s, sdot, s_acc, -A @ self._skew                  # ∂ṡ/∂ω = −A s̄~


def relative_angle(Aa, Ab, rel0, axis):
    """The rotation of b relative to a about `axis` (a unit vector in a's frame) since the relative
    orientation rel0 = A_aᵀA_b: with D = (A_aᵀA_b) rel0ᵀ, φ = atan2(½ n̄·vee(D − Dᵀ), ½(tr D − n̄ᵀDn̄)),
    exact while the relative rotation is about the axis (Shabana 2009, the rotation's axis-angle)."""
    D = (Aa.T @ Ab) @ rel0.T
    n = axis
    s = 0.5 * (n[0] * (D[2, 1] - D[1, 2]) + n[1] * (D[0, 2] - D[2, 0]) + n[2] * (D[1, 0] - D[0, 1]))
    c = 0.5 * (np.trace(D) - float(n @ D @ n))
    return math.atan2(s, c)


class Screw:
    """The screw (helical) row: b turns relative to a about the axis s = A_a s̄ by ρ = 2π/p per unit
    of its advance along it, C = φ − ρ(s·(r_b − r_a) − x₀) = 0 (mod 2π: φ, the relative turn since
    the initial pose, :func:`relative_angle`, is an angle). Its Jacobian, taken where the relative
    rotation is about the axis (the cylindrical rows, or the mechanism's other joints, keep it so):

        Ċ = s·(ω_b − ω_a) − ρ (s·(ṙ_b − ṙ_a) + ṡ·(r_b − r_a)),

    over body-frame ω: s·ω_a = s̄·ω̄_a, s·ω_b = (A_bᵀ s)·ω̄_b; the advance's part is the dot-2 row's.
    γ = −(C̈ at v̇ = 0) = −(ṡ·ω_b − ρ (s̈·d + 2 ṡ·ḋ + s·a_n)) (d/dt(A_b ω̄_b) = A_b ω̄̇_b, and
    ṡ·ω_a = (ω_a × s)·ω_a = 0)."""

    def __init__(self, frame_a, frame_b, axis, rel0, lead, advance0):
        self.vector = _Vector(frame_a, axis)
        self.frame_a, self.frame_b = frame_a, frame_b
        self.axis = np.asarray(axis, dtype=float)
        self.rel0 = np.asarray(rel0, dtype=float)
        self.ratio = 2.0 * math.pi / lead
        self.advance0 = float(advance0)

    def residual(self, Aa, Ab, s, d):
        x = relative_angle(Aa, Ab, self.rel0, self.axis) - self.ratio * (float(s @ d) - self.advance0)
        return math.remainder(x, 2.0 * math.pi)

    def evaluate(self, q, v, d, ddot, a_n, H, wa_cols, wb_cols):
        s, sdot, sacc, Ja = self.vector.evaluate(q, v)
        Aa, _ = self.frame_a.evaluate(q, v)
        Ab, wb = self.frame_b.evaluate(q, v)
        row = -self.ratio * (s @ H)
        if wa_cols is not None:
            row[wa_cols] += -self.axis - self.ratio * (d @ Ja)
        if wb_cols is not None:
            row[wb_cols] += Ab.T @ s
        gamma = -(float(sdot @ (Ab @ wb)) - self.ratio * (float(sacc @ d) + 2.0 * float(sdot @ ddot) + float(s @ a_n)))
        return self.residual(Aa, Ab, s, d), row, gamma


class SpatialJoint:
    """A 3D joint as rows of three kinds over the two bodies' velocity coordinates:
    coincident points (3 rows), dot-1 rows s_a·s_b = 0, dot-2 rows s_a·(r_b − r_a) = 0."""

    def __init__(self, name, kind, pair, frame_a, frame_b, dot1=(), dot2=(), coincident=True, screw=None):
        self.name, self.kind, self.pair = name, kind, pair
        self.dofs = pair.dofs
        self.has_a = pair.a.dofs is not None
        self.has_b = pair.b.dofs is not None
        self.coincident = coincident
        self.dot1 = [(_Vector(frame_a, sa), _Vector(frame_b, sb)) for sa, sb in dot1]
        self.dot2 = [_Vector(frame_a, sa) for sa in dot2]
        self.screw = screw                                       # a Screw row, last
        self.rows = (3 if coincident else 0) + len(self.dot1) + len(self.dot2) + (screw is not None)
        self._wa = slice(3, 6)                                  # a's ω columns within dofs
        self._wb = slice(9, 12) if self.has_a else slice(3, 6)  # b's ω columns within dofs

    def evaluate(self, q, v):
        d, ddot, a_n, H = self.pair.evaluate(q, v)
        k = len(self.dofs)
        C, rows, gamma = [], [], []
        if self.coincident:
            C.extend(d)
            rows.extend(H)
            gamma.extend(-a_n)
        for va, vb in self.dot1:
            sa, sa_dot, sa_acc, Ja = va.evaluate(q, v)
            sb, sb_dot, sb_acc, Jb = vb.evaluate(q, v)
            row = np.zeros(k)
            if self.has_a:
                row[self._wa] = sb @ Ja
            if self.has_b:
                row[self._wb] = sa @ Jb
            C.append(float(sa @ sb))
            rows.append(row)
            gamma.append(-(float(sa_acc @ sb) + 2.0 * float(sa_dot @ sb_dot) + float(sa @ sb_acc)))
        for va in self.dot2:
            sa, sa_dot, sa_acc, Ja = va.evaluate(q, v)
            row = sa @ H
            if self.has_a:
                row[self._wa] += d @ Ja
            C.append(float(sa @ d))
            rows.append(row)
            gamma.append(-(float(sa_acc @ d) + 2.0 * float(sa_dot @ ddot) + float(sa @ a_n)))
        if self.screw is not None:
            c, row, g = self.screw.evaluate(q, v, d, ddot, a_n, H, self._wa if self.has_a else None,
                                            self._wb if self.has_b else None)
            C.append(c)
            rows.append(row)
            gamma.append(g)
        return np.array(C), np.array(rows), np.array(gamma)


def _perpendiculars(axis):
    """Two unit vectors completing `axis` to a right-handed orthonormal frame."""
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
    p1, p2 = _perpendiculars(axis)
    if spec.type == "screw":
        rows = dict(coincident=False) if spec.coupling_only else _cylindrical_rows(axis, p1, p2, in_b, spec)
        d0 = pair.evaluate(q0, z)[0]
        screw = Screw(fa, fb, axis, Aa.T @ Ab, spec.lead, float((Aa @ axis) @ d0))
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
