"""An FMU run's metrics read the FMU's own dense output (inerter.fmu.dense), at the run's accuracy.

The reference is the solver's run of the same scene at the same settings, whose metrics read its
integrator's dense output. While no input changes, the FMU repeats the solver's whole run step for
step (fmu_src/README.md), so a metric of the two differs by round-off only where the solver kept its
dense output (two_bar_2d's steady state), and by the solver's re-integration of the intervals it
reads where it kept none (the braced frame's peaks: engine.compiled.LocalDense, which agrees to the
run's tolerance). Each test also shows the cubic spline through the 10 ms samples, which the FMU's
metrics read before, missing by far more than its bound, so that the bound can fail.
"""
from __future__ import annotations

import numpy as np
import pytest

from conftest import LUMPED, SCENARIOS, TWO_BAR
from inerter.api import compute_metrics
from inerter.engine.simulation import SimulationError
from inerter.fmu.dense import FmuDense, reads_the_fmu

FRAME = SCENARIOS / "braced_frame_3d.toml"


def spline_metrics(fmu):
    """The FMU run's metrics read on a spline through its samples, as they were before."""
    keep, fmu.fmu_dense = fmu.fmu_dense, None
    try:
        return compute_metrics(fmu.model, fmu)
    finally:
        fmu.fmu_dense = keep


def worst_relative(a: dict, b: dict) -> float:
    return max(float(np.max(np.abs(np.subtract(a[k], b[k])) / np.maximum(np.abs(a[k]), 1e-300))) for k in a)


def test_two_bar_metrics_are_the_solvers_to_round_off(runs, fmu_runs):
    """Steady-state peak-to-peak and mean of C_y over the last 10 periods of 60 s (the paper's Fig. 12
    figures): the FMU's equal the solver's to 1e-12 relative (the same steps' polynomials); the spline's
    peak-to-peak is 5e-9 m off (measured), i.e. 3e-8 relative."""
    fmu = fmu_runs(TWO_BAR, **{"effects.centripetal": True})
    solver = runs(TWO_BAR, True)
    assert fmu.status == "ok" and solver.status == "ok"
    assert fmu.fmu_dense is not None and set(fmu.metrics) == set(solver.metrics)
    assert worst_relative(solver.metrics, fmu.metrics) <= 1e-12
    assert worst_relative(solver.metrics, spline_metrics(fmu)) > 1e-9


def test_braced_frame_peaks_are_the_solvers_to_its_tolerance(fmu_runs):
    """Three peaks (drifts and the brace's inerter force) under 60 s of ground record: the FMU's
    within 1e-9 relative of the solver's (rtol 1e-6 run whose dense output is integrated again where
    read; measured 1e-13); the spline misses the inerter force's peak by 1.6 N (6e-4 relative)."""
    import inerter

    fmu = fmu_runs(FRAME)
    solver = inerter.load(FRAME).simulate()
    assert fmu.status == "ok" and solver.status == "ok"
    assert set(fmu.metrics) == set(solver.metrics) and len(fmu.metrics) == 3
    assert worst_relative(solver.metrics, fmu.metrics) <= 1e-9
    assert worst_relative(solver.metrics, spline_metrics(fmu)) > 1e-5


def test_a_second_instance_that_does_not_repeat_the_run_is_refused(fmu_runs):
    """The dense output checks the run's samples where it passes them: an instance started with
    another y0 is not the run's, and says so rather than give its values."""
    fmu = fmu_runs(LUMPED, stop_time=10.0, y0=1.001)
    other = FmuDense(fmu.fmu_dense.path, {"y0": 1.002}, 10.0, fmu)
    try:
        with pytest.raises(SimulationError, match=r"does not repeat the run"):
            other.values("P.r[2]", [0.5])
    finally:
        other.close()
    # and the run's own start values give its samples back, between which it reads the FMU
    same = FmuDense(fmu.fmu_dense.path, fmu.fmu_dense.start_values, 10.0, fmu)
    try:
        t = fmu.time[::97]
        assert np.array_equal(same.values("P.r[2]", t[::-1])[::-1], fmu["P.r[2]"][::97])
    finally:
        same.close()


