"""The Python entry point: ``model = inerter.load(scene, **overrides)``, ``model.simulate(...)``.

A :class:`Model` holds the validated scene and its compiled mechanism (fast path). The oracle is
the same scene compiled with ``oracle=True`` and solved at tight tolerance.
"""
from __future__ import annotations

import re
import subprocess as _subprocess
import sys as _sys
import threading
import time as _time
from pathlib import Path
from typing import Any

import numpy as np

from inerter.engine import metrics as metric_fns
from inerter.engine.events import declares_events, device_events
from inerter.engine.equilibrium import natural_frequencies, static_equilibrium
from inerter.model.mechanism import Mechanism
from inerter.elements.device import MODE_SOLVES
from inerter.oracle import OracleMechanism, require_definitions
from inerter.engine.outputs import Signals
from inerter.scene.reader import KNOWN_EFFECTS, METHODS, closest_name, load_scene
from inerter.scene.units import for_reading
from inerter.common.errors import InerterError, SceneError, SimulationError, shown
from inerter.engine.simulation import (SCIPY_RTOL_FLOOR, Settings, Stepper, dense_windings, for_run,
                                      integrate, numpy_mechanism)

#: Tolerances at which the oracle is solved (DOP853).
ORACLE_RTOL = 1e-12
ORACLE_ATOL = 1e-14
#: Kinds of [[metrics]] that read their signal between the samples (through ``Result.dense``) over
#: whole windows: the compiled run keeps its dense output at every step for them. A peak reads it
#: only around its candidates, which a run's LocalDense integrates again (engine.compiled).
DENSE_METRICS = ("free_oscillation", "harmonics", "steady_state")
#: Held while a model's static equilibrium, natural frequencies or static values are worked out
#: (once per model; re-entered: the frequencies start from the equilibrium).
_ANALYSES = threading.RLock()
#: The experiments a Model keeps read, by their overrides (a sweep of tolerances calls simulate with
#: each again): reading one evaluates the scene's [experiment] expressions (about 0.1 ms).
EXPERIMENTS_KEPT = 32


def load(path, **overrides) -> "Model":
    """Load a scene file. Overrides, Modelica-modifier style: a parameter by name (``b=20``), an
    effect (``**{"effects.centripetal": False}``) or an experiment setting (``experiment.rtol``).
    A value the scene refuses is named with the override that gave it (``override b=-1: ...``)."""
    return Model(path, overrides)


