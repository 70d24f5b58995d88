"""A translational element's terminal geometry, written once: the line it acts along, the L its law
reads, whether its terminals meet, and the terms of an axis that turns with terminal a's body.

These are scalar functions compiled by :func:`~inerter.elements.base.law`: the engine's kernels
(2D and 3D element loops) inline them, and the readable evaluators
(:class:`inerter.model.evaluators.TranslationalElement`) run the same definitions uncompiled
(``.py_func``). They are in the vector form of the paper's Eqs. 5-9 and serve 2D and 3D alike: in
2D every z component is 0, the rotation A_a of terminal a's body is the rotation by θ_a about the
normal and its angular velocity is ω̄_a = (0, 0, θ̇_a).

What they take is the kinematics of the terminals a → b (Eqs. 15-19, 22, 25), which the caller
computes: r = r_b − r_a, its length |r|, ṙ, and A_a as a row-major 9-tuple (:data:`IDENTITY` for
the ground, and wherever the element does not turn with a: :func:`turns_with_a`). Three lines of
action (columns of :mod:`inerter.elements.layout`):

- along r̂ = r/|r| with L = |r| (Sec. 2.2), the default;
- along a fixed unit vector ê₀ (``FIXED_DIRECTION``, ê₀ in ``DIRECTION``), the small-displacement
  law of structural codes: L is the stroke s = ê₀·r, whose rate is ê₀·ṙ;
- along a prismatic joint's axis ê = A_a n̄ (``SLIDER``, n̄ in ``DIRECTION`` in a's body frame), for
  the joint's spring or damper: L = ê·r is the signed slide.

The first two need the terminals apart: where |r| ≤ MIN_LENGTH they meet and r̂ is undefined (the
engine stops or retries the step; L is held at MIN_LENGTH so that nothing divides by zero). The
slide is defined everywhere.

**The turning axis.** ê = A_a n̄ turns with body a, so L = (A_a n̄)·r depends on a's rotation as well
as on r. A small body-frame rotation δφ̄ of a gives δA_a = A_a [δφ̄]×, so

    δL = (A_a(δφ̄ × n̄))·r = δφ̄·(n̄ × A_aᵀ r) = δφ̄·c̄,     c̄ = A_aᵀ(ê × r),

and L̇ = ê·ṙ + ω̄_a·c̄. The element's g = Hᵀê (Eq. 29) then gains c̄ on a's rotation coordinates
(3D: the ω̄_a columns; 2D: c_z on the θ_a column), which the caller adds to H as ê c̄ᵀ on those
columns, and ṙ gains (ω̄_a·c̄) ê, so that ê·ṙ is L̇. c̄ is zero on the joint's line; off it the
force is the gradient of the law's energy, ½k(L − L0)² for a spring. (The oracle,
:mod:`inerter.oracle.derivation`, derives L̇ and ∇L from L(q) with the axis as a second point on
body a, independently.)
"""
from __future__ import annotations

import math

from inerter.common.errors import MIN_LENGTH
from inerter.common.rotations import matrix9_apply, matrix9_apply_transposed
from inerter.elements.base import law, rarely
from inerter.elements.layout import DIRECTION, FIXED_DIRECTION, SLIDER

#: The rotation of the ground (and what an element that does not turn with a is given).
IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


@law
def turns_with_a(row):
    """Whether the element's line is fixed in terminal a's body (a prismatic joint's spring or
    damper): only then does :func:`acting_line` read A_a, and :func:`turning_axis` apply."""
    return row[SLIDER] != 0.0


@law
def acting_line(row, A, rx, ry, rz, distance):
    """(L, ê, meets): the L the element's law reads and the unit vector ê = (ex, ey, ez) it acts
    along (module docstring), from r and its length `distance` = |r|; `meets`: the terminals are
    too close for r̂ (|r| ≤ MIN_LENGTH; L is then held at MIN_LENGTH). A: terminal a's rotation,
    read only where :func:`turns_with_a`."""
    # the two fixed lines are rare: marked so, the kernels lay the r̂ line out as their straight path
    if rarely(row[SLIDER] != 0.0):
        ex, ey, ez = matrix9_apply(A, row[DIRECTION], row[DIRECTION + 1], row[DIRECTION + 2])
        return ex * rx + ey * ry + ez * rz, ex, ey, ez, False
    meets = not distance > MIN_LENGTH
    L = MIN_LENGTH if meets else distance
    if rarely(row[FIXED_DIRECTION] != 0.0):
        # the small-displacement law: along ê₀ on the stroke s = ê₀·r its device's laws read
        ex, ey, ez = row[DIRECTION], row[DIRECTION + 1], row[DIRECTION + 2]
        return ex * rx + ey * ry + ez * rz, ex, ey, ez, meets
    return L, rx / L, ry / L, rz / L, meets


@law
def turning_axis(A, ex, ey, ez, rx, ry, rz, wx, wy, wz, rdx, rdy, rdz):
    """An axis ê = A_a n̄ turning with terminal a's body (rotation A, body-frame angular velocity
    ω̄ = (wx, wy, wz)): (c̄, ṙ + (ω̄·c̄) ê) with c̄ = A_aᵀ(ê × r) = ∂L/∂φ̄_a, the term on H's
    rotation columns of a (module docstring)."""
    px, py, pz = ey * rz - ez * ry, ez * rx - ex * rz, ex * ry - ey * rx
    cx, cy, cz = matrix9_apply_transposed(A, px, py, pz)
    rate = wx * cx + wy * cy + wz * cz
    return cx, cy, cz, rdx + rate * ex, rdy + rate * ey, rdz + rate * ez


@law
def chord_approach(ax, ay, az, bx, by, bz):
    """The closest approach to 0 of the chord from r = r_b − r_a at a step's start, (ax, ay, az), to
    r at its end, (bx, by, bz): where it is not above the element's meeting limit, its terminals
    meet within the step, also where they pass through each other between two accepted steps
    (the engine then stops the run at the meeting)."""
    dx = bx - ax
    dy = by - ay
    dz = bz - az
    dd = dx * dx + dy * dy + dz * dz
    s = 1.0 if dd == 0.0 else min(1.0, max(0.0, -(ax * dx + ay * dy + az * dz) / dd))
    cx = ax + s * dx
    cy = ay + s * dy
    cz = az + s * dz
    return math.sqrt(cx * cx + cy * cy + cz * cz)


@law
def reported_distance(row, L, distance):
    """The element's output s_rel: its L, but |r| under the small-displacement law (whose L is the
    stroke ê₀·r)."""
    if row[FIXED_DIRECTION] != 0.0:
        return distance
    return L
