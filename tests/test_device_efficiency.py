"""A screw efficiency of an inerter device (inerter.elements.device, ``device.efficiency``): the
law and the mode's resolution, the ideal limit, the closed form of a mass on a spring with such an
inerter in 2D and 3D, the energy balance with the efficiency's loss, the scene errors, and the FMU;
in series with a spring (device.compliance, and backlash) against an explicit ODE.

Every reference is named in its test: the closed form (derived in :func:`efficiency_closed_form`),
the explicit ODE (:func:`series_reference`), the ideal inerter's own run, the compliance-only run,
or the initial energy.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.common.errors import SceneError, SimulationError
from inerter.common.inlined import compiled_copy
from inerter.elements import device as dev
from inerter.elements import layout
from inerter.elements import inerter as inerter_law
from test_device import OSCILLATOR, _device, _load, _row, _with_device

ROOT = Path(__file__).resolve().parents[1]
TWO_BAR = ROOT / "scenarios" / "two_bar_2d.toml"
DOUBLE_PENDULUM = ROOT / "scenarios" / "double_pendulum_3d.toml"

M, B, K, X0, ETA_F, ETA_B = 1.0, 1.0, 100.0, 0.25, 0.8, 0.6

EFFICIENCY = '[DEVICE.efficiency]\nforward = "etaf"\nbackward = "etab"\n'
LOSS = '[DEVICE.dissipated_energy]\n'
SCALE = 'velocity_scale = "vs"\n'              # under [DEVICE.efficiency]
#: Dense output kept (a "peak" metric), so that the peaks are read at their closed-form times.
EXPERIMENT = ('\n[experiment]\nstop_time = 3.0\noutput_interval = 0.001\nrtol = 1e-10\natol = 1e-12\n'
              '\n[[metrics]]\nkind = "peak"\nsignal = "P.r[1]"\nreference = 0.0\n')
PARAMETERS = f"[parameters]\netaf = {ETA_F}\netab = {ETA_B}\n"

#: OSCILLATOR (test_device) in 3D along the unit axis u = (1, 2, 2)/3: O at the origin, the mass's
#: centre P at (1 + x0) u from rest, the spring's free length 1 m; every force acts along u through
#: the centre, so the mass moves on that line, L = 1 + x, and nothing turns it.
OSCILLATOR_3D = """
[scene]
name = "device_1dof_3d"
dimension = 3

[parameters]
m = 1.0
b = 1.0
k = 100.0
x0 = 0.25

[ground.points]
O = [0.0, 0.0, 0.0]

[bodies.mass]
mass = "m"
inertia = [1.0, 1.0, 1.0]
position = ["(1 + x0)/3", "2*(1 + x0)/3", "2*(1 + x0)/3"]
points = { P = [0, 0, 0] }

[elements.spring]
type = "spring"
between = ["O", "P"]
k = "k"
length = 1.0

[elements.inerter]
type = "inerter"
between = ["O", "P"]
b = "b"
"""


def efficiency_closed_form(t, x0, m, b, k, eta_f, eta_b):
    """x(t), and the peaks (t_n, x_n), of m ẍ + k x + F = 0 with F = b_eff ẍ from rest at x0.

    While |x| falls toward 0 the speed grows (ẋ·ẍ ≥ 0: the terminals drive the flywheel), so
    b_eff = b/η_f and the motion is harmonic at ω₁ = √(k/(m + b/η_f)): x = x_n cos ω₁τ for a
    quarter period, reaching 0 at the speed ω₁|x_n|. While |x| grows the speed falls (ẋ·ẍ < 0:
    the flywheel drives them), b_eff = b η_b, ω₂ = √(k/(m + b η_b)): x = −x_n (ω₁/ω₂) sin ω₂τ' for a
    quarter period, to the next peak x_{n+1} = −x_n ω₁/ω₂. So each half cycle lasts
    π/(2ω₁) + π/(2ω₂) and shrinks the amplitude by ω₁/ω₂ = √((m + b η_b)/(m + b/η_f))."""
    w1, w2 = math.sqrt(k / (m + b / eta_f)), math.sqrt(k / (m + b * eta_b))
    q1, half = math.pi / (2 * w1), math.pi / (2 * w1) + math.pi / (2 * w2)
    n = np.floor(t / half)
    tau = t - n * half
    xn = x0 * (-w1 / w2) ** n
    x = np.where(tau <= q1, xn * np.cos(w1 * np.minimum(tau, q1)),
                 -xn * (w1 / w2) * np.sin(w2 * np.maximum(tau - q1, 0.0)))
    peaks = [(j * half, x0 * (-w1 / w2) ** j) for j in range(1, int(t[-1] / half) + 1)]
    return x, peaks, w1, w2


def _oscillator(tmp_path, dim=2, loss=False, vs=None, **overrides):
    """The 1-DOF scene with the efficiency (η_f, η_b the parameters etaf, etab) and, where `vs` is
    given, its velocity scale as the parameter vs."""
    text = OSCILLATOR if dim == 2 else OSCILLATOR_3D
    text = text.replace("[parameters]\n", PARAMETERS + (f"vs = {vs!r}\n" if vs is not None else ""))
    device = EFFICIENCY + (SCALE if vs is not None else "") + (LOSS if loss else "")
    return _load(tmp_path, _with_device(text, device) + EXPERIMENT, name=f"efficiency_{dim}d.toml", **overrides)


def _x(r, dim):
    """The mass's displacement x = L − 1 along the line (s_rel of the spring, in 2D and 3D)."""
    return r["spring.s_rel"] - 1.0


# ------------------------------------------------------------------------------------------------
# The law and the mode's resolution
# ------------------------------------------------------------------------------------------------
def assert_follows_the_exact_switch(r, dim):
    """A run of `_oscillator` with the exact switch against the closed form (efficiency_closed_form):
    x(t) to 1e-7 x0; E.mode 1 while |x| falls and 0 while it grows (wherever |ẋ| > 1e-6 m/s); E.p_loss
    the law's (b_eff − b) ẍ ẋ with ẍ = −k x/(m + b_eff) at the run's own (x, ẋ), to 1e-12 · ½ k x0²
    (round-off)."""
    exact, _, _, _ = efficiency_closed_form(r.time, X0, M, B, K, ETA_F, ETA_B)
    x, v = _x(r, dim), r["spring.v_rel"]
    assert np.max(np.abs(x - exact)) <= 1e-7 * X0
    inward, outward = (x * v < 0) & (np.abs(v) > 1e-6), (x * v > 0) & (np.abs(v) > 1e-6)
    assert inward.sum() > 100 and outward.sum() > 100
    assert np.all(r["inerter.mode"][inward] == 1.0) and np.all(r["inerter.mode"][outward] == 0.0)
    beff = np.where(x * v < 0, B / ETA_F, B * ETA_B)
    p_loss = (beff - B) * (-K * x / (M + beff)) * v
    assert np.max(np.abs(r["inerter.p_loss"] - p_loss)) <= 1e-12 * 0.5 * K * X0 ** 2