class Model:
    """A scene read, validated and compiled (:func:`load` makes one).

    Description: ``name``, ``source``, ``experiment`` (the scene's settings), ``terms()`` (what
    was compiled), ``parameter_info()``, ``effect_info()``, ``input_info()``, ``output_info()``
    (what ``inerter describe`` prints, ``describe()`` as its text), ``tunable_parameters()``. Analysis:
    ``static_equilibrium()``, ``natural_frequencies()`` (Hz), ``static_value(signal)``. Runs:
    ``simulate(...)`` (a :class:`Result`), ``stepper(...)`` (co-simulation steps, as an FMU
    takes them), ``oracle()`` (the same scene with the oracle's forces),
    ``with_overrides(**more)``."""
    methods = METHODS

    def __init__(self, path, overrides: dict[str, Any] | None = None, oracle: bool = False,
                 origins: dict[str, str] | None = None):
        """`origins`: where each override came from, as its errors name it (``{"b": "--set b=20"}``;
        default ``override b=20``)."""
        self.path = Path(path)
        self.overrides = dict(overrides or {})
        self.origins = dict(origins or {})
        self.scene = load_scene(self.path, self.overrides, self.origins)
        if oracle:                        # a kind without the oracle's own definition: refused, by name
            require_definitions(self.scene)
        self.mechanism = OracleMechanism(self.scene) if oracle else Mechanism(self.scene)
        self.signals = Signals(self.mechanism)
        self.is_oracle = oracle
        self._static = None
        self._frequencies = None          # natural_frequencies(), once asked for
        self._static_values = {}          # static_value(signal), once asked for
        self._experiments = {}            # settings(): the experiment read with each set of overrides
        self._analysis_mechanism = None   # _analysed()

    # -- description -------------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self.scene.name

    @property
    def source(self) -> str:
        return self.scene.source

    @property
    def experiment(self) -> dict:
        x = self.scene.experiment
        return dict(stop_time=x.stop_time, output_interval=x.output_interval, method=x.method, rtol=x.rtol,
                    atol=x.atol, constraint=x.constraint, baumgarte=x.baumgarte,
                    communication_step=x.communication_step, step=x.step)

    def terms(self) -> list[str]:
        """What the scene compiled, one line each (dimension and coordinates, joints, elements,
        forces, gravity): the "compiled terms" of ``inerter describe``."""
        return self.mechanism.terms()

    def parameter_info(self):
        """Each parameter's value in SI with its SI unit (as the FMU declares it), its description,
        and ``given``: the value as the scene wrote it where its unit is not SI ("1500 mm")."""
        return [dict(name=p.name, value=p.value, unit=p.unit, description=p.description, given=p.given)
                for p in self.scene.parameters.values()]

    def effect_info(self):
        """Boolean effect switches (``effects.centripetal``), present when the scene has inerters."""
        info = []
        for name in ("centripetal", "small_displacement"):
            if self.mechanism.inerters or name in self.scene.effects:
                info.append(dict(name=f"effects.{name}", value=bool(getattr(self.scene, name)),
                                 description=KNOWN_EFFECTS[name]))
        return info

    def tunable_parameters(self) -> list[str]:
        """The parameters and effect switches a running stepper takes between steps
        (``Stepper.retune``): each one that changes the model, and only in element coefficients,
        point-force values, amplitudes, frequencies or gains, or the centripetal switch, found by
        reading the scene with it changed. The others need a new
        model (geometry, masses, free lengths...), or change nothing in it (the experiment's)."""
        from inerter.engine.tables import untunable_changes
        from inerter.scene.changes import differences
        out = []
        # a changed value above and one below (a bounded number, an efficiency η ≤ 1, refuses the first)
        trials = [(p.name, (1.5 * p.value + 1.0, 0.5 * p.value)) for p in self.scene.parameters.values()]
        trials += [(e["name"], (not e["value"],)) for e in self.effect_info()]
        for name, values in trials:
            for value in values:
                try:
                    changed = load_scene(self.path, {**self.overrides, name: value})
                except SceneError:
                    continue                 # a changed value the scene refuses: try the next one
                if differences(self.scene, changed) and not untunable_changes(self.scene, changed):
                    out.append(name)
                break
        return out

    def input_info(self):
        """The FMU inputs the scene declares (``C.f[2]`` of an input force, ``ground.a[1]`` of an
        input ground motion): name, SI unit and description each."""
        info = []
        for n in self.mechanism.input_names:
            axis = n[n.index("[") + 1]
            if n.startswith("ground.a["):
                info.append(dict(name=n, unit="m/s2", description=f"ground acceleration, global axis {axis}, "
                                 "held over each communication step"))
            else:
                info.append(dict(name=n, unit="N", description=f"force at point {n.split('.')[0]}, global "
                                 f"axis {axis}, held over each communication step"))
        return info

    def output_info(self):
        """Every output (docs/scene_format.md, Outputs; derived outputs included), in the CSV's
        column order: name, SI unit, description and ``reads_accelerations`` each (an output read
        from the accelerations, as an inerter's force, which an FMU declares dependent on its inputs)."""
        return self.signals.info()

    def describe(self) -> str:
        """What ``inerter describe`` prints: the name and description, the compiled terms, the
        parameters (SI, with the value as written where its unit is not SI), inputs and outputs."""
        lines = [f"{self.name}: {self.scene.description}" if self.scene.description else self.name, "compiled terms:"]
        lines += ["  " + line for line in self.terms()]
        lines.append("parameters:")
        for p in self.parameter_info():
            given = f" (given as {p['given']})" if p.get("given") else ""
            unit = for_reading(p["unit"])
            text = f"  {p['name']} = {p['value']:g}{' ' + unit if unit else ''}{given}"
            lines.append(f"{text}  {p['description']}" if p["description"] else text)
        lines.append("inputs: " + (", ".join(i["name"] for i in self.input_info()) or "none"))
        lines.append("outputs: " + ", ".join(o["name"] for o in self.output_info()))
        return "\n".join(lines)

    def with_overrides(self, **more) -> "Model":
        merged = dict(self.overrides)
        merged.update(more)
        return Model(self.path, merged, oracle=self.is_oracle, origins=self.origins)

    def oracle(self) -> "Model":
        """The same scene with element forces from the definitions (module `oracle`)."""
        return Model(self.path, self.overrides, oracle=True, origins=self.origins)

    # -- analysis ----------------------------------------------------------------------------
    # The analyses below run once per model, on a copy of its mechanism of their own
    # (_analysed), one thread at a time: runs of the model in other threads (each on its own copy,
    # Mechanism.for_run) and their metrics, which ask for them, change nothing of each other's.
    def static_equilibrium(self):
        with _ANALYSES:
            if self._static is None:
                self._static = static_equilibrium(self._analysed())
            return self._static

    def natural_frequencies(self):
        with _ANALYSES:
            if self._frequencies is None:
                self._frequencies = natural_frequencies(self._analysed(), self.static_equilibrium())
            return self._frequencies

    def static_value(self, signal: str) -> float:
        with _ANALYSES:
            if signal not in self._static_values:
                q = self.static_equilibrium()
                signals = self.signals.for_run(self._analysed())
                self._static_values[signal] = signals.function(signal)(0.0, q, np.zeros(self.mechanism.n))
            return self._static_values[signal]

    def _analysed(self):
        """The analyses' own copy of the mechanism (made at the first, under _ANALYSES)."""
        if self._analysis_mechanism is None:
            self._analysis_mechanism = for_run(self.mechanism)
        return self._analysis_mechanism

    # -- simulation --------------------------------------------------------------------------
    def settings(self, call: str = "simulate()", **overrides) -> Settings:
        """The scene's experiment with `overrides` (None: the scene's value), read and checked by
        the scene reader's function for ``[experiment]`` (errors name the `call` and the field)."""
        given = {k: v for k, v in overrides.items() if v is not None}
        if not given:
            return Settings.from_experiment(self.scene.experiment)
        try:
            # each value with its type: True == 1 as keys, but a bool is refused where 1 is read
            key = (call, tuple(sorted((k, type(v).__name__, v) for k, v in given.items())))
            x = self._experiments.get(key)
        except TypeError:                 # a value that cannot be a key (read, and refused, below)
            key = x = None
        if x is None:
            x = self.scene.experiment_with(given, source=f"{self.source}: {call}")
            if key is not None:
                if len(self._experiments) >= EXPERIMENTS_KEPT:
                    self._experiments.clear()
                self._experiments[key] = x
        return Settings.from_experiment(x)

    def simulate(self, stop_time=None, output_interval=None, method=None, rtol=None, atol=None,
                 constraint=None, step=None, metrics=True, path="compiled") -> "Result":
        """Integrate from the initial state. `path`: "compiled" (the default: numba kernels and
        integrator loops, :mod:`inerter.engine.compiled`, 2D and 3D; the implicit methods, Radau, BDF
        and LSODA, and the projection treatment run scipy's integrators on the compiled right-hand
        side, and ``result.run.extra["path"]`` says so) or "numpy" (the readable reference). The
        oracle always runs its own numpy evaluation.
        With `metrics`, the scene's [[metrics]] are computed from the integrator's dense output (the
        compiled loop keeps it at every step for a metric that reads whole windows of it, and for a
        scene with device events, whose times it refines: :meth:`Result.events`; a peak reads it
        only around its candidates, whose sample intervals are integrated again)."""
        s = self.settings(stop_time=stop_time, output_interval=output_interval, method=method, rtol=rtol,
                          atol=atol, constraint=constraint, step=step)
        if path == "compiled" and not self.is_oracle:
            from inerter.engine import compiled
            try:
                dense = (bool(metrics) and self._metrics_need_dense()) or self._events_need_dense()
                run = compiled.integrate_compiled(self.mechanism, s, dense=dense)
            except (ZeroDivisionError, FloatingPointError, OverflowError) as exc:
                # The compiled loop raises where the state overflows (its error norm turns 0 or NaN);
                # the numpy path stops where the state stops being finite and says so.
                run = integrate(self.mechanism, s)
                run.extra["path"] = f"numpy (the compiled loop stopped on {type(exc).__name__}: the state overflowed)"
        elif path in ("numpy", "compiled"):
            run = integrate(self.mechanism, s)
        else:
            raise SceneError("simulate()", "path", path, "'numpy' or 'compiled'", "unknown path")
        result = Result(self, s, run)
        if metrics and run.status == "ok":
            result.metrics = compute_metrics(self, result)
        return result

    def _metrics_need_dense(self) -> bool:
        """Whether a metric of the scene reads its signal between the samples."""
        return any(m.kind in DENSE_METRICS for m in self.scene.metrics)

    def _events_need_dense(self) -> bool:
        """Whether the scene has device events (end stops, backlash: :mod:`inerter.engine.events`),
        whose times are refined on the dense output."""
        return declares_events(self.scene)

    def stepper(self, method=None, rtol=None, atol=None, path="compiled", stop_time=None) -> Stepper:
        """A co-simulation stepper at t = 0. `path` = "compiled" (the default): each step one call
        of the compiled integrator loop where :func:`inerter.engine.compiled.compiled_stepper` can
        take the scene (DOP853, RK45, RK4); with an implicit method or the projection treatment,
        scipy's stepper on the compiled right-hand side; both have ``stepper.path`` "compiled", the
        numpy stepper where the kernels do not take the scene "numpy"; `path` "numpy": the
        readable reference. On both paths the adaptive integrators run on across communication
        points, their steps clipped to `stop_time` where it is given."""
        s = self.settings("stepper()", method=method, rtol=rtol, atol=atol)
        if path == "compiled" and not self.is_oracle:
            from inerter.engine import compiled
            stepper = compiled.compiled_stepper(self.mechanism, s, self.signals, stop_time)
            if stepper is not None:
                return stepper
            if not compiled.unsupported(self.mechanism):
                # an implicit method or the projection treatment: scipy's steppers on the kernels'
                # right-hand side, as a whole run takes them (integrate_compiled)
                stepper = Stepper(compiled.kernel_mechanism(self.mechanism), s, self.signals, stop_time)
                stepper.path = "compiled"           # the engine's (one word: the FMU's log names it)
                return stepper
        elif path != "numpy" and path != "compiled":
            raise SceneError("stepper()", "path", path, "'numpy' or 'compiled'", "unknown path")
        return Stepper(self.mechanism, s, self.signals, stop_time)


