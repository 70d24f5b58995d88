"""Integrating a compiled mechanism in time: whole runs (:func:`integrate`) and co-simulation
steps (:class:`Stepper`).

The state is y = [q, q̇, z]; its derivative is [q̇, q̈, ż] with q̈ from Eq. (33) and z the elements'
internal states (an inerter device's series deflection, its dissipated energy; ``Mechanism.z0``,
empty for most scenes), whose rates follow once q̈ is solved (``Mechanism.state_rates``). Constraint treatment:
``baumgarte`` adds −2αĊ − α²C to the constraint rows; ``projection`` integrates Eq. (33) as it is
and projects (q, q̇) back onto the constraints at every output point (the integrator restarts there).
"""
from __future__ import annotations

import bisect
import copy
import functools
import io
import math
import pickle
import time as _time
import types
from dataclasses import dataclass, field

import numpy as np

from inerter.common.errors import SimulationError, TerminalsMeet
from inerter.model.mechanism import DEPENDENT_RATIO, rank_kept


#: The smallest rtol scipy's integrators take (100 ε; scipy.integrate._ivp.common.validate_tol):
#: a smaller one runs at this one (``make_solver``; Result.warnings says so); the compiled DOP853 and
#: RK45 loops take the reader's smallest, 1e-14
SCIPY_RTOL_FLOOR = 100 * float(np.finfo(float).eps)


def make_solver(*args, **kwargs):
    """inerter.engine.integrators.make_solver, imported on first use: the compiled path never needs
    scipy.integrate, whose import costs about 0.15 s of a fresh process's start."""
    from inerter.engine.integrators import make_solver as make

    return make(*args, **kwargs)


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
    def from_experiment(cls, x):
        """The settings of an experiment the scene reader has checked (``Scene.experiment_with``
        reads overrides through the same function as the scene's own fields)."""
        return cls(stop_time=x.stop_time, output_interval=x.output_interval, method=x.method, rtol=x.rtol,
                   atol=x.atol, constraint=x.constraint, baumgarte=x.baumgarte, step=x.step,
                   max_steps=x.max_steps)

    @property
    def alpha(self):
        return self.baumgarte if self.constraint == "baumgarte" else 0.0


def for_run(mech):
    """`mech` for one run or stepper: its copy that owns what the run changes as it goes, at its
    value at t = 0 (``Mechanism.for_run``: the 3D rotational elements' φ_ref, the screw
    efficiencies' modes, the caches keyed on the state; on the compiled right-hand side, the
    kernel's tables too), so that the model it came from, and its other runs and steppers, are
    not changed. A stand-in without ``for_run`` is taken as it is."""
    copy_for_run = getattr(mech, "for_run", None)
    return mech if copy_for_run is None else copy_for_run()


def numpy_mechanism(mech):
    """The numpy path's mechanism of `mech` (itself, or the one a kernel's stands for), which the
    output signals are built on (``Signals.for_run``)."""
    return getattr(mech, "mechanism", mech)


def initial_state(mech) -> np.ndarray:
    """y0 = [q0, v0, z0] (z0: the internal states, empty for most scenes)."""
    return np.concatenate((mech.q0, mech.v0, getattr(mech, "z0", np.zeros(0))))


def _project(mech, y):
    """y with (q, v) projected onto the constraints, the internal states z left as they are."""
    n, nv = mech.nq, mech.nq + mech.n
    q, v = mech.project(y[:n], y[n:nv])
    return np.concatenate((q, v, y[nv:]))


def derivative(mech, inputs, alpha, jump=None):
    """y = [q, v] ↦ [q̇ = B(q) v, v̇ from Eq. (33)]. `jump`: a time where the right-hand side jumps
    (a step force switches) or, for a method that restarts there, a kink, ending the segment
    integrated: it is evaluated just before (one ulp), so that stages at the segment's end see the
    values the forces had over the segment. A mechanism backed by the compiled kernels gives its
    own (``state_derivative``); one with internal states z integrates y = [q, v, z]."""
    if hasattr(mech, "state_derivative"):
        return mech.state_derivative(inputs, alpha, jump)
    if len(getattr(mech, "z0", ())):
        return _derivative_with_states(mech, inputs, alpha, jump)
    nq = mech.nq
    before = None if jump is None else float(np.nextafter(jump, -np.inf))

    def fun(t, y):
        if before is not None and t > before:
            t = before
        _check_finite(y, t)
        q, v = y[:nq], y[nq:]
        a, _ = mech.accelerations(t, q, v, inputs, alpha)
        return np.concatenate((mech.qdot(q, v, t), a))
    return fun


def _check_finite(y, t):
    """A state that is not finite (an implicit method's Newton iterate that diverged, a step that
    overflowed) cannot be evaluated: a recoverable SimulationError, so that the trial step is tried
    again shorter (:func:`_step`), as the compiled right-hand side reports it (NOT_FINITE)."""
    if not np.isfinite(y).all():
        raise SimulationError("the state is not finite", t, recoverable=True)


def _derivative_with_states(mech, inputs, alpha, jump=None):
    """:func:`derivative` on y = [q, v, z]: ż from the elements' laws once q̈ is solved."""
    nq, nv = mech.nq, mech.nq + mech.n
    before = None if jump is None else float(np.nextafter(jump, -np.inf))

    def fun(t, y):
        if before is not None and t > before:
            t = before
        _check_finite(y, t)
        q, v, z = y[:nq], y[nq:nv], y[nv:]
        a, _ = mech.accelerations(t, q, v, inputs, alpha, z=z)
        return np.concatenate((mech.qdot(q, v, t), a, mech.state_rates(q, v, z, a)))
    return fun


#: Methods that run on through a kink of the right-hand side (``Mechanism.kinks``: a ground
#: record's samples) instead of restarting there: the explicit Runge-Kutta methods, whose whole
#: state (y, its derivative, the step size) is still valid at a kink. A step that would cross a
#: kink is clipped to end on it (no step straddles one, so the method keeps its order), and the
#: integration goes on from there with its last derivative (FSAL) and the step size its error
#: control proposed before the clip (:func:`_on_through_kink`); RK4 goes on with its fixed step.
#: Radau, BDF and LSODA restart at a kink as at a jump.
THROUGH_KINKS = ("DOP853", "RK45", "RK4")


def _between(times, t0, t1):
    return times[bisect.bisect_right(times, t0):bisect.bisect_right(times, t1)]


def jumps(mech, t0, t1, method=None):
    """Times in (t0, t1] where the integrators restart: ``mech.discontinuities`` (a step force
    switching, a ground record ending on a value other than zero) and, for a method not in
    :data:`THROUGH_KINKS` (or no `method`), ``mech.kinks`` (a ground record's samples) too."""
    times = _between(getattr(mech, "discontinuities", ()), t0, t1)
    if method not in THROUGH_KINKS:
        more = _between(getattr(mech, "kinks", ()), t0, t1)
        if more:
            times = sorted(set(times).union(more))
    return times


def next_jump(mech, t0, t1, method=None):
    """The first of :func:`jumps` in (t0, t1], None where there is none."""
    first = None
    for times in (getattr(mech, "discontinuities", ()),
                  getattr(mech, "kinks", ()) if method not in THROUGH_KINKS else ()):
        i = bisect.bisect_right(times, t0)
        if i < len(times) and times[i] <= t1 and (first is None or times[i] < first):
            first = times[i]
    return first


def kinks(mech, t0, t1):
    """``mech.kinks`` in (t0, t1): where a method of :data:`THROUGH_KINKS` clips its step."""
    times = getattr(mech, "kinks", ())
    return list(times[bisect.bisect_right(times, t0):bisect.bisect_left(times, t1)])


def next_kink(mech, t0, t1):
    """The first of ``mech.kinks`` in (t0, t1), else t1."""
    times = getattr(mech, "kinks", ())
    i = bisect.bisect_right(times, t0)
    return times[i] if i < len(times) and times[i] < t1 else t1


