"""The FMI 2.0 co-simulation FMUs (inerter.fmu_build, fmu_src/), checked through fmpy.

One FMU per scene in scenarios/, built once per session. What is checked: the model description
(fmpy's validator, names, units, descriptions), a run in a fresh process against the solver, two
scenes in one process, bit-identical rollback through FMU state (in memory and serialized),
and that every error leaves the importer standing with a status and a logged message.

pythonfmu 0.7.0 turns every Python exception into fmi2Fatal and lets a Python slave return no
other status than fmi2OK and (from doStep) fmi2Discard, so errors are reported as a logged
message followed by fmi2Discard from the next doStep (see fmu_src/inerter_slave.py).
"""
from __future__ import annotations

import importlib.util
import json
import math
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE,  # noqa: E402
                       fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
from fmpy.validation import validate_fmu  # noqa: E402

import inerter  # noqa: E402
from inerter import fmu_build  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "scenarios").glob("*.toml"))
SCENE_PARAMS = [pytest.param(p, id=p.stem) for p in SCENES] or [
    pytest.param(None, id="no-scenes", marks=pytest.mark.skip(reason="no scene in scenarios/"))]

FMI_DISCARD = 2
#: Length of the runs compared with the solver (s): short, the comparison needs no more.
RUN_TIME = 0.5
RTOL = 1e-10

# A small scene with an input force (the scenes in scenarios/ have none).
INPUT_SCENE = """
[scene]
name = "fmu_test_input"
description = "a mass on a slider, a spring and an inerter to a pole, pushed by an input force"

[parameters]
m = { value = 2.0, unit = "kg", description = "mass" }
k = { value = 50.0, unit = "N/m", description = "spring stiffness" }
b = { value = 1.0, unit = "kg", description = "inertance" }

[ground.points]
O = [0, 0]
G = [1, 0]

[bodies.mass]
mass = "m"
inertia = 0
position = [1, 1]
points = { P = [0, 0] }

[joints.slider]
type = "prismatic"
between = ["G", "P"]
axis = [0, 1]

[elements.spring]
type = "spring"
between = ["O", "P"]
k = "k"

[elements.inerter]
type = "inerter"
between = ["O", "P"]
b = "b"

[forces.push]
point = "P"
function = "input"

[experiment]
stop_time = 1.0
output_interval = 0.01
method = "DOP853"
rtol = 1e-10
atol = 1e-12
"""


# ----------------------------------------------------------------------------------------------
# Fixtures and helpers
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def fmus(tmp_path_factory):
    """scene path -> its FMU, all built once (into a temporary folder, not build/)."""
    out = tmp_path_factory.mktemp("fmu")
    return {scene: fmu_build.build(scene, out, force=True) for scene in SCENES}


@pytest.fixture(scope="session")
def input_fmu(tmp_path_factory):
    """(scene path, FMU) of INPUT_SCENE."""
    folder = tmp_path_factory.mktemp("input_scene")
    scene = folder / "fmu_test_input.toml"
    scene.write_text(INPUT_SCENE)
    return scene, fmu_build.build(scene, folder / "fmu", force=True)


@pytest.fixture(scope="session")
def unzipped(tmp_path_factory):
    """FMU path -> its extracted folder, each extracted once."""
    cache = {}

    def get(fmu: Path) -> str:
        if fmu not in cache:
            cache[fmu] = extract(str(fmu), unzipdir=str(tmp_path_factory.mktemp(fmu.stem)))
        return cache[fmu]
    return get


