"""The compiled path as the default, and its dense output: every accepted step's polynomial kept by
the compiled DOP853 and RK45 loops (inerter.engine.compiled.DenseOutput), the metrics computed from
it, and the output signals evaluated on it in the kernels.

References: the oracle (`model.oracle()`: element forces derived from L(q) on Jets, integrated by
scipy, whose dense output and metrics are scipy's), run at the same settings, so that it takes the
same steps as the compiled loop (right-hand sides equal to round-off); closed forms where a scene
has one. The numpy path is the reference only where the check is of the two paths' plumbing."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import inerter
from conftest import LUMPED, SCENARIOS, TWO_BAR
from inerter.engine import compiled

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT)

STOP = 20.0
STEP_FORCE = SCENARIOS / "hard" / "step_force_1dof_2d.toml"
GIMBAL = SCENARIOS / "gimbal_lock_3d.toml"


@pytest.fixture(scope="module")
def paper():
    """Both paper scenes over 0-20 s with their metrics, on the compiled path and on the oracle at the
    scene's settings (the oracle's integration, dense output and metrics are scipy's)."""
    out = {}
    for scene in (LUMPED, TWO_BAR):
        model = inerter.load(scene)
        out[model.name] = (model, {"compiled": model.simulate(stop_time=STOP, path="compiled"),
                                   "oracle": model.oracle().simulate(stop_time=STOP)})
    return out


def between_samples(time, extra=400, seed=0):
    """The midpoints of the sample intervals and random times, none of them a sample."""
    rng = np.random.default_rng(seed)
    return np.sort(np.concatenate((0.5 * (time[1:] + time[:-1]), rng.uniform(time[0], time[-1], extra))))


# ---------------------------------------------------------------------------------------------
# The default path
# ---------------------------------------------------------------------------------------------
def test_the_default_path_is_the_compiled_one_in_2d_and_3d():
    for scene in (TWO_BAR, GIMBAL):
        model = inerter.load(scene)
        assert model.simulate(stop_time=0.1, metrics=False).run.extra["path"] == "compiled"
        assert model.stepper().path == "compiled"
    numpy_run = inerter.load(TWO_BAR).simulate(stop_time=0.1, metrics=False, path="numpy")
    assert "path" not in numpy_run.run.extra and numpy_run.summary()["statistics"]["path"] == "numpy"


def test_euler_angle_scenes_run_compiled_and_stop_at_their_singularity():
    """Z-X-Z Euler angles run on the compiled path too; through their singularity the loop stops as
    the numpy path does (the same number of samples: plumbing of the two paths' checks), naming the
    body. Reference for the samples before it: the closed form of the steady spin about global X
    (the spinner's major axis): the state's Z-X-Z angles φ = ψ = 0, θ = α0 + ω t, the points
    P = (0, cos θ, sin θ), Q = (0, −sin θ, cos θ), the quaternion output (cos θ/2, sin θ/2, 0, 0),
    within 1e-12 (the Euler rates are constant, so each DOP853 step is exact up to round-off:
    measured 4e-16), the bound the two paths were held to against each other (the kinematics,
    rotations.euler_matrix9 and euler_rates, are the same code compiled and not)."""
    model = inerter.load(GIMBAL, **{"scene.orientation": "euler_zxz"})
    result = model.simulate(stop_time=0.1, metrics=False)
    assert result.status == "ok", result.message
    assert result.run.extra["path"] == "compiled"
    assert model.stepper().path == "compiled"
    fast = model.simulate(metrics=False)
    slow = model.simulate(metrics=False, path="numpy")
    assert fast.status == slow.status == "failed"
    assert "spinner" in fast.message and "singularity" in fast.message and "t = " in fast.message
    assert len(fast.time) == len(slow.time) >= 3
    a0, w = (model.scene.parameters[p].value for p in ("alpha0", "omega"))
    for run in (fast, slow):
        theta = a0 + w * run.time
        exact = {"P.r[1]": 0.0 * theta, "P.r[2]": np.cos(theta), "P.r[3]": np.sin(theta),
                 "Q.r[1]": 0.0 * theta, "Q.r[2]": -np.sin(theta), "Q.r[3]": np.cos(theta),
                 "spinner.q[1]": np.cos(theta / 2), "spinner.q[2]": np.sin(theta / 2)}
        for name, value in exact.items():
            assert np.max(np.abs(run[name] - value)) <= 1e-12, name
        angles = run.run.states[:, model.mechanism.q_index[0] + 3:model.mechanism.q_index[0] + 6]
        assert np.max(np.abs(angles - np.column_stack((0.0 * theta, theta, 0.0 * theta)))) <= 1e-12