def test_the_efficiency_law_and_its_mode():
    """Closed form, the exact switch (v_s = 0): b_eff = b/η_f where L̇·L̈ > 0 and at L̇ = 0, b η_b where
    L̇·L̈ < 0; the stored mode is s = sign(L̈) (+1 at the start, kept at L̈ = 0); the loss
    (b_eff − b) L̈ L̇ ≥ 0 in both; settle flips s once (a solve to repeat) and then agrees."""
    row = _row(_device(efficiency=dict(forward=0.8, backward=0.6)), b=2.0)
    for fn in (lambda f, *a: compiled_copy(f)(*a), lambda f, *a: f.py_func(*a)):
        r = row.copy()
        assert r[layout.EFFICIENCY_MODE] == 1.0 and r[layout.EFFICIENCY_SCALE] == 0.0
        assert fn(dev.inertance, r, 0.0) == 2.0 / 0.8 == fn(dev.inertance, r, 0.5)
        assert fn(dev.efficiency_loss, r, 0.5, 2.0) == pytest.approx((2.0 / 0.8 - 2.0) * 1.0, rel=1e-15)
        assert fn(dev.settle, r, 0.0, -3.0) == 0 and r[layout.EFFICIENCY_MODE] == -1.0   # L̇ = 0: b_eff either way
        assert fn(dev.inertance, r, 0.0) == 2.0 / 0.8
        assert fn(dev.settle, r, -0.5, 0.0) == 0 and r[layout.EFFICIENCY_MODE] == -1.0   # L̈ = 0: s kept
        assert fn(dev.settle, r, -0.5, 2.0) == 1 and r[layout.EFFICIENCY_MODE] == 1.0
        assert fn(dev.settle, r, -0.5, 2.0) == 0
        assert fn(dev.inertance, r, -0.5) == 2.0 * 0.6
        assert fn(dev.efficiency_loss, r, -0.5, 2.0) == pytest.approx((2.0 * 0.6 - 2.0) * -1.0, rel=1e-15)
        # the inerter's force beyond b_eff gᵀq̈ is b_eff (a_n·r̂ + |ṙ⊥|²/L), Eq. (9)
        assert fn(inerter_law.force, r, 2.0, -0.5, 0.3, 0.8) == pytest.approx(1.2 * (0.3 + 0.8 / 2.0), rel=1e-15)


@pytest.mark.parametrize("eta_f, eta_b", [(0.8, 0.6), (0.5, 0.9), (1.0, 0.7)])
def test_the_regularised_law_is_smooth_passive_and_tends_to_the_switch(eta_f, eta_b):
    """Closed form, v_s > 0: b_eff = b (1 + λ(τ)), τ = s tanh(L̇/v_s), λ(τ) = τ ((α+β)/2 + τ (α−β)/2),
    α = 1/η_f − 1, β = 1 − η_b: b at rest; within 1e-12 relative of b/η_f (L̇·L̈ > 0) and b η_b
    (L̇·L̈ < 0) at |L̇| = 20 v_s (tanh 20 = 1 − 8e-18); the loss b λ L̈ L̇ ≥ 0 at every L̇ of both
    signs of L̈ (passive); the output E.mode = (1 + τ)/2; compiled and uncompiled alike."""
    b, vs = 2.0, 1e-3
    row = _row(_device(efficiency=dict(forward=eta_f, backward=eta_b, velocity_scale=vs)), b=b)
    alpha, beta = 1.0 / eta_f - 1.0, 1.0 - eta_b
    for fn in (lambda f, *a: compiled_copy(f)(*a), lambda f, *a: f.py_func(*a)):
        for s in (1.0, -1.0):
            r = row.copy()
            r[layout.EFFICIENCY_MODE] = s
            assert r[layout.EFFICIENCY_SCALE] == vs
            assert fn(dev.inertance, r, 0.0) == b
            assert fn(dev.inertance, r, 20 * vs * s) == pytest.approx(b / eta_f, rel=1e-12)
            assert fn(dev.inertance, r, -20 * vs * s) == pytest.approx(b * eta_b, rel=1e-12)
            for Ld in np.linspace(-5 * vs, 5 * vs, 41):
                tau = s * math.tanh(Ld / vs)
                lam = tau * (0.5 * (alpha + beta) + tau * 0.5 * (alpha - beta))
                assert fn(dev.inertance, r, Ld) == pytest.approx(b * (1.0 + lam), rel=1e-14, abs=1e-15)
                assert fn(dev.efficiency_loss, r, Ld, 3.0 * s) >= 0.0
                out = np.zeros(2)                    # E.p_loss, E.mode
                assert fn(dev.outputs, r, 1.0, Ld, 3.0 * s, np.zeros(0), out, 0) == 2
                assert out[1] == pytest.approx(0.5 * (1.0 + tau), rel=1e-15, abs=1e-15)


def test_a_turnaround_flips_the_mode_and_one_solve_more_settles_it(tmp_path):
    """Reference: the closed form's accelerations. At the first peak the mass is at rest (L̇ = 0:
    driven, ẍ = −k x/(m + b/η_f), whatever the stored s). Moving outward from x0 > 0 (slowing,
    back-driving: ẍ = −k x/(m + b η_b)), started from the wrong stored mode s = +1 (which reads
    driven there), one call returns the back-driving ẍ and stores s = sign(L̈) = −1: the second
    solve settles it (sign(L̈) does not depend on b_eff), and no call is counted unsettled."""
    from inerter.engine import compiled
    kernel = compiled.Kernel(_oscillator(tmp_path).mechanism)
    q, v = kernel.q0.copy(), kernel.v0.copy()
    el_real = kernel.params[4]
    e = int(np.flatnonzero(el_real[:, layout.EFFICIENCY])[0])
    for start in (-1.0, 1.0):
        el_real[e, layout.EFFICIENCY_MODE] = start
        qdd, _ = kernel.accelerations(0.0, q, v)
        assert qdd[0] == pytest.approx(-K * X0 / (M + B / ETA_F), rel=1e-14)
    v[0] = 0.3                                       # moving outward from x0 > 0: slowing, back-driving
    for start in (1.0, -1.0):
        el_real[e, layout.EFFICIENCY_MODE] = start
        qdd, _ = kernel.accelerations(0.0, q, v)
        assert el_real[e, layout.EFFICIENCY_MODE] == -1.0
        assert qdd[0] == pytest.approx(-K * X0 / (M + B * ETA_B), rel=1e-14)
    assert kernel.unsettled == 0


