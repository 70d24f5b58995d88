"""Integrating a compiled mechanism in time: whole runs (:func:`integrate`) and co-simulation
steps (:class:`Stepper`).

The state is y = [q, q̇]; its derivative is [q̇, q̈] with q̈ from Eq. (33). Constraint treatment:
``baumgarte`` adds −2αĊ − α²C to the constraint rows; ``projection`` integrates Eq. (33) as it is
and projects (q, q̇) back onto the constraints at every output point (the integrator restarts there).
"""
from __future__ import annotations

import pickle
import time as _time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import OdeSolution

from .errors import SimulationError
from .integrators import make_solver


@dataclass
class Settings:
    stop_time: float
    output_interval: float
    method: str
    rtol: float
    atol: float
    constraint: str
    baumgarte: float
    step: float
    max_steps: int

    @classmethod
    def from_experiment(cls, x, **overrides):
        values = dict(stop_time=x.stop_time, output_interval=x.output_interval, method=x.method, rtol=x.rtol,
                      atol=x.atol, constraint=x.constraint, baumgarte=x.baumgarte, step=x.step,
                      max_steps=x.max_steps)
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**values)

    @property
    def alpha(self):
        return self.baumgarte if self.constraint == "baumgarte" else 0.0


def derivative(mech, inputs, alpha):
    """y = [q, v] ↦ [q̇ = B(q) v, v̇ from Eq. (33)]."""
    nq = mech.nq

    def fun(t, y):
        q, v = y[:nq], y[nq:]
        a, _ = mech.accelerations(t, q, v, inputs, alpha)
        return np.concatenate((mech.qdot(q, v, t), a))
    return fun


@dataclass
class Run:
    """What :func:`integrate` produced: samples, the solver's dense output, and how it ended."""
    time: np.ndarray
    states: np.ndarray              # (len(time), 2n)
    dense: OdeSolution | None
    status: str                     # "ok" or "failed"
    message: str
    steps: int
    evaluations: int
    cpu_time: float
    max_drift: float = 0.0
    extra: dict = field(default_factory=dict)


def integrate(mech, settings: Settings, inputs=None) -> Run:
    """Integrate from the mechanism's initial state to settings.stop_time. A failure keeps
    everything computed up to the last good step (status "failed", message says where and why)."""
    n = mech.nq
    fun = derivative(mech, inputs, settings.alpha)
    grid = np.arange(0.0, settings.stop_time + 0.5 * settings.output_interval, settings.output_interval)
    grid[-1] = min(grid[-1], settings.stop_time)
    out = np.empty((len(grid), mech.nq + mech.n))
    y = np.concatenate((mech.q0, mech.v0))
    out[0] = y
    k = 1
    ts, interpolants = [0.0], []
    steps = 0
    evaluations = 0
    status, message = "ok", "completed"
    start = _time.process_time()
    project = settings.constraint == "projection"
    t0 = 0.0
    first_step = None
    max_drift = mech.constraint_residual(y[:n])
    try:
        while t0 < settings.stop_time:
            # With projection, each output interval is a fresh integration from a projected state.
            t_end = grid[k] if project else settings.stop_time
            solver = make_solver(settings.method, fun, t0, y, t_end, settings.rtol, settings.atol,
                                 settings.step, first_step)
            dense_prev_y = y.copy()
            while solver.status == "running":
                message_step = solver.step()
                steps += 1
                if solver.status == "failed":
                    raise SimulationError(f"the {settings.method} integrator failed: {message_step}", solver.t)
                if steps > settings.max_steps:
                    raise SimulationError(
                        f"more than max_steps = {settings.max_steps} integrator steps (step size "
                        f"{solver.t - solver.t_old:.3g} s): the scene may be stiff for {settings.method}; try "
                        "method = \"Radau\" or \"BDF\"", solver.t)
                mech.check_step(dense_prev_y, solver.y, solver.t, solver.t_old)
                dense_prev_y = solver.y.copy()
                dense = solver.dense_output()
                ts.append(solver.t)
                interpolants.append(dense)
                while k < len(grid) and grid[k] <= solver.t + 1e-12 * max(1.0, solver.t):
                    out[k] = dense(grid[k])
                    k += 1
            evaluations += solver.nfev
            y = solver.y
            if project:
                q, v = mech.project(y[:n], y[n:])
                y = np.concatenate((q, v))
                out[k - 1] = y
                first_step = getattr(solver, "h_abs", None)
            max_drift = max(max_drift, mech.constraint_residual(y[:n]))
            t0 = solver.t
    except SimulationError as exc:
        status = "failed"
        message = str(exc)
    cpu = _time.process_time() - start
    for i in range(1, k):
        max_drift = max(max_drift, mech.constraint_residual(out[i, :n]))
    dense = OdeSolution(np.array(ts), interpolants) if interpolants else None
    return Run(grid[:k].copy(), out[:k].copy(), dense, status, message, steps, evaluations, cpu, max_drift)


