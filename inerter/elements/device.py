"""An inerter's device: the effects of a real inerter that are laws of its terminal distance and
of the element's internal states.

An ideal inerter's force is b d²L/dt² (paper Eq. 9). A real device adds forces of its own; the
flywheel, friction, end stops and fluid channel depend on the terminal distance L and its rate L̇
only, so each is one more scalar term of the inerter's law (:mod:`inerter.elements.inerter`), the
same in 2D and 3D, and enters the equations as the ideal law's rest does: Q −= F g with g = Hᵀ r̂
(Eqs. 29, 31). Series compliance, backlash and the dissipated energy add internal states x of the
element (its slice of z in the engine's state y = [q, v, z]), with their own laws
(:func:`state_force`, :func:`state_energy`, :func:`state_rates`). A scene declares the effects per
element (``[elements.NAME.device.EFFECT]``, :data:`EFFECTS`); an element without a device has
``row[DEVICE] == 0`` and its law never enters the branch that evaluates them.

Sign convention: the axial force F is tension positive, like every translational element's; a
dissipative force opposes the stroke rate, F·L̇ ≥ 0.

**Flywheel** (``device.flywheel``; Smith 2002, IEEE Trans. Autom. Control 47(10) 1648-1662,
Sec. III; Wang & Su 2008, Veh. Syst. Dyn. 46(7) 575-595): a flywheel of axial moment of inertia J
spun by a ball screw of lead p (stroke per revolution) turns at ω = (2π/p) L̇, so its kinetic
energy ½ J ω² = ½ J (2π/p)² L̇² is that of an inerter of inertance

    b = J (2π/p)²,

or b = J n² for a rack and pinion or gear train that turns the flywheel by n radians per metre of
stroke. Only this axial part is a law of L̇: the flywheel's transverse inertia and mass
(``device.flywheel.transverse_inertia``, ``mass``, ``centre``), the housing and the rod as rigid
bodies carried by the terminals (``device.housing``, ``device.rod``) and, in 3D, the housing's
mount that makes its spin and the flywheel's gyroscopic moments part of the kinetic energy
(``device.mount``) add a mass-matrix block beyond b g gᵀ: :mod:`inerter.elements.device_inertia`,
where they are derived.

**Friction** (``device.friction``): Coulomb friction F_c and viscous friction c_f on the stroke
rate, with the sign function regularised by a hyperbolic tangent of velocity scale v_s,

    F_f = F_c tanh(L̇ / v_s) + c_f L̇

(the "tanh" model of Pennestrì, Rossi, Salvini & Valentini 2016, Nonlinear Dyn. 83 1785-1801,
Sec. 2; friction in ball-screw inerters: Wang & Su 2008). |F_f − F_c sgn L̇ − c_f L̇| ≤ 2 F_c
e^{−2|L̇|/v_s}: the law approaches Coulomb's as v_s → 0, and near L̇ = 0 it is a viscous damper of
coefficient F_c/v_s, so a sticking phase is stiff (eigenvalue ≈ −F_c/(m v_s) for an effective
mass m): integrate small v_s with an implicit method (Radau, BDF). Its dissipation function is
D_f = F_c v_s ln cosh(L̇/v_s) + ½ c_f L̇², F_f = ∂D_f/∂L̇.

**Efficiency** (``device.efficiency``; Wen et al. 2017, J. Vibroeng. 19(6), friction in
ball-screw inerters; Smith 2020, "The inerter: a retrospective", on back-driving): the screw passes
only a part of the force through: η_f of it reaches the flywheel when the terminals drive it, η_b of
the flywheel's reaches the terminals when it drives them (0 < η ≤ 1). With the flywheel's kinetic
energy kept at ½ b L̇², the terminal force is

    F = b_eff L̈,   b_eff = b/η_f  where L̇·L̈ > 0 (flywheel driven: speeding up),
                   b_eff = b η_b  where L̇·L̈ < 0 (flywheel back-driving the terminals: slowing down),

L̈ that of Eq. 9 (or Eq. 8, without the centripetal term). The switch between the two is written
with the stored mode s = sign(L̈) (``EFFICIENCY_MODE``) and the direction

    τ = s tanh(L̇/v_s)    (v_s > 0: ``velocity_scale``),    τ = s sgn(L̇), and +1 at L̇ = 0   (v_s = 0),
    α = 1/η_f − 1 ≥ 0,  β = 1 − η_b ≥ 0,  λ(τ) = τ ((α+β)/2 + τ (α−β)/2),  b_eff = b (1 + λ(τ))

(:func:`efficiency_direction`, :func:`efficiency_factor`): λ(1) = α, λ(−1) = −β, so |L̇| ≫ v_s
gives b/η_f (τ → sgn(L̇L̈) = 1) and b η_b (τ → −1), and L̇ = 0 gives b (v_s > 0; b/η_f, driven,
with the exact switch of v_s = 0).
For |τ| ≤ 1 the bracket is ≥ (α+β)/2 − |α−β|/2 = min(α, β) ≥ 0, so sign λ = sign τ = sign(L̇ L̈),
and 1 + λ ≥ 1 − β = η_b > 0. The work the terminals do, F L̇ = b_eff L̈ L̇, exceeds the flywheel's
d(½ b L̇²)/dt = b L̈ L̇ by the lost power

    (b_eff − b) L̈ L̇ = b λ(τ) L̈ L̇ ≥ 0

at every L̇ and every v_s (passive): part of p_loss (:func:`efficiency_loss`), and of e_loss where
``dissipated_energy`` is declared. b_eff is the inertance the mass matrix of Eq. (33) takes
(:func:`inertance`, a law of the row and L̇).

The mode depends on L̈ = gᵀq̈ + a_n·r̂ + |ṙ⊥|²/L, which holds the unknown accelerations: an
algebraic loop, resolved exactly. Write the augmented system of Eq. (33) without the element as
K₀ x = f₀ and G = [g; 0]; with it, (K₀ + b_eff G Gᵀ) x = f₀ − b_eff c G, c = L̈ − gᵀq̈. Then
x = x₀ − b_eff K₀⁻¹G L̈ with x₀ = K₀⁻¹f₀, and L̈ = Gᵀx + c gives

    L̈ (1 + b_eff s_P) = r,   s_P = Gᵀ K₀⁻¹ G = gᵀ P g ≥ 0,   r = Gᵀx₀ + c,

P the velocity block of K₀⁻¹, the inverse mass matrix projected on the joints' tangent space
(positive semidefinite; where K₀ is singular, the element's own inertance holding a coordinate,
the same follows in the limit of a small mass added there). So, b_eff > 0 in either mode (at the
state's L̇), sign(L̈) = sign(r) does not depend on it: the engine solves once in the mode of the
last call, computes the element's L̈, and where s disagrees with sign(L̈) it flips it
(:func:`settle`; kept where L̈ = 0, where b_eff L̈ = 0 in either) and solves again, which then
agrees: at most two solves for one such element. For several, each solve flips every element that
disagrees; the signs are coupled through P, so the engine checks and solves again up to
:data:`MODE_SOLVES` times and, if the modes still do not settle, solves once more in the modes last
set, keeps that solve (its force and the stored modes agree; its L̈ may ask for other modes) and
counts the call (``Kernel.unsettled``; a run's count is in ``run.extra["unsettled"]``, and its
result warns of it). The numpy path (``Mechanism.accelerations``) does the same. A scene without an
efficiency takes no extra solve (the engine tests a count of such elements, ``dims[EFFICIENT]``).

Where L̈ changes sign (s flips) the force is continuous: b_eff stays bounded and b_eff L̈ → 0 from
both sides. A turnaround, L̇ = 0 with L̈ ≠ 0, keeps s, so b_eff is a smooth function of L̇ there
for v_s > 0: near L̇ = 0 the law is b L̈ + b (α+β)/2 |L̈| L̇/v_s, a viscous damper of coefficient
b (α+β)|L̈|/(2 v_s), and the change of b_eff takes the time ~ v_s/|L̈|, which the integrator's
steps resolve without collapsing (the tanh regularisation of the friction above, Pennestrì et al.
2016; docs/benchmarks/efficiency_steps.md: the smallest step near a peak ≥ 1e-2 of the median).
The regularised run converges to the exact switch's as v_s → 0, at first order on the 1-DOF closed
form (error ≈ 0.037 s · v_s there: the change of b_eff lags the turnaround by ~v_s/|L̈|, a phase
shift of order v_s; tests/test_device_efficiency.py). With v_s = 0 (the default) b_eff jumps from b η_b to b/η_f at a turnaround,
and F and q̈ jump, as at an unregularised Coulomb reversal: the integrator meets the jump by its
error control alone, which rejects and shrinks the steps that straddle it (to ~1e-11 s at rtol
1e-10; no event: the state stays continuous, only q̈ jumps). A mount does not go with the
efficiency (:func:`check_device`: its gyroscopic block spins the flywheel with b, not b_eff). The
linearisation refuses the efficiency (no energy or dissipation function gives the mode's
dependence on sign(L̈)); the oracle derives it from this definition on its own (every sign
assignment of the modes tried, inerter/oracle/efficiency.py).

*In series* (with ``device.compliance``, and so with backlash): the screw turns with the inerter's
own stroke u (u̇ = L̇ − ṡ, a state), driven by the series force F less the drag F_d(u̇) on it. The
same law, on u instead of L, reads

    b_eff ü = F − F_d(u̇),   b_eff = b (1 + λ(τ)),   τ = σ tanh(u̇/v_s)  (v_s = 0: σ sgn(u̇), +1 at u̇ = 0),
    σ = sign(F − F_d(u̇)) = sign(ü)

(:func:`series_drive`; σ = +1 where F − F_d = 0, where ü = 0 in either mode). It is explicit: F
and F_d are laws of the state, and b_eff > 0, so the sign of ü is that of the known right side, and
no algebraic loop arises; no mode is stored and no solve repeated (the element leaves the mass
matrix, inertance 0, and ``dims[EFFICIENT]`` counts only the rigid ones, :func:`mode_solved`).
The flywheel keeps ½ b u̇²; the power the series node hands the screw, (F − F_d) u̇ = b_eff ü u̇,
exceeds d(½ b u̇²)/dt = b ü u̇ by

    b λ(τ) ü u̇ ≥ 0

(sign λ = sign τ = sign(u̇ ü), as in the rigid case: passive at every u̇ and v_s), part of p_loss
and e_loss (:func:`efficiency_power`). The terminals carry F, as without the efficiency, and
``E.mode`` = (1 + τ)/2 takes this τ. η_f = η_b = 1 gives b_eff = b exactly, so the compliance
alone.

**End stops** (``device.end_stops``): stroke limits L_min and L_max. Past one, by the penetration
δ = L_min − L (or L − L_max) > 0 at the rate δ̇, a Hunt-Crossley contact force pushes back:

    N = max(0, k_s δⁿ + c_s δⁿ δ̇),

(Hunt & Crossley 1975, J. Appl. Mech. 42(2) 440-445; the clip at zero, so that the contact never
pulls, as in Marhefka & Orin 1999, IEEE Trans. Syst. Man Cybern. A 29(6) 566-572). The damping
acts only in contact and vanishes with δ, so the force is continuous at first touch. F = −N at the
lower stop (compression), +N at the upper one. The elastic part stores k_s δⁿ⁺¹/(n+1) (in the
element's energy); the rest, (N − k_s δⁿ) δ̇ ≥ 0, is dissipated. For a target coefficient of
restitution e at impact speed v⁻, Lankarani & Nikravesh 1990 (J. Mech. Des. 112 369-376) give
c_s ≈ 3 k_s (1 − e²)/(4 v⁻).

**Fluid inerter** (``device.fluid``; Swift, Smith, Glover, Papageorgiou, Gartner & Houghton 2013,
Int. J. Control 86(11) 2035-2051): a piston of area A_p drives fluid of density ρ through a helical
channel of length ℓ and area A_c at the speed u = (A_p/A_c) L̇; the channel fluid's kinetic energy
½ ρ ℓ A_c u² = ½ (ρ ℓ A_p²/A_c) L̇² is that of an inerter of inertance

    b = ρ ℓ A_p² / A_c,

and the channel's losses, linear and quadratic in the flow rate A_p L̇, give

    F_d = c₁ L̇ + c₂ L̇ |L̇|.

Under a harmonic stroke X sin ωt the quadratic term dissipates (8/3) c₂ ω² X³ per cycle, the
energy π c_eq ω X² of the equivalent viscous damping c_eq = 8/(3π) c₂ ω X.

**Series compliance** (``device.compliance``; the screw's and mounts' elasticity, Wang & Su 2008,
Sec. 3): a spring k_c (and damper c_c) in series with the inerter, terminal a — spring — node —
inerter — terminal b, the node massless. Its deflection s and rate ṡ are internal states of the
element (z in the engine's state y = [q, v, z]). The force through the connection,

    F = k_c s + c_c ṡ,

is known from the state, so the bodies feel it as a spring's (Q −= F g): the element leaves the
mass matrix (its inertance is 0 there). The inerter's own stroke is u = L − s (up to a constant),
and its law (Eq. 9) along the same line, b ü = F − F_d(u̇), with ü = L̈ − s̈ and
L̈ = gᵀq̈ + a_n·r̂ + |ṙ⊥|²/L (the centripetal term included where the scene has it: the node moves
on the line between the terminals, so the inerter's stroke acceleration is the distance's second
derivative less s̈), gives

    s̈ = L̈ − (F − F_d(u̇)) / b,

evaluated once q̈ is solved (:func:`state_rates`; b_eff for b with a screw efficiency, "Efficiency"
above, the series case). The device's other effects on the stroke act on
the inerter's own stroke rate u̇ = L̇ − ṡ: the flywheel spins at n u̇, friction and channel damping
are F_d(u̇) = F_f(u̇) + F_fluid(u̇) (they resist the screw's motion, not the terminals'); the end
stops stay on the terminal distance L (the housing's stroke limits), in parallel with the whole
series connection. Kinetic and elastic energy ½ b u̇² + ½ k_c s²; dissipated power c_c ṡ² + F_d u̇.
b must be > 0.

**Backlash** (``device.backlash``; Wang & Su 2008, Sec. 3, the free play of the ball screw's
nut and the mounts): a dead zone of total width Δ in the series connection. The spring acts on the
deflection beyond the gap, d = s − sgn(s) Δ/2 for |s| > Δ/2 (engaged), 0 inside it (the inerter
free-wheels, F = 0):

    F = k_c d + c_c ṡ engaged, clipped to 0 where it would pull the engaged sides apart (as the end
    stops' contact), F = 0 in the gap.

The spring force is continuous at engagement; the damping's part c_c ṡ jumps there (an impact): the
integrator's error control shortens its steps at the switch (no regularisation; the hard case of
docs/hard_cases.md). Output ``E.engaged`` (1 engaged, 0 in the gap); stored energy ½ k_c d².

**Dissipated energy** (``device.dissipated_energy``, no parameters): the integral of the device's
dissipated power, ż = p_loss, as one more internal state (output ``E.e_loss``, J), so that energy
+ e_loss equals the initial energy to the integrator's tolerance. Opt in: a state changes the
integrator's error norm, and so the steps.

The device's outputs (``E.w_flywheel``, ``E.f_friction``, ``E.f_fluid``, ``E.f_stop``, ``E.p_loss``,
``E.s_series``, ``E.engaged``, ``E.mode``, ``E.e_loss``) are written by :func:`outputs` in the order
:meth:`Device.outputs` names them.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

from inerter.common.inlined import not_inlined
from inerter.elements.base import Parameter, law
from inerter.elements.layout import (BACKLASH, COEFFICIENT, COULOMB, DEVICE, EFFICIENCY, EFFICIENCY_MODE,
                                     EFFICIENCY_SCALE, ETA_BACKWARD, ETA_FORWARD, FLUID, FLUID_LINEAR,
                                     FLUID_QUADRATIC, FLYWHEEL_AXIAL, FLYWHEEL_CENTRE, FLYWHEEL_MASS,
                                     FLYWHEEL_RATIO, FRICTION, GAP, HOUSING_AXIAL, HOUSING_CENTRE,
                                     HOUSING_MASS, INERTIA, LOSS, MOUNT, MOUNT_AXIS, ROD_CENTRE, ROD_MASS,
                                     SERIES, SERIES_DAMPING, SERIES_STIFFNESS, STOPS, STOP_DAMPING,
                                     STOP_EXPONENT, STOP_MAX, STOP_MIN, STOP_STIFFNESS, TRANSVERSE,
                                     VELOCITY_SCALE, VISCOUS)


# ------------------------------------------------------------------------------------------------
# The laws (scalar arithmetic on the element's row). The effects' laws are inlined into the three
# entry points below, and those are called, not inlined, from the inerter's law: an ideal inerter's
# kernels then hold only the test of row[DEVICE] and a call never made, not the device's code.
# ------------------------------------------------------------------------------------------------
#: How many times an evaluation checks the screw efficiencies' modes against a solve of Eq. (33) and
#: solves again (the engine's and the numpy path's): once suffices for one such element, whose sign of
#: L̈ does not depend on its mode.
MODE_SOLVES = 8


def entry(fn):
    """Compile a device law that the inerter's law calls without inlining it (cached on disk)."""
    return not_inlined(fn)