def _on_through_kink(solver, h_want, bound):
    """Run a scipy solver that has just reached a kink (its `t_bound`) on towards `bound` (the next
    kink or its segment's end), with its y and f, and, where its last step was clipped to end on
    the kink, the step size proposed before that step, `h_want`, as the compiled loop does
    (``kernels.rk_advance``): the clipped step's own proposal would shrink the steps after a
    short clipped step, whose error estimate is smaller by (h_clipped/h)^(p+1), and round-off for
    a very short one."""
    solver.t_bound = bound
    solver.status = "running"
    if h_want is not None and hasattr(solver, "h_abs") and solver.t_old + h_want > solver.t:
        solver.h_abs = h_want
    # RK4 (no h_abs): its fixed step goes on


#: Hairer's stiffness test for the explicit Runge–Kutta pairs (DOP853 and DOPRI5 in Hairer and
#: Wanner, Solving ODEs II, Sec. IV.2): h·|λ| estimated from the last two stages, both at t + h, and
#: compared with the size of the method's stability region along the negative real axis.
STIFFNESS_BOUND = {"DOP853": 6.1, "RK45": 3.25}
#: Checked every STIFFNESS_EVERY accepted steps, then at every step while it fires; STIFFNESS_HITS
#: firings in a row stop the run.
STIFFNESS_EVERY = 1000
STIFFNESS_HITS = 15
#: RK4's fixed step: the growth of a mode over steps in a row beyond RK4's stability region that
#: stops the run (kernels.rk4_watch, which both paths run).
RK4_GROWTH = 100.0
#: A step below this (relative to max(1 s, |t|)) is a collapsing step; COLLAPSE_STEPS of them in a row
#: stop the run (a singularity the integrator is creeping towards).
COLLAPSE_RELATIVE = 1e-11
COLLAPSE_STEPS = 200


class StepCollapse(SimulationError):
    """The integrator's step size collapsed: the solution changes faster than the method can follow
    (a stiff effect, a switch narrower than the steps) or approaches a singularity."""


class StiffForMethod(SimulationError):
    """An explicit method's step size is held at its stability limit (Hairer's test): a stiff effect."""


class StepBudget(SimulationError):
    """The run took more than max_steps integrator steps."""


def monitor_slots(method, rk4_watch=True, energy=0.0) -> np.ndarray:
    """The constants of :class:`StepMonitor` for the compiled loops, and the ratio below which the
    joints' rows count as dependent (``mechanism.DEPENDENT_RATIO``: the kernels' change-point watch,
    kernels.loop_watch), in the slots kernels.MONITOR_*; RK4's stability watch (kernels.rk4_watch)
    on unless `rk4_watch` is false, its running values at 0, and its energy watch
    (kernels.energy_watch) with it, `energy` saying what the scene's energy may do
    (:func:`energy_watched`). The numpy path's StepMonitor keeps RK4's watches in such an array
    too."""
    from inerter.engine import kernels as _k
    monitor = np.zeros(_k.MONITOR_SIZE)
    if method == "RK4" and rk4_watch:
        monitor[_k.MONITOR_RK4_WATCH] = 1.0
        monitor[_k.MONITOR_RK4_GROWTH] = RK4_GROWTH
        monitor[_k.MONITOR_ENERGY_WATCH] = energy
        monitor[_k.MONITOR_ENERGY_LOWEST_HELD] = -1.0           # no lowest energy yet
    monitor[_k.MONITOR_STIFF_BOUND] = STIFFNESS_BOUND.get(method, 0.0)
    monitor[_k.MONITOR_STIFF_EVERY] = STIFFNESS_EVERY
    monitor[_k.MONITOR_STIFF_HITS] = STIFFNESS_HITS
    monitor[_k.MONITOR_COLLAPSE_RELATIVE] = COLLAPSE_RELATIVE
    monitor[_k.MONITOR_COLLAPSE_STEPS] = COLLAPSE_STEPS
    monitor[_k.MONITOR_TRIAL_SHRINK] = TRIAL_SHRINK
    monitor[_k.MONITOR_DEPENDENT] = DEPENDENT_RATIO
    return monitor


def energy_watched(mech) -> float:
    """What RK4's energy watch holds the scene `mech` to (kernels.MONITOR_ENERGY_WATCH): its
    energy conserved (``Mechanism.conserves_energy``), only lost (``Mechanism.only_loses_energy``),
    or nothing (forcing, ground motion, inputs, devices)."""
    from inerter.engine import kernels as _k
    if mech.conserves_energy():
        return _k.ENERGY_CONSERVED
    return _k.ENERGY_LOST if mech.only_loses_energy() else _k.ENERGY_OFF


def restart_lowest_energy(watch) -> None:
    """RK4's energy watch (its slots `watch`, or None) compares a scene's energy with its lowest
    from now on (kernels.energy_watch): a retune between steps changes the energy."""
    from inerter.engine import kernels as _k
    if watch is not None:
        watch[_k.MONITOR_ENERGY_LOWEST_HELD] = -1.0


def rk4_unstable_text(step, watch) -> str:
    """Why a run with RK4 stopped at UNSTABLE, from its watch's slots (kernels.rk4_watch): the
    mode's h·λ and RK4's factor on it, and its growth over its steps in a row beyond RK4's
    stability region. What to set follows (:func:`rk4_advice`)."""
    from inerter.engine import kernels as _k
    z, factor, growth = _watched_mode(watch)
    steps = int(watch[_k.MONITOR_RK4_HITS]) - 1            # from the first one's start
    return (f"RK4's step of {step:.3g} s is beyond its stability limit: h·λ ≈ {_mode_text(z)} (|h·λ| = {abs(z):.3g}) "
            f"for a mode of the scene lies outside RK4's stability region, where each step multiplies it by "
            f"|R(h·λ)| = {factor:.3g}, and it grew {growth:.3g} times over the last {steps} steps")


def _watched_mode(watch) -> tuple[complex, float, float]:
    """(the mode's step·λ, RK4's factor |R| on it, its growth over the steps counted) from the
    stability watch's slots `watch` (kernels.rk4_watch)."""
    from inerter.engine import kernels as _k
    z = complex(watch[_k.MONITOR_RK4_RE], watch[_k.MONITOR_RK4_IM])
    return (z, _k.rk4_amplification.py_func(z.real, z.imag),
            watch[_k.MONITOR_RK4_AMPLITUDE] / watch[_k.MONITOR_RK4_FIRST])


def rk4_advice(step, alpha, rows, watch, fun_at, t, y) -> str:
    """What to set after RK4's stability watch stopped a run (UNSTABLE), or its energy watch one
    whose energy can only fall (kernels.energy_watch), at the state y at t: the
    longest step that keeps every mode of the scene's linearisation there inside RK4's region
    (:func:`linearised_modes`, :func:`limiting_mode`; the watch's fit from the stages reads one
    mode, or a mixture of several: the 32-link benchmark chain at 17.5 ms read −2.94 where its
    fastest mode is −0.33 ± 3.37i, and the step it gave, 16 ms, was still outside), or the fit's
    where no mode of the linearisation is outside (a nonlinear growth) or it cannot be evaluated
    (`watch` None, no fit: a shorter step, and the fastest mode, :func:`fastest_mode_text`).
    `fun_at(α)`: the state derivative f(t, y) with Baumgarte's α. With `rows` constraint rows
    corrected at `alpha`, the modes at α/2 tell whether the correction sets the limit
    (:func:`baumgarte_text`). A state of more than LINEARISED_SIZE coordinates keeps the fit's
    (two dense eigenvalue problems of its size and 4·len(y) evaluations would take seconds)."""
    from inerter.engine import kernels as _k
    modes = linearised_modes(fun_at(alpha), t, y) if y is not None and len(y) <= LINEARISED_SIZE else None
    limit = limiting_mode(step, modes)
    adaptive = ", or use an adaptive method (DOP853; Radau or BDF for a stiff scene)"
    if limit is None and watch is None:
        return f"{fastest_mode_text(step, modes)}; set a shorter experiment.step{adaptive}"
    if limit is None:
        z = complex(watch[_k.MONITOR_RK4_RE], watch[_k.MONITOR_RK4_IM])
        return f"; {_below_about('step', step, 's', rk4_stable_fraction(z))}{adaptive}"
    fraction, z = limit
    text = (f"; linearised where it stopped, the scene's mode farthest outside the region has h·λ ≈ "
            f"{_mode_text(z)}: {_below_about('step', step, 's', fraction)}{adaptive}")
    if rows and alpha > 0.0:
        text += baumgarte_text(step, alpha, fraction, z, limiting_mode(step, linearised_modes(fun_at(alpha / 2), t, y)))
    return text


