"""Parameter sweeps on dask.distributed: ``inerter sweep`` and ``inerter sweep-plot``.

    inerter sweep SCENE --vary NAME=START:STOP:NUM [--vary NAME=V1,V2,...] --out DIR
                  [--model solver|fmu] [--workers N] [--scheduler ADDRESS]
                  [--set NAME=VALUE ...] [--stop-time T] [--step H] [--dashboard [ADDRESS]]
    inerter sweep-plot DIR/results.csv --x NAME --y METRIC [--hue NAME] --out FILE.png

A sweep runs every combination of the varied values (the names that ``--set`` takes: parameters,
``effects.NAME``, ``experiment.NAME``), each run in a task of its own on dask.distributed: a
LocalCluster of N worker processes with one thread each, or the workers of a running scheduler
(``--scheduler tcp://host:8786``). A tqdm progress bar counts the runs done and failed and
estimates the time left.

Results. One row per run is appended to ``DIR/results.csv`` (and flushed) as soon as the run
finishes: its key, the scene's name, the model, the value of every ``--set`` and ``--vary`` name
(in SI: a table with a unit or an expression as the number the run reads from it, :meth:`Sweep.written`),
status (``ok`` or ``failed``), the error message of a failed run, the scalar metrics of the scene,
the run time on the worker (s), the worker and the time it finished. The columns are ordered
``key, scene, model, <parameters>, status, error, <metrics>, run_time_s, worker, finished_at``, so
that the file says itself which columns are parameters and which are metrics.

Resuming. Each run is keyed by a hash of the scene file's content, the run's overrides (the
``--set`` values and its varied values) and the run settings (model, stop time, FMU step). A
sweep started again with the same arguments skips every key already in ``results.csv``: nothing
finished is computed twice, and a sweep stopped part-way (Ctrl-C, a killed process, ``--max-runs``)
is finished by running the same command again. A value the scene refuses (a negative inertance)
is an error of the whole sweep, before any run; a run that fails (a mechanism singular for that
combination, a simulation that stops part-way) is recorded with its message and never stops the
sweep; ``--retry-failed`` runs the failed keys again.

With ``--model fmu`` each worker extracts and instantiates the scene's FMU once, and resets it
between runs (:class:`FmuSlot`).

Workers. Each run is sent as :func:`inerter.studies.sweep_task.run`, by value: a worker that cannot
import inerter, or has another version, answers at once and the sweep stops with a message naming
it. ``--dashboard`` serves dask's dashboard (bokeh) and prints its link.
"""
from __future__ import annotations

import argparse
import atexit
import csv
import hashlib
import io
import itertools
import json
import math
import os
import shutil
import socket
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from inerter.studies.arguments import Parser
from inerter.common.atomic import replace_file
from inerter.common.errors import InerterError, SceneError
from inerter.common.options import OptionError, count, output_folder, unwritable

try:  # POSIX: one sweep at a time writes a results file
    import fcntl
except ImportError:  # pragma: no cover - not on Linux
    fcntl = None

RESULTS_FILE = "results.csv"
SWEEP_FILE = "sweep.json"
MODELS = ("solver", "fmu")
PATHS = ("numpy", "compiled")

#: The units of the experiment settings that have one (the others are dimensionless or names).
EXPERIMENT_UNITS = {"stop_time": "s", "output_interval": "s", "communication_step": "s", "step": "s",
                    "baumgarte": "1/s"}

#: Columns before the parameters, between the parameters and the metrics, and after the metrics.
HEAD_COLUMNS = ("key", "scene", "model")
STATUS_COLUMNS = ("status", "error")
TAIL_COLUMNS = ("run_time_s", "worker", "finished_at")
META_COLUMNS = HEAD_COLUMNS + STATUS_COLUMNS + TAIL_COLUMNS

#: The metric keys each kind of [[metrics]] gives (see inerter.api.compute_metrics). Used to lay
#: out the CSV header before any run has finished; a key not listed here still gets its column.
METRIC_KEYS = {
    "natural_frequency": ("natural_frequency",),
    "free_oscillation": ("fundamental_frequency", "fundamental_amplitude", "mean_offset"),
    "harmonics": ("mean", "amplitude"),
    "steady_state": ("peak_to_peak", "mean_offset"),
}


class SweepError(InerterError):
    """A sweep cannot start or a results file cannot be used (the message says which and why)."""


# ----------------------------------------------------------------------------------------------
# What to run
# ----------------------------------------------------------------------------------------------
def _value(name: str, text: str):
    """One value as ``--set`` reads it (a TOML value, else a bare string)."""
    from inerter.scene.overrides import parse_set
    return parse_set([f"{name}={text}"])[name]


def parse_vary(text: str) -> tuple[str, list]:
    """``NAME=START:STOP:NUM`` (NUM evenly spaced values, ends included) or ``NAME=V1,V2,...``."""
    expected = "NAME=START:STOP:NUM or NAME=V1,V2,... (e.g. y0=1.05:1.8:16 or effects.centripetal=true,false)"
    if "=" not in text:
        raise SceneError("--vary", text, text, expected, "missing '='")
    name, spec = (s.strip() for s in text.split("=", 1))
    if not name or not spec:
        raise SceneError("--vary", name or text, text, expected, "missing name or values")
    if ":" in spec and "," not in spec:
        parts = spec.split(":")
        try:
            if len(parts) != 3:
                raise ValueError
            start, stop, num = float(parts[0]), float(parts[1]), int(parts[2])
        except ValueError:
            raise SceneError("--vary", name, spec, "START:STOP:NUM with numbers START, STOP and a whole "
                             "number NUM ≥ 1 (e.g. 1.05:1.8:16)", "not a range") from None
        if num < 1 or not (math.isfinite(start) and math.isfinite(stop)):
            raise SceneError("--vary", name, spec, "finite START and STOP and NUM ≥ 1", "out of range")
        if num > 1 and start == stop:            # NUM copies of one value: one run, not the NUM asked for
            raise SceneError("--vary", name, spec, f"START ≠ STOP for NUM = {num} values (one value: {name}="
                             f"{parts[0]})", "empty range")
        # 12 significant digits: 1.15, not 1.1500000000000001, in the CSV and in the run keys.
        values = [float(f"{v:.12g}") for v in np.linspace(start, stop, num)]
    else:
        items = [s.strip() for s in _split_values(spec)]
        if any(not s for s in items):
            raise SceneError("--vary", name, spec, "values separated by commas", "empty value")
        values = [_value(name, s) for s in items]
    return name, values


