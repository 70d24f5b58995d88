"""A joint's constraint rows, written once: for each row type its residual C, its coefficients in
C_v (the row of the constraint Jacobian over the velocity coordinates) and the right side γ of
C_v v̇ = γ (γ = −C̈ at v̇ = 0, Eq. 26's Q_d; the engine adds Baumgarte's −2αĊ − α²C).

These are scalar functions compiled by :func:`~inerter.elements.base.law`: the engine's kernels
(``kernels.assemble``, ``assemble3``, ``constraint_residual2``/``3``) inline them and place the
coefficients they return into the augmented matrix of Eq. 33, and the readable joints
(:mod:`inerter.model.joints`) run the same definitions uncompiled and place them into their matrices.

The rows are the standard conditions on points and body-fixed vectors (Nikravesh 1988;
Shabana 2009, the dot-1 and dot-2 constraints, as cited by the paper). A body-fixed vector is
s = A s̄ (A: the body's rotation, a row-major 9-tuple; ω̄: its angular velocity in the body frame,
Eq. 22), so ṡ = A(ω̄ × s̄) and a small body-frame rotation δφ̄ moves it by A(δφ̄ × s̄): a row
t·s has the coefficient s̄ × Aᵀt over ω̄. r = r_b − r_a, ṙ and a_n (r̈ = H v̇ + a_n, Eqs. 18-19, 25)
are the joint's points' relative kinematics, which the caller computes; a "translational
coefficient" t of a row is t·r̈'s, placed by the caller on each point's H (tᵀH, Eq. 22).

- Coincident points, C = r = 0 (a revolute joint in 2D, the spherical joint in 3D): C_v = H and
  γ = −a_n, the point kinematics themselves, with nothing written here.
- dot-1, s_a·s_b = 0 (:func:`dot1_row`); dot-2, s_a·r = 0 (:func:`dot2_row`).
- The 3D screw's row, a turn about s_a coupled to the advance along it (:func:`screw_row`).
- The 2D slider (:func:`slider_rows_2d`) and the 2D screw's turn (:func:`screw_turn_2d`): the plane's
  forms of a no-turn row and of the dot-2 row, in the angle θ_a (A_a the rotation by θ_a, ω̄_a = θ̇_a).
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.rotations import cross3 as _cross, matrix9_apply, matrix9_apply_transposed
from inerter.elements.base import law


@law
def turned_coefficient(A, sx, sy, sz, tx, ty, tz):
    """s̄ × (Aᵀ t): the coefficient over a body's ω̄ of t·(A s̄) (or of t·(A ū) for a point ū, the
    rotational columns of tᵀH, Eq. 22): d/dt (A s̄) = A(ω̄ × s̄)."""
    ux, uy, uz = matrix9_apply_transposed(A, tx, ty, tz)
    return _cross(sx, sy, sz, ux, uy, uz)


@law
def body_vector(A, wx, wy, wz, sx, sy, sz):
    """A body-fixed vector s = A s̄, its rate ṡ = A(ω̄ × s̄) and its acceleration at ω̄̇ = 0,
    s̈ = A(ω̄ × (ω̄ × s̄)) (Eq. 25's terms)."""
    s0, s1, s2 = matrix9_apply(A, sx, sy, sz)
    cx, cy, cz = _cross(wx, wy, wz, sx, sy, sz)
    d0, d1, d2 = matrix9_apply(A, cx, cy, cz)
    ex, ey, ez = _cross(wx, wy, wz, cx, cy, cz)
    a0, a1, a2 = matrix9_apply(A, ex, ey, ez)
    return s0, s1, s2, d0, d1, d2, a0, a1, a2


@law
def dot1_row(Aa, wax, way, waz, sax, say, saz, Ab, wbx, wby, wbz, sbx, sby, sbz):
    """The dot-1 row s_a·s_b = 0 (s_a = A_a s̄_a, s_b = A_b s̄_b; Shabana 2009,
    Nikravesh 1988): (C, its coefficients over ω̄_a, s̄_a × A_aᵀ s_b, and over ω̄_b, s̄_b × A_bᵀ s_a, γ)
    with γ = −(s̈_a·s_b + 2 ṡ_a·ṡ_b + s_a·s̈_b)."""
    a0, a1, a2, ad0, ad1, ad2, aa0, aa1, aa2 = body_vector(Aa, wax, way, waz, sax, say, saz)
    b0, b1, b2, bd0, bd1, bd2, bb0, bb1, bb2 = body_vector(Ab, wbx, wby, wbz, sbx, sby, sbz)
    cax, cay, caz = turned_coefficient(Aa, sax, say, saz, b0, b1, b2)
    cbx, cby, cbz = turned_coefficient(Ab, sbx, sby, sbz, a0, a1, a2)
    c = a0 * b0 + a1 * b1 + a2 * b2
    gamma = -((aa0 * b0 + aa1 * b1 + aa2 * b2) + 2.0 * (ad0 * bd0 + ad1 * bd1 + ad2 * bd2)
              + (a0 * bb0 + a1 * bb1 + a2 * bb2))
    return c, cax, cay, caz, cbx, cby, cbz, gamma


@law
def dot2_row(Aa, wax, way, waz, sax, say, saz, rx, ry, rz, rdx, rdy, rdz, anx, any_, anz):
    """The dot-2 row s_a·r = 0, r = r_b − r_a (Shabana 2009, Nikravesh 1988):
    (C, the translational coefficient s_a (on H: −s_aᵀH_a + s_aᵀH_b), the coefficient over ω̄_a
    of s_a's turn, s̄_a × A_aᵀ r, γ) with γ = −(s̈_a·r + 2 ṡ_a·ṙ + s_a·a_n)."""
    a0, a1, a2, ad0, ad1, ad2, aa0, aa1, aa2 = body_vector(Aa, wax, way, waz, sax, say, saz)
    cx, cy, cz = turned_coefficient(Aa, sax, say, saz, rx, ry, rz)
    c = a0 * rx + a1 * ry + a2 * rz
    gamma = -((aa0 * rx + aa1 * ry + aa2 * rz) + 2.0 * (ad0 * rdx + ad1 * rdy + ad2 * rdz)
              + (a0 * anx + a1 * any_ + a2 * anz))
    return c, a0, a1, a2, cx, cy, cz, gamma


@law
def screw_residual(Aa, Ab, nx, ny, nz, rel0, ratio, advance0, rx, ry, rz):
    """A 3D screw's C = φ − ρ(s·r − x₀) mod 2π and its axis s = A_a s̄ (s̄ = (nx, ny, nz)): φ is
    the relative turn about s̄ since the relative orientation rel0 = A_aᵀA_b (row-major 9 numbers)
    of the initial pose; with D = (A_aᵀA_b) rel0ᵀ, φ = atan2(½ s̄·vee(D − Dᵀ), ½(tr D − s̄ᵀD s̄)),
    exact while the relative rotation is about the axis (Shabana 2009, the rotation's axis-angle)."""
    D = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            x = 0.0
            for k in range(3):
                x += (Aa[i] * Ab[k] + Aa[3 + i] * Ab[3 + k] + Aa[6 + i] * Ab[6 + k]) * rel0[3 * j + k]
            D[i, j] = x
    sn = 0.5 * (nx * (D[2, 1] - D[1, 2]) + ny * (D[0, 2] - D[2, 0]) + nz * (D[1, 0] - D[0, 1]))
    nDn = (nx * (D[0, 0] * nx + D[0, 1] * ny + D[0, 2] * nz) + ny * (D[1, 0] * nx + D[1, 1] * ny + D[1, 2] * nz)
           + nz * (D[2, 0] * nx + D[2, 1] * ny + D[2, 2] * nz))
    phi = math.atan2(sn, 0.5 * (D[0, 0] + D[1, 1] + D[2, 2] - nDn))
    sx, sy, sz = matrix9_apply(Aa, nx, ny, nz)
    x = phi - ratio * (sx * rx + sy * ry + sz * rz - advance0)
    return x - 2.0 * math.pi * round(x / (2.0 * math.pi)), sx, sy, sz


@law
def screw_row(Aa, wax, way, waz, Ab, wbx, wby, wbz, nx, ny, nz, rel0, ratio, advance0,
              rx, ry, rz, rdx, rdy, rdz, anx, any_, anz):
    """The 3D screw (helical) row: b turns relative to a about s = A_a s̄ by ρ per unit of its
    advance along it, C = φ − ρ(s·r − x₀) (:func:`screw_residual`). Taken where the relative
    rotation is about the axis, Ċ = s·(ω_b − ω_a) − ρ(s·ṙ + ṡ·r): over body-frame ω̄, s·ω_a = s̄·ω̄_a
    and s·ω_b = (A_bᵀ s)·ω̄_b, and the advance's part is −ρ × the dot-2 row of s̄.
    Returns (C, the translational coefficient −ρ s, the advance's coefficient over ω̄_a,
    s̄ × A_aᵀ(−ρ r), the turn's over ω̄_a, −s̄, and over ω̄_b, A_bᵀ s, γ) with
    γ = −(ṡ·ω_b − ρ(s̈·r + 2 ṡ·ṙ + s·a_n)) (d/dt(A_b ω̄_b) = A_b ω̄̇_b, ṡ·ω_a = 0)."""
    c, sx, sy, sz = screw_residual(Aa, Ab, nx, ny, nz, rel0, ratio, advance0, rx, ry, rz)
    a0, a1, a2, ad0, ad1, ad2, aa0, aa1, aa2 = body_vector(Aa, wax, way, waz, nx, ny, nz)
    cx, cy, cz = turned_coefficient(Aa, nx, ny, nz, -ratio * rx, -ratio * ry, -ratio * rz)
    tx, ty, tz = matrix9_apply_transposed(Ab, a0, a1, a2)
    ox, oy, oz = matrix9_apply(Ab, wbx, wby, wbz)
    gb = ad0 * ox + ad1 * oy + ad2 * oz
    gamma = -(gb - ratio * ((aa0 * rx + aa1 * ry + aa2 * rz) + 2.0 * (ad0 * rdx + ad1 * rdy + ad2 * rdz)
                            + (a0 * anx + a1 * any_ + a2 * anz)))
    return c, -ratio * a0, -ratio * a1, -ratio * a2, cx, cy, cz, -nx, -ny, -nz, tx, ty, tz, gamma


@law
def slider_rows_2d(turns, tha, thb, wa, wb, phi0, nbx, nby, rx, ry, rdx, rdy, anx, any_):
    """A planar slider's two rows: no relative turn, C₁ = θ_b − θ_a − φ0 (C_v: −1 on θ_a, +1 on
    θ_b, Ċ₁ = θ̇_b − θ̇_a, γ₁ = 0), and b's point on the line through a's along the axis,
    C₂ = n·r with the normal n = A_a n̄ (the dot-2 row in the plane, n̄ fixed in a's body where
    `turns`, else in the ground). Returns (C₁, Ċ₁, C₂, the translational coefficient n, the
    coefficient over θ̇_a of n's turn, n⊥·r with n⊥ = dn/dθ_a, γ₂) with
    γ₂ = −(n·a_n − θ̇_a² n·r + 2 θ̇_a n⊥·ṙ)."""
    c1 = thb - tha - phi0
    cd1 = wb - wa
    if turns:
        c = math.cos(tha)
        s = math.sin(tha)
        nx = c * nbx - s * nby
        ny = s * nbx + c * nby
    else:
        nx = nbx
        ny = nby
    npx = -ny
    npy = nx
    c2 = nx * rx + ny * ry
    gamma2 = -((nx * anx + ny * any_) - wa * wa * c2 + 2.0 * wa * (npx * rdx + npy * rdy))
    return c1, cd1, c2, nx, ny, npx * rx + npy * ry, gamma2


@law
def screw_turn_2d(ratio, advance0, c1, nx, ny, wa, rx, ry, rdx, rdy, anx, any_):
    """A 2D screw (rack and pinion) turns b by ρ per unit of its advance t·r along the slider's
    axis t = (n_y, −n_x) (dt/dθ_a = n): its first row is the slider's C₁ − ρ(t·r − x₀). Returns
    (that C₁, the advance's translational coefficient t and its coefficient over θ̇_a, n·r, both to
    be scaled by −ρ, and the row's γ₁ = ρ (t·a_n − θ̇_a² t·r + 2 θ̇_a n·ṙ))."""
    tx = ny
    ty = -nx
    td = tx * rx + ty * ry
    c1 -= ratio * (td - advance0)
    gamma1 = ratio * ((tx * anx + ty * any_) - wa * wa * td + 2.0 * wa * (nx * rdx + ny * rdy))
    return c1, tx, ty, nx * rx + ny * ry, gamma1
