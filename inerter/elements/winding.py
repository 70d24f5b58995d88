"""A 3D rotational element's angle on the covering space: wound on past half a turn.

The relative rotation's angle about the element's axis is read as atan2(s, c), within (−π, π]
(the engine's ``_rotational3``, the evaluators' ``SpatialRotationalElement``): alone it jumps by
2π where the rotation passes half a turn. Each element carries φ_ref, its angle at the last
accepted step (0 at t = 0: measured from the initial pose), and its angle is the value of the
atan2 reading on the branch nearest φ_ref,

    φ = φ_ref + wrap(atan2(s, c) − φ_ref),   wrap into (−π, π],

the lift of the reading to the covering space of the circle (the standard phase unwrapping). Near
every point of the path φ is then a function of the configuration, the reading plus a constant
2πk, so a spring's torque stays the gradient of ½k(φ − φ0)² (conservative), and φ winds on
without limit as long as no single step turns the relative rotation by more than π. φ_ref is held
in the element's table row (``layout.PHI_REF``) and moved on after each accepted step.
"""
import math

from inerter.elements.base import law


@law
def wound(reference, reading):
    """The angle on the branch nearest `reference`: reference + wrap(reading − reference), the
    difference wrapped into (−π, π] (a reading exactly half a turn away goes forward)."""
    turn = 2.0 * math.pi
    # the reading plus whole turns (not reference + wrapped offset): a reading within half a turn of
    # the reference is returned as it is, bit for bit, so an element that never winds is unchanged
    return reading - turn * math.ceil((reading - reference - math.pi) / turn)


@law
def carried(reference, h, rate_start, rate_end):
    """Where the rates at the two ends of a step of length h carry an angle that was `reference`
    at its start: reference + h (φ̇_start + φ̇_end)/2 (the trapezoidal rule). The angle at the
    step's end is the reading :func:`wound` from this, not from `reference`, so that a step that
    turns it by more than half a turn (an adaptive method's long step where no force depends on the
    branch) still winds it on; where the step turns it by less, both branches are the same."""
    return reference + 0.5 * h * (rate_start + rate_end)