@law
def friction(row, Ldot):
    """F_f = F_c tanh(L̇/v_s) + c_f L̇ (N, tension positive)."""
    return row[COULOMB] * math.tanh(Ldot / row[VELOCITY_SCALE]) + row[VISCOUS] * Ldot


@law
def fluid_damping(row, Ldot):
    """F_d = c₁ L̇ + c₂ L̇|L̇| (N, tension positive): the helical channel's losses."""
    return row[FLUID_LINEAR] * Ldot + row[FLUID_QUADRATIC] * Ldot * abs(Ldot)


@law
def end_stop(row, L, Ldot):
    """(F, p): the end stops' axial force (N, tension positive: −N at the lower stop, +N at the
    upper) and the power dissipated in the contact (W), N = max(0, k_s δⁿ + c_s δⁿ δ̇)."""
    d = row[STOP_MIN] - L
    rate = -Ldot
    sign = -1.0
    if not d > 0.0:
        d = L - row[STOP_MAX]
        rate = Ldot
        sign = 1.0
        if not d > 0.0:
            return 0.0, 0.0
    dn = d ** row[STOP_EXPONENT]
    elastic = row[STOP_STIFFNESS] * dn
    damping = row[STOP_DAMPING] * dn * rate
    N = elastic + damping
    if N < 0.0:                       # the contact would pull: it lets go, and its stored energy is lost
        return 0.0, -elastic * rate
    return sign * N, damping * rate