# ---------------------------------------------------------------------------------------------
# Metrics from the dense output
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["lumped_mass_2d", "two_bar_2d"])
def test_compiled_metrics_equal_the_oracles_from_scipys_dense_output(paper, name):
    """Reference: the oracle's metrics, from scipy's dense output; the compiled path's come from its
    own, the same polynomials (they were a cubic spline through the 5 ms samples, 6e-9 off in the
    lumped mass's amplitudes). The two trajectories take the same steps and differ only by
    rounding (the lumped mass: by the step sizes that rounding picks, ~1e-8 m after 20 s; measured
    against the oracle: 1.4e-8 m, and 3.5e-11 relative in the amplitudes). The tolerances are those
    the compiled metrics were held to against the numpy path; the natural frequencies (from the
    model's linearisation, not the run) were equal on the two paths, which share the element laws,
    and are within 1e-12 relative of the oracle's (measured 5e-16)."""
    model, runs = paper[name]
    fast, reference = runs["compiled"], runs["oracle"]
    assert fast.status == reference.status == "ok"
    assert fast.run.extra["path"] == "compiled" and isinstance(fast.run.dense, compiled.DenseOutput)
    assert not fast.metric_errors and not reference.metric_errors
    assert set(fast.metrics) == set(reference.metrics)
    scale = {"mean_offset": reference.metrics.get("fundamental_amplitude"),
             "inerter_force_mean": reference.metrics.get("inerter_force_amplitude"),
             "C_y_mean_offset": reference.metrics.get("C_y_peak_to_peak")}
    for key, expected in reference.metrics.items():
        got = fast.metrics[key]
        if key.startswith("natural_frequenc"):
            assert got == pytest.approx(expected, rel=1e-12), key      # from the model, not the run
        elif key == "fundamental_frequency":
            assert abs(got - expected) <= 2e-9, key          # Hz
        elif key in scale:                                   # a mean: against its signal's size
            assert abs(got - expected) <= 1e-9 * scale[key], (key, got, expected)
        else:
            assert got == pytest.approx(expected, rel=1e-9), key


def test_compiled_metrics_of_a_3d_scene_equal_the_oracles_of_its_2d_twin(paper):
    """The two-bar written as a 3D scene (quaternions): the compiled 3D kernels' dense output gives
    the steady state (the last 10 periods of 1 s) of the same mechanism written in 2D
    (two_bar_2d.toml) run on the oracle over the same 20 s: an explicit model of the same motion
    with other coordinates and element forces derived from L(q). Tolerances as against the numpy
    path of the 3D scene before (1e-9 relative; the offset 1e-9 of the peak-to-peak); measured
    1.3e-11 and 3e-15 (12 s runs)."""
    model = inerter.load(SCENARIOS / "two_bar_2d_as_3d.toml")
    fast = model.simulate(stop_time=STOP, path="compiled")
    reference = paper["two_bar_2d"][1]["oracle"]
    assert fast.run.extra["path"] == "compiled" and fast.run.dense is not None and not fast.metric_errors
    assert fast.metrics["C_y_peak_to_peak"] == pytest.approx(reference.metrics["C_y_peak_to_peak"], rel=1e-9)
    assert abs(fast.metrics["C_y_mean_offset"] - reference.metrics["C_y_mean_offset"]) <= \
        1e-9 * reference.metrics["C_y_peak_to_peak"]