# ------------------------------------------------------------------------------------------------
# The ideal limit
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene, stop_time", [(TWO_BAR, 10.0), (DOUBLE_PENDULUM, 5.0)],
                         ids=["2d-two-bar", "3d-double-pendulum"])
def test_efficiencies_of_one_are_the_ideal_inerter(tmp_path, scene, stop_time):
    """Reference: the ideal scene's own compiled DOP853 run. η_f = η_b = 1: b_eff = b in both modes,
    so every output the two share agrees to 1e-12 of its range (the paper's two-bar in 2D, with the
    centripetal term; the 3D double pendulum), and the loss is 0."""
    ideal = inerter.load(scene).simulate(stop_time=stop_time, metrics=False)
    device = "[DEVICE.efficiency]\nforward = 1.0\nbackward = 1.0\n"
    real = _load(tmp_path, _with_device(scene.read_text(encoding="utf-8"), device)).simulate(
        stop_time=stop_time, metrics=False)
    assert real.run.extra["path"] == ideal.run.extra["path"] == "compiled"
    assert np.array_equal(real.time, ideal.time)
    for name in ideal.names:
        scale = max(1.0, float(np.max(np.abs(ideal[name]))))
        assert np.max(np.abs(real[name] - ideal[name])) <= 1e-12 * scale, name
    assert np.max(np.abs(real["inerter.p_loss"])) == 0.0


# ------------------------------------------------------------------------------------------------
# The closed form, 2D and 3D
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
def test_peaks_and_their_times_follow_the_two_quarter_periods(tmp_path, dim):
    """Closed form (efficiency_closed_form): m = 1 kg, b = 1 kg, k = 100 N/m, x0 = 0.25 m, η_f = 0.8,
    η_b = 0.6: ω₁ = 6.667, ω₂ = 7.906 rad/s, half cycles of 0.4343 s, each peak 0.8433 of the last.
    At DOP853 rtol 1e-10 the dense output at the closed-form peak times t_n gives x_n to 1e-7
    relative and L̇ = 0 to 1e-7 x_n ω₂, and x(t) at every sample is the piecewise-harmonic closed
    form to 1e-7 x0 (a shifted peak time would show as an error ω x δt: the times agree to
    ~1e-8 s). E.mode is 1 while |x| falls, 0 while it grows."""
    model = _oscillator(tmp_path, dim)
    r = model.simulate()
    assert r.status == "ok", r.message
    x = _x(r, dim)
    exact, peaks, w1, w2 = efficiency_closed_form(r.time, X0, M, B, K, ETA_F, ETA_B)
    assert w1 / w2 == pytest.approx(math.sqrt((M + B * ETA_B) / (M + B / ETA_F)), rel=1e-15)
    assert len(peaks) == 6
    assert np.max(np.abs(x - exact)) <= 1e-7 * X0
    s, v = r.dense("spring.s_rel"), r.dense("spring.v_rel")
    for tn, xn in peaks:
        assert s(tn)[0] - 1.0 == pytest.approx(xn, rel=1e-7), tn
        assert abs(v(tn)[0]) <= 1e-7 * abs(xn) * w2, tn
    inward = (x * r["spring.v_rel"] < 0) & (np.abs(r["spring.v_rel"]) > 1e-6)
    outward = (x * r["spring.v_rel"] > 0) & (np.abs(r["spring.v_rel"]) > 1e-6)
    assert np.all(r["inerter.mode"][inward] == 1.0) and np.all(r["inerter.mode"][outward] == 0.0)
    assert r.run.extra["unsettled"] == 0


def test_the_numpy_path_resolves_the_mode_as_the_closed_form(tmp_path):
    """Closed form (efficiency_closed_form; the oracle against it: tests/test_oracle_efficiency.py): the numpy
    path (scipy's DOP853 on the readable evaluators, Mechanism.accelerations solving again where
    the mode flips) follows it over 1 s (two turnarounds) to 1e-7 x0 at rtol 1e-10; its mode is
    1 while |x| falls and 0 while it grows (wherever |ẋ| > 1e-6 m/s), and its loss is the law's,
    p_loss = (b_eff − b) ẍ ẋ with ẍ = −k x/(m + b_eff) at the run's own (x, ẋ), to
    1e-12 · ½ k x0² = 3e-12 W (round-off of a 4.4 W peak; measured 0), tighter than the 1e-6 W the
    numpy path was held to against the compiled run."""
    model = _oscillator(tmp_path)
    r = model.simulate(stop_time=1.0, path="numpy", metrics=False)
    assert r.status == "ok" and r.run.extra.get("path", "numpy").startswith("numpy"), r.message
    assert_follows_the_exact_switch(r, 2)


def test_energy_plus_the_efficiency_loss_is_the_initial_energy(tmp_path):
    """Reference: the initial energy ½ k x0². With dissipated_energy declared, energy + E.e_loss
    stays ½ k x0² to 1e-9 relative over 3 s (DOP853, rtol 1e-10), while the energy itself falls
    to (ω₁/ω₂)^12 = 0.13 of it over six half cycles (checked: below half); E.p_loss ≥ 0 throughout
    and equals (b_eff − b) L̈ L̇ from the outputs, b_eff L̈ = f (the inerter's force), to 1e-12."""
    r = _oscillator(tmp_path, loss=True).simulate()
    assert r.status == "ok", r.message
    E0 = 0.5 * K * X0 ** 2
    assert np.max(np.abs(r["energy"] + r["inerter.e_loss"] - E0)) <= 1e-9 * E0
    assert r["energy"][-1] < 0.5 * E0
    assert np.min(r["inerter.p_loss"]) >= -1e-12 * E0
    beff = np.where(r["inerter.mode"] == 1.0, B / ETA_F, B * ETA_B)
    Lddot = r["inerter.f"] / beff
    np.testing.assert_allclose(r["inerter.p_loss"], (beff - B) * Lddot * r["inerter.v_rel"], rtol=1e-12,
                               atol=1e-12 * E0)


# ------------------------------------------------------------------------------------------------
# The regularised switch (device.efficiency.velocity_scale v_s > 0)
# ------------------------------------------------------------------------------------------------
#: The first quarter's peak speed ω₁ x0 (m/s): the velocity scales below are fractions of it.
PEAK_SPEED = X0 * math.sqrt(K / (M + B / ETA_F))


