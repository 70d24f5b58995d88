"""The FMI 2.0 co-simulation FMUs (inerter.fmu.build, fmu_src/), checked through fmpy.

One FMU per scene in scenarios/, built once per session. What is checked: the model description
(fmpy's validator, names, units, descriptions), the binaries (the status shim in front of
pythonfmu's), a run in a fresh process against the solver, two scenes in one process, a second
importer, bit-identical rollback through FMU state (in memory and serialized), and that every
error gives the status FMI 2.0 asks for with a logged message, never fmi2Fatal:

- an invalid setting: exitInitializationMode fmi2Error;
- a non-finite input, a fixed parameter set after initialisation: setReal fmi2Error, the state
  unchanged;
- a step the solver cannot complete: doStep fmi2Discard, the last good state kept.

Those statuses come from the status shim (fmu_src/status_shim.c), the FMU's Linux binary; an FMU
built without it reports errors through the next doStep's fmi2Discard, which is checked too.
"""
from __future__ import annotations

import contextlib
import ctypes
import hashlib
import importlib.util
import io
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
pythonfmu = pytest.importorskip("pythonfmu")

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi1 import FMICallException  # noqa: E402
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE,  # noqa: E402
                       fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
from fmpy.validation import validate_fmu  # noqa: E402

import inerter  # noqa: E402
from inerter.common.errors import InerterError  # noqa: E402
from inerter.fmu import build as fmu_build  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "scenarios").glob("*.toml"))
SCENE_PARAMS = [pytest.param(p, id=p.stem) for p in SCENES] or [
    pytest.param(None, id="no-scenes", marks=pytest.mark.skip(reason="no scene in scenarios/"))]

FMI_DISCARD = 2
FMI_ERROR = 3
FMI_FATAL = 4
#: Length of the runs compared with the solver (s): short, the comparison needs no more.
RUN_TIME = 0.5
RTOL = 1e-10

#: A scene with an input force (`function = "input"` at C) and the input used from it.
INPUT_SCENE = ROOT / "scenarios" / "two_bar_2d.toml"
INPUT = "C.f[2]"

#: Every function of FMI 2.0's co-simulation API.
FMI2_COSIMULATION_FUNCTIONS = [
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger",
    "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
    "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives", "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus",
    "fmi2GetRealStatus", "fmi2GetIntegerStatus", "fmi2GetBooleanStatus", "fmi2GetStringStatus"]


# ----------------------------------------------------------------------------------------------
# Fixtures and helpers
# ----------------------------------------------------------------------------------------------
class _Built(dict):
    """scene path -> its FMU, each built once when first asked for (a scene that cannot be built
    fails its own tests only)."""

    def __init__(self, out: Path):
        super().__init__()
        self.out = out

    def __missing__(self, scene: Path) -> Path:
        self[scene] = fmu_build.build(scene, self.out, force=True)
        return self[scene]


@pytest.fixture(scope="session")
def fmus(tmp_path_factory):
    """scene path -> its FMU, built once (into a temporary folder, not build/)."""
    return _Built(tmp_path_factory.mktemp("fmu"))


@pytest.fixture(scope="session")
def input_fmu(fmus):
    """(scene path, FMU) of INPUT_SCENE."""
    if INPUT_SCENE not in SCENES:
        pytest.skip(f"no {INPUT_SCENE.name} in scenarios/")
    return INPUT_SCENE, fmus[INPUT_SCENE]


def shim_expected() -> bool:
    """Whether this machine builds FMUs with the status shim."""
    return fmu_build._shim_compiler()[0] is not None