@pytest.mark.parametrize("rtol, coarser", [(5e-5, True), (1e-7, True), (1e-9, False)])
def test_a_runs_metrics_sample_only_as_finely_as_its_tolerance_needs(rtol, coarser):
    """The periodic metrics' grid stops where the trapezoidal rule moves by less than
    api.METRIC_GRID_SHARE of the run's rtol (of the signal's spread): the two-bar's steady state
    over 0-20 s at rtol 5e-5 (the cheapest run reaching 1e-6 m), 1e-7 and 1e-9. Reference: the same
    metric on the same dense output sampled on its finest grid (2048 a period, no grid_rtol),
    which the run's must equal within that share (4/3 of it: a second-order rule's error estimated
    from two grids). The window still holds the start's transient, so its grids' means converge as
    h² (measured 2.9e-10 of the spread from 64 to 128 a period, 1.2e-12 from 1024 to 2048): at
    1e-9 the share, 1e-12, is reached on no grid and the run samples the finest one."""
    from inerter import api
    from inerter.engine import metrics
    model = inerter.load(TWO_BAR)
    result = model.simulate(stop_time=STOP, rtol=rtol, atol=rtol / 100)
    spec = next(m for m in model.scene.metrics if m.kind == "steady_state")
    assert spec.signal in model.signals.kinematic
    share = api.metric_grid_rtol(result.settings, True)
    assert share == api.METRIC_GRID_SHARE * rtol
    read = {}

    def counted(key, dense):
        def values(t):
            read[key] = read.get(key, 0) + np.size(t)
            return dense(t)
        return values

    t, x, dense = result.time, result[spec.signal], result.dense(spec.signal)
    run = metrics.steady_state(t, x, spec.period, spec.periods, 0.0, counted("run", dense), grid_rtol=share)
    finest = metrics.steady_state(t, x, spec.period, spec.periods, 0.0, counted("finest", dense))
    spread = finest["peak_to_peak"]
    assert abs(run["mean"] - finest["mean"]) <= 4.0 / 3.0 * share * spread
    assert abs(run["peak_to_peak"] - finest["peak_to_peak"]) <= 4.0 / 3.0 * share * spread
    assert result.metrics[f"{spec.prefix}_mean_offset"] == run["mean_offset"] - model.static_value(spec.signal)
    if coarser:
        assert read["run"] < read["finest"] / 4
    else:
        assert read["run"] == read["finest"] and run == finest


def test_only_an_output_without_pulses_of_a_run_with_a_tolerance_starts_from_a_coarse_grid(tmp_path):
    """A device's end stop or backlash pulses (its contact), and every force that reads q̈ with it,
    narrower than a coarse grid's step, which two coarse grids would both miss and agree on; a
    derived output may pulse in any scene (an expression such as max(0, x − 0.99)). Their periodic
    metrics read the finest grid (grid_rtol None), as do those of a fixed-step run (RK4 keeps no
    tolerance) and of a history without settings. The outputs of the motion (the points' and
    bodies', an element's s_rel, v_rel, phi_rel, w_rel: listed by hand here) never pulse; in a scene
    without a device, neither does an element's force, power or energy, nor the energy."""
    from inerter import api
    model = inerter.load(TWO_BAR)
    adaptive, fixed = model.settings(rtol=1e-6), model.settings(method="RK4", step=1e-3)
    assert api.metric_grid_rtol(adaptive, True) == pytest.approx(1e-9, rel=1e-15)
    assert api.metric_grid_rtol(model.settings(rtol=1e-11), True) == api.METRIC_GRID_FLOOR
    assert api.metric_grid_rtol(adaptive, False) is None
    assert api.metric_grid_rtol(fixed, True) is None and api.metric_grid_rtol(None, True) is None
    motion = {n for n in model.signals.names if n.split(".")[-1].split("[")[0] in ("r", "v", "s_rel", "v_rel", "phi_rel", "w_rel")}
    assert motion and model.signals.kinematic == motion
    element_names = {name for name in model.scene.elements}
    forces = {n for n in model.signals.names if n.split(".")[0] in element_names} - motion
    assert forces and model.signals.pulse_free == motion | forces | {"energy"}
    device = inerter.load(SCENARIOS / "two_bar_2d_device.toml").signals
    extras = [n for n in device.names if n.endswith((".s_series", ".w_flywheel", ".f_stop", ".f", ".energy"))]
    assert extras and not device.pulse_free & set(extras) and device.pulse_free == device.kinematic
    scene = tmp_path / "lumped_derived.toml"
    scene.write_text(LUMPED.read_text() + '\n[outputs.derived]\nlift = { expression = "P.r[2] / Lb", unit = "1" }\n')
    derived = inerter.load(scene).signals
    assert "lift" in derived.names and "lift" not in derived.pulse_free and "inerter.f" in derived.pulse_free
    spatial = inerter.load(SCENARIOS / "two_bar_2d_as_3d.toml").signals
    assert {n for n in spatial.names if ".q[" in n or ".w[" in n or ".euler[" in n} <= spatial.kinematic


