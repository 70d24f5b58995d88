"""The numpy co-simulation stepper (inerter.engine.simulation.Stepper), which the FMU uses for every scene
the compiled path does not take (3D scenes, implicit methods, step forces, projection): its running
integration against the whole run, rollback through its state, failures, and stepping past the
stop time. References: the numpy whole run (`integrate`) and the closed-form impact time of
scenarios/hard/terminals_meet_2d.toml."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.common.errors import SimulationError

ROOT = Path(__file__).resolve().parents[1]
PLANAR = ROOT / "scenarios" / "two_bar_2d.toml"
SPATIAL = ROOT / "scenarios" / "spherical_pendulum_3d.toml"
STEP_FORCE = ROOT / "scenarios" / "hard" / "step_force_1dof_2d.toml"
TERMINALS_MEET = ROOT / "scenarios" / "hard" / "terminals_meet_2d.toml"
STOP, STEP = 0.5, 0.01


@pytest.mark.parametrize("method", ["DOP853", "RK45", "Radau", "BDF"])
@pytest.mark.parametrize("path", [PLANAR, SPATIAL, STEP_FORCE], ids=lambda p: p.stem)
def test_with_inputs_held_the_numpy_stepper_is_the_whole_run(path, method):
    """One scipy integration runs on across the communication points, bounded by the stop time and
    restarted at a step force's switching time as the whole run is, and the state at each point
    comes from the dense output of the step covering it, as the whole run samples its grid: the
    same steps, and at every point the whole run's state bit for bit."""
    model = inerter.load(path)
    whole = model.simulate(stop_time=STOP, output_interval=STEP, method=method, metrics=False, path="numpy")
    assert whole.status == "ok", whole.message
    st = model.stepper(method=method, stop_time=STOP, path="numpy")
    assert st.path == "numpy"
    for k in range(1, len(whole.time)):
        st.step(whole.time[k])
        assert np.array_equal(st.y, whole.run.states[k]), (k, np.max(np.abs(st.y - whole.run.states[k])))
    assert st.steps == whole.run.steps


@pytest.mark.parametrize("method", ["DOP853", "RK45", "Radau", "BDF", "RK4", "LSODA"])
@pytest.mark.parametrize("path", [SPATIAL, STEP_FORCE], ids=lambda p: p.stem)
def test_the_numpy_stepper_rolls_back_bit_for_bit(path, method):
    """get_state holds the running integration (scipy's solver state): the steps repeated after
    set_state, on the same stepper or on a new one, give the same states bit for bit. The step
    force of STEP_FORCE switches inside the repeated steps."""
    model = inerter.load(path)
    st = model.stepper(method=method, stop_time=1.0, path="numpy")
    for k in range(1, 31):
        st.step(k * STEP)
    blob = st.get_state()

    def run_on(stepper):
        out = []
        for k in range(31, 71):
            stepper.step(k * STEP)
            out.append(stepper.y.copy())
        return np.array(out), stepper.steps

    first = run_on(st)
    st.set_state(blob)
    again = run_on(st)
    other = model.stepper(method=method, stop_time=1.0, path="numpy")
    other.set_state(blob)
    restored = run_on(other)
    assert np.array_equal(first[0], again[0]) and first[1] == again[1]
    assert np.array_equal(first[0], restored[0]) and first[1] == restored[1]


@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_the_numpy_stepper_runs_on_past_its_stop_time(method):
    """An importer that steps past the stop time it gave: the bound is dropped and the integration
    goes on (restarted at the old bound with the proposed step size). Against a whole run to the
    later time: 1e-9 (m, rad, m/s, quaternion) at the scene's rtol 1e-10."""
    model = inerter.load(SPATIAL)
    whole = model.simulate(stop_time=2 * STOP, output_interval=STEP, method=method, metrics=False, path="numpy")
    st = model.stepper(method=method, stop_time=STOP, path="numpy")
    for k in range(1, len(whole.time)):
        st.step(whole.time[k])
    assert st.time == whole.time[-1]
    assert np.max(np.abs(st.y - whole.run.states[-1])) <= 1e-9


