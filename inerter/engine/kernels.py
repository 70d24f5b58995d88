"""Compiled kernels of the fast path (numba ``@njit(cache=True)``): Eq. (33) and explicit integrators.

Everything here works on flat arrays built once per scene by :mod:`inerter.engine.compiled`; there are no
Python objects in the inner loop. A scene's arrays hold only the terms it declares: a loop over
an element kind the scene does not have runs zero times, and gravity is added only when declared.

Importing this module requires numba; :mod:`inerter.engine.compiled` falls back to the numpy path when
it is missing.
"""
from __future__ import annotations

import math

import numpy as np
from numba import carray, cfunc, njit, types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from inerter.scene.ground_motion import (TERM_AMPLITUDE, TERM_AXIS, TERM_FREQUENCY, TERM_PHASE, TERM_START,
                                         TERM_STOP, burst)
from inerter.common.rotations import (EULER_SINGULARITY, cross3, euler_angles9, euler_matrix9, euler_rates,
                                       matrix9_apply, matrix9_apply_transposed, planar_matrix9,
                                       quaternion_matrix9, quaternion_of_matrix9, quaternion_rates)

from inerter.elements import device_inertia, terminals
from inerter.elements import dispatch as law
from inerter.elements.base import axial_scalars, rarely
from inerter.elements.device import MODE_SOLVES
from inerter.elements.inerter import settle
from inerter.elements.joint_rows import (body_vector, dot1_row, dot2_row, screw_residual, screw_row, screw_turn_2d,
                                         slider_rows_2d)
from inerter.elements.kinematics import (frame_force, gyroscopic, pd_magnitude, planar_body_energy, planar_point,
                                         planar_point_force, spatial_body_energy, spatial_point,
                                         spatial_point_force, spatial_turn_row)
from inerter.elements.twist import planar_relative, spatial_twist
from inerter.elements.winding import carried, wound
from inerter.elements.layout import (AXIS, BODY_A, BODY_B, COINCIDENT, DEVICE, DOT1, DOT1_ROWS, DOT2,
                                     DOT2_ROWS, EFFICIENCY, F_AMPLITUDE, F_FREQUENCY,
                                     F_INITIAL, F_OFFSET, F_PHASE, F_TIME, F_VALUE, FORCE_FUNCTION, FORCE_POINT, INERTIA,
                                     JOINT_KIND, KIND, MEET_LIMIT, MOUNT, MOUNT_AXIS, PD_KD, PD_KP, PD_REFERENCE,
                                     PHI_REF, POINT_A, POINT_B, PRISMATIC_ADVANCE0, PRISMATIC_NORMAL,
                                     PRISMATIC_PHI0, PRISMATIC_RATIO, REL0, ROT_KIND, SCREW, SCREW_ADVANCE0,
                                     SCREW_RATIO, SCREW_REL0, SCREW_ROW, STATE,
                                     STATES)

# Joint kinds (column JOINT_KIND of a 2D scene's ``jt_int``).
REVOLUTE, PRISMATIC = 0, 1
# Time functions of applied forces.
F_CONSTANT, F_SINE, F_STEP = 0, 1, 2
# Ground motion (dims[GROUND_MODE]): none; prescribed (a record, linearly interpolated and zero
# outside, plus analytic terms, scene.ground_motion.burst); FMU inputs.
GROUND_NONE, GROUND_PRESCRIBED, GROUND_INPUT = 0, 1, 2
# The slots of P, the scene's tables (PARAMS below, in this order; a 3D scene's P has one more,
# ``spatial``), by name: numba takes these module constants as literal indices.
(MASS, PBODY, PLOC, EL_INT, EL_REAL, ROT_INT, ROT_REAL, JT_INT, JT_REAL, FA_INT, FA_REAL, PD_INT, PD_REAL,
 IN_INT, GRAVITY, PERM, DIMS, GROUND_T, GROUND_A, GROUND_TERMS) = range(20)
# The entries of P[DIMS] (Kernel.__init__ writes them): velocity coordinates n, constraint rows m,
# the band's lower and upper widths, whether gravity is declared, the dimension, coordinates nq,
# the ground motion's mode and the offset of its inputs among the held inputs, the axes (0 = x) of
# the intrinsic sequence of the 3D bodies' Euler-angle outputs, how many translational elements have
# a screw efficiency (device.efficiency: their mode is resolved by repeated solves, :func:`accelerations`)
# and how many calls kept a solve whose modes did not settle (written by the kernels).
N_VELOCITY, N_ROWS, KL, KU, HAS_GRAVITY, DIMENSION, N_COORD, GROUND_MODE, GROUND_OFFSET, EULER_I, EULER_J, \
    EULER_K, EFFICIENT, UNSETTLED, LOOPS = range(15)
# (LOOPS: the closed loops of the joints, ``Mechanism.closed_loops``; 0: the change-point watch is off.)

# Status codes of the integrators. TERMINALS_MEET: a state where a translational element's
# terminals meet, found where it cannot be evaluated (the integrator stays at its last node);
# MEETING: an accepted step whose chord brings them together (:func:`terminals_meet`), the run
# stopped at the meeting located within that step (:func:`locate_meeting`, :func:`_rk4_to_meeting`);
# UNSTABLE: RK4's fixed step beyond the method's stability limit, a mode growing (:func:`rk4_watch`);
# ENERGY_JUMP: one RK4 step of a scene that conserves its energy changed it by more than the scene
# holds, or the energy of one that can only lose it rose above its lowest by more than that
# (:func:`energy_watch`).
OK, MAX_STEPS, STEP_TOO_SMALL, SINGULAR, NOT_FINITE, TERMINALS_MEET, STIFF, COLLAPSED, GIMBAL_LOCK, \
    CHANGE_POINT, MEETING, UNSTABLE, ENERGY_JUMP = range(13)
# The slots of the integrators' `monitor` (inerter.engine.simulation.monitor_slots): Hairer's stiffness
# bound, how often it is tested, its firings in a row that stop a run; the collapse's relative step
# and steps in a row; the trial shrink; the smallest/largest singular value ratio of C_v below which
# the joints' rows count as dependent (Mechanism.DEPENDENT_RATIO, :func:`loop_watch`); RK4's
# stability watch (1: on, 0: off) and the growth that confirms it, then the watch's running values
# (:func:`rk4_watch`), kept here so that they carry across co-simulation steps: its steps in a row
# beyond RK4's region, the watched mode's amplitude at the first of them and now, its step·λ, and
# the sum of log |R(hλ)| (less the exact growth) over those steps before the last, the full steps
# inside the region since the last beyond it (:data:`RK4_PATIENCE`); RK4's energy
# watch (ENERGY_OFF, ENERGY_CONSERVED or ENERGY_LOST: what the scene's energy may do) and its values
# (:func:`energy_watch`): the energy at the last step's end and what the scene holds there, the
# energy it jumped or rose to, the lowest energy so far and what the scene held there (held < 0:
# none yet).
MONITOR_STIFF_BOUND, MONITOR_STIFF_EVERY, MONITOR_STIFF_HITS, MONITOR_COLLAPSE_RELATIVE, MONITOR_COLLAPSE_STEPS, \
    MONITOR_TRIAL_SHRINK, MONITOR_DEPENDENT, MONITOR_RK4_WATCH, MONITOR_RK4_GROWTH, MONITOR_ENERGY_WATCH, \
    MONITOR_RK4_HITS, MONITOR_RK4_FIRST, MONITOR_RK4_AMPLITUDE, MONITOR_RK4_RE, MONITOR_RK4_IM, \
    MONITOR_RK4_LOG_FACTORS, MONITOR_RK4_CALM, MONITOR_ENERGY_LAST, MONITOR_ENERGY_HELD, MONITOR_ENERGY_NOW, \
    MONITOR_ENERGY_LOWEST, MONITOR_ENERGY_LOWEST_HELD = range(22)
MONITOR_SIZE = 22             # the watches' running values last: monitor[MONITOR_RK4_HITS:]
# The values of monitor[MONITOR_ENERGY_WATCH] (:func:`energy_watch`): no watch; a scene that
# conserves its energy (``Mechanism.conserves_energy``); one that can only lose it
# (``Mechanism.only_loses_energy``: dampers too).
ENERGY_OFF, ENERGY_CONSERVED, ENERGY_LOST = 0.0, 1.0, 2.0
# The arrays of work_arrays, in the order of WORK (their names): the kernels take them by these slots.
W_AB, W_RHS, W_GEN, W_ACC, W_K, W_Y_NEW, W_F_NEW, W_YS = range(8)
# The slot of cosim_scratch's fresh[0] (1: the gaps are those at the integration's y), in the order of
# COSIM (gaps, z, fresh, keep: the kernels unpack the others by name).
SCRATCH_FRESH = 2



@njit(cache=True, inline="always")
def _force_magnitude(fa_real, f, code, value, t):
    """The magnitude of applied force f at time t: row f of `fa_real` holds, from column `value`
    (the direction's 2 or 3 components come first) on, the columns F_VALUE ... F_INITIAL."""
    if code == F_CONSTANT:
        return fa_real[f, value + F_VALUE]
    if code == F_SINE:
        return fa_real[f, value + F_OFFSET] + fa_real[f, value + F_AMPLITUDE] * math.sin(
            2.0 * math.pi * fa_real[f, value + F_FREQUENCY] * t + fa_real[f, value + F_PHASE])
    return fa_real[f, value + F_VALUE] if t >= fa_real[f, value + F_TIME] else fa_real[f, value + F_INITIAL]


# ------------------------------------------------------------------------------------------------
# Kinematics (Eqs. 15-19)
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _point(q, v, body, lx, ly):
    """(rx, ry, vx, vy, ux, uy, accx, accy, w): position, velocity, A ū, the acceleration term
    −θ̇² A ū and the body's angular velocity (kinematics.planar_point; a ground point is fixed)."""
    if body < 0:
        return lx, ly, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    k = 3 * body
    rx, ry, vx, vy, ax, ay, cx, cy = planar_point(q[k], q[k + 1], q[k + 2], v[k], v[k + 1], v[k + 2], lx, ly)
    return rx, ry, vx, vy, ax, ay, cx, cy, v[k + 2]


@njit(cache=True, inline="always")
def _pair(q, v, ba, lax, lay, bb, lbx, lby):
    """Relative kinematics b − a: r, ṙ, a_n (Eq. 19) and the θ-columns of H (A_θ ū of each end)."""
    rax, ray, vax, vay, uax, uay, cax, cay, _ = _point(q, v, ba, lax, lay)
    rbx, rby, vbx, vby, ubx, uby, cbx, cby, _ = _point(q, v, bb, lbx, lby)
    rx = rbx - rax
    ry = rby - ray
    rdx = vbx - vax
    rdy = vby - vay
    # a_n = acc_b − acc_a = (θ̇ᵃ)² Aᵃūᵃ − (θ̇ᵇ)² Aᵇūᵇ (Eq. 19)
    anx = cbx - cax
    any_ = cby - cay
    # A_θ ū = (−u_y, u_x)
    return rx, ry, rdx, rdy, anx, any_, -uay, uax, -uby, ubx


@njit(cache=True, inline="always")
def _row_pair(q, v, table, row, pbody, ploc):
    """The points named in columns POINT_A and POINT_B of a table row (element or joint): their
    bodies and :func:`_pair` of them, (ba, bb, r, ṙ, a_n, the θ-columns of H)."""
    pa = table[row, POINT_A]
    pb = table[row, POINT_B]
    ba = pbody[pa]
    bb = pbody[pb]
    rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby = _pair(
        q, v, ba, ploc[pa, 0], ploc[pa, 1], bb, ploc[pb, 0], ploc[pb, 1])
    return ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby


@njit(cache=True, inline="always")
def _element(q, v, e, el_int, el_real, pbody, ploc):
    """A translational element's terminals b − a: (kind, ba, bb, ṙ, a_n, the θ-columns of H, L, the
    direction it acts along, whether the terminals meet, |r|), the element's geometry from
    :mod:`inerter.elements.terminals` (L is held at MIN_LENGTH where the terminals meet)."""
    ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby = _row_pair(q, v, el_int, e, pbody, ploc)
    row = el_real[e]
    turns = ba >= 0 and rarely(terminals.turns_with_a(row))
    A = planar_matrix9(q[3 * ba + 2]) if turns else terminals.IDENTITY
    distance = math.hypot(rx, ry)
    L, ex, ey, _, meets = terminals.acting_line(row, A, rx, ry, 0.0, distance)
    if turns:
        # ê = A_a n̄ turns with θ_a: H's θ_a column gains ê c_z, ṙ gains θ̇_a c_z ê
        _, _, cz, rdx, rdy, _ = terminals.turning_axis(A, ex, ey, 0.0, rx, ry, 0.0, 0.0, 0.0, v[3 * ba + 2],
                                                       rdx, rdy, 0.0)
        tax -= cz * ex
        tay -= cz * ey
    return el_int[e, KIND], ba, bb, rdx, rdy, anx, any_, tax, tay, tbx, tby, L, ex, ey, meets, distance


# ------------------------------------------------------------------------------------------------
# Assembly of the augmented system of Eq. (33) in band storage
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def band_storage(kl, ku, N):
    """Row-wise band storage of an N × N matrix with kl sub- and ku super-diagonals, with room for
    the kl extra super-diagonals that partial pivoting fills: row i holds columns i − kl …
    i + kl + ku, so K[i, j] is AB[i, kl + j − i] (see :func:`band_solve`)."""
    return np.empty((N, 2 * kl + ku + 1))


@njit(cache=True, inline="always")
def _addK(AB, perm, off, i, j, x):
    """K[i, j] += x in the band storage of the permuted matrix (row pi, column off + pj − pi; off = kl)."""
    pi = perm[i]
    pj = perm[j]
    AB[pi, off + pj - pi] += x


@njit(cache=True, inline="always")
def _element_law(kind, row, L, rdx, rdy, rdz, anx, any_, anz, ex, ey, ez):
    """A translational element's law (:mod:`inerter.elements`): (F without the inertance part,
    the inertance b at L̇, L̇)."""
    Ldot, an, perp2 = axial_scalars(rdx, rdy, rdz, anx, any_, anz, ex, ey, ez)
    return law.force(kind, row, L, Ldot, an, perp2), law.inertance(kind, row, Ldot), Ldot


@njit(cache=True, inline="always")
def _states(z, el_int, e):
    """Translational element e's internal states: its slice of z (y = [q, v, z]; empty for most)."""
    o = el_int[e, STATE]
    return z[o:o + el_int[e, STATES]]


@njit(cache=True, inline="always")
def _element_terms(AB, perm, off, gen, ba, bb, ga, gb, F, b, width):
    """A translational element's terms on its bodies' `width` velocity coordinates (3 in 2D, 6 in
    3D), with g = Hᵀ r̂ over a's (ga) and b's (gb): Q −= F g (Eq. 29; an inerter's Q_Iv, Eq. 31)
    and, for an inerter of inertance b (0 for the other elements), M_I += b g gᵀ (Eq. 33)."""
    if b != 0.0:
        if ba >= 0:
            ka = width * ba
            for i in range(width):
                for j in range(width):
                    _addK(AB, perm, off, ka + i, ka + j, b * ga[i] * ga[j])
        if bb >= 0:
            kb = width * bb
            for i in range(width):
                for j in range(width):
                    _addK(AB, perm, off, kb + i, kb + j, b * gb[i] * gb[j])
        if ba >= 0 and bb >= 0:
            ka = width * ba
            kb = width * bb
            for i in range(width):
                for j in range(width):
                    x = b * ga[i] * gb[j]
                    _addK(AB, perm, off, ka + i, kb + j, x)
                    _addK(AB, perm, off, kb + j, ka + i, x)
    if ba >= 0:
        ka = width * ba
        for i in range(width):
            gen[ka + i] -= F * ga[i]
    if bb >= 0:
        kb = width * bb
        for i in range(width):
            gen[kb + i] -= F * gb[i]


@njit(cache=True, inline="always")
def _start_assembly(AB, gen, gravity, n, has_gravity):
    """An empty augmented matrix, and the generalised forces of gravity where it is declared (else
    zero): where :func:`assemble` and :func:`assemble3` start."""
    AB[:, :] = 0.0
    for i in range(n):
        gen[i] = gravity[i] if has_gravity else 0.0


@njit(cache=True, inline="always")
def _rotational2(q, v, e, rot_int):
    """A 2D rotational element: the velocity indices of its bodies' angles (−1: the ground), the
    relative angle φ = θ_b − θ_a and its rate."""
    ia = rot_int[e, BODY_A]
    ib = rot_int[e, BODY_B]
    phi, w = planar_relative(q, v, ia, ib)
    return ia, ib, phi, w


@njit(cache=True, inline="always")
def _add_elements2(q, v, z, P, AB, perm, off, gen, agx, agy, agz):
    """Translational elements of a 2D scene, each through its law (:mod:`inerter.elements`):
    Q −= F g (Eqs. 29, 31) and M_I += b g gᵀ (Eq. 33), g = Hᵀ r̂; F includes the force an
    element's internal states z carry (a series-compliant device's); a device's parts feel the
    ground's acceleration (agx, agy, agz) as the bodies do. Returns a status code."""
    pbody, ploc, el_int, el_real = P[PBODY], P[PLOC], P[EL_INT], P[EL_REAL]
    status = OK
    ga = carray(_stack(3), 3)       # g over a's and b's coordinates (_stack)
    gb = carray(_stack(3), 3)
    for e in range(el_int.shape[0]):
        kind, ba, bb, rdx, rdy, anx, any_, tax, tay, tbx, tby, L, ex, ey, meets, distance = _element(
            q, v, e, el_int, el_real, pbody, ploc)
        if meets:
            status = TERMINALS_MEET
        # g = Hᵀ r̂ over a's then b's coordinates
        ga[0] = -ex
        ga[1] = -ey
        ga[2] = -(tax * ex + tay * ey)
        gb[0] = ex
        gb[1] = ey
        gb[2] = tbx * ex + tby * ey
        F, b, Ldot = _element_law(kind, el_real[e], L, rdx, rdy, 0.0, anx, any_, 0.0, ex, ey, 0.0)
        if rarely(el_int[e, STATES] != 0):
            F += law.state_force(kind, el_real[e], L, Ldot, _states(z, el_int, e))
        _element_terms(AB, perm, off, gen, ba, bb, ga, gb, F, b, 3)
        if rarely(el_real[e, INERTIA] != 0.0):
            _device_terms(q, v, e, pbody, ploc, el_int, el_real, AB, perm, off, gen, ba, bb, 3, agx, agy, agz)
    return status


@njit(cache=True, inline="always")
def _add_rotational2(q, v, P, gen):
    """Rotational elements of a 2D scene: ∓τ on the bodies' angles, τ from the kind's law."""
    rot_int, rot_real = P[ROT_INT], P[ROT_REAL]
    for e in range(rot_int.shape[0]):
        ia, ib, phi, w = _rotational2(q, v, e, rot_int)
        tau = law.torque(rot_int[e, ROT_KIND], rot_real[e], phi, w)
        if ib >= 0:
            gen[ib] -= tau
        if ia >= 0:
            gen[ia] += tau


@njit(cache=True, inline="always")
def _add_point_forces2(t, q, v, inputs, P, gen, agx, agy, agz):
    """Applied point forces with time functions, grounded PD actuators, held inputs and the ground
    motion (−m a_g on every body: coordinates relative to the moving ground) of a 2D scene."""
    mass, pbody, ploc, dims = P[MASS], P[PBODY], P[PLOC], P[DIMS]
    fa_int, fa_real, pd_int, pd_real, in_int = P[FA_INT], P[FA_REAL], P[PD_INT], P[PD_REAL], P[IN_INT]
    for f in range(fa_int.shape[0]):
        p = fa_int[f, FORCE_POINT]
        mag = _force_magnitude(fa_real, f, fa_int[f, FORCE_FUNCTION], 2, t)     # after dx, dy
        _point_force(q, v, pbody[p], ploc[p, 0], ploc[p, 1], mag * fa_real[f, 0], mag * fa_real[f, 1], gen)
    for f in range(pd_int.shape[0]):
        p = pd_int[f, FORCE_POINT]
        rx, ry, vx, vy, ux, uy, _, _, w = _point(q, v, pbody[p], ploc[p, 0], ploc[p, 1])
        dx = pd_real[f, 0]
        dy = pd_real[f, 1]
        mag = pd_magnitude(dx, dy, 0.0, pd_real[f, 2 + PD_REFERENCE], pd_real[f, 2 + PD_KP], pd_real[f, 2 + PD_KD],
                           rx, ry, 0.0, vx, vy, 0.0)
        _point_force(q, v, pbody[p], ploc[p, 0], ploc[p, 1], mag * dx, mag * dy, gen)
    if inputs.shape[0] > 0:
        for f in range(in_int.shape[0]):
            p = in_int[f, FORCE_POINT]
            _point_force(q, v, pbody[p], ploc[p, 0], ploc[p, 1], inputs[2 * f], inputs[2 * f + 1], gen)
    if dims[GROUND_MODE] != GROUND_NONE:
        for k in range(0, dims[N_VELOCITY], 3):
            fx, fy, _ = frame_force(mass[k], agx, agy, 0.0)
            gen[k] -= fx
            gen[k + 1] -= fy


@njit(cache=True, inline="always")
def _revolute2(AB, perm, off, rhs, row, alpha, ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby):
    """A 2D revolute joint's two rows: C = r, C_q = H, γ = −a_n (with Baumgarte's −2αĊ − α²C)."""
    if ba >= 0:
        ka = 3 * ba
        _sym(AB, perm, off, row, ka, -1.0)
        _sym(AB, perm, off, row, ka + 2, -tax)
        _sym(AB, perm, off, row + 1, ka + 1, -1.0)
        _sym(AB, perm, off, row + 1, ka + 2, -tay)
    if bb >= 0:
        kb = 3 * bb
        _sym(AB, perm, off, row, kb, 1.0)
        _sym(AB, perm, off, row, kb + 2, tbx)
        _sym(AB, perm, off, row + 1, kb + 1, 1.0)
        _sym(AB, perm, off, row + 1, kb + 2, tby)
    rhs[perm[row]] = -anx - 2.0 * alpha * rdx - alpha * alpha * rx
    rhs[perm[row + 1]] = -any_ - 2.0 * alpha * rdy - alpha * alpha * ry


@njit(cache=True, inline="always")
def _prismatic2(q, v, AB, perm, off, rhs, row, alpha, jt_real, jn,
                ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby):
    """A 2D prismatic joint's two rows (joint_rows.slider_rows_2d): θ_b − θ_a − φ0 = 0 and
    n·(r_b − r_a) = 0 with n = A_a n̄, its translational coefficient n placed on the points' H and
    its turn n⊥·r on θ_a; a 2D screw (rack and pinion, :func:`_screw2`) turns b by ρ per unit of
    advance along the axis t = A_a t̄ (n = t turned by +90°)."""
    tha = q[3 * ba + 2] if ba >= 0 else 0.0
    thb = q[3 * bb + 2] if bb >= 0 else 0.0
    wa = v[3 * ba + 2] if ba >= 0 else 0.0
    wb = v[3 * bb + 2] if bb >= 0 else 0.0
    c1, cd1, c2, nx, ny, turn, gamma2 = slider_rows_2d(
        ba >= 0, tha, thb, wa, wb, jt_real[jn, PRISMATIC_PHI0], jt_real[jn, PRISMATIC_NORMAL],
        jt_real[jn, PRISMATIC_NORMAL + 1], rx, ry, rdx, rdy, anx, any_)
    cd2 = 0.0
    if ba >= 0:
        ka = 3 * ba
        _sym(AB, perm, off, row, ka + 2, -1.0)
        _sym(AB, perm, off, row + 1, ka, -nx)
        _sym(AB, perm, off, row + 1, ka + 1, -ny)
        h2 = -(nx * tax + ny * tay) + turn
        _sym(AB, perm, off, row + 1, ka + 2, h2)
        cd2 += -nx * v[ka] - ny * v[ka + 1] + h2 * v[ka + 2]
    if bb >= 0:
        kb = 3 * bb
        _sym(AB, perm, off, row, kb + 2, 1.0)
        _sym(AB, perm, off, row + 1, kb, nx)
        _sym(AB, perm, off, row + 1, kb + 1, ny)
        h2 = nx * tbx + ny * tby
        _sym(AB, perm, off, row + 1, kb + 2, h2)
        cd2 += nx * v[kb] + ny * v[kb + 1] + h2 * v[kb + 2]
    gamma1 = 0.0
    rho = jt_real[jn, PRISMATIC_RATIO]
    if rho != 0.0:
        c1, cd1, gamma1 = _screw2(v, AB, perm, off, row, ba, bb, rho, jt_real[jn, PRISMATIC_ADVANCE0], nx, ny, c1, cd1,
                                  rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby, wa)
    rhs[perm[row]] = gamma1 - 2.0 * alpha * cd1 - alpha * alpha * c1
    rhs[perm[row + 1]] = gamma2 - 2.0 * alpha * cd2 - alpha * alpha * c2


@njit(cache=True, inline="always")
def _screw2(v, AB, perm, off, row, ba, bb, rho, x0, nx, ny, c1, cd1, rx, ry, rdx, rdy, anx, any_,
            tax, tay, tbx, tby, wa):
    """The 2D screw's part of its first row, −ρ (t·d − x₀) (joint_rows.screw_turn_2d): its
    translational coefficient t (and its turn n·d on θ_a), scaled by −ρ, placed; returns C, Ċ, γ."""
    c1, tx, ty, turn, gamma1 = screw_turn_2d(rho, x0, c1, nx, ny, wa, rx, ry, rdx, rdy, anx, any_)
    if ba >= 0:
        ka = 3 * ba
        h = -(-(tx * tax + ty * tay) + turn)
        _sym(AB, perm, off, row, ka, rho * tx)
        _sym(AB, perm, off, row, ka + 1, rho * ty)
        _sym(AB, perm, off, row, ka + 2, rho * h)
        cd1 += rho * (tx * v[ka] + ty * v[ka + 1] + h * v[ka + 2])
    if bb >= 0:
        kb = 3 * bb
        h = tx * tbx + ty * tby
        _sym(AB, perm, off, row, kb, -rho * tx)
        _sym(AB, perm, off, row, kb + 1, -rho * ty)
        _sym(AB, perm, off, row, kb + 2, -rho * h)
        cd1 -= rho * (tx * v[kb] + ty * v[kb + 1] + h * v[kb + 2])
    return c1, cd1, gamma1