def fastest_mode_text(step, modes) -> str:
    """Where every mode of the linearisation is inside RK4's region (a run whose energy rose while
    it can only fall): the fastest one's h·λ, RK4's factor on it and the motion's own, |e^(h·λ)|.
    Inside the region, but far from the motion (a damped chain at 98 % of its limit: 0.99 a step
    against 0.29), RK4 keeps the mode alive, and the energy can rise. Empty without modes."""
    from inerter.engine import kernels as _k
    if modes is None or not len(modes):
        return ""
    z = complex(step * max(modes, key=abs))
    return (f"; linearised where it stopped, every mode of the scene is inside RK4's region, the fastest at "
            f"h·λ ≈ {_mode_text(z)}, where each step multiplies it by |R(h·λ)| = "
            f"{_k.rk4_amplification.py_func(z.real, z.imag):.3g} and the motion by |e^(h·λ)| = "
            f"{math.exp(z.real):.3g}")


#: The largest state RK4's advice linearises (:func:`rk4_advice`): a 64-link chain's 384.
LINEARISED_SIZE = 500


def linearised_modes(fun, t, y):
    """The eigenvalues of J = ∂f/∂y at (t, y), by central differences (2·len(y) evaluations of `fun`,
    each coordinate moved by ε^(1/3)·max(1, |y_i|)); None where an evaluation fails."""
    y = np.array(y, dtype=float)
    J = np.empty((len(y), len(y)))
    try:
        for i in range(len(y)):
            d = 6e-6 * max(1.0, abs(y[i]))
            up, down = y.copy(), y.copy()
            up[i] += d
            down[i] -= d
            J[:, i] = (np.asarray(fun(t, up)) - np.asarray(fun(t, down))) / (2.0 * d)
    except (SimulationError, ArithmeticError, ValueError):
        return None
    if not np.isfinite(J).all():
        return None
    return np.linalg.eigvals(J)


def limiting_mode(step, modes):
    """(the largest s ≤ 1 with s·step·λ inside RK4's region for every mode, the step·λ that sets
    it), the modes outside at s = 1 alone judged (:func:`rk4_stable_fraction`); None where none is
    outside, or `modes` is None."""
    if modes is None:
        return None
    worst = None
    for lam in modes:
        z = complex(step * lam)
        if not _outside_region(z):
            continue
        fraction = rk4_stable_fraction(z)
        if worst is None or fraction < worst[0]:
            worst = (fraction, z)
    return worst


def _mode_text(z: complex) -> str:
    """A mode's h·λ as the messages give it: a ± pair, or real."""
    re = z.real if abs(z.real) > 1e-9 * abs(z) else 0.0      # an undamped pair's, to round-off
    return f"{re:.3g} ± {z.imag:.3g}i" if z.imag else f"{re:.3g}"


def watch_so_far(step, watch) -> str:
    """For a run with RK4 that failed otherwise (terminals meeting, accelerations not finite) while
    its stability watch (kernels.rk4_watch, its slots `watch`) held at least RK4_MIN_STEPS steps in
    a row beyond the region, not yet grown RK4_GROWTH times: the mode it read and the step that keeps
    it inside, the likely cause (a stiff mode growing from round-off breaks the state first: two
    masses at h·ω = 2.9 meet after 24 such steps, grown 58 times). Empty otherwise."""
    from inerter.engine import kernels as _k
    if watch is None or watch[_k.MONITOR_RK4_WATCH] == 0.0 or watch[_k.MONITOR_RK4_HITS] < _k.RK4_MIN_STEPS:
        return ""
    z, factor, growth = _watched_mode(watch)
    return (f"; before it, RK4's stability watch had counted {int(watch[_k.MONITOR_RK4_HITS])} steps in a row "
            f"beyond the method's stability region (h·λ ≈ {_mode_text(z)}, |R(h·λ)| = "
            f"{factor:.3g}, grown {growth:.3g} times): RK4's step of "
            f"{step:.3g} s is the likely cause; {_below_about('step', step, 's', rk4_stable_fraction(z))}")


def _below_about(field: str, value: float, unit: str, fraction: float) -> str:
    """The advice to set experiment.`field` below `fraction` of its `value`, rounded down to two
    digits (RK4's region along a mode's h·λ, :func:`rk4_stable_fraction`)."""
    if fraction > 0.0:
        return f"set experiment.{field} below about {_two_digits_down(value * fraction):g} {unit}"
    return f"set a smaller experiment.{field}"


def _two_digits_down(x: float) -> float:
    """x > 0 rounded down to two significant digits: a step printed as inside the region is inside."""
    unit = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.floor(x / unit * (1 + 1e-12)) * unit


def rk4_stable_fraction(z: complex) -> float:
    """The largest s ≤ 1 (to 5e-4) with s·z inside RK4's stability region all the way from 0, as
    the watch counts it (``kernels.rk4_watch``: |R(s z)| within RK4_EXCESS of max(1, |e^(s z)|));
    0 where there is none."""
    inside = 0.0
    for s in np.linspace(0.0, 1.0, 2001)[1:]:
        if _outside_region(s * z):
            break
        inside = float(s)
    return inside


def _outside_region(z: complex) -> bool:
    """Whether RK4's watch counts a step at step·λ = z as beyond its stability region
    (``kernels.rk4_watch``: |R(z)| more than RK4_EXCESS above max(1, |e^z|))."""
    from inerter.engine import kernels as _k
    return _k.rk4_amplification.py_func(z.real, z.imag) > (1.0 + _k.RK4_EXCESS) * _k._exact_growth.py_func(z.real)


def energy_jump_advice(step, alpha, rows, watch, fun_at, t, y) -> str:
    """What follows the message of a run RK4's energy watch stopped (its slots `watch`) at the
    state y at t: for a scene that can only lose its energy, the step from its linearisation there
    (:func:`rk4_advice`, no fit); for one that conserves it, what the stability watch had counted
    (:func:`watch_so_far`). `fun_at`, `rows`, `alpha`: as rk4_advice's."""
    from inerter.engine import kernels as _k
    if watch[_k.MONITOR_ENERGY_WATCH] == _k.ENERGY_LOST:
        return rk4_advice(step, alpha, rows, None, fun_at, t, y)
    return watch_so_far(step, watch)


def failure_context(exc, settings, mech, watch=None) -> str:
    """What a run with `settings` on `mech` adds to the message of its failure `exc`: the scene's
    fastest time scale where the step size collapsed, the steps read as stiff or RK4's step was
    beyond its stability limit (``Mechanism.stiffest``), whether the constraints' Baumgarte mode is
    the last's (:func:`baumgarte_text`), and RK4's hint for a failure that does not name its cause
    (:func:`rk4_hint`), or what RK4's stability watch (its slots `watch`) had counted before
    (:func:`watch_so_far`). As the compiled loops' ``compiled.failure_text`` adds them."""
    text = ""
    inputs = np.zeros(len(mech.input_names))
    if isinstance(exc, UnstableStep):
        text += rk4_advice(settings.step, settings.alpha, mech.m, exc.watch,
                           lambda alpha: derivative(mech, inputs, alpha), exc.time, exc.state)
    if isinstance(exc, (StepCollapse, StiffForMethod, UnstableStep)):
        text += mech.stiffest()
    if isinstance(exc, EnergyJump):
        return text + energy_jump_advice(settings.step, settings.alpha, mech.m, exc.watch,
                                         lambda alpha: derivative(mech, inputs, alpha), exc.time, exc.state)
    if isinstance(exc, NAMES_ITS_CAUSE):
        return text
    return text + (watch_so_far(settings.step, watch) or rk4_hint(settings.method, False))