@pytest.mark.parametrize("rtol, coarser", [(5e-5, 4), (1e-7, 2)])
def test_a_force_of_a_scene_without_a_device_is_sampled_only_as_finely_as_its_tolerance_needs(rtol, coarser):
    """lumped_mass_2d's `harmonics` metric of its inerter's force (a force that reads q̈, in a scene
    without a device) starts from a coarse grid. Reference: the same metric on the same dense output
    sampled on its finest grid (512 a period, no grid_rtol), which the run's must equal within
    api.METRIC_GRID_SHARE of the run's rtol of the force's spread (4/3 of it: a second-order rule's
    error estimated from two grids), while reading the dense output at fewer times (measured: 128 a
    period at rtol 5e-5, 256 at 1e-7)."""
    from inerter import api
    from inerter.engine import metrics
    model = inerter.load(LUMPED)
    result = model.simulate(stop_time=STOP, rtol=rtol, atol=rtol / 100)
    spec = next(m for m in model.scene.metrics if m.kind == "harmonics")
    assert spec.signal in model.signals.pulse_free and spec.signal not in model.signals.kinematic
    share = api.metric_grid_rtol(result.settings, True)
    t, x = result.time, result[spec.signal]
    reads = {}

    def counted(key):
        dense = result.dense(spec.signal)

        def values(times):
            reads[key] = reads.get(key, 0) + np.size(times)
            return dense(times)
        return values

    # the window: whole periods of `period_of`, as the scene's free_oscillation metric of it finds them
    motion = next(m for m in model.scene.metrics if m.kind == "free_oscillation" and m.signal == spec.period_of)
    oscillation = metrics.free_oscillation(t, result[spec.period_of], motion.reference, result.dense(spec.period_of),
                                           grid_rtol=share)
    window, periods = oscillation["window"], oscillation["periods"]
    run = metrics.harmonics(t, x, window, periods, counted("run"), grid_rtol=share)
    finest = metrics.harmonics(t, x, window, periods, counted("finest"))
    spread = float(np.ptp(x))
    assert abs(run["mean"] - finest["mean"]) <= 4.0 / 3.0 * share * spread
    assert abs(run["amplitude"] - finest["amplitude"]) <= 4.0 / 3.0 * share * spread
    assert reads["run"] - 1 <= (reads["finest"] - 1) / coarser     # n + 1 times a grid of n steps
    # the run's own metric is the one on the coarse grid
    assert (result.metrics[f"{spec.prefix}_mean"], result.metrics[f"{spec.prefix}_amplitude"]) == (
        run["mean"], run["amplitude"])



HARMONICS = """
[[metrics]]
kind = "harmonics"
signal = "C.v[2]"
period_of = "C.r[2]"
prefix = "Cv"
"""


def test_a_harmonics_metric_of_a_3d_scene_is_its_2d_twins(tmp_path):
    """A harmonics metric takes no reference, so none is worked out: a 3D scene's (whose static
    equilibrium is not implemented) was refused, asking for the reference it may not give. Reference:
    the same metric of the planar twin on the oracle, over the same 20 s (element forces from L(q),
    scipy's dense output); tolerance as the steady state's above (1e-9 of the amplitude)."""
    runs = {}
    for name, oracle in (("two_bar_2d_as_3d", False), ("two_bar_2d", True)):
        scene = tmp_path / f"{name}.toml"
        scene.write_text((SCENARIOS / f"{name}.toml").read_text() + HARMONICS)
        model = inerter.load(scene)
        runs[name] = (model.oracle() if oracle else model).simulate(stop_time=STOP)
    fast, reference = runs["two_bar_2d_as_3d"], runs["two_bar_2d"]
    assert not fast.metric_errors and not reference.metric_errors
    amplitude = reference.metrics["Cv_amplitude"]
    assert amplitude > 0.1
    assert fast.metrics["Cv_amplitude"] == pytest.approx(amplitude, rel=1e-9)
    assert abs(fast.metrics["Cv_mean"] - reference.metrics["Cv_mean"]) <= 1e-9 * amplitude


