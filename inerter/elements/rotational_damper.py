"""Rotational viscous damper between two bodies (or a body and the ground): τ = d ω_rel."""
from inerter.elements.base import ROTATIONAL, ElementKind, Parameter, law
from inerter.elements.layout import COEFFICIENT

KIND = ElementKind(
    name="rotational_damper", family=ROTATIONAL,
    description="rotational viscous damper, τ = d dφ/dt",
    coefficient=Parameter("d", "N.m.s/rad", "rotational damping coefficient", minimum=0.0))


@law
def torque(row, phi, w):
    return row[COEFFICIENT] * w


@law
def energy(row, phi, w):
    return 0.0
