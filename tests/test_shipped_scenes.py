"""Every shipped scene, end to end: through ``inerter run`` and through its FMU.

The scenes are found by globbing scenarios/*.toml and scenarios/hard/*.toml, so a new scene is
covered as soon as it is added. Each is run briefly (SHORT seconds, or its own stop time where
that is shorter), at its own solver settings:

- ``inerter run SCENE --stop-time T --out DIR``, the installed console script in a new process:
  exit 0 with the CSV (every output, every sample up to T), summary.json (strict JSON, numeric
  metrics) and the PNG. A scene designed to stop part-way (DESIGNED_TO_STOP) exits 3 with the CSV
  up to where it stopped and a summary saying where and why.
- its FMU, built by :func:`inerter.fmu.build.build` into build/fmu/ (a current FMU is not rebuilt,
  so a second run of this file builds nothing) and simulated by fmpy in a new process: its outputs
  equal the solver's at every communication point (TOLERANCE_FACTOR says how closely and why). A
  scene designed to stop part-way ends with fmi2Discard (or fmi2Error) and a logged reason at the
  last communication point before it stops, never with fmi2Fatal or a crash.

tests/test_fmu.py checks the FMUs themselves (model description, binaries, FMU states, statuses)
on scenarios/*.toml, built into a temporary folder with ``force=True`` because some of its tests
are about building; tests/test_hard_cases.py checks the physics of the hard scenes. Nothing is
written outside pytest's temporary folders and build/fmu/.
"""
from __future__ import annotations

import functools
import json
import math
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

import inerter
from conftest import ROOT, SCENARIOS

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

from inerter.fmu import build as fmu_build  # noqa: E402
from test_fmu import FMI_DISCARD, FMI_ERROR, FMI_FATAL  # noqa: E402

SCENES = sorted(SCENARIOS.glob("*.toml")) + sorted((SCENARIOS / "hard").glob("*.toml"))
FMU_DIR = ROOT / "build" / "fmu"

#: Length of each run (s); a scene whose own stop time is shorter runs to that (stiff_1dof_2d).
SHORT = 0.2


@dataclass(frozen=True)
class Stops:
    """A scene designed to stop part-way, as its own comments describe it."""
    at: float                 # the time the comments give for the stop (s)
    stop_time: float          # a run long enough to get there (s)
    names: tuple[str, ...]    # what the message names: the elements, the reason


#: Scenes designed to stop part-way, read from their comments (not from running them). Every other
#: shipped scene runs to its end at its defaults: gimbal_lock_3d stops only with
#: scene.orientation = euler_zxz, massless_inerter_2d's singular pose is reached only with y0 = 0
#: (a load error), snap_through_2d and two_bar_aligned_2d pass through their delicate poses, and
#: stiff_1dof_2d reports stiffness only with explicit methods and c = 1e8 N.s/m.
DESIGNED_TO_STOP = {
    # "reaches O (if v0 >= w L0) at t* = asin(w L0/v0)/w: for the defaults pi*sqrt(2)/4 = 1.1107 s.
    # There the elements' direction is undefined: the run stops at the meeting, naming the
    # elements and the time (the FMU discards the step with that message)."
    "terminals_meet_2d": Stops(at=math.pi * math.sqrt(2.0) / 4.0, stop_time=1.5,
                               names=("spring", "damper", "inerter", "meet")),
}

#: The FMU's outputs against the solver's, in units of the integrator's tolerance for each output:
#: |FMU − solver| ≤ TOLERANCE_FACTOR · (rtol · max|solver| + atol), max over the run, per output.
#: Both integrate the same equations with the same method, rtol and atol (read from the FMU's log),
#: but not through the same steps: the FMU goes from one communication point to the next (its
#: integrator runs on across them, clipped at the stop time fmpy gives it) on whichever path it
#: takes, `Model.simulate` integrates the whole interval. Each result is within its own global
#: error of the exact solution; the integrator keeps every step's local error below
#: atol + rtol·|y|, and these short runs take at most a few hundred steps, so the global errors,
#: and their difference, stay below a few hundred such units. Outputs are smooth functions of the
#: state, so forces and energies follow with their own magnitude. At rtol 1e-10 the bound is 1e-7
#: of each output's largest value: a real difference (an effect or a parameter lost on the way
#: into the FMU) is orders of magnitude larger.
TOLERANCE_FACTOR = 1000.0

#: The FMU's log line of exitInitializationMode: the solver settings it integrates with.
INITIALISED = re.compile(r"initialised at t = 0 s with solver (\w+), rtol (\S+), atol (\S+), (\w+) path")


def scene_id(path: Path) -> str:
    return path.relative_to(SCENARIOS).with_suffix("").as_posix()


ALL = [pytest.param(p, id=scene_id(p)) for p in SCENES]
COMPLETING = [pytest.param(p, id=scene_id(p)) for p in SCENES if p.stem not in DESIGNED_TO_STOP]
STOPPING = [pytest.param(p, id=scene_id(p)) for p in SCENES if p.stem in DESIGNED_TO_STOP]


