"""Flattening a 3D mechanism (quaternion or Z-X-Z Euler orientation) for the 3D section of
:mod:`inerter.engine.kernels`: the arrays (the slots of the planar ones, with 3D column
meanings), the output layout and the structural pattern of Eq. (33); ``compiled.Kernel`` builds
the parameter tuple from them.

    flat = flatten3(model.mechanism)

The initial-pose constants (spring free lengths, joint vectors expressed in body b's frame,
rotational elements' initial relative orientation and free angle, the inertia tensors) are read
from the mechanism's own objects, so the kernels use the same numbers as the numpy path.
"""
from __future__ import annotations

import numpy as np

from inerter.elements import ROTATIONAL, TRANSLATIONAL, layout, output_suffixes
from inerter.engine.tables import _by_name, adds_mass, element_tables, force_rows, kernel_tables
from inerter.model.joints import Coincident, SpatialJoint

# Joint kinds (column JOINT_KIND of ``jt_int``), as in :mod:`inerter.engine.kernels` (its 3D section).
_JOINT_KIND = {"spherical": 0, "revolute": 1, "fixed": 2, "prismatic": 3, "cylindrical": 4, "universal": 5,
               "planar": 6, "screw": 7}


def _joint_rows3(mech, pidx):
    """The ``jt_int`` and ``jt_real`` rows of a 3D scene's joints (see :func:`flatten3`; columns
    named in :mod:`inerter.elements.layout`)."""
    scene = mech.scene
    mech_joints = _by_name(mech.joints)
    jt_int, jt_real = [], []
    for j in scene.joints.values():
        mj = mech_joints[j.name]
        real = np.zeros(layout.JOINT_REAL_COLUMNS_3D)
        if isinstance(mj, Coincident):
            coincident, dot1, dot2 = True, [], []
        elif isinstance(mj, SpatialJoint):
            coincident, dot1, dot2 = mj.coincident, mj.dot1, mj.dot2
        else:
            raise ValueError(f"joint {j.name!r}: {type(mj).__name__} is not a 3D joint")
        if len(dot1) > 3 or len(dot2) > 2:
            raise ValueError(f"joint {j.name!r}: more dot-1/dot-2 rows than the kernels take")
        for k, (sa, sb) in enumerate(dot1):
            c = layout.DOT1 + 6 * k
            real[c:c + 3] = sa
            real[c + 3:c + 6] = sb
        for k, sa in enumerate(dot2):
            c = layout.DOT2 + 3 * k
            real[c:c + 3] = sa
        screw = getattr(mj, "screw", None)
        if screw is not None:
            real[layout.SCREW:layout.SCREW + 3] = screw.axis
            real[layout.SCREW_REL0:layout.SCREW_REL0 + 9] = screw.rel0.ravel()
            real[layout.SCREW_RATIO] = screw.ratio
            real[layout.SCREW_ADVANCE0] = screw.advance0
        row = [0] * layout.JOINT_INT_COLUMNS_3D
        row[layout.JOINT_KIND] = _JOINT_KIND[j.type]
        row[layout.POINT_A] = pidx[j.point_a]
        row[layout.POINT_B] = pidx[j.point_b]
        row[layout.COINCIDENT] = int(bool(coincident))
        row[layout.DOT1_ROWS] = len(dot1)
        row[layout.DOT2_ROWS] = len(dot2)
        row[layout.SCREW_ROW] = int(screw is not None)
        jt_int.append(tuple(row))
        jt_real.append(real)
    return jt_int, jt_real