def test_metrics_read_only_the_signals_they_need(paper):
    """A compiled run evaluates an output when it is first asked for: after simulate, only the
    metrics' signals have been (the others cost nothing), with the values every output has."""
    model, runs = paper["two_bar_2d"]
    fast = runs["compiled"]
    assert set(fast._columns) == {"C.r[2]"} and fast._values is None
    fresh = inerter.api.Result(model, fast.settings, fast.run)
    everything = fresh._all_values()
    for j, name in enumerate(model.signals.names):
        assert np.array_equal(fresh[name], everything[:, j]), name
        assert np.array_equal(fast[name], everything[:, j]), name


# ---------------------------------------------------------------------------------------------
# The dense output itself
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["lumped_mass_2d", "two_bar_2d"])
def test_dense_output_between_samples_matches_the_oracles(paper, name):
    """Reference: the oracle's run and scipy's dense output of it (the same steps, right-hand sides
    equal to round-off): between the samples the compiled dense output is no further from it than
    at the samples (2 × that + atol); for the two-bar, which takes the same steps to the end, within
    rtol of the motion, as against the numpy path before."""
    model, runs = paper[name]
    fast, reference = runs["compiled"].run, runs["oracle"].run
    s = runs["compiled"].settings
    ny = fast.states.shape[1]
    t = between_samples(fast.time)
    mine, scipys = fast.dense(t), reference.dense(t)
    assert mine.shape == scipys.shape == (ny, len(t))
    assert fast.dense(1.2345).shape == (ny,)
    at_samples = float(np.max(np.abs(fast.states - reference.states)))
    between = float(np.max(np.abs(mine - scipys)))
    assert between <= 2.0 * at_samples + s.atol           # no worse between the samples than at them
    if name == "two_bar_2d":                              # the same steps on both paths: the same polynomials
        assert between <= s.rtol * float(np.max(np.abs(scipys)))


@pytest.mark.parametrize("name", ["lumped_mass_2d", "two_bar_2d"])
def test_dense_output_holds_every_step_and_gives_the_samples(paper, name):
    model, runs = paper[name]
    run = runs["compiled"].run
    assert run.dense.count == run.steps                   # every accepted step (past the first room of 256)
    assert run.dense.ts[0] == 0.0 and run.dense.ts[-1] == STOP and np.all(np.diff(run.dense.ts) > 0)
    Y = run.dense(run.time).T
    assert np.max(np.abs(Y - run.states)) <= 1e-14 * np.max(np.abs(run.states))


def test_keeping_the_dense_output_leaves_the_samples_bit_for_bit():
    model = inerter.load(TWO_BAR)
    for method in ("DOP853", "RK45"):
        s = model.settings(stop_time=5.0, method=method)
        plain = compiled.integrate_compiled(model.mechanism, s)
        kept = compiled.integrate_compiled(model.mechanism, s, dense=True)
        assert isinstance(plain.dense, compiled.LocalDense) and isinstance(kept.dense, compiled.DenseOutput)
        assert np.array_equal(plain.states, kept.states) and plain.steps == kept.steps
    # kept only for metrics that read whole windows; otherwise built where it is read
    local = model.simulate(stop_time=5.0, metrics=False).run.dense
    assert isinstance(local, compiled.LocalDense) and not local.intervals and local.evaluations == 0


def test_rk45_dense_output_matches_scipys():
    """Reference: scipy's RK45 dense output of the oracle's run at the same settings (the same
    steps), within 1e-12 between the samples, over 2 s (5 s against the numpy path before: the
    oracle's evaluations cost more)."""
    model = inerter.load(TWO_BAR)
    fast = model.simulate(stop_time=2.0, method="RK45").run
    reference = model.oracle().simulate(stop_time=2.0, method="RK45").run
    t = between_samples(fast.time)
    assert np.max(np.abs(fast.dense(t) - reference.dense(t))) <= 1e-12


def test_dense_output_across_a_discontinuity_follows_the_closed_form():
    """A step force at ts = 0.5 s ends a segment: the integration restarts there and both
    segments' steps are kept, ts among the nodes. x − L0 = F/k (1 − cos w(t − ts)) after ts."""
    model = inerter.load(STEP_FORCE)
    s = model.settings(stop_time=2.0)
    result = inerter.api.Result(model, s, compiled.integrate_compiled(model.mechanism, s, dense=True))
    k, F, m, b, L0, ts = (model.scene.parameters[p].value for p in ("k", "F", "m", "b", "L0", "ts"))
    assert ts in result.run.dense.ts
    w = math.sqrt(k / (m + b))
    t = between_samples(result.time)
    exact = L0 + np.where(t >= ts, F / k * (1.0 - np.cos(w * (t - ts))), 0.0)
    assert np.max(np.abs(result.dense("P.r[1]")(t) - exact)) <= 1e-9
    oracle_dense = model.oracle().simulate(stop_time=2.0, metrics=False).run.dense      # scipy's, restarted at ts
    assert np.max(np.abs(result.run.dense(t) - oracle_dense(t))) <= 1e-9


