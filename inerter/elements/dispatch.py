"""The kernels' call of each element kind's law by its code (its place in
inerter.elements.MODULES). Written by ``python -m inerter.elements.generate``: do not edit."""
from inerter.elements.base import law
from inerter.elements import damper as kind_damper
from inerter.elements import inerter as kind_inerter
from inerter.elements import rotational_damper as kind_rotational_damper
from inerter.elements import rotational_spring as kind_rotational_spring
from inerter.elements import spring as kind_spring


@law
def inertance(kind, row, Ldot):
    if kind == 0:
        return kind_damper.inertance(row, Ldot)
    if kind == 1:
        return kind_inerter.inertance(row, Ldot)
    return kind_spring.inertance(row, Ldot)  # kind == 4


@law
def force(kind, row, L, Ldot, an, perp2):
    if kind == 0:
        return kind_damper.force(row, L, Ldot, an, perp2)
    if kind == 1:
        return kind_inerter.force(row, L, Ldot, an, perp2)
    return kind_spring.force(row, L, Ldot, an, perp2)  # kind == 4


@law
def energy(kind, row, L, Ldot):
    if kind == 0:
        return kind_damper.energy(row, L, Ldot)
    if kind == 1:
        return kind_inerter.energy(row, L, Ldot)
    return kind_spring.energy(row, L, Ldot)  # kind == 4


@law
def extra_outputs(kind, row, L, Ldot, an, perp2, gq, x, out, k):
    if kind == 1:
        return kind_inerter.extra_outputs(row, L, Ldot, an, perp2, gq, x, out, k)
    return k


@law
def state_force(kind, row, L, Ldot, x):
    if kind == 1:
        return kind_inerter.state_force(row, L, Ldot, x)
    return 0.0


@law
def state_energy(kind, row, L, Ldot, x):
    if kind == 1:
        return kind_inerter.state_energy(row, L, Ldot, x)
    return 0.0


@law
def state_rates(kind, row, L, Ldot, an, perp2, gq, x, dx):
    if kind == 1:
        return kind_inerter.state_rates(row, L, Ldot, an, perp2, gq, x, dx)
    return None


@law
def torque(kind, row, phi, w):
    if kind == 2:
        return kind_rotational_damper.torque(row, phi, w)
    return kind_rotational_spring.torque(row, phi, w)  # kind == 3


@law
def rotational_energy(kind, row, phi, w):
    if kind == 2:
        return kind_rotational_damper.energy(row, phi, w)
    return kind_rotational_spring.energy(row, phi, w)  # kind == 3
