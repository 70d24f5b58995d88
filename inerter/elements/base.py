"""What an element kind is: its parameters (key in the scene, symbol, unit, physical range) and its
law, written once as scalar arithmetic.

A law is a plain function of floats and of the element's row of numbers (``row[COEFFICIENT]``...,
the named columns of :mod:`inerter.elements.layout`). :func:`law` compiles it with numba for the
engine's kernels, which inline it into their assembly and output loops, 2D and 3D alike; its
``.py_func`` is the same definition run by the Python interpreter (the readable evaluators of
:mod:`inerter.model.evaluators`). Nothing about an element is written a second time.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from inerter.common.inlined import inlined

#: The families of element kinds: two-terminal elements acting along the line between their
#: terminals (uniaxial, Sec. 2.2), and rotational ones between two bodies' orientations.
TRANSLATIONAL, ROTATIONAL = "translational", "rotational"


def law(fn):
    """A law for the kernels, which inline it where they call it; Python runs it as written
    (:func:`inerter.common.inlined.inlined`)."""
    return inlined(fn)


def rarely(condition):
    """`condition`, marked for the compiler as almost always false: a law's branch that most
    elements never take (an ideal inerter's device) is laid out and register-allocated as a cold
    path, so that the loop it sits in runs as fast as without it. Plain Python returns it as it
    is (``law.py_func``)."""
    return condition


@intrinsic
def _expect_false(typingctx, condition):
    """llvm.expect(condition, false)."""
    def codegen(context, builder, signature, args):
        bit = ir.IntType(1)
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(bit, [bit, bit]), "llvm.expect.i1")
        return builder.call(fn, [args[0], ir.Constant(bit, 0)])
    return types.boolean(types.boolean), codegen


@overload(rarely, inline="always")
def _rarely(condition):
    return lambda condition: _expect_false(condition)


@dataclass(frozen=True)
class Parameter:
    """One parameter of an element kind as a scene declares it (``elements.NAME.<key>``, or
    ``elements.NAME.device.EFFECT.<key>`` for a device effect's): its physical range is
    [minimum, maximum], or (minimum, maximum] where `strict`; an optional one (`required` False)
    takes `default` where the scene leaves it out (None: absent)."""
    key: str
    unit: str
    description: str
    minimum: float = -math.inf
    required: bool = True
    maximum: float = math.inf
    strict: bool = False
    default: float | None = None
    #: 3: a vector of three numbers, made a unit vector (a device mount's axis); 1: a number.
    size: int = 1

    def expected(self) -> str:
        """The range in words, for an error message, as the scene reader writes a field's: "a
        number ≥ 0 N/m", "a number ≥ 1 and ≤ 3" (a dimensionless one's unit "1" not written)."""
        unit = f" {self.unit}" if self.unit != "1" else ""
        if self.size > 1:
            return f"a vector of {self.size} numbers, not all zero" + (f" ({self.unit})" if unit else "")
        parts = []
        if self.minimum != -math.inf:
            parts.append(f"{'>' if self.strict else '≥'} {self.minimum:g}")
        if self.maximum != math.inf:
            parts.append(f"≤ {self.maximum:g}")
        return "a number" + (" " + " and ".join(parts) if parts else "") + unit

    def admits(self, value: float) -> bool:
        """Whether `value` is within the parameter's range."""
        above = value > self.minimum if self.strict else value >= self.minimum
        return above and value <= self.maximum


@dataclass(frozen=True)
class ElementKind:
    """An element kind: the scene's ``type``, its code in the engine's tables (its place in
    :data:`inerter.elements.KINDS`), its family, its coefficient and optional second parameter,
    and its outputs' names with units."""
    name: str
    family: str
    coefficient: Parameter
    description: str
    free: Parameter | None = None          # a spring's free length, a rotational spring's angle
    equation: str = ""
    #: The device effects an element of this kind may declare (``elements.NAME.device.EFFECT``),
    #: each an :class:`inerter.elements.device.Effect`; only the inerter has them.
    device: tuple = ()

    @property
    def outputs(self) -> tuple[tuple[str, str, str], ...]:
        """(suffix, unit, description) of the outputs every element of the family reports."""
        return FAMILY_OUTPUTS[self.family]


#: (suffix, unit, description) of the outputs every element of a family reports, in the order the
#: kernels write them (``E.s_rel``...). ``power`` is what the element absorbs from the mechanism,
#: force times rate (f·v_rel, τ·ω_rel: positive where it takes energy out of the bodies, the
#: conservative and non-conservative power of Drake's force elements together); ``energy`` is what
#: it stores, the terms it adds to the mechanism's energy (a spring's ½k(L − L0)², an inerter's
#: ½bL̇² and its device's, Sec. 2.2; a damper's 0), so that d(energy)/dt = power for a conservative
#: element (an inerter with the centripetal term of Eq. 9; not Eq. 8's, whose force misses it).
FAMILY_OUTPUTS = {
    TRANSLATIONAL: (("s_rel", "m", "distance between the terminals"),
                    ("v_rel", "m/s", "rate of change of the terminal distance"),
                    ("f", "N", "axial force, tension positive"),
                    ("power", "W", "power absorbed from the mechanism, f·v_rel"),
                    ("energy", "J", "energy stored in the element")),
    ROTATIONAL: (("phi_rel", "rad", "relative angle"), ("w_rel", "rad/s", "relative angular velocity"),
                 ("tau", "N.m", "torque (restoring positive)"),
                 ("power", "W", "power absorbed from the mechanism, tau·w_rel"),
                 ("energy", "J", "energy stored in the element"))}

#: The outputs of FAMILY_OUTPUTS computed from the force, which an inerter's reads from q̈.
FORCE_OUTPUTS = ("f", "power", "tau")


def output_suffixes(family) -> tuple[str, ...]:
    """The suffixes of the family's outputs (``E.s_rel``, ...), in the kernels' order."""
    return tuple(suffix for suffix, _, _ in FAMILY_OUTPUTS[family])


@law
def axial_scalars(rdx, rdy, rdz, anx, any_, anz, ex, ey, ez):
    """The scalars every translational law takes, from ṙ, a_n and r̂ (in 2D the z components are
    0): L̇ = ṙ·r̂, a_n·r̂ and |ṙ⊥|² = |ṙ|² − L̇² (the centripetal term's numerator, Eq. 9)."""
    Ldot = rdx * ex + rdy * ey + rdz * ez
    an = anx * ex + any_ * ey + anz * ez
    perp2 = rdx * rdx + rdy * rdy + rdz * rdz - Ldot * Ldot
    return Ldot, an, perp2