@njit(cache=True)
def assemble(t, q, v, z, inputs, alpha, P, AB, rhs, gen):
    """Fill AB (band storage of the permuted augmented matrix of Eq. 33) and rhs (permuted) at
    (t, q, v) and the elements' internal states z for a 2D scene; gen: work vector of length n for the generalised forces. Returns a
    status code."""
    q, v, z, inputs, AB, rhs, gen = _unowned((q, v, z, inputs, AB, rhs, gen))     # its arguments (_unowned)
    mass, pbody, ploc, jt_int, jt_real, gravity, perm, dims = P[MASS], P[PBODY], P[PLOC], P[JT_INT], P[JT_REAL], P[GRAVITY], P[PERM], P[DIMS]
    n = dims[N_VELOCITY]
    off = dims[KL]                   # kl: K[i, j] is AB[i, off + j − i] (band_storage)
    _start_assembly(AB, gen, gravity, n, dims[HAS_GRAVITY])
    for i in range(n):
        _addK(AB, perm, off, i, i, mass[i])
    agx, agy, agz = _ground_frame(t, inputs, P)
    status = _add_elements2(q, v, z, P, AB, perm, off, gen, agx, agy, agz)
    _add_rotational2(q, v, P, gen)
    _add_point_forces2(t, q, v, inputs, P, gen, agx, agy, agz)
    for i in range(n):
        rhs[perm[i]] = gen[i]
    # -- joints: C_q (and its transpose) and γ − 2αĊ − α²C
    row = n
    for jn in range(jt_int.shape[0]):
        ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby = _row_pair(q, v, jt_int, jn, pbody, ploc)
        if jt_int[jn, JOINT_KIND] == REVOLUTE:
            _revolute2(AB, perm, off, rhs, row, alpha, ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby)
        else:
            _prismatic2(q, v, AB, perm, off, rhs, row, alpha, jt_real, jn,
                        ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby)
        row += 2
    return status


@njit(cache=True, inline="always")
def _ground_frame(t, inputs, P):
    """The acceleration of the frame the coordinates are measured in: the ground motion's a_g where
    the scene declares one, else zero (nothing evaluated)."""
    if P[DIMS][GROUND_MODE] == GROUND_NONE:
        return 0.0, 0.0, 0.0
    return ground_acceleration(t, inputs, P)


@njit(cache=True)
def ground_acceleration(t, inputs, P):
    """The ground's acceleration a_g(t) (3 components; the third 0 in 2D), as
    ``GroundMotion.acceleration``: a record (`ground_t` its sample times, `ground_a` the scaled
    values, one row per axis; no record: one sample) plus the analytic terms (`ground_terms`, rows
    of scene.ground_motion's TERM_* columns, amplitudes scaled); or the inputs (the scale in
    ground_a[0, 0], dims[GROUND_OFFSET] the offset of ``ground.a[1]`` among the inputs)."""
    dims = P[DIMS]
    ground_t = P[GROUND_T]
    ground_a = P[GROUND_A]
    terms = P[GROUND_TERMS]
    dim = dims[DIMENSION]
    a = carray(_stack(3), 3)        # _stack: no heap allocation per evaluation
    a[:] = 0.0
    if dims[GROUND_MODE] == GROUND_INPUT:
        off = dims[GROUND_OFFSET]
        if inputs.shape[0] >= off + dim:
            for i in range(dim):
                a[i] = ground_a[0, 0] * inputs[off + i]
        return a[0], a[1], a[2]
    last = ground_t.shape[0] - 1
    if last > 0 and ground_t[0] <= t <= ground_t[last]:
        j = np.searchsorted(ground_t, t, side="right") - 1
        if j >= last:
            for i in range(dim):
                a[i] = ground_a[i, last]
        else:
            x = t - ground_t[j]
            width = ground_t[j + 1] - ground_t[j]
            for i in range(dim):
                a[i] = ground_a[i, j] + x * (ground_a[i, j + 1] - ground_a[i, j]) / width
    for k in range(terms.shape[0]):
        a[int(terms[k, TERM_AXIS])] += burst(t, terms[k, TERM_AMPLITUDE], terms[k, TERM_FREQUENCY],
                                             terms[k, TERM_PHASE], terms[k, TERM_START], terms[k, TERM_STOP])
    return a[0], a[1], a[2]


@njit(cache=True, inline="always")
def _sym(AB, perm, off, row, col, x):
    """C_q[row − n, col] = x and its transpose in the augmented matrix."""
    _addK(AB, perm, off, row, col, x)
    _addK(AB, perm, off, col, row, x)


@njit(cache=True, inline="always")
def _point_force(q, v, body, lx, ly, Fx, Fy, gen):
    """A force at a point: into x, y and, through A_θ ū, the body's angle (virtual work)."""
    if body < 0:
        return
    k = 3 * body
    gx, gy, gt = planar_point_force(q[k + 2], lx, ly, Fx, Fy)
    gen[k] += gx
    gen[k + 1] += gy
    gen[k + 2] += gt


# ------------------------------------------------------------------------------------------------
# Band LU with partial pivoting, stored by rows: O(N kl (kl + ku)), less where rows are sparse
# ------------------------------------------------------------------------------------------------
#: The largest system whose rows' profile :func:`band_solve` keeps on the stack (32 KB); above, on the heap.
STACK_ROWS = 4096


@njit(cache=True)
def band_solve(AB, b, kl):
    """Solve A x = b in place (b becomes x); A in the row-wise band storage of :func:`band_storage`
    with kl sub-diagonals (destroyed; the storage's width gives the rest). Returns False when A is
    singular.

    Gaussian elimination with partial pivoting (the first largest |pivot| in the column, as
    LAPACK's gbtf2; multipliers by division), with two savings that leave the result bit for bit
    that of the plain elimination (tests/test_compiled.py): rows are stored contiguously, so that
    the inner loop, row i −= l · row k, runs over contiguous memory; and each row's last nonzero
    column is tracked (the row's profile), so that the loop stops there instead of at the band's
    edge (an N-link chain's augmented matrix, benchmarks/chain_scene.py, holds 5–6 nonzeros per
    row in a band of 17). The storage is addressed as one flat vector, K[i, j] at
    i·W + kl − i + j: a row taken as a view of the 2-D storage at every use cost as much as the
    arithmetic of a two-bar's 10 × 10 system (1.4 against 0.7 µs, benchmarks/eval_cost.py)."""
    N = b.shape[0]
    W = AB.shape[1]
    F = AB.reshape(N * W)
    # last[i]: no nonzero right of column last[i] in row i; on the stack (_stack_ints) up to
    # STACK_ROWS rows: a heap array cost an allocation per solve, 0.1 µs of a braced frame's 0.3
    last = carray(_stack_ints(N), N) if N <= STACK_ROWS else np.empty(N, dtype=np.int64)
    for i in range(N):
        j = min(W - 1, kl + N - 1 - i)
        while j > kl and F[i * W + j] == 0.0:
            j -= 1
        last[i] = i + j - kl
    for k in range(N):
        imax = min(N - 1, k + kl)
        p = k
        best = abs(F[k * W + kl])
        for i in range(k + 1, imax + 1):
            a = abs(F[i * W + kl + k - i])
            if a > best:
                best = a
                p = i
        if best == 0.0:
            return False
        rk = k * W + kl - k             # column j of row k is F[rk + j]
        if p != k:
            rp = p * W + kl - p
            for j in range(k, max(last[k], last[p]) + 1):
                tmp = F[rk + j]
                F[rk + j] = F[rp + j]
                F[rp + j] = tmp
            tmp = last[k]
            last[k] = last[p]
            last[p] = tmp
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
        piv = F[rk + k]
        jmax = last[k]
        bk = b[k]
        for i in range(k + 1, imax + 1):
            ri = i * W + kl - i
            l = F[ri + k] / piv
            if l != 0.0:
                for j in range(k + 1, jmax + 1):
                    F[ri + j] -= l * F[rk + j]
                b[i] -= l * bk
                if jmax > last[i]:
                    last[i] = jmax
    for i in range(N - 1, -1, -1):
        ri = i * W + kl - i
        s = b[i]
        for j in range(i + 1, last[i] + 1):
            s -= F[ri + j] * b[j]
        b[i] = s / F[ri + i]
    return True


@njit(cache=True)
def accelerations(t, q, v, z, inputs, alpha, P, AB, rhs, gen, out):
    """Eq. (33) at (t, q, v) and the elements' internal states z: out[:n] = q̈, out[n:] = λ
    (original ordering). Returns a status code.

    With screw efficiencies (dims[EFFICIENT] > 0) the system is solved in each one's stored mode,
    the modes are checked against the solved L̈ and, where one flipped, solved again
    (:func:`_settle_modes`; inerter.elements.device: exact, two solves for one such element)."""
    P = _unowned(P)                 # entered from Python (_unowned)
    return _settled(_solve(t, q, v, z, inputs, alpha, P, AB, rhs, gen, out),
                    t, q, v, z, inputs, alpha, P, AB, rhs, gen, out)


@njit(cache=True, inline="always")
def _solve(t, q, v, z, inputs, alpha, P, AB, rhs, gen, out):
    """Assemble Eq. (33) and solve it into `out` (original ordering): the assembly's status, or
    SINGULAR (out untouched)."""
    return _solved(_assemble_of(t, q, v, z, inputs, alpha, P, AB, rhs, gen), P, AB, rhs, out)


@njit(cache=True, inline="always")
def _solved(status, P, AB, rhs, out):
    """Solve Eq. (33) as assembled in AB, rhs into `out` (original ordering): the assembly's
    `status`, or SINGULAR (out untouched)."""
    perm = P[PERM]
    if not band_solve(AB, rhs, P[DIMS][KL]):
        return SINGULAR
    for i in range(out.shape[0]):
        out[i] = rhs[perm[i]]
    return status


@njit(cache=True, inline="always")
def _settled(status, t, q, v, z, inputs, alpha, P, AB, rhs, gen, out):
    """The solve's `status` once the screw efficiencies' modes agree with it (:func:`_settle_modes`;
    nothing to do where the scene declares none)."""
    if rarely(P[DIMS][EFFICIENT] != 0) and status != SINGULAR:
        return _settle_modes(t, q, v, z, inputs, alpha, P, AB, rhs, gen, out, status)
    return status


@njit(cache=True)
def _settle_modes(t, q, v, z, inputs, alpha, P, AB, rhs, gen, out, status):
    """After a solve of Eq. (33) into `out` (its `status`): set the screw efficiencies' modes from
    it and, while one changed, solve again in the new modes; after device.MODE_SOLVES such checks
    whose modes still changed, the call is counted (dims[UNSETTLED]) and the solve in the modes
    last set is kept (so that the force and the stored modes agree). Returns the status."""
    for attempt in range(MODE_SOLVES + 1):
        if attempt == MODE_SOLVES:
            P[DIMS][UNSETTLED] += 1
        elif _settle_of(q, v, out, P) == 0:
            return status
        status = _solve(t, q, v, z, inputs, alpha, P, AB, rhs, gen, out)
        if status == SINGULAR:
            return status
    return status


@njit(cache=True)
def constraint_residual(q, P):
    """Largest |C_i| over the joints."""
    P = _unowned(P)                 # entered from Python (_unowned)
    return _residual_of(q, P)


@njit(cache=True)
def constraint_residual2(q, P):
    """Largest |C_i| over the joints of a 2D scene."""
    pbody = P[PBODY]
    ploc = P[PLOC]
    jt_int = P[JT_INT]
    jt_real = P[JT_REAL]
    worst = 0.0
    z = np.zeros(q.shape[0])
    for jn in range(jt_int.shape[0]):
        ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby = _row_pair(q, z, jt_int, jn, pbody, ploc)
        if jt_int[jn, JOINT_KIND] == REVOLUTE:
            worst = max(worst, abs(rx), abs(ry))
        else:
            tha = q[3 * ba + 2] if ba >= 0 else 0.0
            thb = q[3 * bb + 2] if bb >= 0 else 0.0
            turn, _, c2, nx, ny, _, _ = slider_rows_2d(
                ba >= 0, tha, thb, 0.0, 0.0, jt_real[jn, PRISMATIC_PHI0], jt_real[jn, PRISMATIC_NORMAL],
                jt_real[jn, PRISMATIC_NORMAL + 1], rx, ry, 0.0, 0.0, 0.0, 0.0)
            rho = jt_real[jn, PRISMATIC_RATIO]
            if rho != 0.0:
                turn = screw_turn_2d(rho, jt_real[jn, PRISMATIC_ADVANCE0], turn, nx, ny, 0.0, rx, ry,
                                     0.0, 0.0, 0.0, 0.0)[0]
            worst = max(worst, abs(turn), abs(c2))
    return worst


# ------------------------------------------------------------------------------------------------
# Output signals (the same values as inerter.engine.outputs.Signals, in the layout of `signal_layout`)
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _gq2(qdd, ba, bb, tax, tay, tbx, tby, ex, ey):
    """gᵀq̈ of a 2D translational element (g = Hᵀ r̂ over its bodies' coordinates, Eqs. 17-19)."""
    gq = 0.0
    if ba >= 0:
        ka = 3 * ba
        gq -= (qdd[ka] + qdd[ka + 2] * tax) * ex + (qdd[ka + 1] + qdd[ka + 2] * tay) * ey
    if bb >= 0:
        kb = 3 * bb
        gq += (qdd[kb] + qdd[kb + 2] * tbx) * ex + (qdd[kb + 1] + qdd[kb + 2] * tby) * ey
    return gq


@njit(cache=True)
def state_rates2(q, v, z, qdd, P, dz):
    """dz: the rates of the translational elements' internal states of a 2D scene, at the state
    (q, v, z) and its solved accelerations q̈ (each kind's ``state_rates``, with gᵀq̈)."""
    el_int, el_real = P[EL_INT], P[EL_REAL]
    for e in range(el_int.shape[0]):
        if el_int[e, STATES] == 0:
            continue
        kind, L, Ldot, an, perp2, gq = _axial2(q, v, qdd, e, P)
        o = el_int[e, STATE]
        c = el_int[e, STATES]
        law.state_rates(kind, el_real[e], L, Ldot, an, perp2, gq, z[o:o + c], dz[o:o + c])


@njit(cache=True, inline="always")
def _axial2(q, v, qdd, e, P):
    """Element e's axial kinematics in a 2D scene at the solved accelerations q̈: (kind, L, L̇,
    a_n·r̂, |ṙ⊥|², gᵀq̈), what its laws of the internal states and of the efficiency's mode read."""
    kind, ba, bb, rdx, rdy, anx, any_, tax, tay, tbx, tby, L, ex, ey, meets, distance = _element(
        q, v, e, P[EL_INT], P[EL_REAL], P[PBODY], P[PLOC])
    Ldot, an, perp2 = axial_scalars(rdx, rdy, 0.0, anx, any_, 0.0, ex, ey, 0.0)
    return kind, L, Ldot, an, perp2, _gq2(qdd, ba, bb, tax, tay, tbx, tby, ex, ey)


@njit(cache=True)
def settle2(q, v, qdd, P):
    """Set each screw efficiency's mode of a 2D scene from the solved accelerations q̈
    (inerter.elements.inerter.settle); returns how many changed."""
    el_int, el_real = P[EL_INT], P[EL_REAL]
    changed = 0
    for e in range(el_int.shape[0]):
        if el_real[e, EFFICIENCY] == 0.0:
            continue
        kind, L, Ldot, an, perp2, gq = _axial2(q, v, qdd, e, P)
        changed += settle(el_real[e], L, Ldot, an, perp2, gq)
    return changed


@njit(cache=True)
def signal_values(q, v, z, qdd, P, out):
    """Every output at one state y = [q, v, z] (:func:`signal_values2`, :func:`signal_values3`).
    Returns a status code."""
    P = _unowned(P)                 # entered from Python (_unowned)
    return _signals_of(q, v, z, qdd, P, out)


@njit(cache=True, inline="always")
def _stored_energy(q, v, z, P, e, kind, L, along, width):
    """The energy translational element e stores at (L, L̇ = `along`): its law's, its internal
    states', its device block's kinetic and gravitational energy (`width`: velocity coordinates
    per body, 3 or 6); its ``energy`` output and its share of the scene's (``Mechanism.energy``)."""
    el_int, el_real = P[EL_INT], P[EL_REAL]
    stored = law.energy(kind, el_real[e], L, along)
    if rarely(el_int[e, STATES] != 0):
        stored += law.state_energy(kind, el_real[e], L, along, _states(z, el_int, e))
    if rarely(el_real[e, INERTIA] != 0.0):
        stored += _device_energy(q, v, e, P[PBODY], P[PLOC], el_int, el_real, width)
    return stored


@njit(cache=True, inline="always")
def _element_outputs(q, v, z, P, e, kind, L, distance, rdx, rdy, rdz, anx, any_, anz, ex, ey, ez, gq, width,
                     energy, out, k):
    """Translational element e's outputs from out[k] on (s_rel, v_rel, the axial force F, the power
    F L̇ it absorbs, the energy it stores, its kind's extra outputs: base.FAMILY_OUTPUTS) and that
    energy added to `energy`, in 2D (z components 0.0) and 3D, from
    its terminals' geometry (:func:`_element`, :func:`_element3`) and gq = gᵀq̈ at the accelerations
    (`width`: velocity coordinates per body, 3 or 6). Returns (energy, the next k)."""
    el_int, el_real = P[EL_INT], P[EL_REAL]
    F, b, along = _element_law(kind, el_real[e], L, rdx, rdy, rdz, anx, any_, anz, ex, ey, ez)
    if b != 0.0:
        # r̈·r̂ = gᵀ q̈ + a_n·r̂ (Eqs. 17-19, 25): the inertance part of F = b d²L/dt², Eq. (9) / (8)
        F += b * gq
    x = _states(z, el_int, e)
    if rarely(el_int[e, STATES] != 0):
        F += law.state_force(kind, el_real[e], L, along, x)
    stored = _stored_energy(q, v, z, P, e, kind, L, along, width)
    out[k] = terminals.reported_distance(el_real[e], L, distance)
    out[k + 1] = along
    out[k + 2] = F
    out[k + 3] = F * along
    out[k + 4] = stored
    k += 5
    if rarely(el_real[e, DEVICE] != 0.0):                          # a device's outputs
        _, an, perp2 = axial_scalars(rdx, rdy, rdz, anx, any_, anz, ex, ey, ez)
        k = law.extra_outputs(kind, el_real[e], L, along, an, perp2, gq, x, out, k)
    return energy + stored, k


@njit(cache=True, inline="always")
def _rotational_outputs(kind, row, phi, w, tau, energy, out, k):
    """A rotational element's outputs from out[k] on (φ_rel, ω_rel, τ, the power τ ω_rel it absorbs,
    the energy it stores: base.FAMILY_OUTPUTS), in 2D and 3D; returns (the next k, `energy` plus its)."""
    stored = law.rotational_energy(kind, row, phi, w)
    out[k] = phi
    out[k + 1] = w
    out[k + 2] = tau
    out[k + 3] = tau * w
    out[k + 4] = stored
    return k + 5, energy + stored


@njit(cache=True, inline="always")
def _element_signals2(q, v, z, qdd, P, e, energy, out, k):
    """Translational element e's outputs of a 2D scene from out[k] on, at the accelerations qdd
    (:func:`_element_outputs`): (whether its terminals meet, `energy` plus its, the next k)."""
    kind, ba, bb, rdx, rdy, anx, any_, tax, tay, tbx, tby, L, ex, ey, meets, distance = _element(
        q, v, e, P[EL_INT], P[EL_REAL], P[PBODY], P[PLOC])
    energy, k = _element_outputs(q, v, z, P, e, kind, L, distance, rdx, rdy, 0.0, anx, any_, 0.0, ex, ey, 0.0,
                                 _gq2(qdd, ba, bb, tax, tay, tbx, tby, ex, ey), 3, energy, out, k)
    return meets, energy, k


@njit(cache=True, inline="always")
def element_signals2(q, v, z, qdd, P, e, out):
    """Translational element e's outputs alone, from out[0] on, as :func:`signal_values2` writes
    them. Returns a status code."""
    meets, _, _ = _element_signals2(q, v, z, qdd, P, e, 0.0, out, 0)
    return TERMINALS_MEET if meets else OK


@njit(cache=True, inline="always")
def _bodies_energy2(q, v, P):
    """Σ over a 2D scene's bodies of T + V (kinematics.planar_body_energy; `gravity` is all 0
    where not declared), and Σ of their magnitudes."""
    mass, gravity, n = P[MASS], P[GRAVITY], P[DIMS][N_VELOCITY]
    energy = held = 0.0
    for i in range(0, n, 3):
        part = planar_body_energy(mass[i], mass[i + 2], v[i], v[i + 1], v[i + 2], gravity[i], gravity[i + 1],
                                  q[i], q[i + 1])
        energy += part
        held += abs(part)
    return energy, held


@njit(cache=True)
def scene_energy2(q, v, z, P):
    """A 2D scene's energy (``Mechanism.energy``: its bodies' T + V, its elements' stored energy)
    and what it holds, the sum of those parts' magnitudes (:func:`energy_watch`)."""
    energy, held = _bodies_energy2(q, v, P)
    el_int, el_real, rot_int, rot_real = P[EL_INT], P[EL_REAL], P[ROT_INT], P[ROT_REAL]
    for e in range(el_int.shape[0]):
        kind, _, _, rdx, rdy, anx, any_, _, _, _, _, L, ex, ey, _, _ = _element(q, v, e, el_int, el_real, P[PBODY],
                                                                             P[PLOC])
        part = _stored_energy(q, v, z, P, e, kind, L, axial_scalars(rdx, rdy, 0.0, anx, any_, 0.0, ex, ey, 0.0)[0], 3)
        energy += part
        held += abs(part)
    for e in range(rot_int.shape[0]):
        _, _, phi, w = _rotational2(q, v, e, rot_int)
        part = law.rotational_energy(rot_int[e, ROT_KIND], rot_real[e], phi, w)
        energy += part
        held += abs(part)
    return energy, held


@njit(cache=True)
def signal_values2(q, v, z, qdd, P, out):
    """Every point's position and velocity (4 per point), every translational element's s_rel,
    v_rel, axial force (an inerter's from Eq. 9 or 8 at the accelerations qdd), power and stored energy
    and its kind's extra outputs (an inerter's device: ``signal_layout``), every
    rotational element's φ_rel, ω_rel, torque, power and energy, the energy (as ``Mechanism.energy``)
    and the largest constraint residual of a 2D scene. Returns a status code."""
    pbody, ploc, el_int = P[PBODY], P[PLOC], P[EL_INT]
    rot_int, rot_real, jt_int = P[ROT_INT], P[ROT_REAL], P[JT_INT]
    status = OK
    k = 0
    for p in range(pbody.shape[0]):
        rx, ry, vx, vy, ux, uy, _, _, w = _point(q, v, pbody[p], ploc[p, 0], ploc[p, 1])
        out[k] = rx
        out[k + 1] = ry
        out[k + 2] = vx
        out[k + 3] = vy
        k += 4
    energy, _ = _bodies_energy2(q, v, P)
    for e in range(el_int.shape[0]):
        meets, energy, k = _element_signals2(q, v, z, qdd, P, e, energy, out, k)
        if meets:
            status = TERMINALS_MEET
    for e in range(rot_int.shape[0]):
        ia, ib, phi, w = _rotational2(q, v, e, rot_int)
        kind = rot_int[e, ROT_KIND]
        k, energy = _rotational_outputs(kind, rot_real[e], phi, w, law.torque(kind, rot_real[e], phi, w), energy,
                                        out, k)
    out[k] = energy
    out[k + 1] = constraint_residual2(q, P) if jt_int.shape[0] else 0.0
    return status


# ------------------------------------------------------------------------------------------------
# An inerter device's kinetic block (inerter.elements.device_inertia): the terminals' kinematics it
# takes, from the kinematics above (Eqs. 15-19, 22, 25), and its terms scattered into Eq. (33)
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _terminal2(q, v, body, lx, ly, H, col, rv, vv, acc):
    """A 2D terminal: r, ṙ and its acceleration at v̇ = 0 (−θ̇² A ū, Eq. 17) into rv, vv, acc (z = 0),
    and ∂ṙ/∂v = [I, A_θ ū] (Eq. 16) into H's columns col … col + 2 (none for the ground)."""
    rx, ry, vx, vy, ux, uy, _, _, w = _point(q, v, body, lx, ly)
    rv[0], rv[1], rv[2] = rx, ry, 0.0
    vv[0], vv[1], vv[2] = vx, vy, 0.0
    acc[0], acc[1], acc[2] = -w * w * ux, -w * w * uy, 0.0
    if body >= 0:
        H[0, col] = 1.0
        H[1, col + 1] = 1.0
        H[0, col + 2] = -uy
        H[1, col + 2] = ux


@njit(cache=True, inline="always")
def _terminal3(q, v, body, lx, ly, lz, H, col, rv, vv, acc):
    """A 3D terminal: r, ṙ, its acceleration at v̇ = 0 (Eq. 25) and ∂ṙ/∂v = [I, −A ũ] (Eq. 22; the
    ω̄ column j is A(e_j × ū)) into H's columns col … col + 5 (none for the ground)."""
    A = _rot(q, v, body)
    rv[0], rv[1], rv[2], vv[0], vv[1], vv[2], acc[0], acc[1], acc[2] = _point3(q, v, body, A, lx, ly, lz)
    if body >= 0:
        for j in range(3):
            H[j, col + j] = 1.0
            cx, cy, cz = _cross(1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0, lx, ly, lz)
            H[0, col + 3 + j], H[1, col + 3 + j], H[2, col + 3 + j] = matrix9_apply(A, cx, cy, cz)


@njit(cache=True, inline="always")
def _mount3(q, v, body, row, G, a1, a1d, a1dd):
    """The mount's axis a₁ = A_a a̅₁, ȧ₁ = A_a(ω̄ × a̅₁) = G v (column j of G over ω̄: A_a(e_j × a̅₁)),
    ä₁ at v̇ = 0, A_a(ω̄ × (ω̄ × a̅₁)) (:func:`_vector`); a fixed axis on the ground."""
    sx, sy, sz = row[MOUNT_AXIS], row[MOUNT_AXIS + 1], row[MOUNT_AXIS + 2]
    if body < 0:
        a1[0], a1[1], a1[2] = sx, sy, sz
        return
    A = _rot(q, v, body)
    wx, wy, wz = _omega(v, body)
    a1[0], a1[1], a1[2], a1d[0], a1d[1], a1d[2], a1dd[0], a1dd[1], a1dd[2] = _vector(A, wx, wy, wz, sx, sy, sz)
    for j in range(3):
        cx, cy, cz = _cross(1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0, sx, sy, sz)
        G[0, 3 + j], G[1, 3 + j], G[2, 3 + j] = matrix9_apply(A, cx, cy, cz)


@njit(cache=True)
def _device_block(q, v, e, pbody, ploc, el_int, el_real, width, frame_acc, M, Q):
    """Element e's device block (device_inertia.block) over its terminals' bodies, `width` velocity
    coordinates each (3 in 2D, 6 in 3D), frame_acc the ground's acceleration: fills M, Q; returns the block's energy (kinetic beyond
    ½ b L̇², and its masses' weight's potential). The tables are passed, not P: a call that takes
    the scene's tuple makes the loop it sits in materialise it."""
    pa = el_int[e, POINT_A]
    pb = el_int[e, POINT_B]
    n = 2 * width
    Ha = np.zeros((3, n))
    Hb = np.zeros((3, n))
    Ga1 = np.zeros((3, n))
    ra, rb, va, vb, acc_a, acc_b = np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    a1, a1d, a1dd = np.zeros(3), np.zeros(3), np.zeros(3)
    if width == 3:
        _terminal2(q, v, pbody[pa], ploc[pa, 0], ploc[pa, 1], Ha, 0, ra, va, acc_a)
        _terminal2(q, v, pbody[pb], ploc[pb, 0], ploc[pb, 1], Hb, 3, rb, vb, acc_b)
    else:
        _terminal3(q, v, pbody[pa], ploc[pa, 0], ploc[pa, 1], ploc[pa, 2], Ha, 0, ra, va, acc_a)
        _terminal3(q, v, pbody[pb], ploc[pb, 0], ploc[pb, 1], ploc[pb, 2], Hb, 6, rb, vb, acc_b)
        if el_real[e, MOUNT] != 0.0:
            _mount3(q, v, pbody[pa], el_real[e], Ga1, a1, a1d, a1dd)
    T, V = device_inertia.block(el_real[e], Ha, Hb, ra, rb, va, vb, acc_a, acc_b, frame_acc, a1, a1d, a1dd, Ga1, M, Q)
    return T + V