class Stepper:
    """Co-simulation stepping: inputs held over each step; `step(t_end)` advances the state and,
    on failure, leaves it exactly as before. The integrator is restarted at each communication
    point with the last accepted step size, so (time, state, step size, inputs) is the complete
    state and a rolled-back step repeats bit for bit."""

    def __init__(self, mech, settings: Settings, signals):
        self.mech = mech
        self.settings = settings
        self.signals = signals
        self.time = 0.0
        self.y = np.concatenate((mech.q0, mech.v0))
        self.inputs = np.zeros(len(mech.input_names))
        self.h = None
        self.input_index = {name: i for i, name in enumerate(mech.input_names)}
        self.steps = 0

    def set_input(self, name, value):
        value = float(value)
        if not np.isfinite(value):
            raise SimulationError(f"input {name} = {value!r} is not finite; expected a finite force in N; "
                                  "the input keeps its previous value", self.time)
        self.inputs[self.input_index[name]] = value

    def step(self, t_end):
        n = self.mech.nq
        if not t_end > self.time:
            raise SimulationError(f"step to t = {t_end!r} is not after the current time", self.time)
        s = self.settings
        inputs = self.inputs.copy()
        fun = derivative(self.mech, inputs, s.alpha)
        steps = 0
        try:
            solver = make_solver(s.method, fun, self.time, self.y, t_end, s.rtol, s.atol, s.step, self.h)
            previous = self.y
            while solver.status == "running":
                msg = solver.step()
                steps += 1
                self.mech.check_step(previous, solver.y, solver.t, solver.t_old)
                previous = solver.y.copy()
                if solver.status == "failed":
                    raise SimulationError(f"the {s.method} integrator failed: {msg}", solver.t)
                if steps > s.max_steps:
                    raise SimulationError(f"more than max_steps = {s.max_steps} integrator steps in one "
                                          "communication step: the scene may be stiff; try Radau or BDF", solver.t)
            y = solver.y
            if s.constraint == "projection":
                q, v = self.mech.project(y[:n], y[n:])
                y = np.concatenate((q, v))
            if not np.all(np.isfinite(y)):
                raise SimulationError("the state became non-finite", solver.t)
        except SimulationError:
            raise
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            raise SimulationError(f"the step could not be completed: {exc}", self.time) from None
        self.y = y
        self.time = float(t_end)
        self.h = getattr(solver, "h_abs", None)
        self.steps += steps

    def outputs(self) -> dict:
        n = self.mech.nq
        values = self.signals.evaluate(self.time, self.y[:n], self.y[n:], self.inputs, self.settings.alpha)
        return dict(zip(self.signals.names, values.tolist()))

    def get_state(self) -> bytes:
        return pickle.dumps((self.time, self.y.copy(), self.h, self.inputs.copy(), self.steps))

    def set_state(self, blob: bytes):
        self.time, y, self.h, inputs, self.steps = pickle.loads(blob)
        self.y = np.array(y)
        self.inputs = np.array(inputs)