def rtol_raised(result) -> list[str]:
    """A solver's run through scipy's integrators (the numpy path, the oracle, Radau, BDF, LSODA, the
    projection treatment) at an rtol below the smallest they take ran at that one: its note."""
    s = getattr(result, "settings", None)
    path = str(result.run.extra.get("path", ""))
    if not isinstance(s, Settings) or s.method == "RK4" or s.rtol >= SCIPY_RTOL_FLOOR \
            or path == "compiled" or path.startswith("FMU"):
        return []
    return [f"{result.model.source}: experiment.rtol: {s.rtol:g} is below the {SCIPY_RTOL_FLOOR:.3g} "
            f"(100 ε) scipy's {s.method} takes; it ran at {SCIPY_RTOL_FLOOR:.3g} (the compiled DOP853 "
            "and RK45 loops take down to 1e-14)"]


class UnknownOutput(InerterError, KeyError):
    """An output name a result does not have: a KeyError whose message reads as a scene error's
    (``str`` without the quotes KeyError puts around it)."""

    def __str__(self) -> str:
        return str(self.args[0])


def unknown_output(source, call, name, names) -> UnknownOutput:
    """The error of asking `call` (``result['C.r[3]']``, ``dense('C.r[3]')``) for `name`, not among
    the outputs `names` of the scene file `source`: the closest name, if one is close, then all."""
    close = closest_name(name, names)
    hint = f" (did you mean {close!r}?)" if close else ""
    return UnknownOutput(f"{source}: {call}: not an output{hint} (got {shown(name)}; expected an output "
                         "of the scene: " + ", ".join(names) + ")")