def test_signals_on_the_dense_output_come_from_the_kernels_with_the_oracles_values(paper):
    """Result.dense(name) evaluates the signal at the dense states in compiled code (an element
    force with its accelerations); the oracle's signals at the same states (its forces derived from
    L(q), its accelerations its own) agree to rounding: 1e-12 relative to max(1, |value|), as the
    numpy signals did (measured 1.2e-15)."""
    model, runs = paper["lumped_mass_2d"]
    fast = runs["compiled"]
    t = between_samples(fast.time, extra=0)[::37]
    Y = fast.run.dense(t)
    n = model.mechanism.nq
    oracle = model.oracle().signals
    for name in ("P.r[2]", "P.v[2]", "inerter.f", "inerter.s_rel", "spring.f", "energy"):
        fn = oracle.function(name)
        expected = np.array([fn(ti, Y[:n, i], Y[n:, i]) for i, ti in enumerate(t)])
        got = fast.dense(name)(t)
        assert got.shape == t.shape
        assert np.max(np.abs(got - expected)) <= 1e-12 * max(1.0, float(np.max(np.abs(expected)))), name


def test_rk4_metrics_on_the_compiled_path():
    result = inerter.load(LUMPED).simulate(stop_time=5.0, method="RK4", step=1e-3)
    assert result.status == "ok" and result.run.extra["path"] == "compiled"
    assert result.metrics["fundamental_frequency"] == pytest.approx(1.4506, rel=1e-4)


def test_rk4_dense_output_is_its_steps_not_a_spline_through_the_samples():
    """A compiled RK4 run read between its samples gives its steps' cubic Hermite polynomials, as
    the numpy path's RK4 (inerter.engine.integrators.RK4, the explicit reference: the same fixed
    steps, since the 0.1 s output interval is a multiple of the 1e-3 s step). It read a cubic
    spline through the 0.1 s samples, 0.07 N off the inerter's force at 0.15 s (1 % of it, where
    RK4 at this step is within 1e-9 of a DOP853 run at rtol 1e-12), and its peak metrics with it."""
    model = inerter.load(TWO_BAR)
    kw = dict(stop_time=1.0, output_interval=0.1, method="RK4", step=1e-3)
    fast, explicit = model.simulate(**kw), model.simulate(path="numpy", **kw)
    reference = model.simulate(stop_time=1.0, output_interval=0.1, rtol=1e-12, atol=1e-14)
    assert fast.run.extra["path"] == "compiled"
    t = between_samples(fast.time, extra=200, seed=3)
    for name in ("C.r[2]", "inerter.f", "energy"):
        got, want = fast.dense(name)(t), explicit.dense(name)(t)
        scale = max(1.0, float(np.max(np.abs(want))))
        assert np.max(np.abs(got - want)) <= 1e-10 * scale, name
        assert np.max(np.abs(got - reference.dense(name)(t))) <= 1e-6 * scale, name


def test_rk4_dense_output_integrates_each_interval_once(monkeypatch):
    """A compiled RK4 run's dense output keeps the steps of the sample intervals it integrated
    again: reading the same interval again, at the same or other times, integrates nothing (it
    integrated it at every read: 4 integrations of integrate_rk4 for the reads below, now 2), and
    gives the same values. Reference: the numpy path's RK4 (the same fixed steps: the 0.1 s output
    interval is a multiple of the 1e-3 s step), whose dense output is its steps' cubic Hermite
    polynomials, within 1e-10 of the motion's scale (the cubic read through four of its values)."""
    model = inerter.load(TWO_BAR)
    kw = dict(stop_time=1.0, output_interval=0.1, method="RK4", step=1e-3, metrics=False)
    fast, explicit = model.simulate(**kw), model.simulate(path="numpy", **kw)
    sol = fast.run.dense
    assert isinstance(sol, compiled.RK4Dense)
    calls = []
    integrate = compiled._k.integrate_rk4
    monkeypatch.setattr(compiled._k, "integrate_rk4", lambda *a: calls.append(a[1]) or integrate(*a))
    t, other = np.array([0.1234, 0.1271, 0.5005]), np.array([0.15, 0.52, 0.1])
    first = sol(t)
    assert len(calls) == 2
    assert np.array_equal(sol(t), first) and sol(other).shape == (sol.n, 3)
    assert len(calls) == 2 and sorted(sol.intervals) == [1, 5]
    scale = np.maximum(np.max(np.abs(explicit.run.states), axis=0), 1e-12)
    for times, got in ((t, first), (other, sol(other))):
        assert np.max(np.abs(got - explicit.run.dense(times)).T / scale) < 1e-10
    for name in ("C.r[2]", "inerter.f"):           # a signal read through the kept steps
        want = explicit.dense(name)(t)
        assert np.max(np.abs(fast.dense(name)(t) - want)) <= 1e-10 * max(1.0, float(np.max(np.abs(want)))), name
    assert len(calls) == 2


