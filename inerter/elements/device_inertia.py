"""An inerter device's masses and inertias: the housing, the rod and the flywheel as rigid bodies
carried by the two terminals, and the flywheel's transverse inertia and gyroscopic moments.

These are not laws of the terminal distance: the device's kinetic energy T(q, q̇) depends on the
motion of its line, so Lagrange's equations give a mass-matrix block over the two terminals' bodies
beyond the ideal inerter's b g gᵀ, and right-side terms (:func:`block`). They are written here once,
in vector form, and serve the 2D and the 3D kernels alike (2D vectors have z = 0).

**Geometry.** With r = r_b − r_a, L = |r|, the axis u = r/L, its rate u̇ = (ṙ − u L̇)/L. The
velocities are linear in the velocity coordinates v: ṙ_a = H_a v, ṙ_b = H_b v, ṙ = G_r v with
G_r = H_b − H_a, u̇ = G_u v with G_u = (I − u uᵀ) G_r / L, L̇ = g_Lᵀ v with g_L = G_rᵀ u. At v̇ = 0
(the part of each acceleration that is not in the mass matrix), with r̈ = a_n (Eqs. 19, 25):

    L̈₀ = a_n·u + L |u̇|²,      ü₀ = ((I − u uᵀ) a_n − 2 u̇ L̇)/L − u |u̇|².

**The parts** (the device literature's ball-screw inerter: a housing carried by terminal a, a rod
carried by terminal b that slides in it, a flywheel in the housing spun by the screw; Smith 2002,
IEEE TAC 47(10) Sec. III; Wang & Su 2008, Veh. Syst. Dyn. 46(7)): each part is axisymmetric about
u, of mass m and moments of inertia I_t (transverse) and J (axial) about its centre, the centre on
the line: housing c_h = r_a + h_h u, flywheel c_f = r_a + h_f u, rod c_r = r_b − h_r u. Every part
turns with the line, ω = u × u̇ + s u (the part of ω normal to u is u × u̇, since u̇ = ω × u), with
its own spin s about u: the housing and the rod (keyed to it) s_h, the flywheel s_f = s_h + n L̇
(n = 2π/p, the screw's turn per unit of stroke). Then

    T = Σ ½ m |ċ|² + ½ I_t |u̇|² + ½ J_hr s_h² + ½ J (s_h + n L̇)²,

with I_t the sum of the parts' transverse inertias and J_hr the housing's and rod's axial ones
(|u × u̇| = |u̇|). ½ J n² L̇² = ½ b L̇² is the ideal inerter's (:mod:`inerter.elements.inerter`,
b = J n²): this block holds the rest.

**The mount** (what fixes the housing's spin, 3D only). "The housing does not spin", ω_h·u = 0, is
a non-holonomic condition: substituted into T before Lagrange's equations are applied, it gives
only the axial inertance force and loses the gyroscopic moment J s_f u̇ that the terminals must
carry. Here the housing is carried at terminal a by a universal (Hooke) joint whose first axis a₁
is fixed in body a (``device.mount.axis``, in a's frame) and whose second axis a₂ is fixed in the
housing, normal to its axis u; the rod is keyed to the housing (it slides, it does not turn in it)
and carried at terminal b by a ball joint. a₂ ⊥ a₁ (the cross) and a₂ ⊥ u make the housing's frame
a function of the pose, (e₁, e₂, e₃) = (ŵ, u × ŵ, u) with w = a₁ × u, ŵ = w/|w|: the condition is
holonomic, and the housing's spin is

    s_h = ω_h·e₃ = ė₁·e₂ = e₂·ẇ / |w|,       ẇ = ȧ₁ × u + a₁ × u̇,  ȧ₁ = ω_a × a₁

(ė₁ = ω_h × e₁, and ė₁ = (I − ŵŵᵀ)ẇ/|w| with e₂ ⊥ ŵ). It is linear in v, s_h = σᵀ v with
σ = G_wᵀ e₂/|w|, G_w = −[u]× G_a₁ + [a₁]× G_u; at v̇ = 0

    ṡ_h₀ = (ė₂·ẇ + e₂·ẅ₀)/|w| − (e₂·ẇ)(ŵ·ẇ)/|w|²,   ė₂ = u̇ × ŵ + u × ė₁,
    ẅ₀ = ä₁₀ × u + 2 ȧ₁ × u̇ + a₁ × ü₀.

(The mount is singular where u ∥ a₁, |w| = 0: declare a₁ away from the device's axis.) Without a
declared mount the housing's spin is not modelled (s_h = 0 is not substituted into anything: the
flywheel's spin is n L̇, as for the ideal inerter, and its gyroscopic moment is left out). In 2D
the axis u lies in the plane and the motion turns about the normal, so s_h = 0 holonomically, and
the flywheel's gyroscopic moment J s_f u × u̇ is along the normal's perpendicular in the plane:
the planar constraint carries it (its generalised force, J s_f g_i·(u × u̇) below, is zero because
g_i lies in the plane and u × u̇ along the normal); I_t |u̇|² = I_t φ̇² adds rotary inertia to the
line.

**Equations** (Kane's form of Lagrange's equations, valid with the body-frame angular velocities
of 3D bodies as velocity coordinates; Kane & Levinson 1985, Dynamics: Theory and Applications,
Ch. 6). The generalised inertia force of a part is −(∂ċ/∂v)ᵀ m c̈ − (∂ω/∂v)ᵀ Ḣ with
Ḣ = I_t u × ü + J ṡ u + J s u̇ (axisymmetric, H = I_t u × u̇ + J s u), ∂ω/∂v_i = u × g_i + σ_i u
(g_i: column i of G_u, u·g_i = 0): (u × g_i)·(u × ü) = g_i·ü, (u × g_i)·u̇ = −g_i·(u × u̇). So

    M += Σ m G_cᵀ G_c + I_t G_uᵀ G_u + J_hr σσᵀ + J (σσᵀ + n(σ g_Lᵀ + g_L σᵀ))
    Q −= Σ m G_cᵀ c̈₀ + I_t G_uᵀ ü₀ + J_hr ṡ_h₀ σ + J (ṡ_h₀ σ + n ṡ_h₀ g_L + n L̈₀ σ)
    Q += (J_hr s_h + J s_f) G_uᵀ (u × u̇)                       (the gyroscopic moments)

with G_c = H_a + h G_u (housing, flywheel), H_b − h G_u (rod), c̈₀ = acc_a + h ü₀, acc_b − h ü₀,
and the terms of J n² (b g_L g_Lᵀ and b L̈₀ g_L) left to the ideal inerter. The parts' weight, in
a scene with gravity g, adds Q += Σ m G_cᵀ g (potential −Σ m g·c). Under a ground motion the
coordinates are relative to the ground, which accelerates at a_g: every part feels the inertial
force −m a_g as the scene's bodies do (Q −= Σ m G_cᵀ a_g, the bias accelerations c̈₀ taken absolute),
which is the weight's term with g − a_g; the potential stays the weight's. The oracle
(:mod:`inerter.oracle.derivation`) derives the same from the parts' rigid-body kinetic energy with
their rotations built from the mount's definition, on Jets.
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.inlined import inlined, not_inlined
from inerter.elements.layout import (DEVICE_GRAVITY, FLYWHEEL_AXIAL, FLYWHEEL_CENTRE, FLYWHEEL_MASS,
                                     FLYWHEEL_RATIO, HOUSING_AXIAL, HOUSING_CENTRE, HOUSING_MASS, MOUNT, ROD_CENTRE, ROD_MASS,
                                     TRANSVERSE)


def entry(fn):
    """Compile a function the kernels call without inlining it (cached on disk): an ideal inerter's
    kernels hold only the test of row[INERTIA] and a call never made."""
    return not_inlined(fn)


@inlined
def _cross(a, b):
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]))


@inlined
def _gram(M, Q, G, c0, weight):
    """M += weight Gᵀ G and Q −= weight Gᵀ c₀ for a vector velocity G v with bias acceleration c₀."""
    n = G.shape[1]
    for i in range(n):
        Q[i] -= weight * (G[0, i] * c0[0] + G[1, i] * c0[1] + G[2, i] * c0[2])
        for j in range(n):
            M[i, j] += weight * (G[0, i] * G[0, j] + G[1, i] * G[1, j] + G[2, i] * G[2, j])


@inlined
def _part(M, Q, m, h, Hend, acc, Gu, udd0, r_end, rdot_end, u, ud, g, frame_acc):
    """A part of mass m whose centre is c = r_end + h u: its terms (Gram of G_c = H_end + h G_u with
    c̈₀ = acc_end + h ü₀ + a_g, absolute, and its weight m G_cᵀ g) and its energy, kinetic ½ m |ċ|²
    and potential −m g·c (relative to the ground: a_g does work, it stores none)."""
    if m == 0.0:
        return 0.0, 0.0
    G = Hend + h * Gu
    _gram(M, Q, G, acc + h * udd0 + frame_acc - g, m)
    cd = rdot_end + h * ud
    c = r_end + h * u
    return 0.5 * m * (cd[0] * cd[0] + cd[1] * cd[1] + cd[2] * cd[2]), -m * (g[0] * c[0] + g[1] * c[1] + g[2] * c[2])


@inlined
def _axis(r, rd, Ha, Hb, acc_a, acc_b):
    """(L, u, L̇, u̇, G_r, G_u, g_L, L̈₀, ü₀) of the module docstring's geometry."""
    n = Ha.shape[1]
    L = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    u = r / L
    Ldot = u[0] * rd[0] + u[1] * rd[1] + u[2] * rd[2]
    ud = (rd - u * Ldot) / L
    Gr = Hb - Ha
    gL = np.empty(n)
    Gu = np.empty((3, n))
    for i in range(n):
        gL[i] = u[0] * Gr[0, i] + u[1] * Gr[1, i] + u[2] * Gr[2, i]
        for k in range(3):
            Gu[k, i] = (Gr[k, i] - u[k] * gL[i]) / L
    an = acc_b - acc_a
    an_u = an[0] * u[0] + an[1] * u[1] + an[2] * u[2]
    ud2 = ud[0] * ud[0] + ud[1] * ud[1] + ud[2] * ud[2]
    Ldd0 = an_u + L * ud2
    udd0 = (an - u * an_u - 2.0 * Ldot * ud) / L - u * ud2
    return L, u, Ldot, ud, Gr, Gu, gL, Ldd0, udd0