def _split_values(spec: str) -> list[str]:
    """``V1,V2,...`` split at the commas between values, not at those inside a vector or a table
    (``[0, -9.81],[0, 0]``, ``{value = 1100, unit = "mm"},...``), nor inside quotes or an
    expression's call (``max(1, b),2``)."""
    items, depth, quote, start = [], 0, None, 0
    for i, c in enumerate(spec):
        if quote:
            quote = None if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c in "[{(":
            depth += 1
        elif c in "]})":
            depth -= 1
        elif c == "," and depth == 0:
            items.append(spec[start:i])
            start = i + 1
    return items + [spec[start:]]


def _canonical(value):
    """A value as it enters a run key: 10 and 10.0 are the same run."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, (int, float, np.integer, np.floating)):
        return float(value)
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    return str(value)


def run_key(scene_digest: str, overrides: dict, settings: dict) -> str:
    """The stable key of one run: scene content + overrides + run settings (16 hex digits)."""
    text = json.dumps({"scene": scene_digest,
                       "overrides": {k: _canonical(v) for k, v in overrides.items()},
                       "settings": {k: _canonical(v) for k, v in settings.items()}},
                      sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Run:
    key: str
    overrides: dict          # the --set values and this run's varied values


@dataclass
class Sweep:
    """A scene, the varied names with their values, fixed overrides and the run settings."""
    scene: Path
    axes: list[tuple[str, list]]
    fixed: dict = field(default_factory=dict)
    model: str = "solver"
    stop_time: float | None = None
    step: float | None = None            # FMU communication step (--model fmu)
    path: str = "compiled"               # the solver's path (--model solver): compiled or numpy
    origins: dict = field(default_factory=dict)   # where each fixed value came from ("--set b=3"), for errors

    def __post_init__(self):
        from inerter.api import Model
        from inerter.scene.reader import EXPERIMENT_FIELDS, KNOWN_EFFECTS

        self.scene = Path(self.scene).resolve()
        if not self.scene.is_file():
            raise SweepError(f"{self.scene}: no such scene file")
        if self.model not in MODELS:
            raise SweepError(f"--model {self.model}: expected one of {', '.join(MODELS)}")
        if self.path not in PATHS:
            raise SweepError(f"--path {self.path}: expected one of {', '.join(PATHS)}")
        if not self.axes:
            raise SweepError("nothing to sweep: give at least one --vary NAME=START:STOP:NUM")
        self.content = self.scene.read_bytes()
        self.digest = hashlib.sha256(self.content).hexdigest()
        base = Model(self.scene, self.fixed, origins=self.origins)    # a bad --set is an error of the whole sweep
        self.name = base.name
        params = list(base.scene.parameters)
        names = [n for n, _ in self.axes]
        for name in names:
            if names.count(name) > 1:
                raise SweepError(f"--vary {name}: given more than once")
            if name in self.fixed:
                raise SweepError(f"--vary {name}: also given with --set (vary it or fix it, not both)")
            known = (name in params
                     or (name.startswith("effects.") and name[8:] in KNOWN_EFFECTS)
                     or (name.startswith("experiment.") and name[11:] in EXPERIMENT_FIELDS))
            if not known:
                raise SceneError("--vary", name, name, "a parameter of " + str(self.scene) + ": "
                                 + ", ".join(params) + ", or effects.NAME, or experiment.NAME", "unknown name")
        self._check_values()
        self._check_settings(base)
        if self.model == "fmu":         # a name the FMU cannot take fails every run alike: say so now
            from inerter.fmu.run import start_values
            for name, values in [*self.fixed.items(), *((n, v[0]) for n, v in self.axes)]:
                option = "--set" if name in self.fixed else "--vary"
                try:
                    start_values(base, {name: values})
                except SceneError as exc:
                    raise SweepError(f"{option} {name} with --model fmu: {exc}") from None
        self.metric_columns = []
        for m in base.scene.metrics:
            for k in METRIC_KEYS.get(m.kind, ()):
                key = f"{m.prefix}_{k}" if m.prefix else k
                if key not in self.metric_columns:
                    self.metric_columns.append(key)
        self.parameter_columns = list(self.fixed) + names
        self.units = self._units(base)
        clash = set(self.parameter_columns) & (set(META_COLUMNS) | set(self.metric_columns))
        if clash:
            raise SweepError(f"{', '.join(sorted(clash))}: a name of both a parameter and a column of "
                             "results.csv; rename the parameter in the scene")

    def _check_values(self):
        """Every varied value read by the scene's validator (:func:`inerter.scene.reader.build_scene`,
        with the --set values), before any worker starts: a value the scene refuses is the error the
        scene gives, after the option that gave it (``--vary y0=0: scene.toml: parameters.y0: ...``)."""
        from inerter.scene.overrides import origin_of
        from inerter.scene.reader import build_scene, read_toml
        source, data = self._toml = read_toml(self.scene)
        for name, values in self.axes:
            seen = set()
            for value in values:
                if repr(value) in seen:
                    continue
                seen.add(repr(value))
                origin = f"--vary {origin_of(name, value)[len('override '):]}"
                try:
                    build_scene(source, data, {**self.fixed, name: value}, {**self.origins, name: origin})
                except SceneError as exc:           # named by its option, by the scene reader or here
                    text = str(exc)
                    raise SweepError(text if text.startswith(origin + ":") else f"{origin}: {text}") from None

    def written(self, overrides: dict) -> dict:
        """A run's overrides as its row of results.csv holds them: a parameter or experiment setting
        given as a table with a unit (``y0={value = 1100, unit = "mm"}``) or an expression (``b=2*m``)
        as the SI number the run reads from it, in the unit sweep.json states for its column (a number
        is SI as given); the others as given. The run's key is of the values as given."""
        from inerter.scene.reader import build_scene
        names = [n for n, v in overrides.items() if isinstance(v, (dict, str)) and not n.startswith("effects.")]
        if not names:
            return overrides
        try:
            scene = build_scene(*self._toml, overrides)
        except SceneError:                  # this combination fails its run, which says why
            return overrides
        out = dict(overrides)
        for name in names:
            value = (getattr(scene.experiment, name[len("experiment."):], None) if name.startswith("experiment.")
                     else scene.parameters[name].value if name in scene.parameters else None)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                out[name] = value
        return out

    def _units(self, base) -> dict:
        """The unit of each column of results.csv that has one (sweep.json's ``units``): a parameter's
        SI unit (the values in the file are SI, as ``--set`` takes them), an experiment setting's, a
        metric's (Hz for frequencies, its signal's unit otherwise) and the run time's."""
        from inerter.api import metric_units
        known = {p["name"]: p["unit"] for p in base.parameter_info()}
        known.update({f"experiment.{k}": u for k, u in EXPERIMENT_UNITS.items()})
        units = {name: known[name] for name in self.parameter_columns if known.get(name)}
        units.update(metric_units(base))
        units["run_time_s"] = "s"
        return units

    def _check_settings(self, base):
        """--stop-time and --step read as the runs read them (the experiment's own checks), before any
        worker starts: a value every run would refuse is an error of the sweep, not a failed row each."""
        check_fmu_step(self.step, self.model)
        given = {k: v for k, v in (("stop_time", self.stop_time), ("communication_step", self.step),
                                   ("output_interval", self.step)) if v is not None}
        varied = [n for n, _ in self.axes]
        for key in given:                  # the option is the runs' setting: a value beside it would go unused
            name = f"experiment.{key}"
            if name in varied or name in self.fixed:
                option = "--stop-time" if key == "stop_time" else "--step"
                raise SweepError(f"{option}: {name} is also given with {'--vary' if name in varied else '--set'}, "
                                 f"and {option} would set every run's {key}: give one of them")
        if given:
            option = " and ".join(o for o, v in (("--stop-time", self.stop_time), ("--step", self.step)) if v is not None)
            try:
                base.scene.experiment_with(given, f"{option}: {self.scene}")
            except SceneError as exc:
                raise SweepError(str(exc)) from None

    @property
    def settings(self) -> dict:
        """The run settings that enter each run's key."""
        out = {"model": self.model, "stop_time": self.stop_time}
        if self.model == "fmu":
            out["step"] = self.step
        elif self.path != "numpy":           # (the keys of numpy-path runs stay as they were)
            out["path"] = self.path
        return out

    def runs(self) -> list[Run]:
        """Every combination, in the order of the axes (the last varies fastest); one per key."""
        out, seen = [], set()
        names = [n for n, _ in self.axes]
        for combo in itertools.product(*(values for _, values in self.axes)):
            overrides = dict(self.fixed)
            overrides.update(zip(names, combo))
            key = run_key(self.digest, overrides, self.settings)
            if key not in seen:
                seen.add(key)
                out.append(Run(key, overrides))
        return out

    def describe(self) -> dict:
        return {"scene": str(self.scene), "scene_sha256": self.digest, "name": self.name,
                "model": self.model, "stop_time": self.stop_time, "step": self.step, "path": self.path,
                "set": self.fixed, "vary": {n: v for n, v in self.axes}, "runs": len(self.runs()),
                "units": self.units}


