"""A rotational element's angle and its rate, written once for every rotational kind: in 2D the
difference of the bodies' angles, in 3D the twist about an axis fixed in body a (swing-twist
decomposition of the relative rotation since the initial pose), wound on past half a turn
(:mod:`inerter.elements.winding`).

A module of its own beside the kinds' laws (:mod:`inerter.elements.rotational_spring`, ...): those
take (φ, φ̇) and return a torque; this measures φ, φ̇ and the direction the torque acts along, the
same for every rotational kind. The engine's kernels (``_rotational2``, ``_rotational3``) inline
these laws; the readable evaluators (``RotationalElement``, ``SpatialRotationalElement`` of
:mod:`inerter.model.evaluators`) run them uncompiled.
"""
from __future__ import annotations

import math

from inerter.common.rotations import matrix9_apply
from inerter.elements.base import law
from inerter.elements.winding import wound


@law
def planar_relative(q, v, ia, ib):
    """A 2D rotational element's φ = θ_b − θ_a and φ̇, ia and ib the indices of the bodies' angles
    in q and v (−1: the ground, angle 0)."""
    phi = (q[ib] if ib >= 0 else 0.0) - (q[ia] if ia >= 0 else 0.0)
    w = (v[ib] if ib >= 0 else 0.0) - (v[ia] if ia >= 0 else 0.0)
    return phi, w


@law
def relative_entry(Aa, Ab, rel0, at, i, j):
    """D[i, j] of D = (A_aᵀ A_b) rel0ᵀ, rel0 row-major in rel0[at:at + 9]: the relative rotation
    since the initial pose, in a's frame."""
    x = 0.0
    for k in range(3):
        x += (Aa[i] * Ab[k] + Aa[3 + i] * Ab[3 + k] + Aa[6 + i] * Ab[6 + k]) * rel0[at + 3 * j + k]
    return x


@law
def spatial_twist(Aa, Ab, rel0, at, nx, ny, nz, reference, wax, way, waz, wbx, wby, wbz):
    """A 3D rotational element's (φ, φ̇, g): φ the twist about the axis n̄ (fixed in body a) of
    D = (A_aᵀ A_b) rel0ᵀ, atan2(½ n̄·vee(D − Dᵀ), ½(tr D − n̄ᵀD n̄)) wound on from `reference`
    (its angle at the last accepted step); g = A_a (n̄ + D n̄)/(2h), h = hypot of the two, φ's
    gradient over the relative angular velocity in the global frame (the twist quaternion's
    w² + x² is h), so that a torque τ along g is a spring's −∇V; φ̇ = g·(A_b ω̄_b − A_a ω̄_a).
    On a revolute joint about n̄ (D n̄ = n̄, h = 1) g = A_a n̄. A_a, A_b row-major 9-tuples."""
    d00 = relative_entry(Aa, Ab, rel0, at, 0, 0)
    d01 = relative_entry(Aa, Ab, rel0, at, 0, 1)
    d02 = relative_entry(Aa, Ab, rel0, at, 0, 2)
    d10 = relative_entry(Aa, Ab, rel0, at, 1, 0)
    d11 = relative_entry(Aa, Ab, rel0, at, 1, 1)
    d12 = relative_entry(Aa, Ab, rel0, at, 1, 2)
    d20 = relative_entry(Aa, Ab, rel0, at, 2, 0)
    d21 = relative_entry(Aa, Ab, rel0, at, 2, 1)
    d22 = relative_entry(Aa, Ab, rel0, at, 2, 2)
    s = 0.5 * (nx * (d21 - d12) + ny * (d02 - d20) + nz * (d10 - d01))
    nDn = (nx * (d00 * nx + d01 * ny + d02 * nz) + ny * (d10 * nx + d11 * ny + d12 * nz)
           + nz * (d20 * nx + d21 * ny + d22 * nz))
    c = 0.5 * (d00 + d11 + d22 - nDn)
    phi = wound(reference, math.atan2(s, c))
    h2 = 2.0 * math.hypot(s, c)
    gx, gy, gz = matrix9_apply(Aa, (nx + d00 * nx + d01 * ny + d02 * nz) / h2,
                               (ny + d10 * nx + d11 * ny + d12 * nz) / h2, (nz + d20 * nx + d21 * ny + d22 * nz) / h2)
    ox, oy, oz = matrix9_apply(Ab, wbx, wby, wbz)
    px, py, pz = matrix9_apply(Aa, wax, way, waz)
    w = gx * (ox - px) + gy * (oy - py) + gz * (oz - pz)
    return phi, w, gx, gy, gz