@pytest.mark.parametrize("method, constraint, reads", [
    ("DOP853", "baumgarte", True), ("RK45", "baumgarte", True), ("Radau", "baumgarte", True),
    ("RK4", "baumgarte", False), ("LSODA", "baumgarte", False), ("DOP853", "projection", False)])
def test_only_an_integration_running_across_points_is_read_between_them(method, constraint, reads):
    """RK4, LSODA and projection restart at every communication point: a point placed between two
    would change their trajectory, so their metrics read the spline through the samples."""
    from types import SimpleNamespace
    assert reads_the_fmu(SimpleNamespace(method=method, constraint=constraint)) is reads


def test_a_sample_without_value_in_both_counts_as_repeated():
    """A derived output undefined at a sample is NaN in the run and in the second instance alike:
    that is the run repeated; a NaN on one side only, or a value off by 1e-9, is not."""
    class Instance:
        def __init__(self, values):
            self.values = values

        def getReal(self, refs):
            return [self.values[r] for r in refs]

        def getFMUstate(self):
            return "state"

    samples = {"a": np.array([np.nan, 0.0]), "b": np.array([2.0, 0.0])}
    result = type("Run", (), {"time": np.array([0.0, 1.0]), "names": ["a", "b"],
                              "__getitem__": lambda self, n: samples[n]})()
    dense = FmuDense("unused.fmu", {}, 1.0, result)
    dense._outputs = {"a": 0, "b": 1}
    dense._fmu = Instance([np.nan, 2.0])
    dense._keep(0)
    assert 0 in dense._saved
    for values in ([0.0, 2.0], [np.nan, 2.0 + 1e-9 * 3.0]):
        dense._fmu = Instance(values)
        with pytest.raises(SimulationError, match="does not repeat the run"):
            dense._keep(0)


def test_a_nan_time_reads_nan_and_the_rest_are_read(fmu_runs):
    """A NaN among the times gives NaN there, as the solver's dense output does, and the other times
    their values (the FMU is not asked to step by NaN seconds). Reference: the same dense output at
    the finite times alone."""
    fmu = fmu_runs(LUMPED, stop_time=10.0, y0=1.001)
    f = fmu.dense("P.r[2]")
    finite = f([0.5, 0.2, 10.0])
    got = f([0.5, np.nan, 0.2, 10.0])
    assert np.isnan(got[1]) and np.array_equal(got[[0, 2, 3]], finite)
    assert np.isnan(f(np.nan)).all()


FMPY_AFTER_A_RUN = """
import sys, fmpy
from inerter.fmu.run import simulate_fmu
simulate_fmu(sys.argv[1], {}, stop_time=0.1, metrics=False)   # fmpy.simulate_fmu with a logger of ours
try:   # a second FMU with fmpy's default callbacks, whose exitInitializationMode logs an error
    fmpy.simulate_fmu(sys.argv[2], stop_time=0.1, output_interval=0.05, start_values={"y0": float("nan")})
except Exception as exc:
    print("refused:", exc)
"""