@law
def stop_energy(row, L):
    """The end stops' elastic energy k_s δⁿ⁺¹/(n+1) (J)."""
    d = max(row[STOP_MIN] - L, L - row[STOP_MAX])
    if not d > 0.0:
        return 0.0
    n = row[STOP_EXPONENT]
    return row[STOP_STIFFNESS] * d ** (n + 1.0) / (n + 1.0)


@law
def efficiency_direction(row, sign, rate):
    """τ = sign · tanh(rate/v_s): +1 where the screw drives the flywheel (rate and acceleration of
    one sign, `sign` the acceleration's), −1 where the flywheel drives it, between inside the
    regularisation |rate| ≲ v_s; with v_s = 0 the exact switch τ = sign · sgn(rate), and τ = +1
    (driven) at rate = 0. Rigid: the stroke rate L̇ and the stored mode s = sign(L̈)
    (:func:`rigid_direction`); in series: the inerter's own u̇ and σ = sign(ü) (:func:`series_drive`)."""
    scale = row[EFFICIENCY_SCALE]
    if scale > 0.0:
        return sign * math.tanh(rate / scale)
    if rate == 0.0:
        return 1.0
    return sign if rate > 0.0 else -sign


@law
def rigid_direction(row, Ldot):
    """τ of a rigid device: :func:`efficiency_direction` at L̇ with the stored mode
    s = row[EFFICIENCY_MODE], the sign of L̈ the last solve settled on."""
    return efficiency_direction(row, row[EFFICIENCY_MODE], Ldot)


