"""What an FMU declares and what a co-simulation master can change (issue 24), each checked
against a reference computed apart from the build:

- ModelStructure: which outputs follow an input at the same instant, from setting each input at a
  communication point and reading every output again (the master's view), and from the oracle's
  own evaluation of the outputs; positions and velocities never do;
- the outputs are calculated: in initialization mode they follow the parameters and inputs set
  so far, as a fresh load of the scene with those values gives them;
- the integration method is an Enumeration whose items are the methods the scene format takes;
- ``min`` where the scene format has a range (a value below it is refused by the scene reader),
  display units mm and deg (fmpy's own conversion of a start value given in deg);
- tunable parameters: those whose change only moves the numbers the kernels' tables hold
  (compared table by table), and a change at t = 1 s through the FMU equals the solver run that
  goes on from the same state with a model loaded with the new value;
- the host requirements in the description and requirements.txt are pyproject.toml's;
- the compile notice reaches the importer's logger while the compilation runs;
- fmutool -check (fmu-manipulation-toolbox) finds the FMUs compliant.
"""
from __future__ import annotations

import math
import re
import shutil
import subprocess
import tomllib
import types as pytypes
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from test_fmu import (FMI_ERROR, SCENE_PARAMS, SCENES, Instance, _Built, instance, needs_shim,  # noqa: E402,F401
                      raises_status, shim_expected, unzipped)

import inerter  # noqa: E402
from inerter.common.errors import SceneError  # noqa: E402
from inerter.elements import layout  # noqa: E402
from inerter.fmu import build as fmu_build  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TWO_BAR = ROOT / "scenarios" / "two_bar_2d.toml"
#: |FMU − solver| ≤ TOLERANCE_FACTOR · (rtol · max|solver| + atol) per output, as the shipped
#: scenes' FMU runs are held to (tests/test_shipped_scenes.py).
TOLERANCE_FACTOR = 1000.0


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    return _Built(tmp_path_factory.mktemp("fmu_structure"))


def model_description(fmu: Path) -> ET.Element:
    with zipfile.ZipFile(fmu) as z:
        return ET.fromstring(z.read("modelDescription.xml"))


def structure(fmu: Path, tag: str) -> dict[str, set[str]]:
    """Each Unknown of ModelStructure/`tag` by name -> the names it depends on (None: all)."""
    root = model_description(fmu)
    names = [v.get("name") for v in root.find("ModelVariables")]
    out = {}
    for unknown in root.find("ModelStructure").find(tag):
        deps = unknown.get("dependencies")
        out[names[int(unknown.get("index")) - 1]] = (
            None if deps is None else {names[int(i) - 1] for i in deps.split()})
        # Absent: every dependency is "dependent" (FMI 2.0, 2.2.8), as the build means it.
        assert unknown.get("dependenciesKind") is None
    return out


def step(inst: Instance, n: int, h: float, t: float = 0.0) -> float:
    for _ in range(n):
        inst.fmu.doStep(t, h)
        t += h
    return t


