"""Linear spring between two terminals: F = k (L − L0), tension positive (paper Eq. 5).

Its potential energy is ½ k (L − L0)². L0 defaults to the terminal distance at t = 0 (the scene's
``length`` overrides it).
"""
from inerter.elements.base import TRANSLATIONAL, ElementKind, Parameter, law
from inerter.elements.layout import COEFFICIENT, FREE_LENGTH

KIND = ElementKind(
    name="spring", family=TRANSLATIONAL, equation="Eq. 5",
    description="linear spring, F = k (L − L0)",
    coefficient=Parameter("k", "N/m", "stiffness", minimum=0.0),
    free=Parameter("length", "m", "free length L0 (default: the distance at t = 0)", minimum=0.0,
                   required=False))


@law
def inertance(row, Ldot):
    return 0.0


@law
def force(row, L, Ldot, an, perp2):
    """The axial force; (Ldot, an, perp2) unused."""
    return row[COEFFICIENT] * (L - row[FREE_LENGTH])


@law
def energy(row, L, Ldot):
    """Potential energy ½ k (L − L0)²."""
    d = L - row[FREE_LENGTH]
    return 0.5 * row[COEFFICIENT] * d * d