def test_rk4_dense_output_keeps_a_bounded_number_of_values(monkeypatch):
    """Past RK4_DENSE_KEPT numbers, the intervals read longest ago are dropped (and integrated
    again if read again): memory stays bounded however many intervals are read."""
    result = inerter.load(TWO_BAR).simulate(stop_time=1.0, output_interval=0.1, method="RK4", step=1e-3,
                                            metrics=False)
    sol = result.run.dense
    sol(np.array([0.05]))
    one = sol.kept
    monkeypatch.setattr(compiled, "RK4_DENSE_KEPT", int(2.5 * one))      # room for two intervals
    sol(np.array([0.15, 0.25, 0.35]))
    assert list(sol.intervals) == [2, 3] and sol.kept <= 2.5 * one and sol.integrations == 4
    sol(np.array([0.25]))
    assert sol.integrations == 4 and list(sol.intervals) == [3, 2]


def test_a_dense_output_built_where_it_is_read_integrates_only_those_intervals():
    """A run that kept no dense output (no metric reads whole windows) gives one where it is read:
    each 10 ms sample interval asked for is integrated again from the sample before it. Two times
    in one interval and one in another integrate two intervals, each a few steps, and the values
    equal the kept dense output's to the run's tolerance: both integrate the same equations under
    the same error control from states equal at the samples (rtol 1e-10 here: 1e-9 of the
    motion's amplitude, several steps of local error)."""
    model = inerter.load(TWO_BAR)
    s = model.settings(stop_time=5.0, rtol=1e-10, atol=1e-12)
    plain = compiled.integrate_compiled(model.mechanism, s)
    kept = compiled.integrate_compiled(model.mechanism, s, dense=True)
    t = np.array([1.2345, 1.2371, 3.0005])
    a, b = plain.dense(t), kept.dense(t)
    assert sorted(plain.dense.intervals) == [123, 300]
    assert 0 < plain.dense.evaluations < 0.05 * plain.evaluations
    scale = np.max(np.abs(kept.states), axis=0)
    assert np.max(np.abs(a - b).T / np.maximum(scale, 1e-12)) < 1e-9


@pytest.mark.parametrize("kw", [dict(path="numpy"), dict(method="Radau"), dict(constraint="projection"),
                                dict(method="RK4"), dict()])
def test_dense_takes_times_of_any_shape_none_and_nan(kw):
    """Result.dense(name)(t) on every kind of run reads the times flattened (a 1-D array of values,
    also for a scalar), none as an empty array, and NaN at a NaN time: the numpy path and the scipy
    integrators raised on an empty array (scipy's OdeSolution) or on a 2-D one, a NaN time raised
    whatever the integrator found there (terminals meeting, an integer conversion), and RK4's spline
    gave a scalar for a scalar. Reference: the same callable at the finite times as a 1-D array."""
    result = inerter.load(LUMPED).simulate(stop_time=1.0, metrics=False, **kw)
    f = result.dense("P.r[2]")
    t = np.array([[0.7, 0.1], [1.0, 0.0]])
    flat = f(t.reshape(-1))
    assert flat.shape == (4,) and np.all(np.isfinite(flat))
    assert np.array_equal(f(t), flat)
    assert f(np.array([])).shape == (0,)
    assert np.array_equal(f(0.7), flat[:1])
    got = f([0.7, np.nan, 0.1])
    assert np.isnan(got[1]) and np.array_equal(got[[0, 2]], flat[:2])
    derived = result.dense("energy")([np.nan, 0.5])
    assert np.isnan(derived[0]) and np.isfinite(derived[1])