# ----------------------------------------------------------------------------------------------
# One run, on a worker
# ----------------------------------------------------------------------------------------------
def _cell(value) -> str:
    """A CSV cell: booleans as in a scene file, floats to full precision, one line of text."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    return " ".join(str(value).split())


def _scene_on_worker(task) -> Path:
    """The scene file, or a copy of its content where the worker does not see the same file."""
    path = Path(task["scene_path"])
    try:
        if hashlib.sha256(path.read_bytes()).hexdigest() == task["scene_digest"]:
            return path
    except OSError:
        pass
    folder = Path(tempfile.gettempdir()) / f"inerter-sweep-{task['scene_digest'][:16]}"
    folder.mkdir(parents=True, exist_ok=True)
    copy = folder / path.name
    if not copy.is_file():
        replace_file(copy, lambda part: part.write_bytes(task["scene_content"]))
    return copy


def run_one(task: dict) -> dict:
    """Run one combination and return its row. Never raises: a failure is a row with its error."""
    t0 = time.perf_counter()
    row = {"key": task["key"], "scene": task["name"], "model": task["model"]}
    row.update(task.get("written") or task["overrides"])
    metrics: dict[str, Any] = {}
    try:
        scene = _scene_on_worker(task)
        if task["model"] == "fmu":
            slot = fmu_slot(task["fmu_path"], scene)
            try:
                result = slot.simulate(scene, task["overrides"], task["stop_time"], task["step"])
            except InerterError:          # the overrides: the instance is as good as before
                raise
            except Exception:             # the instance may be broken: the next run makes a new one
                _drop_slot(slot)
                raise
        else:
            from inerter.api import load
            result = load(scene, **task["overrides"]).simulate(stop_time=task["stop_time"],
                                                               path=task.get("path", "compiled"))
        status, error = result.status, ("" if result.status == "ok" else result.message)
        metrics = {k: v for k, v in result.metrics.items()
                   if isinstance(v, (int, float)) and not isinstance(v, bool)}
    except InerterError as exc:
        status, error = "failed", str(exc)
    except Exception as exc:  # a bug or an environment problem: recorded, the sweep goes on
        status, error = "failed", f"{type(exc).__name__}: {exc}"
    row["status"], row["error"] = status, error
    row.update(metrics)
    row["run_time_s"] = round(time.perf_counter() - t0, 4)
    row["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    row["finished_at"] = datetime.now(timezone.utc).isoformat(timespec="microseconds")
    return row


# ----------------------------------------------------------------------------------------------
# The FMU, once per worker
# ----------------------------------------------------------------------------------------------
_local = threading.local()


def _worker_folder() -> Path:
    """A folder that lives as long as this worker (dask's own), else a temporary one."""
    try:
        from distributed import get_worker
        return Path(get_worker().local_directory)
    except (ImportError, ValueError):
        folder = getattr(_local, "tmp", None)
        if folder is None:
            folder = _local.tmp = Path(tempfile.mkdtemp(prefix="inerter-sweep-"))
            atexit.register(shutil.rmtree, folder, True)
        return folder


def fmu_slot(fmu_path, scene) -> "FmuSlot":
    """This thread's instance of the FMU at `fmu_path` (made on first use, then reused)."""
    slots = getattr(_local, "fmus", None)
    if slots is None:
        slots = _local.fmus = {}
    path = Path(fmu_path) if fmu_path else None
    if path is None or not path.is_file():          # a worker on another machine: build it here
        from inerter.fmu.build import build
        path = build(scene, _worker_folder() / "fmu")
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns)
    slot = slots.get(key)
    if slot is None:
        for old in slots.values():
            old.free()
        slots.clear()
        slot = slots[key] = FmuSlot(path)
    return slot


def _drop_slot(slot: "FmuSlot"):
    slots = getattr(_local, "fmus", {})
    for key in [k for k, v in slots.items() if v is slot]:
        del slots[key]
    slot.free()


