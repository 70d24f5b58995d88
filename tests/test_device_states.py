"""An inerter device's internal states (y = [q, v, z]): series compliance against the closed form
of the linear 2-DOF system and its stiff limit, the ideal inerter's centripetal law through the
series connection, backlash (free-wheeling in the gap, engagement at its closed-form time), the
dissipated energy as a state (energy + e_loss = initial energy), end-stop events against the
Hertz contact's closed form, the hard cases at the tightest tolerance, and the states through the
FMU (get/set/serialise state, tunable series stiffness, outputs against the solver).

Every reference is named in its test: a closed form, an explicit model written from the device's
definition (backlash), the ideal inerter's own run, or the initial energy.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import inerter
from test_device import OSCILLATOR, _load

ROOT = Path(__file__).resolve().parents[1]
SERIES = ROOT / "scenarios" / "series_inerter_2d.toml"
TWO_BAR = ROOT / "scenarios" / "two_bar_2d.toml"
HARD = ROOT / "scenarios" / "hard"
HARD_DEVICES = ("stick_slip_device_2d", "backlash_device_2d", "end_stop_device_2d")


def two_dof(m, k, b, kc, x0, t):
    """Closed form: x(t) of m ẍ = −k x − k_c (x − y), b ÿ = k_c (x − y) from x = y = x0 at rest
    (s = x − y = 0), by the modes of K φ = ω² M φ, M = diag(m, b), K = [[k + k_c, −k_c], [−k_c,
    k_c]] (mass-normalised: x(t) = Σ φ_x φᵀ M X0 cos ω t); and the frequencies (Hz) from
    m b ω⁴ − (m k_c + b (k + k_c)) ω² + k k_c = 0."""
    M = np.diag([m, b])
    K = np.array([[k + kc, -kc], [-kc, kc]])
    Minv_half = np.diag(1.0 / np.sqrt([m, b]))
    w2, V = np.linalg.eigh(Minv_half @ K @ Minv_half)
    Phi = Minv_half @ V
    a = Phi.T @ M @ np.array([x0, x0])
    x = (Phi[0] * a * np.cos(np.sqrt(w2)[None, :] * t[:, None])).sum(axis=1)
    A, B, C = m * b, -(m * kc + b * (k + kc)), k * kc
    roots = sorted(((-B - s * math.sqrt(B * B - 4 * A * C)) / (2 * A)) for s in (1, -1))
    return x, np.sqrt(roots) / (2 * math.pi), np.sqrt(w2) / (2 * math.pi)


# ------------------------------------------------------------------------------------------------
# Series compliance
# ------------------------------------------------------------------------------------------------
def test_series_compliance_has_the_two_natural_frequencies_of_the_2dof_system():
    """Closed form (two_dof): the shipped scene's free response is the 2-DOF system's, whose
    frequencies are 0.869 and 4.120 Hz (the scene's comment), to 1e-9 m over 5 s (DOP853 at rtol
    1e-10, 376 steps: measured 2e-11 m); its energy ½ m ẋ² + ½ k x² + ½ b u̇² + ½ k_c s² stays
    ½ k x0² to 1e-9 relative; s_series = x − y starts at 0."""
    r = inerter.load(SERIES).simulate(metrics=False)
    assert r.status == "ok", r.message
    x_ref, f_closed, f_modes = two_dof(1.0, 100.0, 2.0, 400.0, 0.1, r.time)
    np.testing.assert_allclose(f_closed, f_modes, rtol=1e-12)
    np.testing.assert_allclose(f_closed, [0.8695, 4.1201], atol=1e-4)
    assert np.max(np.abs(r["P.r[1]"] - x_ref)) <= 1e-9
    assert np.max(np.abs(r["energy"] - 0.5)) <= 1e-9 * 0.5
    assert r["inerter.s_series"][0] == 0.0 and np.max(np.abs(r["inerter.s_series"])) > 1e-3
    # the inerter's force is the series spring's: f = k_c s
    np.testing.assert_allclose(r["inerter.f"], 400.0 * r["inerter.s_series"], rtol=1e-12, atol=1e-12)


def test_a_stiff_series_spring_recovers_the_ideal_inerter(tmp_path):
    """Reference: the ideal inerter's own run, and the closed form at each k_c. As k_c grows from
    1e3 to 1e6 N/m the response approaches the ideal element's, the gap falling as 1/k_c (the
    low mode's frequency shift, ∝ 1/k_c, accumulates over 5 s as a phase): measured 5.9e-2,
    6.4e-3, 6.4e-4, 5.9e-5 m (k_c times the gap 59 to 64 m·N/m), each run within 1e-8 m of its
    closed form."""
    text = SERIES.read_text(encoding="utf-8")
    head, _ = text.split("[elements.inerter.device.compliance]")
    ideal = _load(tmp_path, head + text[text.index("[experiment]"):]).simulate(metrics=False)
    gaps = []
    for kc in (1e3, 1e4, 1e5, 1e6):
        r = inerter.load(SERIES, kc=kc).simulate(metrics=False)
        assert r.status == "ok", r.message
        x_ref, _, _ = two_dof(1.0, 100.0, 2.0, kc, 0.1, r.time)
        assert np.max(np.abs(r["P.r[1]"] - x_ref)) <= 1e-8, kc
        gaps.append(float(np.max(np.abs(r["P.r[1]"] - ideal["P.r[1]"]))))
    for coarse, fine in zip(gaps, gaps[1:]):
        assert 8.0 < coarse / fine < 12.0, gaps
    assert gaps[-1] < 1e-4


def _two_bar(tmp_path, kc=None, centripetal=True):
    text = TWO_BAR.read_text(encoding="utf-8")
    if not centripetal:
        text = text.replace("centripetal = true", "centripetal = false")
    if kc is not None:
        text += f"\n[elements.inerter.device.compliance]\nstiffness = {kc}\n"
    name = f"two_bar_{kc}_{centripetal}.toml"
    return _load(tmp_path, text, name=name).simulate(stop_time=3.0, metrics=False)


def test_the_series_connection_keeps_the_inerters_centripetal_law(tmp_path):
    """Reference: the ideal two-bar's own runs, with the centripetal term (Eq. 9) and without
    (Eq. 8), which differ by 0.056 m in C.r[2] over 3 s. With a stiff series spring the device
    converges to the ideal element of the same law as 1/k_c (the inerter's stroke acceleration
    ü = L̈ − s̈, with L̈'s |ṙ⊥|²/L where the scene has it): measured 1.74e-5 and 1.74e-6 m at k_c =
    1e6 and 1e7 N/m with the term, 2.55e-5 and 2.55e-6 m without; so the series node carries the
    law's centripetal part, not a 1D stroke's."""
    gap = None
    for centripetal in (True, False):
        ideal = _two_bar(tmp_path, centripetal=centripetal)
        gap = float(np.max(np.abs(ideal["C.r[2]"] - _two_bar(tmp_path, centripetal=not centripetal)["C.r[2]"])))
        errors = []
        for kc in (1e6, 1e7):
            real = _two_bar(tmp_path, kc=kc, centripetal=centripetal)
            assert real.status == "ok", real.message
            errors.append(float(np.max(np.abs(real["C.r[2]"] - ideal["C.r[2]"]))))
        assert 9.0 < errors[0] / errors[1] < 11.0 and errors[1] < 1e-4 * gap, (centripetal, errors, gap)
    assert gap > 0.05


DEVICE_TWO_BAR = ROOT / "scenarios" / "two_bar_2d_device.toml"


def test_flywheel_and_friction_act_on_the_inerters_own_stroke(tmp_path):
    """Reference: the shipped ball-screw device (flywheel, friction and end stops on L̇) run
    without compliance. With a stiff undamped series spring the motion converges to it as 1/k_c
    (measured 3.5e-4 and 3.5e-5 of C.r[2]'s range at k_c = 1e6 and 1e7 N/m over 1 s), and the
    flywheel speed n·u̇ and the friction on the inerter's own stroke rate u̇ = L̇ − ṡ as 1/√k_c:
    the series mode, excited and undamped, keeps ṡ oscillating with an amplitude of order
    F/√(k_c b) (measured 1.2e-2 and 2.6e-3, 3.2e-3 and 9.8e-4 of their ranges). So the series node
    hands the device's other effects the stroke rate, and they tend to their own values on L̇."""
    ref = inerter.load(DEVICE_TWO_BAR).simulate(stop_time=1.0, metrics=False)
    text = DEVICE_TWO_BAR.read_text(encoding="utf-8")
    errors = []
    for kc in (1e6, 1e7):
        r = _load(tmp_path, text + f"\n[elements.inerter.device.compliance]\nstiffness = {kc}\n",
                  name=f"device_{kc}.toml").simulate(stop_time=1.0, metrics=False)
        assert r.status == "ok", r.message
        errors.append([float(np.max(np.abs(r[n] - ref[n])) / np.max(np.abs(ref[n])))
                       for n in ("C.r[2]", "inerter.w_flywheel", "inerter.f_friction")])
    ratios = [coarse / fine for coarse, fine in zip(*errors)]
    assert 8.0 < ratios[0] < 12.0, errors                                # 1/k_c
    assert 2.5 < ratios[1] < 6.0 and 2.5 < ratios[2] < 6.0, errors     # about √10 = 3.2
    assert max(errors[1]) < 1e-2, errors


SPHERICAL = ROOT / "scenarios" / "spherical_pendulum_3d.toml"


def test_series_compliance_in_3d(tmp_path):
    """The 3D kernels' internal states. Closed form (two_dof): the series scene built in 3D
    follows the 2-DOF response to 1e-9 m. Reference: the ideal spherical pendulum's own run, set
    spinning faster than its conical motion (w = 4 rad/s: the rod sweeps round while its length
    oscillates, the inerter's centripetal term at work): with a series spring the bob's position
    converges to it as 1/k_c over 0.4 s: measured 1.6e-4 and 1.6e-5 m at k_c = 1e4 and 1e5 N/m."""
    text = SERIES.read_text(encoding="utf-8").replace('name = "series_inerter_2d"', 'name = "s3"\ndimension = 3')
    text = text.replace("O = [-1.0, 0.0]", "O = [-1.0, 0.0, 0.0]").replace('position = ["x0", 0.0]',
                                                                       'position = ["x0", 0.0, 0.0]')
    text = text.replace("inertia = 1.0", "inertia = [1.0, 1.0, 1.0]").replace("P = [0, 0]", "P = [0, 0, 0]")
    r = _load(tmp_path, text, name="series3.toml").simulate(metrics=False)
    assert r.status == "ok", r.message
    x_ref, _, _ = two_dof(1.0, 100.0, 2.0, 400.0, 0.1, r.time)
    assert np.max(np.abs(r["P.r[1]"] - x_ref)) <= 1e-9
    ideal = inerter.load(SPHERICAL, w=4.0).simulate(stop_time=0.4, metrics=False)
    errors = []
    for kc in (1e4, 1e5):
        device = f"\n[elements.inerter.device.compliance]\nstiffness = {kc}\n"
        real = _load(tmp_path, SPHERICAL.read_text(encoding="utf-8") + device, name=f"sph{kc}.toml",
                     w=4.0).simulate(stop_time=0.4, metrics=False)
        assert real.status == "ok", real.message
        errors.append(max(float(np.max(np.abs(real[c] - ideal[c]))) for c in ("P.r[1]", "P.r[2]", "P.r[3]")))
    assert 8.0 < errors[0] / errors[1] < 12.0 and errors[1] < 1e-4, errors


def test_an_implicit_stepper_integrates_the_internal_states():
    """Closed form (_series_states, the 2-DOF system's modes): Radau's co-simulation stepper on the
    kernels' right-hand side (the compiled loop takes the explicit methods only) carries the
    series deflection, and so does the numpy path's stepper (the readable evaluators): at 1 s the
    mass's x and ẋ and E.s_series = x − y agree with the 2-DOF response to 1e-7 (m, m/s; rtol
    1e-10), the force is k_c s to 1e-12 relative, and the energy ½ k x0² to 1e-7 relative (no
    damping)."""
    model = inerter.load(SERIES)
    x, v, y = (value[0] for value in _series_states(np.array([1.0])))
    for path in ("compiled", "numpy"):
        stepper = model.stepper(method="Radau", rtol=1e-10, atol=1e-12, path=path)
        for k in range(1, 101):
            stepper.step(0.01 * k)
        out = stepper.outputs()
        assert abs(out["P.r[1]"] - x) <= 1e-7 and abs(out["P.v[1]"] - v) <= 1e-7, path
        assert abs(out["inerter.s_series"] - (x - y)) <= 1e-7 and abs(x - y) > 1e-4, path
        assert out["inerter.f"] == pytest.approx(400.0 * out["inerter.s_series"], rel=1e-12), path
        assert out["energy"] == pytest.approx(0.5 * 100.0 * 0.1 ** 2, rel=1e-7), path


# ------------------------------------------------------------------------------------------------
# Backlash
# ------------------------------------------------------------------------------------------------
def test_backlash_free_wheels_in_the_gap_and_engages_at_the_closed_form_time(tmp_path):
    """Closed form: starting in the middle of a gap Δ = 4 mm (s = 0), the inerter free-wheels
    (no force, its stroke rate stays 0: the node does not move), so the mass oscillates alone,
    x = x0 cos(√(k/m) t), until s = x − x0 reaches −Δ/2 at t_e = arccos(1 − Δ/(2 x0))/√(k/m);
    there the gap closes: E.engaged turns 1 and the reported event is at t_e to 1e-9 s."""
    m, k, x0, gap = 1.0, 100.0, 0.25, 4e-3
    t_e = math.acos(1.0 - gap / (2 * x0)) / math.sqrt(k / m)
    text = OSCILLATOR + f"""
[elements.inerter.device.compliance]
stiffness = 1e4
damping = 5.0

[elements.inerter.device.backlash]
gap = {gap}

[experiment]
stop_time = 1.0
output_interval = 0.001
"""
    r = _load(tmp_path, text).simulate(method="DOP853", rtol=1e-12, atol=1e-14, metrics=False)
    assert r.status == "ok", r.message
    free = r.time < t_e
    np.testing.assert_allclose(r["P.r[1]"][free], x0 * np.cos(math.sqrt(k / m) * r.time[free]), rtol=0, atol=1e-10)
    assert np.all(r["inerter.engaged"][free] == 0.0) and np.all(r["inerter.f"][free] == 0.0)
    assert r["inerter.engaged"][np.searchsorted(r.time, t_e) + 1] == 1.0
    first = r.events()[0]
    assert first["event"] == "engaged" and first["where"] == "gap, negative side"
    assert abs(first["time"] - t_e) <= 1e-9, (first["time"], t_e)
    assert r.summary()["events"][0] == first


# ------------------------------------------------------------------------------------------------
# Dissipated energy as a state
# ------------------------------------------------------------------------------------------------
DISSIPATIVE = {
    "friction-fluid-stops": """
[elements.inerter.device.friction]
coulomb = 0.5
viscous = 0.2
velocity_scale = 1e-2

[elements.inerter.device.end_stops]
min = 0.85
max = 1.27
stiffness = 5e4
damping = 2e4
exponent = 1.5

[elements.inerter.device.fluid]
density = 1.0
channel_length = 1.0
channel_area = 1.0
piston_area = 1.0
linear_damping = 0.1
quadratic_damping = 2.0
""",
    "compliance-backlash-friction": """
[elements.inerter.device.friction]
coulomb = 0.5
viscous = 0.2
velocity_scale = 1e-2

[elements.inerter.device.compliance]
stiffness = 2e3
damping = 3.0

[elements.inerter.device.backlash]
gap = 5e-3
""",
}


@pytest.mark.parametrize("case", list(DISSIPATIVE))
def test_energy_plus_the_dissipated_energy_state_is_the_initial_energy(tmp_path, case):
    """Reference: the initial energy. A free oscillation from x = 0.25 m at 1 m/s (no forcing)
    through the device's dissipative effects, E.e_loss = ∫ p_loss integrated with the state
    (device.dissipated_energy): energy + e_loss = energy(0) at every sample to 100·rtol = 1e-10 of
    energy(0), at DOP853 rtol 1e-12. Why that bound: the balance holds exactly along the exact
    flow, and each step keeps its local error below rtol·|y| in every state component, e_loss and
    the energy's ingredients alike, so over N steps the balance can drift by at most about N·rtol
    (343 and 932 steps here: 3e-10 and 9e-10); the errors of successive steps do not add up in
    practice (measured 3.6e-12 and 1.4e-12), and 100·rtol sits between the two. The Simpson
    quadrature of p_loss on samples (test_device) reaches only 2e-9 to 4e-8."""
    text = OSCILLATOR + DISSIPATIVE[case] + """
[elements.inerter.device.dissipated_energy]

[experiment]
stop_time = 2.0
output_interval = 1e-3
"""
    if "fluid" in DISSIPATIVE[case]:
        text = text.replace('b = "b"\n', "")          # the channel gives b = 1 kg
    r = _load(tmp_path, text, v0=1.0).simulate(method="DOP853", rtol=1e-12, atol=1e-14, metrics=False)
    assert r.status == "ok", r.message
    E, lost = r["energy"], r["inerter.e_loss"]
    assert lost[0] == 0.0 and np.all(np.diff(lost) >= -1e-15) and lost[-1] > 0.3 * E[0]
    worst = float(np.max(np.abs(E + lost - E[0])))
    assert worst <= 1e-10 * E[0], worst / E[0]


# ------------------------------------------------------------------------------------------------
# End-stop events
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [1.0, 1.5])
def test_end_stop_contact_events_at_the_hertz_closed_form_times(tmp_path, n):
    """Closed form (test_device's undamped end stop): a mass M = 2 kg at v0 = 0.5 m/s reaches the
    upper stop 0.1 m away at t₁ = 0.2 s and leaves it after the contact time t_c of M δ̈ = −k δⁿ;
    the events are (t₁, contact) and (t₁ + t_c, release), found on the dense output to 1e-9 s
    with 1 ms samples."""
    M, v0, k, Lmax = 2.0, 0.5, 2e4, 1.1
    p = n + 1.0
    d_max = (p * M * v0 ** 2 / (2.0 * k)) ** (1.0 / p)
    t_c = 2.0 * d_max / v0 * math.gamma(1.0 / p) * math.gamma(0.5) / (p * math.gamma(1.0 / p + 0.5))
    text = OSCILLATOR.replace('k = 100.0', 'k = 0.0').replace('x0 = 0.25', 'x0 = 0.0').replace('v0 = 0.0', 'v0 = 0.5') \
        + f'\n[elements.inerter.device.end_stops]\nmax = {Lmax}\nstiffness = {k}\nexponent = {n}\n' \
        + '\n[experiment]\nstop_time = 0.4\noutput_interval = 0.001\n'
    r = _load(tmp_path, text).simulate(method="DOP853", rtol=1e-12, atol=1e-14, metrics=False)
    events = r.events()
    assert [(e["event"], e["where"]) for e in events] == [("contact", "upper stop"), ("release", "upper stop")]
    assert abs(events[0]["time"] - 0.2) <= 1e-9 and abs(events[1]["time"] - (0.2 + t_c)) <= 1e-9, events


# ------------------------------------------------------------------------------------------------
# Hard cases at the tightest tolerance
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", HARD_DEVICES)
def test_device_hard_cases_run_stable_at_the_tightest_tolerance(name):
    """Stick-slip, backlash impacts and end-stop contact over 5 s at DOP853 rtol 1e-13 (atol
    1e-15): the run completes (no step-size collapse, no stiffness stop; the monitor would fail
    it), with a step count of the same order as at 1e-12 (measured 3612, 5880, 1984 against 2549,
    4735, 1553: the steps grow as rtol^(-1/8)·a few, not without bound) and energy + e_loss
    growing only by the force's work (e_loss ≥ 0, never decreasing)."""
    model = inerter.load(HARD / f"{name}.toml")
    steps = {}
    for rtol in (1e-12, 1e-13):
        r = model.simulate(rtol=rtol, atol=rtol * 1e-2, metrics=False)
        assert r.status == "ok", r.message
        steps[rtol] = r.run.steps
        assert np.all(np.diff(r["inerter.e_loss"]) >= -1e-15)
    assert steps[1e-13] <= 2.0 * steps[1e-12], steps


# ------------------------------------------------------------------------------------------------
# Through the FMU
# ------------------------------------------------------------------------------------------------
fmpy = pytest.importorskip("fmpy")


@pytest.fixture(scope="module")
def series_fmu(tmp_path_factory):
    from inerter.fmu import build as fmu_build
    return fmu_build.build(SERIES, tmp_path_factory.mktemp("series_fmu"), force=True)


def test_fmu_state_holds_the_internal_states(series_fmu, tmp_path):
    """Get the FMU state mid-run, go on, set it back and go on again: the same outputs bit for bit,
    the series deflection included (in memory and through serialisation); the FMU validates."""
    from fmpy.validation import validate_fmu
    from test_fmu import Instance
    from fmpy import extract
    assert validate_fmu(str(series_fmu)) == []
    inst = Instance(extract(str(series_fmu), unzipdir=str(tmp_path / "x")))
    try:
        inst.initialise()
        assert "inerter.s_series" in inst.outputs
        t = 0.0
        for _ in range(30):
            inst.fmu.doStep(t, 0.01)
            t += 0.01
        state = inst.fmu.getFMUstate()
        blob = inst.fmu.serializeFMUstate(state)

        def go_on():
            rows, tt = [], t
            for _ in range(20):
                inst.fmu.doStep(tt, 0.01)
                tt += 0.01
                rows.append(inst.get(inst.outputs))
            return rows
        first = go_on()
        assert first[-1][inst.outputs.index("inerter.s_series")] != 0.0
        inst.fmu.setFMUstate(state)
        assert go_on() == first
        inst.fmu.setFMUstate(inst.fmu.deSerializeFMUstate(blob))
        assert go_on() == first
        inst.fmu.freeFMUstate(state)
    finally:
        inst.close()


def test_the_fmus_series_stiffness_is_tunable_and_its_run_matches_the_solver(series_fmu):
    """The FMU's k_c is a tunable parameter; its run at k_c = 900 N/m matches the solver's at the
    same value (and the closed form) to 1e-8 m."""
    from fmpy import read_model_description
    from inerter.fmu.run import simulate_fmu
    md = read_model_description(str(series_fmu))
    kc = next(v for v in md.modelVariables if v.name == "kc")
    assert kc.causality == "parameter" and kc.variability == "tunable"
    r = simulate_fmu(SERIES, {"kc": 900.0}, stop_time=2.0, step=0.01, fmu_path=series_fmu, metrics=False)
    assert r.status == "ok", r.message
    ref = inerter.load(SERIES, kc=900.0).simulate(stop_time=2.0, output_interval=0.01, metrics=False)
    x_ref, _, _ = two_dof(1.0, 100.0, 2.0, 900.0, 0.1, ref.time)
    assert np.max(np.abs(r["P.r[1]"] - ref["P.r[1]"])) <= 1e-8
    assert np.max(np.abs(r["inerter.s_series"] - ref["inerter.s_series"])) <= 1e-8
    assert np.max(np.abs(ref["P.r[1]"] - x_ref)) <= 1e-8


def test_projection_and_scipys_integrators_carry_the_internal_states():
    """Closed form (two_dof): the projection treatment (scipy's DOP853 on the kernels' right-hand
    side, (q, v) projected at every output point, z left alone) and Radau's whole run follow the
    2-DOF response to 1e-8 m over 2 s (rtol 1e-10)."""
    model = inerter.load(SERIES)
    for kwargs in (dict(constraint="projection"), dict(method="Radau")):
        r = model.simulate(stop_time=2.0, rtol=1e-10, atol=1e-12, metrics=False, **kwargs)
        assert r.status == "ok" and "compiled right-hand side" in r.run.extra["path"], (kwargs, r.message)
        x_ref, _, _ = two_dof(1.0, 100.0, 2.0, 400.0, 0.1, r.time)
        assert np.max(np.abs(r["P.r[1]"] - x_ref)) <= 1e-8, kwargs
        np.testing.assert_allclose(r["inerter.f"], 400.0 * r["inerter.s_series"], rtol=1e-12, atol=1e-12)


def _series_states(t, m=1.0, k=100.0, b=2.0, kc=400.0, x0=0.1):
    """Closed form (the modes of two_dof): the mass's x(t) and ẋ(t) and the inerter node's y(t) of
    the series scene from x = y = x0 at rest; the series deflection is s = x − y."""
    M, K = np.diag([m, b]), np.array([[k + kc, -kc], [-kc, kc]])
    Minv_half = np.diag(1.0 / np.sqrt([m, b]))
    w2, V = np.linalg.eigh(Minv_half @ K @ Minv_half)
    Phi = Minv_half @ V
    a = Phi.T @ M @ np.array([x0, x0])
    w = np.sqrt(w2)
    modes, rates = a * np.cos(w[None, :] * t[:, None]), -a * w * np.sin(w[None, :] * t[:, None])
    return (Phi[0] * modes).sum(axis=1), (Phi[0] * rates).sum(axis=1), (Phi[1] * modes).sum(axis=1)


def _backlash_model(p, t_eval):
    """An explicit model of scenarios/hard/backlash_device_2d.toml, written from the device's
    definition (inerter.elements.device, "Backlash"; Wang & Su 2008, Sec. 3), independently of
    the package: the mass x on the line O-P (L = 1 + x, no lateral motion), the inerter's node
    behind a series spring-damper with a dead zone of width Δ,
    m ẍ = −k x − F + F0 sin 2πft,  b ü = F with u = x − s (so s̈ = ẍ − F/b),
    F = k_c d + c_c ṡ beyond the gap (d = s ∓ Δ/2), clipped to 0 where it would pull the engaged
    sides apart, F = 0 inside it. Integrated by scipy's DOP853 at rtol 1e-13, atol 1e-15 (no
    event location: the error control meets the impacts by shortening the steps, as the engine's).
    Returns x, ẋ, s, F at `t_eval`."""
    half = p["gap"] / 2.0

    def force(s, sd):
        if abs(s) <= half:
            return 0.0
        d = s - math.copysign(half, s)
        f = p["kc"] * d + p["cc"] * sd
        return max(f, 0.0) if d > 0 else min(f, 0.0)

    def rhs(t, y):
        x, v, s, sd = y
        f = force(s, sd)
        a = (-p["k"] * x - f + p["F0"] * math.sin(2.0 * math.pi * p["f"] * t)) / p["m"]
        return [v, a, sd, a - f / p["b"]]

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), [0.0, 0.0, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-15,
                    t_eval=t_eval)
    assert sol.status == 0, sol.message
    x, v, s, sd = sol.y
    return x, v, s, np.array([force(a, b) for a, b in zip(s, sd)])