@njit(cache=True)
def _device_terms(q, v, e, pbody, ploc, el_int, el_real, AB, perm, off, gen, ba, bb, width, agx, agy, agz):
    """Element e's device block added to Eq. (33): M += its block and Q += its right side, on the
    coordinates of bodies ba (the block's first `width` rows) and bb (the next), not the ground's;
    its parts feel the ground's acceleration (agx, agy, agz)."""
    n = 2 * width
    M = np.empty((n, n))
    Q = np.empty(n)
    _device_block(q, v, e, pbody, ploc, el_int, el_real, width, np.array((agx, agy, agz)), M, Q)
    for i in range(n):
        bi = ba if i < width else bb
        if bi < 0:
            continue
        gi = width * bi + i % width
        gen[gi] += Q[i]
        for j in range(n):
            bj = ba if j < width else bb
            if bj >= 0:
                _addK(AB, perm, off, gi, width * bj + j % width, M[i, j])


@njit(cache=True)
def _device_energy(q, v, e, pbody, ploc, el_int, el_real, width):
    """Element e's device block's energy (its T beyond ½ b L̇², and its masses' potential)."""
    n = 2 * width
    return _device_block(q, v, e, pbody, ploc, el_int, el_real, width, np.zeros(3), np.empty((n, n)), np.empty(n))


# ------------------------------------------------------------------------------------------------
# Dimension: picked by the type of P when a kernel is compiled for it (a 3D scene's P has one slot
# more than PARAMS, ``spatial``: an int64 array), so that a scene's compiled code holds its own dimension's kernels only: a 2D
# scene compiles no 3D code, and the other way round.
# ------------------------------------------------------------------------------------------------
def is_spatial(P) -> bool:
    """Whether P (a tuple, or its numba type) is a 3D scene's."""
    return len(P) > len(PARAMS)


def _assemble_of(t, q, v, z, inputs, alpha, P, AB, rhs, gen):
    raise NotImplementedError("compiled code only")


@overload(_assemble_of, inline="always")
def _assemble_by_dimension(t, q, v, z, inputs, alpha, P, AB, rhs, gen):
    if is_spatial(P):
        return lambda t, q, v, z, inputs, alpha, P, AB, rhs, gen: assemble3(t, q, v, z, inputs, alpha, P, AB, rhs,
                                                                            gen)
    return lambda t, q, v, z, inputs, alpha, P, AB, rhs, gen: assemble(t, q, v, z, inputs, alpha, P, AB, rhs, gen)


def _assemble_inlined_of(t, q, v, z, inputs, alpha, P, AB, rhs, gen):
    raise NotImplementedError("compiled code only")


@overload(_assemble_inlined_of, inline="always")
def _assemble_inlined_by_dimension(t, q, v, z, inputs, alpha, P, AB, rhs, gen):
    """The 2D assembly compiled into the integrators' right-hand side (:func:`_rhs`, a dozen
    evaluations per step) rather than called: a call passes the scene's twenty arrays field by
    field, 15–20 % of a 2D evaluation (two-bar 2.03 → 1.73 µs, benchmarks/eval_cost.py). The 3D
    assembly stays a call: inlined, it gained 7 % of a 3D evaluation, and the kernels with both
    assemblies inlined took 819 s to compile on 2 cores instead of 543 s."""
    if is_spatial(P):
        return lambda t, q, v, z, inputs, alpha, P, AB, rhs, gen: assemble3(t, q, v, z, inputs, alpha, P, AB, rhs,
                                                                            gen)
    return assemble.py_func


def _residual_of(q, P):
    raise NotImplementedError("compiled code only")


@overload(_residual_of, inline="always")
def _residual_by_dimension(q, P):
    if is_spatial(P):
        return lambda q, P: constraint_residual3(q, P)
    return lambda q, P: constraint_residual2(q, P)


def _signals_of(q, v, z, qdd, P, out):
    raise NotImplementedError("compiled code only")


@overload(_signals_of, inline="always")
def _signals_by_dimension(q, v, z, qdd, P, out):
    if is_spatial(P):
        return lambda q, v, z, qdd, P, out: signal_values3(q, v, z, qdd, P, out)
    return lambda q, v, z, qdd, P, out: signal_values2(q, v, z, qdd, P, out)


def _scene_energy_of(q, v, z, P):
    raise NotImplementedError("compiled code only")


@overload(_scene_energy_of, inline="always")
def _scene_energy_by_dimension(q, v, z, P):
    if is_spatial(P):
        return lambda q, v, z, P: scene_energy3(q, v, z, P)
    return lambda q, v, z, P: scene_energy2(q, v, z, P)


def _element_signals_of(q, v, z, qdd, P, e, out):
    raise NotImplementedError("compiled code only")


@overload(_element_signals_of, inline="always")
def _element_signals_by_dimension(q, v, z, qdd, P, e, out):
    if is_spatial(P):
        return lambda q, v, z, qdd, P, e, out: element_signals3(q, v, z, qdd, P, e, out)
    return lambda q, v, z, qdd, P, e, out: element_signals2(q, v, z, qdd, P, e, out)


def _state_rates_of(q, v, z, qdd, P, dz):
    raise NotImplementedError("compiled code only")


@overload(_state_rates_of, inline="always")
def _state_rates_by_dimension(q, v, z, qdd, P, dz):
    if is_spatial(P):
        return lambda q, v, z, qdd, P, dz: state_rates3(q, v, z, qdd, P, dz)
    return lambda q, v, z, qdd, P, dz: state_rates2(q, v, z, qdd, P, dz)


def _wind_of(y, P):
    raise NotImplementedError("compiled code only")


@overload(_wind_of, inline="always")
def _wind_by_dimension(y, P):
    """After an accepted step to y = [q, v, z]: :func:`wind3` in 3D; nothing in 2D, where a
    rotational element's angle θ_b − θ_a has no branch."""
    if is_spatial(P):
        def wind_spatial(y, P):
            nq = P[DIMS][N_COORD]
            if P[ROT_INT].shape[0]:
                wind3(y[:nq], y[nq:nq + P[DIMS][N_VELOCITY]], P)
        return wind_spatial
    return lambda y, P: None


def _wind_step_of(y, y0, h, P):
    raise NotImplementedError("compiled code only")


@overload(_wind_step_of, inline="always")
def _wind_step_by_dimension(y, y0, h, P):
    """After an accepted step of length h from y0 to y = [q, v, z]: :func:`wind3_step` in 3D;
    nothing in 2D."""
    if is_spatial(P):
        def wind_step_spatial(y, y0, h, P):
            nq = P[DIMS][N_COORD]
            nv = nq + P[DIMS][N_VELOCITY]
            if P[ROT_INT].shape[0]:
                wind3_step(y[:nq], y[nq:nv], y0[:nq], y0[nq:nv], h, P)
        return wind_step_spatial
    return lambda y, y0, h, P: None


@njit(cache=True)
def wind(y, y0, h, P):
    """:func:`_wind_step_of` from Python (the scipy integrators on the compiled right-hand side)."""
    _wind_step_of(y, y0, h, P)


def _record_windings_of(out, k0, k, ny, ts, t_end, y_end, P):
    raise NotImplementedError("compiled code only")


@overload(_record_windings_of, inline="always")
def _record_windings_by_dimension(out, k0, k, ny, ts, t_end, y_end, P):
    """After a loop wrote the samples out[k0:k] at ts[k0:k] (their first `ny` columns: the state)
    inside the accepted step that ends at (t_end, y_end), to which the integrator has wound φ_ref:
    where `out` has a column past the state for each 3D rotational element (a whole run's samples,
    ``compiled.integrate_compiled``), each element's angle at each sample into those columns, on
    the branch the integration followed (:func:`_angle_from3`, from the step's end). The outputs at
    each sample are read wound from it (:func:`signal_history`'s `windings`), not from the sample
    before, which may lie any number of turns away. Samples exactly as wide as the state (a
    co-simulation step's) record nothing; nothing in 2D."""
    if is_spatial(P):
        def record_spatial(out, k0, k, ny, ts, t_end, y_end, P):
            if out.shape[1] > ny:
                record_windings3(out, k0, k, ny, ts, t_end, y_end, P)
        return record_spatial
    return lambda out, k0, k, ny, ts, t_end, y_end, P: None


@njit(cache=True)
def record_windings3(out, k0, k, ny, ts, t_end, y_end, P):
    """:func:`_record_windings_of` in 3D: a call, not inlined, so that the twist's evaluation
    (:func:`_angle_from3`) is compiled once rather than into every sampling site of every
    integration loop."""
    nq = P[DIMS][N_COORD]
    nv = nq + P[DIMS][N_VELOCITY]
    for e in range(out.shape[1] - ny):
        rate_end = _twist_rate3(y_end[:nq], y_end[nq:nv], e, P)      # the same for every sample of the step
        for j in range(k0, k):
            out[j, ny + e] = _angle_from3(out[j, :nq], out[j, nq:nv], rate_end, ts[j] - t_end, e, P)


def _hold_windings_of(windings, i, P):
    raise NotImplementedError("compiled code only")


@overload(_hold_windings_of, inline="always")
def _hold_windings_by_dimension(windings, i, P):
    """Before the outputs at row i of a history: each 3D rotational element's PHI_REF set to
    windings[i], its angle at that sample on the integration's branch (recorded with the sample,
    :func:`_record_windings_of`), so that the reading there is wound to that angle itself;
    `windings` without rows: PHI_REF left as the row before wound it (the rows come in time order,
    close enough to each other); nothing in 2D."""
    if is_spatial(P):
        def hold_spatial(windings, i, P):
            if windings.shape[0]:
                rot_real = P[ROT_REAL]
                for e in range(windings.shape[1]):
                    rot_real[e, PHI_REF] = windings[i, e]
        return hold_spatial
    return lambda windings, i, P: None


@njit(cache=True)
def windings_along(times, states, P, out):
    """out[i] = each 3D rotational element's φ_ref once wound on to states[i] (rows [q, v, z] at
    `times`), row after row from the φ_ref P holds, the first row wound on to, each next one as the
    end of a step from the row before (:func:`_wind_step_of`): where the rows are the states an
    integration accepted, in order (a kept dense output's steps' starts), the values its integrator
    held there, so that a time inside a step is read wound from its step's."""
    P = _unowned(P)                 # entered from Python (_unowned)
    rot_real = P[ROT_REAL]
    for i in range(states.shape[0]):
        if i == 0:
            _wind_of(states[i], P)
        else:
            _wind_step_of(states[i], states[i - 1], times[i] - times[i - 1], P)
        for e in range(out.shape[1]):
            out[i, e] = rot_real[e, PHI_REF]


@njit(cache=True)
def windings_between(times0, states0, windings0, times, states, P, out):
    """out[i, e] = element e's angle at states[i] (rows [q, v, z] at times[i]: a time of a dense
    output) on the branch its integration followed, from the state states0[i] at times0[i] (an end
    of the step that gives the time) where the integrator held φ_ref = windings0[i]
    (:func:`_angle_from3`): right where the step turns it by more than half a turn too."""
    P = _unowned(P)                 # entered from Python (_unowned)
    rot_real = P[ROT_REAL]
    nq = P[DIMS][N_COORD]
    nv = nq + P[DIMS][N_VELOCITY]
    for i in range(states.shape[0]):
        for e in range(out.shape[1]):
            rot_real[e, PHI_REF] = windings0[i, e]
        for e in range(out.shape[1]):
            rate0 = _twist_rate3(states0[i, :nq], states0[i, nq:nv], e, P)
            out[i, e] = _angle_from3(states[i, :nq], states[i, nq:nv], rate0, times[i] - times0[i], e, P)


def _settle_of(q, v, qdd, P):
    raise NotImplementedError("compiled code only")


@overload(_settle_of, inline="always")
def _settle_by_dimension(q, v, qdd, P):
    if is_spatial(P):
        return lambda q, v, qdd, P: settle3(q, v, qdd, P)
    return lambda q, v, qdd, P: settle2(q, v, qdd, P)


def _qdot_of(q, v, P, out):
    raise NotImplementedError("compiled code only")


@njit(cache=True, inline="always")
def _copy(q, v, P, out):
    for i in range(out.shape[0]):
        out[i] = v[i]
    return OK


@overload(_qdot_of, inline="always")
def _qdot_by_dimension(q, v, P, out):
    """q̇ = B(q) v: the identity in 2D, the orientations' rates in 3D (:func:`qdot3`). Returns a
    status code."""
    if is_spatial(P):
        return lambda q, v, P, out: qdot3(q, v, P, out)
    return lambda q, v, P, out: _copy(q, v, P, out)


def _gap_of(q, z, e, P):
    raise NotImplementedError("compiled code only")


@njit(cache=True)
def _gap2(q, z, e, P):
    ba, bb, rx, ry, rdx, rdy, anx, any_, tax, tay, tbx, tby = _row_pair(q, z, P[EL_INT], e, P[PBODY], P[PLOC])
    return rx, ry, 0.0


@njit(cache=True)
def _gap3(q, z, e, P):
    ba, bb, Aa, Ab, rx, ry, rz, rdx, rdy, rdz, anx, any_, anz = _pair3(q, z, P[EL_INT][e, POINT_A], P[EL_INT][e, POINT_B], P[PBODY], P[PLOC])
    return rx, ry, rz


@overload(_gap_of, inline="always")
def _gap_by_dimension(q, z, e, P):
    """r_b − r_a of translational element e at q (z: zero velocities)."""
    if is_spatial(P):
        return lambda q, z, e, P: _gap3(q, z, e, P)
    return lambda q, z, e, P: _gap2(q, z, e, P)


@njit(cache=True)
def terminal_gaps(y, P):
    """(gaps, z): r_b − r_a at y of each translational element whose terminals are checked
    (``el_real[e, MEET_LIMIT]`` > 0: one element per pair of terminals), for :func:`terminals_meet`, and the
    zero velocities it evaluates them with."""
    gaps = np.zeros((P[EL_INT].shape[0], 3))
    z = np.zeros(P[DIMS][N_VELOCITY])
    gaps_at(y, P, gaps, z)
    return gaps, z


@njit(cache=True)
def gaps_at(y, P, gaps, z):
    """The gaps of :func:`terminal_gaps` at y into `gaps` (`z`: zero velocities)."""
    q = y[:P[DIMS][N_COORD]]
    for e in range(gaps.shape[0]):
        if P[EL_REAL][e, MEET_LIMIT] > 0.0:
            gaps[e, 0], gaps[e, 1], gaps[e, 2] = _gap_of(q, z, e, P)


@njit(cache=True)
def terminals_meet(gaps, z, y_new, P):
    """Whether an accepted step brings a translational element's terminals together, as
    ``Mechanism.chord_margin`` checks each step of the numpy path: the closest approach of the
    chord from r_b − r_a at the step's start (`gaps`, :func:`terminal_gaps`) to r_b − r_a at y_new
    (``terminals.chord_approach``) is not above the element's limit (``el_real[e, MEET_LIMIT]``, MEET_RELATIVE of its initial length; 0: the
    pair of terminals is another element's). A fixed step (RK4) would otherwise pass through the
    meeting, where the direction is undefined, and go on with garbage. Otherwise `gaps` moves on
    to y_new."""
    el_real = P[EL_REAL]
    q1 = y_new[:P[DIMS][N_COORD]]
    for e in range(gaps.shape[0]):
        limit = el_real[e, MEET_LIMIT]
        if limit == 0.0:
            continue
        bx, by, bz = _gap_of(q1, z, e, P)
        if not terminals.chord_approach(gaps[e, 0], gaps[e, 1], gaps[e, 2], bx, by, bz) > limit:
            return True
        gaps[e, 0] = bx
        gaps[e, 1] = by
        gaps[e, 2] = bz
    return False


@njit(cache=True)
def chord_margin(gaps0, gaps1, P):
    """The smallest, over the translational elements whose terminals are checked, of the closest
    approach of the chord from r_b − r_a = `gaps0` to `gaps1` (rows of :func:`terminal_gaps`) over
    the element's limit (``el_real[e, MEET_LIMIT]``): at most 1 where :func:`terminals_meet` finds
    the terminals meeting along that chord (the same test, read as a ratio); inf without such
    elements."""
    el_real = P[EL_REAL]
    worst = np.inf
    for e in range(gaps0.shape[0]):
        limit = el_real[e, MEET_LIMIT]
        if limit == 0.0:
            continue
        approach = terminals.chord_approach(gaps0[e, 0], gaps0[e, 1], gaps0[e, 2],
                                            gaps1[e, 0], gaps1[e, 1], gaps1[e, 2])
        worst = min(worst, approach / limit)
    return worst


#: Positions in work_arrays' tuple (WORK names them, in this order): the first SOLVER_WORK serve every
#: evaluation and integrator; then the change-point watch's C_v at a step's start and end, its
#: scratch, its Gram matrix and whether the start's C_v is known (loop_watch).
SOLVER_WORK = 9
CV_START, CV_END, CV_WORK, CV_GRAM, CV_KNOWN = range(SOLVER_WORK, SOLVER_WORK + 5)


@njit(cache=True)
def work_arrays(P, ny, stages):
    """Scratch arrays of the integrators and of the outputs, allocated once per integration:
    (AB, rhs, gen, acc: Eq. 33 in band storage; K: `stages` rows of Runge-Kutta stages; y_new,
    f_new, ys: a step's solution, derivative and stage argument; sig_acc: the accelerations the
    outputs are evaluated with, zero where they need none; cv_start, cv_end, cv_work, cv_gram,
    cv_known: the change-point watch's, :func:`loop_watch`, empty where the joints close no loop)."""
    n = P[DIMS][N_VELOCITY]
    N = n + P[DIMS][N_ROWS]
    m, nv = (P[DIMS][N_ROWS], n) if P[DIMS][LOOPS] != 0 else (0, 0)
    return (band_storage(P[DIMS][KL], P[DIMS][KU], N), np.empty(N), np.empty(n), np.empty(N),
            np.zeros((stages, ny)), np.empty(ny), np.empty(ny), np.empty(ny), np.zeros(N),
            np.zeros((m, nv)), np.zeros((m, nv)), np.zeros((m, nv)), np.zeros((m, m)), np.zeros(1))


#: signal_values inlined where the outputs of one state at a time are evaluated (:func:`_signals_at`:
#: a whole run's samples, a co-simulation step, the FMU's native step), so that its arrays are not
#: passed field by field once more per sample.
_signal_values_inlined = njit(inline="always")(signal_values.py_func)


@njit(cache=True, inline="always")
def _signals_at(t, y, inputs, alpha, need_acc, P, work, out):
    """`signal_values` at one state y = [q, v, z]; accelerations from Eq. (33) only when `need_acc`.
    Inlined where it is called."""
    nq = P[DIMS][N_COORD]
    nv = nq + P[DIMS][N_VELOCITY]
    AB, rhs, gen, acc, K, y_new, f_new, ys, sig_acc = _unowned(work)[:SOLVER_WORK]
    _wind_of(y, P)                  # the samples come in time order: each winds on from the last
    if need_acc:
        st = accelerations(t, y[:nq], y[nq:nv], y[nv:], inputs, alpha, P, AB, rhs, gen, sig_acc)
        if st != OK:
            return st
    return _signal_values_inlined(y[:nq], y[nq:nv], y[nv:], sig_acc, P, out)


@njit(cache=True)
def signal_history(times, states, windings, inputs, alpha, need_acc, P, out):
    """`signal_values` at every sample of a history (rows [q, v, z]), each 3D rotational element's
    angle wound from windings[i] (:func:`_hold_windings_of`). Returns (status, index of the sample
    where it was raised)."""
    P = _unowned(P)                 # entered from Python (_unowned)
    work = work_arrays(P, states.shape[1], 1)
    for i in range(states.shape[0]):
        _hold_windings_of(windings, i, P)
        st = _signals_at(times[i], states[i], inputs, alpha, need_acc, P, work, out[i])
        if st != OK:
            return st, i
    return OK, states.shape[0]


# ------------------------------------------------------------------------------------------------
# 3D scenes with quaternion orientations: Eq. (33), q̇ = B(q) v, the residual and the outputs
# ------------------------------------------------------------------------------------------------
# Each body has the coordinates q = [R(3), p(4)] (p a quaternion, normalised on the fly as
# ``spatial.quat_matrix``) and the velocity coordinates v = [Ṙ(3), ω(3)], ω in the body frame
# (``Mechanism.q_index``, ``v_index``); the arrays, with the 3D meaning of each column, come from
# :func:`inerter.engine.compiled_spatial.flatten3`. Point kinematics (Sec. 3.2, Eqs. 15, 22, 25):
# r = R + A ū, ṙ = Ṙ + A(ω × ū), r̈ = R̈ − A ũ ω̇ + A(ω × (ω × ū)). A global vector s projected on a
# point's H = [I, −A ũ] gives sᵀH = [sᵀ, (ū × Aᵀs)ᵀ]; :func:`_wcol` computes the second part
# (kinematics.spatial_turn_row: joint_rows.turned_coefficient, which the joint rows' laws take their
# ω̄ coefficients from). The points' kinematics and forces are the laws of inerter.elements.kinematics.

# Joint kinds (column JOINT_KIND of ``jt_int`` in 3D; every kind is evaluated from its row counts, columns
# COINCIDENT, DOT1_ROWS, DOT2_ROWS and SCREW_ROW).
SPHERICAL, REVOLUTE3, FIXED, PRISMATIC3 = 0, 1, 2, 3
# A body's coordinates with a quaternion orientation (R, p); with Z-X-Z Euler angles: 6 (R, φ θ ψ).
QUATERNION_COORDS = 7


# ------------------------------------------------------------------------------------------------
# Small vector helpers on scalar triples and row-major 3×3 tuples
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _coords_per_body(q, v):
    """A 3D body's coordinates: 7 = R(3) and a quaternion, 6 = R(3) and Z-X-Z Euler angles (each
    body has 6 velocity coordinates, so q and v give it)."""
    return (6 * q.shape[0]) // v.shape[0]