def flatten3(mech) -> dict:
    """The arrays the 3D kernels run on, from a 3D mechanism (index maps in ``mech.scene`` order:
    bodies, points, joints, elements, forces).

    Coordinates: q = [R(3), p(4)] per body with quaternions (nq = 7 per body), [R(3), (φ, θ, ψ)]
    with Z-X-Z Euler angles (nq = 6 per body), v = [Ṙ(3), ω(3)] per body with ω in
    the body frame (n = 6 per body), as ``Mechanism.q_index`` / ``v_index``. Bodies are numbered
    in scene order, −1 is the ground. Columns of the arrays:

    * ``mass`` (n + 9·bodies): [m, m, m, J11, J22, J33] per body (the diagonal of M0), then each
      body's full inertia tensor J (body frame) row-major, body b's at n + 9b.
    * ``pbody`` (points): the point's body; ``ploc`` (points, 3): ū in the body frame (the global
      position for a ground point).
    * ``el_int`` (elements, 4): kind (0 spring, 1 damper, 2 inerter), point a, point b,
      centripetal term (1: Eq. 9, 0: Eq. 8); ``el_real`` (elements, 3): coefficient (k, c or b),
      spring free length (0 otherwise), the distance below which the terminals meet
      (``compiled.meet_limits``: 0 where an earlier element has the same terminals).
    * ``rot_int`` (rotational elements, 3): kind (0 spring, 1 damper), body a, body b;
      ``rot_real`` (rotational elements, 14): coefficient (k or d), free angle, axis n̄ in body a's
      frame (3), rel0 = A_aᵀA_b at the initial pose (9, row-major).
    * ``jt_int`` (joints, 7): kind (0 spherical, 1 revolute, 2 fixed, 3 prismatic, 4 cylindrical,
      5 universal, 6 planar, 7 screw: a label; the kernels evaluate the rows the counts give), point a,
      point b, coincident rows (1: three rows r_b − r_a = 0), number of dot-1 rows, number of
      dot-2 rows, a screw row (1: one, :class:`inerter.model.joints.Screw`), in columns JOINT_KIND,
      POINT_A, POINT_B, COINCIDENT, DOT1_ROWS, DOT2_ROWS, SCREW_ROW of :mod:`inerter.elements.layout`;
      the joint's rows are in that order. ``jt_real`` (joints, 38): the dot-1 pairs (s̄_a in a's
      frame, s̄_b in b's frame) at columns DOT1 + 6k (k < 3), the dot-2 vectors s̄_a at columns
      DOT2 + 3k (k < 2), the screw's numbers from column SCREW on; unused columns are 0.
    * ``fa_int`` (forces, 2): point, time function (0 constant, 1 sine, 2 step); ``fa_real``
      (forces, 10): direction (3), value, amplitude, frequency, phase, offset, time, initial.
    * ``pd_int`` (pd forces, 1): point; ``pd_real`` (pd forces, 6): direction (3), kp, kd, reference.
    * ``in_int`` (input forces, 1): point; the inputs hold three force components per input force.
    * ``gravity`` (n): m·g on each body's Ṙ coordinates (zero on ω).
    """
    scene = mech.scene
    if scene.dimension != 3:
        raise ValueError(f"flatten3 takes 3D scenes; scene {scene.name!r} has dimension {scene.dimension}")
    body_names = list(mech.body_names)
    bidx = {name: i for i, name in enumerate(body_names)}
    nb = len(body_names)
    n, nq = 6 * nb, (3 + mech.orientation.size) * nb
    point_names = list(scene.points)
    pidx = {name: i for i, name in enumerate(point_names)}
    pbody = np.array([bidx.get(p.body, -1) for p in scene.points.values()], dtype=np.int64)
    ploc = np.array([list(p.local)[:3] for p in scene.points.values()], dtype=float).reshape(-1, 3)

    M0 = np.asarray(mech.M0, dtype=float)
    mass = np.zeros(n + 9 * nb)
    mass[:n] = np.diag(M0)
    for i in range(nb):
        k = 6 * i + 3
        mass[n + 9 * i:n + 9 * i + 9] = M0[k:k + 3, k:k + 3].ravel()

    jt_int, jt_real = _joint_rows3(mech, pidx)
    m = sum(_row_count(row) for row in jt_int)

    def rotational(e, me):          # body indices; the axis, the initial relative orientation, φ_ref = 0
        extra = [*np.asarray(me.axis, dtype=float), *np.asarray(me.rel0, dtype=float).ravel(), 0.0]
        return me.fa.body, me.fb.body, me.free_angle, extra

    tables = element_tables(mech, pidx, rotational)

    has_gravity = mech.gravity is not None
    gravity = np.array(mech.gravity, dtype=float) if has_gravity else np.zeros(n)

    arrays = kernel_tables(3, tables, (jt_int, jt_real), force_rows(scene, pidx, 3))
    return dict(n=n, m=m, nq=nq, dim=3, mass=mass, pbody=pbody, ploc=np.ascontiguousarray(ploc),
                **arrays, gravity=gravity, has_gravity=bool(has_gravity),
                point_names=point_names, body_names=body_names, el_names=tables["el_names"],
                rot_names=tables["rot_names"], el_extra=tables["el_extra"], n_internal=tables["n_internal"])


def signal_layout3(flat) -> list[str]:
    """The names of the values :func:`compiled_kernels.signal_values3` writes, in its order."""
    axes = ("r[1]", "r[2]", "r[3]", "v[1]", "v[2]", "v[3]")
    names = [f"{p}.{x}" for p in flat["point_names"] for x in axes]
    names += [f"{e}.{x}" for e, extra in zip(flat["el_names"], flat["el_extra"])
              for x in (*output_suffixes(TRANSLATIONAL), *extra)]
    names += [f"{e}.{x}" for e in flat["rot_names"] for x in output_suffixes(ROTATIONAL)]
    names += [f"{b}.{x}" for b in flat["body_names"] for x in BODY_OUTPUTS]
    return names + ["energy", "constraint_residual"]


#: Each 3D body's outputs, in the order the kernels write them (kernels._body_outputs3).
BODY_OUTPUTS = ("q[1]", "q[2]", "q[3]", "q[4]", "euler[1]", "euler[2]", "euler[3]", "w[1]", "w[2]", "w[3]")


def joint_row_counts(flat) -> list[int]:
    """The number of constraint rows of each joint, in order: two per 2D joint (Eq. 33's rows of a
    revolute or slider joint), :func:`_row_count` per 3D joint."""
    if flat["dim"] == 2:
        return [2] * len(flat["jt_int"])
    return [_row_count(row) for row in flat["jt_int"]]


def _row_count(row_int):
    """Number of constraint rows of the joint of ``jt_int`` row `row_int`: 3 coincident, its dot-1
    and dot-2 rows, its screw row."""
    return (3 * row_int[layout.COINCIDENT] + row_int[layout.DOT1_ROWS] + row_int[layout.DOT2_ROWS]
            + row_int[layout.SCREW_ROW])