@pytest.fixture
def needs_shim():
    if not shim_expected():
        pytest.skip("no status shim here (gcc missing, or not Linux x86-64)")


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

    def __init__(self, unzipdir: str, name: str = "instance", messages=None, logging: bool = True):
        self.md = read_model_description(unzipdir)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.outputs = [v.name for v in self.md.modelVariables if v.causality == "output"]
        self.messages: list[tuple[int, str]] = [] if messages is None else messages
        # The callbacks must live as long as the instance.
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=unzipdir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=logging)

    def _log(self, env, instance, status, category, message):
        self.messages.append((status, message.decode("utf-8")))

    def initialise(self, reals=None, strings=None, start_time=0.0, tolerance=None, booleans=None):
        self.fmu.setupExperiment(tolerance=tolerance, startTime=start_time)
        self.fmu.enterInitializationMode()
        for name, value in (reals or {}).items():
            self.fmu.setReal([self.vr[name]], [value])
        for name, value in (strings or {}).items():
            if self.variables[name].type == "Enumeration":    # by item name, or an integer
                self.fmu.setInteger([self.vr[name]], [self.item(name, value)])
            else:
                self.fmu.setString([self.vr[name]], [value])
        for name, value in (booleans or {}).items():
            self.fmu.setBoolean([self.vr[name]], [value])
        self.fmu.exitInitializationMode()

    def item(self, name: str, value) -> int:
        """The value of Enumeration `name`'s item named `value` (an integer is taken as it is)."""
        if isinstance(value, int):
            return value
        items = self.variables[name].declaredType.items
        return next(int(i.value) for i in items if i.name == value)

    def get(self, names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def set(self, name, value):
        self.fmu.setReal([self.vr[name]], [value])

    def logged(self) -> str:
        return "\n".join(m for _, m in self.messages)

    def errors(self) -> list[str]:
        return [m for s, m in self.messages if s == FMI_ERROR]

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

    def make(fmu: Path, name: str = "instance", logging: bool = True) -> Instance:
        made.append(Instance(unzipped(fmu), name, logging=logging))
        return made[-1]
    yield make
    for inst in reversed(made):
        inst.close()
    for inst in made:     # nothing is fatal
        assert not [m for s, m in inst.messages if s >= FMI_FATAL], inst.logged()


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


def first_parameter(inst: Instance, variability=None) -> str:
    return next(v.name for v in inst.md.modelVariables
                if v.causality == "parameter" and v.type == "Real" and v.name not in ("rtol", "atol")
                and variability in (None, v.variability))


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
        assert (v.causality, v.type) == ("parameter", "Real") and v.variability in ("fixed", "tunable")
        assert v.unit == p["unit"] and float(v.start) == p["value"]
    tunable = set(model.tunable_parameters())
    for e in model.effect_info():
        v = vars_[e["name"]]
        expected = "tunable" if e["name"] in tunable else "fixed"     # the centripetal switch is tunable
        assert (v.causality, v.variability, v.type) == ("parameter", expected, "Boolean")
        assert v.start == ("true" if e["value"] else "false")
    solver = vars_["solver"]
    assert solver.type == "Enumeration" and solver.variability == "fixed"
    assert [i.name for i in solver.declaredType.items][int(solver.start) - 1] == model.experiment["method"]
    assert float(vars_["rtol"].start) == model.experiment["rtol"]
    assert float(vars_["atol"].start) == model.experiment["atol"]
    assert (vars_["compiled"].type, vars_["compiled"].variability, vars_["compiled"].start) == \
        ("Boolean", "fixed", "true")
    for i in model.input_info():
        v = vars_[i["name"]]
        assert (v.causality, v.type, v.unit, float(v.start)) == ("input", "Real", i["unit"], 0.0)
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    assert [v.name for v in outputs] == [o["name"] for o in model.output_info()]
    assert [v.unit for v in outputs] == [o["unit"] for o in model.output_info()]
    assert all(v.initial == "calculated" and v.start is None for v in outputs)
    status = vars_[fmu_build.STATUS_VARIABLE]     # read by the status shim
    assert (status.type, status.causality, status.variability) == ("Integer", "local", "discrete")
    assert status.valueReference == max(v.valueReference for v in md.modelVariables)
    defined = {u.name: u.baseUnit for u in md.unitDefinitions}
    if "N" in defined:
        assert defined["N"].kg == 1 and defined["N"].m == 1 and defined["N"].s == -2
    assert {v.unit for v in md.modelVariables if v.unit} <= set(defined)


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_fmu_ships_the_solver_and_the_scene(fmus, scene):
    name = inerter.load(scene).name
    with zipfile.ZipFile(fmus[scene]) as z:
        files = set(z.namelist())
        module = z.read("resources/slavemodule.txt").decode().strip()
        built = (fmus[scene].parent / f"{name}{fmu_build.HASH_SUFFIX}").read_text().strip()
        assert module == fmu_build.module_name(name, built) and module.startswith(f"inerter_fmu_{name}_")
        assert z.read(f"resources/{scene.name}") == scene.read_bytes()
        requirements = [line for line in z.read("resources/requirements.txt").decode().splitlines()
                        if line and not line.startswith("#")]
    assert [r.split(">=")[0] for r in requirements] == ["numpy", "scipy", "numba"]
    assert {f"resources/{module}.py", "resources/inerter_slave.py",
            f"resources/{fmu_build.PAYLOAD_FILE}", f"binaries/linux64/{name}.so"} <= files
    # The modules the slave can import, in one archive (tests/test_fmu_payload.py checks which).
    with zipfile.ZipFile(fmus[scene]) as z:
        archive = zipfile.ZipFile(io.BytesIO(z.read(f"resources/{fmu_build.PAYLOAD_FILE}")))
    shipped = {f[len("inerter/"):] for f in archive.namelist() if f.startswith("inerter/")}
    package = {p.relative_to(ROOT / "inerter").as_posix()
               for p in fmu_build._shipped_package_files()}
    assert package == shipped
    assert not any("__pycache__" in f or f.endswith(".pyc") for f in files)


def pythonfmus_stripped_binary(tmp_path) -> bytes:
    """pythonfmu's Linux binary as `strip --strip-all` leaves it (its symbol table dropped, its
    code and dynamic symbols kept), or as it is where strip is missing."""
    original = (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64"
                / "libpythonfmu-export.so").read_bytes()
    if not shutil.which("strip"):
        return original
    copy = tmp_path / "libpythonfmu-export.so"
    copy.write_bytes(original)
    subprocess.run(["strip", "--strip-all", str(copy)], check=True)
    assert len(copy.read_bytes()) < len(original)
    return copy.read_bytes()


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_linux_binary_is_the_status_shim_in_front_of_the_python_bridge(fmus, scene, tmp_path):
    name = inerter.load(scene).name
    pythonfmu_binaries = Path(pythonfmu.__file__).parent / "resources" / "binaries"
    with zipfile.ZipFile(fmus[scene]) as z:
        binaries = {f for f in z.namelist() if f.startswith("binaries/")}
        linux = z.read(f"binaries/linux64/{name}.so")
        # The win64 binary is pythonfmu's own: there, errors come from the next doStep.
        assert (z.read(f"binaries/win64/{name}.dll")
                == (pythonfmu_binaries / "win64" / "pythonfmu-export.dll").read_bytes())
        original = (pythonfmu_binaries / "linux64" / "libpythonfmu-export.so").read_bytes()
        if not shim_expected():
            assert linux == original
            return
        assert linux != original and linux.startswith(b"\x7fELF")
        if fmu_build._python_include() is None:       # no Python.h: pythonfmu's binary behind it
            assert binaries == {f"binaries/linux64/{name}.so",
                                f"binaries/linux64/{name}{fmu_build.ORIGINAL_SUFFIX}",
                                f"binaries/win64/{name}.dll"}
            assert (z.read(f"binaries/linux64/{name}{fmu_build.ORIGINAL_SUFFIX}")
                    == pythonfmus_stripped_binary(tmp_path))
            return
        assert binaries == {f"binaries/linux64/{name}.so",
                            f"binaries/linux64/{name}{fmu_build.BRIDGE_SUFFIX}",
                            f"binaries/win64/{name}.dll"}
        bridge = z.read(f"binaries/linux64/{name}{fmu_build.BRIDGE_SUFFIX}")
        assert bridge.startswith(b"\x7fELF") and bridge not in (linux, original)
        # the model module and class it imports are compiled in (fmu_src/python_bridge.c)
        assert z.read("resources/slavemodule.txt").decode().strip().encode() in bridge


def test_the_python_bridge_imports_the_model_module_once(input_fmu, instance, needs_shim):
    """The bridge takes the model class from the module it imports (once per process), where
    pythonfmu's binary executed the module's code again for every instance: the template's branch
    for that second execution (it keeps a reference to the module's namespace) never runs."""
    if fmu_build._python_include() is None:
        pytest.skip("no Python.h here: pythonfmu's binary is behind the shim")
    with zipfile.ZipFile(input_fmu[1]) as z:
        module = z.read("resources/slavemodule.txt").decode().strip()
    first = instance(input_fmu[1], "first")
    loaded = sys.modules[module]
    second = instance(input_fmu[1], "second")
    for inst in (first, second):
        inst.initialise()
        inst.fmu.doStep(0.0, 0.01)
    assert sys.modules[module] is loaded and loaded._namespace_references == []
    assert first.get(first.outputs) == second.get(second.outputs)


def test_instances_of_one_fmu_read_and_set_their_own_variables(input_fmu, instance):
    """The slave's variables are made once per slave class and copied, with each instance's getters
    and setters, for every instance (``_variables`` in fmu_src/inerter_slave.py): three instances in
    one process, one given b = 20 (the scene's is 10) and rtol 1e-9, read their own values (the
    other two the scene's, from the scene file), and their outputs after 0.5 s are their own runs':
    the two with the scene's values agree bit for bit, the one with b = 20 differs from them."""
    scene, fmu = input_fmu
    defaults = {p["name"]: p["value"] for p in inerter.load(scene).parameter_info()}
    changed, first, second = (instance(fmu, name) for name in ("changed", "first", "second"))
    changed.initialise(reals={"b": 20.0, "rtol": 1e-9})
    for inst in (first, second):
        inst.initialise()
    assert changed.get(["b", "rtol"]) == [20.0, 1e-9]
    scene_rtol = inerter.load(scene).experiment["rtol"]
    for inst in (first, second):
        assert inst.get(["b", "rtol"]) == [defaults["b"], scene_rtol]
    for k in range(50):
        for inst in (changed, first, second):
            inst.fmu.doStep(k * 0.01, 0.01)
    assert first.get(first.outputs) == second.get(second.outputs)
    assert changed.get(changed.outputs) != first.get(first.outputs)


BROKEN_MODULE_PROBE = r"""
import sys, fmpy
from fmpy import read_model_description
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE,
                       fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE)
folder = sys.argv[1]
md = read_model_description(folder)
messages = []
callbacks = fmi2CallbackFunctions()
callbacks.logger = fmi2CallbackLoggerTYPE(lambda e, i, status, c, m: messages.append((status, m.decode())))
callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
fmu = FMU2Slave(guid=md.guid, unzipDirectory=folder, modelIdentifier=md.coSimulation.modelIdentifier,
                instanceName="broken")
try:
    fmu.instantiate(callbacks=callbacks, loggingOn=False)
    print("instantiated")
except Exception as exc:
    print("refused:", exc)
for status, message in messages:
    print(status, message)
"""


def test_a_model_module_that_raises_is_a_logged_refusal_to_instantiate(input_fmu, unzipped, tmp_path,
                                                                        needs_shim):
    """The bridge turns a Python exception into fmi2Fatal with its repr logged (pythonfmu's contract):
    a model module that raises at import makes fmi2Instantiate return NULL, with the exception said
    although the importer turned logging off, and the importer's process goes on. In a new process:
    this one has the module imported already."""
    if fmu_build._python_include() is None:
        pytest.skip("no Python.h here: pythonfmu's binary is behind the shim")
    folder = tmp_path / "unzipped"
    shutil.copytree(unzipped(input_fmu[1]), folder)
    module = (folder / "resources" / "slavemodule.txt").read_text().strip()
    source = folder / "resources" / f"{module}.py"
    source.write_text('raise RuntimeError("broken on purpose")\n' + source.read_text())
    proc = subprocess.run([sys.executable, "-c", BROKEN_MODULE_PROBE, str(folder)], capture_output=True,
                          text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("refused:"), proc.stdout
    fatal = [line for line in lines[1:] if line.startswith(f"{FMI_FATAL} ")]
    assert fatal and fatal[0].startswith(f"{FMI_FATAL} {input_fmu[0].name}: "), proc.stdout
    assert f"import {module}" in fatal[0] and "broken on purpose" in fatal[0], proc.stdout


def test_the_status_shim_exports_the_cosimulation_api(input_fmu, unzipped, needs_shim):
    scene, fmu = input_fmu
    folder = Path(unzipped(fmu)) / "binaries" / "linux64"
    shim = ctypes.CDLL(str(folder / f"{inerter.load(scene).name}.so"))
    assert [f for f in FMI2_COSIMULATION_FUNCTIONS if not hasattr(shim, f)] == []
    proc = subprocess.run(["nm", "-D", "--defined-only", str(folder / f"{fmu.stem}.so")],
                          capture_output=True, text=True)
    if proc.returncode == 0:      # and nothing else (binutils may be missing)
        exported = {line.split()[-1] for line in proc.stdout.splitlines() if line.strip()}
        assert exported - {"_init", "_fini"} == set(FMI2_COSIMULATION_FUNCTIONS)


def test_without_the_binary_behind_it_the_shim_fails_to_instantiate_with_a_message(
        input_fmu, unzipped, tmp_path, needs_shim):
    fmu = input_fmu[1]
    folder = tmp_path / "unzipped"
    shutil.copytree(unzipped(fmu), folder)
    behind = fmu_build.BRIDGE_SUFFIX if fmu_build._python_include() else fmu_build.ORIGINAL_SUFFIX
    (folder / "binaries" / "linux64" / f"{fmu.stem}{behind}").unlink()
    messages = []
    with pytest.raises(Exception, match="Failed to instantiate"):
        Instance(str(folder), messages=messages)
    assert messages and messages[0][0] == FMI_ERROR
    assert "cannot load the binary behind the status shim" in messages[0][1]
    assert f"{fmu.stem}{behind}" in messages[0][1]


def test_a_current_fmu_is_not_rebuilt(tmp_path, capsys, monkeypatch):
    if INPUT_SCENE not in SCENES:
        pytest.skip(f"no {INPUT_SCENE.name} in scenarios/")
    scene = tmp_path / INPUT_SCENE.name
    scene.write_bytes(INPUT_SCENE.read_bytes())
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
    with open(src / fmu_build.SHIM_FILE, "a") as f:                   # the shim changed
        f.write("\n/* changed */\n")
    stamp = fmu.stat().st_mtime_ns
    assert fmu_build.build(scene, out) == fmu and fmu.stat().st_mtime_ns != stamp


def test_a_bad_scene_is_reported_by_the_build(tmp_path, capsys):
    text = INPUT_SCENE.read_text()
    assert "M1 = { value = 1.0," in text
    scene = tmp_path / "bad.toml"
    scene.write_text(text.replace("M1 = { value = 1.0,", "M1 = { value = -2.0,"))
    assert fmu_build.main([str(scene), "-o", str(tmp_path / "fmu")]) == 1
    err = capsys.readouterr().err
    assert "bad.toml" in err and "-2" in err
    assert not (tmp_path / "fmu" / "two_bar_2d.fmu").exists()


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
def test_the_fmu_runs_in_a_fresh_process_like_the_solver(fmus, fresh_run, scene):
    run = fresh_run(scene)
    # Its own copy: the package archive in its resources/, unpacked into a folder named by the
    # archive's hash (fmu_src/inerter_slave.py, unpack_payload).
    with zipfile.ZipFile(fmus[scene]) as z:
        digest = hashlib.sha256(z.read(f"resources/{fmu_build.PAYLOAD_FILE}")).hexdigest()[:16]
    assert digest in Path(run["inerter"]).parts, f"the FMU did not use its own inerter copy: {run['inerter']}"
    assert_matches_solver(scene, run["results"][0])


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_on_the_compiled_path_the_fmu_gives_the_whole_runs_outputs_bit_for_bit(fresh_run, scene):
    """Inputs held: the FMU on the compiled path keeps one integration running across the
    communication points, clipped to the stop time fmpy gives to fmi2SetupExperiment, so every
    output at every communication point equals `Model.simulate(path="compiled")` exactly."""
    model = inerter.load(scene, **{"experiment.rtol": RTOL})
    if model.stepper(path="compiled").path != "compiled":
        pytest.skip("the compiled stepper does not take this scene (or numba is missing)")
    result = fresh_run(scene)["results"][0]
    ref = model.simulate(stop_time=RUN_TIME, output_interval=model.experiment["output_interval"],
                         metrics=False, path="compiled")
    assert ref.run.extra["path"] == "compiled"
    assert np.array_equal(result["time"], ref.time)
    different = [name for name in model.signals.names if not np.array_equal(result[name], ref[name])]
    assert not different, different


def test_two_scenes_run_side_by_side_in_one_process(fmus, tmp_path):
    pair = [s for s in SCENES if s.stem in ("lumped_mass_2d", "two_bar_2d")]
    if len(pair) < 2:
        pytest.skip("needs the scenes lumped_mass_2d and two_bar_2d")
    a, b = pair
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
                  "values": observer.last_real_values(index, [vr[n] for n in job["outputs"]])}), flush=True)
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
    # The bound, 1e-9 (in each output's unit), relative or absolute. The importers pass the
    # communication times differently (libcosimpy in integer nanoseconds), so the FMU's adaptive
    # integrator restarts at times that differ in the last bits; on a scene solved at rtol 1e-8
    # (braced_frame_3d) that leaves differences of a few 1e-12 m on millimetre-sized outputs.
    for name, value in zip(job["outputs"], cosim["values"]):
        assert value == pytest.approx(reference[name][-1], rel=1e-9, abs=1e-9), name