@njit(cache=True, inline="always")
def _rot(q, v, body):
    """A body's rotation matrix A (row-major 9-tuple) from its orientation coordinates: a quaternion
    (normalised on the fly) or Z-X-Z Euler angles (Eq. B.1), ``spatial.Orientation.matrix``; the
    identity for the ground."""
    if body < 0:
        return (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    nqb = _coords_per_body(q, v)
    k = nqb * body + 3
    if nqb == QUATERNION_COORDS:
        return quaternion_matrix9(q[k], q[k + 1], q[k + 2], q[k + 3])
    return euler_matrix9(q[k], q[k + 1], q[k + 2])


@njit(cache=True, inline="always")
def _omega(v, body):
    """A body's angular velocity in its own frame (zero for the ground)."""
    if body < 0:
        return 0.0, 0.0, 0.0
    k = 6 * body + 3
    return v[k], v[k + 1], v[k + 2]


#: The rotation of the ground, row-major.
IDENTITY = terminals.IDENTITY
#: a × b on components (common.rotations.cross3).
_cross = cross3
#: ū × (Aᵀ s): the ω-columns of sᵀ H for a point ū (H = [I, −A ũ], Eq. 22 with body-frame ω).
_wcol = spatial_turn_row
#: A body-fixed vector s = A s̄, its rate A(ω × s̄) and its acceleration at ω̇ = 0, A(ω × (ω × s̄)).
_vector = body_vector


# ------------------------------------------------------------------------------------------------
# Kinematics (Eqs. 15, 22, 25)
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _point3(q, v, body, A, lx, ly, lz):
    """(r, ṙ, acc) of a point ū on a body with rotation A: r = R + A ū, ṙ = Ṙ + A(ω × ū),
    acc = A(ω × (ω × ū)) (the point's part of a_n, Eq. 25). A ground point is fixed at ū."""
    if body < 0:
        return lx, ly, lz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    wx, wy, wz = _omega(v, body)
    k = 6 * body
    j = _coords_per_body(q, v) * body
    return spatial_point(A, q[j], q[j + 1], q[j + 2], v[k], v[k + 1], v[k + 2], wx, wy, wz, lx, ly, lz)


@njit(cache=True, inline="always")
def _rotation_of(q, v, body, A, held):
    """(A of `body`, body): `A` where it is the rotation of body `held` already, else computed
    (:func:`_rot`), so that a loop over elements computes a body's rotation once for a run of
    elements on it (the same arithmetic: the same A)."""
    if body == held:
        return A, held
    return _rot(q, v, body), body


@njit(cache=True, inline="always")
def _pair3(q, v, pa, pb, pbody, ploc):
    """Relative kinematics b − a of two points (Eqs. 18, 19, 25): the bodies, their rotations,
    r, ṙ and a_n = acc_b − acc_a."""
    return _pair_at(q, v, pa, pb, pbody, ploc, _rot(q, v, pbody[pa]), _rot(q, v, pbody[pb]))


@njit(cache=True, inline="always")
def _pair_at(q, v, pa, pb, pbody, ploc, Aa, Ab):
    """:func:`_pair3` with the bodies' rotations Aa, Ab given."""
    ba = pbody[pa]
    bb = pbody[pb]
    rax, ray, raz, vax, vay, vaz, aax, aay, aaz = _point3(q, v, ba, Aa, ploc[pa, 0], ploc[pa, 1], ploc[pa, 2])
    rbx, rby, rbz, vbx, vby, vbz, abx, aby, abz = _point3(q, v, bb, Ab, ploc[pb, 0], ploc[pb, 1], ploc[pb, 2])
    return (ba, bb, Aa, Ab, rbx - rax, rby - ray, rbz - raz, vbx - vax, vby - vay, vbz - vaz,
            abx - aax, aby - aay, abz - aaz)


@njit(cache=True, inline="always")
def _element3(q, v, e, el_int, el_real, pbody, ploc, ga, gb):
    """:func:`_element_at` with the rotations of its terminals' bodies computed."""
    return _element_at(q, v, e, el_int, el_real, pbody, ploc, ga, gb,
                       _rot(q, v, pbody[el_int[e, POINT_A]]), _rot(q, v, pbody[el_int[e, POINT_B]]))


@njit(cache=True, inline="always")
def _element_at(q, v, e, el_int, el_real, pbody, ploc, ga, gb, Aa, Ab):
    """A translational element's terminals b − a: (kind, ba, bb, ṙ, a_n, L, the direction ê it acts
    along, whether the terminals meet, |r|), the element's geometry from
    :mod:`inerter.elements.terminals` (L is held at MIN_LENGTH where the terminals meet), with
    g = Hᵀ ê written to ga (a's six coordinates) and gb (b's)."""
    pa = el_int[e, POINT_A]
    pb = el_int[e, POINT_B]
    ba, bb, Aa, Ab, rx, ry, rz, rdx, rdy, rdz, anx, any_, anz = _pair_at(q, v, pa, pb, pbody, ploc, Aa, Ab)
    row = el_real[e]
    distance = math.sqrt(rx * rx + ry * ry + rz * rz)
    L, ex, ey, ez, meets = terminals.acting_line(row, Aa, rx, ry, rz, distance)
    # g = Hᵀ ê = [−ê, −ū_a × (A_aᵀ ê), ê, ū_b × (A_bᵀ ê)] (H = [−H_a, H_b], Eq. 18)
    wx, wy, wz = _wcol(Aa, ploc[pa, 0], ploc[pa, 1], ploc[pa, 2], ex, ey, ez)
    ga[0] = -ex
    ga[1] = -ey
    ga[2] = -ez
    ga[3] = -wx
    ga[4] = -wy
    ga[5] = -wz
    wx, wy, wz = _wcol(Ab, ploc[pb, 0], ploc[pb, 1], ploc[pb, 2], ex, ey, ez)
    gb[0] = ex
    gb[1] = ey
    gb[2] = ez
    gb[3] = wx
    gb[4] = wy
    gb[5] = wz
    if ba >= 0 and rarely(terminals.turns_with_a(row)):
        # ê = A_a n̄ turns with a: H's ω̄_a columns gain ê c̄ᵀ (so g's gain c̄), ṙ gains (ω̄_a·c̄) ê
        wx, wy, wz = _omega(v, ba)
        cx, cy, cz, rdx, rdy, rdz = terminals.turning_axis(Aa, ex, ey, ez, rx, ry, rz, wx, wy, wz, rdx, rdy, rdz)
        ga[3] += cx
        ga[4] += cy
        ga[5] += cz
    return el_int[e, KIND], ba, bb, rdx, rdy, rdz, anx, any_, anz, L, ex, ey, ez, meets, distance


@njit(cache=True, inline="always")
def _rotational3(q, v, e, rot_int, rot_real):
    """A 3D rotational element (``evaluators.SpatialRotationalElement``), as :func:`_rotational2`
    in 2D: its bodies, A_a, A_b, the twist φ about the axis n̄ fixed in body a (wound on from
    PHI_REF), its rate φ̇ and the direction g its torque acts along in the global frame
    (:func:`inerter.elements.twist.spatial_twist`); its kind's torque is the caller's, where it is
    needed (the winding kernels read the angle and its rate alone)."""
    ia = rot_int[e, BODY_A]
    ib = rot_int[e, BODY_B]
    Aa = _rot(q, v, ia)
    Ab = _rot(q, v, ib)
    wax, way, waz = _omega(v, ia)
    wbx, wby, wbz = _omega(v, ib)
    phi, w, gx, gy, gz = spatial_twist(Aa, Ab, rot_real[e], REL0, rot_real[e, AXIS], rot_real[e, AXIS + 1],
                                       rot_real[e, AXIS + 2], rot_real[e, PHI_REF], wax, way, waz, wbx, wby, wbz)
    return ia, ib, Aa, Ab, phi, w, gx, gy, gz


@njit(cache=True, inline="always")
def _point_force3(q, v, body, lx, ly, lz, Fx, Fy, Fz, gen):
    """A force F at a point ū: Hᵀ F (virtual work, δr = H δv): F into Ṙ's and ū × (Aᵀ F) into ω's."""
    if body < 0:
        return
    A = _rot(q, v, body)
    gx, gy, gz, mx, my, mz = spatial_point_force(A, lx, ly, lz, Fx, Fy, Fz)
    k = 6 * body
    gen[k] += gx
    gen[k + 1] += gy
    gen[k + 2] += gz
    gen[k + 3] += mx
    gen[k + 4] += my
    gen[k + 5] += mz


@njit(cache=True, inline="always")
def _jrow(AB, perm, off, row, v, body, A, lx, ly, lz, sx, sy, sz):
    """Row `row` of C_v += sᵀ H over a point's body (and the transpose); returns its part of Ċ = C_v v."""
    if body < 0:
        return 0.0
    k = 6 * body
    wx, wy, wz = _wcol(A, lx, ly, lz, sx, sy, sz)
    _sym(AB, perm, off, row, k, sx)
    _sym(AB, perm, off, row, k + 1, sy)
    _sym(AB, perm, off, row, k + 2, sz)
    _sym(AB, perm, off, row, k + 3, wx)
    _sym(AB, perm, off, row, k + 4, wy)
    _sym(AB, perm, off, row, k + 5, wz)
    return sx * v[k] + sy * v[k + 1] + sz * v[k + 2] + wx * v[k + 3] + wy * v[k + 4] + wz * v[k + 5]


@njit(cache=True, inline="always")
def _wrow(AB, perm, off, row, v, body, cx, cy, cz):
    """Row `row` of C_v += c over a body's ω-columns (and the transpose), c a joint row's coefficient
    over ω̄ (joint_rows); returns its part of Ċ."""
    if body < 0:
        return 0.0
    k = 6 * body + 3
    _sym(AB, perm, off, row, k, cx)
    _sym(AB, perm, off, row, k + 1, cy)
    _sym(AB, perm, off, row, k + 2, cz)
    return cx * v[k] + cy * v[k + 1] + cz * v[k + 2]


# ------------------------------------------------------------------------------------------------
# Assembly of the augmented system of Eq. (33) in band storage
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _add_bodies3(v, P, AB, perm, off, gen):
    """The mass matrix diag(m I, J) per body and the gyroscopic term −ω × Jω (body frame)."""
    mass, perm, dims = P[MASS], P[PERM], P[DIMS]
    n = dims[N_VELOCITY]
    for b in range(n // 6):
        k = 6 * b
        for i in range(3):
            _addK(AB, perm, off, k + i, k + i, mass[k + i])
        J = n + 9 * b
        for i in range(3):
            for j in range(3):
                _addK(AB, perm, off, k + 3 + i, k + 3 + j, mass[J + 3 * i + j])
        cx, cy, cz = gyroscopic(mass, J, v[k + 3], v[k + 4], v[k + 5])
        gen[k + 3] -= cx
        gen[k + 4] -= cy
        gen[k + 5] -= cz


@njit(cache=True, inline="always")
def _add_elements3(q, v, z, P, AB, perm, off, gen, agx, agy, agz):
    """Translational elements of a 3D scene, each through its law (:mod:`inerter.elements`):
    Q −= F g (Eqs. 29, 31) and M_I += b g gᵀ (Eq. 33), g = Hᵀ r̂; F includes the force an
    element's internal states z carry; a device's parts feel the ground's acceleration. Returns a
    status code."""
    pbody, ploc, el_int, el_real = P[PBODY], P[PLOC], P[EL_INT], P[EL_REAL]
    status = OK
    ga = carray(_stack(6), 6)       # g over a's and b's coordinates (_stack)
    gb = carray(_stack(6), 6)
    Aa = Ab = IDENTITY              # the rotations of the bodies ha, hb (none yet): _rotation_of
    ha = hb = -2
    for e in range(el_int.shape[0]):
        Aa, ha = _rotation_of(q, v, pbody[el_int[e, POINT_A]], Aa, ha)
        Ab, hb = _rotation_of(q, v, pbody[el_int[e, POINT_B]], Ab, hb)
        kind, ba, bb, rdx, rdy, rdz, anx, any_, anz, L, ex, ey, ez, meets, distance = _element_at(
            q, v, e, el_int, el_real, pbody, ploc, ga, gb, Aa, Ab)
        if meets:
            status = TERMINALS_MEET
        F, b, Ldot = _element_law(kind, el_real[e], L, rdx, rdy, rdz, anx, any_, anz, ex, ey, ez)
        if rarely(el_int[e, STATES] != 0):
            F += law.state_force(kind, el_real[e], L, Ldot, _states(z, el_int, e))
        _element_terms(AB, perm, off, gen, ba, bb, ga, gb, F, b, 6)
        if rarely(el_real[e, INERTIA] != 0.0):
            _device_terms(q, v, e, pbody, ploc, el_int, el_real, AB, perm, off, gen, ba, bb, 6, agx, agy, agz)
    return status


@njit(cache=True, inline="always")
def _add_rotational3(q, v, P, gen):
    """Rotational elements about an axis fixed in body a: ∓τ g on the bodies' ω (body frames), g the
    gradient of the angle (:func:`_rotational3`)."""
    rot_int, rot_real = P[ROT_INT], P[ROT_REAL]
    for e in range(rot_int.shape[0]):
        ia, ib, Aa, Ab, phi, w, gx, gy, gz = _rotational3(q, v, e, rot_int, rot_real)
        tau = law.torque(rot_int[e, ROT_KIND], rot_real[e], phi, w)
        if ib >= 0:
            tx, ty, tz = matrix9_apply_transposed(Ab, gx, gy, gz)
            k = 6 * ib + 3
            gen[k] -= tau * tx
            gen[k + 1] -= tau * ty
            gen[k + 2] -= tau * tz
        if ia >= 0:
            tx, ty, tz = matrix9_apply_transposed(Aa, gx, gy, gz)
            k = 6 * ia + 3
            gen[k] += tau * tx
            gen[k + 1] += tau * ty
            gen[k + 2] += tau * tz


@njit(cache=True, inline="always")
def _add_point_forces3(t, q, v, inputs, P, gen, agx, agy, agz):
    """Applied point forces with time functions, grounded PD actuators (F = −[kp (d·r − ref) +
    kd d·ṙ] d), held inputs (three components each) and the ground motion (−m a_g on every body's
    Ṙ: coordinates relative to the moving ground) of a 3D scene."""
    mass, pbody, ploc, dims = P[MASS], P[PBODY], P[PLOC], P[DIMS]
    fa_int, fa_real, pd_int, pd_real, in_int = P[FA_INT], P[FA_REAL], P[PD_INT], P[PD_REAL], P[IN_INT]
    for f in range(fa_int.shape[0]):
        p = fa_int[f, FORCE_POINT]
        mag = _force_magnitude(fa_real, f, fa_int[f, FORCE_FUNCTION], 3, t)     # after dx, dy, dz
        _point_force3(q, v, pbody[p], ploc[p, 0], ploc[p, 1], ploc[p, 2],
                      mag * fa_real[f, 0], mag * fa_real[f, 1], mag * fa_real[f, 2], gen)
    for f in range(pd_int.shape[0]):
        p = pd_int[f, FORCE_POINT]
        b = pbody[p]
        A = _rot(q, v, b)
        rx, ry, rz, vx, vy, vz, ax, ay, az = _point3(q, v, b, A, ploc[p, 0], ploc[p, 1], ploc[p, 2])
        dx = pd_real[f, 0]
        dy = pd_real[f, 1]
        dz = pd_real[f, 2]
        mag = pd_magnitude(dx, dy, dz, pd_real[f, 3 + PD_REFERENCE], pd_real[f, 3 + PD_KP], pd_real[f, 3 + PD_KD],
                           rx, ry, rz, vx, vy, vz)
        _point_force3(q, v, b, ploc[p, 0], ploc[p, 1], ploc[p, 2], mag * dx, mag * dy, mag * dz, gen)
    if inputs.shape[0] > 0:
        for f in range(in_int.shape[0]):
            p = in_int[f, FORCE_POINT]
            _point_force3(q, v, pbody[p], ploc[p, 0], ploc[p, 1], ploc[p, 2],
                          inputs[3 * f], inputs[3 * f + 1], inputs[3 * f + 2], gen)
    if dims[GROUND_MODE] != GROUND_NONE:
        for k in range(0, dims[N_VELOCITY], 6):
            fx, fy, fz = frame_force(mass[k], agx, agy, agz)
            gen[k] -= fx
            gen[k + 1] -= fy
            gen[k + 2] -= fz


@njit(cache=True, inline="always")
def _joint3(q, v, alpha, P, AB, perm, off, rhs, jn, row):
    """Joint jn's rows from `row` on (model/joints.py): C_v (and its transpose) and γ − 2αĊ − α²C,
    Ċ = C_v v, for its coincident, dot-1 and dot-2 rows (joint_rows.dot1_row, dot2_row) and its
    screw row (:func:`_screw3`). Returns the next row."""
    pbody, ploc, jt_int, jt_real = P[PBODY], P[PLOC], P[JT_INT], P[JT_REAL]
    pa = jt_int[jn, POINT_A]
    pb = jt_int[jn, POINT_B]
    ba, bb, Aa, Ab, rx, ry, rz, rdx, rdy, rdz, anx, any_, anz = _pair3(q, v, pa, pb, pbody, ploc)
    lax = ploc[pa, 0]
    lay = ploc[pa, 1]
    laz = ploc[pa, 2]
    lbx = ploc[pb, 0]
    lby = ploc[pb, 1]
    lbz = ploc[pb, 2]
    if jt_int[jn, COINCIDENT]:
        # coincident points: C = r, C_v = H, γ = −a_n (Eqs. 18-19, 25)
        for i in range(3):
            sx = 1.0 if i == 0 else 0.0
            sy = 1.0 if i == 1 else 0.0
            sz = 1.0 if i == 2 else 0.0
            cd = _jrow(AB, perm, off, row, v, ba, Aa, lax, lay, laz, -sx, -sy, -sz)
            cd += _jrow(AB, perm, off, row, v, bb, Ab, lbx, lby, lbz, sx, sy, sz)
            c = sx * rx + sy * ry + sz * rz
            gamma = -(sx * anx + sy * any_ + sz * anz)
            rhs[perm[row]] = gamma - 2.0 * alpha * cd - alpha * alpha * c
            row += 1
    wax, way, waz = _omega(v, ba)
    wbx, wby, wbz = _omega(v, bb)
    for d in range(jt_int[jn, DOT1_ROWS]):
        # dot-1: s_a·s_b = 0 for body-fixed s_a = A_a s̄_a, s_b = A_b s̄_b
        j = DOT1 + 6 * d
        c, cax, cay, caz, cbx, cby, cbz, gamma = dot1_row(
            Aa, wax, way, waz, jt_real[jn, j], jt_real[jn, j + 1], jt_real[jn, j + 2],
            Ab, wbx, wby, wbz, jt_real[jn, j + 3], jt_real[jn, j + 4], jt_real[jn, j + 5])
        cd = _wrow(AB, perm, off, row, v, ba, cax, cay, caz)
        cd += _wrow(AB, perm, off, row, v, bb, cbx, cby, cbz)
        rhs[perm[row]] = gamma - 2.0 * alpha * cd - alpha * alpha * c
        row += 1
    for d in range(jt_int[jn, DOT2_ROWS]):
        # dot-2: s_a·(r_b − r_a) = 0
        j = DOT2 + 3 * d
        c, a0, a1, a2, cax, cay, caz, gamma = dot2_row(
            Aa, wax, way, waz, jt_real[jn, j], jt_real[jn, j + 1], jt_real[jn, j + 2],
            rx, ry, rz, rdx, rdy, rdz, anx, any_, anz)
        cd = _jrow(AB, perm, off, row, v, ba, Aa, lax, lay, laz, -a0, -a1, -a2)
        cd += _jrow(AB, perm, off, row, v, bb, Ab, lbx, lby, lbz, a0, a1, a2)
        cd += _wrow(AB, perm, off, row, v, ba, cax, cay, caz)
        rhs[perm[row]] = gamma - 2.0 * alpha * cd - alpha * alpha * c
        row += 1
    if jt_int[jn, SCREW_ROW]:
        _screw3(v, alpha, AB, perm, off, rhs, jt_real[jn], row, ba, bb, Aa, Ab, lax, lay, laz, lbx, lby, lbz,
                rx, ry, rz, rdx, rdy, rdz, anx, any_, anz)
        row += 1
    return row


@njit(cache=True, inline="always")
def _screw3(v, alpha, AB, perm, off, rhs, jr, row, ba, bb, Aa, Ab, lax, lay, laz, lbx, lby, lbz,
            rx, ry, rz, rdx, rdy, rdz, anx, any_, anz):
    """A screw joint's row (joint_rows.screw_row) placed: its translational coefficient −ρ s on the
    points' H, its advance's and its turn's coefficients over ω̄_a and its turn's over ω̄_b, with
    Baumgarte's −2αĊ − α²C."""
    wax, way, waz = _omega(v, ba)
    wbx, wby, wbz = _omega(v, bb)
    c, tx, ty, tz, cx, cy, cz, nx, ny, nz, bx, by, bz, gamma = screw_row(
        Aa, wax, way, waz, Ab, wbx, wby, wbz, jr[SCREW], jr[SCREW + 1], jr[SCREW + 2],
        jr[SCREW_REL0:SCREW_REL0 + 9], jr[SCREW_RATIO], jr[SCREW_ADVANCE0], rx, ry, rz, rdx, rdy, rdz, anx, any_, anz)
    # the advance's part, −ρ × the dot-2 row of s
    cd = _jrow(AB, perm, off, row, v, ba, Aa, lax, lay, laz, -tx, -ty, -tz)
    cd += _jrow(AB, perm, off, row, v, bb, Ab, lbx, lby, lbz, tx, ty, tz)
    cd += _wrow(AB, perm, off, row, v, ba, cx, cy, cz)
    # the turn's part: −s̄·ω̄_a + (A_bᵀ s)·ω̄_b
    cd += _wrow(AB, perm, off, row, v, ba, nx, ny, nz)
    cd += _wrow(AB, perm, off, row, v, bb, bx, by, bz)
    rhs[perm[row]] = gamma - 2.0 * alpha * cd - alpha * alpha * c


@njit(cache=True)
def assemble3(t, q, v, z, inputs, alpha, P, AB, rhs, gen):
    """Fill AB (band storage of the permuted augmented matrix [[M + M_I, C_vᵀ], [C_v, 0]]) and rhs
    (permuted [Q_e + Q_Iv, γ − 2αĊ − α²C]) at (t, q, v) for a 3D mechanism, as ``Mechanism.assemble``
    and ``Mechanism.constraints``. gen: work vector of length n. Returns a status code."""
    q, v, z, inputs, AB, rhs, gen = _unowned((q, v, z, inputs, AB, rhs, gen))     # its arguments (_unowned)
    jt_int, gravity, perm, dims = P[JT_INT], P[GRAVITY], P[PERM], P[DIMS]
    n = dims[N_VELOCITY]
    off = dims[KL]                   # kl: K[i, j] is AB[i, off + j − i] (band_storage)
    _start_assembly(AB, gen, gravity, n, dims[HAS_GRAVITY])
    _add_bodies3(v, P, AB, perm, off, gen)
    agx, agy, agz = _ground_frame(t, inputs, P)
    status = _add_elements3(q, v, z, P, AB, perm, off, gen, agx, agy, agz)
    _add_rotational3(q, v, P, gen)
    _add_point_forces3(t, q, v, inputs, P, gen, agx, agy, agz)
    for i in range(n):
        rhs[perm[i]] = gen[i]
    row = n
    for jn in range(jt_int.shape[0]):
        row = _joint3(q, v, alpha, P, AB, perm, off, rhs, jn, row)
    return status


# ------------------------------------------------------------------------------------------------
# q̇ = B(q) v and the constraint residual
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def qdot3(q, v, P, out):
    """out = q̇ = B(q) v: Ṙ, and the orientation's rates from ω (``spatial.Orientation.rate``): the
    quaternion rate ṗ = ½ p ⊗ (0, ω) (p not normalised), or the Z-X-Z Euler angles' rates, which
    do not exist where |sin θ| < EULER_SINGULARITY (returns GIMBAL_LOCK there; OK otherwise)."""
    nb = P[DIMS][N_VELOCITY] // 6
    nqb = _coords_per_body(q, v)
    for b in range(nb):
        j = nqb * b
        k = 6 * b
        out[j] = v[k]
        out[j + 1] = v[k + 1]
        out[j + 2] = v[k + 2]
        if nqb == QUATERNION_COORDS:
            out[j + 3], out[j + 4], out[j + 5], out[j + 6] = quaternion_rates(
                q[j + 3], q[j + 4], q[j + 5], q[j + 6], v[k + 3], v[k + 4], v[k + 5])
        else:
            if abs(math.sin(q[j + 4])) < EULER_SINGULARITY:
                return GIMBAL_LOCK
            out[j + 3], out[j + 4], out[j + 5] = euler_rates(q[j + 4], q[j + 5], v[k + 3], v[k + 4], v[k + 5])
    return OK


@njit(cache=True)
def euler_lock_within(y, y_new, P):
    """Whether a step from y to y_new takes a body's Z-X-Z Euler angles through their singularity
    (sin θ changes sign or ends below EULER_SINGULARITY), as ``Mechanism.check_step``: the rates
    there are undefined and the result past it would be garbage. False for quaternions and in 2D."""
    dims = P[DIMS]
    n = dims[N_VELOCITY]
    if dims[DIMENSION] != 3 or n == 0:
        return False
    nq = dims[N_COORD]
    if (6 * nq) // n == QUATERNION_COORDS:
        return False
    for b in range(n // 6):
        s0 = math.sin(y[6 * b + 4])
        s1 = math.sin(y_new[6 * b + 4])
        if s0 * s1 <= 0.0 or abs(s1) < EULER_SINGULARITY:
            return True
    return False


@njit(cache=True)
def constraint_residual3(q, P):
    """Largest |C_i| over the joints' rows (coincident, dot-1, dot-2)."""
    pbody = P[PBODY]
    ploc = P[PLOC]
    jt_int = P[JT_INT]
    jt_real = P[JT_REAL]
    worst = 0.0
    z = np.zeros(P[DIMS][N_VELOCITY])
    for jn in range(jt_int.shape[0]):
        ba, bb, Aa, Ab, rx, ry, rz, rdx, rdy, rdz, anx, any_, anz = _pair3(
            q, z, jt_int[jn, POINT_A], jt_int[jn, POINT_B], pbody, ploc)
        if jt_int[jn, COINCIDENT]:
            worst = max(worst, abs(rx), abs(ry), abs(rz))
        for d in range(jt_int[jn, DOT1_ROWS]):
            j = DOT1 + 6 * d
            c = dot1_row(Aa, 0.0, 0.0, 0.0, jt_real[jn, j], jt_real[jn, j + 1], jt_real[jn, j + 2],
                         Ab, 0.0, 0.0, 0.0, jt_real[jn, j + 3], jt_real[jn, j + 4], jt_real[jn, j + 5])[0]
            worst = max(worst, abs(c))
        for d in range(jt_int[jn, DOT2_ROWS]):
            j = DOT2 + 3 * d
            c = dot2_row(Aa, 0.0, 0.0, 0.0, jt_real[jn, j], jt_real[jn, j + 1], jt_real[jn, j + 2],
                         rx, ry, rz, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)[0]
            worst = max(worst, abs(c))
        if jt_int[jn, SCREW_ROW]:
            jr = jt_real[jn]
            c = screw_residual(Aa, Ab, jr[SCREW], jr[SCREW + 1], jr[SCREW + 2], jr[SCREW_REL0:SCREW_REL0 + 9],
                               jr[SCREW_RATIO], jr[SCREW_ADVANCE0], rx, ry, rz)[0]
            worst = max(worst, abs(c))
    return worst


# ------------------------------------------------------------------------------------------------
# Output signals (the same values as inerter.engine.outputs.Signals, in the layout of `signal_layout3`)
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _gq3(qdd, ba, bb, ga, gb):
    """gᵀq̈ of a 3D translational element (g = Hᵀ r̂: ga over a's six coordinates, gb over b's)."""
    gq = 0.0
    if ba >= 0:
        ka = 6 * ba
        for i in range(6):
            gq += ga[i] * qdd[ka + i]
    if bb >= 0:
        kb = 6 * bb
        for i in range(6):
            gq += gb[i] * qdd[kb + i]
    return gq


@njit(cache=True)
def state_rates3(q, v, z, qdd, P, dz):
    """dz: the rates of the translational elements' internal states of a 3D scene (as
    :func:`state_rates2`)."""
    el_int, el_real = P[EL_INT], P[EL_REAL]
    ga = carray(_stack(6), 6)       # g over a's and b's coordinates (_stack)
    gb = carray(_stack(6), 6)
    for e in range(el_int.shape[0]):
        if el_int[e, STATES] == 0:
            continue
        kind, L, Ldot, an, perp2, gq = _axial3(q, v, qdd, e, P, ga, gb)
        o = el_int[e, STATE]
        c = el_int[e, STATES]
        law.state_rates(kind, el_real[e], L, Ldot, an, perp2, gq, z[o:o + c], dz[o:o + c])


@njit(cache=True, inline="always")
def _axial3(q, v, qdd, e, P, ga, gb):
    """Element e's axial kinematics in a 3D scene at q̈ (as :func:`_axial2`); ga, gb: work (6)."""
    kind, ba, bb, rdx, rdy, rdz, anx, any_, anz, L, ex, ey, ez, meets, distance = _element3(
        q, v, e, P[EL_INT], P[EL_REAL], P[PBODY], P[PLOC], ga, gb)
    Ldot, an, perp2 = axial_scalars(rdx, rdy, rdz, anx, any_, anz, ex, ey, ez)
    return kind, L, Ldot, an, perp2, _gq3(qdd, ba, bb, ga, gb)


@njit(cache=True)
def settle3(q, v, qdd, P):
    """Set each screw efficiency's mode of a 3D scene from the solved accelerations q̈ (as
    :func:`settle2`); returns how many changed."""
    el_int, el_real = P[EL_INT], P[EL_REAL]
    ga = carray(_stack(6), 6)       # g over a's and b's coordinates (_stack)
    gb = carray(_stack(6), 6)
    changed = 0
    for e in range(el_int.shape[0]):
        if el_real[e, EFFICIENCY] == 0.0:
            continue
        kind, L, Ldot, an, perp2, gq = _axial3(q, v, qdd, e, P, ga, gb)
        changed += settle(el_real[e], L, Ldot, an, perp2, gq)
    return changed


@njit(cache=True)
def wind3(q, v, P):
    """Move each 3D rotational element's φ_ref (PHI_REF) on to its angle at (q, v), an accepted
    state (inerter.elements.winding): the next steps read their angles on its branch."""
    rot_int, rot_real = P[ROT_INT], P[ROT_REAL]
    for e in range(rot_int.shape[0]):
        _, _, _, _, phi, _, _, _, _ = _rotational3(q, v, e, rot_int, rot_real)
        rot_real[e, PHI_REF] = phi


@njit(cache=True)
def wind3_step(q, v, q0, v0, h, P):
    """Move each 3D rotational element's φ_ref on to its angle at (q, v), the end of an accepted
    step of length h from (q0, v0): the reading there on the branch nearest φ_ref + h (φ̇(q0, v0) +
    φ̇(q, v))/2, where the rates at the step's ends carry the angle (the trapezoidal rule), not
    nearest φ_ref. A step that turns the relative rotation by more than half a turn (an adaptive
    method's long step where no force depends on the branch: a damper, a spring too weak to
    matter; DOP853 at rtol 1e-3 turns a free rotor by 5.5 rad a step) still winds it on. Where the
    step turns it by less, both branches are the same and φ_ref is the angle read from φ_ref, bit
    for bit (:func:`inerter.elements.winding.wound` returns the reading itself)."""
    rot_int, rot_real = P[ROT_INT], P[ROT_REAL]
    for e in range(rot_int.shape[0]):
        rot_real[e, PHI_REF] = _angle_from3(q, v, _twist_rate3(q0, v0, e, P), h, e, P)


@njit(cache=True, inline="always")
def _twist_rate3(q, v, e, P):
    """Element e's rate φ̇ at (q, v), which carries its angle over a step (:func:`_angle_from3`)."""
    rot_int, rot_real = P[ROT_INT], P[ROT_REAL]
    _, _, _, _, _, rate, _, _, _ = _rotational3(q, v, e, rot_int, rot_real)
    return rate


@njit(cache=True, inline="always")
def _angle_from3(q, v, rate0, h, e, P):
    """Element e's angle at (q, v), h after a state where it held φ_ref and turned at rate0
    (:func:`_twist_rate3`; h < 0: before): the reading there on the branch nearest φ_ref + h (rate0
    + φ̇(q, v))/2, where the rates carry the angle over h (the trapezoidal rule); the reading as
    :func:`_rotational3` winds it from φ_ref, bit for bit, where both branches are the same
    (:func:`inerter.elements.winding.wound` returns it as it is)."""
    rot_int, rot_real = P[ROT_INT], P[ROT_REAL]
    _, _, _, _, phi, rate, _, _, _ = _rotational3(q, v, e, rot_int, rot_real)
    return wound(carried(rot_real[e, PHI_REF], h, rate0, rate), phi)


@njit(cache=True, inline="always")
def _bodies_energy3(q, v, P):
    """Σ over a 3D scene's bodies of T + V (kinematics.spatial_body_energy, M0 = diag(m I, J) per
    body; `gravity` is all 0 where not declared), and Σ of their magnitudes."""
    mass, gravity, n = P[MASS], P[GRAVITY], P[DIMS][N_VELOCITY]
    nqb = _coords_per_body(q, v)
    energy = held = 0.0
    for b in range(n // 6):
        i, c = 6 * b, nqb * b
        part = spatial_body_energy(mass[i], mass, n + 9 * b, v[i], v[i + 1], v[i + 2], v[i + 3], v[i + 4], v[i + 5],
                                   gravity[i], gravity[i + 1], gravity[i + 2], q[c], q[c + 1], q[c + 2])
        energy += part
        held += abs(part)
    return energy, held


@njit(cache=True)
def scene_energy3(q, v, z, P):
    """:func:`scene_energy2` of a 3D scene."""
    energy, held = _bodies_energy3(q, v, P)
    el_int, el_real, rot_int, rot_real = P[EL_INT], P[EL_REAL], P[ROT_INT], P[ROT_REAL]
    ga = carray(_stack(6), 6)
    gb = carray(_stack(6), 6)
    for e in range(el_int.shape[0]):
        kind, _, _, rdx, rdy, rdz, anx, any_, anz, L, ex, ey, ez, _, _ = _element3(q, v, e, el_int, el_real, P[PBODY],
                                                                                P[PLOC], ga, gb)
        part = _stored_energy(q, v, z, P, e, kind, L, axial_scalars(rdx, rdy, rdz, anx, any_, anz, ex, ey, ez)[0], 6)
        energy += part
        held += abs(part)
    for e in range(rot_int.shape[0]):
        _, _, _, _, phi, w, _, _, _ = _rotational3(q, v, e, rot_int, rot_real)
        part = law.rotational_energy(rot_int[e, ROT_KIND], rot_real[e], phi, w)
        energy += part
        held += abs(part)
    return energy, held


@njit(cache=True)
def signal_values3(q, v, z, qdd, P, out):
    """Every point's position and velocity (6 per point), every translational element's s_rel,
    v_rel, axial force (an inerter's from Eq. 9 or 8 at the accelerations qdd), power and stored energy
    and its kind's extra outputs (an inerter's device: ``signal_layout3``), every rotational element's
    φ_rel, ω_rel, torque, power and energy, every body's orientation and angular velocity
    (BODY_OUTPUTS3 each), the energy (as ``Mechanism.energy``) and the largest constraint
    residual. Returns a status code."""
    pbody, ploc, el_int = P[PBODY], P[PLOC], P[EL_INT]
    rot_int, rot_real, jt_int, dims = P[ROT_INT], P[ROT_REAL], P[JT_INT], P[DIMS]
    nb = dims[N_VELOCITY] // 6
    status = OK
    k = 0
    for p in range(pbody.shape[0]):
        b = pbody[p]
        A = _rot(q, v, b)
        rx, ry, rz, vx, vy, vz, ax, ay, az = _point3(q, v, b, A, ploc[p, 0], ploc[p, 1], ploc[p, 2])
        out[k] = rx
        out[k + 1] = ry
        out[k + 2] = rz
        out[k + 3] = vx
        out[k + 4] = vy
        out[k + 5] = vz
        k += 6
    energy, _ = _bodies_energy3(q, v, P)
    for e in range(el_int.shape[0]):
        meets, energy, k = _element_signals3(q, v, z, qdd, P, e, energy, out, k)
        if meets:
            status = TERMINALS_MEET
    for e in range(rot_int.shape[0]):
        _, _, _, _, phi, w, _, _, _ = _rotational3(q, v, e, rot_int, rot_real)
        tau = law.torque(rot_int[e, ROT_KIND], rot_real[e], phi, w)
        k, energy = _rotational_outputs(rot_int[e, ROT_KIND], rot_real[e], phi, w, tau, energy, out, k)
    for b in range(nb):
        k = _body_outputs3(q, v, b, dims, out, k)
    out[k] = energy
    out[k + 1] = constraint_residual3(q, P) if jt_int.shape[0] else 0.0
    return status


@njit(cache=True, inline="always")
def _element_signals3(q, v, z, qdd, P, e, energy, out, k):
    """Translational element e's outputs of a 3D scene from out[k] on, at the accelerations qdd
    (:func:`_element_outputs`): (whether its terminals meet, `energy` plus its, the next k)."""
    ga = carray(_stack(6), 6)       # g over a's and b's coordinates (_stack: once per kernel call)
    gb = carray(_stack(6), 6)
    kind, ba, bb, rdx, rdy, rdz, anx, any_, anz, L, ex, ey, ez, meets, distance = _element3(
        q, v, e, P[EL_INT], P[EL_REAL], P[PBODY], P[PLOC], ga, gb)
    energy, k = _element_outputs(q, v, z, P, e, kind, L, distance, rdx, rdy, rdz, anx, any_, anz, ex, ey, ez,
                                 _gq3(qdd, ba, bb, ga, gb), 6, energy, out, k)
    return meets, energy, k


@njit(cache=True, inline="always")
def element_signals3(q, v, z, qdd, P, e, out):
    """Translational element e's outputs alone, from out[0] on, as :func:`signal_values3` writes
    them: what a column of one of them needs, without every other signal. Returns a status code."""
    meets, _, _ = _element_signals3(q, v, z, qdd, P, e, 0.0, out, 0)
    return TERMINALS_MEET if meets else OK


@njit(cache=True, inline="always")
def _body_outputs3(q, v, b, dims, out, k):
    """Body b's orientation and angular velocity from out[k] on (``outputs.Signals``): its unit
    quaternion (the state's, normalised, with quaternions; w ≥ 0 from its matrix with Euler
    angles), its Euler angles in the scene's sequence, ω in the global frame. Returns the next k."""
    A = _rot(q, v, b)
    nqb = _coords_per_body(q, v)
    if nqb == QUATERNION_COORDS:
        j = nqb * b + 3
        norm = math.sqrt(q[j] * q[j] + q[j + 1] * q[j + 1] + q[j + 2] * q[j + 2] + q[j + 3] * q[j + 3])
        pw, px, py, pz = q[j] / norm, q[j + 1] / norm, q[j + 2] / norm, q[j + 3] / norm
    else:
        pw, px, py, pz = quaternion_of_matrix9(A[0], A[1], A[2], A[3], A[4], A[5], A[6], A[7], A[8])
    out[k], out[k + 1], out[k + 2], out[k + 3] = pw, px, py, pz
    out[k + 4], out[k + 5], out[k + 6] = euler_angles9(A, dims[EULER_I], dims[EULER_J], dims[EULER_K])
    wx, wy, wz = _omega(v, b)
    out[k + 7], out[k + 8], out[k + 9] = matrix9_apply(A, wx, wy, wz)
    return k + BODY_OUTPUTS3


#: Outputs of each 3D body (_body_outputs3): quaternion (4), Euler angles (3), ω (3).
BODY_OUTPUTS3 = 10


# ------------------------------------------------------------------------------------------------
# Integrators: DOP853 and RK45 (scipy's error control, step-size rule and dense output, sampled
# at the output grid) and the classical RK4 with a fixed step (cubic Hermite between nodes).
# ------------------------------------------------------------------------------------------------
@njit(cache=True)
def _rhs(t, y, inputs, alpha, P, AB, rhs, gen, acc, dy):
    """dy = [q̇, v̇, ż] at y = [q, v, z]: q̇ = B(q) v (the identity in 2D), v̇ from Eq. (33), ż the
    elements' internal states' rates at those accelerations (z is empty where the scene declares
    none, and then never evaluated)."""
    P = _unowned(P)                 # entered from Python (_unowned)
    y, inputs, AB, rhs, gen, acc, dy = _unowned((y, inputs, AB, rhs, gen, acc, dy))     # and its arrays
    n = P[DIMS][N_VELOCITY]
    nq = P[DIMS][N_COORD]
    nv = nq + n
    q = y[:nq]
    v = y[nq:nv]
    z = y[nv:]
    st = _settled(_solved(_assemble_inlined_of(t, q, v, z, inputs, alpha, P, AB, rhs, gen), P, AB, rhs, acc),
                  t, q, v, z, inputs, alpha, P, AB, rhs, gen, acc)     # accelerations, its assembly inlined
    if _qdot_of(q, v, P, dy[:nq]) == GIMBAL_LOCK:
        return GIMBAL_LOCK
    for i in range(n):
        dy[nq + i] = acc[i]
    if y.shape[0] > nv:
        _state_rates_of(q, v, z, acc, P, dy[nv:])
    if st == OK:
        for i in range(y.shape[0]):
            if not math.isfinite(dy[i]):
                return NOT_FINITE
    return st


# ------------------------------------------------------------------------------------------------
# Change points of closed loops: where the joints' constraint rows become dependent
# ------------------------------------------------------------------------------------------------
# What the watch of an accepted step finds (:func:`loop_watch`).
LOOP_CLEAR, LOOP_REACHED, LOOP_CROSSED = range(3)


@njit(cache=True)
def joint_jacobian(t, y, inputs, alpha, P, work, Cv):
    """Cv = C_v (m × n, the joints' rows of Eq. 33's matrix) at the state y, read back out of the
    band storage the assembly fills (:func:`_addK`), so that the joints' rows are written once, in
    the assembly; `work`: :func:`work_arrays` (AB, rhs, gen are overwritten)."""
    AB, rhs, gen = work[W_AB], work[W_RHS], work[W_GEN]
    dims, perm = P[DIMS], P[PERM]
    n, nq, off = dims[N_VELOCITY], dims[N_COORD], dims[KL]
    _assemble_of(t, y[:nq], y[nq:nq + n], y[nq + n:], inputs, alpha, P, AB, rhs, gen)
    for r in range(Cv.shape[0]):
        pi = perm[n + r]
        for j in range(n):
            c = off + perm[j] - pi
            Cv[r, j] = AB[pi, c] if 0 <= c < AB.shape[1] else 0.0


@njit(cache=True)
def dependence(Cv, R):
    """How close the rows of Cv are to dependent, scale-free: the last over the first pivot of
    Gram-Schmidt with row pivoting (at each stage the row farthest from the span of those taken;
    Businger & Golub 1965's column pivoting on C_vᵀ). The last pivot is the distance of a row from
    the span of the others, at least σ_min; the first is the largest row norm, at most σ_max: the
    value is at least σ_min/σ_max, so that a value below a ratio means the singular values'
    ratio is below it too (Mechanism._dependent_joints then names the joints). `R`: scratch of
    Cv's shape."""
    m, n = Cv.shape
    R[:, :] = Cv
    taken = np.zeros(m, dtype=np.bool_)
    first = last = 0.0
    for stage in range(m):
        best, p = -1.0, 0
        for i in range(m):
            if not taken[i]:
                norm2 = 0.0
                for j in range(n):
                    norm2 += R[i, j] * R[i, j]
                if norm2 > best:
                    best, p = norm2, i
        last = math.sqrt(best)
        if stage == 0:
            first = last
        if last == 0.0:
            return 0.0
        taken[p] = True
        for i in range(m):
            if not taken[i]:
                dot = 0.0
                for j in range(n):
                    dot += R[i, j] * R[p, j]
                c = dot / best
                for j in range(n):
                    R[i, j] -= c * R[p, j]
    return last / first if m > 0 else 1.0


@njit(cache=True)
def orientation(Ca, Cb, G):
    """The sign of det(Ca Cbᵀ) (1.0, −1.0; 0.0 where singular), by Gaussian elimination with
    partial pivoting of G = Ca Cbᵀ (m × m scratch). With Cb = C_v at a step's start (of full rank:
    det(Cb Cbᵀ) > 0) and Ca = C_v(q(s)) along the step, det(Ca Cbᵀ) = det([C_v(q(s)); Tᵀ]) ·
    det([Cbᵀ T]) for T a basis of Cb's null space: the orientation of the augmented Jacobian,
    whose sign changes where a path through a simple bifurcation point crosses it (Allgower &
    Georg 1990, Sec. 8.1), here where the joints' rows lose rank."""
    m, n = Ca.shape
    for i in range(m):
        for k in range(m):
            s = 0.0
            for j in range(n):
                s += Ca[i, j] * Cb[k, j]
            G[i, k] = s
    sign = 1.0
    for k in range(m):
        p = k
        best = abs(G[k, k])
        for i in range(k + 1, m):
            if abs(G[i, k]) > best:
                best, p = abs(G[i, k]), i
        if best == 0.0:
            return 0.0
        if p != k:
            sign = -sign
            for j in range(k, m):
                G[k, j], G[p, j] = G[p, j], G[k, j]
        if G[k, k] < 0.0:
            sign = -sign
        for i in range(k + 1, m):
            f = G[i, k] / G[k, k]
            for j in range(k + 1, m):
                G[i, j] -= f * G[k, j]
    return sign


@njit(cache=True)
def loop_watch(t, y, t_new, y_new, inputs, alpha, P, work, monitor):
    """The change-point watch of an accepted step from (t, y) to (t_new, y_new) of a mechanism
    with closed loops (dims[LOOPS] > 0; a tree of joints keeps C_v of full rank and is not
    watched): LOOP_REACHED where the joints' rows at y_new are dependent within the ratio
    monitor[MONITOR_DEPENDENT] (:func:`dependence`), LOOP_CROSSED where the orientation
    det(C_v(y_new) C_v(y)ᵀ) is not positive (:func:`orientation`): the step jumped across a change
    point (its rows' measure may be small at neither end), else LOOP_CLEAR.

    Both are needed: a step accepted by the error control near a change point either keeps to
    its branch, and the orientation changes sign across it, or resolves the turn onto the other
    branch in steps of ~1e-8 s (the accelerations of Eq. 33 grow as 1/σ_min there: measured on
    tests/data/parallelogram_2d.toml, |q̈| from 0.7 to 4e7 m/s², docs/changepoint.md), whose nodes
    come within the ratio of it while the orientation may keep its sign.

    C_v at the step's start is the last clear step's C_v at its end, carried in `work`
    (cv_start, with cv_known[0] = 1; the caller sets it to 0 where y did not come from that step):
    one assembly per watched step instead of two, the same values."""
    C0, C1, R, G, known = work[CV_START], work[CV_END], work[CV_WORK], work[CV_GRAM], work[CV_KNOWN]
    joint_jacobian(t_new, y_new, inputs, alpha, P, work, C1)
    if dependence(C1, R) < monitor[MONITOR_DEPENDENT]:
        known[0] = 0.0
        return LOOP_REACHED
    if known[0] == 0.0:             # C_v at the step's start, unless the last clear step left it
        joint_jacobian(t, y, inputs, alpha, P, work, C0)
    if orientation(C1, C0, G) <= 0.0:
        known[0] = 0.0
        return LOOP_CROSSED
    C0[:, :] = C1                   # the next step starts where this one ends
    known[0] = 1.0
    return LOOP_CLEAR


@njit(cache=True, inline="always")
def _hermite(y, f, y_new, f_new, h, s, out, k):
    """out[k] = the cubic Hermite interpolant of RK4's step (y, f) → (y_new, f_new) of length h at
    the fraction s of it."""
    h00 = 2 * s ** 3 - 3 * s ** 2 + 1
    h10 = s ** 3 - 2 * s ** 2 + s
    h01 = -2 * s ** 3 + 3 * s ** 2
    h11 = s ** 3 - s ** 2
    for i in range(y.shape[0]):
        out[k, i] = h00 * y[i] + h10 * h * f[i] + h01 * y_new[i] + h11 * h * f_new[i]


@njit(cache=True)
def _state_in_step(method, hdr, y, y_prev, f_prev, f, dense, Pm, t, s, ts, out):
    """out[0] = the state at s in the last step (from hdr[RK_T_PREV], of length hdr[RK_H_LAST],
    to (t, y)): the dense output of DOP853 and RK45 (:func:`_rk_sample`), RK4's cubic Hermite
    (method NATIVE_RK4, from (y_prev, f_prev) to (y, f))."""
    if method == NATIVE_RK4:
        h = hdr[RK_H_LAST]
        _hermite(y_prev, f_prev, y, f, h, (s - hdr[RK_T_PREV]) / h, out, 0)
    else:
        ts[0] = s
        _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, 0, out)


@njit(cache=True)
def locate_crossing(method, hdr, y, y_prev, f_prev, f, dense, Pm, t, inputs, alpha, P, work, monitor, out):
    """Where the last step (as :func:`_state_in_step` reads it), found LOOP_CROSSED, crosses the
    change point: bisection on the sign of det(C_v(q(s)) C_v(q(t0))ᵀ) (:func:`orientation`) to
    adjacent floats, on the step's own interpolant. Returns the last time before the crossing, its
    state in out[0], where the joints' rows are dependent there within monitor[MONITOR_DEPENDENT]
    (:func:`dependence`); −1.0 where they are not (the sign changed as the rows turned by a right
    angle within the step, not through a loss of rank: no change point)."""
    m, n = P[DIMS][N_ROWS], P[DIMS][N_VELOCITY]
    C0 = np.empty((m, n))
    C1 = np.empty((m, n))
    G = np.empty((m, m))
    ts = np.empty(1)
    lo, hi = hdr[RK_T_PREV], t
    joint_jacobian(lo, y_prev, inputs, alpha, P, work, C0)
    while True:
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        _state_in_step(method, hdr, y, y_prev, f_prev, f, dense, Pm, t, mid, ts, out)
        joint_jacobian(mid, out[0], inputs, alpha, P, work, C1)
        if orientation(C1, C0, G) > 0.0:
            lo = mid
        else:
            hi = mid
    _state_in_step(method, hdr, y, y_prev, f_prev, f, dense, Pm, t, lo, ts, out)
    joint_jacobian(lo, out[0], inputs, alpha, P, work, C1)
    return lo if dependence(C1, C0) < monitor[MONITOR_DEPENDENT] else -1.0


@njit(cache=True)
def _stop_at_change_point(loop, method, hdr, y, y_prev, f_prev, f, dense, Pm, t, ts, k, out, inputs, alpha, P,
                          work, monitor):
    """After the last step (to (t, y), see :func:`_state_in_step`), which :func:`loop_watch` found
    at or across a change point (`loop`): its samples up to where the run stops and (status, the
    time it stops at, the first k not written). LOOP_REACHED: it stops at t, the step's samples
    written; LOOP_CROSSED: at the last time before the crossing (:func:`locate_crossing`), the
    samples before it written (the mechanism's motion is determined up to there), y becoming the
    state there (for the message); or, where the crossing is not a change point, OK and nothing
    written. Where every time of `ts` lies before the stop (a co-simulation step's integrator step
    reaching past its communication point), their samples are written and the status is OK: the
    caller takes the step again when asked further (:func:`_step_back`)."""
    ny = y.shape[0]
    t_stop = t
    stop = np.empty((1, ny))
    stop[0, :] = y
    if loop == LOOP_CROSSED:
        t_stop = locate_crossing(method, hdr, y, y_prev, f_prev, f, dense, Pm, t, inputs, alpha, P, work, monitor,
                                 stop)
        if t_stop < 0.0:
            return OK, t, k
    limit = t + 1e-12 * max(1.0, t) if loop == LOOP_REACHED else t_stop      # as _rk_sample_covered
    sampled = k
    while k < ts.shape[0] and ts[k] <= limit:
        if method == NATIVE_RK4:
            h = hdr[RK_H_LAST]
            _hermite(y_prev, f_prev, y, f, h, (ts[k] - hdr[RK_T_PREV]) / h, out, k)
        else:
            _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, k, out)
        k += 1
    _record_windings_of(out, sampled, k, ny, ts, t, y, P)
    if k == ts.shape[0]:
        return OK, t, k
    y[:] = stop[0]
    return CHANGE_POINT, t_stop, k


@njit(cache=True)
def _step_back(hdr, y, f, y_prev, f_prev, P, gaps, z):
    """Undo the last accepted step (from hdr[RK_T_PREV], y_prev, f_prev: its start) where it reached
    a change point past every time asked for (:func:`_stop_at_change_point`): the integration
    stays at the step's start, without a dense output (every sample before it is written), and
    the terminals' gaps are those there; taken again from there with the same size, the step is
    the same (a co-simulation step's samples do not depend on where the communication points
    fall). Returns the time it stays at."""
    y[:] = y_prev
    f[:] = f_prev
    hdr[RK_DENSE] = 0.0
    gaps_at(y, P, gaps, z)
    return hdr[RK_T_PREV]


@njit(cache=True)
def locate_meeting(method, hdr, y, y_prev, dense, Pm, t, P, out):
    """Where the last step of DOP853 or RK45 (from hdr[RK_T_PREV], y_prev to (t, y), its dense
    output `dense` computed), whose chord brings a translational element's terminals together
    (:func:`terminals_meet`), brings them together along its own dense output: bisection to
    adjacent floats, keeping the half whose chord (r_b − r_a at its ends, :func:`chord_margin`)
    comes within the element's limit, the earlier half where both do; where neither does (the
    longer chord cut a corner of the path), the half whose chord comes closer. The test that
    declares the meeting is the same, on ever shorter chords of the step's own solution, as an
    event is located on it. Returns the last time before the meeting, its state in out[0]."""
    lo, hi = hdr[RK_T_PREV], t
    gaps_lo, z = terminal_gaps(y_prev, P)
    gaps_hi, _ = terminal_gaps(y, P)
    gaps_mid = np.zeros_like(gaps_lo)
    ts = np.empty(1)
    while True:
        mid = 0.5 * (lo + hi)
        if not lo < mid < hi:
            break
        ts[0] = mid
        _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, 0, out)
        gaps_at(out[0], P, gaps_mid, z)
        first = chord_margin(gaps_lo, gaps_mid, P)
        if first <= 1.0 or first <= chord_margin(gaps_mid, gaps_hi, P):
            hi = mid
            gaps_hi[:, :] = gaps_mid
        else:
            lo = mid
            gaps_lo[:, :] = gaps_mid
    ts[0] = lo
    _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, 0, out)
    return lo