@law
def efficiency_factor(row, tau):
    """b_eff / b = 1 + λ(τ), λ(τ) = τ ((α+β)/2 + τ (α−β)/2), α = 1/η_f − 1, β = 1 − η_b, at the
    direction τ (:func:`efficiency_direction`): 1/η_f driven (τ = 1), η_b back-driving (τ = −1);
    with v_s = 0 those two numbers as such (the exact switch)."""
    if row[EFFICIENCY_SCALE] == 0.0:
        return 1.0 / row[ETA_FORWARD] if tau > 0.0 else row[ETA_BACKWARD]
    alpha = 1.0 / row[ETA_FORWARD] - 1.0
    beta = 1.0 - row[ETA_BACKWARD]
    return 1.0 + tau * (0.5 * (alpha + beta) + tau * 0.5 * (alpha - beta))


@law
def efficiency_sign(row, Lddot):
    """The mode s the solved L̈ asks for: sign(L̈), the stored one where L̈ = 0."""
    if Lddot > 0.0:
        return 1.0
    if Lddot < 0.0:
        return -1.0
    return row[EFFICIENCY_MODE]


@law
def efficiency_power(row, tau, rate, accel):
    """The power the screw loses, (b_eff − b) ẍ ẋ = b λ(τ) ẍ ẋ (W), ẋ, ẍ the screw's stroke rate and
    acceleration (L̇, L̈ rigid; u̇, ü in series): ≥ 0 where sign τ = sign(ẋ ẍ) (sign λ = sign τ)."""
    return (efficiency_factor(row, tau) - 1.0) * row[COEFFICIENT] * accel * rate


@law
def efficiency_loss(row, Ldot, Lddot):
    """A rigid device's :func:`efficiency_power` at L̇, L̈ in the stored mode (W): ≥ 0 where the
    stored s is sign(L̈)."""
    return efficiency_power(row, rigid_direction(row, Ldot), Ldot, Lddot)


@law
def mode_solved(row):
    """Whether the element has a screw efficiency whose mode the solves of Eq. (33) settle: a rigid
    one (in series the mode is a law of the state, :func:`series_drive`)."""
    return row[EFFICIENCY] != 0.0 and row[SERIES] == 0.0


@law
def drag(row, ud):
    """F_d(u̇): friction and channel damping on the stroke rate u̇ (N, tension positive)."""
    F = 0.0
    if row[FRICTION] != 0.0:
        F += friction(row, ud)
    if row[FLUID] != 0.0:
        F += fluid_damping(row, ud)
    return F


@law
def deflection(row, s):
    """The series spring's deflection beyond the backlash gap: s, or s ∓ Δ/2 outside the gap and 0
    inside it (m)."""
    if row[BACKLASH] == 0.0:
        return s
    half = 0.5 * row[GAP]
    if s > half:
        return s - half
    if s < -half:
        return s + half
    return 0.0


@law
def series_force(row, s, sdot):
    """(F, engaged): the force through the series connection, k_c d + c_c ṡ (N, tension positive;
    d = :func:`deflection`), and 1.0 where the backlash gap is closed (0.0 inside it). With backlash
    the force never pulls the engaged sides apart (clipped to 0, as the end stops')."""
    d = deflection(row, s)
    if row[BACKLASH] != 0.0 and d == 0.0:
        return 0.0, 0.0
    F = row[SERIES_STIFFNESS] * d + row[SERIES_DAMPING] * sdot
    if row[BACKLASH] != 0.0 and F * d < 0.0:
        return 0.0, 1.0
    return F, 1.0


@law
def stroke_rate(row, Ldot, x):
    """The inerter's own stroke rate: u̇ = L̇ − ṡ with series compliance, L̇ without."""
    if row[SERIES] != 0.0:
        return Ldot - x[1]
    return Ldot


@law
def series_drive(row, Ldot, x):
    """(ü, τ) in a series connection: the inerter's own stroke acceleration from b_eff ü = F − F_d(u̇)
    (F = :func:`series_force`, u̇ = L̇ − ṡ), b_eff = b without an efficiency (τ = 1 then), and with
    one b (1 + λ(τ)) at τ = :func:`efficiency_direction` of u̇ and σ = sign(F − F_d(u̇)) = sign(ü)
    (b_eff > 0, so no loop; σ = +1 where F − F_d = 0, ü = 0 in either mode)."""
    ud = Ldot - x[1]
    push = series_force(row, x[0], x[1])[0] - drag(row, ud)
    if row[EFFICIENCY] == 0.0:
        return push / row[COEFFICIENT], 1.0
    tau = efficiency_direction(row, 1.0 if push >= 0.0 else -1.0, ud)
    return push / (row[COEFFICIENT] * efficiency_factor(row, tau)), tau


@law
def loss(row, L, Ldot, Lddot, x):
    """The power the device dissipates (W, ≥ 0): friction and channel damping F_d(u̇) u̇, the
    contacts' damping, the series connection's (F − k_c d) ṡ (c_c ṡ², or the stored energy a
    clipped contact lets go) and the screw's efficiency loss b λ ẍ ẋ, on L̇, L̈ rigid (`Lddot` = L̈)
    and on u̇, ü in series (:func:`efficiency_power`)."""
    p = 0.0
    ud = Ldot
    if row[SERIES] != 0.0:
        F, engaged = series_force(row, x[0], x[1])
        p += (F - row[SERIES_STIFFNESS] * deflection(row, x[0])) * x[1]
        ud = Ldot - x[1]
    p += drag(row, ud) * ud
    if row[STOPS] != 0.0:
        p += end_stop(row, L, Ldot)[1]
    if row[EFFICIENCY] != 0.0:
        if row[SERIES] != 0.0:
            udd, tau = series_drive(row, Ldot, x)
            p += efficiency_power(row, tau, ud, udd)
        else:
            p += efficiency_loss(row, Ldot, Lddot)
    return p


