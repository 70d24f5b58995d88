"""Rotation math shared by every layer (paper Sec. 3.2, Appendix B): quaternions p = (w, x, y, z),
the paper's Z-X-Z Euler angles (Eq. B.1, singular where sin θ = 0), axis-angle matrices and cross
products. How bodies use them: :mod:`inerter.model.spatial`.

An orientation's matrix and its coordinates' rates are written once, as scalar functions
(``*_matrix9``, ``*_rates``) that the engine's kernels inline compiled and the numpy functions
below run uncompiled (``.py_func``).
"""
from __future__ import annotations

import math

import numpy as np

from inerter.common.errors import SimulationError
from inerter.common.inlined import inlined


def _scalar(fn):
    """A scalar kinematic function, inlined by the kernels where they call it and run as written
    from Python."""
    return inlined(fn)

#: |sin θ| below which Z-X-Z Euler angles are taken to be at their singularity.
EULER_SINGULARITY = 1e-6


def cross(a, b):
    """a × b for 3-vectors (np.cross costs tens of µs on arrays this small)."""
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]))


@_scalar
def cross3(ax, ay, az, bx, by, bz):
    """a × b on the components of two 3-vectors (the kernels' scalar form of :func:`cross`)."""
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


def skew(u):
    return np.array(((0.0, -u[2], u[1]), (u[2], 0.0, -u[0]), (-u[1], u[0], 0.0)))


@_scalar
def matrix9_apply(A, x, y, z):
    """A (x, y, z) for a rotation A given as a row-major 9-tuple: a direction fixed in a body, in
    the global frame."""
    return A[0] * x + A[1] * y + A[2] * z, A[3] * x + A[4] * y + A[5] * z, A[6] * x + A[7] * y + A[8] * z


@_scalar
def matrix9_apply_transposed(A, x, y, z):
    """Aᵀ (x, y, z) for a rotation A given as a row-major 9-tuple: a global direction in the body's
    frame."""
    return A[0] * x + A[3] * y + A[6] * z, A[1] * x + A[4] * y + A[7] * z, A[2] * x + A[5] * y + A[8] * z


# -- planar bodies (Sec. 3.1) -----------------------------------------------------------------------
@_scalar
def planar_matrix9(theta):
    """A planar body's rotation A(θ) about the normal (Eq. 15) as a 3D rotation matrix (row-major
    9-tuple), for the geometry written once for 2D and 3D (inerter.elements.terminals)."""
    c = math.cos(theta)
    s = math.sin(theta)
    return (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)


# -- quaternions ---------------------------------------------------------------------------------
@_scalar
def quaternion_matrix9(w, x, y, z):
    """The rotation matrix (row-major 9-tuple) of a quaternion, normalised on the fly with
    s = 2/(w² + x² + y² + z²)."""
    s = 2.0 / (w * w + x * x + y * y + z * z)
    return (1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y),
            s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x),
            s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y))


@_scalar
def quaternion_rates(w, x, y, z, a, b, c):
    """ṗ = ½ p ⊗ (0, ω), ω = (a, b, c) in the body frame."""
    return (0.5 * (-x * a - y * b - z * c), 0.5 * (w * a + y * c - z * b), 0.5 * (w * b + z * a - x * c),
            0.5 * (w * c + x * b - y * a))


def quat_matrix(p):
    """Rotation matrix of a quaternion (normalised on the fly)."""
    return np.array(quaternion_matrix9.py_func(*p)).reshape(3, 3)


def quat_rate(p, omega):
    """ṗ = ½ p ⊗ (0, ω), ω in the body frame."""
    return np.array(quaternion_rates.py_func(*p, *omega))


@_scalar
def quaternion_of_matrix9(a00, a01, a02, a10, a11, a12, a20, a21, a22):
    """The unit quaternion (w, x, y, z), w ≥ 0, of a rotation matrix given row by row (Shepperd's
    method: the largest of w, x, y, z first, for accuracy)."""
    tr = a00 + a11 + a22
    if tr > 0:
        s = 2.0 * math.sqrt(tr + 1.0)
        w, x, y, z = 0.25 * s, (a21 - a12) / s, (a02 - a20) / s, (a10 - a01) / s
    elif a00 > a11 and a00 > a22:
        s = 2.0 * math.sqrt(1.0 + a00 - a11 - a22)
        w, x, y, z = (a21 - a12) / s, 0.25 * s, (a01 + a10) / s, (a02 + a20) / s
    elif a11 > a22:
        s = 2.0 * math.sqrt(1.0 + a11 - a00 - a22)
        w, x, y, z = (a02 - a20) / s, (a01 + a10) / s, 0.25 * s, (a12 + a21) / s
    else:
        s = 2.0 * math.sqrt(1.0 + a22 - a00 - a11)
        w, x, y, z = (a10 - a01) / s, (a02 + a20) / s, (a12 + a21) / s, 0.25 * s
    if w < 0.0:
        return -w, -x, -y, -z
    return w, x, y, z


