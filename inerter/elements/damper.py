"""Linear viscous damper between two terminals: F = c dL/dt = c ṙ·r̂, tension positive (Eq. 7)."""
from inerter.elements.base import TRANSLATIONAL, ElementKind, Parameter, law
from inerter.elements.layout import COEFFICIENT

KIND = ElementKind(
    name="damper", family=TRANSLATIONAL, equation="Eq. 7",
    description="linear viscous damper, F = c dL/dt",
    coefficient=Parameter("c", "N.s/m", "damping coefficient", minimum=0.0))


@law
def inertance(row, Ldot):
    return 0.0


@law
def force(row, L, Ldot, an, perp2):
    return row[COEFFICIENT] * Ldot


@law
def energy(row, L, Ldot):
    """A damper stores no energy."""
    return 0.0