@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("scene, tolerance", [(SERIES, 1e-9), (HARD / "backlash_device_2d.toml", 1e-7)],
                         ids=["series", "backlash"])
def test_both_paths_integrate_the_internal_states(scene, tolerance, path):
    """Over 1 s (DOP853 at the scenes' rtol 1e-10), each path (the compiled loop, and the numpy
    path: scipy's DOP853 on the readable evaluators; the engine against the oracle's derivation of
    the internal states is tests/test_engine_vs_oracle.py)
    against a reference of its own: for the series scene the closed form of its two modes
    (_series_states), for the backlash scene an explicit model (_backlash_model). The mass's
    position and velocity, the series deflection, the device's force (and the spring's) within
    `tolerance` of max(1, the output's range), the tolerances the two paths were held to against
    each other: 1e-9 (series) and 1e-7 (backlash: the impacts make the steps sensitive to
    round-off). Measured, worst over the outputs and the paths: 1.4e-10 (series, the force) and
    8.1e-10 (backlash, the force: 1.5e-8 N of 18 N). E.engaged is 1 exactly where |s| > Δ/2."""
    model = inerter.load(scene)
    r = model.simulate(stop_time=1.0, metrics=False, path=path)
    assert r.status == "ok", r.message
    assert r.run.extra.get("path", "numpy") == path
    p = {name: model.scene.parameters[name].value for name in model.scene.parameters}
    if scene == SERIES:
        x, v, y = _series_states(r.time, p["m"], p["k"], p["b"], p["kc"], p["x0"])
        s, f = x - y, p["kc"] * (x - y)
    else:
        x, v, s, f = _backlash_model(p, r.time)
        engaged = np.abs(r["inerter.s_series"]) > p["gap"] / 2.0
        assert np.array_equal(r["inerter.engaged"] == 1.0, engaged)
    expected = {"P.r[1]": x, "P.v[1]": v, "inerter.s_series": s, "inerter.f": f, "spring.f": p["k"] * x}
    for name, value in expected.items():
        scale = max(1.0, float(np.ptp(value)))
        assert np.max(np.abs(r[name] - value)) <= tolerance * scale, (name, np.max(np.abs(r[name] - value)))


def test_the_linearisation_refuses_internal_states():
    """The linearisation is of (q, v): for a series-compliant device it would miss the series
    mode (it would report √(k/m) alone), so it refuses in one line."""
    with pytest.raises(inerter.SimulationError, match="internal states"):
        inerter.load(SERIES).natural_frequencies()