# ----------------------------------------------------------------------------------------------
# The exit of a process that ran an FMU
# ----------------------------------------------------------------------------------------------
# pythonfmu 0.7.0's binary releases its Python state a second time when it is still loaded at the
# process's exit, which the first pythonfmu binary of a process always is: a write to freed heap
# memory that glibc sometimes reported as "corrupted double-linked list" after complete results.
# The status shim has the state released before exit (fmu_src/status_shim.c). These tests run the
# importers under tests/native/freed_guard.c, which finds such a write deterministically.
NATIVE = ROOT / "tests" / "native"


def _compile(tmp: Path, source: str, shared: bool) -> Path:
    gcc = shutil.which("gcc")
    if gcc is None or sys.platform != "linux":
        pytest.skip("needs gcc on Linux")
    out = tmp / Path(source).stem
    library = ["-shared", "-fPIC"] if shared else []
    subprocess.run([gcc, *library, "-O2", "-I", str(ROOT / "fmu_src"), "-o", str(out),
                    str(NATIVE / source), "-ldl"], check=True)
    return out


@pytest.fixture(scope="session")
def freed_guard(tmp_path_factory):
    return _compile(tmp_path_factory.mktemp("guard"), "freed_guard.c", shared=True)


def run_guarded(script: list[str], preload: list[Path], tmp_path, env=None) -> subprocess.CompletedProcess:
    """`script` run from tmp_path with `preload` (the guard last): exit status 0 and the guard's
    report that no deleted object was written, whatever else it printed."""
    env = dict(env or {}, PATH=os.environ.get("PATH", ""),
               LD_PRELOAD=" ".join(str(p) for p in preload))
    proc = subprocess.run(script, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0 and "none written after" in proc.stderr, (
        f"exit status {proc.returncode}: {proc.stderr[-3000:]}")
    return proc


def test_fmpy_processes_exit_without_writing_freed_memory(input_fmu, freed_guard, needs_shim,
                                                          tmp_path):
    scene, fmu = input_fmu
    script = ("import fmpy, sys\n"
              "for _ in range(2):\n"
              "    fmpy.simulate_fmu(sys.argv[1], stop_time=0.05, output_interval=0.01)\n")
    run_guarded([sys.executable, "-I", "-c", script, str(fmu)], [freed_guard], tmp_path)


def test_libcosimpy_processes_exit_without_writing_freed_memory(input_fmu, freed_guard,
                                                                needs_shim, tmp_path):
    """Three executions one after the other, then the interpreter's own exit."""
    if importlib.util.find_spec("libcosimpy") is None:
        pytest.skip("libcosimpy is not installed")
    scene, fmu = input_fmu
    script = ("import sys\n"
              "from libcosimpy.CosimExecution import CosimExecution\n"
              "from libcosimpy.CosimObserver import CosimObserver\n"
              "from libcosimpy.CosimSlave import CosimLocalSlave\n"
              "for _ in range(3):\n"
              "    execution = CosimExecution.from_step_size(step_size=10_000_000)\n"
              "    execution.add_local_slave(CosimLocalSlave(fmu_path=sys.argv[1], instance_name='fmu'))\n"
              "    observer = CosimObserver.create_last_value()\n"
              "    execution.add_observer(observer)\n"
              "    assert execution.simulate_until(target_time=50_000_000)\n")
    run_guarded([sys.executable, "-I", "-c", script, str(fmu)], [freed_guard], tmp_path)


def test_a_c_importer_loads_the_fmu_three_times_and_exits_cleanly(input_fmu, unzipped, freed_guard,
                                                                   needs_shim, tmp_path):
    """tests/native/c_importer.c, a host without Python of its own (libpython preloaded): there
    pythonfmu's binary starts the interpreter, which stays running across the three loads of the
    binary until the process exits (the first two loads are unloaded, the last one stays loaded
    until exit). Every load gives the solver's result."""
    import site
    import sysconfig
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        pytest.skip("this Python has no shared libpython to preload")
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("INSTSONAME")
    importer = _compile(tmp_path, "c_importer.c", shared=False)
    scene, fmu = input_fmu
    description = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    steps, h = 20, 0.01
    proc = run_guarded([str(importer), unzipped(fmu), description.coSimulation.modelIdentifier,
                        description.guid, "3", str(steps), str(h), str(vr["C.r[2]"])],
                       [libpython, freed_guard], tmp_path,
                       env={"PYTHONPATH": os.pathsep.join(site.getsitepackages())})
    values = [float(line.split(":")[1]) for line in proc.stdout.splitlines() if line.startswith("load")]
    assert len(values) == 3 and values[0] == values[1] == values[2]
    # The scene's own tolerance (fmi2SetupExperiment gives none): the solver's stepper at the same
    # communication points, on the FMU's default path (compiled: the same environment, so where
    # numba is missing both fall back to the numpy path), gives the same value bit for bit.
    stepper = inerter.load(scene).stepper(path="compiled")
    for k in range(1, steps + 1):
        stepper.step(k * h)
    assert values[0] == stepper.outputs()["C.r[2]"]


def test_an_input_is_held_over_each_step(input_fmu, fresh_run, tmp_path):
    scene, fmu = input_fmu
    t = np.arange(0.0, RUN_TIME + 1e-9, inerter.load(scene).experiment["output_interval"])
    force = 20.0 * np.sin(2 * np.pi * 2.0 * t)
    run = run_fresh(tmp_path, [job_for(scene, fmu, input={"time": t.tolist(),
                                                          "values": {INPUT: force.tolist()}})])
    result = run["results"][0]
    # The solver's own stepper with the same held inputs and the stop time fmpy gives the FMU, on
    # the FMU's default path (compiled where numba is installed, numpy otherwise), gives exactly
    # the same outputs.
    model = inerter.load(scene, **{"experiment.rtol": RTOL})
    stepper = model.stepper(path="compiled", stop_time=RUN_TIME)
    assert result["C.r[2]"][0] == stepper.outputs()["C.r[2]"]
    for i in range(1, len(result["time"])):
        stepper.set_input(INPUT, force[i - 1])
        stepper.step(result["time"][i])
        assert result["C.r[2]"][i] == stepper.outputs()["C.r[2]"]
    unpushed = fresh_run(scene)["results"][0]["C.r[2]"]
    assert np.max(np.abs(np.array(result["C.r[2]"]) - unpushed)) > 1e-4   # the input did push


# ----------------------------------------------------------------------------------------------
# FMU state
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_a_rolled_back_step_repeats_bit_for_bit(fmus, scene, instance):
    inst = instance(fmus[scene], "a")
    name = "b" if "b" in inst.vr else first_parameter(inst)
    changed = {name: 1.5 * float(inst.variables[name].start)}   # no getter before initialisation
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


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_the_compiled_and_the_numpy_path_of_the_fmu_agree_with_the_oracle(fmus, scene, instance):
    """The parameter `compiled` picks the path (the log says which ran; the compiled one where numba
    is installed and the scene allows it): plumbing of the FMU, for which the numpy path, still
    offered there, is the reference: both take the same integrator steps, so the outputs agree to
    round-off carried over the steps, 1e-9, relative or absolute, in the units of the motion. The
    physics of both: the oracle's stepper (element forces derived from L(q), the numpy stepper's
    steps) over the same 20 communication steps, to the same 1e-9 (measured: 2e-10 at most,
    lumped_mass_2d), where the oracle takes the scene (not with an inerter device's internal states
    or screw efficiency, series_inerter_2d: their closed forms are in test_device_states.py and
    test_device_efficiency.py). An element's force is compared as force /
    coefficient (f/k an elongation in m, f/c a rate in m/s, f/b an acceleration in m/s², τ/k in
    rad): round-off in a length carries over to a spring's force multiplied by k, so a stiff
    spring's force can differ by more than 1e-9 N although the lengths agree to 1e-14 m
    (braced_frame_3d's columns: k = 2e6 N/m, 2e-8 N). Its power and energy likewise, as power /
    coefficient and energy / coefficient (½Δ² in m² for a spring): lumped_mass_2d's spring
    (k = 1e4 N/m, Δ = 0.22 m) held 245 J, and on an AMD EPYC host the two paths' energies were
    2.8e-7 J apart, 1.2e-9 relative (measured 2026-11-28; an elongation 1.3e-10 m different)."""
    model = inerter.load(scene)
    expected = model.stepper(path="compiled").path
    scale = {f"{e.name}.{quantity}": e.coefficient
             for e in model.mechanism.elements if e.coefficient > 0
             for quantity in ("tau" if e.kind.startswith("rotational") else "f", "power", "energy")}
    outputs = {}
    for flag in (True, False):
        inst = instance(fmus[scene], f"compiled-{flag}")
        inst.initialise(booleans={"compiled": flag})
        assert f"{expected if flag else 'numpy'} path" in inst.logged()
        h, t = float(inst.md.defaultExperiment.stepSize), 0.0
        for _ in range(20):
            inst.fmu.doStep(t, h)
            t += h
        values = inst.get(inst.outputs)
        outputs[flag] = [value / scale.get(name, 1.0) for name, value in zip(inst.outputs, values)]
    assert outputs[True] == pytest.approx(outputs[False], rel=1e-9, abs=1e-9)
    try:
        oracle = model.oracle().stepper()
    except InerterError as exc:
        assert "internal states" in str(exc) or "efficiency" in str(exc), exc
        return
    for k in range(1, 21):
        oracle.step(k * h)
    got = oracle.outputs()
    reference = [got[name] / scale.get(name, 1.0) for name in inst.outputs]
    for flag in (True, False):
        assert outputs[flag] == pytest.approx(reference, rel=1e-9, abs=1e-9), flag


# ----------------------------------------------------------------------------------------------
# Errors: the status FMI 2.0 asks for, a message, never fmi2Fatal, and the importer goes on
# ----------------------------------------------------------------------------------------------
def raises_status(status: int, call, *args):
    """`call(*args)` fails with `status` (fmpy raises FMICallException for any status > warning)."""
    with pytest.raises(FMICallException) as caught:
        call(*args)
    assert caught.value.status == status, caught.value
    return caught.value


@pytest.mark.parametrize("scene", SCENE_PARAMS)
@pytest.mark.parametrize("setting, value, field", [
    ("rtol", 5.0, "experiment.rtol"), ("solver", 99, "solver: no such item"),
    # b: the first element whose coefficient it makes negative, e.g. "inerter.b: out of range" (a
    # scene whose other coefficients are expressions of b, tid_storey_2d's kt, may fail there first)
    ("b", -1.0, ": out of range"), ("M1", 0.0, "bodies.bar1.mass"),
    ("first parameter", math.nan, "not finite")])
def test_an_invalid_setting_fails_initialisation_with_fmi2error(fmus, scene, instance, needs_shim,
                                                               setting, value, field):
    inst = instance(fmus[scene])
    if setting == "first parameter":
        setting = first_parameter(inst)
    if setting not in inst.vr:
        pytest.skip(f"the scene has no {setting}")
    enumeration = inst.variables[setting].type == "Enumeration"
    strings, reals = ({setting: value}, {}) if enumeration else ({}, {setting: value})
    raises_status(FMI_ERROR, inst.initialise, reals, strings)
    # The message names the scene's field and the FMU variable with the value set.
    errors = inst.errors()
    assert len(errors) == 1 and field in errors[0] and f"{setting} = {value!r}" in errors[0]
    if setting in ("b", "M1"):                  # a scene parameter: the value is named as the FMU's
        assert f"FMU parameter {setting} = {value!r}: " in errors[0], errors[0]
    assert all(math.isnan(v) for v in inst.get(inst.outputs))
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.doStep, 0.0, 0.01)    # every step is refused until reset
    assert field in inst.logged()
    # FMI 2.0 lets the importer reset the instance, and initialise it with valid values.
    inst.fmu.reset()
    inst.initialise()
    inst.fmu.doStep(0.0, 0.01)