class FmuSlot:
    """One FMU instance kept across runs: extracted and instantiated once, reset between runs.

    Each run sets the start values, runs setupExperiment, enter/exitInitializationMode, then
    doStep over the communication step to the stop time, reading every output after each step,
    as ``fmpy.simulate_fmu`` does (``inerter.fmu.run.simulate_fmu`` gives the same numbers). The
    metrics then read the FMU's dense output from the same instance, reset and stepped again to the
    times they read (:class:`inerter.fmu.dense.FmuDense`).
    """

    instances = 0          # made in this process (the tests check the reuse)

    def __init__(self, fmu_path: Path):
        import fmpy
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

        self.path = Path(fmu_path)
        self.md = read_model_description(str(self.path))
        self.unzipdir = tempfile.mkdtemp(prefix=f"{self.path.stem}-", dir=_worker_folder())
        extract(str(self.path), unzipdir=self.unzipdir)
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.outputs = [v for v in self.md.modelVariables if v.causality == "output" and v.type == "Real"]
        self.variable_step = bool(self.md.coSimulation.canHandleVariableCommunicationStepSize)
        self.messages: list[str] = []
        # The callbacks must live as long as the instance.
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="sweep")
        self.fmu.instantiate(callbacks=self.callbacks, loggingOn=True)
        self.fresh = True
        self.runs = 0
        FmuSlot.instances += 1

    def _log(self, env, instance, status, category, message):
        self.messages.append(message.decode("utf-8", errors="replace") if isinstance(message, bytes)
                             else str(message))

    def free(self):
        try:
            self.fmu.freeInstance()
        except Exception:
            pass
        shutil.rmtree(self.unzipdir, ignore_errors=True)

    def _set(self, values: dict):
        by_type: dict[str, tuple[list, list]] = {}
        for name, value in values.items():
            var = self.variables.get(name)
            if var is None:
                raise SweepError(f"{name}: not a variable of the FMU {self.path.name}")
            vrs, vals = by_type.setdefault(var.type, ([], []))
            vrs.append(var.valueReference)
            vals.append(value)
        for kind, (vrs, vals) in by_type.items():
            if kind == "Real":
                self.fmu.setReal(vrs, [float(v) for v in vals])
            elif kind == "Boolean":
                self.fmu.setBoolean(vrs, [bool(v) for v in vals])
            elif kind == "String":
                self.fmu.setString(vrs, [str(v) for v in vals])
            else:
                self.fmu.setInteger(vrs, [int(v) for v in vals])

    def simulate(self, scene, overrides: dict, stop_time=None, step=None):
        from fmpy.fmi1 import FMICallException

        from inerter.fmu.run import FmuResult, FmuRunInfo, start_values
        from inerter.api import Model

        from inerter.engine.simulation import Settings

        model = Model(scene, overrides)                # the solver's messages for bad overrides
        # the importer samples the FMU at its communication points: a step given is the output interval too
        given = {k: v for k, v in (("stop_time", stop_time), ("communication_step", step), ("output_interval", step))
                 if v is not None}
        experiment = model.scene.experiment_with(given) if given else model.scene.experiment
        settings = Settings.from_experiment(experiment)
        comm = experiment.communication_step
        start = start_values(model, overrides)
        if not self.fresh:
            self.fmu.reset()
        self.fresh = False
        self.runs += 1
        self.messages.clear()
        stop = settings.stop_time
        vrs = [v.valueReference for v in self.outputs]
        t0 = time.process_time()
        self.fmu.setupExperiment(tolerance=None, startTime=0.0, stopTime=stop)
        self._set(start)
        self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        rows = [(0.0, *self.fmu.getReal(vrs))]
        t, n = 0.0, 0
        failure = None
        while not (t > stop or math.isclose(t, stop)):
            regular = (n + 1) * comm
            nxt = regular
            if nxt > stop and not math.isclose(nxt, stop):
                if not self.variable_step:
                    break
                nxt = stop
            try:
                self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=nxt - t)
            except FMICallException:
                failure = "; ".join(self.messages[-3:]) or "a step was discarded"
                break
            t = nxt
            rows.append((t, *self.fmu.getReal(vrs)))
            if math.isclose(t, regular):
                n += 1
        cpu = time.process_time() - t0
        table = np.array(rows, dtype=[("time", np.float64)] + [(v.name, np.float64) for v in self.outputs])
        ok = failure is None and abs(t - stop) <= 1e-9 * max(1.0, stop)
        message = "completed" if ok else f"the FMU stopped at t = {t:.9g} s: {failure or 'before the stop time'}"
        run = FmuRunInfo(steps=len(table) - 1, evaluations=0, cpu_time=cpu,
                          max_drift=float(np.max(table["constraint_residual"]))
                          if "constraint_residual" in table.dtype.names else 0.0,
                          status="ok" if ok else "failed", message=message)
        result = FmuResult(model, table, settings, run, comm)
        if ok:                              # the metrics read the FMU's dense output, as simulate_fmu's
            result.read_the_fmu(self.path, start, instance=self.fmu)
            result.compute_metrics()
        return result


