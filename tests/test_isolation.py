"""Two runs of one model do not share state: each run and each co-simulation stepper works on its own
copy of what it changes as it goes (``Mechanism.for_run``, ``Kernel.for_run``: the 3D rotational
elements' wound angles φ_ref, the screw efficiencies' modes, the caches keyed on the state), and the
model stays as it was loaded.

The reference of every comparison is the same run alone, in a fresh stepper of the same model: two
runs interleaved must give it bit for bit. The scene is the 3D bar of tests/test_winding.py spun at
20 rad/s, whose spring winds past 2π within the second compared: before the fix, a second stepper
of the model reset the first one's φ_ref to 0 (numpy path, and scipy's Radau and BDF on the compiled
right-hand side), and its angle output jumped by 2π (the FMU's too, two instances in one process
sharing the model)."""
from __future__ import annotations

import threading
from pathlib import Path

import numpy as np
import pytest

from test_fmu import fmus, instance, unzipped  # noqa: F401

import inerter
from inerter.elements import layout
from inerter.engine import compiled

DATA = Path(__file__).parent / "data"
BAR_3D = DATA / "winding_bar_3d.toml"
EFFICIENCY = DATA / "device_combo_efficiency_pair_3d.toml"

#: Communication steps of the comparisons: 100 of 10 ms; the second run starts half-way.
STEPS, DT = 100, 0.01

#: The stepper paths and methods compared: the numpy path, scipy's implicit methods on the compiled
#: right-hand side (which shared the model's kernel tables), and the compiled loop (DOP853).
KINDS = [dict(path="numpy"), dict(path="compiled", method="Radau"), dict(path="compiled", method="BDF"),
         dict(path="compiled")]


@pytest.fixture(scope="module")
def bar():
    return inerter.load(BAR_3D, w=20.0)