@njit(cache=True)
def _rk_meeting(method, hdr, y, y_prev, f, dense, Pm, t, ts, k, out, P, work, gaps, z):
    """After the step :func:`rk_advance` has just accepted (from hdr[RK_T_PREV], y_prev to (t, y),
    its dense output computed), whose chord brings a translational element's terminals together
    (:func:`terminals_meet`): the meeting located on the step's dense output
    (:func:`locate_meeting`), the samples of `ts` up to it written, y becoming the state there, and
    (MEETING, the time it stops at, the first k not written). Where every time of `ts` lies before
    the meeting (a co-simulation step's integrator step reaching past its communication point),
    their samples are written and the step is taken back (:func:`_step_back`): (OK, the time it
    stays at, k); the caller takes it again when asked further, and meets the terminals again."""
    ny = y.shape[0]
    stop = np.empty((1, ny))
    t_stop = locate_meeting(method, hdr, y, y_prev, dense, Pm, t, P, stop)
    sampled = k
    while k < ts.shape[0] and ts[k] <= t_stop:
        _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, k, out)
        k += 1
    _record_windings_of(out, sampled, k, ny, ts, t, y, P)
    if k == ts.shape[0]:
        return OK, _step_back(hdr, y, f, y_prev, work[W_K][0], P, gaps, z), k
    y[:] = stop[0]
    return MEETING, t_stop, k


@njit(cache=True)
def _rms(x):
    s = 0.0
    for i in range(x.shape[0]):
        s += x[i] * x[i]
    return math.sqrt(s / x.shape[0])


@njit(cache=True)
def _initial_step(t0, y0, f0, t_bound, order, rtol, atol, inputs, alpha, P, AB, rhs, gen, acc, before):
    """scipy.integrate._ivp.common.select_initial_step (one extra evaluation)."""
    ny = y0.shape[0]
    interval = abs(t_bound - t0)
    if interval == 0.0:
        return 0.0
    scale = atol + np.abs(y0) * rtol
    d0 = _rms(y0 / scale)
    d1 = _rms(f0 / scale)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval)
    y1 = y0 + h0 * f0
    f1 = np.empty(ny)
    _rhs(min(t0 + h0, before), y1, inputs, alpha, P, AB, rhs, gen, acc, f1)
    d2 = _rms((f1 - f0) / scale) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100 * h0, h1, interval)


@njit(cache=True)
def rk_stages(A):
    """Rows of stages :func:`rk_advance` needs for the tableau A (DOP853's 16 with its dense-output
    stages; RK45's 6 + 1)."""
    return max(A.shape[0], 7)


# Header of the resumable adaptive Runge-Kutta state (``rk_advance``): float slots.
# RK_STEPS counts the steps of the current segment (the stiffness test's cadence), RK_TOTAL every
# step since the integration started; RK_JUMP is the discontinuity the segment ends at (0: none).
RK_T, RK_H, RK_T_PREV, RK_H_LAST, RK_DENSE, RK_STEPS, RK_EVALS, RK_HITS, RK_CALM, RK_SMALL, RK_STARTED, \
    RK_JUMP, RK_TOTAL = range(13)
RK_HEADER = 13
# rk_advance's status when the arrays keeping every step's dense output are full (integrate_rk
# gives them room and resumes; never returned further).
DENSE_FULL = -1


@njit(cache=True, inline="always")
def _before(jump):
    """The last time the right-hand side is evaluated at in a segment that ends at a discontinuity
    `jump` (a step force's switch, a ground record's end on a value other than zero; 0: none): one
    ulp before it, so that
    stages at the segment's end see the values the forces had over the segment (as
    ``simulation.derivative``)."""
    return np.nextafter(jump, -np.inf) if jump > 0.0 else np.inf


@njit(cache=True, inline="always")
def _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, k, out):
    """out[k] = y(ts[k]) for a sample covered by the last step (within 1e-12·max(1 s, t) of its end
    node t): the step's own solution at the node, its dense output inside the step. A node at the
    segment's discontinuity (RK_JUMP) also takes the samples within that tolerance before it, so
    that a communication point one ulp off a record's sample time (t + h of the importer against
    the whole run's grid) gets the same state."""
    ny = y.shape[0]
    if ts[k] >= t or hdr[RK_DENSE] == 0.0 or (t == hdr[RK_JUMP] and ts[k] >= t - 1e-12 * max(1.0, t)):
        for i in range(ny):
            out[k, i] = y[i]
        return
    h = hdr[RK_H_LAST]
    x = (ts[k] - hdr[RK_T_PREV]) / h
    if method == 0:
        for i in range(ny):
            val = 0.0
            for r in range(6, -1, -1):
                val += dense[r, i]
                if (6 - r) % 2 == 0:
                    val *= x
                else:
                    val *= 1.0 - x
            out[k, i] = val + y_prev[i]
    else:
        for i in range(ny):
            val = 0.0
            p = 1.0
            for r in range(Pm.shape[1]):
                p *= x
                val += dense[r, i] * p
            out[k, i] = y_prev[i] + h * val