# ----------------------------------------------------------------------------------------------
# The results file
# ----------------------------------------------------------------------------------------------
class ResultsFile:
    """``results.csv``: rows appended and flushed one by one, read back to resume.

    Held under an exclusive lock while a sweep writes it (``results.csv.lock`` beside it, removed
    when the file is closed). A row cut short by a killed process (no final newline) is dropped
    when the file is opened again. A row with a parameter or metric the header lacks rewrites the
    file with the column added in its place.
    """

    #: Attempts at taking the lock while other sweeps remove their lock files (see _take_lock).
    LOCK_ATTEMPTS = 10

    def __init__(self, path):
        self.path = Path(path)
        self.lock_path = self.path.with_name(self.path.name + ".lock")
        self.columns: list[str] = []
        self.rows: list[dict] = []
        self._fh = None
        self._lock = None

    # -- reading (no lock needed) -------------------------------------------------------------
    @staticmethod
    def read(path) -> tuple[list[str], list[dict]]:
        path = Path(path)
        if not path.is_file():
            raise SweepError(f"{path}: no such results file")
        text = path.read_text(encoding="utf-8")
        if text and not text.endswith("\n"):
            text = text[: text.rfind("\n") + 1]
        reader = csv.DictReader(io.StringIO(text))
        rows = [r for r in reader if r.get("key")]
        return list(reader.fieldnames or []), rows

    # -- writing ------------------------------------------------------------------------------
    def open(self, parameters=(), metrics=(), check=None) -> "ResultsFile":
        """Lock the file, read its rows and add the columns it lacks. `check(rows)`: called on the
        rows before anything is written (it raises to refuse the file). Whatever fails, the lock is
        released and its file removed."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._take_lock()
        try:
            return self._load(parameters, metrics, check)
        except BaseException:
            self.close()
            raise

    def _take_lock(self):
        """The exclusive lock on ``results.csv.lock``. The file a sweep locked may be removed by it
        as it ends (close) between this sweep's opening it and locking it: then this sweep holds
        the lock of a file no longer there, and locks the one now at that path instead."""
        if fcntl is None:
            return
        for _ in range(self.LOCK_ATTEMPTS):
            fh = open(self.lock_path, "a")
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                fh.close()
                break
            try:
                here = os.stat(self.lock_path)
                mine = os.fstat(fh.fileno())
                if (here.st_dev, here.st_ino) == (mine.st_dev, mine.st_ino):
                    self._lock = fh
                    return
            except FileNotFoundError:
                pass
            fh.close()
        raise SweepError(f"{self.path}: another sweep is writing this file; wait for it to finish "
                         "or use another --out")

    def _load(self, parameters, metrics, check) -> "ResultsFile":
        if self.path.is_file() and self.path.stat().st_size:
            data = self.path.read_bytes()
            if not data.endswith(b"\n"):                        # a row cut short by a kill
                with open(self.path, "r+b") as fh:
                    fh.truncate(data.rfind(b"\n") + 1)
            self.columns, self.rows = self.read(self.path)
        if check is not None:
            check(self.rows)
        if not self.columns or "key" not in self.columns or "status" not in self.columns:
            if self.rows:
                raise SweepError(f"{self.path}: not a results file of inerter sweep (no key/status columns)")
            self.columns = list(HEAD_COLUMNS) + list(STATUS_COLUMNS) + list(TAIL_COLUMNS)
            self._add_columns(parameters, metrics)
            self._rewrite()
        elif self._add_columns(parameters, metrics):
            self._rewrite()
        self._fh = open(self.path, "a", newline="", encoding="utf-8")
        return self

    def _add_columns(self, parameters=(), metrics=()) -> bool:
        """Put new parameter columns before ``status`` and new metric columns before ``run_time_s``."""
        changed = False
        for name in parameters:
            if name not in self.columns:
                self.columns.insert(self.columns.index("status"), name)
                changed = True
        for name in metrics:
            if name not in self.columns:
                at = self.columns.index("run_time_s") if "run_time_s" in self.columns else len(self.columns)
                self.columns.insert(at, name)
                changed = True
        return changed

    def _rewrite(self):
        def write(part):
            with open(part, "w", newline="", encoding="utf-8") as fh:
                writer = csv.DictWriter(fh, self.columns, lineterminator="\n", extrasaction="ignore")
                writer.writeheader()
                writer.writerows(self.rows)
        replace_file(self.path, write)
        if self._fh is not None:
            self._fh.close()
            self._fh = open(self.path, "a", newline="", encoding="utf-8")

    def append(self, row: dict, parameters=()):
        cells = {k: _cell(v) for k, v in row.items()}
        new_params = [k for k in parameters if k not in self.columns]
        new_metrics = [k for k in cells if k not in self.columns and k not in parameters]
        self.rows.append(cells)
        if new_params or new_metrics:
            self._add_columns(new_params, new_metrics)
            self._rewrite()                     # the new row is written with the others
            return
        csv.DictWriter(self._fh, self.columns, lineterminator="\n", extrasaction="ignore").writerow(cells)
        self._fh.flush()

    def drop(self, keys: set):
        """Remove the rows of these keys (``--retry-failed``)."""
        before = len(self.rows)
        self.rows = [r for r in self.rows if r.get("key") not in keys]
        if len(self.rows) != before:
            self._rewrite()

    def close(self):
        if self._fh is not None:
            self._fh.close()
            self._fh = None
        if self._lock is not None:          # removed while held: no other sweep holds it meanwhile
            try:
                os.unlink(self.lock_path)
            except OSError:
                pass
            self._lock.close()
            self._lock = None


# ----------------------------------------------------------------------------------------------
# Running a sweep
# ----------------------------------------------------------------------------------------------
@dataclass
class SweepReport:
    total: int                     # runs in the sweep
    skipped: int                   # already in results.csv
    ok: int = 0                    # run now
    failed: int = 0                # run now
    failed_before: int = 0         # skipped, recorded as failed by an earlier start
    pending: int = 0               # left for a later start (--max-runs, interrupted)
    results: Path | None = None
    wall_time: float = 0.0
    rows: list = field(default_factory=list)    # the rows written now


#: Settings of the workers of the local cluster a sweep starts: no statistical profiler (it samples the
#: running task every 10 ms) and a slower event-loop tick and system monitor. They cost each run a few per
#: cent of its time, for a dashboard that a sweep does not show.
LOCAL_WORKER_CONFIG = {"distributed.worker.profile.enabled": False,
                       "distributed.admin.tick.interval": "1s",
                       "distributed.admin.system-monitor.interval": "2s"}


#: Attempts at the handshake with a running scheduler (see DaskClient).
CONNECT_ATTEMPTS = 3


def _check_dashboard_available():
    """dask serves its dashboard with bokeh, an optional dependency: say so before a cluster starts."""
    try:
        import bokeh  # noqa: F401
    except ImportError:
        raise SweepError("--dashboard: dask's dashboard needs bokeh, which is not installed here (pip install "
                         "'bokeh>=3.1', or pip install 'inerter[dashboard]')") from None


class DaskClient:
    """``with DaskClient(workers=2) as client``: a dask Client on a LocalCluster of `workers` processes
    with one thread each (default: one per core), or on the running scheduler at `scheduler`.

    `dashboard`: the address of dask's dashboard (``":8787"``, ``"127.0.0.1:0"`` for any free port) on
    the local cluster, whose link is printed; with `scheduler`, the link of that scheduler's own
    dashboard is printed (a scheduler started where bokeh is installed serves one). None (the
    default): no dashboard is started."""

    def __init__(self, workers: int | None = None, scheduler: str | None = None, dashboard: str | None = None):
        if workers is not None and workers < 1:
            raise SweepError(f"--workers {workers}: expected at least 1")
        if dashboard is not None and not scheduler:
            _check_dashboard_available()
        self.workers, self.scheduler, self.dashboard = workers, scheduler, dashboard
        self.cluster = self.client = None

    def __enter__(self):
        import logging

        from distributed import Client, LocalCluster
        if self.scheduler:
            for attempt in range(1, CONNECT_ATTEMPTS + 1):
                try:
                    self.client = Client(self.scheduler, timeout="20s")
                    break
                except (OSError, TimeoutError) as exc:
                    raise SweepError(f"--scheduler {self.scheduler}: cannot connect ({exc})") from None
                except ValueError as exc:           # not an address (check_address said it, for the command)
                    raise SweepError(f"--scheduler {self.scheduler}: {exc}") from None
                except AssertionError:
                    # distributed's Client asserts that the scheduler's first reply is one message; on a
                    # scheduler busy with other clients it can come batched with another: connect anew.
                    if attempt == CONNECT_ATTEMPTS:
                        raise SweepError(f"--scheduler {self.scheduler}: the connection handshake failed "
                                         f"{CONNECT_ATTEMPTS} times") from None
                    time.sleep(0.2 * attempt)
        else:
            import dask
            n = self.workers or os.cpu_count() or 1
            with dask.config.set(LOCAL_WORKER_CONFIG):
                # Without a dashboard the scheduler still serves its HTTP routes (health, metrics), on
                # any free port rather than on the dashboard's 8787.
                http = {"dashboard": True, "dashboard_address": self.dashboard} if self.dashboard else \
                    {"dashboard": False, "dashboard_address": "127.0.0.1:0"}
                # CRITICAL: a run's failure is its row; what dask logs as it shuts down, stopped part-way (a
                # worker's heartbeat to the closed scheduler, a cancelled result), is a traceback on stderr.
                self.cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, host="127.0.0.1",
                                            scheduler_kwargs=http, silence_logs=logging.CRITICAL)
            self.client = Client(self.cluster)
        if self.dashboard is not None:
            where = f" (the dashboard of the scheduler at {self.scheduler}, if it serves one)" if self.scheduler else ""
            print(f"dask dashboard: {self.client.dashboard_link}{where}", flush=True)
        return self.client

    def __exit__(self, *exc):
        if self.client is not None:
            self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def run_sweep(sweep: Sweep, out, workers: int | None = None, scheduler: str | None = None, client=None,
              progress: bool = True, max_runs: int | None = None, retry_failed: bool = False,
              fmu_dir=None, dashboard: str | None = None) -> SweepReport:
    """Run the runs of `sweep` not yet in ``out/results.csv`` and append their rows.

    `client`: a dask Client to use (else one is made from `workers` / `scheduler` / `dashboard`, as
    :class:`DaskClient` takes them).
    `max_runs`: stop after this many new runs (the rest are left for a later start).
    `fmu_dir`: where the FMU is built with ``--model fmu`` (default: build/fmu, as ``inerter run``).
    """
    from tqdm.auto import tqdm

    t_start = time.perf_counter()
    out = Path(out)
    runs = sweep.runs()
    results = ResultsFile(out / RESULTS_FILE)
    try:
        results.open(sweep.parameter_columns, sweep.metric_columns, check=lambda rows: check_scene(sweep, out, rows))
        if retry_failed:
            results.drop({r["key"] for r in results.rows if r.get("status") != "ok"})
        finished = {r["key"] for r in results.rows if r.get("status") in ("ok", "failed")}
        todo = [r for r in runs if r.key not in finished]
        report = SweepReport(total=len(runs), skipped=len(runs) - len(todo), results=results.path)
        keys = {r.key for r in runs}
        report.failed_before = sum(1 for r in results.rows if r.get("key") in keys and r.get("status") == "failed")
        if max_runs is not None:
            todo = todo[:max(0, max_runs)]
        write_description(sweep, out)
        if todo:
            fmu_path = None
            if sweep.model == "fmu":
                from inerter.fmu.build import DEFAULT_OUT_DIR, build
                fmu_path = str(Path(build(sweep.scene, fmu_dir or DEFAULT_OUT_DIR)).resolve())
            from inerter import __version__
            tasks = [dict(key=r.key, name=sweep.name, model=sweep.model, overrides=r.overrides,
                          written=sweep.written(r.overrides), version=__version__,
                          stop_time=sweep.stop_time, step=sweep.step, fmu_path=fmu_path, path=sweep.path,
                          scene_path=str(sweep.scene), scene_digest=sweep.digest, scene_content=sweep.content)
                     for r in todo]
            bar = tqdm(total=report.skipped + len(todo), initial=report.skipped, desc=sweep.name, unit="run",
                       disable=not progress, dynamic_ncols=True, smoothing=0.1)
            bar.set_postfix_str(f"ok 0, failed 0, skipped {report.skipped}")
            try:
                if client is not None:
                    _run_tasks(client, tasks, results, sweep, report, bar)
                else:
                    with DaskClient(workers, scheduler, dashboard) as own:
                        _run_tasks(own, tasks, results, sweep, report, bar)
            finally:
                bar.close()
    finally:
        results.close()
    report.pending = report.total - report.skipped - report.ok - report.failed
    report.wall_time = time.perf_counter() - t_start
    return report


def check_scene(sweep: Sweep, out: Path, rows: list[dict]):
    """A folder holds the sweeps of one scene: rows in its results.csv of another scene are refused
    before any run (its rows would be mixed with this sweep's, its parameters' columns beside these).
    The scene a folder holds is the one its sweep.json names (the same file, or a copy of its
    content), else the scene column of its rows."""
    if not rows:
        return
    try:
        held = json.loads((Path(out) / SWEEP_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        held = None
    if isinstance(held, dict) and isinstance(held.get("scene"), str):
        if held["scene"] == str(sweep.scene) or held.get("scene_sha256") == sweep.digest:
            return
        other = f"{held['scene']} (its {SWEEP_FILE})"
    else:
        names = sorted({r["scene"] for r in rows if r.get("scene")} - {sweep.name})
        if not names:
            return
        other = f"{', '.join(names)} (the scene column of {RESULTS_FILE})"
    raise OptionError("--out", str(out), f"a folder without {RESULTS_FILE}, or one holding a sweep of {sweep.scene}",
                      f"holds the sweep of another scene, {other}")


def write_description(sweep: Sweep, out: Path):
    """``out/sweep.json``: this sweep, and the units of every column of results.csv, those of an
    earlier sweep of the same scene into the same folder (other parameters) kept beside this one's."""
    description = sweep.describe()
    description["units"] = {**column_units(out / RESULTS_FILE), **description["units"]}
    (out / SWEEP_FILE).write_text(json.dumps(description, indent=2, default=str))


