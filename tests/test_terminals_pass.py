"""Terminals that pass through each other within one long step stop the run at the meeting, on every
path and method.

The scenes: tests/data/terminals_pass_3d.toml (two free bodies joined by an inerter alone, closing
head-on along X) and tests/data/terminals_pass_2d.toml (a ball joined to the ground point O by an
inerter alone, moving straight at O along a diagonal). Neither has a relative acceleration along
the line ((m_eff + b) s'' = 0), so the closed form is L(t) = L0 − v t and the terminals meet at
t* = L0/v. Nothing shortens the adaptive methods' steps on the way: one step jumps across t*.

What "meet" means is the engine's (Mechanism.MEET_RELATIVE, kernels.terminals_meet): the chord of a
step comes within LIMIT = 1e-6·L0 of the other terminal. The run stops where the closed form reaches
that limit, T_STOP = (L0 − LIMIT)/v (5e-7 s and 8e-7 s before t*). Tolerances:
- the stop time within 1e-9 s of T_STOP: the meeting is located to adjacent floats on the step's own
  interpolant (or, RK4, by ever shorter steps), and every method integrates this uniform motion to
  round-off (the samples below are within 1e-12 m of L0 − v t), so 1e-9 s is the accuracy of the
  run's rtol = 1e-10 on L ~ 1 m over v ≥ 1 m/s with a margin; hence within 1e-6 s of t* as well;
- the samples: every output-grid sample up to the stop is in the result, and the element's
  distance s_rel there equals L0 − v t within 1e-12 m (closed form; round-off of sums of ~100 steps).
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.common.errors import SimulationError
from inerter.model.mechanism import MEET_RELATIVE

DATA = Path(__file__).parent / "data"
#: scene: (L0, v, the element's terminals)
SCENES = {"terminals_pass_3d": (1.0, 2.0, ("A", "C")), "terminals_pass_2d": (1.0, 1.25, ("O", "P"))}
INTERVAL = 0.01                                   # the scenes' output interval
STOP_TOLERANCE = 1e-9                             # s, about T_STOP (module docstring)
SAMPLE_TOLERANCE = 1e-12                          # m, about L0 − v t


def _closed_form(scene):
    """(L0, v, terminals, t* = L0/v, T_STOP = where L0 − v t reaches the meeting limit)."""
    L0, v, terminals = SCENES[scene]
    limit = MEET_RELATIVE * L0
    return L0, v, terminals, L0 / v, (L0 - limit) / v


def _meeting_time(message, terminals):
    """The meeting time the message names, with the element and its terminals."""
    found = re.search(rf"element 'inerter': terminals {terminals[0]} and {terminals[1]} meet at t = "
                      r"([0-9.e+-]+) s", message)
    assert found, message
    return float(found.group(1))


RUNS = [("compiled", m) for m in ("DOP853", "RK45", "RK4", "Radau", "BDF")] + \
       [("numpy", m) for m in ("DOP853", "RK45", "Radau", "BDF", "RK4")]


@pytest.mark.parametrize("scene", sorted(SCENES))
@pytest.mark.parametrize("path,method", RUNS)
def test_a_whole_run_stops_at_the_meeting_keeping_every_sample_before_it(scene, path, method):
    """compiled DOP853, RK45, RK4: kernels.locate_meeting on the crossing step's dense output, RK4's
    step taken again in shorter steps (kernels._rk4_to_meeting); compiled Radau, BDF: scipy's
    integrators on the compiled right-hand side; numpy: StepMonitor.stop_at_meeting."""
    L0, v, terminals, t_meet, t_stop = _closed_form(scene)
    r = inerter.load(DATA / f"{scene}.toml").simulate(method=method, path=path, metrics=False)
    assert r.status == "failed", r.message
    if path == "compiled" and method in ("DOP853", "RK45", "RK4"):
        assert r.run.extra["path"] == "compiled"
    said = _meeting_time(r.message, terminals)
    assert abs(said - t_stop) <= STOP_TOLERANCE, (said, t_stop)
    assert abs(said - t_meet) <= 1e-6
    # every sample of the output grid up to the meeting, none after it
    expected = np.round(np.arange(0.0, said, INTERVAL), 12)
    assert len(r.time) == len(expected) and np.allclose(r.time, expected, rtol=0, atol=1e-12), r.time[-3:]
    assert np.max(np.abs(r["inerter.s_rel"] - (L0 - v * r.time))) <= SAMPLE_TOLERANCE


def _step_until_it_fails(stepper, h=INTERVAL, most=200):
    """Step `stepper` by h until a step fails; (the states' times, their s_rel, the exception)."""
    times, lengths = [], []
    for k in range(1, most):
        try:
            stepper.step(k * h)
        except SimulationError as exc:
            return np.array(times), np.array(lengths), exc
        times.append(stepper.time)
        lengths.append(stepper.outputs()["inerter.s_rel"])
    raise AssertionError("no step failed")


@pytest.mark.parametrize("path,method", [("compiled", "DOP853"), ("compiled", "RK45"), ("compiled", "RK4"),
                                         ("numpy", "DOP853"), ("numpy", "Radau"), ("numpy", "RK4")])
def test_the_stepper_stops_at_the_meeting_and_keeps_the_last_point(path, method):
    """Model.stepper: every communication point before the meeting is reached (the adaptive
    integration's step that crosses it is valid up to it: its dense output gives them, and the
    compiled loop takes the step back at each, kernels._rk_meeting); the step holding the
    meeting fails naming it, leaves the stepper where it was, and fails the same way again."""
    scene = "terminals_pass_3d"
    L0, v, terminals, t_meet, t_stop = _closed_form(scene)
    st = inerter.load(DATA / f"{scene}.toml").stepper(method=method, path=path)
    times, lengths, exc = _step_until_it_fails(st)
    assert np.allclose(times, np.arange(1, len(times) + 1) * INTERVAL, rtol=0, atol=1e-12)
    assert times[-1] <= t_stop < times[-1] + INTERVAL           # only the step holding the meeting fails
    assert np.max(np.abs(lengths - (L0 - v * times))) <= SAMPLE_TOLERANCE
    said = _meeting_time(str(exc), terminals)
    assert abs(said - t_stop) <= STOP_TOLERANCE and abs(exc.time - t_stop) <= STOP_TOLERANCE   # said: 9 digits
    before = (st.time, list(st.y))
    with pytest.raises(SimulationError) as again:
        st.step(st.time + INTERVAL)
    assert (st.time, list(st.y)) == before
    assert _meeting_time(str(again.value), terminals) == said


@pytest.fixture(scope="module")
def pass_fmu(tmp_path_factory):
    """terminals_pass_3d's FMU, extracted (one build for the module)."""
    fmpy = pytest.importorskip("fmpy")
    from inerter.fmu import build as fmu_build
    out = tmp_path_factory.mktemp("terminals_pass_fmu")
    fmu = fmu_build.build(DATA / "terminals_pass_3d.toml", out, force=True)
    return fmpy.extract(str(fmu), unzipdir=str(out / "unzipped"))


@pytest.mark.parametrize("solver", ["DOP853", "RK4"])
def test_the_fmu_discards_the_step_holding_the_meeting_and_names_it(pass_fmu, solver):
    """The FMU stepped by 10 ms: every point before the meeting (native steps on the compiled
    loop, whose integrator step across the meeting is taken back at each point before it,
    kernels._rk_meeting), then fmi2Discard on the step holding it, naming the element, its
    terminals and the meeting time (the slave's CompiledStepper takes the step the native code
    declines), the FMU staying at the last point."""
    from fmpy.fmi1 import FMICallException
    from test_fmu import FMI_DISCARD, Instance, shim_expected

    L0, v, terminals, t_meet, t_stop = _closed_form("terminals_pass_3d")
    inst = Instance(pass_fmu)
    try:
        inst.initialise(strings={"solver": solver})
        t, lengths = 0.0, []
        while True:
            try:
                inst.fmu.doStep(t, INTERVAL)
            except FMICallException as exc:
                assert exc.status == FMI_DISCARD
                break
            t = round(t + INTERVAL, 12)
            lengths.append(inst.get(["inerter.s_rel"])[0])
            assert t < 1.0, "no step was discarded"
        assert t <= t_stop < t + INTERVAL
        times = np.arange(1, len(lengths) + 1) * INTERVAL
        assert np.max(np.abs(np.array(lengths) - (L0 - v * times))) <= SAMPLE_TOLERANCE
        log = inst.logged()
        assert abs(_meeting_time(log, terminals) - t_stop) <= STOP_TOLERANCE
        assert f"the FMU stays at t = {t!r} s" in log, log
        assert inst.get(["inerter.s_rel"])[0] == pytest.approx(L0 - v * t, abs=SAMPLE_TOLERANCE)
        inst.fmu.terminate()
        [done] = [m for _, m in inst.messages if m.startswith("terminated")]
        if shim_expected():
            assert done.endswith(f"{len(lengths)} communication steps, {len(lengths)} of them taken in native "
                                 f"code by the FMU's binary"), done
    finally:
        inst.fmu.freeInstance()


def test_after_the_discarded_step_the_fmu_asks_to_terminate(pass_fmu):
    """fmi2GetBooleanStatus(fmi2Terminated) is fmi2True after the discarded step (FMI 2.0 section
    4.2.3: asked after doStep returned fmi2Discard), with fmi2LastSuccessfulTime the last point, so
    that a master such as fmpy's simulate_fmu ends the run there rather than trying the same step
    again, forever; fmi2False before it, and again once a state of an earlier point is restored;
    fmi2True again when the same step is discarded again."""
    from fmpy.fmi1 import FMICallException
    from test_fmu import Instance, shim_expected

    if not shim_expected():
        pytest.skip("the status functions are the status shim's (no C compiler here)")
    last_successful_time, terminated = 2, 3                    # fmi2StatusKind, FMI 2.0 section 4.2.3
    inst = Instance(pass_fmu)
    try:
        inst.initialise()
        t, saved = 0.0, None
        while True:
            assert inst.fmu.getBooleanStatus(terminated) is False
            if saved is not None:
                inst.fmu.freeFMUstate(saved)
            saved = inst.fmu.getFMUstate()
            try:
                inst.fmu.doStep(t, INTERVAL)
            except FMICallException:
                break
            t = round(t + INTERVAL, 12)
            assert t < 1.0, "no step was discarded"
        assert inst.fmu.getBooleanStatus(terminated) is True
        assert inst.fmu.getRealStatus(last_successful_time) == t
        inst.fmu.setFMUstate(saved)
        assert inst.fmu.getBooleanStatus(terminated) is False
        with pytest.raises(FMICallException):
            inst.fmu.doStep(t, INTERVAL)
        assert inst.fmu.getBooleanStatus(terminated) is True
        inst.fmu.freeFMUstate(saved)
        inst.fmu.terminate()
    finally:
        inst.fmu.freeInstance()


def test_fmpy_ends_its_run_at_the_meeting(pass_fmu):
    """fmpy.simulate_fmu, which asks fmi2Terminated after a discarded step, ends at the last
    point before the meeting (recorded twice, as fmpy does), in a subprocess with a time limit: a
    master that retried the same step would never end."""
    import subprocess
    import sys

    from test_fmu import shim_expected

    if not shim_expected():
        pytest.skip("fmi2Terminated is the status shim's (no C compiler here)")
    L0, v, terminals, t_meet, t_stop = _closed_form("terminals_pass_3d")
    code = ("import sys, fmpy; r = fmpy.simulate_fmu(sys.argv[1], stop_time=1.0, output_interval=0.01); "
            "print(repr(float(r['time'][-1])), repr(float(r['inerter.s_rel'][-1])))")
    done = subprocess.run([sys.executable, "-c", code, pass_fmu], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    last, length = (float(x) for x in done.stdout.splitlines()[-1].split())     # after fmpy's log lines
    assert last <= t_stop < last + INTERVAL
    assert length == pytest.approx(L0 - v * last, abs=SAMPLE_TOLERANCE)        # the closed form


def test_terminals_that_never_meet_run_as_before(tmp_path):
    """The 2D ball aimed 1e-3 m to the side of O (its inerter bends the path near O, which it
    passes at some 7e-4 m, far above the limit 1e-6 m) runs to its stop time on the compiled
    loops, adaptive and fixed-step: only a meeting stops a run (as tests/test_hard_cases.py's near
    miss). That a normal step pays nothing is checked by comparing runs before and after
    (docs/hard_cases.md)."""
    text = (DATA / "terminals_pass_2d.toml").read_text()
    assert 'position = ["0.6*L0", "0.8*L0"]' in text
    moved = text.replace('position = ["0.6*L0", "0.8*L0"]', 'position = ["0.6*L0 + 0.8e-3", "0.8*L0 - 0.6e-3"]')
    path = tmp_path / "terminals_near_miss_2d.toml"
    path.write_text(moved)
    for method in ("DOP853", "RK4"):
        r = inerter.load(path).simulate(method=method, metrics=False)
        assert r.status == "ok", r.message
        assert np.min(r["inerter.s_rel"]) > 100 * MEET_RELATIVE
        assert math.isclose(r.time[-1], 1.5)