@inlined
def _housing_spin(u, ud, Gu, udd0, a1, a1d, a1dd0, Ga1):
    """The housing's spin s_h under the Hooke mount, its gradient σ over v and ṡ_h₀ (module
    docstring, "The mount")."""
    n = Gu.shape[1]
    w = _cross(a1, u)
    wn = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    e1 = w / wn
    e2 = _cross(u, e1)
    wd = _cross(a1d, u) + _cross(a1, ud)
    s = (e2[0] * wd[0] + e2[1] * wd[1] + e2[2] * wd[2]) / wn
    sigma = np.empty(n)
    for i in range(n):
        gw = _cross(Ga1[:, i].copy(), u) + _cross(a1, Gu[:, i].copy())
        sigma[i] = (e2[0] * gw[0] + e2[1] * gw[1] + e2[2] * gw[2]) / wn
    e1d = (wd - e1 * (e1[0] * wd[0] + e1[1] * wd[1] + e1[2] * wd[2])) / wn
    e2d = _cross(ud, e1) + _cross(u, e1d)
    wdd0 = _cross(a1dd0, u) + 2.0 * _cross(a1d, ud) + _cross(a1, udd0)
    e1wd = e1[0] * wd[0] + e1[1] * wd[1] + e1[2] * wd[2]
    sd0 = ((e2d[0] * wd[0] + e2d[1] * wd[1] + e2d[2] * wd[2]) + (e2[0] * wdd0[0] + e2[1] * wdd0[1]
           + e2[2] * wdd0[2])) / wn - s * e1wd / wn
    return s, sigma, sd0