def baumgarte_text(step, alpha, fraction, z, at_half) -> str:
    """Whether the joints' Baumgarte correction at α = `alpha` sets RK4's step limit, `fraction` of
    `step` along the mode z = h·λ (:func:`limiting_mode`), given the limit `at_half` with α/2: a
    violation C obeys C̈ + 2αĊ + α²C = 0, a mode λ = −α (twice) that the scene's motion moves and
    splits (two_bar_2d at 0.0559 s, α·h = 2.7: its linearisation reaches −2.83, and the watch read
    −3.46), so α·h < 2.785 alone does not tell. Where halving α lengthens the limit by more than
    BAUMGARTE_RELAXED, the correction sets it: the advice scales α as the step (the correction's
    modes scale with α). Empty otherwise."""
    if at_half is not None and at_half[0] <= BAUMGARTE_RELAXED * fraction:
        return ""
    return (f"; this mode is the joints' Baumgarte correction (with experiment.baumgarte at half its value, "
            f"no mode sets a shorter limit): α = {alpha:g} 1/s makes a violation C of the joints obey "
            f"C'' + 2αC' + α²C = 0, λ = −α twice (h·α = {alpha * step:.3g}), which the motion moves to "
            f"h·λ ≈ {_mode_text(z)}; {_below_about('baumgarte', alpha, '1/s', fraction)} (the limit where it "
            f"stopped: the motion moves the mode, so leave a margin), or a shorter step")


#: How much longer RK4's step limit must get with Baumgarte's α halved for the correction to count
#: as what sets it (:func:`baumgarte_text`); a mode of the scene's own sets the same limit at α/2.
BAUMGARTE_RELAXED = 1.2


def rk4_hint(method: str, names_its_cause: bool) -> str:
    """What to add to the message of a run with RK4 that failed otherwise than by a check that
    names its cause, its stability watch or its step budget (`names_its_cause`): where terminals
    meet, accelerations are not finite or a pose is singular, a step too long for a nonlinear
    motion, which the watch of linear modes does not see (``kernels.rk4_watch``), can have driven
    the state there. Empty for other methods."""
    if method != "RK4" or names_its_cause:
        return ""
    return "; with RK4's fixed step this can also be a step too long for the motion, which grows the state " \
        "until it gets there: a shorter experiment.step, or DOP853, shows whether it does"


class UnstableStep(SimulationError):
    """RK4's fixed step is beyond the method's stability limit and a mode grows (kernels.rk4_watch):
    `watch`, the watch's slots when it stopped the run, `state` the state at the start of the step."""

    def __init__(self, message: str, time: float | None = None, watch=None, state=None):
        super().__init__(message, time)
        self.watch, self.state = watch, state


class EnergyJump(SimulationError):
    """One RK4 step changed the energy of a scene that conserves it by more than it held, or the
    energy of one that can only lose it rose above its lowest by more than that
    (kernels.energy_watch): `watch`, the watch's slots when it stopped the run, `state` the state
    at the start of the step."""

    def __init__(self, message: str, time: float | None = None, watch=None, state=None):
        super().__init__(message, time)
        self.watch, self.state = watch, state


def energy_jump_text(step, watch) -> str:
    """Why a run with RK4 stopped at ENERGY_JUMP, from its watch's slots (kernels.energy_watch).
    A scene that can only lose its energy: what to set follows (:func:`rk4_advice`)."""
    from inerter.engine import kernels as _k
    if watch[_k.MONITOR_ENERGY_WATCH] == _k.ENERGY_LOST:
        return _energy_rise_text(step, watch)
    before, after, held = watch[_k.MONITOR_ENERGY_LAST], watch[_k.MONITOR_ENERGY_NOW], watch[_k.MONITOR_ENERGY_HELD]
    return (f"an RK4 step (experiment.step = {step:.3g} s) changed the scene's energy from {before:.6g} J to "
            f"{after:.6g} J, by more "
            f"than the {held:.3g} J its bodies and elements held (the sum of their T + V): the scene conserves its "
            f"energy (no forcing, no damping), so the step is too long for the motion there; set a shorter "
            f"experiment.step, or use an adaptive method (DOP853)")


def _energy_rise_text(step, watch) -> str:
    from inerter.engine import kernels as _k
    lowest, now = watch[_k.MONITOR_ENERGY_LOWEST], watch[_k.MONITOR_ENERGY_NOW]
    held = watch[_k.MONITOR_ENERGY_LOWEST_HELD]
    return (f"RK4's steps (experiment.step = {step:.3g} s) raised the scene's energy from its lowest, "
            f"{lowest:.6g} J, to {now:.6g} J, by more than the {held:.3g} J its bodies and elements held "
            f"there (the sum of their T + V): the scene can only lose energy (dampers, no forcing), so the "
            f"steps are too long for its motion")


#: The numpy path's failures whose message names their cause: no RK4 hint (:func:`rk4_hint`).
NAMES_ITS_CAUSE = (UnstableStep, StepBudget, EnergyJump)


#: scipy's words when an implicit method's step size reaches the spacing of floating-point numbers.
SCIPY_COLLAPSE = "Required step size is less than spacing between numbers."