def _stepped(model, kind, meanwhile=None):
    """A stepper's outputs after each of STEPS steps; `meanwhile()`, from the half-way step on,
    called once and its result (a second stepper) stepped from 0 alongside, before each step."""
    a = model.stepper(**kind)
    rows, other = [], None
    for k in range(STEPS):
        if meanwhile is not None and k == STEPS // 2:
            other = meanwhile()
        if hasattr(other, "step"):
            other.step((k - STEPS // 2 + 1) * DT)
            other.output_values()
        a.step((k + 1) * DT)
        rows.append(a.output_values())
    return np.array(rows)


@pytest.mark.parametrize("kind", KINDS, ids=lambda k: k.get("method", k["path"]))
def test_two_steppers_of_one_model_step_as_each_alone(bar, kind):
    """A second stepper started half-way and stepped in turn with the first leaves the first's
    outputs bit for bit as alone (its angle past 2π, not reset to the second's 0), and gives its own
    outputs as the first gave them (the same model, from t = 0)."""
    alone = _stepped(bar, kind)
    assert alone[:, bar.signals.index["torsion.phi_rel"]].max() > 2 * np.pi       # it winds
    seconds = []
    both = _stepped(bar, kind, lambda: seconds.append(bar.stepper(**kind)) or seconds[0])
    assert np.array_equal(both, alone)
    second = seconds[0]
    assert second.time == pytest.approx((STEPS - STEPS // 2) * DT)
    assert np.array_equal(np.array(second.output_values()), alone[STEPS - STEPS // 2 - 1])


@pytest.mark.parametrize("kind", KINDS[:2] + KINDS[3:], ids=lambda k: k.get("method", k["path"]))
def test_a_whole_run_and_its_outputs_between_steps_change_nothing_of_a_stepper(bar, kind):
    """simulate() of the same model, and every output of its result read (which winds the
    angles of the mechanism it reads them on), between two steps leave the stepper's outputs bit
    for bit as alone; the run's own outputs are those of a run alone."""
    alone = _stepped(bar, kind)
    run = dict(path=kind["path"], method=kind.get("method"), metrics=False)
    reference = bar.simulate(stop_time=1.0, **run).values()
    results = []
    both = _stepped(bar, kind, lambda: results.append(bar.simulate(stop_time=1.0, **run).values()))
    assert np.array_equal(both, alone)
    assert np.array_equal(results[0], reference)


def _run_state(model):
    """What a run changes as it goes, as the model holds it: its mechanism's φ_ref and screw
    efficiencies' modes, its kernel's tables and its count of unsettled solves."""
    mech = model.mechanism
    kernel = compiled._kernel_for(mech)
    return (mech.windings.tolist(), [float(e.row[layout.EFFICIENCY_MODE]) for e in mech.efficient],
            kernel.params[compiled._k.EL_REAL].tolist(), kernel.params[compiled._k.ROT_REAL].tolist(),
            kernel.unsettled)


@pytest.mark.parametrize("scene", [BAR_3D, EFFICIENCY], ids=lambda p: p.stem)
def test_runs_and_steppers_leave_the_model_as_loaded(scene):
    """After whole runs and steppers of every path (and their outputs read), the model's mechanism
    and kernel hold the φ_ref (0) and modes (+1) they were loaded with: the next run starts from
    the model as loaded, whatever ran before. (Before the fix the efficiency's mode was left at −1
    and φ_ref at the last run's angle.)"""
    model = inerter.load(scene)
    loaded = _run_state(model)
    for kind in KINDS:
        model.simulate(stop_time=0.2, path=kind["path"], method=kind.get("method"), metrics=False).values()
        stepper = model.stepper(**kind)
        stepper.step(0.2)
        stepper.output_values()
        assert _run_state(model) == loaded, kind


def test_whole_runs_in_threads_give_the_run_alone(bar):
    """Three simulate() of one model at once in threads (an importer stepping FMU instances of one
    scene in worker threads shares the model the same way) each give the run alone bit for bit."""
    for kind in KINDS[:2] + KINDS[3:]:
        run = dict(path=kind["path"], method=kind.get("method"), metrics=False)
        reference = bar.simulate(stop_time=1.0, **run).values()
        got = {}
        threads = [threading.Thread(target=lambda i=i: got.__setitem__(i, bar.simulate(stop_time=1.0, **run).values()))
                   for i in range(3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert len(got) == 3 and all(np.array_equal(v, reference) for v in got.values()), kind


def test_first_runs_with_metrics_in_threads_give_the_metrics_alone():
    """Three first simulate() with metrics of one fresh model at once, in threads: their metrics
    read the model's static equilibrium, natural frequencies and static values, worked out once, on
    the analyses' own copy of the mechanism (Model._analysed), while the runs go on: each gives the
    metrics of a run alone on another fresh model, bit for bit. two_bar_2d: a natural frequency and
    a steady state whose reference is a static value."""
    scene = Path(__file__).resolve().parents[1] / "scenarios" / "two_bar_2d.toml"
    run = dict(stop_time=30.0, rtol=1e-8, atol=1e-10)
    alone = inerter.load(scene).simulate(**run).metrics
    assert set(alone) >= {"natural_frequency", "C_y_mean_offset"}, alone
    for _ in range(3):
        model, got = inerter.load(scene), {}
        threads = [threading.Thread(target=lambda i=i: got.__setitem__(i, model.simulate(**run).metrics))
                   for i in range(3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert len(got) == 3 and all(metrics == alone for metrics in got.values()), (alone, got)


@pytest.mark.parametrize("solver, compiled_path", [("DOP853", True), ("Radau", True), ("BDF", True),
                                                    ("DOP853", False)])
def test_two_fmu_instances_of_one_scene_step_as_each_alone(fmus, instance, solver, compiled_path):
    """Two instances of the bar's FMU in one process (which share the loaded model): the second,
    initialised half-way and stepped in turn with the first, leaves the first's φ and τ bit for bit
    as an instance alone gave them (the first's angle jumped by 2π before the fix)."""
    fmu = fmus[BAR_3D]
    names = ["torsion.phi_rel", "torsion.tau"]

    def start(name):
        inst = instance(fmu, name, logging=False)
        inst.initialise(reals={"w": 20.0}, strings={"solver": solver}, booleans={"compiled": compiled_path})
        return inst

    ref = start("alone")
    alone = []
    for k in range(STEPS):
        ref.fmu.doStep(k * DT, DT)
        alone.append(ref.get(names))
    first = start("first")
    got, second = [], None
    for k in range(STEPS):
        if k == STEPS // 2:
            second = start("second")
        if second is not None:
            second.fmu.doStep((k - STEPS // 2) * DT, DT)
        first.fmu.doStep(k * DT, DT)
        got.append(first.get(names))
    assert max(row[0] for row in alone) > 2 * np.pi
    assert got == alone
    assert second.get(names) == alone[STEPS - STEPS // 2 - 1]