class Result:
    """A time history: ``result.time``, ``result["C.r[2]"]``, ``result.metrics``.

    Also ``status`` ("ok" or "failed") and ``message`` ("completed", or where and why a failed run
    stopped: it holds the samples up to there), ``metric_errors`` (why a metric was left out), ``warnings``,
    ``events()``, ``dense(name)`` (an output between the samples), ``units()``, ``summary()``
    (what summary.json holds), ``write_csv(path)`` and ``to_dataframe()``.

    The outputs are evaluated when first asked for: on a compiled run each signal on its own in
    the kernels (a point's coordinate from that point alone, accelerations only for a force that
    needs them), on the numpy path all of them at once. An output that cannot be evaluated at a
    sample (terminals met there, Eq. (33) singular there) ends the result before that sample,
    failed, when it is first asked for (``simulate`` asks for its metrics' signals)."""

    def __init__(self, model: Model, settings: Settings, run):
        self.model = model
        self.settings = settings
        self.run = run
        self.time = run.time
        self.status = run.status
        self.message = run.message
        self.metrics: dict[str, float] = {}
        self.metric_errors: dict[str, str] = {}
        self.names = list(model.signals.names)
        kernel = run.extra.get("kernel")             # a compiled run's outputs come from its kernels
        self._kernel = kernel if getattr(kernel, "compiled", False) else None
        self._values = None                          # every output at every sample, once asked for
        self._columns: dict[str, np.ndarray] = {}    # one output at every sample, once asked for
        self._own = None                             # (mechanism, signals) of the numpy evaluation

    def _evaluation(self):
        """(mechanism, signals) the numpy path reads this result's outputs on: the run's own copy of
        the model's mechanism (a numpy run's, as the run left it; ``integrate``), else a copy of its
        own (``Mechanism.for_run``); never the model's, whose other runs and steppers would see the
        angles and modes an evaluation sets."""
        if self._own is None:
            mech = self.run.extra.get("mechanism")
            mech = self.model.mechanism.for_run() if mech is None else numpy_mechanism(mech)
            self._own = (mech, self.model.signals.for_run(mech))
        return self._own

    def _all_values(self) -> np.ndarray:
        """Every output at every sample (time × signal), in the order of ``names``."""
        if self._values is not None:
            return self._values
        run, settings, sig = self.run, self.settings, self.model.signals
        values, start = [], 0
        kernel = self._kernel
        order = kernel.signal_order(sig) if kernel is not None else None
        if order is not None:
            compiled_values, start = kernel.signal_history(sig, order, run.time, run.states, None, settings.alpha,
                                                           self._windings())
            values = list(compiled_values)
        values += self._numpy_rows(start)
        self._values = np.array(values) if values else np.zeros((0, len(sig.names)))
        return self._values

    def _numpy_rows(self, start) -> list:
        """Every output at the samples from `start` on, by the numpy path's signals, up to a sample
        where they cannot be evaluated (the run is truncated there, with the message). The 3D
        rotational elements' angles are wound from the angle recorded with each sample
        (:meth:`_windings`; where none was, sample by sample from t = 0)."""
        run = self.run
        mech, sig = self._evaluation()
        n, nv = mech.nq, mech.nq + mech.n
        recorded = self._windings()
        rows = []
        with mech.wound_from_start():
            for y in (run.states[:start] if mech.winding and recorded is None else ()):
                mech.wind(y)
            for i in range(start, len(run.time)):
                t, y = run.time[i], run.states[i]
                try:
                    if recorded is not None:
                        mech.windings = recorded[i]
                    mech.wind(y)
                    rows.append(sig.evaluate(t, y[:n], y[n:nv], None, self.settings.alpha, z=y[nv:]))
                except SimulationError as exc:   # an output undefined at a sample: keep what came before
                    self._truncate(i, exc if exc.time is not None else SimulationError(exc.message, float(t)))
                    break
        return rows

    def values(self) -> np.ndarray:
        """Every output at every sample (samples × outputs, in the order of ``names``); outputs are
        otherwise evaluated one signal at a time, when first read."""
        return self._all_values()

    def _column(self, name) -> np.ndarray:
        """One output at every sample: in the kernels on a compiled run, up to a sample where it
        cannot be evaluated, from which the numpy path's signals give the values or the message."""
        if self.model.signals.is_derived(name):
            return self._derived_column(name)
        kernel = self._kernel
        index = kernel.signal_index(name) if kernel is not None else None
        if index is None:
            return self._all_values()[:, self.model.signals.index[name]]
        run, alpha = self.run, self.settings.alpha
        values, k = kernel.signal_column(index, run.time, run.states, None, alpha, self._windings())
        if k < len(run.time):
            j = self.model.signals.index[name]
            values = np.array(list(values) + [row[j] for row in self._numpy_rows(k)], dtype=float)
        self._columns[name] = values
        return values

    @property
    def warnings(self) -> list[str]:
        """The scene's warnings, one where screw efficiencies' modes did not settle at some
        evaluations (the run's count), and one for each derived output that has no value (NaN) at some
        samples: its expression is undefined there (a square root of a negative number, 0/0)."""
        notes = [n for n in self.model.scene.warnings if n not in self._unreached_record_warnings()]
        unsettled = self.run.extra.get("unsettled", 0)
        if unsettled:
            notes.append(f"{self.model.source}: device.efficiency: {unsettled} evaluations of the equations of "
                         f"motion kept a solve whose efficiency modes did not settle in {MODE_SOLVES} checks "
                         f"(several efficiency elements whose modes are coupled; inerter.elements.device)")
        for d in self.model.signals.derived:
            try:
                column = self[d.name]
            except KeyError:                      # an FMU run that did not record it
                continue
            missing = missing_values(self.time, column)
            if missing:
                notes.append(f"{self.model.source}: outputs.derived.{d.name}: {missing} "
                             f"(written as NaN): the expression is undefined there")
        notes += long_step_windings(self)
        notes += stops_at_start(self)
        notes += rtol_raised(self)
        return notes

    def _unreached_record_warnings(self) -> list[str]:
        """The ground record's warnings (its last value is not zero, so the acceleration steps to zero
        there) where the run ends before the record does: that step is never reached."""
        g = self.model.scene.effects.get("ground_acceleration")
        record = getattr(g, "record", None)
        if record is None or not len(self.time) or record[0][-1] < self.time[-1]:
            return []
        return list(g.warnings)

    def _derived_column(self, name) -> np.ndarray:
        """A derived output at every sample, from the columns of the outputs it reads (the values the
        CSV's row-wise evaluation gives: the same expression on the same numbers)."""
        signals = self.model.signals
        reads = {x: self[x] for x in signals.derived_reads(name)}
        k = len(self.time)                # reading one may have ended the result before a sample
        values = np.array(signals.derive(name, {x: column[:k] for x, column in reads.items()}), dtype=float)
        self._columns[name] = values
        return values

    def _truncate(self, i, exc):
        """The outputs cannot be evaluated from sample i on: the result ends before it, failed."""
        run = self.run
        run.time, run.states = run.time[:i], run.states[:i]
        run.message = str(exc) if run.message == "completed" else f"{exc}; the integrator had reported: {run.message}"
        run.status = "failed"
        self.time, self.status, self.message = run.time, run.status, run.message
        self._columns = {key: column[:i] for key, column in self._columns.items()}
        if self._values is not None:
            self._values = self._values[:i]

    def _check_name(self, name, call):
        if name not in self.model.signals.index:
            raise unknown_output(self.model.source, call, name, self.names)

    def __getitem__(self, name) -> np.ndarray:
        self._check_name(name, f"result[{name!r}]")
        if self._values is not None:
            return self._values[:, self.model.signals.index[name]]
        column = self._columns.get(name)
        return column if column is not None else self._column(name)

    def _windings(self):
        """(samples × elements) each 3D rotational element's angle at each sample on the branch its
        integration followed, recorded by the integrators from the end of the step that covers the
        sample (``run.extra["windings"]``), from which the sample's outputs are read, however many
        turns lie between two samples; None where the run recorded none (no such elements)."""
        recorded = self.run.extra.get("windings")
        return None if recorded is None else recorded[:len(self.time)]

    def _dense_windings(self, t):
        """(len(t) × elements) each 3D rotational element's angle at each time t of the dense output,
        from the step that gives it (:func:`inerter.engine.simulation.dense_windings`); None: none
        recorded."""
        return dense_windings(self.run, t, self._evaluation()[0])

    def dense(self, name):
        """A callable t ↦ signal(t), vectorised over t (a 1-D array of the values), through the
        integrator's dense output: on a compiled run, the states from the kept steps' polynomials
        (or, where the run kept none, from the sample intervals read, integrated again:
        ``engine.compiled.LocalDense``) and the signal from the kernels, in one compiled call; on the
        numpy path, scipy's dense output and the numpy signals; a compiled RK4 run's sample
        intervals read integrated again on its fixed steps (``engine.compiled.RK4Dense``). Where
        there is none: a cubic spline through the samples. A derived output:
        its expression on the dense values of the outputs it reads. A 3D rotational element's angle
        is read on the branch its integration followed in the step that gives each t, the times in
        any order (inerter.elements.winding). The times may have any shape (read flattened; none:
        an empty array); a NaN time reads NaN; a time outside the run's samples raises a
        ValueError (:func:`at_times`)."""
        return at_times(self._dense(name), self.time, f"{self.model.name}: dense({name!r})")

    def _dense(self, name):
        """:meth:`dense`'s callable, for a 1-D array of times, none of them NaN."""
        self._check_name(name, f"dense({name!r})")
        signals = self.model.signals
        if signals.is_derived(name):
            # the expression on the dense values of the outputs it reads, not a spline through its samples
            reads = {x: self._dense(x) for x in signals.derived_reads(name)}   # times checked by dense()
            return lambda t: np.array(signals.derive(name, {x: f(t) for x, f in reads.items()}), dtype=float)
        sol = self.run.dense
        if sol is None:
            return sample_spline(self.time, self[name], name, self.__getitem__)
        alpha = self.settings.alpha

        def numpy_values(t):
            mech, own_signals = self._evaluation()      # made where the numpy signals are read, not before
            fn = own_signals.function(name)
            n = mech.nq
            Y = sol(t)
            nv = n + mech.n
            values = []
            windings = self._dense_windings(t)
            with mech.wound_from_start():
                for i, ti in enumerate(t):
                    if windings is not None:
                        mech.windings = windings[i]
                    mech.wind(Y[:, i])
                    values.append(fn(ti, Y[:n, i], Y[n:nv, i], None, alpha, Y[nv:, i]))
            return np.array(values)

        kernel = self._kernel
        index = kernel.signal_index(name) if kernel is not None else None
        if index is None:
            return lambda t: numpy_values(np.atleast_1d(np.asarray(t, dtype=float)))

        reader = kernel.dense_reader(sol, index, alpha)

        def compiled_values(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            if reader is not None:
                values, k = reader(t)
            else:
                windings = self._dense_windings(t) if kernel.reads_windings(index) else None
                values, k = kernel.dense_signal(sol, index, t, None, alpha, windings)
            if k < len(t):            # not defined at t[k]: the numpy path's values, or its message
                values = np.concatenate((values, numpy_values(t[k:])))
            return values
        return compiled_values

    def events(self) -> list[dict]:
        """The device events of the run (end-stop contacts, backlash engagement), in time order,
        each {time, element, event, where}, times refined on the integrator's dense output
        (:func:`inerter.engine.events.device_events`); [] for a scene without any."""
        if not declares_events(self.model.scene) or len(self.time) < 2:
            return []
        nodes = self._event_nodes()
        nodes = nodes[(nodes >= self.time[0]) & (nodes <= self.time[-1])]
        return device_events(self.model.scene, np.concatenate((self.time, nodes)), self.dense)

    def _event_nodes(self) -> np.ndarray:
        """The integrator's step ends, where :meth:`events` brackets crossings beside the samples (a
        contact shorter than an output interval shortens the steps through it); none where the run
        keeps no dense output."""
        return np.asarray(getattr(getattr(self.run, "dense", None), "ts", np.zeros(0)), dtype=float)

    def summary(self) -> dict:
        """What a run was and how it went, as plain JSON values (``json.dumps`` needs no default):
        numbers, strings, lists and dicts; an effect held as an object (a ground motion) appears as
        its ``describe()`` text."""
        s = self.settings
        return _plain({
            "scene": self.model.name,
            "source": self.model.source,
            "status": self.status,
            "message": self.message,
            "metrics": self.metrics,
            "metric_units": {k: u for k, u in metric_units(self.model).items() if k in self.metrics},
            "metric_errors": self.metric_errors,
            "events": self.events(),
            "output_units": output_units(self),
            "warnings": self.warnings,
            "settings": {"stop_time": s.stop_time, "output_interval": s.output_interval, "method": s.method,
                         "rtol": s.rtol, "atol": s.atol, "constraint": s.constraint, "baumgarte": s.baumgarte,
                         "oracle": self.model.is_oracle,
                         "parameters": {p.name: p.value for p in self.model.scene.parameters.values()},
                         "effects": dict(self.model.scene.effects)},
            "statistics": {"path": self.run.extra.get("path", "numpy"),
                           "steps": self.run.steps, "evaluations": self.run.evaluations,
                           "cpu_time_s": self.run.cpu_time, "max_constraint_drift": self.run.max_drift,
                           "energy_start": float(self["energy"][0]) if len(self.time) else None,
                           "energy_end": float(self["energy"][-1]) if len(self.time) else None},
        })

    def units(self) -> dict[str, str]:
        """The unit of each output, by name (``time`` in s): the CSV header's and the summary's."""
        return output_units(self)

    def write_csv(self, path):
        """Time and every output, one row per sample; the header names each column with its unit in
        parentheses (``time (s),C.r[1] (m),...``), one header row, so that spreadsheets and
        ``pandas.read_csv`` read it as it is."""
        values = self._all_values()
        np.savetxt(path, np.column_stack((self.time, values)), delimiter=",", header=csv_header(self),
                   comments="", fmt="%.12g")

    def to_dataframe(self):
        """The time history as a pandas DataFrame (pandas is optional: ``pip install pandas``)."""
        return to_dataframe(self)


def long_step_windings(result) -> list[str]:
    """A note for each 3D rotational element whose relative rotation may turn by more than half a
    turn within one step of RK4 (|ω_rel| at the samples times experiment.step, more than π). Its
    angle is wound on at every accepted step (the branch its rates carry it to: kernels.wind3_step),
    and every output reads it wound from the angle its integrator held at the step that covers it,
    so neither the output interval nor a long step loses turns in the outputs; but within a step
    the stages read the angle on the branch nearest the step's start, and a stage more than half a
    turn from it reads a spring's torque whole turns off. The adaptive methods' error control
    rejects such a step where that torque matters (it jumps by 2πk); RK4's fixed step is taken as
    it is, and known here (docs/hard_cases.md)."""
    notes = []
    settings = result.settings
    if settings.method != "RK4" or len(result.time) < 2:
        return notes
    step = float(settings.step)
    for e in result.model.mechanism.winding:
        try:
            rate = np.abs(result[f"{e.name}.w_rel"])
        except KeyError:                      # an FMU run that did not record it
            continue
        k = int(np.argmax(rate))
        if rate[k] * step > np.pi:
            notes.append(f"{result.model.source}: elements.{e.name}: its relative rotation turns by up to "
                         f"{rate[k] * step:.3g} rad in one RK4 step of experiment.step = {step:.3g} s (at t = "
                         f"{result.time[k]:.6g} s), more than half a turn: within a step its angle is read within "
                         f"half a turn of the step's start, so a spring's torque there may be whole turns off; take "
                         f"experiment.step below pi/max|w_rel| = {np.pi / float(rate[k]):.3g} s")
    return notes


#: A device's terminal distance at t = 0 past an end stop by at most this fraction of it is the
#: round-off of a pose that starts at the stop, not noted (:func:`stops_at_start`).
STOP_START_SLACK = 1e-9


def stops_at_start(result) -> list[str]:
    """A note for each inerter device whose terminal distance at t = 0 lies past one of its end stops
    (inerter.elements.device, "End stops"): it starts pressed into the stop, with the contact's force
    and elastic energy at t = 0, which the scene may not mean (a stop given on the wrong side of the
    initial length). A start in contact is allowed (a device resting on its stop), so it is a note,
    not an error."""
    notes = []
    if not len(result.time):
        return notes
    for name, spec in result.model.scene.elements.items():
        device = getattr(spec, "device", None)
        if device is None or not device.has("end_stops"):
            continue
        try:
            L0, force = float(result[f"{name}.s_rel"][0]), float(result[f"{name}.f_stop"][0])
        except KeyError:                      # an FMU run that did not record them
            continue
        stops, slack = device.values("end_stops"), STOP_START_SLACK * L0
        for key, past in (("min", lambda s: L0 < s - slack), ("max", lambda s: L0 > s + slack)):
            stop = stops.get(key)
            if stop is not None and past(stop):
                notes.append(f"{result.model.source}: elements.{name}.device.end_stops.{key}: the device starts "
                             f"past its stop, pressed in by {abs(L0 - stop):.3g} m (terminal distance {L0:.6g} m "
                             f"at t = 0, {key} = {stop:.6g} m; contact force {force:.3g} N)")
    return notes


def output_units(result) -> dict[str, str]:
    """``{"time": "s", name: unit, ...}`` for the outputs a result holds (a solver's or an FMU's)."""
    signals = result.model.signals
    unit = dict(zip(signals.names, signals.units))
    return {"time": "s", **{name: unit[name] for name in result.names}}


def csv_header(result) -> str:
    """``time (s),C.r[1] (m),...``: a name never holds a space, so ``name (unit)`` splits back at its
    last " (" (a dimensionless output reads ``(1)``)."""
    units = output_units(result)
    return ",".join(f"{name} ({units[name]})" for name in ["time"] + list(result.names))


def to_dataframe(result):
    """Time as the index (named ``time``), one column per output, units in ``df.attrs["units"]``."""
    try:
        import pandas as pd
    except ImportError:
        raise ModuleNotFoundError("to_dataframe() needs pandas, which is not installed: pip install pandas "
                                  "(or pip install 'inerter[pandas]')", name="pandas") from None
    columns = {name: np.asarray(result[name], dtype=float) for name in result.names}
    frame = pd.DataFrame(columns, index=pd.Index(np.asarray(result.time, dtype=float), name="time"))
    frame.attrs["units"] = output_units(result)
    return frame


def _plain(value):
    """`value` as plain JSON values: numpy scalars and arrays to numbers and lists, tuples to lists,
    a number that is not finite to None (JSON has no NaN), an object with a ``describe()`` (a
    ground motion) to that text, anything else to its str()."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, np.bool_):
        return bool(value)
    describe = getattr(value, "describe", None)
    return describe() if callable(describe) else str(value)


def at_times(values, time, what):
    """`values` (a callable on a 1-D array of times, none NaN, of at least one) on times as
    Result.dense takes them: any shape, flattened; none; NaN where a time is NaN. A time outside
    the run's samples `time` (its first to its last, to rounding) raises a ValueError that names
    `what`, the time and the span: past them a polynomial or a spline would be extrapolated, not
    the run's result (a failed run's last sample is where it stopped)."""
    t0, t1 = (float(time[0]), float(time[-1])) if len(time) else (np.inf, -np.inf)
    slack = 1e-12 * max(1.0, abs(t0), abs(t1)) if len(time) else 0.0
    span = f"whose samples span [{t0:.9g}, {t1:.9g}] s" if len(time) else "which has no samples"

    def at(t):
        t = np.asarray(t, dtype=float).reshape(-1)
        lo, hi = (float(t.min()), float(t.max())) if len(t) else (t0, t1)
        every = lo == lo and hi == hi          # min and max are NaN where a time is
        read = None if every else ~np.isnan(t)
        given = t if every else t[read]
        if not every and len(given):
            lo, hi = float(given.min()), float(given.max())
        if len(given) and (lo < t0 - slack or hi > t1 + slack):
            bad = given[(given < t0 - slack) | (given > t1 + slack)][0]
            raise ValueError(f"{what}: t = {bad:.9g} s is outside the run, {span}; its dense output "
                             "is read only there")
        if every and len(t):                   # the common case, without the copies below
            return np.asarray(values(t), dtype=float).reshape(-1)
        out = np.full(len(t), np.nan)
        if np.any(read):
            out[read] = values(t[read])
        return out
    return at


def sample_spline(time, values, name=None, column=None):
    """A cubic spline through samples (error O(h⁴); linear interpolation would flatten peaks by
    (ωh)²/12): metrics of runs without a dense output (an FMU restarting at each communication
    point, a compiled RK4 run with 3D rotational elements). A body's Euler
    angle (`name` ``B.euler[i]``), read in (−π, π], is splined through its samples unwrapped and
    read in (−π, π] again, so that the spline does not cross the 2π jumps where it wraps. A
    body's quaternion component (``B.q[i]``; `column(name)` gives the other components' samples)
    is splined through samples made continuous first, where they flip sign: see
    :func:`_quaternion_spline`."""
    from scipy.interpolate import CubicSpline
    if name is not None and column is not None and _QUATERNION.fullmatch(name):
        return _quaternion_spline(time, name, column)
    if name is None or ".euler[" not in name:
        return CubicSpline(time, values)
    spline = CubicSpline(time, np.unwrap(values))
    return lambda t: np.pi - np.mod(np.pi - spline(t), 2 * np.pi)


_QUATERNION = re.compile(r"(.+)\.q\[([1-4])\]")


def _quaternion_spline(time, name, column):
    """The spline of quaternion component `name`. With Euler angles a body's quaternion output
    is the one with w ≥ 0 of its rotation matrix, so it flips to −q where w crosses 0 (q and −q
    are the same rotation): a spline through those samples crosses each jump. The samples are
    made continuous first (each sample's sign the one nearest the previous sample: q_k·q_(k−1)
    ≥ 0), splined, and read back with w ≥ 0 (the sign of the splined w). Samples without such
    flips (a quaternion state, continuous) are splined as they are."""
    from scipy.interpolate import CubicSpline
    body, index = _QUATERNION.fullmatch(name).groups()
    q = np.column_stack([np.asarray(column(f"{body}.q[{i}]"), dtype=float) for i in range(1, 5)])
    turn = np.sign(np.einsum("ij,ij->i", q[1:], q[:-1]))
    signs = np.cumprod(np.concatenate([[1.0], np.where(turn < 0, -1.0, 1.0)]))
    if np.all(signs > 0) or np.any(q[:, 0] < 0):      # no flip, or not the w >= 0 convention
        return CubicSpline(time, q[:, int(index) - 1])
    component = CubicSpline(time, signs * q[:, int(index) - 1])
    w = CubicSpline(time, signs * q[:, 0])
    return lambda t: component(t) * np.where(w(t) < 0, -1.0, 1.0)


def _key(prefix, name):
    return f"{prefix}_{name}" if prefix else name


def metric_units(model: Model) -> dict[str, str]:
    """The unit of each metric the scene's [[metrics]] define, by its key in ``result.metrics``:
    frequencies in Hz, every other metric in its signal's unit (a peak of ``C.r[2]`` in m)."""
    units: dict[str, str] = {}
    signal_unit = dict(zip(model.signals.names, model.signals.units))
    for m in model.scene.metrics:
        unit = signal_unit.get(m.signal, "1")
        keys = {"natural_frequency": {"natural_frequency": "Hz", "natural_frequencies": "Hz"},
                "peak": {"peak": unit},
                "free_oscillation": {"fundamental_frequency": "Hz", "fundamental_amplitude": unit,
                                     "mean_offset": unit},
                "harmonics": {"mean": unit, "amplitude": unit},
                "steady_state": {"peak_to_peak": unit, "mean_offset": unit}}[m.kind]
        units.update({_key(m.prefix, k): u for k, u in keys.items()})
    return units