class StepMonitor:
    """Watches an integration after every accepted step: the mechanism's own checks (terminals
    meeting, Euler-angle singularity), the explicit methods' stiffness (Hairer's test), RK4's step
    beyond its stability limit (``kernels.rk4_watch``), a step size collapsing towards a
    singularity, and the step budget max_steps. Each stops the run with a
    SimulationError that names the method and what to do. A step that passes them moves the 3D
    rotational elements' angles on (``mech.wind``: they wind past half a turn from there)."""

    def __init__(self, mech, method, max_steps, watch=None):
        """`watch`: RK4's stability watch to go on with (:func:`monitor_slots`; a co-simulation
        keeps one across its steps), a fresh one if None."""
        self.mech, self.method, self.max_steps = mech, method, max_steps
        self.bound = STIFFNESS_BOUND.get(method)
        if watch is None and method == "RK4":
            watch = monitor_slots("RK4", energy=energy_watched(mech))
        self.watch = watch
        self.energy_on = False
        if watch is not None:
            from inerter.engine import kernels as _k
            watch[_k.MONITOR_ENERGY_HELD] = -1.0         # the energy watch starts at this call's state
            self.energy_on = watch[_k.MONITOR_ENERGY_WATCH] != 0.0
        self.steps = 0
        self.hits = self.calm = 0
        self.small = 0
        self.loops = mech.closed_loops() > 0         # only a closed loop can reach a change point
        self.terminals = getattr(mech, "watches_terminals", False)   # terminals that can meet
        self._rows = None                            # (q, C_v(q)) at the last step's end

    def after_step(self, solver, y_old):
        self.steps += 1
        t, t_old = solver.t, solver.t_old
        h = t - t_old
        if self.steps > self.max_steps:
            raise StepBudget(
                f"more than max_steps = {self.max_steps} integrator steps (step size {h:.3g} s): "
                + max_steps_advice(self.method), t_old)
        if self.terminals and self.mech.chord_margin(y_old, solver.y) <= 1.0:
            self.stop_at_meeting(solver, t_old, y_old, getattr(solver, "f_old", None))
        self.mech.check_step(y_old, solver.y, t, t_old)
        if self.loops:
            self._watch_loops(solver, y_old)
        if self.bound is not None and (self.hits or self.steps % STIFFNESS_EVERY == 0):
            self._stiffness(solver, h)
        if self.watch is not None:
            self._rk4_stability(solver, h, y_old)
        if h < COLLAPSE_RELATIVE * max(1.0, abs(t)):
            self.small += 1
            if self.small >= COLLAPSE_STEPS:
                raise StepCollapse(
                    f"the {self.method} step size collapsed ({self.small} steps in a row below "
                    f"{COLLAPSE_RELATIVE:g}·max(1 s, t), the last {h:.3g} s): the solution is approaching a "
                    f"singularity" + self.mech.diagnose(solver.y), t_old)
        else:
            self.small = 0
        self.mech.wind(solver.y, y_old, h)
        if self.energy_on:
            self._energy(solver, y_old)

    def stop_at_meeting(self, solver, t_old, y_old, f_old=None, t_new=None):
        """Terminals meet within the step from (t_old, y_old) to solver.t (or to `t_new`, RK4's step
        whose stage found them meeting): raise TerminalsMeet at the meeting, located as the
        compiled loops locate it (``kernels.locate_meeting``, ``kernels._rk4_to_meeting``), its
        `located` the dense outputs valid up to it, for the samples before it. An adaptive
        method's step, which its error control accepted, is valid up to the meeting: located by
        bisection on its dense output, keeping the half whose chord brings the terminals within
        their limit (:meth:`Mechanism.chord_margin`; the earlier where both do, the closer where
        neither does). RK4's fixed step is not: taken again from its start in ever shorter steps
        (:func:`_rk4_to_meeting`), only those that keep the terminals apart kept."""
        if self.method == "RK4":
            t_hi = solver.t if t_new is None else t_new
            lo, y_lo, pieces = _rk4_to_meeting(solver.fun, self.mech, t_old, y_old, f_old, t_hi)
        else:
            dense = solver.dense_output()
            lo, hi, y_lo, y_hi, pieces = t_old, solver.t, y_old, solver.y, [dense]
            while lo < 0.5 * (lo + hi) < hi:
                mid = 0.5 * (lo + hi)
                y_mid = dense(mid)
                first = self.mech.chord_margin(y_lo, y_mid)
                if first <= 1.0 or first <= self.mech.chord_margin(y_mid, y_hi):
                    hi, y_hi = mid, y_mid
                else:
                    lo, y_lo = mid, y_mid
            y_lo = dense(lo) if lo > t_old else y_old
        self.mech.wind(y_lo, y_old, lo - t_old)
        exc = TerminalsMeet(self.mech.meeting_message(y_lo, lo), lo)
        exc.located = pieces
        raise exc

    def _rows_at(self, y):
        """C_v at the state y (the joints' rows; None where they are not finite)."""
        q = np.asarray(y[:self.mech.nq], dtype=float)
        if self._rows is not None and np.array_equal(self._rows[0], q):
            return self._rows[1]
        rows = self.mech.constraints(q, np.zeros(self.mech.n))[1]
        return rows if np.all(np.isfinite(rows)) else None

    def _watch_loops(self, solver, y_old):
        """A change point of a mechanism whose joints close a loop stops the run, as the compiled
        loops' watch does (kernels.loop_watch, docs/changepoint.md): the step reaches it (the rows
        at its end within DEPENDENT_RATIO of dependent, Gram-Schmidt's bound there, the SVD's here)
        or jumps across it (det(C_v(q₁) C_v(q₀)ᵀ) ≤ 0, located by bisection on the step's dense
        output and confirmed by the ratio there: rows turning by a right angle without a loss of
        rank are not one). scipy's integrators (Radau, BDF, LSODA) and the projection treatment
        went on across it along one branch or the other without a word."""
        rows0, rows1 = self._rows_at(y_old), self._rows_at(solver.y)
        self._rows = (np.array(solver.y[:self.mech.nq], dtype=float), rows1)
        if rows0 is None or rows1 is None:
            return
        where = solver.t
        if not _rank_kept(rows1):
            q = solver.y
        elif np.linalg.det(rows1 @ rows0.T) <= 0.0:
            dense = solver.dense_output()
            a, b = solver.t_old, solver.t
            for _ in range(60):                      # to adjacent floats within the step
                mid = 0.5 * (a + b)
                if not a < mid < b:
                    break
                inside = self._rows_at(dense(mid))
                if inside is not None and np.linalg.det(inside @ rows0.T) > 0.0:
                    a = mid
                else:
                    b = mid
            q, where = dense(b), b
            if _rank_kept(self._rows_at(q)):
                return
        else:
            return
        raise SimulationError("a step reaches a pose where the joints' constraint rows lose rank"
                              + self.mech.diagnose(q), where)

    def _rk4_stability(self, solver, h, y_old):
        """RK4's stability watch on the step just taken: the kernels' (``kernels.rk4_watch``), run
        uncompiled."""
        from inerter.engine import kernels as _k
        k2, k3 = solver.midpoints
        if _k.rk4_watch.py_func(solver.f_old, k2, k3, h, solver.h, self.watch) != _k.OK:
            raise UnstableStep(rk4_unstable_text(solver.h, self.watch), solver.t_old, watch=self.watch.copy(),
                               state=np.array(y_old))

    def _energy(self, solver, y_old):
        """RK4's energy watch on a scene that conserves its energy or can only lose it: the kernels'
        (``kernels.energy_watch``), run uncompiled, at the step's end (after the 3D angles wound on,
        as the compiled loop) and, at the first step of a call, at its start."""
        from inerter.engine import kernels as _k
        mech = self.mech
        nq, n = mech.nq, mech.n
        if self.watch[_k.MONITOR_ENERGY_HELD] < 0.0:
            _k.energy_watch.py_func(*mech.energy_held(y_old[:nq], y_old[nq:nq + n], y_old[nq + n:]), self.watch)
        y = solver.y
        energy, held = mech.energy_held(y[:nq], y[nq:nq + n], y[nq + n:])
        if _k.energy_watch.py_func(energy, held, self.watch) != _k.OK:
            raise EnergyJump(energy_jump_text(solver.t - solver.t_old, self.watch), solver.t_old,
                             watch=self.watch.copy(), state=np.array(y_old))

    def _stiffness(self, solver, h):
        K = getattr(solver, "K", None)
        A = getattr(solver, "A", None)
        y_old = getattr(solver, "y_old", None)
        if K is None or A is None or y_old is None:
            return
        s = solver.n_stages
        y_stage = y_old + h * (K[:s - 1].T @ A[s - 1, :s - 1])       # the last stage's argument (c = 1)
        den = float(np.linalg.norm(solver.y - y_stage))
        if den == 0.0:
            return
        hlam = h * float(np.linalg.norm(K[s] - K[s - 1])) / den
        if hlam > self.bound:
            self.calm = 0
            self.hits += 1
            if self.hits >= STIFFNESS_HITS:
                raise StiffForMethod(
                    f"the scene is stiff for {self.method}: its step size ({h:.3g} s) is held at the method's "
                    f"stability limit (h·|λ| ≈ {hlam:.3g} > {self.bound:g} in {self.hits} steps in a row, "
                    f"Hairer's test) after {self.steps} steps; use method = \"Radau\" or \"BDF\" (implicit)",
                    solver.t_old)
        else:
            self.calm += 1
            if self.calm >= 6:
                self.hits = 0


def _rank_kept(rows) -> bool:
    """The joints' rows of full rank (:func:`inerter.model.mechanism.rank_kept`), or rows that
    cannot be evaluated."""
    return rows is None or not rows.size or rank_kept(rows)


#: A trial step of an explicit Runge-Kutta method that reaches a state where the accelerations cannot
#: be evaluated is rejected and tried again this much shorter (scipy's smallest step-size factor).
TRIAL_SHRINK = 0.2
#: The methods whose trial step is tried again shorter where an evaluation fails (:func:`_step`):
#: their whole state between steps is y, f and the step size (BDF's differences are scaled to its
#: step size, and LSODA's state is Fortran's: neither is shortened from outside).
SHRINK_ON_FAILURE = ("DOP853", "RK45", "Radau")


def _rk4_to_meeting(fun, mech, t, y, f, t_hi):
    """RK4's step from (t, y, f) to t_hi brings terminals together (:meth:`StepMonitor.stop_at_meeting`):
    taken again from its start in ever shorter steps, by bisection of what is left of it down to
    adjacent floats, each kept where it keeps the terminals apart (:meth:`Mechanism.chord_margin`
    above 1, no stage where they meet) and halved where it does not, as the compiled loop does
    (``kernels._rk4_to_meeting``). Returns (the time it stops at, the state there, the cubic
    Hermite of each step kept)."""
    from inerter.engine.integrators import Hermite, rk4_step

    pieces = []
    while t < 0.5 * (t_hi - t) + t < t_hi:
        part = 0.5 * (t_hi - t)
        mid = t + part
        try:
            y_mid, f_mid, _ = rk4_step(fun, t, y, f, part)
        except TerminalsMeet:
            t_hi = mid
            continue
        if mech.chord_margin(y, y_mid) <= 1.0:
            t_hi = mid
            continue
        pieces.append(Hermite(t, mid, y, y_mid, f, f_mid))
        t, y, f = mid, y_mid, f_mid
    return t, y, pieces