def test_the_regularised_run_converges_to_the_exact_switch_at_first_order(tmp_path):
    """Reference: the exact switch's closed form (efficiency_closed_form). At v_s = 1e-2, 1e-3,
    1e-4 of the peak speed (DOP853, rtol 1e-10, 3 s, six turnarounds) the largest error of x falls
    tenfold with v_s each time: observed order 1.00 (errors 6.2e-4, 6.2e-5, 6.2e-6 m, about
    0.037 s · v_s: b_eff reaches its exact value ~v_s/|L̈| later at each turnaround, a shift of the
    phase of order v_s); checked: each order within 1 ± 0.05, the last error below 1e-5 m, and
    every call settled its mode."""
    errors = []
    for fraction in (1e-2, 1e-3, 1e-4):
        r = _oscillator(tmp_path, vs=fraction * PEAK_SPEED).simulate(metrics=False)
        assert r.status == "ok" and r.run.extra["unsettled"] == 0, r.message
        exact, _, _, _ = efficiency_closed_form(r.time, X0, M, B, K, ETA_F, ETA_B)
        errors.append(float(np.max(np.abs(_x(r, 2) - exact))))
    orders = np.log10(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 1.0) <= 0.05), (errors, orders)
    assert errors[-1] <= 1e-5, errors


def test_the_regularised_switch_is_passive_and_balances_the_energy(tmp_path):
    """Reference: the initial energy ½ k x0². With v_s = 1e-2 of the peak speed and dissipated_energy
    declared, energy + E.e_loss stays ½ k x0² to 1e-9 relative over 3 s (DOP853, rtol 1e-10);
    E.p_loss = b λ L̈ L̇ ≥ 0 at every sample (sign λ = sign(L̇ L̈) by construction, no tolerance),
    so E.e_loss never decreases (between samples by at most 1e-12 E0, the integrator's round-off);
    E.mode leaves {0, 1} at the turnarounds (inside the regularisation)."""
    r = _oscillator(tmp_path, loss=True, vs=1e-2 * PEAK_SPEED).simulate()
    assert r.status == "ok", r.message
    E0 = 0.5 * K * X0 ** 2
    assert np.max(np.abs(r["energy"] + r["inerter.e_loss"] - E0)) <= 1e-9 * E0
    assert r["energy"][-1] < 0.5 * E0
    assert np.min(r["inerter.p_loss"]) >= 0.0
    assert np.min(np.diff(r["inerter.e_loss"])) >= -1e-12 * E0
    mode = r["inerter.mode"]
    assert np.min(mode) >= 0.0 and np.max(mode) <= 1.0 and np.any((mode > 0.01) & (mode < 0.99))


@pytest.mark.parametrize("dim, path", [(3, "compiled"), (2, "numpy")], ids=["3d-compiled", "2d-numpy"])
def test_the_regularised_switch_in_3d_and_on_the_numpy_path(tmp_path, dim, path):
    """Reference: the 2D compiled run at v_s = 1e-2 of the peak speed (1 s, two turnarounds, DOP853
    rtol 1e-10). The 3D scene along u = (1, 2, 2)/3 and the numpy path (scipy's DOP853 on the
    readable evaluators, Mechanism.accelerations settling the mode) give the same x to 1e-8 x0 and
    the same E.mode and E.p_loss to 1e-6 (the mode's slope at a turnaround is 1/(2 v_s) per m/s)."""
    vs = 1e-2 * PEAK_SPEED
    ref = _oscillator(tmp_path, vs=vs).simulate(stop_time=1.0, metrics=False)
    r = _oscillator(tmp_path, dim=dim, vs=vs).simulate(stop_time=1.0, metrics=False,
                                                       **({"path": "numpy"} if path == "numpy" else {}))
    assert r.status == "ok" and ref.status == "ok", r.message
    assert r.run.extra.get("path", "numpy").startswith(path), r.run.extra.get("path")
    assert np.max(np.abs(_x(r, dim) - _x(ref, 2))) <= 1e-8 * X0
    for name in ("inerter.mode", "inerter.p_loss"):
        assert np.max(np.abs(r[name] - ref[name])) <= 1e-6, name


#: Two masses in a chain, ground — m1 — m2, each link a spring (free length 1 m) and an efficiency
#: inerter with its dissipated energy: the two modes are coupled through the mass matrix.
CHAIN = """
[scene]
name = "efficiency_chain"

[parameters]
etaf = 0.7
etab = 0.5

[ground.points]
O = [-1.0, 0.0]

[bodies.m1]
mass = 1.0
inertia = 1.0
position = [0.2, 0.0]
points = { P1 = [0, 0] }

[bodies.m2]
mass = 0.5
inertia = 1.0
position = [0.9, 0.0]
points = { P2 = [0, 0] }

[elements.s1]
type = "spring"
between = ["O", "P1"]
k = 100.0
length = 1.0

[elements.s2]
type = "spring"
between = ["P1", "P2"]
k = 150.0
length = 1.0

[elements.i1]
type = "inerter"
between = ["O", "P1"]
b = 1.0

[elements.i2]
type = "inerter"
between = ["P1", "P2"]
b = 0.8
""" + "".join(f"""
[elements.{e}.device.efficiency]
forward = "etaf"
backward = "etab"

[elements.{e}.device.dissipated_energy]
""" for e in ("i1", "i2")) + """
[experiment]
stop_time = 3.0
output_interval = 0.001
rtol = 1e-10
atol = 1e-12
"""


def test_two_coupled_efficiencies_settle_and_balance_the_energy(tmp_path):
    """Reference: the initial energy ½ 100 (0.2)² + ½ 150 (0.3)² = 8.75 J. Two efficiency inerters in
    a chain, their modes coupled: every evaluation's modes settled within device.MODE_SOLVES solves
    (the run's count is 0, and no warning), the energy + both e_loss stay 8.75 J to 1e-9 relative
    over 3 s, each p_loss ≥ 0, and each mode agrees with the sign of L̇·L̈ at every sample where
    |L̇·L̈| is not at round-off (L̈ = f / b_eff from the outputs)."""
    r = _load(tmp_path, CHAIN).simulate(metrics=False)
    assert r.status == "ok", r.message
    assert r.run.extra["unsettled"] == 0 and not r.warnings
    E0 = 0.5 * 100.0 * 0.2 ** 2 + 0.5 * 150.0 * 0.3 ** 2
    total = r["energy"] + r["i1.e_loss"] + r["i2.e_loss"]
    assert np.max(np.abs(total - E0)) <= 1e-9 * E0
    assert r["energy"][-1] < 0.5 * E0
    for e, b in (("i1", 1.0), ("i2", 0.8)):
        assert np.min(r[f"{e}.p_loss"]) >= -1e-12 * E0, e
        mode = r[f"{e}.mode"]
        Lddot = r[f"{e}.f"] / np.where(mode == 1.0, b / 0.7, b * 0.5)
        power = r[f"{e}.v_rel"] * Lddot
        clear = np.abs(power) > 1e-9
        assert np.array_equal(mode[clear], (power[clear] >= 0).astype(float)), e


