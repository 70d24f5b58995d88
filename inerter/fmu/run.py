"""Running a scene through its FMU with fmpy: ``inerter run SCENE --model fmu``.

The FMU is built first if it is stale, then simulated by ``fmpy.simulate_fmu`` with an explicit
communication step (fmpy ignores ``step_size`` for co-simulation and would otherwise choose one).
The result has the same interface as the solver's (time, ``result[name]``, metrics, CSV, summary).
Its metrics and events read the FMU's own dense output between the samples, from a second instance
of the FMU stepped to the times they read (:mod:`inerter.fmu.dense`): at the run's accuracy, as the
solver's. Where the FMU restarts its integration at every communication point (RK4, LSODA, the
``projection`` treatment) they read a cubic spline through the samples, as the solver's RK4 runs.
"""
from __future__ import annotations

import time as _time
from dataclasses import dataclass, field

import numpy as np

from inerter.common.errors import SceneError
from inerter.engine.simulation import Settings
from inerter.fmu.dense import FmuDense, reads_the_fmu
from inerter.api import (Model, Result, at_times, compute_metrics, csv_header, output_units, sample_spline,
                         to_dataframe, unknown_output)


@dataclass
class FmuRunInfo:
    """How an FMU run went (the solver's `Run` has the same fields, for the summaries)."""
    steps: int
    evaluations: int
    cpu_time: float
    max_drift: float
    status: str
    message: str
    extra: dict = field(default_factory=dict)


#: fmpy's default logger, kept for the process (see :func:`_restore_fmpy_logger`).
_FMPY_DEFAULT_LOGGER = []


def _restore_fmpy_logger():
    """Point fmpy's logger proxy back at its default logger, one kept alive for the process.

    fmpy (0.3) formats an FMU's message in a native proxy that calls the logger registered last: a
    ``fmpy.simulate_fmu(..., logger=f)`` registers a callback that is freed when the call returns,
    and an FMU instantiated afterwards with fmpy's default callbacks (FmuDense's second instance,
    an importer's own FMU2Slave) then calls freed memory the first time it logs (a segmentation
    fault on an error's message)."""
    from ctypes import byref

    from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, printLogMessage
    from fmpy.logging import addLoggerProxy
    if not _FMPY_DEFAULT_LOGGER:
        callbacks = fmi2CallbackFunctions()
        callbacks.logger = fmi2CallbackLoggerTYPE(printLogMessage)
        _FMPY_DEFAULT_LOGGER.append(callbacks)
    addLoggerProxy(byref(_FMPY_DEFAULT_LOGGER[0]))


def solver_item(method: str) -> int:
    """The value of the FMU's ``solver`` Enumeration item for an integration method (1, 2, ...)."""
    return list(Model.methods).index(method) + 1


#: ``experiment.NAME`` overrides that an FMU run takes from the loaded scene rather than as start
#: values: the importer's stop time and communication step (by default the output interval).
RUN_SETTINGS = ("experiment.stop_time", "experiment.output_interval", "experiment.communication_step")
#: ``experiment.NAME`` overrides that are parameters of the FMU, by the FMU's name.
FMU_SETTINGS = {"experiment.method": "solver", "experiment.rtol": "rtol", "experiment.atol": "atol"}


def start_values(model: Model, overrides: dict) -> dict:
    """FMU start values for the overrides that ``inerter.load`` took: each the value the scene
    reader made of it, in the FMU's SI units (``b=2*pi`` or ``{value = 2, unit = "kN/m"}`` arrive
    as numbers); the run settings (RUN_SETTINGS) are the caller's, not start values."""
    scene = model.scene
    experiment = {"solver": scene.experiment.method, "rtol": scene.experiment.rtol, "atol": scene.experiment.atol}
    out = {}
    for key in overrides:
        if key in scene.parameters:
            out[key] = scene.parameters[key].value
        elif key.startswith("effects.") and key[len("effects."):] in ("centripetal", "small_displacement"):
            out[key] = bool(getattr(scene, key[len("effects."):]))
        elif key == "experiment.method":             # the solver Enumeration's item (1, 2, ...)
            out["solver"] = solver_item(experiment["solver"])
        elif key in FMU_SETTINGS:
            out[FMU_SETTINGS[key]] = experiment[FMU_SETTINGS[key]]
        elif key not in RUN_SETTINGS:
            raise SceneError(f"{scene.source} (FMU)", key, overrides[key],
                             "a parameter of the scene, effects.centripetal, effects.small_displacement, "
                             + ", ".join(FMU_SETTINGS) + " (FMU parameters) or " + ", ".join(RUN_SETTINGS)
                             + " (the run's)", "not settable on the FMU")
    return out