#: The fewest samples a metric of a time history is computed from: fewer (an output interval or
#: FMU communication step close to the stop time) leave it out, with the reason.
MIN_METRIC_SAMPLES = 5


def missing_values(time, column) -> str:
    """"no value at N of M samples, the first at t = T s" where `column` has no value (NaN, inf) at
    some samples, else ""."""
    missing = ~np.isfinite(column)
    if not missing.any():
        return ""
    return (f"no value at {int(missing.sum())} of {len(column)} samples, the first at "
            f"t = {time[missing.argmax()]:.6g} s")


def compute_metrics(model: Model, result) -> dict:
    """The scene's [[metrics]] from a time history (module `metrics`). A metric that cannot be
    computed from this history (too short, too few samples, no oscillation, ...) is left out and
    its reason is recorded in ``result.metric_errors``."""
    out: dict[str, Any] = {}
    windows: dict = {}
    samples = len(result.time)
    for i, m in enumerate(model.scene.metrics):
        if m.kind != "natural_frequency" and samples < MIN_METRIC_SAMPLES:
            label = f"metrics[{i + 1}] ({m.kind}{' ' + m.signal if m.signal else ''})"
            step = getattr(result, "communication_step", None)
            result.metric_errors[label] = (
                f"{samples} sample(s) to t = {result.time[-1] if samples else 0:g} s, at least "
                f"{MIN_METRIC_SAMPLES} needed: lower " + ("the communication step (--step)" if step else
                                                           "experiment.output_interval"))
            continue
        try:
            _compute_metric(model, result, m, out, windows)
        except (ValueError, SimulationError) as exc:
            label = f"metrics[{i + 1}] ({m.kind}{' ' + m.signal if m.signal else ''})"
            result.metric_errors[label] = str(exc)
    return out