# ------------------------------------------------------------------------------------------------
# Scene errors and description
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("device, field, expected", [
    ("[DEVICE.efficiency]\nforward = 0.0\nbackward = 0.5\n", "elements.inerter.device.efficiency.forward", "> 0"),
    ("[DEVICE.efficiency]\nforward = 0.9\nbackward = 1.2\n", "elements.inerter.device.efficiency.backward",
     "≤ 1"),
    ("[DEVICE.efficiency]\nforward = 0.9\nbackward = 0.8\nvelocity_scale = -1e-3\n",
     "elements.inerter.device.efficiency.velocity_scale", "≥ 0"),
    ("[DEVICE.efficiency]\nforward = 0.9\n", "elements.inerter.device.efficiency.backward", ""),
])
def test_efficiency_errors_name_the_field_value_and_expectation(tmp_path, device, field, expected):
    """The scene reader's one-line error names the field, and what was expected."""
    with pytest.raises(SceneError) as info:
        _load(tmp_path, _with_device(OSCILLATOR, device))
    text = str(info.value)
    assert field in text and expected in text and "\n" not in text.strip(), text


def test_efficiency_with_a_mount_is_refused_and_the_linearisation_refuses_it(tmp_path):
    """A mount beside it is a scene error naming device.mount; the linearisation, which needs a
    smooth mass matrix, refuses it with the reason, on the engine's mechanism and on the oracle's
    (which derives the efficiency itself: tests/test_oracle_efficiency.py)."""
    text = _with_device(DOUBLE_PENDULUM.read_text(encoding="utf-8"),
                        "[DEVICE.efficiency]\nforward = 0.9\nbackward = 0.8\n[DEVICE.mount]\naxis = [0, 0, 1]\n")
    with pytest.raises(SceneError, match="device.mount"):
        _load(tmp_path, text)
    model = _oscillator(tmp_path)
    from inerter.engine.equilibrium import linearize
    for mech in (model.mechanism, model.oracle().mechanism):
        with pytest.raises(SimulationError, match="efficiency"):
            linearize(mech)


def test_describe_and_outputs_list_the_efficiency(tmp_path):
    """describe names the effect and its numbers; the outputs are the loss and the mode."""
    model = _oscillator(tmp_path, loss=True)
    line = next(t for t in model.terms() if "device" in t)
    assert "efficiency (forward = 0.8, backward = 0.6)" in line, line
    names = [o["name"] for o in model.output_info() if o["name"].startswith("inerter.")]
    assert names == ["inerter.s_rel", "inerter.v_rel", "inerter.f", "inerter.power", "inerter.energy",
                     "inerter.p_loss", "inerter.mode", "inerter.e_loss"]


# ------------------------------------------------------------------------------------------------
# Through the FMU
# ------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def efficiency_fmu(tmp_path_factory):
    pytest.importorskip("fmpy")
    from inerter.fmu import build as fmu_build
    path = tmp_path_factory.mktemp("efficiency_scene")
    scene = path / "efficiency_2d.toml"
    scene.write_text(_with_device(OSCILLATOR.replace("[parameters]\n", PARAMETERS + "vs = 0.0\n"),
                                  EFFICIENCY + SCALE + LOSS) + EXPERIMENT, encoding="utf-8")
    return scene, fmu_build.build(scene, tmp_path_factory.mktemp("efficiency_fmu"), force=True)