@entry
def force(row, L, Ldot):
    """The device's axial force on the terminals beyond b L̈ (N, tension positive): friction and
    channel damping on L̇ and the end stops, each where declared; with series compliance only the
    end stops (the rest acts through the series connection: :func:`state_force`)."""
    F = 0.0
    if row[SERIES] == 0.0:
        F += drag(row, Ldot)
    if row[STOPS] != 0.0:
        F += end_stop(row, L, Ldot)[0]
    return F


@entry
def inertance(row, Ldot):
    """The factor of gᵀq̈ in the element's force: 0 with series compliance (the series connection
    carries the force), b_eff = b (1 + λ) with an efficiency (:func:`efficiency_factor`, at the
    stroke rate L̇), else b."""
    if row[SERIES] != 0.0:
        return 0.0
    if row[EFFICIENCY] != 0.0:
        return row[COEFFICIENT] * efficiency_factor(row, rigid_direction(row, Ldot))
    return row[COEFFICIENT]


@entry
def settle(row, Ldot, Lddot):
    """Set the efficiency's mode s to sign(L̈) (:func:`efficiency_sign`; `Lddot` = L̈ from the solved
    accelerations); 1 where that changed b_eff (the solve is to be repeated), else 0 (at L̇ = 0
    b_eff does not depend on s). In series nothing is stored (0: the mode is a law of the state,
    :func:`series_drive`)."""
    if not mode_solved(row):
        return 0
    mode = efficiency_sign(row, Lddot)
    if mode == row[EFFICIENCY_MODE]:
        return 0
    before = efficiency_factor(row, rigid_direction(row, Ldot))
    row[EFFICIENCY_MODE] = mode
    return 1 if efficiency_factor(row, rigid_direction(row, Ldot)) != before else 0


@entry
def energy(row, L):
    """The energy the device stores beyond ½ b L̇²: the end stops' elastic energy (J)."""
    if row[STOPS] != 0.0:
        return stop_energy(row, L)
    return 0.0


@entry
def state_force(row, x):
    """The force its internal states carry to the terminals: the series connection's (N)."""
    if row[SERIES] != 0.0:
        return series_force(row, x[0], x[1])[0]
    return 0.0


@entry
def state_energy(row, Ldot, x):
    """With series compliance, the inerter's ½ b u̇² and the spring's ½ k_c d² (J; the element's
    ½ b L̇² is then left out)."""
    if row[SERIES] == 0.0:
        return 0.0
    ud = Ldot - x[1]
    d = deflection(row, x[0])
    return 0.5 * row[COEFFICIENT] * ud * ud + 0.5 * row[SERIES_STIFFNESS] * d * d


@entry
def state_rates(row, L, Ldot, Lddot, x, dx):
    """dx = ż of the element's internal states, once q̈ is known (`Lddot` = L̈ = gᵀq̈ + a_n·r̂ +
    |ṙ⊥|²/L): with series compliance (s, ṡ) ↦ (ṡ, L̈ − ü), ü = (F − F_d(u̇))/b_eff
    (:func:`series_drive`: b_eff = b without an efficiency); the dissipated energy's rate p_loss."""
    k = 0
    if row[SERIES] != 0.0:
        dx[0] = x[1]
        dx[1] = Lddot - series_drive(row, Ldot, x)[0]
        k = 2
    if row[LOSS] != 0.0:
        dx[k] = loss(row, L, Ldot, Lddot, x)


@entry
def outputs(row, L, Ldot, Lddot, x, out, k):
    """Write the device's outputs at out[k], out[k + 1], ... in the order of
    :meth:`Device.outputs` (flywheel speed; friction, channel and end-stop forces; dissipated
    power; series deflection, engagement; the efficiency's mode; dissipated energy) and return the
    index after them (`Lddot` = L̈ at the solved accelerations, for the efficiency's loss)."""
    ud = stroke_rate(row, Ldot, x)
    if row[FLYWHEEL_RATIO] != 0.0:
        out[k] = row[FLYWHEEL_RATIO] * ud
        k += 1
    if row[FRICTION] != 0.0:
        out[k] = friction(row, ud)
        k += 1
    if row[FLUID] != 0.0:
        out[k] = fluid_damping(row, ud)
        k += 1
    if row[STOPS] != 0.0:
        out[k] = end_stop(row, L, Ldot)[0]
        k += 1
    if (row[FRICTION] != 0.0 or row[FLUID] != 0.0 or row[STOPS] != 0.0 or row[SERIES] != 0.0
            or row[EFFICIENCY] != 0.0):
        out[k] = loss(row, L, Ldot, Lddot, x)
        k += 1
    if row[SERIES] != 0.0:
        out[k] = x[0]
        k += 1
        if row[BACKLASH] != 0.0:
            out[k] = series_force(row, x[0], x[1])[1]
            k += 1
    if row[EFFICIENCY] != 0.0:
        tau = series_drive(row, Ldot, x)[1] if row[SERIES] != 0.0 else rigid_direction(row, Ldot)
        out[k] = 0.5 * (1.0 + tau)
        k += 1
    if row[LOSS] != 0.0:
        out[k] = x[2 if row[SERIES] != 0.0 else 0]
        k += 1
    return k


# ------------------------------------------------------------------------------------------------
# The effects a scene may declare, and a declared device
# ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Effect:
    """One device effect as a scene declares it (``elements.NAME.device.<name>``): its parameters
    with units and physical ranges, the literature it follows, a check of how its parameters go
    together (``check(values)`` → None or (key, value, expected, problem)) and, for an effect that
    sets the inertance, ``inertance(values)``."""
    name: str
    description: str
    citation: str
    parameters: tuple[Parameter, ...]
    check: Callable | None = None
    inertance: Callable | None = None
    dimensions: tuple = (2, 3)
    why_not_2d: str = ""


def _one_of(values, keys, what):
    given = [k for k in keys if values.get(k) is not None]
    if len(given) != 1:
        return (keys[0] if not given else given[1], [values.get(k) for k in keys],
                f"exactly one of {' or '.join(keys)} ({what})", "none given" if not given else "both given")
    return None


def _flywheel_ratio(values) -> float:
    """The flywheel's angle per unit of stroke (rad/m): 2π/p for a ball screw of lead p."""
    return 2.0 * math.pi / values["lead"] if values.get("lead") is not None else values["ratio"]