def _step(solver, method, monitor=None):
    """solver.step(), its failures as SimulationError at the last good time.

    DOP853, RK45 and Radau: a stage or a Newton iterate of the trial step that cannot be evaluated
    (a recoverable SimulationError: a wild stage of too long a step, an iterate far from the
    solution that brings an element's terminals together) rejects the step, which is tried again
    TRIAL_SHRINK times as long, until it is shorter than 10 ulp of t; scipy's step leaves the
    solver's state as it was when an evaluation raises (Radau's factorisations, made for the old
    step size, are dropped so that it makes them anew, as it does after a step it rejects)."""
    t = solver.t
    while True:
        try:
            with np.errstate(all="ignore"):     # a wild stage overflows; non-finite results are checked
                message = solver.step()
            break
        except SimulationError as exc:
            if method == "RK4" and monitor is not None and isinstance(exc, TerminalsMeet) and exc.recoverable:
                # a stage where terminals meet: the meeting lies within this step
                monitor.stop_at_meeting(solver, t, solver.y, solver.f, t + min(solver.h, abs(solver.t_bound - t)))
            shrinkable = exc.recoverable and hasattr(solver, "h_abs") and method in SHRINK_ON_FAILURE
            if shrinkable and solver.h_abs * TRIAL_SHRINK >= 10 * abs(np.nextafter(t, np.inf) - t):
                solver.h_abs *= TRIAL_SHRINK
                if method == "Radau":
                    solver.LU_real = solver.LU_complex = None
                continue
            if exc.time is None:
                raise type(exc)(exc.message, t) from None
            raise
        except ValueError as exc:
            if "infs or NaNs" not in str(exc):
                raise
            # scipy's Radau and BDF factorise I/h − J: a step or a Jacobian that overflowed
            raise SimulationError(f"the {method} integrator failed: its Newton matrix is not finite (step "
                                  f"{getattr(solver, 'h_abs', float('nan')):.3g} s: the tolerances may be "
                                  "too small to resolve, or the state overflowed)", t) from None
    if solver.status == "failed":
        if message == SCIPY_COLLAPSE:                 # Radau's and BDF's: said in the project's words
            raise StepCollapse(f"the {method} step size collapsed (the step it asked for, after "
                               f"{solver.h_abs:.3g} s, is below the spacing of floating-point numbers at t)", t)
        raise SimulationError(f"the {method} integrator failed: {message}", t)