@njit(cache=True, inline="always")
def _keep_step(keep, t, t_new, y_start, dense):
    """Append the accepted step from t to t_new (solution `y_start` at its start, dense-output
    coefficients `dense`) to `keep` = (nodes, coeffs, kept), see :func:`rk_advance`."""
    nodes, coeffs, kept = keep
    i = kept[KEPT_COUNT]
    nodes[i] = t
    nodes[i + 1] = t_new
    for j in range(y_start.shape[0]):
        coeffs[i, 0, j] = y_start[j]
    for r in range(1, coeffs.shape[1]):
        for j in range(y_start.shape[0]):
            coeffs[i, r, j] = dense[r - 1, j]
    kept[KEPT_COUNT] = i + 1


@njit(cache=True, inline="always")
def _step_of(nodes, count, t, i):
    """The step of a kept dense output (`count` steps from `nodes`) whose polynomial gives y(t), as
    scipy's OdeSolution chooses it: a node belongs to the step ending there; before the first
    node the first step, after the last the last. `i`: a guess (the previous time's step)."""
    if (i == 0 or nodes[i] < t) and (i == count - 1 or t <= nodes[i + 1]):
        return i
    if i + 1 < count and nodes[i + 1] < t and (i + 1 == count - 1 or t <= nodes[i + 2]):
        return i + 1
    lo = 0
    hi = count + 1                   # the first node >= t, by bisection over nodes[:count + 1]
    while lo < hi:
        mid = (lo + hi) // 2
        if nodes[mid] < t:
            lo = mid + 1
        else:
            hi = mid
    return min(max(lo - 1, 0), count - 1)


@njit(cache=True, inline="always")
def _dop853_at(nodes, coeffs, i, t, comps, Y, row):
    """Y[row, j] = y_j(t) for j in `comps` from DOP853's polynomial of kept step i, as
    :func:`_rk_sample` evaluates it (its loop unrolled: the same operations)."""
    t0 = nodes[i]
    x = (t - t0) / (nodes[i + 1] - t0)
    xm = 1.0 - x
    for c in range(comps.shape[0]):
        j = comps[c]
        val = (0.0 + coeffs[i, 7, j]) * x
        val = (val + coeffs[i, 6, j]) * xm
        val = (val + coeffs[i, 5, j]) * x
        val = (val + coeffs[i, 4, j]) * xm
        val = (val + coeffs[i, 3, j]) * x
        val = (val + coeffs[i, 2, j]) * xm
        val = (val + coeffs[i, 1, j]) * x
        Y[row, j] = val + coeffs[i, 0, j]


@njit(cache=True, inline="always")
def _rk45_at(nodes, coeffs, i, t, comps, Y, row):
    """Y[row, j] = y_j(t) for j in `comps` from RK45's polynomial of kept step i, as
    :func:`_rk_sample` evaluates it."""
    t0 = nodes[i]
    h = nodes[i + 1] - t0
    x = (t - t0) / h
    for c in range(comps.shape[0]):
        j = comps[c]
        val = 0.0
        p = 1.0
        for r in range(1, coeffs.shape[1]):
            p *= x
            val += coeffs[i, r, j] * p
        Y[row, j] = coeffs[i, 0, j] + h * val


@njit(cache=True, inline="always")
def _dense_block(method, nodes, coeffs, count, times, start, end, comps, Y, i):
    """Y[k − start, j] = y_j(times[k]) for start ≤ k < end and j in `comps`, from the kept dense
    output of :func:`rk_advance` (`count` steps), in the steps :func:`_step_of` chooses (`i`: a
    guess for the first). Returns the step of the last time."""
    if method == 0:
        for k in range(start, end):
            i = _step_of(nodes, count, times[k], i)
            _dop853_at(nodes, coeffs, i, times[k], comps, Y, k - start)
    else:
        for k in range(start, end):
            i = _step_of(nodes, count, times[k], i)
            _rk45_at(nodes, coeffs, i, times[k], comps, Y, k - start)
    return i


# Keeping every accepted step's dense output (rk_advance's `keep`): (nodes, coeffs, kept) with
# kept[KEPT_COUNT] steps kept so far and kept[KEPT_ON] = 1 where the caller wants them (0: a
# placeholder, so that rk_advance compiles once for both uses).
KEPT_COUNT, KEPT_ON = range(2)


@njit(cache=True)
def no_keep(ny):
    """A `keep` for :func:`rk_advance` that keeps nothing (kept[KEPT_ON] = 0)."""
    return np.empty(1), np.empty((0, 1, ny)), np.zeros(2, dtype=np.int64)


def cosim_scratch(P, ny):
    """The arrays a running co-simulation integration keeps besides its state and
    :func:`work_arrays`, allocated once instead of at every communication step: (gaps, z, fresh,
    keep): the terminals' gaps at y and the zero velocities they are evaluated with
    (:func:`terminal_gaps`), fresh[0] = 1 where `gaps` are those at the integration's y (the last
    accepted step moved them there, :func:`terminals_meet`; 0: computed at the next step's start),
    and a `keep` that keeps nothing (:func:`no_keep`), see :func:`cosim_rk`."""
    return (np.zeros((P[EL_INT].shape[0], 3)), np.zeros(P[DIMS][N_VELOCITY]), np.zeros(1),
            no_keep.py_func(ny))


@njit(cache=True, inline="always")
def _rk_shape(method):
    """(stages of the step, order of its error estimate's lower solution + 1 = the exponent's base)
    of DOP853 (method 0) and RK45 (method 1), as scipy's ``n_stages`` and ``error_estimator_order``."""
    if method == 0:
        return 12, 7
    return 6, 4


@njit(cache=True)
def _rk_start(hdr, y, f, t_bound, order, rtol, atol, inputs, alpha, P, work, before):
    """A fresh integration's derivative at its start and, where RK_H is 0, its first step chosen as
    scipy's select_initial_step does. Returns the right-hand side's status."""
    AB, rhs, gen, acc = work[W_AB], work[W_RHS], work[W_GEN], work[W_ACC]
    t = hdr[RK_T]
    st = _rhs(min(t, before), y, inputs, alpha, P, AB, rhs, gen, acc, f)
    hdr[RK_EVALS] += 1
    if st != OK:
        return st
    if not hdr[RK_H] > 0.0:
        hdr[RK_H] = _initial_step(t, y, f, t_bound, order, rtol, atol, inputs, alpha, P, AB, rhs, gen, acc, before)
        hdr[RK_EVALS] += 1
    hdr[RK_STARTED] = 1.0
    hdr[RK_DENSE] = 0.0
    hdr[RK_T_PREV] = t
    hdr[RK_H_LAST] = 0.0
    return OK


@njit(cache=True, inline="always")
def _rk_stages(first, last, hdr, t, h, y, inputs, alpha, P, A, C, work, before):
    """Stages K[s] for first ≤ s < last of a step of length h from (t, y): the derivative at
    y + h Σ_j A[s, j] K[j] and t + C[s] h (clipped `before` a discontinuity). Returns the status of
    the first right-hand side that failed (OK: none)."""
    AB, rhs, gen, acc, K, ys = work[W_AB], work[W_RHS], work[W_GEN], work[W_ACC], work[W_K], work[W_YS]
    for s in range(first, last):
        for i in range(y.shape[0]):
            acc_s = 0.0
            for j in range(s):
                acc_s += K[j, i] * A[s, j]
            ys[i] = y[i] + acc_s * h
        st = _rhs(min(t + C[s] * h, before), ys, inputs, alpha, P, AB, rhs, gen, acc, K[s])
        hdr[RK_EVALS] += 1
        if st != OK:
            return st
    return OK


@njit(cache=True)
def _rk_trial(n_stages, hdr, t, h, y, f, inputs, alpha, P, A, B, C, work, before):
    """The stages K[0..n_stages] of one trial step of length h from (t, y) with derivative f, its
    solution y_new and the derivative f_new there (K[n_stages] = f_new). Returns the status of the
    first right-hand side that failed (OK: none)."""
    AB, rhs, gen, acc, K = work[W_AB], work[W_RHS], work[W_GEN], work[W_ACC], work[W_K]
    y_new, f_new = work[W_Y_NEW], work[W_F_NEW]
    ny = y.shape[0]
    for i in range(ny):
        K[0, i] = f[i]
    st = _rk_stages(1, n_stages, hdr, t, h, y, inputs, alpha, P, A, C, work, before)
    if st != OK:
        return st
    for i in range(ny):
        acc_s = 0.0
        for j in range(n_stages):
            acc_s += K[j, i] * B[j]
        y_new[i] = y[i] + h * acc_s
    st = _rhs(min(t + h, before), y_new, inputs, alpha, P, AB, rhs, gen, acc, f_new)
    hdr[RK_EVALS] += 1
    for i in range(ny):
        K[n_stages, i] = f_new[i]
    return st


@njit(cache=True)
def _rk_error(method, n_stages, h, y, y_new, K, E, E3, rtol, atol):
    """The scaled error norm of a trial step as scipy computes it: DOP853's blend of its 5th- and
    3rd-order estimates (Hairer's), RK45's RMS of its 4th-order estimate."""
    ny = y.shape[0]
    if method == 0:
        e5 = 0.0
        e3 = 0.0
        for i in range(ny):
            sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
            a5 = 0.0
            a3 = 0.0
            for j in range(n_stages + 1):
                a5 += K[j, i] * E[j]
                a3 += K[j, i] * E3[j]
            a5 /= sc
            a3 /= sc
            e5 += a5 * a5
            e3 += a3 * a3
        if e5 == 0.0 and e3 == 0.0:
            return 0.0
        return abs(h) * e5 / math.sqrt((e5 + 0.01 * e3) * ny)
    e = 0.0
    for i in range(ny):
        sc = atol + max(abs(y[i]), abs(y_new[i])) * rtol
        a = 0.0
        for j in range(n_stages + 1):
            a += K[j, i] * E[j]
        a = a * h / sc
        e += a * a
    return math.sqrt(e / ny)


@njit(cache=True)
def _rk_attempt(method, hdr, t, h_abs, kink, t_bound, y, f, rtol, atol, inputs, alpha, P, A, B, C, E, E3,
                monitor, work, before):
    """Trial steps from (t, y) until the error control accepts one, as scipy's ``_step_impl``: each
    clipped to `t_bound` and to end on the next `kink`; a trial whose stages cannot be evaluated
    (singular, not finite, terminals that meet: a wild stage of too long a step) is tried again
    `monitor[MONITOR_TRIAL_SHRINK]` times as long, as inerter.engine.simulation does with scipy's integrators. Returns (status, t_new, h,
    the step size proposed next): STEP_TOO_SMALL (or the failing stage's status) below 10 ulp of t.
    A clipped step accepted at its first trial proposes the size proposed before the clip (see
    :func:`rk_advance`)."""
    n_stages, order = _rk_shape(method)
    err_exp = -1.0 / (order + 1)
    h_want = h_abs
    min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
    if h_abs < min_step:
        h_abs = min_step
    rejected = False
    trial_failure = OK
    while True:
        if h_abs < min_step:
            return (STEP_TOO_SMALL if trial_failure == OK else trial_failure), t, 0.0, h_abs
        t_new = min(t + h_abs, t_bound)
        clipped = t_new > kink          # ends on the kink instead of straddling it
        if clipped:
            t_new = kink
        h = t_new - t
        h_abs = abs(h)
        st = _rk_trial(n_stages, hdr, t, h, y, f, inputs, alpha, P, A, B, C, work, before)
        if st == SINGULAR or st == NOT_FINITE or st == TERMINALS_MEET:
            trial_failure = st
            h_abs *= monitor[MONITOR_TRIAL_SHRINK]
            rejected = True
            continue
        if st != OK:
            return st, t, h, h_abs
        err = _rk_error(method, n_stages, h, y, work[W_Y_NEW], work[W_K], E, E3, rtol, atol)
        if err < 1.0:
            factor = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** err_exp)
            if rejected:
                factor = min(1.0, factor)
            h_abs *= factor
            if clipped and not rejected:
                h_abs = h_want          # the step size goes on as proposed before the clip
            return OK, t_new, h, h_abs
        h_abs *= max(0.2, 0.9 * err ** err_exp)
        rejected = True


@njit(cache=True)
def _rk_watch(n_stages, hdr, t_new, h, y, y_new, K, A, monitor):
    """After an accepted step, the watch of :func:`rk_advance`'s docstring: Hairer's stiffness test
    (STIFF after `monitor[MONITOR_STIFF_HITS]` firings in a row) and a step size collapsing (COLLAPSED), with its
    counters in `hdr` (RK_HITS, RK_CALM, RK_SMALL). Returns OK or the status that stops the run."""
    if monitor[MONITOR_STIFF_BOUND] > 0.0 and (hdr[RK_HITS] > 0
                                           or int(hdr[RK_STEPS]) % int(monitor[MONITOR_STIFF_EVERY]) == 0):
        num = 0.0
        den = 0.0
        last = n_stages - 1
        for i in range(y.shape[0]):
            acc_s = 0.0
            for j in range(last):
                acc_s += K[j, i] * A[last, j]
            d = y_new[i] - (y[i] + h * acc_s)     # y_new − the last stage's argument (c = 1)
            e = K[n_stages, i] - K[last, i]
            den += d * d
            num += e * e
        if den > 0.0:
            if abs(h) * math.sqrt(num / den) > monitor[MONITOR_STIFF_BOUND]:
                hdr[RK_CALM] = 0.0
                hdr[RK_HITS] += 1
                if hdr[RK_HITS] >= monitor[MONITOR_STIFF_HITS]:
                    return STIFF
            else:
                hdr[RK_CALM] += 1
                if hdr[RK_CALM] >= 6:
                    hdr[RK_HITS] = 0.0
    if abs(h) < monitor[MONITOR_COLLAPSE_RELATIVE] * max(1.0, abs(t_new)):
        hdr[RK_SMALL] += 1
        if hdr[RK_SMALL] >= monitor[MONITOR_COLLAPSE_STEPS]:
            return COLLAPSED
    else:
        hdr[RK_SMALL] = 0.0
    return OK


@njit(cache=True)
def _rk_dense(method, hdr, t, h, y, inputs, alpha, P, A, C, Dm, Pm, work, before, dense):
    """The dense-output coefficients of the accepted step from (t, y) of length h into `dense`, as
    scipy's ``_dense_output_impl`` (DOP853's three extra stages are evaluated here). Returns the
    status of the right-hand side."""
    K, y_new, f_new = work[W_K], work[W_Y_NEW], work[W_F_NEW]
    n_stages, _ = _rk_shape(method)
    ny = y.shape[0]
    if method != 0:
        for i in range(ny):
            for r in range(Pm.shape[1]):
                qr = 0.0
                for j in range(n_stages + 1):
                    qr += K[j, i] * Pm[j, r]
                dense[r, i] = qr
        return OK
    st = _rk_stages(n_stages + 1, A.shape[0], hdr, t, h, y, inputs, alpha, P, A, C, work, before)
    if st != OK:
        return st
    for i in range(ny):
        dlt = y_new[i] - y[i]
        dense[0, i] = dlt
        dense[1, i] = h * K[0, i] - dlt
        dense[2, i] = 2.0 * dlt - h * (f_new[i] + K[0, i])
        for r in range(4):
            acc_s = 0.0
            for j in range(Dm.shape[1]):
                acc_s += Dm[r, j] * K[j, i]
            dense[3 + r, i] = h * acc_s
    return OK


@njit(cache=True, inline="always")
def _rk_sample_covered(method, hdr, y, y_prev, dense, Pm, t, ts, k, out):
    """out[k] = y(ts[k]) for every sample from k on that the last step covers (:func:`_rk_sample`);
    returns the first k not written."""
    while k < ts.shape[0] and ts[k] <= t + 1e-12 * max(1.0, t):
        _rk_sample(method, hdr, y, y_prev, dense, Pm, t, ts, k, out)
        k += 1
    return k


@njit(cache=True)
def rk_advance(method, hdr, y, f, y_prev, dense, ts, out, k0, t_bound, rtol, atol, max_steps, inputs, alpha, P,
               A, B, C, E, E3, Dm, Pm, monitor, work, kinks, keep, gaps, z):
    """Advance an adaptive explicit Runge-Kutta integration until its last step covers the last of
    the increasing times `ts`, writing out[k] = y(ts[k]) for k ≥ k0 as the steps cover them: the step's own
    solution at a node (within 1e-12·max(1 s, t)), its dense output inside a step. Steps are
    clipped to `t_bound` and to the kinks of the right-hand side, never to a sample time, so
    samples taken in one call or over many calls lie on the steps of one integration from its
    start to `t_bound`.

    `kinks`: increasing times where the right-hand side's slope jumps but its value does not (a
    ground record's samples, ``Mechanism.kinks``). A step that would cross one is clipped to end
    on it, so that no step straddles a kink and the method keeps its order; the integration runs
    on from there with its last derivative f and the step size the error control proposed before
    the clip (the clipped step's own proposal would shrink the steps after a short clipped step,
    whose error estimate is smaller by (h_clipped/h)^(p+1), and round-off for a very short one),
    as ``simulation._on_through_kink`` does on the numpy path. A clipped trial step that is
    rejected is tried again shorter, under the error control as any other.

    The integration is resumable: its whole state lives in the arrays passed in, `hdr` (time, the
    step size the error control proposes next, the last step's start and length, whether its dense
    output is computed, counters; slots RK_*), the solution `y` and its derivative `f` at the last
    node, the solution `y_prev` at the start of the last step and that step's dense-output
    coefficients `dense` (7 × len(y)). A fresh state has RK_STARTED = 0 (:func:`_rk_start`).

    Watched as inerter.engine.simulation.StepMonitor watches scipy's integrators (:func:`_rk_watch`),
    with its constants in `monitor` = (stiffness bound, every, hits, collapse relative, collapse
    steps, trial shrink), and the step budget `max_steps` of this call (MAX_STEPS: a whole run is
    one call, a co-simulation step another).

    method 0: DOP853 (A, B, C, E5 = E, E3, D = Dm as in scipy), method 1: RK45 (A, B, C, E, P = Pm).
    `work`: scratch from :func:`work_arrays` with rk_stages(A) rows of stages.
    `keep`: (nodes, coeffs, kept); where kept[KEPT_ON] is 1, every accepted step's dense output is
    kept, as scipy's ``dense_output=True`` does (DOP853's three extra stages are then evaluated at
    every step): step i = kept[KEPT_COUNT] spans nodes[i] to nodes[i + 1], coeffs[i, 0] is the
    solution at its start and coeffs[i, 1:] its coefficients (:func:`_dop853_at`, :func:`_rk45_at`).
    When coeffs is full the call returns DENSE_FULL before the next step, resumable once the caller
    gave it room (:func:`integrate_rk`). Keeping them changes neither the steps nor the samples.
    `gaps`, `z`: the terminals' gaps at y (:func:`terminal_gaps`), moved on with every accepted
    step (:func:`terminals_meet`), so that a call resuming the integration need not evaluate them
    again. A mechanism whose joints close a loop (dims[LOOPS] > 0) is watched for change points
    after each accepted step (:func:`_rk_loop_watch`). An accepted step whose chord brings a
    translational element's terminals together (:func:`terminals_meet`) is valid up to the
    meeting: it is taken, with its dense output, and the integration stops at the meeting located
    on it (:func:`_rk_meeting`, MEETING). Returns (status, the first k not written); on failure y, f
    and the last step's data are those of the last good node (`gaps` may be the failed step's),
    except at a change point (CHANGE_POINT) or a meeting (MEETING), where y is the state it stopped
    at, and hdr[RK_T] the time there."""
    work = _unowned(work)
    K, y_new, f_new = work[W_K], work[W_Y_NEW], work[W_F_NEW]
    work[CV_KNOWN][0] = 0.0         # C_v at y is not known yet (loop_watch): y may have been set anew
    n_stages, order = _rk_shape(method)
    keeping = keep[2][KEPT_ON] == 1
    before = _before(hdr[RK_JUMP])
    if hdr[RK_STARTED] == 0.0:
        st = _rk_start(hdr, y, f, t_bound, order, rtol, atol, inputs, alpha, P, work, before)
        if st != OK:
            return st, k0
    t = hdr[RK_T]
    h_abs = hdr[RK_H]
    steps_before = hdr[RK_STEPS]
    status = OK
    k = _rk_sample_covered(method, hdr, y, y_prev, dense, Pm, t, ts, k0, out)
    _record_windings_of(out, k0, k, y.shape[0], ts, t, y, P)
    ik = np.searchsorted(kinks, t, side="right")             # the next kink: kinks[ik] > t
    while k < ts.shape[0] and status == OK:
        if keeping and keep[2][KEPT_COUNT] >= keep[1].shape[0]:
            status = DENSE_FULL
            break
        kink = kinks[ik] if ik < kinks.shape[0] else np.inf
        status, t_new, h, h_abs = _rk_attempt(method, hdr, t, h_abs, kink, t_bound, y, f, rtol, atol, inputs,
                                              alpha, P, A, B, C, E, E3, monitor, work, before)
        if status != OK:
            break
        hdr[RK_STEPS] += 1
        meets = terminals_meet(gaps, z, y_new, P)       # located below, on the step's dense output
        if not meets:                                   # a meeting ends the run before these matter
            if euler_lock_within(y, y_new, P):
                status = GIMBAL_LOCK
            else:
                status = _rk_watch(n_stages, hdr, t_new, h, y, y_new, K, A, monitor)
        if status != OK:
            h_abs = abs(h)
            break
        # The step is accepted: it becomes the last step, with its dense output where a sample lies
        # inside it (DOP853's extra stages are evaluated only then) or where every step's is kept.
        hdr[RK_DENSE] = 0.0
        if keeping or meets or (ts[k] <= t_new + 1e-12 * max(1.0, t_new) and ts[k] < t_new):
            status = _rk_dense(method, hdr, t, h, y, inputs, alpha, P, A, C, Dm, Pm, work, before, dense)
            if status != OK:
                break
            hdr[RK_DENSE] = 1.0
        for i in range(y.shape[0]):
            y_prev[i] = y[i]
            y[i] = y_new[i]
            f[i] = f_new[i]
        _wind_step_of(y, y_prev, h, P)
        hdr[RK_T_PREV] = t
        hdr[RK_H_LAST] = h
        if keeping:
            _keep_step(keep, t, t_new, y_prev, dense)
        t = t_new
        while ik < kinks.shape[0] and kinks[ik] <= t:
            ik += 1
        if rarely(meets):
            status, t, k = _rk_meeting(method, hdr, y, y_prev, f, dense, Pm, t, ts, k, out, P, work, gaps, z)
            h_abs = abs(h)
            break
        if rarely(P[DIMS][LOOPS] != 0):
            status, t, k = _rk_loop_watch(method, hdr, y, y_prev, f, dense, t, ts, k, out, inputs, alpha, P, A, C,
                                          Dm, Pm, monitor, work, before, gaps, z)
            if status != OK or k == ts.shape[0]:
                h_abs = abs(h)
                break
        sampled = k
        k = _rk_sample_covered(method, hdr, y, y_prev, dense, Pm, t, ts, k, out)
        _record_windings_of(out, sampled, k, y.shape[0], ts, t, y, P)
        if hdr[RK_STEPS] - steps_before > max_steps:
            status = MAX_STEPS
    hdr[RK_T] = t
    hdr[RK_H] = h_abs
    hdr[RK_TOTAL] += hdr[RK_STEPS] - steps_before
    return status, k


@njit(cache=True)
def integrate_rk(method, y0, t0, t_end, grid, out, rtol, atol, first_step, max_steps, inputs, alpha, P,
                 A, B, C, E, E3, Dm, Pm, monitor, jump, kinks, keep):
    """One integration from t0 to t_end with :func:`rk_advance`, sampling `out[k] = y(grid[k])` for
    k ≥ 1 (grid[-1] = t_end), running on through the `kinks` (see :func:`rk_advance`); `jump`: the
    discontinuity it ends at (0: none), see :func:`_before`. `keep`: (nodes, coeffs, kept) of
    :func:`rk_advance` (:func:`no_keep`: nothing kept), to which every step's dense output is
    appended, the arrays replaced by ones twice as long when full. Returns (status, samples written, steps,
    evaluations, t reached, next step size, keep, the state reached): the step size is the one the
    error control proposes after the last accepted step (scipy's ``h_abs``); the state, where it
    stopped at a change point (CHANGE_POINT) or where terminals meet (MEETING), the one there."""
    P = _unowned(P)                 # entered from Python (_unowned)
    ny = y0.shape[0]
    hdr = np.zeros(RK_HEADER)
    hdr[RK_T] = t0
    hdr[RK_H] = first_step
    hdr[RK_JUMP] = jump
    y = y0.copy()
    f = np.empty(ny)
    y_prev = y0.copy()
    dense = np.zeros((7, ny))
    work = work_arrays(P, ny, rk_stages(A))
    gaps, z = terminal_gaps(y, P)
    nodes, coeffs, kept = keep
    k = np.int64(1)                     # not a literal: a literal k0 would compile rk_advance once more
    while True:
        # the step budget is the whole integration's, over the calls
        st, k = rk_advance(method, hdr, y, f, y_prev, dense, grid, out, k, t_end, rtol, atol,
                           max_steps - int(hdr[RK_STEPS]), inputs, alpha, P, A, B, C, E, E3, Dm, Pm, monitor,
                           work, kinks, (nodes, coeffs, kept), gaps, z)
        if st != DENSE_FULL:
            break
        room = coeffs.shape[0]
        size = max(2 * room, 16)
        more = np.empty((size, coeffs.shape[1], coeffs.shape[2]))
        more[:room] = coeffs
        coeffs = more
        longer = np.empty(size + 1)
        longer[:room + 1] = nodes
        nodes = longer
    return st, k, int(hdr[RK_STEPS]), int(hdr[RK_EVALS]), hdr[RK_T], hdr[RK_H], (nodes, coeffs, kept), y


# ------------------------------------------------------------------------------------------------
# One output signal along a history or a dense output (metrics, Result.dense): a point's coordinate
# from that point's kinematics alone, any other signal from signal_values (with the accelerations
# where that signal needs them); the same values as signal_history's.
# ------------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def _point_value2(q, v, p, c, P):
    pbody, ploc = P[PBODY], P[PLOC]
    rx, ry, vx, vy, ux, uy, _, _, w = _point(q, v, pbody[p], ploc[p, 0], ploc[p, 1])
    if c == 0:
        return rx
    if c == 1:
        return ry
    if c == 2:
        return vx
    return vy


@njit(cache=True, inline="always")
def _point_value3(q, v, p, c, P):
    pbody, ploc = P[PBODY], P[PLOC]
    b = pbody[p]
    A = _rot(q, v, b)
    rx, ry, rz, vx, vy, vz, ax, ay, az = _point3(q, v, b, A, ploc[p, 0], ploc[p, 1], ploc[p, 2])
    if c == 0:
        return rx
    if c == 1:
        return ry
    if c == 2:
        return rz
    if c == 3:
        return vx
    if c == 4:
        return vy
    return vz