# ----------------------------------------------------------------------------------------------
# ModelStructure
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_positions_and_velocities_depend_on_no_input(fmus, scene):
    md = read_model_description(str(fmus[scene]))
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
    inputs = {v.name for v in md.modelVariables if v.causality == "input"}
    for tag in ("Outputs", "InitialUnknowns"):
        declared = structure(fmus[scene], tag)
        assert list(declared) == outputs, tag                 # every output, in their order
        for name, deps in declared.items():
            assert deps is not None, (tag, name)              # never "depends on everything"
            if ".r[" in name or ".v[" in name:
                assert not deps & inputs, (tag, name, deps)
    assert all(not deps - inputs for deps in structure(fmus[scene], "Outputs").values())


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_outputs_declared_to_follow_an_input_are_those_that_do(fmus, scene, instance):
    """Each input set at a communication point, every output read again at that instant: the
    outputs that changed are declared to depend on that input, and every output declared to
    depend on inputs changed with one of them. (A declared dependency may be zero where a joint
    takes the force: two_bar_2d_as_3d's C.f[3], out of its plane, moves nothing.)"""
    declared = structure(fmus[scene], "Outputs")
    inst = instance(fmus[scene])
    inputs = [v.name for v in inst.md.modelVariables if v.causality == "input"]
    if not inputs:
        assert all(deps == set() for deps in declared.values())
        return
    inst.initialise()
    step(inst, 5, 0.01)
    followed = set()
    for name in inputs:
        before = inst.get(inst.outputs)
        inst.set(name, inst.get([name])[0] + 10.0)
        after = inst.get(inst.outputs)
        moved = {o for o, a, b in zip(inst.outputs, before, after) if a != b}
        assert moved <= {o for o, deps in declared.items() if name in deps}, name
        followed |= moved
    assert followed == {o for o, deps in declared.items() if deps}
    assert followed, "no output follows an input: the check would prove nothing"


@pytest.mark.parametrize("scene", [p for p in SCENE_PARAMS if p.values[0] is not None
                                   and inerter.load(p.values[0]).input_info()])
def test_the_oracle_sees_the_same_feedthrough(fmus, scene):
    """The oracle (element forces from their definitions) evaluates every output at a state with
    the inputs at 0 and at 1: those that differ are the ones the FMU declares."""
    oracle = inerter.load(scene).oracle()
    mech, signals = oracle.mechanism, oracle.signals
    rng = np.random.default_rng(5)
    q, v = np.asarray(mech.q0, dtype=float), rng.normal(0.0, 0.3, len(mech.v0))
    zero = signals.evaluate(0.0, q, v, np.zeros(len(mech.input_names)))
    declared = structure(fmus[scene], "Outputs")
    followed = set()
    for i, name in enumerate(mech.input_names):
        inputs = np.zeros(len(mech.input_names))
        inputs[i] = 1.0
        values = signals.evaluate(0.0, q, v, inputs)
        moved = {o for o, a, b in zip(signals.names, zero, values) if abs(a - b) > 1e-12 * max(1.0, abs(a))}
        assert moved <= {o for o, deps in declared.items() if name in deps}, name
        followed |= moved
    assert followed == {o for o, deps in declared.items() if deps} != set()


def test_in_initialization_mode_the_outputs_follow_parameters_and_inputs(fmus, instance):
    """Outputs are calculated: read in initialization mode they are those of a fresh load of the
    scene with the values set so far (th1 moves the pose; an input moves the inerter's force)."""
    inst = instance(fmus[TWO_BAR])
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()
    inst.set("th1", 0.7)
    inst.set("C.f[2]", 3.0)
    got = dict(zip(inst.outputs, inst.get(inst.outputs)))
    stepper = inerter.load(TWO_BAR, th1=0.7).stepper()
    stepper.set_input("C.f[2]", 3.0)
    want = dict(zip(stepper.signals.names, stepper.output_values()))
    assert got == pytest.approx(want, rel=1e-12, abs=1e-12)
    assert got["inerter.f"] != pytest.approx(
        inerter.load(TWO_BAR, th1=0.7).stepper().outputs()["inerter.f"], abs=1e-6)
    inst.fmu.exitInitializationMode()
    assert dict(zip(inst.outputs, inst.get(inst.outputs))) == got


