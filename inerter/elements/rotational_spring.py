"""Rotational spring between two bodies (or a body and the ground): τ = k (φ − φ0), restoring
positive. In 2D φ is the difference of the bodies' angles; in 3D the rotation about an axis fixed in
body a since the initial relative orientation, the twist about it where the bodies also swing (the
engine measures φ and applies τ along its gradient; this module holds the law). Its potential
energy is ½ k (φ − φ0)²."""
from inerter.elements.base import ROTATIONAL, ElementKind, Parameter, law
from inerter.elements.layout import COEFFICIENT, FREE_ANGLE

KIND = ElementKind(
    name="rotational_spring", family=ROTATIONAL,
    description="rotational spring, τ = k (φ − φ0)",
    coefficient=Parameter("k", "N.m/rad", "rotational stiffness", minimum=0.0),
    free=Parameter("angle", "rad", "free angle φ0 (default: the relative angle at t = 0)", required=False))


@law
def torque(row, phi, w):
    return row[COEFFICIENT] * (phi - row[FREE_ANGLE])


@law
def energy(row, phi, w):
    d = phi - row[FREE_ANGLE]
    return 0.5 * row[COEFFICIENT] * d * d
