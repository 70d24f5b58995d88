"""Inerter: F = b d²L/dt², tension positive (paper Eq. 9), or, without the centripetal term,
the 1D law F = b r̈·r̂ (Eq. 8); with a device (:mod:`inerter.elements.device`), plus its friction,
channel damping and end-stop forces.

With r = r_b − r_a, L = |r|, r̂ = r/L and r̈ = H q̈ + a_n (Eqs. 18-19):

    d²L/dt² = r̈·r̂ + (ṙ·ṙ − (ṙ·r̂)²)/L = gᵀ q̈ + a_n·r̂ + |ṙ⊥|²/L,     g = Hᵀ r̂.

The part b gᵀ q̈ goes into the mass matrix, M_I = b g gᵀ (Eq. 33): :func:`inertance` is b. The rest,
b (a_n·r̂ + |ṙ⊥|²/L), is :func:`force`, the right side's Q_Iv (Eq. 31), to which a declared device
adds its forces of L and L̇ (a branch an ideal inerter, ``row[DEVICE] == 0``, never takes: marked
:func:`~inerter.elements.base.rarely` and calling the device's laws without inlining them, it
leaves the kernels' loops as fast as without it). Its
kinetic energy is ½ b L̇² (the correct model is Lagrangian, Sec. 2.2); the model without the term
has none, and its energy output keeps the same ½ b L̇² for comparison. A device's end stops add
their elastic energy.

The inertance is the scene's ``b``, or what the device's flywheel (b = J (2π/p)²) or fluid channel
(b = ρ ℓ A_p²/A_c) gives: the scene reader computes it (:meth:`device.Device.inertance`).
"""
from inerter.elements import device
from inerter.elements.base import TRANSLATIONAL, ElementKind, Parameter, law, rarely
from inerter.elements.layout import CENTRIPETAL, COEFFICIENT, DEVICE

KIND = ElementKind(
    name="inerter", family=TRANSLATIONAL, equation="Eq. 9 (Eq. 8 without the centripetal term)",
    description="ideal inerter, F = b d²L/dt², or a device",
    coefficient=Parameter("b", "kg", "inertance", minimum=0.0),
    device=device.EFFECTS)


@law
def inertance(row):
    """b: the factor of gᵀ q̈ in F, which goes into the mass matrix (Eq. 33)."""
    return row[COEFFICIENT]


@law
def force(row, L, Ldot, an, perp2):
    """F − b gᵀ q̈ = b (a_n·r̂ + |ṙ⊥|²/L) (Eq. 9), or b a_n·r̂ without the centripetal term
    (Eq. 8), plus a declared device's forces. `an` is a_n·r̂, `perp2` is |ṙ|² − L̇² = |ṙ⊥|²."""
    term = an
    if row[CENTRIPETAL] != 0.0:
        term += perp2 / L
    F = row[COEFFICIENT] * term
    if rarely(row[DEVICE] != 0.0):
        F += device.force(row, L, Ldot)
    return F


@law
def energy(row, L, Ldot):
    """Kinetic energy ½ b L̇² (and a device's end stops' elastic energy)."""
    E = 0.5 * row[COEFFICIENT] * Ldot * Ldot
    if rarely(row[DEVICE] != 0.0):
        E += device.energy(row, L)
    return E


@law
def extra_outputs(row, L, Ldot, out, k):
    """A device's outputs at out[k], ... (:func:`device.outputs`); returns the index after them."""
    if rarely(row[DEVICE] != 0.0):
        return device.outputs(row, L, Ldot, out, k)
    return k


def extra_output_names(spec) -> tuple[tuple[str, str, str], ...]:
    """(suffix, unit, description) of the outputs :func:`extra_outputs` writes for scene element
    `spec`: its device's, if it declares one."""
    dev = getattr(spec, "device", None)
    return dev.outputs() if dev is not None else ()