def _point_value_of(q, v, p, c, P):
    raise NotImplementedError("compiled code only")


@overload(_point_value_of, inline="always")
def _point_value_by_dimension(q, v, p, c, P):
    """Component c of point p's [r, ṙ] (the values signal_values writes for it)."""
    if is_spatial(P):
        return lambda q, v, p, c, P: _point_value3(q, v, p, c, P)
    return lambda q, v, p, c, P: _point_value2(q, v, p, c, P)


@njit(cache=True, inline="always")
def _point_signal(index, P):
    """(point, component) of the signal at `index` of signal_values' layout, (-1, 0) where it is not
    a point's coordinate."""
    width = 2 * P[DIMS][DIMENSION]
    if index < width * P[PBODY].shape[0]:
        return index // width, index % width
    return -1, 0


@njit(cache=True, inline="always")
def _signal_at(t, y, inputs, alpha, need_acc, P, work, raw, index, element, slot):
    """(status, the signal at `index` of signal_values' layout at y = [q, v, z]): translational
    element `element`'s output `slot` evaluated alone where `element` ≥ 0 (:func:`element_signals2`),
    else every signal (:func:`_signals_at`); accelerations from Eq. (33) only when `need_acc`."""
    if element < 0:
        st = _signals_at(t, y, inputs, alpha, need_acc, P, work, raw)
        return st, raw[index]
    nq = P[DIMS][N_COORD]
    nv = nq + P[DIMS][N_VELOCITY]
    AB, rhs, gen, acc, K, y_new, f_new, ys, sig_acc = _unowned(work)[:SOLVER_WORK]
    _wind_of(y, P)                  # as _signals_at: the accelerations read the wound angles
    st = accelerations(t, y[:nq], y[nq:nv], y[nv:], inputs, alpha, P, AB, rhs, gen, sig_acc) if need_acc else OK
    if st == OK:
        st = _element_signals_of(y[:nq], y[nq:nv], y[nv:], sig_acc, P, element, raw)
    return st, raw[slot]


@njit(cache=True)
def signal_column(times, states, comps, windings, inputs, alpha, index, element, slot, need_acc, P, raw, out):
    """out[k] = the signal at `index` of signal_values' layout at each sample of a history (rows
    [q, v, z]) (:func:`_signal_at`: `element` ≥ 0, the signal is that translational element's
    output `slot`, evaluated alone), the 3D rotational elements' angles wound from windings[k]
    (:func:`_hold_windings_of`). `comps`: the state components the signal reads (the others are
    read as 0). `raw`: scratch of the layout's length. Returns (status, the first sample where it
    could not be evaluated)."""
    P = _unowned(P)                 # entered from Python (_unowned)
    ny = states.shape[1]
    nq = P[DIMS][N_COORD]
    y = np.zeros(ny)
    q = y[:nq]
    v = y[nq:nq + P[DIMS][N_VELOCITY]]
    work = work_arrays(P, ny, 1)
    point, component = _point_signal(index, P)
    for k in range(states.shape[0]):
        for i in range(comps.shape[0]):
            y[comps[i]] = states[k, comps[i]]
        if point >= 0:
            out[k] = _point_value_of(q, v, point, component, P)
        else:
            _hold_windings_of(windings, k, P)
            st, out[k] = _signal_at(times[k], y, inputs, alpha, need_acc, P, work, raw, index, element, slot)
            if st != OK:
                return st, k
    return OK, states.shape[0]


@njit(cache=True)
def dense_rows(method, nodes, coeffs, count, times, out):
    """out[k, j] = y_j(times[k]), every component j, from a kept dense output (:func:`rk_advance`,
    `count` steps), as scipy's ``OdeSolution(times)`` evaluates it."""
    _dense_block(method, nodes, coeffs, count, times, 0, times.shape[0], np.arange(coeffs.shape[2]), out, 0)


#: Times a dense-output signal is evaluated at in one block (:func:`dense_signal`).
DENSE_BLOCK = 256


@njit(cache=True)
def dense_signal(method, nodes, coeffs, count, times, comps, windings, inputs, alpha, index, element, slot, need_acc,
                 P, raw, out):
    """out[k] = the signal at `index` of signal_values' layout at times[k] on a kept dense output:
    block after block of times, the state components `comps` the signal reads (:func:`_dense_block`,
    the others 0), then :func:`signal_column` on them, called (one compiled copy of the outputs'
    code for samples and dense output alike), with the 3D rotational elements' angles wound from
    windings[k]. Returns (status, the first time where it could not be evaluated)."""
    n = times.shape[0]
    ny = coeffs.shape[2]
    states = np.zeros((DENSE_BLOCK, ny))
    values = np.empty(DENSE_BLOCK)
    i = 0
    for start in range(0, n, DENSE_BLOCK):
        end = min(n, start + DENSE_BLOCK)
        m = end - start
        i = _dense_block(method, nodes, coeffs, count, times, start, end, comps, states, i)
        # windings without rows (none given): the angles wound from the PHI_REF P holds, as signal_column's
        st, done = signal_column(times[start:end], states[:m], comps, windings[start:end], inputs, alpha, index,
                                 element, slot, need_acc, P, raw, values[:m])
        for k in range(done):
            out[start + k] = values[k]
        if done < m:
            return st, start + done
    return OK, n


# rk_advance inlined where a co-simulation step enters it (one call per communication step instead of
# one per integration: the call's dozens of arrays are passed, and reference-counted, once less).
_rk_advance_inlined = njit(inline="always")(rk_advance.py_func)


@njit(inline="always")
def cosim_rk(method, hdr, y, f, y_prev, dense, ts, out, t_bound, rtol, atol, max_steps, inputs, alpha, P,
             tableau, monitor, work, need_acc, raw, order, values, kinks, scratch):
    """One co-simulation step on the compiled path: :func:`rk_advance` to the one time in `ts`
    (out[0] = y there), running on through the `kinks`, then every output signal there: `raw` in the layout of
    :func:`signal_values`, `values[i] = raw[order[i]]`. `tableau`: (A, B, C, E, E3, D, P) of the
    method. `scratch`: (gaps, z, fresh, keep) of :func:`cosim_scratch`; the gaps are computed at y
    where fresh[0] is 0, and fresh[0] is 0 again after a failed step (its gaps may be the rejected
    node's). Returns (integrator status, signal status); NOT_FINITE where the state is not finite.
    Inlined where it is called (:func:`cosim_step`)."""
    gaps, z, fresh, keep = scratch
    A, B, C, E, E3, Dm, Pm = tableau
    if fresh[0] == 0.0:
        gaps_at(y, P, gaps, z)
        fresh[0] = 1.0
    st, k = _rk_advance_inlined(method, hdr, y, f, y_prev, dense, ts, out, np.int64(0), t_bound, rtol, atol,
                                max_steps, inputs, alpha, P, A, B, C, E, E3, Dm, Pm, monitor, work, kinks, keep,
                                gaps, z)   # np.int64: as integrate_rk
    if st != OK:
        fresh[0] = 0.0
        return st, OK
    y_out = out[0]
    for i in range(y_out.shape[0]):
        if not math.isfinite(y_out[i]):
            return NOT_FINITE, OK
    st = _signals_at(ts[0], y_out, inputs, alpha, need_acc, P, work, raw)
    for i in range(order.shape[0]):
        values[i] = raw[order[i]]
    return OK, st


@njit(cache=True)
def next_jump(jumps, t):
    """The first of the increasing discontinuities `jumps` after t (0.0: none)."""
    i = np.searchsorted(jumps, t, side="right")
    return jumps[i] if i < jumps.shape[0] else 0.0


@njit(cache=True, inline="always")
def _restart_at_jump(hdr, y, y_prev, jumps, jump):
    """Start the integration afresh at the discontinuity `jump` it stands on (RK_STARTED = 0: the
    next step chooses its size as scipy does, from the state there), the next discontinuity after
    it becoming RK_JUMP."""
    for slot in (RK_H, RK_STARTED, RK_DENSE, RK_H_LAST, RK_STEPS, RK_EVALS, RK_HITS, RK_CALM, RK_SMALL):
        hdr[slot] = 0.0
    hdr[RK_T_PREV] = hdr[RK_T]
    hdr[RK_JUMP] = next_jump(jumps, jump)
    y_prev[:] = y


def _cosim_step(method, hdr, y, f, y_prev, dense, t_end, ts, out, t_bound, rtol, atol, max_steps, inputs, alpha, P,
                tableau, monitor, work, need_acc, raw, order, values, jumps, kinks, scratch):
    """A co-simulation step to t_end on the running integration (:func:`cosim_rk`), segment by
    segment: a segment ends at its discontinuity (RK_JUMP: a step force's switch, a ground record's
    end on a value other than zero, of the increasing `jumps`), where the integration starts
    afresh, with the step size chosen as scipy does, from the state there, as :func:`integrate_rk`
    over the segments of a whole run; through the `kinks` (a ground record's samples) it runs on
    (:func:`rk_advance`). Steps are clipped to the segment's end, to the kinks and to `t_bound`.
    `ts` (one slot) and `out` (one row) take the sample; `tableau`: (A, B, C, E, E3, D, P) of the
    method; `scratch`: :func:`cosim_scratch`, whose gaps hold on where a segment starts afresh (the
    state does not change there). Returns (integrator status, signal status)."""
    P = _unowned(P)                 # entered from Python (_unowned); a no-op where P is unowned already
    while True:
        jump = hdr[RK_JUMP]
        if jump > 0.0 and hdr[RK_T] >= jump and t_end > jump:
            _restart_at_jump(hdr, y, y_prev, jumps, jump)
            continue
        ts[0] = min(t_end, jump) if jump > 0.0 else t_end
        bound = min(t_bound, jump) if jump > 0.0 else t_bound
        st, sst = cosim_rk(method, hdr, y, f, y_prev, dense, ts, out, bound, rtol, atol, max_steps, inputs, alpha,
                           P, tableau, monitor, work, need_acc, raw, order, values, kinks, scratch)
        if st != OK or ts[0] == t_end:
            return st, sst


#: The co-simulation step entered from Python (``CompiledStepper.step``), and inlined into the FMU's
#: native step (:func:`native_step_on`): each kernel call that is not inlined passes every array of
#: its arguments field by field (P alone is some 150 words), which cost the native step about
#: 0.8 µs of each communication step through two such calls (lumped_mass_2d, 2026-11-26). An
#: inlined kernel's calls keep to 30 arguments: Python compiles a call of more to CALL_FUNCTION_EX
#: (the arguments as one tuple), which numba's inliner refuses ("Calling a closure with *args").
cosim_step = njit(cache=True)(_cosim_step)
_cosim_step_inlined = njit(inline="always")(_cosim_step)


@njit(cache=True)
def _rk_loop_watch(method, hdr, y, y_prev, f, dense, t, ts, k, out, inputs, alpha, P, A, C, Dm, Pm, monitor, work,
                   before, gaps, z):
    """:func:`loop_watch` on the step :func:`rk_advance` has just accepted (from hdr[RK_T_PREV],
    y_prev to (t, y); its stages still in `work`) and, where it finds a change point,
    :func:`_stop_at_change_point`, the step's dense output computed first where a crossing is to be
    located on it; where every time of `ts` lies before the stop, the step is taken back
    (:func:`_step_back`), the caller ending its call there. Kept out of :func:`rk_advance`'s loop,
    which a tree of joints runs as before. Returns (status, the time it stops or stays at, the
    first k not written)."""
    loop = loop_watch(hdr[RK_T_PREV], y_prev, t, y, inputs, alpha, P, work, monitor)
    if loop == LOOP_CLEAR:
        return OK, t, k
    if loop == LOOP_CROSSED and hdr[RK_DENSE] == 0.0:
        st = _rk_dense(method, hdr, hdr[RK_T_PREV], hdr[RK_H_LAST], y_prev, inputs, alpha, P, A, C, Dm, Pm, work,
                       before, dense)
        if st != OK:
            return st, t, k
        hdr[RK_DENSE] = 1.0
    status, t_stop, k = _stop_at_change_point(loop, method, hdr, y, y_prev, y_prev, f, dense, Pm, t, ts, k, out,
                                              inputs, alpha, P, work, monitor)
    if status == OK and k == ts.shape[0]:
        return OK, _step_back(hdr, y, f, y_prev, work[W_K][0], P, gaps, z), k
    return status, t_stop, k


@njit(cache=True)
def _rk4_loop_watch(t, y, f, t_new, y_new, f_new, grid, k, out, inputs, alpha, P, work, monitor):
    """:func:`loop_watch` on RK4's step from (t, y, f) to (t_new, y_new, f_new) and, where it finds
    a change point, :func:`_stop_at_change_point` on the step's cubic Hermite (y_new becoming the
    state it stops at). Returns (status, the time it stops at, the first k not written)."""
    loop = loop_watch(t, y, t_new, y_new, inputs, alpha, P, work, monitor)
    if loop == LOOP_CLEAR:
        return OK, t, k
    hdr = np.zeros(RK_HEADER)
    hdr[RK_T_PREV] = t
    hdr[RK_H_LAST] = t_new - t
    # np.int64: the method as a value, not a literal, so that numba compiles _stop_at_change_point and
    # locate_crossing once for every method rather than again for RK4's constant
    return _stop_at_change_point(loop, np.int64(NATIVE_RK4), hdr, y_new, y, f, f_new, work[W_K], work[W_K], t_new,
                                 grid, k, out, inputs, alpha, P, work, monitor)


@njit(cache=True)
def integrate_rk4(y0, t0, t_end, grid, out, step, max_steps, inputs, alpha, P, jump, kinks, monitor):
    """Classical RK4 with a fixed step, cubic Hermite between nodes; `jump`: a discontinuity the
    integration ends at (0: none), see :func:`_before`. The step before t_end and the step before
    each of the increasing `kinks` (a ground record's samples, where the right-hand side's slope
    jumps) are shortened to end there, and from a kink the steps go on with the fixed step and the
    last derivative, as from a restart there without its evaluation. A mechanism with closed loops
    is watched for change points (:func:`loop_watch`, its ratio in `monitor`). A step that brings a
    translational element's terminals together is taken again in shorter steps up to the meeting
    (:func:`_rk4_to_meeting`, MEETING). Returns (status, samples written, steps, evaluations, t
    reached, the state reached: where it stopped at a change point or a meeting, the one there)."""
    P = _unowned(P)                 # entered from Python (_unowned)
    work = work_arrays(P, y0.shape[0], 4)
    y = y0.copy()
    st, k, steps, evals, t = _rk4_run(y, t0, t_end, grid, out, step, max_steps, inputs, alpha, P, jump, kinks, work,
                                      monitor)
    return st, k, steps, evals, t, y


@njit(cache=True, inline="always")
def _rk4_step(t, h, y, f, k2, k3, k4, y_new, f_new, ys, inputs, alpha, P, AB, rhs, gen, acc, before):
    """One classical RK4 step of length h from (t, y) with derivative f: its stages into k2, k3,
    k4 (`ys`: scratch), its solution y_new and the derivative f_new there. Returns the worst
    status of the right-hand sides (OK: none failed)."""
    ny = y.shape[0]
    for i in range(ny):
        ys[i] = y[i] + h / 2 * f[i]
    st = _rhs(min(t + h / 2, before), ys, inputs, alpha, P, AB, rhs, gen, acc, k2)
    for i in range(ny):
        ys[i] = y[i] + h / 2 * k2[i]
    st = max(st, _rhs(min(t + h / 2, before), ys, inputs, alpha, P, AB, rhs, gen, acc, k3))
    for i in range(ny):
        ys[i] = y[i] + h * k3[i]
    st = max(st, _rhs(min(t + h, before), ys, inputs, alpha, P, AB, rhs, gen, acc, k4))
    for i in range(ny):
        y_new[i] = y[i] + h / 6 * (f[i] + 2 * k2[i] + 2 * k3[i] + k4[i])
    return max(st, _rhs(min(t + h, before), y_new, inputs, alpha, P, AB, rhs, gen, acc, f_new))


#: The shortest step RK4's stability watch reads, relative to the fixed step, and by how much a
#: step must multiply the mode beyond both 1 and the exact solution's |e^(hλ)| to count
#: (:func:`rk4_watch`): a forced response fitted as a mode that grows, or round-off, is not a step
#: outside RK4's region; a mode that grows less than 0.1 % a step would take 4600 steps to grow 100 times.
RK4_SHORTEST = 1e-3
RK4_EXCESS = 1e-3
#: The fewest steps in a row outside the region that stop a run: a λ fitted to a state barely
#: moving, or moving mostly under its forcing (a chain's first steps from rest under a sine force:
#: one spurious h·λ = 715i, then two of a forced response), does not last.
RK4_MIN_STEPS = 4


@njit(cache=True, inline="always")
def rk4_amplification(re, im):
    """|R(z)|, z = re + i·im: what RK4 multiplies a mode of h·λ = z by at every step,
    R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 (its stability region: |R| ≤ 1)."""
    z = complex(re, im)
    return abs(1.0 + z * (1.0 + z * (0.5 + z * (1.0 / 6.0 + z / 24.0))))


@njit(cache=True, inline="always")
def _exact_growth(re):
    """max(1, |e^(hλ)|) for Re(hλ) = re: what a step may multiply a mode by without growing it
    faster than the exact solution does, or at all where that decays."""
    return max(1.0, math.exp(min(re, 700.0)))


@njit(cache=True, inline="always")
def _dominant_mode(uu, pu, pp, wu, wp, h):
    """(Re λ, Im λ ≥ 0, |λ|) of the mode that dominates f, from the products of u = f, p = J f and
    w = J² f: the monic quadratic λ² − a λ − b whose J² f ≈ a J f + b f fits best (least squares
    over the state) has the mode's eigenvalues as roots, a damped pair's (a = 2 Re λ, b = −|λ|²)
    or two real ones, of which the one RK4 amplifies most beyond the exact solution at the step h.
    Where J f lies along f, the real λ = f·J f/‖f‖²."""
    det = pp * uu - pu * pu
    if det <= 1e-12 * pp * uu:
        lam = pu / uu
        return lam, 0.0, abs(lam)
    a = (wp * uu - wu * pu) / det
    b = (pp * wu - pu * wp) / det
    disc = 0.25 * a * a + b
    if disc < 0.0:
        return 0.5 * a, math.sqrt(-disc), math.sqrt(-b)
    r1, r2 = 0.5 * a + math.sqrt(disc), 0.5 * a - math.sqrt(disc)
    e1 = rk4_amplification(h * r1, 0.0) / _exact_growth(h * r1)
    e2 = rk4_amplification(h * r2, 0.0) / _exact_growth(h * r2)
    return (r1 if e1 >= e2 else r2), 0.0, max(abs(r1), abs(r2))


@njit(cache=True, inline="always")
def rk4_watch(f, k2, k3, h, step, monitor):
    """RK4's stability watch after a step of length h (the fixed `step`, or shorter to end at a
    kink or a communication point) from a state with derivative f = k1 and midpoint stages k2, k3
    (:func:`_rk4_step`). Both stages are taken at t + h/2, so J f ≈ (k2 − k1)·2/h (less ∂f/∂t,
    a forcing's) and J² f ≈ (k3 − k2)·4/h²: the step's own stages give the Krylov vectors f, J f,
    J² f, whatever the units of positions and velocities, and from them

    * the eigenvalue λ of the mode that dominates f (:func:`_dominant_mode`), real or one of a
      damped pair, and RK4's factor on it, |R(hλ)| (:func:`rk4_amplification`);
    * the mode's amplitude √(‖f‖² + ‖J f‖²/|λ|²): the mode's quadratic form at two phases a
      quarter period apart for an undamped pair, the same at every phase (within a factor
      ((1 + |cos φ|)/(1 − |cos φ|))^½ for a damped pair at the angle φ of λ), where ‖f‖ alone
      swings by the ratio of the units' scales.

    A step counts as beyond the stability region where |R(hλ)| exceeds both 1 and what the exact
    solution does, |e^(hλ)|, by RK4_EXCESS (a mode that grows physically, an unstable
    equilibrium's or a forced response fitted as one, is not the integrator's). Each step is judged at the h it takes: where kinks (a ground record's samples)
    or communication points closer than the fixed step shorten every step, no longer step is
    taken. A shortened step within the region leaves the count as it is (the remainder before a
    communication point, between full steps beyond it); RK4_PATIENCE full ones in a row restart
    it, and one alone adds its factor (below 1) to the product: with several modes in the stages
    the fit alternates between them, and a count restarted at every step read inside let the
    8-link benchmark chain at 18 ms (its fastest mode at |R| = 1.18) grow and saturate, status ok
    and 1.2e-2 m off. A step shorter
    than RK4_SHORTEST of the fixed step is left out: its stage differences are too small to read.
    Returns UNSTABLE when at least RK4_MIN_STEPS steps in a row were beyond, and both the
    amplitude and the product of the steps' factors |R(hλ)| (each over the exact growth) have grown
    MONITOR_RK4_GROWTH times since then. The amplitude confirms it, as a nonlinearity can bound a
    mode that the estimate puts beyond (a saturating friction's sticking mode); the factors confirm
    that the growth is the steps', as the amplitude of a nonlinear motion, read through a λ fitted
    anew at each step, can jump where the factors are barely above 1. Its running
    values: monitor[MONITOR_RK4_HITS:] (the mode's step·λ for the message); MONITOR_RK4_WATCH 0:
    the watch is off."""
    if monitor[MONITOR_RK4_WATCH] == 0.0 or h < RK4_SHORTEST * step:
        return OK
    uu = pu = pp = wu = wp = 0.0
    for i in range(f.shape[0]):
        p = (k2[i] - f[i]) * (2.0 / h)
        w = (k3[i] - k2[i]) * (4.0 / (h * h))
        uu += f[i] * f[i]
        pu += p * f[i]
        pp += p * p
        wu += w * f[i]
        wp += w * p
    if not (uu > 0.0 and pp > 0.0 and math.isfinite(wp)):     # at rest, or not finite (the rhs says so)
        monitor[MONITOR_RK4_HITS] = 0.0
        monitor[MONITOR_RK4_CALM] = 0.0
        return OK
    re, im, size = _dominant_mode(uu, pu, pp, wu, wp, h)
    factor = rk4_amplification(h * re, h * im) / _exact_growth(h * re)
    if not factor > 1.0 + RK4_EXCESS:
        if h >= step * (1.0 - 1e-9):        # a shortened step within leaves the count as it is (h:
            monitor[MONITOR_RK4_CALM] += 1.0    # t_new − t on the numpy path, the fixed step to rounding)
            if monitor[MONITOR_RK4_CALM] >= RK4_PATIENCE:
                monitor[MONITOR_RK4_HITS] = 0.0
            elif monitor[MONITOR_RK4_HITS] > 0.0:     # a step read inside between them: its factor counts
                monitor[MONITOR_RK4_LOG_FACTORS] += math.log(max(factor, 1e-300))
        return OK
    monitor[MONITOR_RK4_CALM] = 0.0
    amplitude = math.sqrt(uu + pp / (size * size))
    if monitor[MONITOR_RK4_HITS] == 0.0:
        monitor[MONITOR_RK4_FIRST] = amplitude
        monitor[MONITOR_RK4_LOG_FACTORS] = 0.0
    monitor[MONITOR_RK4_HITS] += 1.0
    monitor[MONITOR_RK4_AMPLITUDE] = amplitude
    monitor[MONITOR_RK4_RE] = step * re
    monitor[MONITOR_RK4_IM] = step * im
    growth = monitor[MONITOR_RK4_GROWTH]
    grown = (amplitude >= growth * monitor[MONITOR_RK4_FIRST]
             and monitor[MONITOR_RK4_LOG_FACTORS] >= math.log(growth)     # the steps before this one's
             and monitor[MONITOR_RK4_HITS] >= RK4_MIN_STEPS)
    monitor[MONITOR_RK4_LOG_FACTORS] += math.log(factor)
    return UNSTABLE if grown else OK


#: Full RK4 steps read inside the region, in a row, that restart the stability watch's count
#: (:func:`rk4_watch`).
RK4_PATIENCE = 3


#: The most one RK4 step may change the energy of a scene that conserves it, relative to what the
#: scene holds at the step's start; and the most the energy of a scene that can only lose it may
#: rise above its lowest, relative to what the scene held there (:func:`energy_watch`).
ENERGY_JUMP_LIMIT = 1.0


@njit(cache=True, inline="always")
def energy_watch(energy, held, monitor):
    """RK4's energy watch, with the energy and what the scene holds (the sum of its parts'
    magnitudes, :func:`scene_energy2`) at the end of the step just taken. ENERGY_JUMP:

    * in a scene that conserves its energy (no forcing, no dissipation: MONITOR_ENERGY_WATCH
      ENERGY_CONSERVED), where that one step changed the energy by more than ENERGY_JUMP_LIMIT
      times what the scene held at its start. RK4 changes a conserved energy by O(h⁵) a step; a
      step across a state where the motion's time scale collapses can multiply it
      (snap_through_2d at 0.105 s: 65 and 6400 times in single steps, while every mode the stages
      show stays inside RK4's region, :func:`rk4_watch`);
    * in a scene that can only lose its energy (dampers too: ENERGY_LOST), where the energy rose
      above the lowest it had by more than ENERGY_JUMP_LIMIT times what the scene held there,
      while the stability watch follows no mode (monitor[MONITOR_RK4_HITS] 0: where it does, it
      decides, with the mode and the step that keeps it inside). The motion's energy cannot rise,
      and RK4 raises it by O(h⁵) a step inside its region; beyond it, where the modes of the
      stages alternate, the stability watch's count restarts and a nonlinearity bounds the mode
      it reads (a damped three-mass chain at 1.05 times its limit ended with status ok, its
      energy from 8.1 J to 2.3e3 J).

    Also call it at a call's start, with monitor[MONITOR_ENERGY_HELD] < 0: it takes the start's
    values. The lowest so far carries over from call to call (a run's segments, a co-simulation's
    steps) until monitor[MONITOR_ENERGY_LOWEST_HELD] < 0 (none yet: a run's start, or a stepper
    retuned, its energy changed between steps). Its values: monitor[MONITOR_ENERGY_LAST:]."""
    if monitor[MONITOR_ENERGY_HELD] >= 0.0 and (_energy_jumped(energy, monitor) or _energy_rose(energy, monitor)):
        monitor[MONITOR_ENERGY_NOW] = energy
        return ENERGY_JUMP
    if monitor[MONITOR_ENERGY_LOWEST_HELD] < 0.0 or energy < monitor[MONITOR_ENERGY_LOWEST]:
        monitor[MONITOR_ENERGY_LOWEST] = energy
        monitor[MONITOR_ENERGY_LOWEST_HELD] = held
    monitor[MONITOR_ENERGY_LAST] = energy
    monitor[MONITOR_ENERGY_HELD] = held
    return OK


@njit(cache=True, inline="always")
def _energy_jumped(energy, monitor):
    """Whether one step of a scene that conserves its energy changed it by more than the scene held
    at the step's start (:func:`energy_watch`)."""
    held_before = monitor[MONITOR_ENERGY_HELD]
    return (monitor[MONITOR_ENERGY_WATCH] == ENERGY_CONSERVED and held_before > 0.0
            and abs(energy - monitor[MONITOR_ENERGY_LAST]) > ENERGY_JUMP_LIMIT * held_before)