# ----------------------------------------------------------------------------------------------
# Types, ranges, units
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_integration_method_is_an_enumeration_of_the_scene_formats_methods(fmus, scene, instance):
    md = read_model_description(str(fmus[scene]))
    solver = next(v for v in md.modelVariables if v.name == "solver")
    assert solver.type == "Enumeration" and solver.declaredType.name == fmu_build.METHOD_TYPE
    items = {int(i.value): i.name for i in solver.declaredType.items}
    assert sorted(items) == list(range(1, len(items) + 1))
    model = inerter.load(scene)
    assert items[int(solver.start)] == model.experiment["method"]
    for value, name in items.items():         # each item is a method a scene may name
        assert inerter.load(scene, **{"experiment.method": name}).settings().method == name
    with pytest.raises(SceneError):
        inerter.load(scene, **{"experiment.method": "Euler"})
    inst = instance(fmus[scene], "RK45")
    inst.initialise(strings={"solver": "RK45"})
    assert "with solver RK45," in inst.logged()
    assert inst.fmu.getInteger([inst.vr["solver"]]) == [next(v for v, n in items.items() if n == "RK45")]


def test_a_value_that_is_no_item_fails_initialisation_naming_the_items(fmus, instance, needs_shim):
    inst = instance(fmus[TWO_BAR])
    raises_status(FMI_ERROR, inst.initialise, None, {"solver": 0})
    [error] = inst.errors()
    assert "solver: no such item (got 0; expected one of 1 (DOP853), 2 (RK45)" in error


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_a_value_below_a_parameters_min_is_refused_by_the_scene(fmus, scene):
    md = read_model_description(str(fmus[scene]))
    bounded = [v for v in md.modelVariables if v.causality == "parameter" and v.type == "Real"
               and v.min is not None and v.name not in ("rtol", "atol")]
    for v in bounded:
        low = float(v.min) - 1e-3 * max(1.0, abs(float(v.min)))
        # refused where the value is used, or earlier where another parameter is an expression of
        # it (tid_storey_2d: c = 0.04·sqrt(k·m) fails for k < 0 before the spring's range is checked)
        with pytest.raises(SceneError, match="out of range|out of the domain"):
            inerter.load(scene, **{v.name: low})
    rtol = next(v for v in md.modelVariables if v.name == "rtol")
    for bad in (float(rtol.min) / 2, float(rtol.max) * 2):
        with pytest.raises(SceneError, match="experiment.rtol"):
            inerter.load(scene, **{"experiment.rtol": bad})
    for good in (float(rtol.min), float(rtol.max)):
        inerter.load(scene, **{"experiment.rtol": good})


def test_element_coefficients_of_the_paper_scene_have_their_kinds_range(fmus):
    md = read_model_description(str(fmus[TWO_BAR]))
    bounds = {v.name: v.min for v in md.modelVariables if v.causality == "parameter"}
    # k, c, b, kr fill element coefficients (≥ 0), J1, J2 the bodies' inertias (≥ 0); M1, M2 are
    # masses (> 0, an exclusive bound FMI's min cannot state), th1, th2 angles, Fa and f unbounded
    assert {n for n, m in bounds.items() if m is not None} == {"k", "c", "b", "kr", "J1", "J2", "rtol"}
    assert all(float(bounds[n]) == 0.0 for n in ("k", "c", "b", "kr", "J1", "J2"))


def test_display_units_are_mm_and_deg(fmus, tmp_path):
    md = read_model_description(str(fmus[TWO_BAR]))
    factors = {u.name: {d.name: d.factor for d in u.displayUnits} for u in md.unitDefinitions}
    assert factors["m"] == {"mm": pytest.approx(1000.0, rel=1e-15)}
    assert factors["rad"] == {"deg": pytest.approx(180.0 / math.pi, rel=1e-15)}
    shown = {v.name: v.displayUnit for v in md.modelVariables}
    assert shown["th1"] == "deg" and shown["C.r[2]"] == "mm" and shown["C.v[2]"] == "mm/s"
    # fmpy converts a start value given in a display unit with the factor declared
    runs = [fmpy.simulate_fmu(str(fmus[TWO_BAR]), stop_time=0.02, output_interval=0.01,
                              start_values=start, output=["C.r[1]", "C.r[2]"])
            for start in ({"th1": (40.0, "deg")}, {"th1": math.radians(40.0)})]
    assert runs[0]["C.r[2]"] == pytest.approx(runs[1]["C.r[2]"], rel=1e-14)
    assert runs[0]["C.r[2]"][0] == pytest.approx(inerter.load(TWO_BAR, th1=math.radians(40.0))
                                                 .stepper().outputs()["C.r[2]"], abs=1e-14)