@pytest.mark.parametrize("switched_off", ["at instantiation", "by setDebugLogging"])
def test_with_logging_off_an_error_is_still_logged(input_fmu, instance, needs_shim, switched_off):
    """With the importer's logging off (fmpy's default), an fmi2Error or fmi2Discard still comes
    with its message (the status shim passes on those statuses' messages always), and only those:
    the fmi2OK messages of initialisation and of a good step are not logged."""
    inst = instance(input_fmu[1], logging=switched_off != "at instantiation")
    if switched_off == "by setDebugLogging":
        inst.fmu.setDebugLogging(False, [])
        inst.messages.clear()                 # what instantiation logged with logging on
    raises_status(FMI_ERROR, inst.initialise, {"b": -1.0})
    [(status, message)] = inst.messages
    assert status == FMI_ERROR and "inerter.b: out of range" in message and "b = -1.0" in message
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.doStep, 0.0, 0.01)
    assert inst.messages and all(s >= FMI_DISCARD for s, _ in inst.messages), inst.messages
    inst.messages.clear()
    inst.fmu.reset()
    inst.initialise()
    inst.fmu.doStep(0.0, 0.01)
    raises_status(FMI_ERROR, inst.set, INPUT, math.nan)    # a non-finite input: setReal's fmi2Error
    assert inst.errors() and "not finite" in inst.errors()[0] and all(s == FMI_ERROR for s, _ in inst.messages)


