"""The Python entry point: ``model = inerter.load(scene, **overrides)``, ``model.simulate(...)``.

A :class:`Model` holds the validated scene and its compiled mechanism (fast path). The oracle is
the same scene compiled with ``oracle=True`` and solved at tight tolerance.
"""
from __future__ import annotations

import time as _time
from pathlib import Path
from typing import Any

import numpy as np

from inerter.engine import metrics as metric_fns
from inerter.engine.equilibrium import natural_frequencies, static_equilibrium
from inerter.model.mechanism import Mechanism
from inerter.oracle import OracleElement
from inerter.engine.outputs import Signals
from inerter.scene.reader import KNOWN_EFFECTS, METHODS, load_scene
from inerter.common.errors import SimulationError
from inerter.engine.simulation import Settings, Stepper, integrate

#: Tolerances at which the oracle is solved (DOP853).
ORACLE_RTOL = 1e-12
ORACLE_ATOL = 1e-14


def load(path, **overrides) -> "Model":
    """Load a scene file. Overrides, Modelica-modifier style: a parameter by name (``b=20``), an
    effect (``**{"effects.centripetal": False}``) or an experiment setting (``experiment.rtol``)."""
    return Model(path, overrides)


class Model:
    methods = METHODS

    def __init__(self, path, overrides: dict[str, Any] | None = None, oracle: bool = False):
        self.path = Path(path)
        self.overrides = dict(overrides or {})
        self.scene = load_scene(self.path, self.overrides)
        self.mechanism = Mechanism(self.scene, element_factory=OracleElement if oracle else None)
        self.signals = Signals(self.mechanism)
        self.is_oracle = oracle
        self._static = None

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
        return self.mechanism.terms()

    def parameter_info(self):
        return [dict(name=p.name, value=p.value, unit=p.unit, description=p.description)
                for p in self.scene.parameters.values()]

    def effect_info(self):
        """Boolean effect switches (``effects.centripetal``), present when the scene has inerters."""
        info = []
        if self.mechanism.inerters or "centripetal" in self.scene.effects:
            info.append(dict(name="effects.centripetal", value=self.scene.centripetal,
                             description=KNOWN_EFFECTS["centripetal"]))
        return info

    def input_info(self):
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
        return self.signals.info()

    def with_overrides(self, **more) -> "Model":
        merged = dict(self.overrides)
        merged.update(more)
        return Model(self.path, merged, oracle=self.is_oracle)

    def oracle(self) -> "Model":
        """The same scene with element forces from the definitions (module `oracle`)."""
        return Model(self.path, self.overrides, oracle=True)

    # -- analysis ----------------------------------------------------------------------------
    def static_equilibrium(self):
        if self._static is None:
            self._static = static_equilibrium(self.mechanism)
        return self._static

    def natural_frequencies(self):
        return natural_frequencies(self.mechanism, self.static_equilibrium())

    def static_value(self, signal: str) -> float:
        q = self.static_equilibrium()
        return self.signals.function(signal)(0.0, q, np.zeros(self.mechanism.n))

    # -- simulation --------------------------------------------------------------------------
    def settings(self, **overrides) -> Settings:
        return Settings.from_experiment(self.scene.experiment, **overrides)

    def simulate(self, stop_time=None, output_interval=None, method=None, rtol=None, atol=None,
                 constraint=None, step=None, metrics=True, path="numpy") -> "Result":
        """Integrate from the initial state. `path`: "numpy" (the readable reference) or "compiled"
        (numba kernels and integrator loops, module `compiled`; 2D scenes, falls back to numpy
        where numba is missing or the scene is 3D)."""
        s = self.settings(stop_time=stop_time, output_interval=output_interval, method=method, rtol=rtol,
                          atol=atol, constraint=constraint, step=step)
        if path == "compiled" and not self.is_oracle:
            from inerter.engine import compiled
            run = compiled.integrate_compiled(self.mechanism, s)
        elif path in ("numpy", "compiled"):
            run = integrate(self.mechanism, s)
        else:
            raise ValueError(f"path = {path!r}; expected 'numpy' or 'compiled'")
        result = Result(self, s, run)
        if metrics and run.status == "ok":
            result.metrics = compute_metrics(self, result)
        return result

    def stepper(self, method=None, rtol=None, atol=None, path="numpy", stop_time=None) -> Stepper:
        """A co-simulation stepper at t = 0. `path` = "compiled": each step one call of the compiled
        integrator loop where :func:`inerter.engine.compiled.compiled_stepper` can take the scene (the numpy
        stepper otherwise; ``stepper.path`` says which). On both paths the adaptive integrators run
        on across communication points, their steps clipped to `stop_time` where it is given."""
        s = self.settings(method=method, rtol=rtol, atol=atol)
        if path == "compiled" and not self.is_oracle:
            from inerter.engine import compiled
            stepper = compiled.compiled_stepper(self.mechanism, s, self.signals, stop_time)
            if stepper is not None:
                return stepper
        elif path != "numpy" and path != "compiled":
            raise ValueError(f"path = {path!r}; expected 'numpy' or 'compiled'")
        return Stepper(self.mechanism, s, self.signals, stop_time)