#: The fields that give a friction force (velocity_scale only shapes the Coulomb part).
FRICTION_FORCES = "coulomb (N) with its velocity_scale (m/s), or viscous (N.s/m)"


def _check_friction(values):
    if values.get("coulomb") is None and values.get("viscous") is None:
        if values.get("velocity_scale") is not None:       # v_s alone: a scale of no force
            return ("velocity_scale", values["velocity_scale"], FRICTION_FORCES,
                    "no friction given (velocity_scale alone adds none)")
        return ("coulomb", None, FRICTION_FORCES, "no friction given")
    if values.get("coulomb") is None and values.get("velocity_scale") is not None:
        return ("velocity_scale", values["velocity_scale"], "coulomb (N) beside it (v_s regularises the Coulomb "
                "friction only), or no velocity_scale", "velocity_scale without coulomb")
    if values.get("coulomb") is not None and values.get("velocity_scale") is None:
        return ("velocity_scale", None, "the regularisation's velocity scale v_s > 0 (m/s) with coulomb",
                "missing field")
    return None


def _check_stops(values):
    low, high = values.get("min"), values.get("max")
    if low is None and high is None:
        return ("min", None, "min (m) or max (m), or both", "no stroke limit given")
    if low is not None and high is not None and not low < high:
        return ("max", high, f"a longest terminal distance > min = {low:g} m", "out of range")
    return None


FLYWHEEL = Effect(
    "flywheel", "ball-screw (or geared) flywheel: b = J (2π/p)² or J n²",
    "Smith 2002, IEEE TAC 47(10), Sec. III; Wang & Su 2008, Veh. Syst. Dyn. 46(7)",
    (Parameter("inertia", "kg.m2", "the flywheel's moment of inertia J about its spin axis", minimum=0.0),
     Parameter("lead", "m", "ball-screw lead p: stroke per flywheel revolution", minimum=0.0, strict=True,
               required=False),
     Parameter("ratio", "rad/m", "flywheel angle per unit of stroke n (rack and pinion, gears)", minimum=0.0,
               strict=True, required=False),
     Parameter("transverse_inertia", "kg.m2", "the flywheel's moment of inertia about a diameter, through its "
               "centre", minimum=0.0, required=False),
     Parameter("mass", "kg", "the flywheel's mass", minimum=0.0, required=False),
     Parameter("centre", "m", "distance of the flywheel's centre from terminal a, along the device (0 where "
               "not given)", minimum=0.0, required=False)),
    check=lambda v: _one_of(v, ("lead", "ratio"), "ball screw or gear train"),
    inertance=lambda v: v["inertia"] * _flywheel_ratio(v) ** 2)

FRICTION_EFFECT = Effect(
    "friction", "Coulomb and viscous friction on dL/dt, F_c tanh(v/v_s) + c_f v",
    "Pennestrì et al. 2016, Nonlinear Dyn. 83, Sec. 2 (tanh regularisation); Wang & Su 2008",
    (Parameter("coulomb", "N", "Coulomb friction force F_c", minimum=0.0, required=False),
     Parameter("viscous", "N.s/m", "viscous friction coefficient c_f (0 where not given)", minimum=0.0,
               required=False),
     Parameter("velocity_scale", "m/s", "velocity scale v_s of the tanh regularisation", minimum=0.0,
               strict=True, required=False)),
    check=_check_friction)

END_STOPS = Effect(
    "end_stops", "stroke limits with a Hunt-Crossley contact, max(0, k_s δⁿ + c_s δⁿ dδ/dt)",
    "Hunt & Crossley 1975, J. Appl. Mech. 42(2); Marhefka & Orin 1999, IEEE Trans. SMC A 29(6)",
    (Parameter("min", "m", "shortest terminal distance L_min (lower stop)", minimum=0.0, required=False),
     Parameter("max", "m", "longest terminal distance L_max (upper stop)", minimum=0.0, strict=True,
               required=False),
     Parameter("stiffness", "N/m^n", "contact stiffness k_s", minimum=0.0),
     Parameter("damping", "N.s/m^(n+1)", "Hunt-Crossley contact damping c_s", minimum=0.0, required=False,
               default=0.0),
     Parameter("exponent", "1", "contact force exponent n (1: linear, 1.5: Hertz)", minimum=1.0, maximum=3.0,
               required=False, default=1.0)),
    check=_check_stops)

FLUID_EFFECT = Effect(
    "fluid", "helical-channel fluid inerter: b = ρ ℓ A_p²/A_c, damping c1 v + c2 v|v|",
    "Swift et al. 2013, Int. J. Control 86(11)",
    (Parameter("density", "kg/m3", "fluid density ρ", minimum=0.0, strict=True),
     Parameter("channel_length", "m", "helical channel length ℓ", minimum=0.0, strict=True),
     Parameter("channel_area", "m2", "channel cross-section A_c", minimum=0.0, strict=True),
     Parameter("piston_area", "m2", "effective piston area A_p", minimum=0.0, strict=True),
     Parameter("linear_damping", "N.s/m", "channel damping linear in the flow, c_1", minimum=0.0,
               required=False, default=0.0),
     Parameter("quadratic_damping", "N.s2/m2", "channel damping quadratic in the flow, c_2", minimum=0.0,
               required=False, default=0.0)),
    inertance=lambda v: v["density"] * v["channel_length"] * v["piston_area"] ** 2 / v["channel_area"])



def _body_part(name, end, what):
    return Effect(
        name, f"the {what} as a rigid body carried by terminal {end}, axisymmetric about the device's axis",
        "Smith 2002, IEEE TAC 47(10), Sec. III (ball-screw inerter: housing, screw, flywheel)",
        (Parameter("mass", "kg", f"the {what}'s mass", minimum=0.0),
         Parameter("centre", "m", f"distance of the {what}'s centre of mass from terminal {end}, along the device",
                   minimum=0.0, required=False, default=0.0),
         Parameter("transverse_inertia", "kg.m2", f"the {what}'s moment of inertia about a diameter through its "
                   "centre", minimum=0.0, required=False, default=0.0),
         Parameter("axial_inertia", "kg.m2", f"the {what}'s moment of inertia about the device's axis (it spins "
                   "with the housing: device.mount)", minimum=0.0, required=False, default=0.0)))


HOUSING = _body_part("housing", "a", "housing")
ROD = _body_part("rod", "b", "rod")