def test_an_error_names_the_scene_file_not_the_importers_unzip_folder(input_fmu, instance, unzipped,
                                                                       needs_shim):
    """The scene file is named as the user knows it (its name in the FMU's resources/, as in the
    scene's folder), never by the temporary folder the importer unzipped the FMU into."""
    scene, fmu = input_fmu
    inst = instance(fmu)
    raises_status(FMI_ERROR, inst.initialise, {"b": -1.0})
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.doStep, 0.0, 0.01)     # the failure, repeated by the step
    folder = str(Path(unzipped(fmu)).resolve())
    for message in inst.errors() + [m for s, m in inst.messages if s == FMI_DISCARD]:
        assert f"FMU parameter b = -1.0: {scene.name}: elements." in message, message
        assert folder not in message and "resources" not in message, message


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_a_start_time_other_than_zero_is_refused(fmus, scene, instance, needs_shim):
    inst = instance(fmus[scene])
    raises_status(FMI_ERROR, inst.initialise, None, None, 1.0)
    assert "startTime" in inst.logged()
    raises_status(FMI_ERROR, inst.fmu.doStep, 1.0, 0.01)


@pytest.mark.parametrize("stop_time", [-1.0, math.nan])
def test_a_stop_time_before_the_start_is_refused(input_fmu, instance, needs_shim, stop_time):
    """fmi2SetupExperiment's stopTime before startTime = 0 (or NaN): exitInitializationMode
    fmi2Error, logged with the scene file, stopTime, the value and what was expected (a run of no
    length, stopTime = 0, stays allowed: the outputs at t = 0)."""
    inst = instance(input_fmu[1], logging=False)
    inst.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)
    inst.fmu.enterInitializationMode()
    raises_status(FMI_ERROR, inst.fmu.exitInitializationMode)
    [message] = inst.errors()
    assert f"two_bar_2d.toml: stopTime: before the start (got stopTime = {stop_time!r} s" in message, message
    assert "expected a stop time ≥ startTime = 0 s" in message
    raises_status(FMI_ERROR, inst.fmu.doStep, 0.0, 0.01)
    inst.fmu.reset()
    inst.fmu.setupExperiment(startTime=0.0, stopTime=0.0)
    inst.fmu.enterInitializationMode()
    inst.fmu.exitInitializationMode()


