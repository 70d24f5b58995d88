"""Inerter: F = b d²L/dt², tension positive (paper Eq. 9), or, without the centripetal term,
the 1D law F = b r̈·r̂ (Eq. 8); with a device (:mod:`inerter.elements.device`), plus its friction,
channel damping and end-stop forces, and b replaced by b/η_f or b η_b where it declares a screw
efficiency (smoothed at a turnaround over the velocity scale it declares).

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
from inerter.elements.layout import CENTRIPETAL, COEFFICIENT, DEVICE, SERIES

KIND = ElementKind(
    name="inerter", family=TRANSLATIONAL, equation="Eq. 9 (Eq. 8 without the centripetal term)",
    description="ideal inerter, F = b d²L/dt², or a device",
    coefficient=Parameter("b", "kg", "inertance", minimum=0.0),
    device=device.EFFECTS)


@law
def inertance(row, Ldot):
    """b: the factor of gᵀ q̈ in F, which goes into the mass matrix (Eq. 33); with a device
    :func:`device.inertance`: 0 where a series connection carries the force (device.compliance: the
    force is a law of the state), b_eff = b (1 + λ) at the stroke rate L̇ with a screw efficiency
    (device.efficiency: b/η_f driven, b η_b back-driving)."""
    if rarely(row[DEVICE] != 0.0):
        return device.inertance(row, Ldot)
    return row[COEFFICIENT]


@law
def convective(row, L, an, perp2):
    """L̈ − gᵀq̈ = a_n·r̂ + |ṙ⊥|²/L (Eq. 9), or a_n·r̂ without the centripetal term (Eq. 8)."""
    term = an
    if row[CENTRIPETAL] != 0.0:
        term += perp2 / L
    return term


@law
def force(row, L, Ldot, an, perp2):
    """F − b gᵀ q̈ = b (a_n·r̂ + |ṙ⊥|²/L) (Eq. 9), or b a_n·r̂ without the centripetal term
    (Eq. 8), plus a declared device's forces. `an` is a_n·r̂, `perp2` is |ṙ|² − L̇² = |ṙ⊥|². With
    series compliance the inertial part is carried by the series connection (:func:`state_force`);
    with a screw efficiency it is b_eff (a_n·r̂ + |ṙ⊥|²/L), b_eff = :func:`inertance`."""
    F = inertance(row, Ldot) * convective(row, L, an, perp2)
    if rarely(row[DEVICE] != 0.0):
        F += device.force(row, L, Ldot)
    return F


@law
def energy(row, L, Ldot):
    """Kinetic energy ½ b L̇² (and a device's end stops' elastic energy); with series compliance
    the inerter's energy is a law of the state (:func:`state_energy`)."""
    E = 0.5 * row[COEFFICIENT] * Ldot * Ldot
    if rarely(row[DEVICE] != 0.0):
        if row[SERIES] != 0.0:
            E = 0.0
        E += device.energy(row, L)
    return E


@law
def extra_outputs(row, L, Ldot, an, perp2, gq, x, out, k):
    """A device's outputs at out[k], ... (:func:`device.outputs`, with L̈ = gᵀq̈ + :func:`convective`
    at the solved accelerations, `gq` = gᵀq̈; `x` the element's internal states); returns the index
    after them."""
    if rarely(row[DEVICE] != 0.0):
        return device.outputs(row, L, Ldot, gq + convective(row, L, an, perp2), x, out, k)
    return k


@law
def settle(row, L, Ldot, an, perp2, gq):
    """A screw efficiency's mode set from the solved accelerations (`gq` = gᵀq̈): 1 where it changed
    (:func:`device.settle`; the engine calls it only where row[EFFICIENCY] is set)."""
    return device.settle(row, Ldot, gq + convective(row, L, an, perp2))


# Laws of an element's internal states x (a view of z; only a device declares them), which the
# kernels call only for an element that has some (el_int[e, STATES] > 0).
@law
def state_force(row, L, Ldot, x):
    """The axial force the internal states carry (the series connection's, N)."""
    return device.state_force(row, x)


@law
def state_energy(row, L, Ldot, x):
    """The energy held in the internal states (½ b u̇² + ½ k_c d² with series compliance, J)."""
    return device.state_energy(row, Ldot, x)


@law
def state_rates(row, L, Ldot, an, perp2, gq, x, dx):
    """dx = ẋ once q̈ is solved (`gq` = gᵀq̈): :func:`device.state_rates` with
    L̈ = gᵀq̈ + :func:`convective`."""
    device.state_rates(row, L, Ldot, gq + convective(row, L, an, perp2), x, dx)


def extra_output_names(spec) -> tuple[tuple[str, str, str], ...]:
    """(suffix, unit, description) of the outputs :func:`extra_outputs` writes for scene element
    `spec`: its device's, if it declares one."""
    dev = getattr(spec, "device", None)
    return dev.outputs() if dev is not None else ()
