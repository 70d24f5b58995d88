"""A point's kinematics, a point force's generalised force and a body's energy, written once
(paper Sec. 3.1-3.2, Eqs. 15-17, 22, 25, 26; the virtual work of a force at a point).

Scalar functions compiled by :func:`~inerter.elements.base.law`: the engine's kernels inline them
(``kernels._point``, ``_point3``, ``_point_force``, ``_point_force3``, the PD actuators, the ground
motion's frame force, the 3D bodies' gyroscopic term, the bodies' share of the energy output),
and the readable model (:mod:`inerter.model.planar`, :mod:`inerter.model.spatial`,
:class:`inerter.model.mechanism.Mechanism`) runs the same definitions uncompiled and places what
they return into its vectors and matrices (and sums the energies). They sit here, below the
model and beside the element laws that take their results, because the elements' terminals, the
joints' rows and the applied forces all start from them.

A planar body has q = (x, y, θ) and v = (ẋ, ẏ, θ̇); a spatial body has its centre R, a rotation A
(a row-major 9-tuple) and v = (Ṙ, ω̄), ω̄ its angular velocity in the body frame (Eq. 22 written
with body-frame ω). A point is fixed at ū in its body. What a ground point is (fixed at ū, no
coordinates) the callers decide.
"""
from __future__ import annotations

import math

from inerter.common.rotations import cross3
from inerter.elements.base import law
from inerter.elements.joint_rows import body_vector, turned_coefficient


@law
def planar_turned(th, lx, ly):
    """A(θ) ū, a body-fixed vector ū of a planar body in the global frame (Eq. 15)."""
    c = math.cos(th)
    s = math.sin(th)
    return c * lx - s * ly, s * lx + c * ly


@law
def planar_point(x, y, th, vx, vy, w, lx, ly):
    """A point ū of a planar body: (r, ṙ, A ū, acc) with r = R + A ū (Eq. 15),
    ṙ = Ṙ + θ̇ A_θ ū (Eq. 16), A_θ ū = (−(A ū)_y, (A ū)_x) the θ-column of H, and
    acc = −θ̇² A ū, so that r̈ = H q̈ + acc (Eq. 17; a pair's a_n = acc_b − acc_a, Eq. 19)."""
    ax, ay = planar_turned(th, lx, ly)
    return x + ax, y + ay, vx - w * ay, vy + w * ax, ax, ay, -w * w * ax, -w * w * ay


@law
def spatial_point(A, x, y, z, vx, vy, vz, wx, wy, wz, lx, ly, lz):
    """A point ū of a spatial body with rotation A: (r, ṙ, acc) with r = R + A ū (Eq. 15),
    ṙ = Ṙ + A(ω̄ × ū) (Eq. 22) and acc = A(ω̄ × (ω̄ × ū)), so that r̈ = H v̇ + acc (Eq. 25's a_n
    is acc_b − acc_a). H = [I, −A ũ]; its ω̄-columns, as tᵀH, are :func:`spatial_turn_row`."""
    u0, u1, u2, d0, d1, d2, a0, a1, a2 = body_vector(A, wx, wy, wz, lx, ly, lz)
    return x + u0, y + u1, z + u2, vx + d0, vy + d1, vz + d2, a0, a1, a2


#: (A, ū, t) ↦ ū × (Aᵀ t) = tᵀ(−A ũ), the ω̄-columns of tᵀH for a point ū (Eq. 22; t = e_i: row i).
spatial_turn_row = turned_coefficient


@law
def planar_point_force(th, lx, ly, fx, fy):
    """Hᵀ F for a force F at a point ū of a planar body (virtual work, δr = H δq, Eq. 16): F on
    x and y, and A_θ ū · F on θ."""
    ax, ay = planar_turned(th, lx, ly)
    return fx, fy, -ay * fx + ax * fy


@law
def spatial_point_force(A, lx, ly, lz, fx, fy, fz):
    """Hᵀ F for a force F at a point ū of a spatial body (virtual work, δr = H δv): F on Ṙ and
    ū × (Aᵀ F) on ω̄."""
    mx, my, mz = turned_coefficient(A, lx, ly, lz, fx, fy, fz)
    return fx, fy, fz, mx, my, mz


@law
def pd_magnitude(dx, dy, dz, reference, kp, kd, rx, ry, rz, vx, vy, vz):
    """A grounded PD actuator's force along its fixed unit direction d, F = f d with
    f = −[kp (d·r − ref) + kd d·ṙ] (in 2D the z components are 0)."""
    along = dx * rx + dy * ry + dz * rz - reference
    rate = dx * vx + dy * vy + dz * vz
    return -(kp * along + kd * rate)


@law
def frame_force(m, agx, agy, agz):
    """m a_g of a body of mass m on a ground moving with the acceleration a_g: the coordinates
    are relative to the ground frame, so each body's R feels −m a_g (d'Alembert's force of the
    frame's acceleration; the caller subtracts this)."""
    return m * agx, m * agy, m * agz


@law
def angular_momentum(J, at, wx, wy, wz):
    """J ω̄, J row-major in J[at:at + 9]: a spatial body's angular momentum about its centre, in
    its frame (the ω̄-block of its constant mass matrix diag(m I, J) times ω̄)."""
    hx = J[at] * wx + J[at + 1] * wy + J[at + 2] * wz
    hy = J[at + 3] * wx + J[at + 4] * wy + J[at + 5] * wz
    hz = J[at + 6] * wx + J[at + 7] * wy + J[at + 8] * wz
    return hx, hy, hz


@law
def gyroscopic(J, at, wx, wy, wz):
    """ω̄ × J ω̄, J row-major in J[at:at + 9]: a spatial body's generalised force over ω̄ has
    −ω̄ × J ω̄ (Euler's equations in the body frame, where the mass matrix is the constant
    diag(m I, J))."""
    hx, hy, hz = angular_momentum(J, at, wx, wy, wz)
    return cross3(wx, wy, wz, hx, hy, hz)


@law
def planar_body_energy(m, J, vx, vy, w, fx, fy, x, y):
    """A planar body's T + V: its kinetic energy T = ½ m |Ṙ|² + ½ J θ̇² (½ vᵀ M v with the
    constant centroidal mass matrix diag(m, m, J) of Eq. 26, Shabana 2009) and its weight's
    potential V = −f·R, f = m g (so that f = −∂V/∂R; f = 0 without gravity)."""
    return 0.5 * m * (vx * vx + vy * vy) + 0.5 * J * w * w - (fx * x + fy * y)


@law
def spatial_body_energy(m, J, at, vx, vy, vz, wx, wy, wz, fx, fy, fz, x, y, z):
    """A spatial body's T + V, J its inertia about the centre in its frame, row-major in
    J[at:at + 9]: T = ½ m |Ṙ|² + ½ ω̄ᵀ J ω̄ (½ vᵀ M v with v = (Ṙ, ω̄) and the constant mass
    matrix diag(m I, J) of Eq. 26 in centroidal coordinates, Eq. 22 with body-frame ω̄; Shabana
    2009) and its weight's potential V = −f·R, f = m g (f = −∂V/∂R; f = 0 without gravity)."""
    hx, hy, hz = angular_momentum(J, at, wx, wy, wz)
    kinetic = 0.5 * m * (vx * vx + vy * vy + vz * vz) + 0.5 * (wx * hx + wy * hy + wz * hz)
    return kinetic - (fx * x + fy * y + fz * z)