def stepped_pair(fmu: Path, instance) -> tuple[Instance, Instance, float]:
    """Two instances of `fmu` initialised the same way, one step of h done with INPUT at 5 N."""
    h = 0.01
    pair = instance(fmu, "seen"), instance(fmu, "clean")
    for inst in pair:
        inst.initialise()
        inst.set(INPUT, 5.0)
        inst.fmu.doStep(0.0, h)
    return pair[0], pair[1], h


def test_a_non_finite_input_gives_fmi2error_and_leaves_the_state(input_fmu, instance, needs_shim):
    inst, clean, h = stepped_pair(input_fmu[1], instance)
    outputs = inst.get(inst.outputs)
    for bad in (math.nan, math.inf, -math.inf):
        inst.messages.clear()
        raises_status(FMI_ERROR, inst.set, INPUT, bad)
        [message] = inst.errors()
        assert INPUT in message and "not finite" in message and repr(bad) in message
        assert inst.get([INPUT]) == [5.0] and inst.get(inst.outputs) == outputs
    # The next step goes on from the state as it was, like an instance that never saw it.
    inst.fmu.doStep(h, h)
    clean.fmu.doStep(h, h)
    assert inst.get(inst.outputs) == clean.get(clean.outputs) != outputs
    # Among several values, the finite ones are set.
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.setReal, [inst.vr["C.f[1]"], inst.vr[INPUT]], [1.0, math.nan])
    assert inst.get(["C.f[1]", INPUT]) == [1.0, 5.0] and len(inst.errors()) == 1


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_setting_a_fixed_parameter_after_initialisation_gives_fmi2error(fmus, scene, instance,
                                                                       needs_shim):
    inst, clean = instance(fmus[scene], "seen"), instance(fmus[scene], "clean")
    h = 0.01
    for i in (inst, clean):
        i.initialise()
        i.fmu.doStep(0.0, h)
    name = first_parameter(inst, "fixed")
    before = inst.get([name])
    raises_status(FMI_ERROR, inst.set, name, 2.0 * before[0] + 1.0)
    assert inst.get([name]) == before
    assert f"{name}: a fixed parameter cannot be changed" in inst.logged()
    # Setting an output, or the status variable, is refused the same way.
    raises_status(FMI_ERROR, inst.set, inst.outputs[0], 1.0)
    assert "an output cannot be set" in inst.logged()
    raises_status(FMI_ERROR, inst.fmu.setInteger, [inst.vr[fmu_build.STATUS_VARIABLE]], [0])
    # Nothing moved, and the importer goes on.
    for i in (inst, clean):
        i.fmu.doStep(h, h)
    assert inst.get(inst.outputs) == clean.get(clean.outputs)


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
    raises_status(FMI_DISCARD, inst.fmu.doStep, t, h)         # still there: the same step fails


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_tolerance_from_setup_experiment_is_used_unless_rtol_is_set(fmus, scene, instance):
    inst = instance(fmus[scene], "tolerance")
    inst.initialise(tolerance=1e-7)
    assert "rtol 1e-07" in inst.logged()
    other = instance(fmus[scene], "explicit")
    other.initialise(reals={"rtol": 1e-9}, tolerance=1e-7)
    assert "rtol 1e-09" in other.logged()