#: A sweep with runs left and no worker for this long stops with an error (its rows are kept).
NO_WORKER_TIMEOUT = 120.0
WORKER_CHECK_INTERVAL = 5.0


def _run_tasks(client, tasks, results: ResultsFile, sweep: Sweep, report: SweepReport, bar):
    from distributed import as_completed

    from inerter.studies import sweep_task

    run = sweep_task.sendable()          # by value: each run reaches any worker (see sweep_task)
    futures = client.map(run, tasks, key=[f"inerter-run-{t['key']}" for t in tasks], pure=False)
    by_future = dict(zip(futures, tasks))
    finished = as_completed(futures)
    seen_workers = checked = time.monotonic()
    try:
        while not finished.is_empty():
            batch = finished.next_batch(block=False)
            if not batch:
                time.sleep(0.05)
                now = time.monotonic()
                if now - checked > WORKER_CHECK_INTERVAL:    # no worker left (killed, or none joined the scheduler)?
                    checked = now
                    if client.scheduler_info(n_workers=1).get("workers"):
                        seen_workers = now
                    elif now - seen_workers > NO_WORKER_TIMEOUT:
                        raise SweepError(f"no dask worker for {NO_WORKER_TIMEOUT:.0f} s with {len(finished.futures)}"
                                         f" runs left; the finished runs are in {results.path}: start the sweep "
                                         "again to run the others")
                continue
            for future in batch:
                _record(future, by_future[future], results, sweep, report, bar)
    finally:
        client.cancel([f for f in futures if not f.done()])