# ----------------------------------------------------------------------------------------------
# Tunable parameters
# ----------------------------------------------------------------------------------------------
def tables(model) -> dict:
    from inerter.engine import compiled
    if compiled.unsupported(model.mechanism):
        return {}
    return compiled.Kernel(model.mechanism).flat


def table_tunable(scene: Path) -> set[str]:
    """The parameters whose change (× 1.5 + 1, or × 0.5 where the scene refuses that) and the effect
    switches whose flip move only the numbers the kernels read at each evaluation: element
    coefficients (column COEFFICIENT), the centripetal column and an inerter device's columns, a
    point force's value, amplitude, frequency, a PD actuator's gains; the initial state and every
    other table entry stay."""
    base = inerter.load(scene)
    flat0 = tables(base)
    out = set()
    trials = [(p["name"], (1.5 * p["value"] + 1.0, 0.5 * p["value"])) for p in base.parameter_info()]
    trials += [(e["name"], (not e["value"],)) for e in base.effect_info()]
    for name, values in trials:
        other = None
        for trial in values:
            try:
                other = inerter.load(scene, **{name: trial})
                break
            except SceneError:
                continue
        if other is None:
            continue
        flat1 = tables(other)
        if not (np.array_equal(base.mechanism.q0, other.mechanism.q0)
                and np.array_equal(base.mechanism.v0, other.mechanism.v0)) or not flat0:
            continue
        dim = flat0["dim"]
        device = list(range(layout.DEVICE, layout.FLUID_QUADRATIC + 1))
        device += list(range(layout.INERTIA, layout.MOUNT_AXIS + 3))       # its masses, inertias and mount
        device += list(range(layout.SERIES, layout.LOSS + 1))             # its series connection
        device += list(range(layout.EFFICIENCY, layout.EFFICIENCY_SCALE + 1))  # its screw efficiency
        tunable_columns = {"el_real": [layout.COEFFICIENT, layout.CENTRIPETAL] + device,
                           "rot_real": [layout.COEFFICIENT],
                           "fa_real": [dim + layout.F_VALUE, dim + layout.F_AMPLITUDE, dim + layout.F_FREQUENCY],
                           "pd_real": [dim + layout.PD_KP, dim + layout.PD_KD]}
        moved = tuned = False
        for key, a in flat0.items():
            b = flat1[key]
            if not isinstance(a, np.ndarray):
                moved |= a != b
                continue
            if a.shape != b.shape:
                moved = True
                continue
            differs = a != b
            if key in tunable_columns and differs.size:
                tuned |= bool(differs[:, tunable_columns[key]].any())
                differs[:, tunable_columns[key]] = False
            moved |= bool(differs.any())
        if tuned and not moved:
            out.add(name)
    return out


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_tunable_parameters_are_those_the_kernels_tables_take(fmus, scene):
    md = read_model_description(str(fmus[scene]))
    model = inerter.load(scene)
    parameters = {p["name"] for p in model.parameter_info()} | {e["name"] for e in model.effect_info()}
    tunable = {v.name for v in md.modelVariables if v.variability == "tunable"}
    assert tunable <= parameters
    assert tunable == table_tunable(scene)
    said = re.search(r"Tunable between steps: (.*?)(?:; |\. |\.$)", md.description)   # names may hold dots
    assert (set(said.group(1).split(", ")) if said else set()) == tunable, md.description