MOUNT_EFFECT = Effect(
    "mount", "the housing on a Hooke joint at terminal a (first axis fixed in a's body): its spin, the flywheel's "
    "gyroscopic moments", "Kane & Levinson 1985, Dynamics, Ch. 6; inerter.elements.device_inertia",
    (Parameter("axis", "1", "the Hooke joint's first axis a1, fixed in terminal a's body (its frame); singular "
               "where the device's axis is parallel to it", size=3),),
    dimensions=(3,), why_not_2d="in 2D the housing cannot spin about its in-plane axis: the planar constraint "
    "carries the flywheel's gyroscopic moment")


def _check_compliance(values):
    if not values["stiffness"] > 0.0 and not values["damping"] > 0.0:
        return ("stiffness", values["stiffness"], "stiffness > 0 (N/m) or damping > 0 (N.s/m)",
                "a series connection that carries no force")
    return None


COMPLIANCE = Effect(
    "compliance", "a spring k_c and damper c_c in series with the inerter, F = k_c s + c_c ds/dt (state s, ds/dt)",
    "Wang & Su 2008, Veh. Syst. Dyn. 46(7), Sec. 3 (the screw's elastic effect)",
    (Parameter("stiffness", "N/m", "series stiffness k_c", minimum=0.0),
     Parameter("damping", "N.s/m", "series damping c_c", minimum=0.0, required=False, default=0.0)),
    check=_check_compliance)

BACKLASH_EFFECT = Effect(
    "backlash", "a gap of total width Δ in the series connection: no force while |s| < Δ/2",
    "Wang & Su 2008, Veh. Syst. Dyn. 46(7), Sec. 3 (backlash of the ball screw)",
    (Parameter("gap", "m", "total free play Δ of the series connection", minimum=0.0),))

EFFICIENCY_EFFECT = Effect(
    "efficiency", "screw efficiency by the power flow's direction: b/η_f driven (L̇·L̈ > 0), b η_b back-driving, "
    "switched at a turnaround or smoothed over tanh(L̇/v_s)",
    "Wen et al. 2017, J. Vibroeng. 19(6) (ball-screw inerter losses); Smith 2020, The inerter: a retrospective "
    "(back-driving)",
    (Parameter("forward", "1", "η_f: the part of the force that reaches the flywheel when the terminals drive it",
               minimum=0.0, strict=True, maximum=1.0),
     Parameter("backward", "1", "η_b: the part that reaches the terminals when the flywheel drives them",
               minimum=0.0, strict=True, maximum=1.0),
     Parameter("velocity_scale", "m/s", "v_s: the switch at a turnaround smoothed as tanh(L̇/v_s); 0 (default): "
               "the exact switch", minimum=0.0, required=False)))

DISSIPATED_ENERGY = Effect(
    "dissipated_energy", "the device's dissipated energy integrated as a state (output e_loss)",
    "ż = p_loss: energy + e_loss is the initial energy (Drake's non-conservative power, integrated)", ())

#: The effects an inerter may declare, in the order they are listed and their outputs written.
EFFECTS = (FLYWHEEL, FRICTION_EFFECT, END_STOPS, FLUID_EFFECT, HOUSING, ROD, MOUNT_EFFECT, COMPLIANCE,
           BACKLASH_EFFECT, EFFICIENCY_EFFECT, DISSIPATED_ENERGY)


def check_device(effects: dict):
    """How a device's effects go together: None, or (effect, key, value, expected, problem)."""
    if "compliance" in effects and "mount" in effects:
        # the mount's gyroscopic terms spin the flywheel at n dL/dt (device_inertia); in series the
        # flywheel follows the inerter's own stroke u = L − s, which that block does not model
        return ("mount", "axis", effects["mount"].get("axis"), "no device.mount beside device.compliance (the "
                "gyroscopic terms take the flywheel's spin from the terminal distance, not from the inerter's "
                "own stroke in a series connection)", "mount and compliance together")
    if "efficiency" in effects and "mount" in effects:
        # the mount's gyroscopic block spins the flywheel with b, not b_eff: the screw's loss would
        # not reach the housing's reaction moments
        return ("efficiency", "forward", effects["efficiency"].get("forward"), "no device.efficiency beside "
                "device.mount (the gyroscopic terms take the flywheel's inertial force without the screw's "
                "efficiency)", "efficiency and mount together")
    if "backlash" in effects and "compliance" not in effects:
        return ("backlash", "gap", effects["backlash"].get("gap"),
                "device.compliance beside it (the gap is in the series connection)", "backlash without compliance")
    for part in ("housing", "rod"):
        spin = effects.get(part, {}).get("axial_inertia")
        if spin and "mount" not in effects:
            # without a mount the model holds the parts' spin about the device's axis at zero (the
            # terminals take the screw's reaction moment): an axial inertia there acts on nothing
            return (part, "axial_inertia", spin, "device.mount beside it (only a mount lets the housing and the "
                    "rod spin about the device's axis; 3D only), or no axial_inertia", "axial inertia without a mount")
    flywheel = effects.get("flywheel", {})
    if flywheel.get("centre") is not None and not flywheel.get("mass"):
        return ("flywheel", "centre", flywheel["centre"], "flywheel.mass > 0 beside it (the centre places the "
                "flywheel's mass along the device), or no centre", "centre without mass")
    if "dissipated_energy" in effects and not any(n in effects for n in ("friction", "end_stops", "fluid",
                                                                          "compliance", "efficiency")):
        return ("dissipated_energy", "", {}, "a dissipative effect beside it (friction, end_stops, fluid, "
                "compliance or efficiency)", "nothing to dissipate")
    return None
EFFECT = {e.name: e for e in EFFECTS}


def _number(v) -> str:
    return f"{v:g}" if not isinstance(v, tuple) else "[" + ", ".join(f"{x:g}" for x in v) + "]"