def _record(future, task, results: ResultsFile, sweep: Sweep, report: SweepReport, bar):
    try:
        row = future.result()
    except Exception as exc:   # the worker died (KilledWorker) or the task was lost
        row = {"key": task["key"], "scene": task["name"], "model": task["model"],
               **(task.get("written") or task["overrides"]),
               "status": "failed", "error": f"{type(exc).__name__}: {exc} (run again with --retry-failed)",
               "finished_at": datetime.now(timezone.utc).isoformat(timespec="microseconds")}
    future.release()
    if "environment_error" in row:            # a worker that cannot run inerter: no run is to blame
        raise SweepError(row["environment_error"])
    results.append(row, parameters=sweep.parameter_columns)
    report.rows.append(row)
    if row["status"] == "ok":
        report.ok += 1
    else:
        report.failed += 1
    bar.set_postfix_str(f"ok {report.ok}, failed {report.failed}, skipped {report.skipped}", refresh=False)
    bar.update(1)


# ----------------------------------------------------------------------------------------------
# Plotting any metric against any parameter
# ----------------------------------------------------------------------------------------------
def read_results(path) -> tuple[list[str], list[str], list[dict]]:
    """(parameter columns, metric columns, rows) of a results file."""
    columns, rows = ResultsFile.read(path)
    if "status" not in columns or "model" not in columns:
        raise SweepError(f"{path}: not a results file of inerter sweep (no model/status columns)")
    params = columns[columns.index("model") + 1:columns.index("status")]
    end = columns.index("run_time_s") if "run_time_s" in columns else len(columns)
    metrics = columns[columns.index("error") + 1:end] if "error" in columns else []
    return params, metrics, rows


def column_units(results) -> dict:
    """The units of a results file's columns, from the sweep.json beside it (``{}`` without one)."""
    try:
        units = json.loads((Path(results).parent / SWEEP_FILE).read_text(encoding="utf-8")).get("units")
    except (OSError, ValueError, AttributeError):
        return {}
    return units if isinstance(units, dict) else {}


def _label(name: str, units: dict) -> str:
    """An axis label: the column and its unit (none for a dimensionless one or a switch)."""
    from inerter.scene.units import for_reading
    unit = for_reading(units.get(name))
    return f"{name} ({unit})" if unit else name