def test_solver_settings_reach_the_stepper_as_a_load_with_them_reads_them(instance, tmp_path):
    """The FMU's solver, rtol and atol are read as ``inerter.load(..., experiment.NAME=...)`` reads
    them, without a new load: where the scene states no atol, atol follows an rtol the importer sets
    (rtol/100, the scene format's default). Reference: the loaded model's settings."""
    text = INPUT_SCENE.read_text()
    assert "\natol = 1e-12\n" in text and '\nname = "two_bar_2d"\n' in text
    scene = tmp_path / "two_bar_no_atol.toml"       # an FMU of its own name, beside no other
    scene.write_text(text.replace("\natol = 1e-12\n", "\n")
                     .replace('\nname = "two_bar_2d"\n', '\nname = "two_bar_no_atol"\n'))
    fmu = fmu_build.build(scene, tmp_path / "fmu")
    cases = [({"rtol": 1e-6}, {}), ({"rtol": 1e-6, "atol": 1e-11}, {"solver": "RK45"}), ({}, {"solver": "Radau"})]
    for i, (reals, strings) in enumerate(cases):
        inst = instance(fmu, f"settings {i}")
        inst.initialise(reals, strings)
        overrides = {f"experiment.{'method' if k == 'solver' else k}": v for k, v in {**reals, **strings}.items()}
        want = inerter.load(scene, **overrides).settings()
        assert (f"with solver {want.method}, rtol {want.rtol:g}, atol {want.atol:g}," in inst.logged()), \
            (overrides, inst.logged())
    assert want.method == "Radau" and inerter.load(scene, **{"experiment.rtol": 1e-6}).settings().atol == 1e-8


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_misuse_of_value_references_is_an_error_not_fatal(fmus, scene, instance, needs_shim):
    inst = instance(fmus[scene])
    inst.initialise()
    raises_status(FMI_ERROR, inst.fmu.getReal, [10_000])       # logged, nothing more
    assert "valueReference 10000" in inst.logged()
    raises_status(FMI_ERROR, inst.fmu.setReal, [10_000], [1.0])
    raises_status(FMI_ERROR, inst.fmu.setBoolean,              # a Real, set as a Boolean
                  [inst.vr[first_parameter(inst)]], [True])
    inst.fmu.doStep(0.0, 0.01)