def quat_from_matrix(A):
    """A unit quaternion (w ≥ 0) for a rotation matrix."""
    return np.array(quaternion_of_matrix9.py_func(*np.asarray(A, dtype=float).ravel()))


#: Euler-angle sequences for outputs, intrinsic (R = R_i(α) R_j(β) R_k(γ)), by name; axes 0 = x.
EULER_SEQUENCES = {name: tuple("xyz".index(c) for c in name)
                   for name in ("xyz", "xzy", "yxz", "yzx", "zxy", "zyx",
                                "xyx", "xzx", "yxy", "yzy", "zxz", "zyz")}


@_scalar
def euler_angles9(A, i, j, k):
    """(α, β, γ) with A = R_i(α) R_j(β) R_k(γ) (intrinsic axes i, j, k; A a row-major 9-tuple):
    Tait–Bryan angles (i, j, k distinct; β in [−π/2, π/2]) or proper Euler angles (k = i;
    β in [0, π]). At β's singularity (gimbal lock) γ is 0 and α carries the whole turn."""
    s = 1.0 if (j - i) % 3 == 1 else -1.0            # the sign of the permutation (i, j, third axis)
    if i != k:
        cb = math.hypot(A[3 * i + i], A[3 * i + j])     # β from atan2: well conditioned near ±π/2
        beta = math.atan2(s * A[3 * i + k], cb)
        if cb > 1e-12:
            return math.atan2(-s * A[3 * j + k], A[3 * k + k]), beta, math.atan2(-s * A[3 * i + j], A[3 * i + i])
        return math.atan2(s * A[3 * k + j], A[3 * j + j]), beta, 0.0
    m = 3 - i - j                                     # the third axis
    sb = math.hypot(A[3 * i + j], A[3 * i + m])
    beta = math.atan2(sb, A[3 * i + i])               # well conditioned near 0 and π
    if sb > 1e-12:
        return math.atan2(A[3 * j + i], -s * A[3 * m + i]), beta, math.atan2(A[3 * i + j], s * A[3 * i + m])
    return math.atan2(s * A[3 * m + j], A[3 * j + j]), beta, 0.0


def axis_angle_matrix(axis, angle):
    n = np.asarray(axis, dtype=float)
    n = n / np.linalg.norm(n)
    K = skew(n)
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * (K @ K)


# -- Z-X-Z Euler angles (Appendix B) --------------------------------------------------------------
@_scalar
def euler_matrix9(phi, th, psi):
    """Eq. (B.1): A = R_z(φ) R_x(θ) R_z(ψ), row-major 9-tuple."""
    cf, sf, ct, st, cp, sp = math.cos(phi), math.sin(phi), math.cos(th), math.sin(th), math.cos(psi), math.sin(psi)
    return (cp * cf - ct * sf * sp, -sp * cf - ct * sf * cp, st * sf,
            cp * sf + ct * cf * sp, -sp * sf + ct * cf * cp, -st * cf,
            st * sp, st * cp, ct)


@_scalar
def euler_rates(th, psi, a, b, c):
    """(φ̇, θ̇, ψ̇) from the body-frame angular velocity ω = (a, b, c): ω = G_b(θ) ė (Eq. 23) inverted,
    which divides by sin θ (the caller checks it against EULER_SINGULARITY first)."""
    cp, sp = math.cos(psi), math.sin(psi)
    phidot = (a * sp + b * cp) / math.sin(th)
    return phidot, a * cp - b * sp, c - phidot * math.cos(th)


def euler_matrix(e):
    """Eq. (B.1): A = R_z(φ) R_x(θ) R_z(ψ)."""
    return np.array(euler_matrix9.py_func(*e)).reshape(3, 3)


def euler_from_matrix(A):
    th = math.acos(max(-1.0, min(1.0, A[2, 2])))
    if abs(math.sin(th)) < EULER_SINGULARITY:
        return np.array((math.atan2(A[1, 0], A[0, 0]), th, 0.0))
    return np.array((math.atan2(A[0, 2], -A[1, 2]), th, math.atan2(A[2, 0], A[2, 1])))


def euler_rate(e, omega, body_name="", t=None):
    """Euler-angle rates from the body-frame angular velocity: ω = G_b(θ) ė, inverted."""
    _, th, psi = e
    st = math.sin(th)
    if abs(st) < EULER_SINGULARITY:
        raise SimulationError(
            f"body '{body_name}': its Z-X-Z Euler angles reach their singularity (gimbal lock, "
            f"sin θ = {st:.2e}): the angle rates are undefined; use orientation = \"quaternion\"", t)
    return np.array(euler_rates.py_func(th, psi, *omega))