def test_an_fmu_logging_after_a_run_in_the_same_process_does_not_crash(tmp_path):
    """fmpy's native logger proxy calls the logger registered last; simulate_fmu's own is freed when
    its call returns, so an FMU instantiated afterwards with fmpy's default callbacks (the FMU's
    dense output, an importer's next run) crashed the process (SIGSEGV) the first time it logged.
    After the run, fmpy's default logger is registered again: the error is printed and raised."""
    import subprocess
    import sys
    from inerter.fmu.build import build
    fmu = build(LUMPED, tmp_path)
    proc = subprocess.run([sys.executable, "-c", FMPY_AFTER_A_RUN, str(LUMPED), str(fmu)],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, (proc.returncode, proc.stderr[-2000:])
    assert "refused: fmi2ExitInitializationMode failed" in proc.stdout
    assert "y0: not finite (got nan" in proc.stdout + proc.stderr


def test_a_time_outside_the_fmu_run_is_refused(fmu_runs):
    """As the solver's dense output (tests/test_dense.py): a time past the run's last sample raises a
    ValueError naming it; the FMU's dense output clamped it to the last sample without a word."""
    fmu = fmu_runs(LUMPED, stop_time=10.0, y0=1.001)
    with pytest.raises(ValueError, match=r"\(FMU\): dense\('P.r\[2\]'\): t = 10.5 s is outside the run"):
        fmu.dense("P.r[2]")([1.0, 10.5])


def test_a_contact_between_two_communication_points_is_found_as_the_solver_finds_it(fmu_runs):
    """tests/data/short_contact_2d.toml: an end-stop contact from t = 0.437 s (closed form: the mass
    coasts at 0.1 m/s to the stop 0.0437 m away) to its release 14 ms later, inside the FMU's
    communication interval [0.4, 0.5] s. The FMU's events are bracketed on its integrator's steps, as
    the solver's are (the solver's run at the same settings takes the same steps) and refined on the
    FMU's own dense output: the same two events as the solver's run at the same output interval, to
    1e-12 s (the same polynomials), the contact at the closed form's time to 1e-9 s. On its samples
    alone both events were missed."""
    import inerter

    scene = SCENARIOS.parent / "tests" / "data" / "short_contact_2d.toml"
    fmu = fmu_runs(scene, step=0.1, metrics=False)
    solver = inerter.load(scene).simulate(output_interval=0.1)
    assert fmu.status == "ok" and fmu.fmu_dense is not None
    found, expected = fmu.events(), solver.events()
    assert [(e["event"], e["where"]) for e in found] == [("contact", "upper stop"), ("release", "upper stop")]
    assert [(e["event"], e["where"]) for e in expected] == [(e["event"], e["where"]) for e in found]
    assert np.allclose([e["time"] for e in found], [e["time"] for e in expected], rtol=0.0, atol=1e-12)
    assert found[0]["time"] == pytest.approx(0.437, abs=1e-9) and 0.44 < found[1]["time"] < 0.5


def test_the_states_kept_are_as_dense_as_stepping_them_costs_a_restore():
    """The second instance keeps a state every SAVE_EVERY samples where a sample's steps cost a tenth
    of a restore or less (an explicit method: 0.04 against 0.45 ms, two_bar_2d), and at every sample
    where they cost a restore or more (an implicit method through a stiff contact), in between as
    many samples as cost one restore."""
    from inerter.fmu.dense import SAVE_EVERY

    dense = FmuDense.__new__(FmuDense)
    dense._restore_seconds = 4.5e-4
    for per_sample, stride in ((4e-5, SAVE_EVERY), (1e-4, 4), (4.5e-4, 1), (3e-3, 1), (0.0, SAVE_EVERY)):
        dense._adapt(per_sample)
        assert dense._stride == stride, per_sample


def test_the_event_nodes_are_found_by_one_solver_run_per_result(monkeypatch):
    """FmuResult._event_nodes runs the solver at the FMU's settings for its integrator's step ends
    (where events() brackets crossings): once per result, however often events() asks (it ran at
    each call). Reference: the nodes of the solver's run at the same settings; none (and no run)
    where the FMU restarts at every communication point (no fmu_dense)."""
    from types import SimpleNamespace

    import inerter
    from inerter.fmu.run import FmuResult

    model = inerter.load(SCENARIOS.parent / "tests" / "data" / "short_contact_2d.toml")
    settings = model.settings(output_interval=0.1)
    simulate, runs = model.simulate, []

    def counted(**kw):
        runs.append(kw)
        return simulate(**kw)
    monkeypatch.setattr(model, "simulate", counted)
    fmu = FmuResult(model, np.zeros(2, dtype=[("time", float)]), settings, SimpleNamespace(status="ok", message=""),
                    0.1)
    assert len(fmu._event_nodes()) == 0 and runs == []
    fmu.fmu_dense = SimpleNamespace(close=lambda: None)      # an FMU that reads its own dense output
    first = fmu._event_nodes()
    assert fmu._event_nodes() is first and fmu._event_nodes() is first and len(runs) == 1
    reference = simulate(stop_time=settings.stop_time, output_interval=0.1, metrics=False)._event_nodes()
    assert len(first) > len(fmu.time) and np.array_equal(first, reference)