def test_the_fmu_validates_tunes_the_efficiency_and_matches_the_solver(efficiency_fmu):
    """The FMU validates with fmpy; η_f and η_b are tunable parameters; its run at η_f = 0.7,
    η_b = 0.5 matches the solver's at the same values to 1e-8 (positions, the inerter's force, the
    mode and e_loss), and the solver follows the closed form at those values to 1e-7 x0."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu
    from inerter.fmu.run import simulate_fmu
    scene, fmu = efficiency_fmu
    assert validate_fmu(str(fmu)) == []
    md = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    for name in ("etaf", "etab"):
        assert md[name].causality == "parameter" and md[name].variability == "tunable", name
    assert {"inerter.mode", "inerter.p_loss", "inerter.e_loss"} <= set(md)
    values = {"etaf": 0.7, "etab": 0.5}
    r = simulate_fmu(scene, values, stop_time=2.0, step=0.01, fmu_path=fmu, metrics=False)
    assert r.status == "ok", r.message
    ref = inerter.load(scene, **values).simulate(stop_time=2.0, output_interval=0.01, metrics=False)
    for name in ("P.r[1]", "inerter.f", "inerter.mode", "inerter.e_loss"):
        assert np.max(np.abs(r[name] - ref[name])) <= 1e-8, name
    exact, _, _, _ = efficiency_closed_form(ref.time, X0, M, B, K, 0.7, 0.5)
    assert np.max(np.abs(ref["P.r[1]"] - exact)) <= 1e-7 * X0


def test_the_fmu_tunes_the_velocity_scale_and_matches_the_solver(efficiency_fmu):
    """The velocity scale v_s (parameter vs, 0 in the scene) is a tunable parameter of the FMU; its
    run at v_s = 0.01 m/s matches the solver's at the same value to 1e-8 (positions, the inerter's
    force, the mode and e_loss)."""
    from fmpy import read_model_description
    from inerter.fmu.run import simulate_fmu
    scene, fmu = efficiency_fmu
    md = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    assert md["vs"].causality == "parameter" and md["vs"].variability == "tunable"
    values = {"vs": 0.01}
    r = simulate_fmu(scene, values, stop_time=2.0, step=0.01, fmu_path=fmu, metrics=False)
    assert r.status == "ok", r.message
    ref = inerter.load(scene, **values).simulate(stop_time=2.0, output_interval=0.01, metrics=False)
    for name in ("P.r[1]", "inerter.f", "inerter.mode", "inerter.e_loss"):
        assert np.max(np.abs(r[name] - ref[name])) <= 1e-8, name


# ------------------------------------------------------------------------------------------------
# In series: the efficiency with device.compliance (and backlash)
# ------------------------------------------------------------------------------------------------
#: The series connection: k_c, c_c (N/m, N.s/m); the mass starts at x0 moving at V0 (m/s), so that
#: the inerter's own stroke rate u̇(0) = V0 ≠ 0 (the series deflection starts at rest, s = ṡ = 0).
KC, CC, V0 = 400.0, 2.0, 0.5
#: The velocity scale of the regularised rows (m/s), about 1e-2 of the peak |u̇|.
SERIES_VS = 1e-2
COMPLIANCE = '[DEVICE.compliance]\nstiffness = "kc"\ndamping = "cc"\n'
BACKLASH = '[DEVICE.backlash]\ngap = "gap"\n'
SERIES_EXPERIMENT = '\n[experiment]\nstop_time = 3.0\noutput_interval = 0.001\nrtol = 1e-12\natol = 1e-14\n'


def series_reference(times, m=M, b=B, k=K, kc=KC, cc=CC, eta_f=ETA_F, eta_b=ETA_B, vs=0.0, gap=0.0, x0=X0,
                     v0=V0):
    """The explicit model, written here from the device's law: a mass m on a spring k (free length
    1 m: x = L − 1) with, between it and the ground, a spring k_c and damper c_c in series with an
    inerter b of own stroke u (u(0) = x0, so the deflection s = x − u starts at 0), the screw's
    efficiency on u:

        m ẍ = −k x − F,   b (1 + λ(τ)) ü = F,   F = k_c d + c_c ṡ (d = s; with a gap Δ, d = s ∓ Δ/2
        beyond it, 0 in it, and F clipped to 0 where F d < 0),
        τ = σ tanh(u̇/v_s) (v_s = 0: σ sgn u̇, +1 at u̇ = 0),  σ = sign F (+1 at F = 0),
        λ(τ) = τ ((α+β)/2 + τ (α−β)/2),  α = 1/η_f − 1,  β = 1 − η_b.

    y = [x, ẋ, u, u̇], integrated by scipy's DOP853 at rtol 1e-12, atol 1e-14, and restarted at each
    switch of the right side, located as an event (u̇ = 0 with v_s = 0, where b_eff jumps; |s| = Δ/2,
    where c_c ṡ enters or leaves F): no step straddles a jump. Returns y at `times`, and p, the
    screw's loss b λ ü u̇ at those samples."""
    from scipy.integrate import solve_ivp
    alpha, beta = 1.0 / eta_f - 1.0, 1.0 - eta_b

    def force(s, sd):
        if gap == 0.0:
            return kc * s + cc * sd
        if abs(s) <= 0.5 * gap:
            return 0.0
        d = s - math.copysign(0.5 * gap, s)
        F = kc * d + cc * sd
        return 0.0 if F * d < 0.0 else F

    def drive(y, side):
        """(ü, λ) with u̇'s sign `side` in this piece (v_s = 0)."""
        x, xd, u, ud = y
        F = force(x - u, xd - ud)
        sigma = 1.0 if F >= 0.0 else -1.0
        tau = sigma * math.tanh(ud / vs) if vs > 0.0 else sigma * side
        lam = tau * (0.5 * (alpha + beta) + tau * 0.5 * (alpha - beta))
        return F / (b * (1.0 + lam)), lam, F

    def rhs(t, y, side):
        udd, _, F = drive(y, side)
        return [y[1], (-k * y[0] - F) / m, y[3], udd]

    def events(side):
        out = []
        if vs == 0.0:
            out.append(lambda t, y, side: y[3])
        if gap > 0.0:
            out += [lambda t, y, side: y[0] - y[2] - 0.5 * gap, lambda t, y, side: y[0] - y[2] + 0.5 * gap]
        return out

    def leaving(g, rate):
        # the direction of a crossing from the side the piece starts on (its rate where g ≈ 0)
        side = g if abs(g) > 1e-13 else rate
        return -1.0 if side > 0.0 else 1.0

    y, t0, side = np.array([x0, v0, x0, v0]), 0.0, math.copysign(1.0, v0)
    pieces = []
    while t0 < times[-1]:
        evs = events(side)
        for ev in evs:
            g = ev(t0, y, side)
            rate = drive(y, side)[0] if ev is evs[0] and vs == 0.0 else y[1] - y[3]
            ev.terminal, ev.direction = True, leaving(g, rate)
        sol = solve_ivp(rhs, (t0, times[-1]), y, method="DOP853", rtol=1e-12, atol=1e-14, args=(side,),
                        events=evs or None, dense_output=True)
        assert sol.success, sol.message
        pieces.append((t0, sol.t[-1], sol.sol, side))
        t0, y = sol.t[-1], sol.y[:, -1].copy()
        if vs == 0.0 and sol.status == 1 and sol.t_events[0].size:
            y[3] = 0.0
            side = 1.0 if drive(y, 1.0)[2] >= 0.0 else -1.0     # u̇ leaves 0 with the sign of ü, sign F
    Y, p = np.empty((len(times), 4)), np.empty(len(times))
    for i, t in enumerate(times):
        start, end, sol, side = next(piece for piece in pieces if piece[0] <= t <= piece[1])
        Y[i] = sol(t)
        udd, lam, _ = drive(Y[i], side)
        p[i] = b * lam * udd * Y[i][3]
    return Y, p


def _series(tmp_path, dim=2, vs=0.0, gap=0.0, loss=False, etaf=ETA_F, etab=ETA_B, efficiency=True,
            experiment=SERIES_EXPERIMENT, **overrides):
    """The 1-DOF scene (2D, or 3D along u = (1, 2, 2)/3) with the device: compliance (kc, cc), the
    efficiency (etaf, etab, vs) and, where given, backlash (gap) and the dissipated energy; the mass
    starts at x0 moving outward at v0."""
    if dim == 2:
        text = OSCILLATOR.replace("v0 = 0.0", f"v0 = {V0!r}")
    else:
        text = OSCILLATOR_3D.replace('position = ["(1 + x0)/3", "2*(1 + x0)/3", "2*(1 + x0)/3"]\n',
                                     'position = ["(1 + x0)/3", "2*(1 + x0)/3", "2*(1 + x0)/3"]\n'
                                     'velocity = ["v0/3", "2*v0/3", "2*v0/3"]\n')
        text = text.replace("x0 = 0.25\n", f"x0 = 0.25\nv0 = {V0!r}\n")
    # a name of its own: an FMU's model identifier is its scene's name, and a process loads one
    # binary per identifier (the FMU of test_the_fmu_validates_... is device_1dof's)
    text = re.sub(r'name = "(device_1dof[^"]*)"', r'name = "series_\1"', text, count=1)
    params = f"kc = {KC!r}\ncc = {CC!r}\netaf = {etaf!r}\netab = {etab!r}\nvs = {vs!r}\ngap = {gap!r}\n"
    text = text.replace("[parameters]\n", "[parameters]\n" + params)
    device = COMPLIANCE + (BACKLASH if gap > 0.0 else "") + (EFFICIENCY + SCALE if efficiency else "") \
        + (LOSS if loss else "")
    name = f"series_{dim}d_{vs}_{gap}_{efficiency}_{loss}.toml"
    return _load(tmp_path, _with_device(text, device) + experiment, name=name, **overrides)