@entry
def block(row, Ha, Hb, ra, rb, ra_dot, rb_dot, acc_a, acc_b, frame_acc, a1, a1d, a1dd0, Ga1, M, Q):
    """The device's terms beyond b g gᵀ (module docstring, "Equations", and its masses' weight):
    M (n × n) and Q (n) over the velocity coordinates v of terminal a's body then terminal b's
    (n = 6 in 2D, 12 in 3D), both overwritten; returns (T − ½ b L̇², V), its kinetic energy beyond
    the ideal inerter's and its masses' gravitational potential (J).

    Ha, Hb (3 × n): ṙ_a = H_a v, ṙ_b = H_b v (zero columns for the other body); ra, rb, ra_dot,
    rb_dot the terminals' positions and velocities, acc_a, acc_b their accelerations at v̇ = 0
    (relative to the ground); frame_acc (3) the ground's acceleration a_g (zero without a ground motion);
    a1, a1d, a1dd0, Ga1 the mount's axis a₁ (global), ȧ₁ = G_a₁ v and ä₁ at v̇ = 0 (read only
    where row[MOUNT] is set)."""
    M[:, :] = 0.0
    Q[:] = 0.0
    g = row[DEVICE_GRAVITY:DEVICE_GRAVITY + 3]
    L, u, Ldot, ud, Gr, Gu, gL, Ldd0, udd0 = _axis(rb - ra, rb_dot - ra_dot, Ha, Hb, acc_a, acc_b)
    T, V = _part(M, Q, row[HOUSING_MASS], row[HOUSING_CENTRE], Ha, acc_a, Gu, udd0, ra, ra_dot, u, ud, g, frame_acc)
    dT, dV = _part(M, Q, row[FLYWHEEL_MASS], row[FLYWHEEL_CENTRE], Ha, acc_a, Gu, udd0, ra, ra_dot, u, ud, g, frame_acc)
    T, V = T + dT, V + dV
    dT, dV = _part(M, Q, row[ROD_MASS], -row[ROD_CENTRE], Hb, acc_b, Gu, udd0, rb, rb_dot, u, ud, g, frame_acc)
    T, V = T + dT, V + dV
    It = row[TRANSVERSE]
    if It != 0.0:
        _gram(M, Q, Gu, udd0, It)
        T += 0.5 * It * (ud[0] * ud[0] + ud[1] * ud[1] + ud[2] * ud[2])
    if row[MOUNT] == 0.0:
        return T, V
    Jhr = row[HOUSING_AXIAL]
    J = row[FLYWHEEL_AXIAL]
    ratio = row[FLYWHEEL_RATIO]
    s, sigma, sd0 = _housing_spin(u, ud, Gu, udd0, a1, a1d, a1dd0, Ga1)
    sf = s + ratio * Ldot
    perp = _cross(u, ud)
    n = Gu.shape[1]
    for i in range(n):
        Q[i] -= (Jhr + J) * sd0 * sigma[i] + J * ratio * (sd0 * gL[i] + Ldd0 * sigma[i])
        Q[i] += (Jhr * s + J * sf) * (Gu[0, i] * perp[0] + Gu[1, i] * perp[1] + Gu[2, i] * perp[2])
        for j in range(n):
            M[i, j] += (Jhr + J) * sigma[i] * sigma[j] + J * ratio * (sigma[i] * gL[j] + gL[i] * sigma[j])
    return T + 0.5 * Jhr * s * s + J * (0.5 * s * s + ratio * s * Ldot), V