def solver_with_a_change(scene: Path, t_change: float, stop: float, h: float, name: str, value: float,
                         rtol: float):
    """Outputs at each communication point of the solver's stepper, which goes on at t_change from
    its state with the stepper of a model loaded with `name` = `value` (a new load, not a retune)."""
    first = inerter.load(scene, **{"experiment.rtol": rtol}).stepper()
    rows = [first.output_values()]
    n_change, n = round(t_change / h), round(stop / h)
    for k in range(1, n_change + 1):
        first.step(k * h)
        rows.append(first.output_values())
    second = inerter.load(scene, **{"experiment.rtol": rtol, name: value}).stepper()
    second.time, second.y, second.h = first.time, first.y.copy(), first.h
    for k in range(n_change + 1, n + 1):
        second.step(k * h)
        rows.append(second.output_values())
    return np.array(rows), first.signals.names


def _case(scene: str, name: str, factor: float, compiled: bool = True):
    path = ROOT / "scenarios" / f"{scene}.toml"
    return pytest.param(path, name, factor, compiled, id=f"{scene}-{name}-{'compiled' if compiled else 'numpy'}")


@pytest.mark.parametrize("scene, name, factor, compiled", [
    _case("two_bar_2d", "b", 2.0), _case("two_bar_2d", "Fa", 0.25), _case("two_bar_2d", "f", 1.5),
    _case("two_bar_2d", "b", 2.0, compiled=False), _case("two_bar_2d_pd", "kp", 3.0),
    _case("double_pendulum_3d", "c", 4.0), _case("two_bar_2d_device", "Fc", 4.0)])
def test_a_tunable_parameter_changed_mid_run_equals_the_solver_changing_it(fmus, instance, scene, name,
                                                                          factor, compiled):
    """Through fmpy's FMU2Slave on the FMU's compiled and numpy paths; the reference is the
    solver's default stepper, which goes on at t = 1 s from the same state with a model loaded
    with the new value."""
    rtol, h, t_change, stop = 1e-10, 0.01, 1.0, 1.5
    inst = instance(fmus[scene])
    assert inst.variables[name].variability == "tunable"
    inst.initialise(reals={"rtol": rtol}, booleans={"compiled": compiled})
    assert f"{'compiled' if compiled else 'numpy'} path" in inst.logged()
    value = factor * inst.get([name])[0]
    rows = [inst.get(inst.outputs)]
    t = 0.0
    for k in range(1, round(stop / h) + 1):
        if k - 1 == round(t_change / h):
            inst.set(name, value)
            assert inst.get([name]) == [value]
        inst.fmu.doStep(t, h)
        t = k * h
        rows.append(inst.get(inst.outputs))
    fmu = np.array(rows)
    ref, names = solver_with_a_change(scene, t_change, stop, h, name, value, rtol)
    unchanged, _ = solver_with_a_change(scene, t_change, stop, h, name, value / factor, rtol)
    assert list(names) == inst.outputs
    atol = inerter.load(scene, **{"experiment.rtol": rtol}).settings().atol
    # After the change the two restart differently (the FMU's first step lands on the next
    # communication point), so each output is held to the scale of the outputs of its unit: a
    # velocity component that stays near 0 to the speeds of the scene.
    units = inerter.load(scene).signals.units
    for j, output in enumerate(names):
        scale = max(float(np.max(np.abs(ref[:, i]))) for i, u in enumerate(units) if u == units[j])
        tolerance = TOLERANCE_FACTOR * (rtol * scale + atol)
        assert np.max(np.abs(fmu[:, j] - ref[:, j])) <= tolerance, output
    # the change mattered: without it the run differs by far more than the tolerance
    lengths = [j for j, o in enumerate(names) if ".r[" in o]
    assert max(np.max(np.abs(unchanged[:, j] - ref[:, j])) for j in lengths) > 1e-5
    assert f"{name} = {value!r} from t = 1.0 s on" in inst.logged()