@dataclass(frozen=True)
class Device:
    """An element's declared device: ((effect name, ((parameter key, value or None), ...)), ...),
    in the order of :data:`EFFECTS`, every parameter present (None: optional and absent)."""
    effects: tuple

    def has(self, name: str) -> bool:
        return any(n == name for n, _ in self.effects)

    def values(self, name: str) -> dict:
        for n, values in self.effects:
            if n == name:
                return dict(values)
        return {}

    def inertance(self) -> float | None:
        """The inertance its flywheel or fluid channel gives (kg); None where the scene gives b."""
        for name, values in self.effects:
            fn = EFFECT[name].inertance
            if fn is not None:
                return float(fn(dict(values)))
        return None

    def columns(self) -> dict[int, float]:
        """Its columns of the element table (:mod:`inerter.elements.layout`)."""
        cols = {DEVICE: 1.0}
        if self.has("flywheel"):
            cols[FLYWHEEL_RATIO] = float(_flywheel_ratio(self.values("flywheel")))
        if self.has("friction"):
            v = self.values("friction")
            cols.update({FRICTION: 1.0, COULOMB: v["coulomb"] or 0.0, VISCOUS: v["viscous"] or 0.0,
                         VELOCITY_SCALE: v["velocity_scale"] or 1.0})
        if self.has("end_stops"):
            v = self.values("end_stops")
            cols.update({STOPS: 1.0, STOP_MIN: v["min"] if v["min"] is not None else 0.0,
                         STOP_MAX: v["max"] if v["max"] is not None else math.inf,
                         STOP_STIFFNESS: v["stiffness"], STOP_DAMPING: v["damping"],
                         STOP_EXPONENT: v["exponent"]})
        if self.has("fluid"):
            v = self.values("fluid")
            cols.update({FLUID: 1.0, FLUID_LINEAR: v["linear_damping"], FLUID_QUADRATIC: v["quadratic_damping"]})
        if self.has("compliance"):
            v = self.values("compliance")
            cols.update({SERIES: 1.0, SERIES_STIFFNESS: v["stiffness"], SERIES_DAMPING: v["damping"] or 0.0})
        if self.has("backlash"):
            cols.update({BACKLASH: 1.0, GAP: self.values("backlash")["gap"]})
        if self.has("efficiency"):
            v = self.values("efficiency")
            cols.update({EFFICIENCY: 1.0, ETA_FORWARD: v["forward"], ETA_BACKWARD: v["backward"],
                         EFFICIENCY_MODE: 1.0, EFFICIENCY_SCALE: v["velocity_scale"] or 0.0})
        if self.has("dissipated_energy"):
            cols[LOSS] = 1.0
        if self.inertia():
            cols.update(self._inertia_columns())
        return cols

    def inertia(self) -> bool:
        """Whether it declares masses or inertias beyond the flywheel's axial one, or a mount: a
        kinetic block of its own (:mod:`inerter.elements.device_inertia`)."""
        fly = self.values("flywheel")
        return (any(self.has(n) for n in ("housing", "rod", "mount"))
                or fly.get("transverse_inertia") is not None or fly.get("mass") is not None)

    def _inertia_columns(self) -> dict[int, float]:
        fly, housing, rod = self.values("flywheel"), self.values("housing"), self.values("rod")
        cols = {INERTIA: 1.0, HOUSING_MASS: housing.get("mass") or 0.0, HOUSING_CENTRE: housing.get("centre") or 0.0,
                ROD_MASS: rod.get("mass") or 0.0, ROD_CENTRE: rod.get("centre") or 0.0,
                FLYWHEEL_MASS: fly.get("mass") or 0.0, FLYWHEEL_CENTRE: fly.get("centre") or 0.0,
                TRANSVERSE: ((fly.get("transverse_inertia") or 0.0) + (housing.get("transverse_inertia") or 0.0)
                             + (rod.get("transverse_inertia") or 0.0)),
                HOUSING_AXIAL: (housing.get("axial_inertia") or 0.0) + (rod.get("axial_inertia") or 0.0),
                FLYWHEEL_AXIAL: fly.get("inertia") or 0.0}
        if self.has("mount"):
            cols[MOUNT] = 1.0
            for i, x in enumerate(self.values("mount")["axis"]):
                cols[MOUNT_AXIS + i] = float(x)
        return cols

    def dissipative(self) -> bool:
        """Whether it has a p_loss: friction, end stops, a fluid channel or a series connection
        (whose damping may be 0: a number, tunable, while the outputs are fixed by the effects
        declared; the condition :func:`outputs` tests on the row)."""
        return any(self.has(n) for n in ("friction", "end_stops", "fluid", "compliance", "efficiency"))

    def states(self) -> tuple[tuple[str, str, str], ...]:
        """(name, unit, description) of its internal states, in their order in z (:func:`state_rates`)."""
        out = []
        if self.has("compliance"):
            out += [("s_series", "m", "series deflection s (the spring's extension)"),
                    ("v_series", "m/s", "series deflection rate ds/dt")]
        if self.has("dissipated_energy"):
            out.append(("e_loss", "J", "energy dissipated in the device since t = 0"))
        return tuple(out)

    def outputs(self) -> tuple[tuple[str, str, str], ...]:
        """(suffix, unit, description) of its outputs, in the order :func:`outputs` writes them."""
        out = []
        if self.has("flywheel"):
            out.append(("w_flywheel", "rad/s", "flywheel speed, n dL/dt"))
        if self.has("friction"):
            out.append(("f_friction", "N", "device friction F_c tanh(v/v_s) + c_f v, tension positive (part of f)"))
        if self.has("fluid"):
            out.append(("f_fluid", "N", "channel damping c1 v + c2 v|v|, tension positive (part of f)"))
        if self.has("end_stops"):
            out.append(("f_stop", "N", "end-stop contact force, tension positive (part of f)"))
        if self.dissipative():
            out.append(("p_loss", "W", "power dissipated in the device (friction, channel, contact, series damping, "
                                       "screw efficiency)"))
        if self.has("compliance"):
            out.append(("s_series", "m", "series deflection s: terminal distance less the inerter's stroke, "
                                         "0 at t = 0"))
            if self.has("backlash"):
                out.append(("engaged", "1", "1 where the backlash gap is closed (the spring carries force), 0 in it"))
        if self.has("efficiency"):
            out.append(("mode", "1", "screw efficiency's mode (1 + tau)/2: 1 flywheel driven (b/eta_f), 0 back-driving "
                                     "(b eta_b), between inside the regularisation |dL/dt| < ~velocity_scale (in series: of "
                                     "the inerter's own stroke)"))
        if self.has("dissipated_energy"):
            out.append(("e_loss", "J", "energy dissipated in the device since t = 0 (integral of p_loss)"))
        return tuple(out)

    def describe(self) -> str:
        """One line: each effect with its parameters."""
        parts = []
        for name, values in self.effects:
            effect = EFFECT[name]
            units = {p.key: p.unit for p in effect.parameters}
            given = ", ".join(f"{k} = {_number(v)}" + (f" {units[k]}" if units[k] != "1" else "")
                              for k, v in values if v is not None)
            parts.append(f"{name} ({given})" if given else name)
        b = self.inertance()
        text = "; ".join(parts) + (f"; inertance from the device b = {b:g} kg" if b is not None else "")
        if self.inertia():
            text += ("; kinetic block: masses and transverse inertia" + (", housing spin and gyroscopic "
                     "moments (Hooke mount)" if self.has("mount") else ""))
        return text