class Result:
    """A time history: ``result.time``, ``result["C.r[2]"]``, ``result.metrics``."""

    def __init__(self, model: Model, settings: Settings, run):
        self.model = model
        self.settings = settings
        self.run = run
        self.time = run.time
        self.status = run.status
        self.message = run.message
        self.metrics: dict[str, float] = {}
        self.metric_errors: dict[str, str] = {}
        n = model.mechanism.nq
        sig = model.signals
        values, start = [], 0
        kernel = run.extra.get("kernel")             # a compiled run's outputs come from its kernels
        order = kernel.signal_order(sig) if kernel is not None and hasattr(kernel, "signal_order") else None
        if order is not None:
            compiled_values, start = kernel.signal_history(sig, order, run.time, run.states, None, settings.alpha)
            values = list(compiled_values)
        for i in range(start, len(run.time)):        # the numpy path (and its messages where one fails)
            t, y = run.time[i], run.states[i]
            try:
                values.append(sig.evaluate(t, y[:n], y[n:], None, settings.alpha))
            except SimulationError as exc:   # an output undefined at a sample: keep what came before
                self._truncate(i, exc if exc.time is not None else SimulationError(exc.message, float(t)))
                break
        self._values = np.array(values) if values else np.zeros((0, len(sig.names)))
        self.names = list(sig.names)

    def _truncate(self, i, exc):
        """The outputs cannot be evaluated from sample i on: the result ends before it, failed."""
        run = self.run
        run.time, run.states = run.time[:i], run.states[:i]
        run.message = str(exc) if run.message == "completed" else f"{exc}; the integrator had reported: {run.message}"
        run.status = "failed"
        self.time, self.status, self.message = run.time, run.status, run.message

    def __getitem__(self, name) -> np.ndarray:
        try:
            return self._values[:, self.model.signals.index[name]]
        except KeyError:
            raise KeyError(f"{name!r} is not an output of {self.model.name}; outputs: "
                           + ", ".join(self.names)) from None

    def dense(self, name):
        """A callable t ↦ signal(t) through the integrator's dense output (vectorised over t), or
        a cubic spline through the samples where the run kept no dense output."""
        if self.run.dense is None:
            return sample_spline(self.time, self[name])
        fn = self.model.signals.function(name)
        n = self.model.mechanism.nq
        sol = self.run.dense
        alpha = self.settings.alpha

        def f(t):
            t = np.atleast_1d(np.asarray(t, dtype=float))
            Y = sol(t)
            return np.array([fn(ti, Y[:n, i], Y[n:, i], None, alpha) for i, ti in enumerate(t)])
        return f

    def summary(self) -> dict:
        s = self.settings
        return {
            "scene": self.model.name,
            "source": self.model.source,
            "status": self.status,
            "message": self.message,
            "metrics": self.metrics,
            "metric_errors": self.metric_errors,
            "settings": {"stop_time": s.stop_time, "output_interval": s.output_interval, "method": s.method,
                         "rtol": s.rtol, "atol": s.atol, "constraint": s.constraint, "baumgarte": s.baumgarte,
                         "oracle": self.model.is_oracle,
                         "parameters": {p.name: p.value for p in self.model.scene.parameters.values()},
                         "effects": {k: (list(v) if isinstance(v, tuple) else v)
                                     for k, v in self.model.scene.effects.items()}},
            "statistics": {"path": self.run.extra.get("path", "numpy"),
                           "steps": self.run.steps, "evaluations": self.run.evaluations,
                           "cpu_time_s": self.run.cpu_time, "max_constraint_drift": self.run.max_drift,
                           "energy_start": float(self["energy"][0]) if len(self.time) else None,
                           "energy_end": float(self["energy"][-1]) if len(self.time) else None},
        }

    def write_csv(self, path):
        header = ",".join(["time"] + self.names)
        np.savetxt(path, np.column_stack((self.time, self._values)), delimiter=",", header=header,
                   comments="", fmt="%.12g")