def test_a_state_that_cannot_be_restored_gives_fmi2error(input_fmu, instance, needs_shim):
    """Refused where it is deserialized (it was taken there, and refused by setFMUstate only);
    tests/test_fmu_refusals.py has the other kinds of bytes."""
    inst, clean, h = stepped_pair(input_fmu[1], instance)
    outputs = inst.get(inst.outputs)
    raises_status(FMI_ERROR, inst.fmu.deSerializeFMUstate, b'{"format": "something else"}')
    assert "fmi2DeSerializeFMUstate: 28 bytes that are not a serialized state of this FMU: format " \
           "'something else'" in inst.logged()
    assert inst.get(inst.outputs) == outputs
    inst.fmu.doStep(h, h)
    clean.fmu.doStep(h, h)
    assert inst.get(inst.outputs) == clean.get(clean.outputs)


# ----------------------------------------------------------------------------------------------
# Without Python's headers at build time: pythonfmu's binary behind the shim
# ----------------------------------------------------------------------------------------------
def built_as_if(tmp_path_factory, name: str, missing: str, why):
    """An FMU of INPUT_SCENE, named `name`, built with the build's `missing` (a function) answering
    `why` as on a machine without it, and the build's stderr."""
    folder = tmp_path_factory.mktemp(name)
    scene = folder / f"{name}.toml"
    scene.write_text(INPUT_SCENE.read_text().replace('name = "two_bar_2d"', f'name = "{name}"', 1))
    err = io.StringIO()
    with pytest.MonkeyPatch.context() as patch, contextlib.redirect_stderr(err):
        patch.setattr(fmu_build, missing, lambda: why)
        assert fmu_build.main([str(scene), "-o", str(folder / "fmu")]) == 0
    return folder / "fmu" / f"{name}.fmu", err.getvalue()


@pytest.fixture(scope="module")
def unbridged_fmu(tmp_path_factory):
    """An FMU of INPUT_SCENE (under another name) built as if Python.h were missing."""
    return built_as_if(tmp_path_factory, "fmu_test_unbridged", "_python_include", None)


def test_without_pythons_headers_pythonfmus_binary_goes_behind_the_shim(unbridged_fmu, instance,
                                                                         needs_shim, tmp_path):
    fmu, err = unbridged_fmu
    assert "warning: fmu_test_unbridged.fmu: built without the Python bridge" in err
    assert "Python.h was not found" in err
    behind = f"binaries/linux64/fmu_test_unbridged{fmu_build.ORIGINAL_SUFFIX}"
    with zipfile.ZipFile(fmu) as z:
        assert {f for f in z.namelist() if f.startswith("binaries/linux64/")} == {
            "binaries/linux64/fmu_test_unbridged.so", behind}
        assert z.read(behind) == pythonfmus_stripped_binary(tmp_path)
    assert validate_fmu(str(fmu)) == []
    # The shim's statuses hold in front of it: an invalid setting is exitInitializationMode's
    # fmi2Error, with the scene's message; a valid run steps.
    inst = instance(fmu)
    raises_status(FMI_ERROR, inst.initialise, {"M1": 0.0})
    assert "M1 = 0.0" in inst.errors()[-1]
    inst.fmu.reset()
    inst.initialise()
    for k in range(3):
        inst.fmu.doStep(0.01 * k, 0.01)
    assert all(math.isfinite(v) for v in inst.get(inst.outputs))


# ----------------------------------------------------------------------------------------------
# Without the shim (no gcc at build time; the win64 binary): errors come from the next doStep
# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def unshimmed_fmu(tmp_path_factory):
    """An FMU of INPUT_SCENE (under another name) built as if gcc were missing."""
    return built_as_if(tmp_path_factory, "fmu_test_unshimmed", "_shim_compiler",
                       (None, "gcc was not found on PATH"))


def test_without_a_compiler_the_build_warns_and_ships_pythonfmus_binary(unshimmed_fmu,
                                                                        monkeypatch, tmp_path):
    fmu, err = unshimmed_fmu
    assert "warning: fmu_test_unshimmed.fmu: built without the status shim" in err
    assert "gcc was not found" in err
    original = (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64"
                / "libpythonfmu-export.so").read_bytes()
    with zipfile.ZipFile(fmu) as z:
        assert z.read("binaries/linux64/fmu_test_unshimmed.so") == original
        assert not [f for f in z.namelist() if f.endswith(fmu_build.ORIGINAL_SUFFIX)]
    assert validate_fmu(str(fmu)) == []
    # What the command line prints is a FmuBuildWarning of the build.
    monkeypatch.setattr(fmu_build, "_shim_compiler", lambda: (None, "gcc was not found on PATH"))
    with pytest.warns(fmu_build.FmuBuildWarning, match="x.fmu: built without the status shim"):
        assert fmu_build._compile_shim("x", 0, tmp_path, "x.fmu") is None


def test_without_the_shim_a_rejected_value_fails_the_next_step_once(unshimmed_fmu, instance):
    inst = instance(unshimmed_fmu[0])
    inst.initialise()
    h = 0.01
    inst.set(INPUT, 5.0)
    inst.fmu.doStep(0.0, h)
    outputs = inst.get(inst.outputs)
    inst.set(INPUT, math.nan)                                  # fmi2OK: no shim to say otherwise
    assert "not finite" in inst.errors()[0]
    inst.messages.clear()
    raises_status(FMI_DISCARD, inst.fmu.doStep, h, h)
    assert "refused, once" in inst.logged() and "not finite" in inst.logged()
    assert inst.get(inst.outputs) == outputs and inst.get([INPUT]) == [5.0]
    inst.fmu.doStep(h, h)                                      # reported: the importer goes on
    # An invalid setting: exitInitializationMode gives fmi2OK, every doStep fmi2Discard.
    inst.fmu.reset()
    inst.initialise(reals={"M1": 0.0})
    assert "M1 = 0.0" in inst.errors()[-1]
    raises_status(FMI_DISCARD, inst.fmu.doStep, 0.0, h)
    raises_status(FMI_DISCARD, inst.fmu.doStep, 0.0, h)