class FmuResult:
    """Samples at the communication points, with the solver Result's interface."""

    def __init__(self, model, table, settings, run, comm_step):
        self.model = model
        self.settings = settings
        self.run = run
        self.time = np.asarray(table["time"], dtype=float)
        self.names = [n for n in model.signals.names if n in table.dtype.names]
        self._table = table
        self.status = run.status
        self.message = run.message
        self.metrics = {}
        self.metric_errors = {}
        self.communication_step = comm_step
        #: The FMU stepped again where a metric reads it (:class:`inerter.fmu.dense.FmuDense`), or
        #: None: a spline through the samples.
        self.fmu_dense = None
        self._nodes = None                  # _event_nodes', once computed

    def __getitem__(self, name):
        self._check(name, f"result[{name!r}]")
        return np.asarray(self._table[name], dtype=float)

    #: The scene's warnings and the derived outputs without value at some samples, as the solver's.
    warnings = Result.warnings
    _unreached_record_warnings = Result._unreached_record_warnings

    def dense(self, name):
        """A callable t ↦ output(t): the FMU's own dense output (a second instance stepped to the
        times asked for, :class:`inerter.fmu.dense.FmuDense`), or, where the FMU restarts its
        integration at every communication point, a cubic spline through the samples. Times as
        the solver's :meth:`inerter.api.Result.dense` takes them (:func:`inerter.api.at_times`)."""
        what = f"{self.model.name} (FMU): dense({name!r})"
        self._check(name, f"dense({name!r})")
        if self.fmu_dense is not None and name in self.fmu_dense.names():
            return at_times(lambda t: self.fmu_dense.values(name, t), self.time, what)
        return at_times(sample_spline(self.time, self[name], name, self.__getitem__), self.time, what)

    def _check(self, name, call):
        if name not in self.names:
            raise unknown_output(f"{self.model.source} (FMU)", call, name, self.names)

    def events(self):
        """Device events (:meth:`inerter.api.Result.events`), their times refined on :meth:`dense`."""
        try:
            return Result.events(self)
        finally:
            self.close()

    def _event_nodes(self) -> np.ndarray:
        """The FMU's integrator's step ends, where :meth:`events` brackets crossings beside the
        communication points: an FMU that reads its own dense output keeps one integration across
        its communication points, clipped only at the stop time, on the solver's compiled loop, so
        the solver's run with the same settings and start values takes the same steps (their
        outputs agree bit for bit, tests/test_fmu_dense.py). The values bracketed and refined there
        are the FMU's own (:meth:`dense`). Elsewhere (the FMU restarting at each communication
        point) none: its samples only. The solver runs once per result; later calls take its nodes."""
        if self.fmu_dense is None:
            return np.zeros(0)
        if self._nodes is None:
            s = self.settings
            run = self.model.simulate(stop_time=s.stop_time, output_interval=s.output_interval, method=s.method,
                                      rtol=s.rtol, atol=s.atol, constraint=s.constraint, metrics=False)
            self._nodes = run._event_nodes()
        return self._nodes

    def read_the_fmu(self, fmu_path, start_values, instance=None):
        """Let :meth:`dense` read the FMU itself (:class:`inerter.fmu.dense.FmuDense`: the run's FMU,
        start values and stop time; `instance`, one to reset and step again) where its integration
        runs across communication points; elsewhere it stays a spline through the samples."""
        if reads_the_fmu(self.settings):
            self.fmu_dense = FmuDense(fmu_path, start_values, self.settings.stop_time, self, instance)

    def compute_metrics(self):
        """The scene's metrics on :meth:`dense`, into :attr:`metrics`; then the second instance freed."""
        try:
            self.metrics = compute_metrics(self.model, self)
        finally:
            self.close()

    def close(self):
        """Free the second FMU instance :meth:`dense` reads (a later call makes it again)."""
        if self.fmu_dense is not None:
            self.fmu_dense.close()

    def summary(self):
        out = Result.summary(self)
        out["settings"]["model"] = "fmu"
        out["settings"]["communication_step"] = self.communication_step
        return out

    def units(self) -> dict[str, str]:
        return output_units(self)

    def values(self) -> np.ndarray:
        """Every output at every communication point (samples × outputs, in the order of ``names``), as
        the solver's (``Result.values``)."""
        return np.column_stack([self[n] for n in self.names]) if self.names else np.zeros((len(self.time), 0))

    def write_csv(self, path):
        """As the solver's (``Result.write_csv``): units in the header, ``time (s),C.r[1] (m),...``."""
        data = np.column_stack((self.time, self.values()))
        np.savetxt(path, data, delimiter=",", header=csv_header(self), comments="", fmt="%.12g")

    def to_dataframe(self):
        return to_dataframe(self)