def sample_spline(time, values):
    """A cubic spline through samples (error O(h⁴); linear interpolation would flatten peaks by
    (ωh)²/12): metrics of runs without a dense output (compiled path, FMUs)."""
    from scipy.interpolate import CubicSpline
    return CubicSpline(time, values)


def _key(prefix, name):
    return f"{prefix}_{name}" if prefix else name


def compute_metrics(model: Model, result) -> dict:
    """The scene's [[metrics]] from a time history (module `metrics`). A metric that cannot be
    computed from this history (too short, no oscillation, ...) is left out and its reason is
    recorded in ``result.metric_errors``."""
    out: dict[str, Any] = {}
    windows: dict = {}
    for i, m in enumerate(model.scene.metrics):
        try:
            _compute_metric(model, result, m, out, windows)
        except (ValueError, SimulationError) as exc:
            label = f"metrics[{i + 1}] ({m.kind}{' ' + m.signal if m.signal else ''})"
            result.metric_errors[label] = str(exc)
    return out


def _compute_metric(model, result, m, out, windows):
    """One [[metrics]] entry into `out`."""
    if m.kind == "natural_frequency":
        freqs = model.natural_frequencies()
        out[_key(m.prefix, "natural_frequency")] = float(freqs[0]) if len(freqs) else float("nan")
        out[_key(m.prefix, "natural_frequencies")] = [float(f) for f in freqs]
        return
    t, x, dense = result.time, result[m.signal], result.dense(m.signal)
    if m.kind == "peak":
        # largest excursion from the reference (default: the signal's initial value)
        ref = m.reference if m.reference is not None else float(x[0])
        out[_key(m.prefix, "peak")] = float(np.max(np.abs(x - ref)))
        return
    reference = m.reference if m.reference is not None else model.static_value(m.signal)
    if m.kind == "free_oscillation":
        r = metric_fns.free_oscillation(t, x, reference, dense=dense)
        windows[m.signal] = (r["window"], r["periods"])
        for key in ("fundamental_frequency", "fundamental_amplitude", "mean_offset"):
            out[_key(m.prefix, key)] = float(r[key])
    elif m.kind == "harmonics":
        if m.period_of not in windows:
            r0 = metric_fns.free_oscillation(t, result[m.period_of], 0.0, dense=result.dense(m.period_of))
            windows[m.period_of] = (r0["window"], r0["periods"])
        window, periods = windows[m.period_of]
        r = metric_fns.harmonics(t, x, window, periods, dense=dense)
        out[_key(m.prefix, "mean")] = float(r["mean"])
        out[_key(m.prefix, "amplitude")] = float(r["amplitude"])
    elif m.kind == "steady_state":
        r = metric_fns.steady_state(t, x, m.period, m.periods, reference, dense=dense)
        out[_key(m.prefix, "peak_to_peak")] = float(r["peak_to_peak"])
        out[_key(m.prefix, "mean_offset")] = float(r["mean_offset"])


def warm_up(spatial: bool = False):
    """Compile (or load from numba's cache) every kernel once for 2D scenes (`spatial`: for 3D
    scenes too), so timings exclude compilation. Returns the seconds it took."""
    from inerter.engine import compiled

    if not compiled.AVAILABLE:
        return 0.0

    t0 = _time.perf_counter()
    folder = Path(__file__).resolve().parents[1] / "scenarios"
    for name in ("two_bar_2d.toml", "two_bar_2d_as_3d.toml")[:2 if spatial else 1]:
        if not (folder / name).exists():
            continue
        model = load(folder / name)
        for method in compiled.COMPILED_METHODS:
            compiled.integrate_compiled(model.mechanism, model.settings(method=method, stop_time=0.05, step=1e-2))
        kernel = compiled._kernel_for(model.mechanism)
        kernel.accelerations(0.0, kernel.q0, kernel.v0)
        for method in compiled._RK_CODE:                       # the co-simulation step (the FMU's)
            stepper = model.stepper(method=method, path="compiled", stop_time=0.05)
            stepper.step(0.01)
            stepper.output_values()
        compiled._k.native_step_cfunc(kernel.spatial)         # the FMU's native step (inerter.fmu.native)
    return _time.perf_counter() - t0