@pytest.mark.parametrize("compiled", [True, False], ids=["compiled", "numpy"])
def test_the_centripetal_switch_flipped_mid_run_equals_the_solver_flipping_it(fmus, instance, compiled):
    """effects.centripetal set false at t = 1 s through fmpy's FMU2Slave; the reference is the
    solver's stepper going on from the same state with a model loaded without the term."""
    scene, name, rtol, h, t_change, stop = TWO_BAR, "effects.centripetal", 1e-10, 0.01, 1.0, 1.5
    inst = instance(fmus[scene])
    assert inst.variables[name].variability == "tunable"
    inst.initialise(reals={"rtol": rtol}, booleans={"compiled": compiled})
    rows = [inst.get(inst.outputs)]
    t = 0.0
    for k in range(1, round(stop / h) + 1):
        if k - 1 == round(t_change / h):
            inst.fmu.setBoolean([inst.vr[name]], [False])
        inst.fmu.doStep(t, h)
        t = k * h
        rows.append(inst.get(inst.outputs))
    fmu = np.array(rows)
    ref, names = solver_with_a_change(scene, t_change, stop, h, name, False, rtol)
    kept, _ = solver_with_a_change(scene, t_change, stop, h, name, True, rtol)
    atol = inerter.load(scene, **{"experiment.rtol": rtol}).settings().atol
    units = inerter.load(scene).signals.units
    for j, output in enumerate(names):
        scale = max(float(np.max(np.abs(ref[:, i]))) for i, u in enumerate(units) if u == units[j])
        assert np.max(np.abs(fmu[:, j] - ref[:, j])) <= TOLERANCE_FACTOR * (rtol * scale + atol), output
    lengths = [j for j, o in enumerate(names) if ".r[" in o]
    assert max(np.max(np.abs(kept[:, j] - ref[:, j])) for j in lengths) > 1e-5     # the flip mattered


def test_a_tunable_value_the_scene_refuses_is_an_error_and_changes_nothing(fmus, instance, needs_shim):
    inst, clean = instance(fmus[TWO_BAR], "seen"), instance(fmus[TWO_BAR], "clean")
    for i in (inst, clean):
        i.initialise()
        step(i, 3, 0.01)
    raises_status(FMI_ERROR, inst.set, "b", -1.0)
    [error] = inst.errors()
    assert "b: cannot change to -1.0 at t = 0.03 s" in error and "elements.inerter.b" in error \
        and "expected a number ≥ 0" in error
    assert inst.get(["b"]) == [10.0]
    for i in (inst, clean):
        i.fmu.doStep(0.03, 0.01)
    assert inst.get(inst.outputs) == clean.get(clean.outputs)


def test_an_inertance_that_was_zero_cannot_become_non_zero_between_steps(fmus, instance, needs_shim):
    """The compiled band is laid out for the inerters whose inertance is not 0 at initialisation."""
    inst = instance(fmus[TWO_BAR])
    inst.initialise(reals={"b": 0.0})
    step(inst, 2, 0.01)
    raises_status(FMI_ERROR, inst.set, "b", 5.0)
    assert "element inerter: an inertance that was 0" in inst.errors()[0]
    inst.set("b", 0.0)                      # and back: an inertance that stays 0 is fine
    step(inst, 1, 0.01, 0.02)


def test_a_rollback_after_a_change_repeats_it(fmus, instance):
    """FMU state holds the tuned value: a rolled-back step after a change repeats bit for bit."""
    inst = instance(fmus[TWO_BAR])
    inst.initialise()
    t = step(inst, 3, 0.01)
    inst.set("c", 250.0)
    state = inst.fmu.getFMUstate()
    inst.fmu.doStep(t, 0.01)
    first = inst.get(inst.outputs)
    inst.set("c", 100.0)
    inst.fmu.setFMUstate(state)
    inst.fmu.freeFMUstate(state)
    assert inst.get(["c"]) == [250.0]
    inst.fmu.doStep(t, 0.01)
    assert inst.get(inst.outputs) == first