#: A periodic metric's grid is fine enough when its quadrature moves by less than this share of
#: the run's relative tolerance (of the signal's spread, :func:`inerter.engine.metrics._window_grid`):
#: the metric adds a thousandth of the run's own error at most.
METRIC_GRID_SHARE = 1e-3
#: ... and never asked to settle closer than this share of the spread, near which the sums' rounding
#: and the dense output's own step-to-step differences leave the grids (lumped_mass_2d at its rtol
#: 1e-10: 64 → 128 → 256 → 512 a period moved its mean by 0.9, 2.6 and 0.2 e-13 of the spread).
METRIC_GRID_FLOOR = 1e-12


def metric_grid_rtol(settings, pulse_free: bool) -> float | None:
    """The `grid_rtol` of a run's periodic metric: :data:`METRIC_GRID_SHARE` of the run's rtol (at
    least :data:`METRIC_GRID_FLOOR`) for an output that holds no pulse the integrator's steps do not
    resolve (`pulse_free`, ``Signals.pulse_free``: the motion's outputs, and every element's and the
    energy in a scene without an inerter device) where the integrator keeps a tolerance. None (the
    finest grid) otherwise: a device's end stop or backlash pulses (its contact, a series spring's
    deflection with it, every force that reads q̈ with them), and so may a derived output, narrower
    than a coarse grid's step, which two coarse grids would both miss and agree on; and for RK4
    (fixed steps) and a history without settings."""
    if settings is None or settings.method == "RK4" or not pulse_free:
        return None
    return max(METRIC_GRID_FLOOR, METRIC_GRID_SHARE * settings.rtol)