def test_the_series_law_is_explicit_and_passive():
    """Closed form, the device's own law on rows (compiled and uncompiled): b_eff ü = F − F_d(u̇),
    F = k_c s + c_c ṡ, u̇ = L̇ − ṡ, with τ = σ tanh(u̇/v_s), σ = sign(F − F_d) (v_s > 0), or σ sgn u̇
    (v_s = 0; τ = +1 at u̇ = 0): ü to 1e-15 relative of F_net/(b (1 + λ(τ))) at every (s, ṡ, L̇) of a grid
    of both signs, E.mode = (1 + τ)/2, p_loss = c_c ṡ² + F_d u̇ + b λ ü u̇ with the screw's part ≥ 0;
    the inertance is 0 (the series force is a law of the state) and settle stores no mode."""
    b, kc, cc, Fc, vsf = 2.0, 300.0, 1.5, 0.4, 1e-2
    alpha, beta = 1.0 / ETA_F - 1.0, 1.0 - ETA_B
    for vs in (0.0, 1e-2):
        row = _row(_device(friction=dict(coulomb=Fc, velocity_scale=vsf), compliance=dict(stiffness=kc, damping=cc),
                           efficiency=dict(forward=ETA_F, backward=ETA_B, velocity_scale=vs)), b=b)
        for fn in (lambda f, *a: compiled_copy(f)(*a), lambda f, *a: f.py_func(*a)):
            assert fn(dev.inertance, row, 0.3) == 0.0 and fn(dev.settle, row, 0.3, -2.0) == 0
            assert not fn(dev.mode_solved, row)
            for s in (-2e-3, 0.0, 1e-3):
                for sd in (-0.2, 0.0, 0.05):
                    for Ld in (-0.3, -0.05, 0.05, 0.4):
                        x = np.array([s, sd])
                        ud = Ld - sd
                        net = kc * s + cc * sd - (Fc * math.tanh(ud / vsf))
                        sigma = 1.0 if net >= 0.0 else -1.0
                        if vs > 0.0:
                            tau = sigma * math.tanh(ud / vs)
                        else:                                # τ = +1 (driven) at u̇ = 0
                            tau = 1.0 if ud == 0.0 else sigma * math.copysign(1.0, ud)
                        lam = tau * (0.5 * (alpha + beta) + tau * 0.5 * (alpha - beta))
                        udd = net / (b * (1.0 + lam))
                        dx = np.zeros(2)
                        fn(dev.state_rates, row, 1.0, Ld, 7.0, x, dx)
                        assert dx[0] == sd and dx[1] == pytest.approx(7.0 - udd, rel=1e-15, abs=1e-15)
                        out = np.zeros(4)                    # E.f_friction, E.p_loss, E.s_series, E.mode
                        assert fn(dev.outputs, row, 1.0, Ld, 7.0, x, out, 0) == 4
                        assert out[3] == pytest.approx(0.5 * (1.0 + tau), rel=1e-15, abs=1e-15)
                        screw = b * lam * udd * ud
                        assert screw >= 0.0
                        assert out[1] == pytest.approx(cc * sd * sd + Fc * math.tanh(ud / vsf) * ud + screw,
                                                       rel=1e-14, abs=1e-15)


@pytest.mark.parametrize("dim, vs, path", [(2, 0.0, "compiled"), (2, SERIES_VS, "compiled"), (3, 0.0, "compiled"),
                                           (3, SERIES_VS, "compiled"), (2, 0.0, "numpy"), (2, SERIES_VS, "numpy")],
                         ids=["2d-switch", "2d-vs", "3d-switch", "3d-vs", "2d-switch-numpy", "2d-vs-numpy"])
def test_in_series_the_efficiency_follows_the_explicit_ode(tmp_path, dim, vs, path):
    """Reference: the explicit ODE (series_reference) of [x, ẋ, u, u̇], m = 1 kg, k = 100 N/m,
    b = 1 kg, k_c = 400 N/m, c_c = 2 N.s/m, η_f = 0.8, η_b = 0.6, from x0 = 0.25 m at 0.5 m/s, over
    3 s (7 turnarounds of u̇). The scene (2D, and 3D along u = (1, 2, 2)/3) at DOP853 rtol
    1e-12 gives x and the series deflection s = x − u to 1e-8 m, the series force f = F to k_c · 1e-8 m
    = 4e-6 N, and E.mode takes just 0 and 1 on the exact switch; on the compiled path and the numpy
    path (Mechanism's evaluators running the same laws uncompiled). Measured: x within 4e-11 m in
    every case (the largest, 2D compiled with the exact switch, 3.3e-11 m). No mode is
    stored and no solve repeated: the engine counts no such element (dims[EFFICIENT] = 0) and
    Mechanism.efficient is empty."""
    model = _series(tmp_path, dim, vs=vs)
    assert model.mechanism.efficient == []
    r = model.simulate(metrics=False, **({"path": "numpy"} if path == "numpy" else {}))
    assert r.status == "ok", r.message
    assert r.run.extra.get("path", "numpy").startswith(path), r.run.extra.get("path")
    if path == "compiled":
        from inerter.engine import kernels
        assert r.run.extra["kernel"].params[kernels.DIMS][kernels.EFFICIENT] == 0
    Y, _ = series_reference(r.time, vs=vs)
    assert np.max(np.abs(_x(r, dim) - Y[:, 0])) <= 1e-8
    assert np.max(np.abs(r["inerter.s_series"] - (Y[:, 0] - Y[:, 2]))) <= 1e-8
    F = KC * (Y[:, 0] - Y[:, 2]) + CC * (Y[:, 1] - Y[:, 3])
    assert np.max(np.abs(r["inerter.f"] - F)) <= KC * 1e-8
    turns = int(np.sum(np.diff(np.sign(Y[:, 3])) != 0))
    assert turns >= 5, turns
    if vs == 0.0:
        assert set(np.unique(r["inerter.mode"])) == {0.0, 1.0}