@njit(cache=True, inline="always")
def _energy_rose(energy, monitor):
    """Whether the energy of a scene that can only lose it rose above its lowest by more than the
    scene held there, the stability watch following no mode (:func:`energy_watch`)."""
    held_lowest = monitor[MONITOR_ENERGY_LOWEST_HELD]
    return (monitor[MONITOR_ENERGY_WATCH] == ENERGY_LOST and monitor[MONITOR_RK4_HITS] == 0.0
            and held_lowest > 0.0 and energy - monitor[MONITOR_ENERGY_LOWEST] > ENERGY_JUMP_LIMIT * held_lowest)


@njit(cache=True, inline="always")
def _energy_watch_at(y, P, monitor):
    """:func:`energy_watch` at the state y = [q, v, z] of the compiled loops."""
    nq = P[DIMS][N_COORD]
    nv = nq + P[DIMS][N_VELOCITY]
    energy, held = _scene_energy_of(y[:nq], y[nq:nv], y[nv:], P)
    return energy_watch(energy, held, monitor)


@njit(cache=True)
def _rk4_to_meeting(t, h, y, f, grid, k, out, inputs, alpha, P, AB, rhs, gen, acc, before):
    """RK4's step of length h from (t, y, f) brings a translational element's terminals together
    (its chord, :func:`terminals_meet`, or a stage where they meet, TERMINALS_MEET): taken again
    from its start in ever shorter steps, by bisection of what is left of it down to adjacent
    floats, each shorter step kept where it keeps them apart and halved where it does not, the
    grid's samples in the steps kept written from their cubic Hermite. A fixed step has no error
    control that accepted the crossing step, nor a dense output of its order: only steps that end
    before the meeting are kept. Returns (MEETING, or the status of a right-hand side that failed
    otherwise, the first k not written, the evaluations made, the time it stops at); y becomes the
    state there (f the derivative there). AB, rhs, gen, acc: the scratch of :func:`_rhs`."""
    ny = y.shape[0]
    stages = np.empty((6, ny))
    k2, k3, k4, y_mid, f_mid, ys = stages[0], stages[1], stages[2], stages[3], stages[4], stages[5]
    gaps, z = terminal_gaps(y, P)
    gaps_mid = np.zeros_like(gaps)
    t_hi = t + h
    evals = 0
    while True:
        part = 0.5 * (t_hi - t)
        mid = t + part
        if not t < mid < t_hi:
            break
        st = _rk4_step(t, part, y, f, k2, k3, k4, y_mid, f_mid, ys, inputs, alpha, P, AB, rhs, gen, acc, before)
        evals += 4
        gaps_mid[:, :] = gaps
        if st == TERMINALS_MEET or (st == OK and terminals_meet(gaps_mid, z, y_mid, P)):
            t_hi = mid
            continue
        if st != OK:
            return st, k, evals, t
        sampled = k
        while k < grid.shape[0] and grid[k] <= mid:
            _hermite(y, f, y_mid, f_mid, part, (grid[k] - t) / part, out, k)
            k += 1
        _wind_step_of(y_mid, y, part, P)
        _record_windings_of(out, sampled, k, ny, grid, mid, y_mid, P)
        y[:] = y_mid
        f[:] = f_mid
        gaps[:, :] = gaps_mid
        t = mid
    return MEETING, k, evals, t


@njit(cache=True, inline="always")
def rk4_step_length(t, t_end, step, kinks, ik):
    """(the length of the RK4 step from t, the index of the next kink after t): the fixed `step`,
    shortened to end at the next of the increasing `kinks` (from index ik on) or at t_end. The one
    rule of :func:`integrate_rk4`'s steps, which compiled._rk4_nodes runs uncompiled to find the
    same step ends."""
    while ik < kinks.shape[0] and kinks[ik] <= t:
        ik += 1
    end = kinks[ik] if ik < kinks.shape[0] and kinks[ik] < t_end else t_end
    return min(step, abs(end - t)), ik


@njit(cache=True)
def _rk4_run(y, t0, t_end, grid, out, step, max_steps, inputs, alpha, P, jump, kinks, work, monitor):
    """:func:`integrate_rk4` from y (overwritten) with the scratch `work` (:func:`work_arrays`, 4 rows
    of stages), an argument so that it can be taken without reference counting (_unowned)."""
    AB, rhs, gen, acc, K, y_new, f_new, ys, sig_acc = _unowned(work)[:SOLVER_WORK]
    f, k2, k3, k4 = K[0], K[1], K[2], K[3]
    work[CV_KNOWN][0] = 0.0         # C_v at y is not known yet (loop_watch)
    before = _before(jump)
    ny = y.shape[0]
    t = t0
    evals = 1
    st = _rhs(min(t, before), y, inputs, alpha, P, AB, rhs, gen, acc, f)
    if st != OK:
        return st, 1, 0, evals, t
    k = np.int64(1)         # a value, not the literal 1: the kernels k is passed to compile once, not again for it
    ngrid = grid.shape[0]
    steps = 0
    gaps, z = terminal_gaps(y, P)
    ik = np.searchsorted(kinks, t, side="right")             # the next kink: kinks[ik] > t
    if rarely(monitor[MONITOR_ENERGY_WATCH] != 0.0):
        monitor[MONITOR_ENERGY_HELD] = -1.0                  # the start's values
        _energy_watch_at(y, P, monitor)
    while t < t_end:
        h, ik = rk4_step_length(t, t_end, step, kinks, ik)
        st = _rk4_step(t, h, y, f, k2, k3, k4, y_new, f_new, ys, inputs, alpha, P, AB, rhs, gen, acc, before)
        t_new = t + h
        evals += 4
        if st == TERMINALS_MEET or (st == OK and terminals_meet(gaps, z, y_new, P)):
            steps += 1
            st, k, more, t = _rk4_to_meeting(t, h, y, f, grid, k, out, inputs, alpha, P, AB, rhs, gen, acc,
                                             before)
            return st, k, steps, evals + more, t
        if st != OK:
            return st, k, steps, evals, t
        steps += 1
        if rk4_watch(f, k2, k3, h, step, monitor) != OK:
            return UNSTABLE, k, steps, evals, t
        if euler_lock_within(y, y_new, P):
            return GIMBAL_LOCK, k, steps, evals, t
        _wind_step_of(y_new, y, h, P)
        if rarely(monitor[MONITOR_ENERGY_WATCH] != 0.0) and _energy_watch_at(y_new, P, monitor) != OK:
            return ENERGY_JUMP, k, steps, evals, t          # (after the winding: a 3D angle read wound)
        if rarely(P[DIMS][LOOPS] != 0):
            st, t_stop, k = _rk4_loop_watch(t, y, f, t_new, y_new, f_new, grid, k, out, inputs, alpha, P, work,
                                            monitor)
            if st != OK:
                y[:] = y_new                # the state it stopped at (_stop_at_change_point)
                return st, k, steps, evals, t_stop
        sampled = k
        while k < ngrid and grid[k] <= t_new + 1e-12 * max(1.0, t_new):
            _hermite(y, f, y_new, f_new, h, (grid[k] - t) / h, out, k)
            k += 1
        _record_windings_of(out, sampled, k, ny, grid, t_new, y_new, P)
        for i in range(ny):
            y[i] = y_new[i]
            f[i] = f_new[i]
        t = t_new
        if steps > max_steps:
            return MAX_STEPS, k, steps, evals, t
    return OK, k, steps, evals, t


@njit(cache=True)
def rk4_cosim_step(y, t0, t_end, jumps, kinks, ts, out, step, max_steps, inputs, alpha, P, monitor):
    """RK4 from (t0, y) to t_end, y left at t_end (a co-simulation step: CompiledStepper.step and
    the FMU's native step), segment by segment: a discontinuity of the increasing `jumps` in
    (t0, t_end) ends a segment there, where :func:`integrate_rk4` restarts; within
    eps = 1e-12·max(1 s, |t_end|) one at t_end ends the last segment and one at t0 starts none.
    The increasing `kinks` in (t0 + eps, t_end − eps] end steps, which run on from them
    (:func:`integrate_rk4`). `ts`, `out`: scratch of two samples. Returns (status, steps, the time
    reached, the start of the segment that failed); y is left at that start, or where the step
    stopped at a change point (CHANGE_POINT) or where terminals meet (MEETING), at the state there."""
    P = _unowned(P)                 # entered from Python (_unowned)
    eps = 1e-12 * max(1.0, abs(t_end))
    steps = 0
    inside = kinks[np.searchsorted(kinks, t0 + eps, side="right"):np.searchsorted(kinks, t_end - eps, side="right")]
    i = np.searchsorted(jumps, t0 + eps, side="right")
    while True:
        if i < jumps.shape[0] and jumps[i] <= t_end - eps:
            end = jumps[i]
            i += 1
        else:
            end = t_end
        j = np.searchsorted(jumps, end - eps, side="right")
        jump = end if j < jumps.shape[0] and jumps[j] <= end + eps else 0.0
        ts[0] = t0
        ts[1] = end
        st, k, s_steps, evals, t_reached, y_reached = integrate_rk4(y, t0, end, ts, out, step, max_steps, inputs,
                                                                    alpha, P, jump, inside, monitor)
        steps += s_steps
        if st != OK:
            if st == CHANGE_POINT or st == MEETING:
                y[:] = y_reached            # the state it stopped at, for the message
            return st, steps, t_reached, t0
        y[:] = out[1]
        if end == t_end:
            return OK, steps, t_end, t0
        t0 = end


@njit(cache=True)
def max_residual(states, P):
    """The largest constraint residual over a history (rows [q, v, z])."""
    P = _unowned(P)                 # entered from Python (_unowned)
    nq = P[DIMS][N_COORD]
    worst = 0.0
    for k in range(states.shape[0]):
        worst = max(worst, constraint_residual(states[k, :nq], P))
    return worst


# ------------------------------------------------------------------------------------------------
# The co-simulation step as a C function (the FMU's native doStep, see inerter/fmu/native.py)
# ------------------------------------------------------------------------------------------------
# The arrays of one running integration are passed as a table of int64: TABLE_HEAD slots (the
# table's length, method code, max_steps, need_acc), then three per array (address, shape[0],
# shape[1]) in the order of NATIVE_SLOTS, whose kinds say the dtype (f: float64, i: int64) and the
# number of dimensions. `clock` holds the floats: the communication time, the step bound, rtol,
# atol, alpha, whether a step is under way (CLOCK_BUSY: set when a step starts, cleared when it
# succeeds), the tolerance on communication points, the number of steps taken, and RK4's step.
# Method codes: 0 DOP853, 1 RK45 (a running integration, cosim_rk), NATIVE_RK4 (integrate_rk4 from
# the communication point, `y` the state there and `ts`, `out` two rows; the tableau slots unused).
TABLE_LENGTH, TABLE_METHOD, TABLE_MAX_STEPS, TABLE_NEED_ACC = range(4)
TABLE_HEAD = 4
#: The groups of arrays, in the order they are passed: the running integration's state (as
#: rk_advance takes it), the mechanism's arrays (Kernel.params), the tableau (A, B, C, E, E3, D, P),
#: the scratch (work_arrays).
RK_STATE = (("hdr", "f1"), ("y", "f1"), ("f", "f1"), ("y_prev", "f1"), ("dense", "f2"))
PARAMS = (("mass", "f1"), ("pbody", "i1"), ("ploc", "f2"), ("el_int", "i2"), ("el_real", "f2"),
          ("rot_int", "i2"), ("rot_real", "f2"), ("jt_int", "i2"), ("jt_real", "f2"), ("fa_int", "i2"),
          ("fa_real", "f2"), ("pd_int", "i2"), ("pd_real", "f2"), ("in_int", "i2"), ("gravity", "f1"),
          ("perm", "i1"), ("dims", "i1"), ("ground_t", "f1"), ("ground_a", "f2"), ("ground_terms", "f2"))
TABLEAU = (("A", "f2"), ("B", "f1"), ("C", "f1"), ("E", "f1"), ("E3", "f1"), ("D", "f2"), ("Pm", "f2"))
WORK = (("AB", "f2"), ("rhs", "f1"), ("gen", "f1"), ("acc", "f1"), ("K", "f2"), ("y_new", "f1"), ("f_new", "f1"),
        ("ys", "f1"), ("sig_acc", "f1"), ("cv_start", "f2"), ("cv_end", "f2"), ("cv_work", "f2"), ("cv_gram", "f2"),
        ("cv_known", "f1"))
assert [name for name, _ in WORK[CV_START:]] == ["cv_start", "cv_end", "cv_work", "cv_gram", "cv_known"]
assert [name for name, _ in WORK[:W_YS + 1]] == ["AB", "rhs", "gen", "acc", "K", "y_new", "f_new", "ys"]
#: cosim_scratch (gaps, z, fresh, keep), keep's coefficients (a (0, 1, ny) array) left out: native_step
#: makes them an empty view of `nodes`.
COSIM = (("gaps", "f2"), ("z", "f1"), ("fresh", "f1"), ("nodes", "f1"), ("kept", "i1"))
assert [name for name, _ in COSIM][SCRATCH_FRESH] == "fresh"
NATIVE_SLOTS = (RK_STATE + (("ts", "f1"), ("out", "f2"), ("inputs", "f1")) + PARAMS + TABLEAU
                + (("monitor", "f1"),) + WORK
                + (("raw", "f1"), ("order", "i1"), ("values", "f1"), ("clock", "f1"))
                + tuple(("b_" + name, kind) for name, kind in RK_STATE) + (("b_monitor", "f1"),)
                + (("jumps", "f1"), ("kinks", "f1"), ("spatial", "i1"))
                + COSIM)
CLOCK_TIME, CLOCK_BOUND, CLOCK_RTOL, CLOCK_ATOL, CLOCK_ALPHA, CLOCK_BUSY, CLOCK_TOLERANCE, CLOCK_TAKEN, \
    CLOCK_STEP = range(9)
CLOCK_SIZE = 9
NATIVE_RK4 = 2
#: What the C function returns when it took the step (anything else: it declined, see below).
NATIVE_TOOK_STEP = 1
_SLOT = {name: i for i, (name, _) in enumerate(NATIVE_SLOTS)}
# Where native_step finds each block of NATIVE_SLOTS (the RK state, its backup, the scene's P, the
# tableau, the scratch) and each single slot: numba takes these module constants as literals.
S_RK, S_BACKUP, S_PARAMS, S_TABLEAU, S_WORK, S_COSIM = (_SLOT["hdr"], _SLOT["b_hdr"], _SLOT["mass"], _SLOT["A"],
                                                        _SLOT["AB"], _SLOT["gaps"])
S_TS, S_OUT, S_INPUTS, S_MONITOR, S_RAW, S_ORDER, S_VALUES, S_CLOCK, S_JUMPS, S_KINKS, S_SPATIAL = (
    _SLOT["ts"], _SLOT["out"], _SLOT["inputs"], _SLOT["monitor"], _SLOT["raw"], _SLOT["order"], _SLOT["values"],
    _SLOT["clock"], _SLOT["jumps"], _SLOT["kinks"], _SLOT["spatial"])
S_BACKUP_MONITOR = _SLOT["b_monitor"]


@intrinsic
def _pointer(typingctx, address, dtype):
    """The int64 `address` as a pointer to `dtype` (np.float64, np.int64)."""
    if not isinstance(address, types.Integer) or not isinstance(dtype, types.NumberClass):
        return None
    sig = types.CPointer(dtype.instance_type)(address, dtype)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(signature.return_type))
    return sig, codegen


@intrinsic
def _unowned(typingctx, arrays):
    """The tuple of arrays `arrays` as views that numba does not reference-count (no owner: a null
    meminfo, as a view of a raw pointer has, :func:`_f1`).

    Numba increments and decrements, atomically, the reference count of every array of a tuple
    each time the tuple enters or leaves a kernel that is not inlined. A scene's P (19 arrays) and
    the integrators' scratch (:func:`work_arrays`) are passed down through a few nested kernels
    per evaluation of Eq. (33): counted, they took half of a whole run's time on the paper scenes
    (two-bar, 20 s: 78 ms counted, 39 ms not; the same steps, bit for bit the same results).
    So a kernel entered from Python takes P through this at its start, and the loops that call
    kernels take their scratch through it (:func:`rk_advance`, :func:`_rk4_run`,
    :func:`_signals_at`); the right-hand side (:func:`_rhs`) and the assemblies take their own
    arrays through it too, as a counted array (the held inputs, any array from Python) was
    counted again at each inlined function it entered, at every element
    (docs/benchmarks/eval_cost_3d.md). Only for a kernel's own arguments: its caller holds them
    for the whole call, and no kernel returns or keeps them, so the views never outlive the arrays. An array a
    kernel allocates itself may be released after its last use, before the views are: such
    scratch is passed to an inner kernel as an argument instead (:func:`integrate_rk4`)."""
    if not isinstance(arrays, types.BaseTuple) or not all(isinstance(a, types.Array) for a in arrays):
        return None

    def codegen(context, builder, signature, args):
        tup = args[0]
        for i, ty in enumerate(signature.args[0]):
            view = context.make_array(ty)(context, builder, builder.extract_value(tup, i))
            view.meminfo = cgutils.get_null_value(view.meminfo.type)
            view.parent = cgutils.get_null_value(view.parent.type)
            tup = builder.insert_value(tup, view._getvalue(), i)
        return tup
    return arrays(arrays), codegen


@intrinsic
def _stack(typingctx, size):
    """A pointer to `size` float64 (a literal) in the stack frame of the kernel this is compiled into,
    for ``carray``: numba's ``alloca`` at that function's entry, so allocated once per call of the
    kernel however often the line runs, and released when it returns. Scratch of a fixed small size
    (an element's g over its two bodies, the ground's acceleration) without a heap allocation and,
    having no owner, without reference counting: as ``np.empty(6)``, it cost an allocation per
    evaluation of Eq. (33) and an atomic count each time it entered an inlined function, i.e. at
    every element (benchmarks/eval_cost.py; docs/benchmarks/eval_cost_3d.md). Only for scratch that
    the kernel neither returns nor keeps."""
    if not isinstance(size, types.IntegerLiteral):
        return None
    sig = types.CPointer(types.float64)(size)

    def codegen(context, builder, signature, args):
        return cgutils.alloca_once(builder, context.get_value_type(types.float64),
                                   size=signature.args[0].literal_value)
    return sig, codegen


@intrinsic
def _stack_ints(typingctx, size):
    """A pointer to `size` int64 (any integer, at most :data:`STACK_ROWS`) on the stack of the kernel
    this is compiled into, allocated where this line runs and released when that kernel returns:
    :func:`_stack` for a size known only at run time, so only in a kernel that is called, not
    inlined, and never in a loop (each run of the line takes more stack)."""
    if not isinstance(size, types.Integer):
        return None
    sig = types.CPointer(types.int64)(size)

    def codegen(context, builder, signature, args):
        return builder.alloca(context.get_value_type(types.int64), size=args[0])
    return sig, codegen


@njit(cache=True, inline="always")
def _f1(tab, s):
    j = TABLE_HEAD + 3 * s
    return carray(_pointer(tab[j], np.float64), (tab[j + 1],))


@njit(cache=True, inline="always")
def _f2(tab, s):
    j = TABLE_HEAD + 3 * s
    return carray(_pointer(tab[j], np.float64), (tab[j + 1], tab[j + 2]))


@njit(cache=True, inline="always")
def _i1(tab, s):
    j = TABLE_HEAD + 3 * s
    return carray(_pointer(tab[j], np.int64), (tab[j + 1],))


@njit(cache=True, inline="always")
def _i2(tab, s):
    j = TABLE_HEAD + 3 * s
    return carray(_pointer(tab[j], np.int64), (tab[j + 1], tab[j + 2]))


@njit(cache=True, inline="always")
def _native_scratch(tab, ny):
    """:func:`cosim_scratch` from the table (its COSIM block, from slot S_COSIM on)."""
    s = S_COSIM
    nodes = _f1(tab, s + 3)
    coeffs = carray(_pointer(tab[TABLE_HEAD + 3 * (s + 3)], np.float64), (0, 1, ny))   # empty: nothing kept
    return _f2(tab, s), _f1(tab, s + 1), _f1(tab, s + 2), (nodes, coeffs, _i1(tab, s + 4))


@njit(cache=True, inline="always")
def _native_params(tab):
    """P of a 2D scene from the table (its PARAMS block, from slot S_PARAMS on)."""
    s = S_PARAMS
    return (_f1(tab, s + MASS), _i1(tab, s + PBODY), _f2(tab, s + PLOC), _i2(tab, s + EL_INT),
            _f2(tab, s + EL_REAL), _i2(tab, s + ROT_INT), _f2(tab, s + ROT_REAL), _i2(tab, s + JT_INT),
            _f2(tab, s + JT_REAL), _i2(tab, s + FA_INT), _f2(tab, s + FA_REAL), _i2(tab, s + PD_INT),
            _f2(tab, s + PD_REAL), _i2(tab, s + IN_INT), _f1(tab, s + GRAVITY), _i1(tab, s + PERM),
            _i1(tab, s + DIMS), _f1(tab, s + GROUND_T), _f2(tab, s + GROUND_A), _f2(tab, s + GROUND_TERMS))


@njit(cache=True)
def native_step(tab, t, h):
    """:func:`native_step_on` a 2D scene's table."""
    return native_step_on(tab, t, h, _native_params(tab))


@njit(cache=True)
def native_step3(tab, t, h):
    """:func:`native_step_on` a 3D scene's table (P with its ``spatial`` slot, table slot S_SPATIAL)."""
    return native_step_on(tab, t, h, _native_params(tab) + (_i1(tab, S_SPATIAL),))


@njit(inline="always")
def native_step_on(tab, t, h, P):
    """One co-simulation step (t, t + h] of the running integration whose arrays `tab` lists: what
    ``CompiledStepper.step`` does while the inputs hold (:func:`cosim_step` with the step bound,
    then every output into `values`; RK4: :func:`rk4_cosim_step` from the communication point,
    then the outputs). Returns NATIVE_TOOK_STEP,
    or 0 where it declines and leaves the step to the Python path: a communication point that is
    not the current one, a step size that is not finite and > 0, a failed step or outputs the
    kernels cannot evaluate. A declined step leaves CLOCK_BUSY set and the integration's state and
    its monitor as they were in the backup arrays (b_*), which the Python path restores before it takes the step
    itself, so that it gives the messages and the results the Python path always gives; it also
    marks the terminals' gaps (:func:`cosim_scratch`) as not current."""
    clock = _f1(tab, S_CLOCK)
    now = clock[CLOCK_TIME]
    if not (math.isfinite(t) and math.isfinite(h) and h > 0.0):
        return 0
    if abs(t - now) > clock[CLOCK_TOLERANCE] * max(1.0, abs(t), abs(now)):
        return 0
    t_end = t + h
    if not t_end > now:
        return 0
    hdr, y, f = _f1(tab, S_RK), _f1(tab, S_RK + 1), _f1(tab, S_RK + 2)
    y_prev, dense = _f1(tab, S_RK + 3), _f2(tab, S_RK + 4)
    b_hdr, b_y, b_f = _f1(tab, S_BACKUP), _f1(tab, S_BACKUP + 1), _f1(tab, S_BACKUP + 2)
    b_y_prev, b_dense = _f1(tab, S_BACKUP + 3), _f2(tab, S_BACKUP + 4)
    b_hdr[:] = hdr
    b_y[:] = y
    b_f[:] = f
    b_y_prev[:] = y_prev
    b_dense[:, :] = dense
    monitor = _f1(tab, S_MONITOR)
    _f1(tab, S_BACKUP_MONITOR)[:] = monitor     # its counters, RK4's watch among them, go back too
    clock[CLOCK_BUSY] = 1.0
    bound = clock[CLOCK_BOUND]
    ts, out, inputs, alpha = _f1(tab, S_TS), _f2(tab, S_OUT), _f1(tab, S_INPUTS), clock[CLOCK_ALPHA]
    w = S_WORK                                  # as WORK lists them
    work = (_f2(tab, w), _f1(tab, w + 1), _f1(tab, w + 2), _f1(tab, w + 3), _f2(tab, w + 4), _f1(tab, w + 5),
            _f1(tab, w + 6), _f1(tab, w + 7), _f1(tab, w + 8), _f2(tab, w + CV_START), _f2(tab, w + CV_END),
            _f2(tab, w + CV_WORK), _f2(tab, w + CV_GRAM), _f1(tab, w + CV_KNOWN))
    raw, order, values = _f1(tab, S_RAW), _i1(tab, S_ORDER), _f1(tab, S_VALUES)
    if tab[TABLE_METHOD] == NATIVE_RK4:
        st, steps, t_reached, t_fail = rk4_cosim_step(y, now, t_end, _f1(tab, S_JUMPS), _f1(tab, S_KINKS), ts, out,
                                                      clock[CLOCK_STEP], tab[TABLE_MAX_STEPS], inputs, alpha, P,
                                                      monitor)
        if st != OK:
            return 0
        for n in range(y.shape[0]):
            if not math.isfinite(y[n]):
                return 0
        hdr[RK_TOTAL] += steps
        if _signals_at(t_end, y, inputs, alpha, tab[TABLE_NEED_ACC] != 0, P, work, raw) != OK:
            return 0
        for n in range(order.shape[0]):
            values[n] = raw[order[n]]
    else:
        if t_end > bound:                       # the importer went past its stop time
            bound = np.inf
        scratch = _native_scratch(tab, y.shape[0])
        tableau = (_f2(tab, S_TABLEAU), _f1(tab, S_TABLEAU + 1), _f1(tab, S_TABLEAU + 2), _f1(tab, S_TABLEAU + 3),
                   _f1(tab, S_TABLEAU + 4), _f2(tab, S_TABLEAU + 5), _f2(tab, S_TABLEAU + 6))
        st, sst = _cosim_step_inlined(tab[TABLE_METHOD], hdr, y, f, y_prev, dense, t_end, ts, out, bound,
                                      clock[CLOCK_RTOL], clock[CLOCK_ATOL], tab[TABLE_MAX_STEPS], inputs, alpha, P,
                                      tableau, monitor, work, tab[TABLE_NEED_ACC] != 0, raw, order,
                                      values, _f1(tab, S_JUMPS), _f1(tab, S_KINKS), scratch)
        if st != OK or sst != OK:
            scratch[SCRATCH_FRESH][0] = 0.0     # the Python path restores y from the backup
            return 0
    clock[CLOCK_TIME] = t_end
    clock[CLOCK_BOUND] = bound
    clock[CLOCK_BUSY] = 0.0
    clock[CLOCK_TAKEN] += 1.0
    return NATIVE_TOOK_STEP


def _native_entry(table, t, h):
    return native_step(carray(table, (table[0],)), t, h)


def _native_entry3(table, t, h):
    return native_step3(carray(table, (table[0],)), t, h)


_NATIVE_CFUNC = {}


def native_step_cfunc(spatial: bool = False):
    """:func:`native_step` (``spatial``: :func:`native_step3`) as a C function
    ``int32 (const int64 *table, double t, double h)`` (compiled on first use, cached on disk). A
    Python exception inside it (none is expected) is printed and the function returns 0: it
    declines."""
    spatial = bool(spatial)
    if spatial not in _NATIVE_CFUNC:
        sig = types.int32(types.CPointer(types.int64), types.float64, types.float64)
        _NATIVE_CFUNC[spatial] = cfunc(sig, cache=True)(_native_entry3 if spatial else _native_entry)
    return _NATIVE_CFUNC[spatial]