# ----------------------------------------------------------------------------------------------
# What the FMU needs of its host, and what it says while it compiles
# ----------------------------------------------------------------------------------------------
def test_the_host_requirements_are_the_packages_own(fmus):
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    required = {d.split(">=")[0].strip(): ">=" + d.split(">=")[1].strip() for d in project["dependencies"]}
    wanted = {"python": project["requires-python"], **{n: required[n] for n in ("numpy", "scipy", "numba")}}
    assert fmu_build.HOST_REQUIREMENTS == wanted
    md = read_model_description(str(fmus[TWO_BAR]))
    for name, spec in wanted.items():
        assert f"{'Python' if name == 'python' else name} {spec}" in md.description
    with zipfile.ZipFile(fmus[TWO_BAR]) as z:
        shipped = [line for line in z.read("resources/requirements.txt").decode().splitlines()
                   if line and not line.startswith("#")]          # under a note on the interpreter
    assert shipped == [f"{n}{s}" for n, s in wanted.items() if n != "python"]
    docs = " ".join((ROOT / "docs" / "fmu.md").read_text().split())
    assert all(f"{'Python' if n == 'python' else n} {s}" in docs for n, s in wanted.items())


def test_the_compile_notice_reaches_the_importers_logger_while_it_compiles(fmus, instance, needs_shim,
                                                                         monkeypatch):
    """numba's compile events fed by hand inside exitInitializationMode (nothing compiles): the
    notice's first line is in the importer's log before the compilation ends, not only when the
    call returns."""
    from numba.core import types
    from inerter.engine import compiled
    kernels = compiled._k
    params = types.Tuple([types.Array(types.float64, 1, "C")] * len(kernels.PARAMS))

    def event(name):
        func = pytypes.SimpleNamespace(__name__=name, __module__=kernels.__name__)
        return pytypes.SimpleNamespace(data={"dispatcher": pytypes.SimpleNamespace(py_func=func),
                                             "args": (types.int64, params)})
    monkeypatch.setattr(compiled.NOTICE, "_announced", set())
    inst = instance(fmus[TWO_BAR])
    seen_during = []
    original = compiled.CompiledStepper.__init__

    def compiling(self, *args, **kwargs):
        for name in ("integrate_rk", "signal_values"):     # the first of the dimension, another one
            compiled.NOTICE.on_start(event(name))
            seen_during.append([m for _, m in inst.messages])
            compiled.NOTICE.on_end(event(name))
        original(self, *args, **kwargs)
    monkeypatch.setattr(compiled.CompiledStepper, "__init__", compiling)
    inst.initialise()
    assert any("compiling the engine's 2D kernels for this machine" in m for m in seen_during[0]), seen_during
    assert any("compiling the engine's 2D kernels: the outputs" in m for m in seen_during[1]), seen_during
    assert sum(m.startswith("inerter: ... done in") for _, m in inst.messages) == 2
    assert compiled.NOTICE.stream is None and not compiled.NOTICE.eager       # as the FMU found them


# ----------------------------------------------------------------------------------------------
# A second validator
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_fmpy_and_fmutool_find_the_fmu_compliant(fmus, scene):
    assert validate_fmu(str(fmus[scene])) == []
    fmutool = shutil.which("fmutool") or str(Path(__import__("sys").executable).with_name("fmutool"))
    if not Path(fmutool).exists():
        pytest.skip("fmutool (fmu-manipulation-toolbox) is not installed")
    proc = subprocess.run([fmutool, "-input", str(fmus[scene]), "-check"], capture_output=True, text=True,
                          timeout=300)
    text = proc.stdout + proc.stderr
    assert proc.returncode == 0, text
    assert "This FMU seems to be compliant with FMI-2.0." in text
    assert "No semantic error against the FMI-2 standard." in text
    assert not [line for line in text.splitlines() if line.startswith(("WARNING", "ERROR"))], text