@functools.lru_cache(maxsize=None)
def model(scene: Path):
    return inerter.load(scene)


def stop_time(scene: Path) -> float:
    stops = DESIGNED_TO_STOP.get(scene.stem)
    return stops.stop_time if stops else min(SHORT, model(scene).experiment["stop_time"])


def output_names(scene: Path) -> list[str]:
    return [o["name"] for o in model(scene).output_info()]


def cli() -> list[str]:
    """The installed console script, or the module where it is not installed beside this Python."""
    script = Path(sys.executable).with_name("inerter")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "inerter.cli"]


def strict_json(path: Path):
    """JSON as the standard has it: no NaN or Infinity."""
    def refuse(constant):
        raise AssertionError(f"{path.name}: {constant} is not JSON")
    return json.loads(path.read_text(), parse_constant=refuse)


def is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def first_time(message: str) -> float:
    match = re.search(r"t = ([0-9.eE+-]+) s", message)
    assert match, f"the message gives no time: {message}"
    return float(match.group(1))


# ----------------------------------------------------------------------------------------------
# inerter run
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("scene", ALL)
def test_inerter_run_writes_the_csv_the_summary_and_the_plot(scene, tmp_path):
    name, stop = model(scene).name, stop_time(scene)
    dt = model(scene).experiment["output_interval"]
    stops = DESIGNED_TO_STOP.get(scene.stem)
    out = tmp_path / "out"
    proc = subprocess.run(cli() + ["run", str(scene), "--stop-time", repr(stop), "--out", str(out)],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == (3 if stops else 0), proc.stdout + proc.stderr
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [f"{name}.csv", f"{name}.summary.json", "summary.json", f"{name}.png"])

    with open(out / f"{name}.csv") as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(out / f"{name}.csv", delimiter=",", skiprows=1, ndmin=2)
    units = {o["name"]: o["unit"] for o in model(scene).output_info()}
    assert header == ["time (s)"] + [f"{n} ({units[n]})" for n in output_names(scene)]   # each with its unit
    assert data.shape[1] == len(header) and np.all(np.isfinite(data))
    time = data[:, 0]
    assert time[0] == 0.0 and np.allclose(np.diff(time), dt, rtol=0, atol=1e-9)

    summary = strict_json(out / "summary.json")
    assert summary == strict_json(out / f"{name}.summary.json")
    assert summary["scene"] == name and summary["settings"]["stop_time"] == stop
    for key, value in summary["metrics"].items():
        assert is_number(value) or (isinstance(value, list) and all(map(is_number, value))), (key, value)
    assert all(isinstance(v, str) for v in summary["metric_errors"].values())
    png = (out / f"{name}.png").read_bytes()
    assert png.startswith(b"\x89PNG\r\n\x1a\n") and len(png) > 10_000

    if stops is None:
        assert summary["status"] == "ok", summary["message"]
        assert len(time) == round(stop / dt) + 1 and time[-1] == pytest.approx(stop, abs=1e-9)
        return
    # Stopped where the scene's comments say, at the last sample before it, saying why.
    assert summary["status"] == "failed"
    message = summary["message"]
    assert all(n in message for n in stops.names), message
    assert first_time(message) == pytest.approx(stops.at, abs=dt), message
    assert stops.at - dt < time[-1] <= stops.at
    assert "failed" in proc.stdout


# ----------------------------------------------------------------------------------------------
# The FMU
# ----------------------------------------------------------------------------------------------
class _Built(dict):
    """scene -> its FMU in build/fmu/, built (or found current) once, when first asked for."""

    def __missing__(self, scene: Path) -> Path:
        self[scene] = fmu_build.build(scene, FMU_DIR)
        return self[scene]


@pytest.fixture(scope="module")
def fmus():
    return _Built()


#: Run in a new, isolated interpreter (so the FMU uses nothing but what it ships and the installed
#: numpy, scipy and fmpy): the table, the FMU's log and the status of every doStep.
RUN_FMU = r"""
import json, sys
from fmpy import simulate_fmu
job = json.loads(sys.argv[1])
log, calls, table, error = [], [], None, None

def logger(component, instance, status, category, message):
    log.append([int(status), message.decode("utf-8", "replace")])

try:
    result = simulate_fmu(job["fmu"], stop_time=job["stop_time"], output_interval=job["output_interval"],
                          output=job["outputs"], logger=logger, debug_logging=True,
                          fmi_call_logger=calls.append)
    table = {n: result[n].tolist() for n in ["time"] + job["outputs"]}
except Exception as exc:
    error = repr(exc)
print(json.dumps({"table": table, "error": error, "log": log,
                  "do_step": [c.rsplit("-> ", 1)[-1] for c in calls if c.startswith("fmi2DoStep(")]}))
"""