def test_an_input_that_changes_restarts_the_numpy_integration_there():
    """An input set to a new value is a discontinuity: the integration restarts at that point (the
    segment after it lands on the next point) and runs on after it. Reference: a stepper whose
    first step to the change is taken, then resumed from get_state with the input set — the same
    restart; and the state differs from the run without the change."""
    model = inerter.load(ROOT / "scenarios" / "two_bar_2d_pd.toml")
    name = model.mechanism.input_names[0]
    held = model.stepper(stop_time=STOP, path="numpy")
    moved = model.stepper(stop_time=STOP, path="numpy")
    for k in range(1, 21):
        held.step(k * STEP)
        moved.step(k * STEP)
    moved.set_input(name, 2.0)
    replay = model.stepper(stop_time=STOP, path="numpy")
    replay.set_state(moved.get_state())
    for k in range(21, 51):
        held.step(k * STEP)
        moved.step(k * STEP)
        replay.step(k * STEP)
    assert np.array_equal(moved.y, replay.y)
    assert np.max(np.abs(moved.y - held.y)) > 1e-6


def test_a_failed_numpy_step_leaves_the_state_and_fails_again():
    """Terminals meeting at the closed-form time π√2/4 s (the scene's comment): the step holding it
    fails naming the elements and a time in that step; time, state and outputs are as before. The
    failure drops the running integration, so the retried step restarts from the communication
    point (as on the compiled path) and fails again in the same step."""
    model = inerter.load(TERMINALS_MEET)
    st = model.stepper(stop_time=2.0, path="numpy")
    impact = math.pi * math.sqrt(2) / 4
    k = 1
    while (k + 1) * STEP < impact:
        st.step(k * STEP)
        k += 1
    before = (st.time, list(st.y), st.output_values())
    for _ in range(2):
        with pytest.raises(SimulationError) as failed:
            st.step((k + 1) * STEP)
        assert (st.time, list(st.y), st.output_values()) == before
        assert "terminals O and P meet" in str(failed.value)
        assert st.time <= failed.value.time < (k + 1) * STEP
    assert st.time < impact <= (k + 1) * STEP


# ----------------------------------------------------------------------------------------------
# Retuning between steps (what an FMU's tunable parameters do)
# ----------------------------------------------------------------------------------------------
def _stepped(model, path, until, h=STEP, method=None):
    st = model.stepper(path=path, method=method)
    for k in range(1, round(until / h) + 1):
        st.step(k * h)
    return st


@pytest.mark.parametrize("path, method", [("numpy", None), ("compiled", None), ("compiled", "Radau")])
def test_a_retuned_stepper_goes_on_as_a_stepper_of_the_scene_loaded_with_the_new_values(path, method):
    """Retuned at t = 0.2 s to b = 20, Fa = 2 (with an input changed there, a discontinuity both
    take alike), the stepper gives, bit for bit, what a stepper of the scene loaded with those
    values, put at the same state and step size, gives with the same input change. Radau on the
    compiled path stays on the compiled right-hand side (it went on on the numpy path's, 6e-13 m
    off, while its ``path`` still said "compiled")."""
    if path == "compiled":
        pytest.importorskip("numba")
    base, tuned = inerter.load(PLANAR), inerter.load(PLANAR, b=20.0, Fa=2.0)
    st = _stepped(base, path, 0.2, method=method)
    ref = tuned.stepper(path=path, method=method)
    ref.time, ref.y, ref.h = st.time, st.y.copy(), st.h
    st.retune(tuned.mechanism, tuned.signals)
    for s in (st, ref):
        s.set_input("C.f[2]", 1.0)
    assert st.output_values() == ref.output_values()        # inerter.f follows b at once
    for k in range(21, 41):
        st.step(k * STEP)
        ref.step(k * STEP)
        assert np.array_equal(st.y, ref.y), k
    assert st.output_values() == ref.output_values()
    # the model's own tables are untouched: a new stepper of it is the untuned run
    again = _stepped(base, path, 0.4, method=method)
    assert np.array_equal(again.y, _stepped(inerter.load(PLANAR), path, 0.4, method=method).y)
    assert not np.array_equal(again.y, st.y)


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_a_retune_that_changes_more_than_numbers_is_refused_naming_the_fields(path):
    if path == "compiled":
        pytest.importorskip("numba")
    st = _stepped(inerter.load(PLANAR), path, 0.05)
    state = st.get_state()
    other = inerter.load(PLANAR, th1=0.7, M1=2.0)
    with pytest.raises(ValueError) as caught:
        st.retune(other.mechanism, other.signals)
    message = str(caught.value)
    # M1 is bar1's mass; th1 its angle, its position and the rotational spring's free angle
    assert all(field in message for field in ("bodies.bar1.mass", "bodies.bar1.angle",
                                              "bodies.bar1.position", "elements.kr.angle"))
    assert st.get_state() == state