@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_in_series_with_backlash_the_efficiency_follows_the_explicit_ode(tmp_path, path):
    """Reference: the explicit ODE (series_reference) with the gap's law (series_force: no force in
    the gap of Δ = 4 mm, k_c d + c_c ṡ beyond it, clipped where it would pull the engaged sides
    apart), engagement and u̇'s turnarounds located as events; same parameters as above, v_s = 0,
    over 3 s. The scene at DOP853 rtol 1e-12 (compiled path and numpy path) gives x and s = x − u
    to 1e-8 m (measured 3e-12 m compiled, 6e-11 m numpy), and E.engaged 0 where the reference's
    |s| < Δ/2 − 1e-6 m, 1 beyond Δ/2 + 1e-6 m."""
    gap = 4e-3
    r = _series(tmp_path, gap=gap).simulate(metrics=False, **({"path": "numpy"} if path == "numpy" else {}))
    assert r.status == "ok", r.message
    Y, _ = series_reference(r.time, gap=gap)
    assert np.max(np.abs(_x(r, 2) - Y[:, 0])) <= 1e-8
    s = Y[:, 0] - Y[:, 2]
    assert np.max(np.abs(r["inerter.s_series"] - s)) <= 1e-8
    inside, beyond = np.abs(s) < 0.5 * gap - 1e-6, np.abs(s) > 0.5 * gap + 1e-6
    assert np.any(inside) and np.any(beyond)
    assert np.all(r["inerter.engaged"][inside] == 0.0) and np.all(r["inerter.engaged"][beyond] == 1.0)


def test_in_series_the_efficiency_loss_balances_the_energy(tmp_path):
    """Reference: the initial energy ½ k x0² + ½ m v0² + ½ b u̇(0)² = 3.375 J. With dissipated_energy
    declared and v_s = 1e-2 m/s, energy + E.e_loss stays 3.375 J to 100·rtol = 1e-10 relative over
    3 s at DOP853 rtol 1e-12 (the bound of test_device_states' balance: each step's local error below
    rtol; measured 3e-13); E.p_loss ≥ 0 at every sample and E.e_loss never decreases (by more than
    1e-15 J between samples, round-off); the screw's part of p_loss, p_loss − c_c ṡ², is the explicit
    ODE's b λ ü u̇ (series_reference) to 1e-8 W (measured 5e-10 W), and its integral is most of
    e_loss (above half; measured 93 %)."""
    r = _series(tmp_path, vs=SERIES_VS, loss=True).simulate(metrics=False)
    assert r.status == "ok", r.message
    E0 = 0.5 * K * X0 ** 2 + 0.5 * M * V0 ** 2 + 0.5 * B * V0 ** 2
    assert r["energy"][0] == pytest.approx(E0, rel=1e-15)
    assert np.max(np.abs(r["energy"] + r["inerter.e_loss"] - E0)) <= 1e-10 * E0
    assert np.min(r["inerter.p_loss"]) >= 0.0
    assert np.min(np.diff(r["inerter.e_loss"])) >= -1e-15
    Y, screw = series_reference(r.time, vs=SERIES_VS)
    damper = CC * (Y[:, 1] - Y[:, 3]) ** 2
    assert np.min(screw) >= 0.0
    assert np.max(np.abs(r["inerter.p_loss"] - damper - screw)) <= 1e-8
    from scipy.integrate import trapezoid
    assert trapezoid(screw, r.time) > 0.5 * r["inerter.e_loss"][-1]


@pytest.mark.parametrize("vs", [0.0, SERIES_VS], ids=["switch", "vs"])
@pytest.mark.parametrize("gap", [0.0, 4e-3], ids=["compliance", "backlash"])
def test_in_series_efficiencies_of_one_are_the_compliance_alone(tmp_path, vs, gap):
    """Reference: the same scene's run without the efficiency (compliance, and backlash). η_f = η_b
    = 1 gives b_eff = b exactly (1 + λ = 1), so every output the two share agrees to 1e-12 of its
    range (measured: bit for bit), p_loss and e_loss included: the screw's loss is 0."""
    ref = _series(tmp_path, gap=gap, efficiency=False, loss=True).simulate(metrics=False)
    real = _series(tmp_path, gap=gap, vs=vs, etaf=1.0, etab=1.0, loss=True).simulate(metrics=False)
    assert real.status == ref.status == "ok", real.message
    assert np.array_equal(real.time, ref.time)
    for name in ref.names:
        scale = max(1.0, float(np.max(np.abs(ref[name]))))
        assert np.max(np.abs(real[name] - ref[name])) <= 1e-12 * scale, name


@pytest.fixture(scope="module")
def series_efficiency_fmu(tmp_path_factory):
    pytest.importorskip("fmpy")
    from inerter.fmu import build as fmu_build
    path = tmp_path_factory.mktemp("series_efficiency_scene")
    model = _series(path, vs=SERIES_VS, loss=True,
                    experiment='\n[experiment]\nstop_time = 3.0\noutput_interval = 0.01\nrtol = 1e-10\natol = 1e-12\n')
    scene = next(path.glob("*.toml"))                 # the scene file _series wrote
    return scene, fmu_build.build(scene, tmp_path_factory.mktemp("series_efficiency_fmu"), force=True)


def test_the_fmu_of_a_series_efficiency_validates_and_matches_the_solver(series_efficiency_fmu):
    """Reference: the solver's run of the same scene. The FMU (compliance, efficiency with v_s =
    1e-2 m/s, dissipated energy) validates with fmpy, η_f, η_b and k_c are tunable parameters, and its
    run at η_f = 0.7, η_b = 0.5 matches the solver's at the same values to 1e-8 (the mass's position,
    the inerter's force, s_series, mode, p_loss and e_loss) over 2 s."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu
    from inerter.fmu.run import simulate_fmu
    scene, fmu = series_efficiency_fmu
    assert validate_fmu(str(fmu)) == []
    md = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    for name in ("etaf", "etab", "kc"):
        assert md[name].causality == "parameter" and md[name].variability == "tunable", name
    assert {"inerter.mode", "inerter.p_loss", "inerter.e_loss", "inerter.s_series"} <= set(md)
    values = {"etaf": 0.7, "etab": 0.5}
    r = simulate_fmu(scene, values, stop_time=2.0, step=0.01, fmu_path=fmu, metrics=False)
    assert r.status == "ok", r.message
    ref = inerter.load(scene, **values).simulate(stop_time=2.0, output_interval=0.01, metrics=False)
    for name in ("P.r[1]", "inerter.f", "inerter.s_series", "inerter.mode", "inerter.p_loss", "inerter.e_loss"):
        assert np.max(np.abs(r[name] - ref[name])) <= 1e-8, name