@dataclass
class Run:
    """What :func:`integrate` produced: samples, the solver's dense output, and how it ended.
    ``dense(t)``: the states at t, shape (len(y),) for a scalar t and (len(y), len(t)) for an
    array (scipy's OdeSolution here; the compiled loop's :class:`~inerter.engine.compiled.DenseOutput`
    on the compiled path, None where it kept none)."""
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
    everything computed up to the last good step (status "failed", message says where and why).

    The integration restarts at each jump of the right-hand side (``mech.discontinuities``); DOP853,
    RK45 and RK4 run on through its kinks (``mech.kinks``), their steps clipped to end on each
    (:data:`THROUGH_KINKS`), as the compiled loop does, and take the same steps; the other methods
    restart at a kink too.

    The run works on its own copy of `mech` (:func:`for_run`): the 3D rotational elements' angles
    wind on from the initial pose, the screw efficiencies' modes start at +1, and neither `mech`
    nor another run or :class:`Stepper` of it sees them change. ``run.extra["mechanism"]`` is that
    copy, as the run left it."""
    mech = for_run(mech)
    with mech.wound_from_start():           # the angles are measured from the initial pose
        run = _integrate(mech, settings, inputs)
    run.extra["mechanism"] = mech
    return run


def output_grid(stop_time: float, interval: float) -> np.ndarray:
    """The output samples of a run: 0, h, 2h, ... below the stop time, and the stop time itself,
    always the last (an interval that does not divide the stop time leaves a shorter last one, as an
    importer's communication steps do). A multiple of h within 1e-9 of the stop time (relative, as
    fmpy's ``isclose``) is the stop time."""
    grid = np.arange(0.0, stop_time + 0.5 * interval, interval)
    if stop_time - grid[-1] > 1e-9 * stop_time:
        return np.append(grid, stop_time)
    grid[-1] = stop_time
    return grid


def _integrate(mech, settings: Settings, inputs=None) -> Run:
    """:func:`integrate`, its angles wound on from where the mechanism holds them."""
    n = mech.nq
    fun = derivative(mech, inputs, settings.alpha)
    grid = output_grid(settings.stop_time, settings.output_interval)
    y = initial_state(mech)
    out = np.empty((len(grid), len(y)))
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
    monitor = StepMonitor(mech, settings.method, settings.max_steps)
    record = _WindingRecord(mech, len(grid))
    solver = None
    try:
        while t0 < settings.stop_time:
            # With projection, each output interval is a fresh integration from a projected state;
            # a jump of the right-hand side (a step force's switch) also ends a segment (the
            # integrator restarts there), and so does a kink (a ground record's sample) for a
            # method that does not run on through it (THROUGH_KINKS).
            t_end = grid[k] if project else settings.stop_time
            switch = next_jump(mech, t0, t_end, settings.method)
            if switch is not None:
                t_end = switch
            fun = derivative(mech, inputs, settings.alpha, switch)
            ahead = kinks(mech, t0, t_end) if settings.method in THROUGH_KINKS else []
            ahead.append(t_end)                 # the bounds the solver is given, one after the other
            solver = make_solver(settings.method, fun, t0, y, ahead[0], settings.rtol, settings.atol,
                                 settings.step, first_step)
            i = 0
            dense_prev_y = y.copy()
            while solver.status == "running":
                h_want = getattr(solver, "h_abs", None)
                _step(solver, settings.method, monitor)
                steps += 1
                if solver.status == "finished" and solver.t < t_end:        # at a kink
                    i += 1
                    _on_through_kink(solver, h_want, ahead[i])
                monitor.after_step(solver, dense_prev_y)
                dense_prev_y = solver.y.copy()
                dense = solver.dense_output()
                ts.append(solver.t)
                interpolants.append(dense)
                k = _step_samples(grid, k, solver, dense, out, record)
            evaluations += solver.nfev
            y = solver.y
            if project:
                y = _project(mech, y)
                if abs(grid[k - 1] - solver.t) <= 1e-12 * max(1.0, solver.t):
                    out[k - 1] = y
            # Projection restarts go on with the step size the error control proposed; after a
            # step force the solution's derivative jumps, and the integrator starts afresh.
            first_step = getattr(solver, "h_abs", None) if (project and switch is None) else None
            max_drift = max(max_drift, mech.constraint_residual(y[:n]))
            t0 = solver.t
    except SimulationError as exc:
        status = "failed"
        message = str(exc)
        k = _samples_before_meeting(exc, grid, k, out, record, ts, interpolants)
        if solver is not None and not isinstance(exc, TerminalsMeet) and "terminals" not in message:
            found = mech.diagnose(solver.y)
            message += found if found not in message else ""    # the monitor's collapse says it already
        message += failure_context(exc, settings, mech, monitor.watch)
    cpu = _time.process_time() - start
    for i in range(1, k):
        max_drift = max(max_drift, mech.constraint_residual(out[i, :n]))
    dense = None
    if interpolants:
        from scipy.integrate import OdeSolution

        dense = OdeSolution(np.array(ts), interpolants)
    return Run(grid[:k].copy(), out[:k].copy(), dense, status, message, steps, evaluations, cpu, max_drift,
               record.extra(k))


def _samples_before_meeting(exc, grid, k, out, record, ts, interpolants):
    """Where the run stopped at a meeting of terminals located within its last step
    (:meth:`StepMonitor.stop_at_meeting`): out[k:] = the samples of the grid up to it, from the dense
    outputs valid there (`exc.located`), which join the run's (`ts`, `interpolants`); the first k
    not written."""
    pieces = getattr(exc, "located", None)
    if not pieces:
        return k
    for piece in pieces:
        first, end = k, min(piece.t_max, exc.time)
        while k < len(grid) and grid[k] <= end:
            out[k] = piece(grid[k])
            k += 1
        ts.append(piece.t_max)
        interpolants.append(piece)
        record.step(grid[first:k], out[first:k], end, piece(end))
    return k


def _step_samples(grid, k, solver, dense, out, record):
    """out[k:] = the dense output of the step that has just ended (at solver.t), at the times of the
    grid it covers (within 1e-12·max(1 s, t) of its end), recorded with their 3D rotational
    elements' angles (:class:`_WindingRecord`); the first k not written."""
    first, t = k, solver.t
    while k < len(grid) and grid[k] <= t + 1e-12 * max(1.0, t):
        out[k] = dense(grid[k])
        k += 1
    record.step(grid[first:k], out[first:k], t, solver.y)
    return k


class _WindingRecord:
    """What :func:`integrate` records of its 3D rotational elements (nothing without them): after
    each accepted step, the φ_ref the step wound them to (at its end), and their angle at each
    sample the step covers, on the branch the integration followed (``mech.angles_between``, from
    the step's end). A sample's outputs are then read wound from its own angle (``Result``), not
    from the sample before, which may lie any number of turns away."""

    def __init__(self, mech, samples):
        self.mech = mech
        count = len(mech.windings) if hasattr(mech, "windings") else 0
        self.samples = np.zeros((samples, count)) if count else None     # 0 at t = 0
        self.steps = []
        self.k = 1

    def step(self, times, states, t, y):
        """After an accepted step to (t, y) (wound: StepMonitor.after_step) that gave the samples
        `states` at `times`."""
        if self.samples is None:
            return
        held = np.array(self.mech.windings, dtype=float)
        self.steps.append(held)
        if len(times):
            ends = np.ones(len(times))
            self.samples[self.k:self.k + len(times)] = self.mech.angles_between(
                t * ends, np.tile(y, (len(times), 1)), np.tile(held, (len(times), 1)), times, states)
            self.k += len(times)

    def extra(self, k) -> dict:
        """``run.extra``'s "windings" (samples × elements) and "step_windings" (steps × elements,
        in the order of the dense output's segments); {} without such elements."""
        if self.samples is None:
            return {}
        steps = np.array(self.steps, dtype=float).reshape(-1, self.samples.shape[1])
        return {"windings": self.samples[:k].copy(), "step_windings": steps}


def dense_windings(run, times, mech):
    """(len(times) × elements) the 3D rotational elements' angles at each time of the run's dense
    output, on the branch its integration followed: a compiled run's dense output knows its own
    (``windings_at``); scipy's, from the φ_ref recorded at the end of the step (the segment
    OdeSolution takes) that gives the time (``run.extra["step_windings"]``), by `mech` (the run's:
    its kernel where it has one, ``angles_between``). None where the run recorded none."""
    sol = run.dense
    if hasattr(sol, "windings_at"):
        return sol.windings_at(times)
    steps = run.extra.get("step_windings")
    if sol is None or steps is None or not len(steps):
        return None
    kernel = run.extra.get("kernel")
    between = kernel.windings_between if getattr(kernel, "compiled", False) else mech.angles_between
    t = np.asarray(times, dtype=float).reshape(-1)
    i = np.clip(np.searchsorted(sol.ts, t, side="left") - 1, 0, len(steps) - 1)
    ends = np.asarray(sol.ts, dtype=float)[i + 1]
    return between(ends, np.asarray(sol(ends)).T.reshape(len(t), -1), steps[i], t,
                   np.asarray(sol(t)).T.reshape(len(t), -1))


#: Methods whose integration a :class:`Stepper` keeps running across communication points (the
#: others restart at every point: RK4, whose last step lands on it, and LSODA, whose state is
#: Fortran's).
RUNS_ON = ("DOP853", "RK45", "Radau", "BDF")


def max_steps_advice(method: str) -> str:
    """What to do when a run takes more than max_steps steps: an explicit method's small steps are
    likely stiffness (an implicit method takes long steps there); an implicit one's, or RK4's fixed
    ones, are not helped by switching to Radau or BDF."""
    if method in ("DOP853", "RK45"):
        return f"the scene may be stiff for {method}; try method = \"Radau\" or \"BDF\""
    return "raise experiment.max_steps, or " + ("lengthen experiment.step" if method == "RK4" else
                                                 "loosen experiment.rtol")


class Stepper:
    """Co-simulation stepping: inputs held over each step; `step(t_end)` advances the state and,
    on failure, leaves (time, state) exactly as before.

    DOP853, RK45, Radau and BDF keep one scipy integration running across communication points: a
    step advances it until its last step covers the point and takes the state there from that
    step's dense output, as :func:`integrate` samples its output grid. Its steps are bounded by the
    experiment's stop time (`stop_time`, where the importer gave one; dropped if it steps past it)
    and by the jumps of the right-hand side (a step force's switch), where it restarts as the whole
    run does, and clipped to end on its kinks (a ground record's samples), through which DOP853 and
    RK45 run on as the whole run does (Radau and BDF restart there); so while the
    inputs hold, the states equal the whole run's bit for bit. An input that changes is a
    discontinuity: the integration restarts at that point with the step size the error control
    proposed last, and that segment lands on the next point. RK4, LSODA and the projection
    treatment restart at every point (projection projects the state there). (time, state, inputs,
    the running integration's own state) is the complete state: a rolled-back step repeats bit for
    bit."""

    #: Whether the stepper works on its own copy of the mechanism (:func:`for_run`): its run state
    #: (φ_ref, modes) lives there. CompiledStepper's lives in its kernel's tables (Kernel.for_run).
    owns_mechanism = True

    def __init__(self, mech, settings: Settings, signals, stop_time=None):
        if self.owns_mechanism:
            mech = for_run(mech)              # its own run state: another stepper of the model has its own
            signals = signals.for_run(numpy_mechanism(mech)) if signals is not None else None
        self.mech = mech
        self.settings = settings
        self.signals = signals
        self.time = 0.0
        self.y = initial_state(mech)
        self.inputs = np.zeros(len(mech.input_names))
        self.h = None
        self.input_index = {name: i for i, name in enumerate(mech.input_names)}
        self.steps = 0
        self.path = "numpy"
        self.t_bound = float(stop_time) if stop_time is not None and stop_time > 0 else np.inf
        if self.owns_mechanism:
            mech.reset_windings()             # the angles are measured from the initial pose
        self._runs_on = settings.method in RUNS_ON and settings.constraint != "projection"
        self._solver = None                   # the running integration (scipy OdeSolver)
        self._segment = None                  # its (end, ends at a jump)
        self._dense = None                    # the dense output of its last step, once asked for
        self._input_moved = False             # an input changed since the last step
        self._meeting = None                  # (time, message): terminals meet within its last step
        self._watch = None                    # RK4's stability watch across its steps, from the first on

    def set_input(self, name, value):
        value = float(value)
        if not np.isfinite(value):
            raise SimulationError(f"input {name} = {value!r} is not finite; expected a finite force in N; "
                                  "the input keeps its previous value", self.time)
        i = self.input_index[name]
        if self.inputs[i] != value:
            self._solver = None               # a discontinuity: the integration restarts here
            self._input_moved = True
        self.inputs[i] = value

    def retune(self, mech, signals):
        """Go on from the current state with the element coefficients and point-force numbers of
        `mech`, the same scene read with other parameter values (``Model.with_overrides``): a
        discontinuity, the integration restarts here, as after an input change. Raises ValueError,
        the stepper unchanged, where `mech` differs in anything else (geometry, masses, ...)."""
        from inerter.engine.tables import check_retune
        check_retune(self.mech.scene, mech.scene)
        # the other model's mechanism, a copy of its own (on its kernel where this one runs on one)
        mech = self.mech.retuned(mech) if hasattr(self.mech, "retuned") else for_run(mech)
        mech.windings = self.mech.windings    # the angles wind on from where they are
        self.mech, self.signals = mech, signals.for_run(numpy_mechanism(mech))
        self._solver = None
        self._input_moved = True
        restart_lowest_energy(self._watch)

    def step(self, t_end):
        t_end = float(t_end)
        if not t_end > self.time:
            raise SimulationError(f"step to t = {t_end!r} is not after the current time", self.time)
        monitor = StepMonitor(self.mech, self.settings.method, self.settings.max_steps, self._watch)
        self._watch = monitor.watch
        try:
            if self._runs_on:
                y = self._run_on(t_end, monitor)
                h = getattr(self._solver, "h_abs", self.h)
            else:
                y, h = self._restarted(t_end, monitor)
            if not np.all(np.isfinite(y)):
                raise SimulationError("the state became non-finite", t_end)
        except SimulationError as exc:
            self._solver = None               # the next step restarts at (time, y), left as they were
            exc.append(failure_context(exc, self.settings, self.mech, monitor.watch))
            raise
        except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
            self._solver = None
            raise SimulationError(f"the step could not be completed: {exc}", self.time) from None
        self.y = y
        self.time = t_end
        self.h = h
        self.steps += monitor.steps
        self._input_moved = False

    def _start(self, t0, y0, h, bound):
        """A new segment of the integration from (t0, y0), to `bound` or to the first jump before it
        (with the forces' values from before it, as :func:`integrate`); the solver's own bound is
        the segment's first kink, where it runs on (:meth:`_next_kink`), or its end."""
        s = self.settings
        switch = next_jump(self.mech, t0, bound, s.method)
        end = bound if switch is None else switch
        fun = derivative(self.mech, self.inputs.copy(), s.alpha, switch)
        first = next_kink(self.mech, t0, end) if s.method in THROUGH_KINKS else end
        self._solver = make_solver(s.method, fun, t0, np.array(y0, dtype=float), first, s.rtol, s.atol, s.step, h)
        self._segment = (end, switch is not None)
        self._dense = None
        self._meeting = None
        return self._solver

    def _next_kink(self, solver, h_want):
        """After a step: where the solver stopped at a kink inside its segment, it runs on towards
        the next kink or the segment's end (:func:`_on_through_kink`)."""
        end = self._segment[0]
        if solver.status == "finished" and solver.t < end:
            _on_through_kink(solver, h_want, next_kink(self.mech, solver.t, end))

    def _run_on(self, t_end, monitor):
        """Advance the running integration until its last step covers t_end; the state there."""
        s = self.settings
        if t_end > self.t_bound:               # the importer went past its stop time
            self.t_bound = np.inf
        # Right after an input changed, the segment lands on t_end; otherwise it runs on.
        bound = t_end if self._input_moved else self.t_bound
        solver = self._solver
        if solver is None:
            solver = self._start(self.time, self.y, self.h, bound)
        while True:
            if self._meeting is not None and t_end > self._meeting[0]:
                raise TerminalsMeet(self._meeting[1], self._meeting[0])
            covered = solver.t_old is not None and t_end <= solver.t + 1e-12 * max(1.0, solver.t)
            if covered:
                break
            if solver.status == "finished":    # at a switch, or at a stop time the importer passed
                end, switched = self._segment
                solver = self._start(solver.t, solver.y, None if switched else getattr(solver, "h_abs", None),
                                     max(bound, t_end))
            previous = solver.y.copy()
            h_want = getattr(solver, "h_abs", None)
            _step(solver, s.method, monitor)
            self._next_kink(solver, h_want)
            try:
                monitor.after_step(solver, previous)
            except TerminalsMeet as exc:      # the states up to the meeting are the crossing step's
                if getattr(exc, "located", None) is None or t_end > exc.time:
                    raise
                self._meeting = (exc.time, exc.message)
            self._dense = None
        if self._dense is None:
            self._dense = solver.dense_output()
        return self._dense(t_end)

    def _restarted(self, t_end, monitor):
        """RK4, LSODA, projection: the integration restarts at the communication point, with the
        last step size, and its last step lands on t_end (a jump or a kink inside ends a segment,
        and the next one starts afresh). The state at t_end and the step size to restart with."""
        s = self.settings
        t0, y, h = self.time, self.y, self.h
        eps = 1e-12 * max(1.0, abs(t_end))
        # a kink ends a segment too (jumps without a method): this readable reference restarts there
        ends = [t for t in jumps(self.mech, t0 + eps, t_end - eps)] + [t_end]
        for end in ends:
            jump = end if jumps(self.mech, end - eps, end + eps) else None
            fun = derivative(self.mech, self.inputs.copy(), s.alpha, jump)
            solver = make_solver(s.method, fun, t0, y, end, s.rtol, s.atol, s.step, h)
            previous = y
            while solver.status == "running":
                _step(solver, s.method, monitor)
                monitor.after_step(solver, previous)
                previous = solver.y.copy()
            t0, y, h = solver.t, solver.y, getattr(solver, "h_abs", None)
            if jump is not None:        # the derivative jumps here: a fresh start after it
                h = None
        if s.constraint == "projection":
            y = _project(self.mech, y)
        return y, h

    def output_values(self) -> list:
        """The outputs at the current time, in the order of ``signals.names``."""
        if hasattr(self.mech, "output_values"):          # the kernels' outputs (internal states included)
            return self.mech.output_values(self.signals, self.time, self.y, self.inputs, self.settings.alpha)
        n, nv = self.mech.nq, self.mech.nq + self.mech.n
        return self.signals.evaluate(self.time, self.y[:n], self.y[n:nv], self.inputs, self.settings.alpha,
                                     z=self.y[nv:]).tolist()

    def outputs(self) -> dict:
        return dict(zip(self.signals.names, self.output_values()))

    def get_state(self) -> bytes:
        running = None if self._solver is None else (self._segment, solver_state(self._solver))
        return pickle.dumps((self.time, self.y.copy(), self.h, self.inputs.copy(), self.steps, self.t_bound,
                             self._input_moved, running, self.mech.windings, self._meeting,
                             None if self._watch is None else self._watch.copy()))

    def set_state(self, blob: bytes):
        (self.time, y, self.h, inputs, self.steps, self.t_bound, self._input_moved, running,
         self.mech.windings, meeting, self._watch) = load_state(blob)
        self.y = np.array(y)
        self.inputs = np.array(inputs)
        self._solver = self._dense = None
        if running is not None:
            (end, switched), state = running
            solver = self._start(state["t"], state["y"], None, end)
            restore_solver_state(solver, state)
            self._segment = (end, switched)
            self._meeting = meeting           # the running integration's last step meets terminals


#: The globals a stepper's state (:meth:`Stepper.get_state`, ``CompiledStepper.get_state``) holds,
#: by module, for every method on both paths: numpy's arrays and scalars (their reconstruction
#: functions, under numpy 2's module names and numpy 1's; ``_frombuffer``: pickle protocol 5's),
#: the dense output Radau keeps to start its Newton iteration (the numpy path snapshots scipy's
#: solver objects: :func:`solver_state`), the compiled path's running integration, and builtins a
#: solver's attributes may hold. Nothing else is looked up (:class:`StateUnpickler`).
STATE_GLOBALS = {
    "numpy": {"ndarray", "dtype"},
    "numpy._core.multiarray": {"_reconstruct", "scalar"},
    "numpy.core.multiarray": {"_reconstruct", "scalar"},
    "numpy._core.numeric": {"_frombuffer"},
    "numpy.core.numeric": {"_frombuffer"},
    "scipy.integrate._ivp.radau": {"RadauDenseOutput"},
    "inerter.engine.compiled": {"Running"},
    "builtins": {"complex", "set", "frozenset", "slice"},
}


class StateUnpickler(pickle.Unpickler):
    """Unpickles a stepper's state, bytes an importer hands back (fmi2DeSerializeFMUstate), looking
    up only the globals of :data:`STATE_GLOBALS`: a pickle that names any other (``os.system``, a
    class whose reconstruction runs code) is refused before anything of it runs."""

    def find_class(self, module, name):
        if name in STATE_GLOBALS.get(module, ()):
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"it names {module}.{name}, which no stepper state holds (a state holds "
                                     f"numpy arrays, scipy's Radau dense output, the compiled path's running "
                                     f"integration and plain values)")


def load_state(blob: bytes):
    """The object of a stepper's state `blob` (:class:`StateUnpickler`); raises pickle.UnpicklingError
    where it names a global no state holds, and what pickle raises where it is no pickle."""
    return StateUnpickler(io.BytesIO(bytes(blob))).load()


#: Attributes of a scipy solver that are its code, not its state (rebuilt with the solver).
_CODE = (types.FunctionType, types.MethodType, types.BuiltinFunctionType, functools.partial)


def solver_state(solver) -> dict:
    """A scipy OdeSolver's own state (every attribute but its functions), copied."""
    return copy.deepcopy({k: v for k, v in vars(solver).items() if not isinstance(v, _CODE)})


def restore_solver_state(solver, state: dict):
    """Make a solver built for the same problem continue as the one `state` was taken from: arrays
    are copied into the solver's own where they match (some are views of others: DOP853's K of
    K_extended), the rest replaced."""
    for key, value in state.items():
        mine = getattr(solver, key, None)
        if isinstance(mine, np.ndarray) and isinstance(value, np.ndarray) and mine.shape == value.shape \
                and mine.dtype == value.dtype:
            mine[...] = value
        else:
            setattr(solver, key, copy.deepcopy(value))