def test_an_euler_angle_splined_through_its_wraps_is_the_steady_spins():
    """Where a run keeps no dense output (RK4), an Euler angle is splined through its samples
    unwrapped and read in (−π, π] again: the spline through the wrapped samples crossed each 2π jump
    (3.7 rad off between the samples). Reference: the closed form of the steady spin about global X
    (the spinner's major axis), roll = α0 + ω t wrapped into (−π, π], within 1e-9 rad (RK4's steps
    of a constant rate are exact up to round-off; the spline of a linear function is exact); a
    time on a wrap is left out (both ends of the interval are its value)."""
    model = inerter.load(GIMBAL)
    result = model.simulate(stop_time=3.0, output_interval=0.05, method="RK4", metrics=False)
    a0, w = (model.scene.parameters[p].value for p in ("alpha0", "omega"))
    t = np.linspace(0.0, 3.0, 3001)
    exact = np.pi - np.mod(np.pi - (a0 + w * t), 2 * np.pi)
    off = np.abs(np.abs(exact) - np.pi) > 1e-6
    got = result.dense("spinner.euler[3]")(t)
    assert np.max(np.abs(got - exact)[off]) <= 1e-9
    assert np.all((got > -np.pi) & (got <= np.pi))


@pytest.mark.parametrize("kw", [dict(), dict(path="numpy"), dict(method="Radau"), dict(method="RK4")])
def test_dense_refuses_a_time_outside_the_run(kw):
    """A time before the first sample or after the last raises a ValueError naming the scene, the
    signal, the time and the run's span: past them the dense output's polynomial (or RK4's spline)
    was extrapolated and returned as if the run had reached there. The first and last samples
    themselves are read (to rounding: linspace's ends)."""
    result = inerter.load(LUMPED).simulate(stop_time=1.0, metrics=False, **kw)
    f = result.dense("P.r[2]")
    assert np.all(np.isfinite(f(np.linspace(0.0, 1.0, 7))))
    for t in (1.0 + 1e-6, -0.01):
        with pytest.raises(ValueError, match=r"lumped_mass_2d: dense\('P.r\[2\]'\): t = .* s is outside the run, "
                                             r"whose samples span \[0, 1\] s"):
            f([0.5, t])


def test_a_quaternion_splined_across_its_sign_flips_is_the_steady_spins():
    """With Euler angles a body's quaternion output is the one with w ≥ 0, which flips to −q where
    w crosses 0; RK4's dense output (a spline through the samples) is taken through samples made
    continuous first, and read back with w ≥ 0. Reference: the closed form of the steady spin
    about global Z of a body with equal principal inertias, q(t) = (cos ωt/2, 0, 0, sin ωt/2) ⊗ q0
    with w ≥ 0 (q0 from the initial Z-X-Z angles). The spline's error through a sinusoid of
    frequency ω/2 sampled every h is about 5/384 h⁴ (ω/2)⁴ = 3.2e-6 (the not-a-knot ends about
    double it): within 2e-5 (the spline through the flipping samples was 1.3 off); a time within
    1e-3 of a flip (where w's sign is that of the spline's w, not the closed form's) is left out."""
    from scipy.spatial.transform import Rotation
    model = inerter.load(Path(__file__).parent / "data" / "steady_spin_euler_3d.toml")
    result = model.simulate(metrics=False)
    omega = model.scene.parameters["omega"].value
    t = np.linspace(0.0, 3.0, 3001)
    turn = Rotation.from_rotvec(np.outer(omega * t, [0.0, 0.0, 1.0]))
    xyzw = (turn * Rotation.from_euler("ZXZ", [0.3, 0.7, 0.2])).as_quat()
    exact = np.column_stack([xyzw[:, 3], xyzw[:, :3]])
    assert np.any(exact[:, 0] < 0) and np.any(exact[:, 0] > 0)     # the spin takes w through 0
    exact *= np.where(exact[:, :1] < 0, -1.0, 1.0)
    off = np.abs(exact[:, 0]) > 1e-3
    for i in range(4):
        got = result.dense(f"ball.q[{i + 1}]")(t)
        assert np.max(np.abs(got - exact[:, i])[off]) <= 2e-5, i + 1