def _compute_metric(model, result, m, out, windows):
    """One [[metrics]] entry into `out`."""
    if m.kind == "natural_frequency":
        freqs = model.natural_frequencies()
        out[_key(m.prefix, "natural_frequency")] = float(freqs[0]) if len(freqs) else float("nan")
        out[_key(m.prefix, "natural_frequencies")] = [float(f) for f in freqs]
        return
    x = result[m.signal]            # first: a sample where it is undefined ends the result before it
    t = result.time
    missing = missing_values(t, x)
    if missing:                      # a derived output without value at some samples (NaN)
        raise ValueError(f"{m.signal} has {missing}: the metric needs it at every sample")
    dense = result.dense(m.signal)
    if m.kind == "peak":
        # largest excursion from the reference (default: the signal's initial value), between samples too
        ref = m.reference if m.reference is not None else float(x[0])
        out[_key(m.prefix, "peak")] = float(metric_fns.peak(t, x, ref, dense=dense))
        return
    settings, pulse_free = getattr(result, "settings", None), model.signals.pulse_free
    if m.kind in ("free_oscillation", "steady_state"):     # (harmonics has no reference: none worked out)
        reference = m.reference if m.reference is not None else model.static_value(m.signal)
    if m.kind == "free_oscillation":
        r = metric_fns.free_oscillation(t, x, reference, dense=dense,
                                        grid_rtol=metric_grid_rtol(settings, m.signal in pulse_free))
        windows[m.signal] = (r["window"], r["periods"])
        for key in ("fundamental_frequency", "fundamental_amplitude", "mean_offset"):
            out[_key(m.prefix, key)] = float(r[key])
    elif m.kind == "harmonics":
        if m.period_of not in windows:
            r0 = metric_fns.free_oscillation(t, result[m.period_of], 0.0, dense=result.dense(m.period_of),
                                             grid_rtol=metric_grid_rtol(settings, m.period_of in pulse_free))
            windows[m.period_of] = (r0["window"], r0["periods"])
        window, periods = windows[m.period_of]
        r = metric_fns.harmonics(t, x, window, periods, dense=dense,
                                 grid_rtol=metric_grid_rtol(settings, m.signal in pulse_free))
        out[_key(m.prefix, "mean")] = float(r["mean"])
        out[_key(m.prefix, "amplitude")] = float(r["amplitude"])
    elif m.kind == "steady_state":
        r = metric_fns.steady_state(t, x, m.period, m.periods, reference, dense=dense,
                                    grid_rtol=metric_grid_rtol(settings, m.signal in pulse_free))
        out[_key(m.prefix, "peak_to_peak")] = float(r["peak_to_peak"])
        out[_key(m.prefix, "mean_offset")] = float(r["mean_offset"])