def simulate_fmu(scene, overrides=None, stop_time=None, step=None, fmu_path=None, metrics=True):
    """Run the scene `scene` through its FMU with fmpy (``inerter run SCENE --model fmu``) and
    return an :class:`FmuResult`: time, ``result[name]``, metrics, ``summary()``, ``write_csv``,
    ``to_dataframe``, as the solver's :class:`~inerter.api.Result`.

    `overrides` as :func:`inerter.load` takes them, set as the FMU's start values; `stop_time`
    and `step` (the communication step, which is also the output interval) override the scene's
    ``[experiment]`` and are checked as its fields are. `fmu_path`: an FMU to run; by default the
    scene's, built into ``build/fmu`` first where it is stale. With `metrics`, the scene's metrics
    and events read the FMU's own dense output (:mod:`inerter.fmu.dense`)."""
    import fmpy

    from inerter.fmu.build import build

    overrides = dict(overrides or {})
    model = Model(scene, overrides)                  # validates the overrides with the solver's messages
    # the importer samples the FMU at its communication points: a step given is the output interval too
    given = {k: v for k, v in (("stop_time", stop_time), ("communication_step", step), ("output_interval", step))
             if v is not None}
    experiment = (model.scene.experiment_with(given, source=f"{model.source}: simulate_fmu()") if given
                  else model.scene.experiment)
    settings = Settings.from_experiment(experiment)
    comm = experiment.communication_step
    fmu_file = fmu_path or build(scene)
    messages = []

    def logger(component, instance, status, category, message):
        messages.append(message.decode(errors="replace") if isinstance(message, bytes) else str(message))

    outputs = [n for n in model.signals.names]
    starts = start_values(model, overrides)
    t0 = _time.process_time()
    try:
        table = fmpy.simulate_fmu(str(fmu_file), stop_time=settings.stop_time, output_interval=comm,
                                  start_values=starts, output=outputs,
                                  logger=logger, debug_logging=True)   # so the FMU's messages reach `logger`
    finally:
        _restore_fmpy_logger()                    # `logger`'s callback is freed with the call
    cpu = _time.process_time() - t0
    t_last = float(table["time"][-1]) if len(table) else 0.0
    ok = abs(t_last - settings.stop_time) <= 1e-9 * max(1.0, settings.stop_time)
    message = "completed" if ok else (f"the FMU stopped at t = {t_last:.9g} s: " + ("; ".join(messages[-3:])
                                      or "a step was discarded"))
    run = FmuRunInfo(steps=len(table) - 1, evaluations=0, cpu_time=cpu,
                  max_drift=float(np.max(table["constraint_residual"])) if len(table) else 0.0,
                  status="ok" if ok else "failed", message=message)
    # the FMU's log of exitInitializationMode names the path its stepper took
    path = next((p for p in ("compiled", "numpy") if any(f"{p} path" in m for m in messages)), None)
    run.extra["path"] = f"FMU ({path} path)" if path else "FMU"
    result = FmuResult(model, table, settings, run, comm)
    if ok:
        result.read_the_fmu(fmu_file, starts)
        if metrics:
            result.compute_metrics()
    return result