class Instance:
    """One FMU instance through fmpy's low-level API, with its log messages captured."""

    def __init__(self, unzipdir: str, name: str = "instance"):
        self.md = read_model_description(unzipdir)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.messages: list[tuple[int, str]] = []
        # The callbacks must live as long as the instance.
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzipdir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=True)

    def _log(self, env, instance, status, category, message):
        self.messages.append((status, message.decode("utf-8")))

    def initialise(self, reals=None, strings=None, start_time=0.0, tolerance=None):
        self.fmu.setupExperiment(tolerance=tolerance, startTime=start_time)
        self.fmu.enterInitializationMode()
        for name, value in (reals or {}).items():
            self.fmu.setReal([self.vr[name]], [value])
        for name, value in (strings or {}).items():
            self.fmu.setString([self.vr[name]], [value])
        self.fmu.exitInitializationMode()

    def get(self, names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def set(self, name, value):
        self.fmu.setReal([self.vr[name]], [value])

    def logged(self) -> str:
        return "\n".join(m for _, m in self.messages)

    def close(self):
        try:
            self.fmu.terminate()
        except FMICallException:
            pass
        self.fmu.freeInstance()


@pytest.fixture
def instance(unzipped):
    """instance(fmu, name) -> an instantiated Instance, freed after the test."""
    made = []

    def make(fmu: Path, name: str = "instance") -> Instance:
        made.append(Instance(unzipped(fmu), name))
        return made[-1]
    yield make
    for inst in reversed(made):
        inst.close()


def run_fresh(tmp_path, jobs) -> dict:
    """Simulate FMUs with fmpy in a new interpreter: a clean environment (PATH and the virtual
    environment only), isolated mode, started outside the repository, so that the FMU can use
    nothing but what it ships and the installed numpy, scipy and fmpy."""
    script = r"""
import json, sys
import numpy as np
from fmpy import simulate_fmu
results = []
for job in json.loads(sys.argv[1]):
    kw = {}
    if job.get("input"):
        names = list(job["input"]["values"])
        signal = np.zeros(len(job["input"]["time"]),
                          dtype=[("time", np.float64)] + [(n, np.float64) for n in names])
        signal["time"] = job["input"]["time"]
        for n in names:
            signal[n] = job["input"]["values"][n]
        kw["input"] = signal
    r = simulate_fmu(job["fmu"], stop_time=job["stop_time"], output_interval=job["output_interval"],
                     start_values=job["start_values"], output=job["outputs"], **kw)
    results.append({n: r[n].tolist() for n in ["time"] + job["outputs"]})
print(json.dumps({"results": results,
                  "inerter": sys.modules["inerter"].__file__,
                  "modules": sorted(m for m in sys.modules if m.startswith("inerter_fmu_"))}))
"""
    env = {"PATH": os.environ.get("PATH", "")}
    if os.environ.get("VIRTUAL_ENV"):
        env["VIRTUAL_ENV"] = os.environ["VIRTUAL_ENV"]
    proc = subprocess.run([sys.executable, "-I", "-c", script, json.dumps(jobs)], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.strip().splitlines()[-1])


def job_for(scene: Path, fmu: Path, stop_time=RUN_TIME, **extra) -> dict:
    model = inerter.load(scene)
    return dict(fmu=str(fmu), stop_time=stop_time,
                output_interval=model.experiment["output_interval"],
                start_values={"rtol": RTOL}, outputs=[o["name"] for o in model.output_info()],
                **extra)


def assert_matches_solver(scene: Path, result: dict, stop_time=RUN_TIME):
    """The FMU's outputs against the solver's own run at the same tolerance."""
    model = inerter.load(scene)
    dt = model.experiment["output_interval"]
    ref = model.simulate(stop_time=stop_time, output_interval=dt, rtol=RTOL, metrics=False)
    time = np.array(result["time"])
    assert time[-1] == pytest.approx(stop_time, abs=1e-9), "the FMU stopped early"
    assert np.allclose(time, ref.time, rtol=0, atol=1e-9)
    lengths = [o["name"] for o in model.output_info() if o["unit"] == "m"]
    assert lengths
    worst = max(np.max(np.abs(np.array(result[n]) - ref[n])) for n in lengths)
    assert worst <= 1e-6, f"FMU and solver differ by {worst:.3g} m"


def first_parameter(inst: Instance) -> str:
    return next(v.name for v in inst.md.modelVariables
                if v.causality == "parameter" and v.type == "Real" and v.name not in ("rtol", "atol"))


# ----------------------------------------------------------------------------------------------
# Building
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("unit, exponents", [
    ("m", {"m": 1}), ("s", {"s": 1}), ("kg", {"kg": 1}), ("N", {"kg": 1, "m": 1, "s": -2}),
    ("J", {"kg": 1, "m": 2, "s": -2}), ("rad", {"rad": 1}), ("m/s", {"m": 1, "s": -1}),
    ("N.m", {"kg": 1, "m": 2, "s": -2}), ("kg.m2", {"kg": 1, "m": 2}), ("N/m", {"kg": 1, "s": -2}),
    ("N.s/m", {"kg": 1, "s": -1}), ("Hz", {"s": -1}), ("1", {}), ("m/s2", {"m": 1, "s": -2}),
    ("N.m/rad", {"kg": 1, "m": 2, "s": -2, "rad": -1}), ("rad/s", {"rad": 1, "s": -1}),
    ("J/(kg.K)", {"m": 2, "s": -2, "K": -1}),
])
def test_units_have_their_si_exponents(unit, exponents):
    assert fmu_build.si_unit(unit) == (exponents, 1.0)


@pytest.mark.parametrize("unit", ["furlong", "m/s.kg", "", "m^2"])
def test_unknown_units_are_refused(unit):
    with pytest.raises(ValueError):
        fmu_build.si_unit(unit)


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_fmpy_validates_the_fmu(fmus, scene):
    assert validate_fmu(str(fmus[scene])) == []


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_variables_are_named_and_united_like_the_model(fmus, scene):
    model = inerter.load(scene)
    md = read_model_description(str(fmus[scene]))
    assert md.coSimulation.modelIdentifier == md.modelName == model.name
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    assert float(md.defaultExperiment.stopTime) == model.experiment["stop_time"]
    step = model.experiment.get("communication_step") or model.experiment["output_interval"]
    assert float(md.defaultExperiment.stepSize) == step
    vars_ = {v.name: v for v in md.modelVariables}
    assert all(v.description for v in md.modelVariables)
    for p in model.parameter_info():
        v = vars_[p["name"]]
        assert (v.causality, v.variability, v.type) == ("parameter", "fixed", "Real")
        assert v.unit == p["unit"] and float(v.start) == p["value"]
    for e in model.effect_info():
        v = vars_[e["name"]]
        assert (v.causality, v.variability, v.type) == ("parameter", "fixed", "Boolean")
        assert v.start == ("true" if e["value"] else "false")
    assert vars_["solver"].type == "String" and vars_["solver"].start == model.experiment["method"]
    assert float(vars_["rtol"].start) == model.experiment["rtol"]
    assert float(vars_["atol"].start) == model.experiment["atol"]
    for i in model.input_info():
        v = vars_[i["name"]]
        assert (v.causality, v.type, v.unit, float(v.start)) == ("input", "Real", i["unit"], 0.0)
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    assert [v.name for v in outputs] == [o["name"] for o in model.output_info()]
    assert [v.unit for v in outputs] == [o["unit"] for o in model.output_info()]
    assert all(v.initial == "exact" for v in outputs)
    defined = {u.name: u.baseUnit for u in md.unitDefinitions}
    assert defined["N"].kg == 1 and defined["N"].m == 1 and defined["N"].s == -2
    assert {v.unit for v in md.modelVariables if v.unit} <= set(defined)


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_fmu_ships_the_solver_and_the_scene(fmus, scene):
    name = inerter.load(scene).name
    with zipfile.ZipFile(fmus[scene]) as z:
        files = set(z.namelist())
        assert z.read("resources/slavemodule.txt").decode().strip() == f"inerter_fmu_{name}"
        assert z.read(f"resources/{scene.name}") == scene.read_bytes()
        requirements = z.read("resources/requirements.txt").decode().split()
    assert {"numpy", "scipy"} <= set(requirements)
    assert {f"resources/inerter_fmu_{name}.py", "resources/inerter_slave.py",
            "resources/inerter/__init__.py", f"binaries/linux64/{name}.so"} <= files
    shipped = {f[len("resources/inerter/"):] for f in files if f.startswith("resources/inerter/")}
    package = {p.relative_to(ROOT / "inerter").as_posix() for p in (ROOT / "inerter").rglob("*.py")
               if "__pycache__" not in p.parts}
    assert package <= shipped
    assert not any("__pycache__" in f or f.endswith(".pyc") for f in files)


def test_a_current_fmu_is_not_rebuilt(tmp_path, capsys, monkeypatch):
    if not SCENES:
        pytest.skip("no scene in scenarios/")
    scene = tmp_path / SCENES[0].name
    scene.write_bytes(SCENES[0].read_bytes())
    out = tmp_path / "fmu"
    fmu = fmu_build.build(scene, out)
    stamp = fmu.stat().st_mtime_ns
    assert fmu_build.build(scene, out) == fmu and fmu.stat().st_mtime_ns == stamp
    assert (out / f"{fmu.stem}{fmu_build.HASH_SUFFIX}").is_file()
    assert fmu_build.main([str(scene), "-o", str(out)]) == 0
    assert "up to date" in capsys.readouterr().out
    scene.write_bytes(scene.read_bytes() + b"\n# changed\n")        # the scene changed
    assert fmu_build.main([str(scene), "-o", str(out)]) == 0
    assert "built" in capsys.readouterr().out and fmu.stat().st_mtime_ns != stamp
    stamp = fmu.stat().st_mtime_ns
    fmu_build.build(scene, out, force=True)
    assert fmu.stat().st_mtime_ns != stamp
    # The shipped code changed: a copy of fmu_src/ with an edited slave.
    src = tmp_path / "fmu_src"
    shutil.copytree(fmu_build.FMU_SRC, src)
    with open(src / fmu_build.SLAVE_FILE, "a") as f:
        f.write("\n# changed\n")
    monkeypatch.setattr(fmu_build, "FMU_SRC", src)
    stamp = fmu.stat().st_mtime_ns
    assert fmu_build.build(scene, out) == fmu and fmu.stat().st_mtime_ns != stamp
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/inerter_slave.py").endswith(b"# changed\n")


def test_a_bad_scene_is_reported_by_the_build(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text(INPUT_SCENE.replace('m = { value = 2.0', 'm = { value = -2.0'))
    assert fmu_build.main([str(scene), "-o", str(tmp_path / "fmu")]) == 1
    err = capsys.readouterr().err
    assert "bad.toml" in err and "-2" in err
    assert not (tmp_path / "fmu" / "fmu_test_input.fmu").exists()


# ----------------------------------------------------------------------------------------------
# Running
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="session")
def fresh_run(fmus, tmp_path_factory):
    """scene -> run_fresh of its FMU alone (RUN_TIME s), run once."""
    cache = {}

    def get(scene: Path) -> dict:
        if scene not in cache:
            cache[scene] = run_fresh(tmp_path_factory.mktemp("run"), [job_for(scene, fmus[scene])])
        return cache[scene]
    return get


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_fmu_runs_in_a_fresh_process_like_the_solver(fresh_run, scene):
    run = fresh_run(scene)
    assert "resources" in Path(run["inerter"]).parts, "the FMU did not use its own inerter copy"
    assert_matches_solver(scene, run["results"][0])


def test_two_scenes_run_side_by_side_in_one_process(fmus, tmp_path):
    if len(SCENES) < 2:
        pytest.skip("needs two scenes")
    a, b = SCENES[:2]
    run = run_fresh(tmp_path, [job_for(a, fmus[a]), job_for(b, fmus[b]), job_for(a, fmus[a])])
    first, second, again = run["results"]
    assert len(run["modules"]) == 2
    assert_matches_solver(a, first)
    assert_matches_solver(b, second)
    assert again == first


COSIM_SCRIPT = r"""
import json, sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
log_output_level(CosimLogLevel.WARNING)
job = json.loads(sys.argv[1])
execution = CosimExecution.from_step_size(step_size=round(job["output_interval"] * 1e9))
index = execution.add_local_slave(CosimLocalSlave(fmu_path=job["fmu"], instance_name="fmu"))
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
for name, value in job["start_values"].items():
    execution.real_initial_value(index, vr[name], value)
assert execution.simulate_until(target_time=round(job["stop_time"] * 1e9))
print(json.dumps({"time": execution.status().current_time / 1e9,
                  "values": observer.last_real_values(index, [vr[n] for n in job["outputs"]])}))
"""


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_a_second_importer_gives_the_same_results(fmus, fresh_run, scene, tmp_path):
    """libcosimpy (the Open Simulation Platform's C++ co-simulation engine) against fmpy."""
    if importlib.util.find_spec("libcosimpy") is None:
        pytest.skip("libcosimpy is not installed")
    job = job_for(scene, fmus[scene])
    proc = subprocess.run([sys.executable, "-I", "-c", COSIM_SCRIPT, json.dumps(job)],
                          cwd=tmp_path, env={"PATH": os.environ.get("PATH", "")},
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    cosim = json.loads(next(line for line in reversed(proc.stdout.splitlines())
                            if line.startswith("{")))
    assert cosim["time"] == pytest.approx(RUN_TIME, abs=1e-9)
    reference = fresh_run(scene)["results"][0]
    for name, value in zip(job["outputs"], cosim["values"]):
        assert value == pytest.approx(reference[name][-1], rel=1e-9, abs=1e-12), name


def test_an_input_is_held_over_each_step(input_fmu, tmp_path):
    scene, fmu = input_fmu
    t = np.arange(0.0, RUN_TIME + 1e-9, 0.01)
    force = 20.0 * np.sin(2 * np.pi * 2.0 * t)
    run = run_fresh(tmp_path, [job_for(scene, fmu, input={"time": t.tolist(),
                                                          "values": {"P.f[2]": force.tolist()}})])
    result = run["results"][0]
    # The solver's own stepper with the same held inputs gives exactly the same outputs.
    model = inerter.load(scene, **{"experiment.rtol": RTOL})
    stepper = model.stepper()
    assert result["P.r[2]"][0] == stepper.outputs()["P.r[2]"]
    for i in range(1, len(result["time"])):
        stepper.set_input("P.f[2]", force[i - 1])
        stepper.step(result["time"][i])
        assert result["P.r[2]"][i] == stepper.outputs()["P.r[2]"]
    assert max(result["P.r[2]"]) - min(result["P.r[2]"]) > 0.01   # the input did push


# ----------------------------------------------------------------------------------------------
# FMU state
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_a_rolled_back_step_repeats_bit_for_bit(fmus, scene, instance):
    inst = instance(fmus[scene], "a")
    name = "b" if "b" in inst.vr else first_parameter(inst)
    changed = {name: 1.5 * inst.get([name])[0]}
    inst.initialise(reals=changed)
    h = float(inst.md.defaultExperiment.stepSize)
    t = 0.0
    for _ in range(5):
        inst.fmu.doStep(t, h)
        t += h
    state = inst.fmu.getFMUstate()

    def three_steps(i: Instance):
        out = []
        for n in range(3):
            i.fmu.doStep(t + n * h, h)
            out.append(i.get(i.outputs))
        return out

    first = three_steps(inst)
    inst.fmu.setFMUstate(state)
    assert three_steps(inst) == first
    # Serialized and restored in another instance initialised with the scene's own parameters:
    # the state carries the parameters too.
    blob = inst.fmu.serializeFMUstate(state)
    inst.fmu.freeFMUstate(state)
    other = instance(fmus[scene], "b")
    other.initialise()
    restored = other.fmu.deSerializeFMUstate(blob)
    other.fmu.setFMUstate(restored)
    other.fmu.freeFMUstate(restored)
    assert other.get([name]) == [changed[name]]
    assert three_steps(other) == first
    assert not [m for s, m in inst.messages + other.messages if s > 1]


# ----------------------------------------------------------------------------------------------
# Errors: a status and a message, never fmi2Fatal, and the importer goes on
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", SCENE_PARAMS)
@pytest.mark.parametrize("setting, value, field", [
    ("rtol", 5.0, "experiment.rtol"), ("solver", "Euler", "experiment.method"),
    ("b", -1.0, "b"), ("first parameter", math.nan, "not finite")])
def test_an_invalid_setting_fails_initialisation_with_its_message(fmus, scene, instance,
                                                                  setting, value, field):
    inst = instance(fmus[scene])
    if setting == "first parameter":
        setting = first_parameter(inst)
    if setting not in inst.vr:
        pytest.skip(f"the scene has no {setting}")
    strings, reals = ({setting: value}, {}) if isinstance(value, str) else ({}, {setting: value})
    inst.initialise(reals=reals, strings=strings)      # fmi2OK: pythonfmu can return no error here
    errors = [m for s, m in inst.messages if s == 3]
    assert errors and field in errors[0] and repr(value).strip("'") in errors[0]
    assert all(math.isnan(v) for v in inst.get(inst.outputs))
    inst.messages.clear()
    with pytest.raises(FMICallException) as caught:
        inst.fmu.doStep(0.0, 0.01)
    assert caught.value.status == FMI_DISCARD
    assert field in inst.logged()
    # The importer can go on: reset, and initialise with valid values.
    inst.fmu.reset()
    inst.initialise()
    inst.fmu.doStep(0.0, 0.01)


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_a_start_time_other_than_zero_is_refused(fmus, scene, instance):
    inst = instance(fmus[scene])
    inst.initialise(start_time=1.0)
    assert "startTime" in inst.logged()
    with pytest.raises(FMICallException) as caught:
        inst.fmu.doStep(1.0, 0.01)
    assert caught.value.status == FMI_DISCARD


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_setting_a_fixed_parameter_after_initialisation_is_refused(fmus, scene, instance):
    inst = instance(fmus[scene])
    inst.initialise()
    name = first_parameter(inst)
    before = inst.get([name])
    h = 0.01
    inst.fmu.doStep(0.0, h)
    outputs = inst.get(inst.outputs)
    inst.set(name, 2.0 * before[0] + 1.0)
    assert inst.get([name]) == before
    assert f"{name}: a fixed parameter cannot be changed" in inst.logged()
    inst.messages.clear()
    with pytest.raises(FMICallException) as caught:
        inst.fmu.doStep(h, h)
    assert caught.value.status == FMI_DISCARD and name in inst.logged()
    assert inst.get(inst.outputs) == outputs                  # nothing moved
    inst.fmu.doStep(h, h)                                     # and the importer goes on
    # Setting an output is refused the same way.
    inst.set(inst.outputs[0], 1.0)
    with pytest.raises(FMICallException):
        inst.fmu.doStep(2 * h, h)
    assert "an output cannot be set" in inst.logged()


def test_a_non_finite_input_is_refused_and_the_state_kept(input_fmu, instance):
    inst = instance(input_fmu[1])
    inst.initialise()
    h = 0.01
    inst.set("P.f[2]", 5.0)
    inst.fmu.doStep(0.0, h)
    state = inst.get(inst.outputs)
    for bad in (math.nan, math.inf):
        inst.messages.clear()
        inst.set("P.f[2]", bad)
        with pytest.raises(FMICallException) as caught:
            inst.fmu.doStep(h, h)
        assert caught.value.status == FMI_DISCARD
        assert "P.f[2]" in inst.logged() and "not finite" in inst.logged()
        assert inst.get(inst.outputs) == state
    inst.set("P.f[2]", 5.0)
    inst.fmu.doStep(h, h)
    assert inst.get(inst.outputs) != state


@pytest.mark.parametrize("scene", SCENE_PARAMS)
@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # numpy's overflow as the state blows up
def test_a_step_the_solver_cannot_complete_is_discarded(fmus, scene, instance):
    inst = instance(fmus[scene])
    if "k" not in inst.vr:
        pytest.skip("the scene has no stiffness k to make it blow up")
    # A fixed-step RK4 far beyond its stability limit: the state blows up within a few steps.
    inst.initialise(reals={"k": 1e12}, strings={"solver": "RK4"})
    h, t = 0.01, 0.0
    for _ in range(100):
        good = inst.get(inst.outputs)
        try:
            inst.fmu.doStep(t, h)
        except FMICallException as exc:
            assert exc.status == FMI_DISCARD
            break
        t += h
    else:
        pytest.fail("the step never failed")
    assert [s for s, _ in inst.messages if s == FMI_DISCARD]
    assert f"stays at t = {t!r}" in inst.logged()
    assert inst.get(inst.outputs) == good                     # the last good state is kept
    with pytest.raises(FMICallException) as caught:           # still there: the same step fails
        inst.fmu.doStep(t, h)
    assert caught.value.status == FMI_DISCARD


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_tolerance_from_setup_experiment_is_used_unless_rtol_is_set(fmus, scene, instance):
    inst = instance(fmus[scene], "tolerance")
    inst.initialise(tolerance=1e-7)
    assert "rtol 1e-07" in inst.logged()
    other = instance(fmus[scene], "explicit")
    other.initialise(reals={"rtol": 1e-9}, tolerance=1e-7)
    assert "rtol 1e-09" in other.logged()


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_misuse_of_value_references_is_logged_not_fatal(fmus, scene, instance):
    inst = instance(fmus[scene])
    inst.initialise()
    assert math.isnan(inst.fmu.getReal([10_000])[0])
    assert "valueReference 10000" in inst.logged()
    inst.fmu.setBoolean([inst.vr[first_parameter(inst)]], [True])   # a Real, set as a Boolean
    with pytest.raises(FMICallException):
        inst.fmu.doStep(0.0, 0.01)
    inst.fmu.doStep(0.0, 0.01)