@pytest.fixture(scope="module")
def fmu_run(fmus, tmp_path_factory):
    """scene -> its FMU's run to stop_time(scene) by fmpy in a new process, run once."""
    cache = {}
    keep = ("PATH", "VIRTUAL_ENV", "HOME", "XDG_CACHE_HOME", "INERTER_CACHE_DIR", "NUMBA_CACHE_DIR")
    env = {k: os.environ[k] for k in keep if k in os.environ}     # where numba's cache is, too

    def get(scene: Path) -> dict:
        if scene not in cache:
            job = dict(fmu=str(fmus[scene]), stop_time=stop_time(scene),
                       output_interval=model(scene).experiment["output_interval"], outputs=output_names(scene))
            proc = subprocess.run([sys.executable, "-I", "-c", RUN_FMU, json.dumps(job)],
                                  cwd=tmp_path_factory.mktemp("fmu_run"), env=env, capture_output=True,
                                  text=True, timeout=600)
            assert proc.returncode == 0, f"the process running the FMU crashed:\n{proc.stderr[-3000:]}"
            cache[scene] = json.loads(proc.stdout.strip().splitlines()[-1])
        return cache[scene]
    return get


def solver_run(scene: Path, run: dict):
    """The solver's run at the settings the FMU logged it integrates with, which are the scene's."""
    logged = next((m for _, m in run["log"] if INITIALISED.search(m)), None)
    assert logged, "the FMU logged no solver settings:\n" + "\n".join(m for _, m in run["log"])
    method, rtol, atol, _ = INITIALISED.search(logged).groups()
    s = model(scene).settings()
    assert (method, float(rtol), float(atol)) == (s.method, pytest.approx(s.rtol, rel=1e-5),
                                                  pytest.approx(s.atol, rel=1e-5)), logged
    result = model(scene).simulate(stop_time=stop_time(scene), output_interval=s.output_interval,
                                   method=s.method, rtol=s.rtol, atol=s.atol, metrics=False)
    return result, s


def assert_outputs_match(scene: Path, table: dict, ref, s, n: int):
    """The first n samples of every output, each within TOLERANCE_FACTOR of its tolerance."""
    worst = {}
    for name in output_names(scene):
        fmu, solver = np.asarray(table[name][:n]), ref[name][:n]
        tolerance = TOLERANCE_FACTOR * (s.rtol * float(np.max(np.abs(solver))) + s.atol)
        error = float(np.max(np.abs(fmu - solver)))
        if not error <= tolerance:
            worst[name] = f"{error:.3g} > {tolerance:.3g}"
    assert not worst, f"FMU and solver differ: {worst}"


@pytest.mark.parametrize("scene", COMPLETING)
def test_its_fmu_gives_the_solvers_outputs(scene, fmu_run):
    run = fmu_run(scene)
    assert run["error"] is None, run["error"]
    assert set(run["do_step"]) == {"OK"}
    assert not [m for status, m in run["log"] if status >= FMI_DISCARD], run["log"]
    ref, s = solver_run(scene, run)
    assert ref.status == "ok", ref.message
    time = np.asarray(run["table"]["time"])
    assert time[-1] == pytest.approx(stop_time(scene), abs=1e-9), "the FMU stopped early"
    assert len(time) == len(ref.time) and np.allclose(time, ref.time, rtol=0, atol=1e-9)
    assert_outputs_match(scene, run["table"], ref, s, len(time))


@pytest.mark.parametrize("scene", STOPPING)
def test_its_fmu_discards_the_step_where_the_scene_stops(scene, fmu_run):
    stops = DESIGNED_TO_STOP[scene.stem]
    run = fmu_run(scene)
    assert run["error"] is None, run["error"]          # fmi2Discard: fmpy returns what it has
    *before, last = run["do_step"]
    assert set(before) == {"OK"} and last in ("DISCARD", "ERROR"), run["do_step"][-3:]
    assert not [m for status, m in run["log"] if status >= FMI_FATAL], run["log"]
    reasons = [m for status, m in run["log"] if status in (FMI_DISCARD, FMI_ERROR)]
    assert reasons and all(n in reasons[-1] for n in stops.names), run["log"]
    # fmpy records the last successful time once more after a discarded step
    time = np.asarray(run["table"]["time"])
    n = len(time) - 1 if len(time) > 1 and time[-1] == time[-2] else len(time)
    dt = model(scene).experiment["output_interval"]
    assert stops.at - dt < time[n - 1] <= stops.at
    # up to there, the solver's run (which stops there too)
    ref, s = solver_run(scene, run)
    assert ref.status == "failed" and stops.at - dt < ref.time[-1] <= stops.at, ref.message
    assert n == len(ref.time) and np.allclose(time[:n], ref.time, rtol=0, atol=1e-9)
    assert_outputs_match(scene, run["table"], ref, s, n)


def test_every_shipped_scene_is_here():
    """The glob finds both folders' scenes, every scene named above exists, and no TOML file under
    scenarios/ escapes the glob (a file there is a scene a user may run: data that is not a scene,
    such as the devices' values, lives in devices/)."""
    assert {p.parent.name for p in SCENES} == {"scenarios", "hard"}
    assert sorted(SCENARIOS.rglob("*.toml")) == sorted(SCENES)
    assert set(DESIGNED_TO_STOP) <= {p.stem for p in SCENES}