def _number(text):
    if text in ("true", "false"):
        return float(text == "true")
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def plot_results(path, x: str, y: str, out, hue: str | None = None, title: str | None = None, ax=None):
    """`y` against `x` from a results file: one line per value of `hue` and of every other
    parameter that varies in the file (failed runs left out)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    params, metrics, rows = read_results(path)
    columns = params + metrics
    for flag, name in (("--x", x), ("--y", y), ("--hue", hue)):
        if name is not None and name not in columns:
            raise SweepError(f"{flag} {name}: not a column of {path}; parameters: {', '.join(params)}; "
                             f"metrics: {', '.join(metrics)}")
    ok = [r for r in rows if r.get("status") == "ok"]
    if not ok:
        raise SweepError(f"{path}: no finished run to plot (all {len(rows)} failed or none yet)")
    varying = [p for p in params if p not in (x, y) and len({r.get(p, "") for r in ok}) > 1]
    groups = [hue] if hue in varying else []
    groups += [p for p in varying if p != hue]
    series: dict[tuple, list] = {}
    for r in ok:
        series.setdefault(tuple(r.get(g, "") for g in groups), []).append((_number(r[x]), _number(r[y])))
    own = ax is None
    if own:
        fig, ax = plt.subplots(figsize=(7, 4.2))
    for label, points in sorted(series.items()):
        points.sort()
        xs, ys = zip(*points)
        text = ", ".join(f"{g} = {v}" for g, v in zip(groups, label)) or None
        style = {"marker": "o", "ms": 3.5, "lw": 1.3}
        if hue and label and label[0] == "false":
            style["ls"] = "--"
        ax.plot(xs, ys, label=text, **style)
    units = column_units(path)
    ax.set_xlabel(_label(x, units))
    ax.set_ylabel(_label(y, units))
    ax.grid(alpha=0.3)
    if any(label for label in series):
        ax.legend(fontsize=8)
    if own:
        ax.set_title(title or f"{y} against {x}")
        fig.tight_layout()
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(out, dpi=130)
        plt.close(fig)
    return out


# ----------------------------------------------------------------------------------------------
# Command lines
# ----------------------------------------------------------------------------------------------
def add_run_arguments(p: argparse.ArgumentParser):
    """Options shared by ``sweep`` and ``study``."""
    p.add_argument("--model", choices=MODELS, default="solver",
                   help="run each combination on the solver (default) or on the scene's FMU")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on a running dask scheduler (tcp://host:8786) instead of a local cluster")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="fix a parameter, effects.NAME or experiment.NAME for every run (repeatable)")
    p.add_argument("--stop-time", type=float, default=None, help="stop time of every run (s)")
    p.add_argument("--step", type=float, default=None, help="FMU communication step (s), with --model fmu")
    p.add_argument("--path", choices=PATHS, default="compiled",
                   help="with --model solver: the compiled path (default: numba kernels and integrator loops) "
                        "or the numpy one (the readable reference)")
    p.add_argument("--max-runs", type=int, default=None,
                   help="stop after this many new runs; run the same command again to go on")
    p.add_argument("--retry-failed", action="store_true", help="run the failed runs of results.csv again")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--dashboard", nargs="?", const=":8787", default=None, metavar="ADDRESS",
                   help="serve dask's dashboard (needs bokeh) at ADDRESS (default :8787; 127.0.0.1:0: any free "
                        "port) and print its link; with --scheduler, print that scheduler's link")


def check_fmu_step(step, model: str):
    """``--step`` is the FMU's communication step: without ``--model fmu`` it would be taken and do
    nothing (the solver's samples are its output interval). The one check of run, compare, sweep and
    study; `step`: as given (the typed text or a number), None when not given."""
    if step is not None and model != "fmu":
        raise OptionError("--step", step, "--model fmu beside it; the solver's samples are set by --set "
                          "experiment.output_interval=SECONDS", "the FMU's communication step, without --model fmu")


def check_run_arguments(args):
    """The options of ``sweep`` and ``study`` that no scene is needed to check, before anything runs."""
    output_folder(args.out)
    count(args.workers, "--workers")
    count(args.max_runs, "--max-runs", least=0)
    if args.scheduler:
        check_address(args.scheduler)


def check_address(address: str):
    """--scheduler's value read as distributed reads it (scheme, host and port; no connection)."""
    from distributed.comm.addressing import get_address_host_port
    try:
        get_address_host_port(address)
    except ValueError as exc:               # distributed's own words say why
        raise OptionError("--scheduler", address, "a scheduler's address, such as tcp://HOST:8786",
                          f"not an address: {exc}") from None


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill PID``), stopping a sweep as Ctrl-C does: the cluster closed, the rows kept."""


def _terminate(signum, frame):
    raise Terminated()


def _guarded(fn, argv):
    import signal
    main_thread = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _terminate) if main_thread else None
    try:
        return fn(argv)
    except InerterError as exc:
        print(f"inerter: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:            # an output file that cannot be written (as inerter run says it)
        print(f"inerter: error: {unwritable(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        print(f"inerter: {'terminated' if isinstance(exc, Terminated) else 'interrupted'}; the runs that finished "
              "are in results.csv: run the same command again to go on", file=sys.stderr)
        return 143 if isinstance(exc, Terminated) else 130
    finally:
        if main_thread:
            signal.signal(signal.SIGTERM, previous)


def print_report(report: SweepReport, sweep: Sweep):
    text = (f"{sweep.name}: {report.total} runs: {report.ok + report.failed} run now ({report.failed} failed), "
            f"{report.skipped} already in {report.results}")
    if report.failed_before:
        text += f" ({report.failed_before} of them failed)"
    if report.pending:
        text += f", {report.pending} left (run the same command again to go on)"
    print(text)
    for row in report.rows:
        if row["status"] != "ok":
            values = ", ".join(f"{n} = {_cell(row.get(n))}" for n, _ in sweep.axes)
            print(f"  failed: {values}: {row['error']}")
    print(f"wrote {report.results} in {report.wall_time:.1f} s")


def status_code(report: SweepReport) -> int:
    """0: every run of the sweep so far is ok; 3: some failed (as ``inerter run``)."""
    return 3 if report.failed or report.failed_before else 0


def sweep_parser() -> argparse.ArgumentParser:
    """The options of ``inerter sweep``."""
    p = Parser(prog="inerter sweep", description="Run every combination of the varied "
               "parameters in parallel on dask; rows go to DIR/results.csv as runs finish.")
    p.add_argument("scene", help="the scene file (TOML)")
    p.add_argument("--vary", action="append", required=True, metavar="NAME=START:STOP:NUM",
                   help="a parameter, effects.NAME or experiment.NAME and its values: START:STOP:NUM "
                        "(evenly spaced) or V1,V2,... (repeatable: every combination is run)")
    p.add_argument("--out", required=True, metavar="DIR", help="folder of results.csv (resumed if present)")
    add_run_arguments(p)
    return p


def _sweep(argv) -> int:
    from inerter.scene.overrides import parse_set, set_origins
    args = sweep_parser().parse_args(argv)
    check_run_arguments(args)
    sweep = Sweep(args.scene, [parse_vary(v) for v in args.vary], parse_set(args.set), args.model,
                  args.stop_time, args.step, args.path, origins=set_origins(args.set))
    report = run_sweep(sweep, args.out, workers=args.workers, scheduler=args.scheduler,
                       progress=not args.no_progress, max_runs=args.max_runs, retry_failed=args.retry_failed,
                       dashboard=args.dashboard)
    print_report(report, sweep)
    return status_code(report)


def sweep_plot_parser() -> argparse.ArgumentParser:
    """The options of ``inerter sweep-plot``."""
    p = Parser(prog="inerter sweep-plot", description="Plot a metric of a sweep against a "
               "varied parameter.")
    p.add_argument("results", help="results.csv of a sweep")
    p.add_argument("--x", required=True, help="a parameter column (e.g. y0)")
    p.add_argument("--y", required=True, help="a metric column (e.g. fundamental_frequency)")
    p.add_argument("--hue", default=None, help="one line per value of this parameter (e.g. effects.centripetal)")
    p.add_argument("--out", default=None, metavar="PNG",
                   help="the PNG to write (default: beside RESULTS, named <y>_vs_<x>.png)")
    p.add_argument("--title", default=None, help="the plot's title (default: '<y> against <x>')")
    return p


def _sweep_plot(argv) -> int:
    args = sweep_plot_parser().parse_args(argv)
    if args.out is not None:
        output_folder(args.out, file=True)
    out = args.out or Path(args.results).parent / f"{_file_part(args.y)}_vs_{_file_part(args.x)}.png"
    out = plot_results(args.results, args.x, args.y, out, hue=args.hue, title=args.title)
    print(f"wrote {out}")
    return 0


def _file_part(name: str) -> str:
    """A column name as part of a file name (``effects.centripetal`` stays, ``C.r[2]`` → ``C.r_2_``)."""
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in name)


def main_sweep(argv=None) -> int:
    """``inerter sweep``: exit 0 (all ok), 3 (some runs failed, recorded), 2 (bad arguments)."""
    return _guarded(_sweep, argv)


def main_sweep_plot(argv=None) -> int:
    """``inerter sweep-plot``: exit 0, or 2 for an unknown column or an unreadable file."""
    return _guarded(_sweep_plot, argv)
