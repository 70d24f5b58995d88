"""Ideal inerter: F = b d²L/dt², tension positive (paper Eq. 9), or, without the centripetal term,
the 1D law F = b r̈·r̂ (Eq. 8).

With r = r_b − r_a, L = |r|, r̂ = r/L and r̈ = H q̈ + a_n (Eqs. 18-19):

    d²L/dt² = r̈·r̂ + (ṙ·ṙ − (ṙ·r̂)²)/L = gᵀ q̈ + a_n·r̂ + |ṙ⊥|²/L,     g = Hᵀ r̂.

The part b gᵀ q̈ goes into the mass matrix, M_I = b g gᵀ (Eq. 33): :func:`inertance` is b. The rest,
b (a_n·r̂ + |ṙ⊥|²/L), is :func:`force`, the right side's Q_Iv (Eq. 31). Its kinetic energy is
½ b L̇² (the correct model is Lagrangian, Sec. 2.2); the model without the term has none, and its
energy output keeps the same ½ b L̇² for comparison.
"""
from inerter.elements.base import TRANSLATIONAL, ElementKind, Parameter, law
from inerter.elements.layout import CENTRIPETAL, COEFFICIENT

KIND = ElementKind(
    name="inerter", family=TRANSLATIONAL, equation="Eq. 9 (Eq. 8 without the centripetal term)",
    description="ideal inerter, F = b d²L/dt²",
    coefficient=Parameter("b", "kg", "inertance", minimum=0.0))


@law
def inertance(row):
    """b: the factor of gᵀ q̈ in F, which goes into the mass matrix (Eq. 33)."""
    return row[COEFFICIENT]


@law
def force(row, L, Ldot, an, perp2):
    """F − b gᵀ q̈ = b (a_n·r̂ + |ṙ⊥|²/L) (Eq. 9), or b a_n·r̂ without the centripetal term
    (Eq. 8). `an` is a_n·r̂, `perp2` is |ṙ|² − L̇² = |ṙ⊥|²."""
    term = an
    if row[CENTRIPETAL] != 0.0:
        term += perp2 / L
    return row[COEFFICIENT] * term


@law
def energy(row, L, Ldot):
    """Kinetic energy ½ b L̇²."""
    return 0.5 * row[COEFFICIENT] * Ldot * Ldot
