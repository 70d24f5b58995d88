"""The compiled path as the default, and its dense output: every accepted step's polynomial kept by
the compiled DOP853 and RK45 loops (inerter.engine.compiled.DenseOutput), the metrics computed from
it, and the output signals evaluated on it in the kernels."""
from __future__ import annotations

import math

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
    """Both paper scenes over 0-20 s with their metrics, on the numpy and the compiled path."""
    out = {}
    for scene in (LUMPED, TWO_BAR):
        model = inerter.load(scene)
        out[model.name] = (model, {path: model.simulate(stop_time=STOP, path=path) for path in ("numpy", "compiled")})
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
    the numpy path does, naming the body, with the samples before it equal to the numpy path's
    (the same kinematics: rotations.euler_matrix9 and euler_rates, compiled and uncompiled)."""
    model = inerter.load(GIMBAL, **{"scene.orientation": "euler_zxz"})
    result = model.simulate(stop_time=0.1, metrics=False)
    assert result.status == "ok", result.message
    assert result.run.extra["path"] == "compiled"
    assert model.stepper().path == "compiled"
    fast = model.simulate(metrics=False)
    slow = model.simulate(metrics=False, path="numpy")
    assert fast.status == slow.status == "failed"
    assert "spinner" in fast.message and "singularity" in fast.message and "t = " in fast.message
    k = min(len(fast.time), len(slow.time))
    assert len(fast.time) == len(slow.time) and k >= 3
    assert np.max(np.abs(fast.run.states[:k] - slow.run.states[:k])) < 1e-12       # round-off of the same steps


# ---------------------------------------------------------------------------------------------
# Metrics from the dense output
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["lumped_mass_2d", "two_bar_2d"])
def test_compiled_metrics_equal_the_numpy_paths_from_scipys_dense_output(paper, name):
    """The numpy path's metrics come from scipy's dense output; the compiled path's from its own,
    the same polynomials (they were a cubic spline through the 5 ms samples, 6e-9 off in the
    lumped mass's amplitudes). The two paths' trajectories differ only by rounding (the lumped
    mass: by the step sizes that rounding picks, ~1e-8 m after 20 s)."""
    model, runs = paper[name]
    fast, reference = runs["compiled"], runs["numpy"]
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
            assert got == expected, key                     # from the model, not the run
        elif key == "fundamental_frequency":
            assert abs(got - expected) <= 2e-9, key          # Hz
        elif key in scale:                                   # a mean: against its signal's size
            assert abs(got - expected) <= 1e-9 * scale[key], (key, got, expected)
        else:
            assert got == pytest.approx(expected, rel=1e-9), key


def test_compiled_metrics_of_a_3d_scene_equal_the_numpy_paths():
    """The two-bar written as a 3D scene (quaternions): the compiled 3D kernels' dense output gives
    the numpy path's steady state (12 s: the last 10 periods of 1 s)."""
    model = inerter.load(SCENARIOS / "two_bar_2d_as_3d.toml")
    fast, reference = (model.simulate(stop_time=12.0, path=path) for path in ("compiled", "numpy"))
    assert fast.run.extra["path"] == "compiled" and fast.run.dense is not None and not fast.metric_errors
    assert fast.metrics["C_y_peak_to_peak"] == pytest.approx(reference.metrics["C_y_peak_to_peak"], rel=1e-9)
    assert abs(fast.metrics["C_y_mean_offset"] - reference.metrics["C_y_mean_offset"]) <= \
        1e-9 * reference.metrics["C_y_peak_to_peak"]


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
def test_dense_output_between_samples_matches_the_numpy_paths(paper, name):
    model, runs = paper[name]
    fast, reference = runs["compiled"].run, runs["numpy"].run
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
    model = inerter.load(TWO_BAR)
    fast = model.simulate(stop_time=5.0, method="RK45").run
    reference = model.simulate(stop_time=5.0, method="RK45", path="numpy").run
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
    numpy_dense = model.simulate(stop_time=2.0, path="numpy", metrics=False).run.dense
    assert np.max(np.abs(result.run.dense(t) - numpy_dense(t))) <= 1e-9


def test_signals_on_the_dense_output_come_from_the_kernels_with_the_numpy_values(paper):
    """Result.dense(name) evaluates the signal at the dense states in compiled code (an element
    force with its accelerations); the numpy signals at the same states agree to rounding."""
    model, runs = paper["lumped_mass_2d"]
    fast = runs["compiled"]
    t = between_samples(fast.time, extra=0)[::37]
    Y = fast.run.dense(t)
    n = model.mechanism.nq
    for name in ("P.r[2]", "P.v[2]", "inerter.f", "inerter.s_rel", "spring.f", "energy"):
        fn = model.signals.function(name)
        expected = np.array([fn(ti, Y[:n, i], Y[n:, i]) for i, ti in enumerate(t)])
        got = fast.dense(name)(t)
        assert got.shape == t.shape
        assert np.max(np.abs(got - expected)) <= 1e-12 * max(1.0, float(np.max(np.abs(expected)))), name


def test_rk4_keeps_no_polynomial_and_its_metrics_come_from_a_spline():
    result = inerter.load(LUMPED).simulate(stop_time=5.0, method="RK4", step=1e-3)
    assert result.status == "ok" and result.run.extra["path"] == "compiled"
    assert result.run.dense is None
    assert result.metrics["fundamental_frequency"] == pytest.approx(1.4506, rel=1e-4)


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