#: The shipped scene each dimension's kernels are compiled on (:func:`warm_up`).
WARM_UP_SCENES = {2: "two_bar_2d.toml", 3: "two_bar_2d_as_3d.toml"}


#: The second process of a parallel warm-up: the 3D kernels; prints the seconds it compiled for.
_WARM_UP_3D = ("from inerter.api import warm_up; from inerter.engine import compiled; warm_up(dims=(3,)); "
               "print(compiled.NOTICE.seconds if compiled.NOTICE is not None else 0.0)")

#: A process building one dimension's entry kernels ahead of time (:func:`build_ahead`).
_BUILD_AHEAD = "import sys; from inerter.api import _build_ahead_here; _build_ahead_here(int(sys.argv[1]))"


def build_ahead(dims=(2, 3), parallel: bool = True) -> dict:
    """Build the kernels a run enters from Python ahead of time for each of `dims` where this
    machine lacks the build (:mod:`inerter.engine.ahead`), each dimension in a process of its own,
    side by side where `parallel`. Returns {dimension: None (built, or there already), or the
    reason it could not be built}; a dimension without its build still runs, its kernels loaded
    from numba's cache."""
    from inerter.engine import ahead, compiled

    outcome = {}
    wanted = [d for d in dims if not ahead.built(compiled._k, d)]
    outcome.update({d: None for d in dims if d not in wanted})
    groups = [wanted] if parallel else [[d] for d in wanted]
    for group in groups:
        started = {d: _subprocess.Popen([_sys.executable, "-c", _BUILD_AHEAD, str(d)], stdout=_subprocess.PIPE,
                                        stderr=_subprocess.PIPE, text=True) for d in group}
        for d, process in started.items():
            _, err = process.communicate()
            last = (err.strip().splitlines() or ["no message"])[-1]
            outcome[d] = None if process.returncode == 0 and ahead.built(compiled._k, d) else last
    return outcome


def _build_ahead_here(dimension: int):
    """:func:`build_ahead`'s process for `dimension`: its warm-up through numba's dispatchers (from
    the cache ``inerter compile`` filled first), then the build."""
    from inerter.engine import ahead, compiled

    compiled.NOTICE.enabled = False             # numba.pycc compiles through numba: not the kernels' first use
    _warm_up_dimensions((dimension,))
    print(ahead.build(compiled._k, dimension) or "")


def warm_up(spatial: bool = False, parallel: bool = False, dims=None):
    """Compile (or load from numba's cache) every kernel once for 2D scenes (`spatial`: for 3D
    scenes too; `dims` names them instead), so timings exclude compilation. Returns the seconds it
    took.

    `parallel` (both dimensions): the 3D kernels compile in a second process while this one
    compiles the 2D kernels (numba compiles on one core; `inerter compile` on 2 cores), then this
    process loads the 3D kernels too, compiling whatever the other's cache entries lack (two
    processes that save the same kernel's cache index at once keep one entry), so that the cache is
    complete when it returns."""
    from inerter.engine import compiled

    if not compiled.AVAILABLE:
        return 0.0
    dims = tuple(dims or ((2, 3) if spatial else (2,)))
    t0 = _time.perf_counter()
    if parallel and 3 in dims and len(dims) > 1:
        other = _subprocess.Popen([_sys.executable, "-c", _WARM_UP_3D], stdout=_subprocess.PIPE,
                                  stderr=_subprocess.DEVNULL, text=True)
        try:
            _warm_up_dimensions([d for d in dims if d != 3])
        except BaseException:
            other.kill()
            other.wait()
            raise
        reported = other.communicate()[0].split()      # its outcome is checked by loading what it compiled, below
        if compiled.NOTICE is not None and reported:
            compiled.NOTICE.seconds += float(reported[-1])     # what it compiled counts as compiled here
        dims = (3,)                 # the 2D kernels are loaded here already
    _warm_up_dimensions(dims)
    return _time.perf_counter() - t0


def _warm_up_dimensions(dims):
    """Every kernel called for the shipped scenes of `dims` (:data:`WARM_UP_SCENES`), compiled or
    loaded through numba's dispatchers (not the builds ahead of time: the cache is what this fills,
    and the builds are made for the signatures it compiles): whole runs of each compiled method with
    and without the dense output, their outputs and metrics, the accelerations, scipy's methods on
    the kernels, the co-simulation steps and the FMU's native step."""
    from inerter.engine import compiled

    with compiled.ENTRIES.dispatchers_only():
        _warm_up_scenes(dims)


def _warm_up_scenes(dims):
    """:func:`_warm_up_dimensions`' calls."""
    from inerter.engine import compiled

    from inerter.common.locations import scenarios
    folder = scenarios()
    for name in (WARM_UP_SCENES[d] for d in dims):
        if not (folder / name).exists():         # nothing compiled would pass unnoticed: say so
            raise InerterError(f"{folder / name}: the shipped scene the kernels are compiled on is missing "
                               "(reinstall inerter)")
        model = load(folder / name)
        for method in compiled.COMPILED_METHODS:
            compiled.integrate_compiled(model.mechanism, model.settings(method=method, stop_time=0.05, step=1e-2))
            s = model.settings(method=method, stop_time=0.05, step=1e-2)     # with the dense output (metrics)
            result = Result(model, s, compiled.integrate_compiled(model.mechanism, s, dense=True))
            for signal in ("C.r[2]", "inerter.f"):
                result[signal]
                result.dense(signal)(np.array([0.01, 0.02]))
            if result.run.dense is not None:
                result.run.dense(np.array([0.01, 0.02]))
            result._all_values()
            result.run.max_drift
        kernel = compiled._kernel_for(model.mechanism)
        kernel.accelerations(0.0, kernel.q0, kernel.v0)
        if kernel.spatial:        # a dense output's steps' φ_ref (a scene with 3D rotational elements)
            along = kernel.windings_along(result.time, result.run.states)
            kernel.windings_between(result.time, result.run.states, along, result.time, result.run.states)
        model.simulate(method="Radau", stop_time=0.02, metrics=False)      # scipy's methods on the kernels
        for method in (*compiled._RK_CODE, "RK4"):             # the co-simulation steps (the FMU's)
            stepper = model.stepper(method=method, path="compiled", stop_time=0.05)
            stepper.output_values()                            # at t = 0, before a step (an FMU's initialisation)
            stepper.step(0.01)
            stepper.output_values()
        compiled._k.native_step_cfunc(kernel.spatial)         # the FMU's native step (inerter.fmu.native)
