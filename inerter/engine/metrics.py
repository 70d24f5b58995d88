"""Metrics of a simulated time history.

All functions are pure: they take the sample times `t` (non-decreasing, first < last),
the sampled coordinate `x` (same length) and, optionally, a *dense* callable
``dense(t_array) -> x_array`` that evaluates the solver's continuous interpolant at
any times inside ``[t[0], t[-1]]``.  When `dense` is given it is used for every
refinement (root finding, resampling, extremum search) because it is far more
accurate than linear interpolation between output samples.  Each refinement calls it
with every candidate at once (a few calls in all, however many crossings or extrema),
so that a dense output evaluated in compiled code costs little per call.

Periodic quantities are computed over a whole number of periods on a uniform grid with
both of the window's ends, by the trapezoidal rule (:func:`_fourier`): for a periodic
signal it is spectrally accurate (the sum over the grid without its end point, an FFT
bin), and where the signal does not quite repeat over the window (a transient still
decaying, a drift), its error falls as the square of the grid step, not as the step.
Given a `grid_rtol`, the grid is only as fine as the signal needs (:func:`_window_grid`): a
smooth periodic signal settles at 64 or 128 samples a period, and a signal with a kink, a
jump or a drift is sampled as finely as the metric allows. The caller gives it only for a
signal that cannot hold a feature narrower than the coarse grids' step (a pulse both miss
leaves their sums equal): :func:`inerter.api.metric_grid_rtol`.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = ["crossing_times", "free_oscillation", "harmonics", "steady_state"]

Dense = Callable[[np.ndarray], np.ndarray]

# Relative time tolerance of the root refinement on the dense interpolant.
_ROOT_XTOL = 1e-14
# Iterations of the root refinement at most (each one call of the dense interpolant).
_ROOT_ITERATIONS = 100
# Parabolic refinements of an extremum: the half-widths of the three-point stencils after
# the grid's own, relative to the grid step.
_EXTREME_STENCILS = (1.0 / 32.0, 1.0 / 1024.0, 1.0 / 32768.0)
# Relative slack allowed when a window edge falls a rounding error outside the history.
_EDGE_SLACK = 1e-9
# With a `grid_rtol`, a periodic metric's grid starts at this many samples a period and halves its
# step while the trapezoidal rule's results move by more than `grid_rtol` of the signal's spread
# (:func:`_window_grid`); without, it is the finest grid at once.
_COARSEST_GRID = 64


# --------------------------------------------------------------------------- helpers


def _history(t, x) -> tuple[np.ndarray, np.ndarray]:
    """Validate a time history and return it as float arrays."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.ndim != 1 or x.ndim != 1:
        raise ValueError(f"t and x must be 1-D arrays (got shapes {t.shape} and {x.shape})")
    if t.size != x.size:
        raise ValueError(f"t and x must have the same length (got {t.size} and {x.size})")
    if t.size < 2:
        raise ValueError(f"a time history needs at least 2 samples (got {t.size})")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ValueError("t and x must be finite (the history contains nan or inf)")
    if np.any(np.diff(t) < 0.0) or not t[-1] > t[0]:
        raise ValueError("t must be non-decreasing with t[-1] > t[0]")
    return t, x


def _dense_values(dense: Dense, tau: np.ndarray) -> np.ndarray:
    """Evaluate the dense interpolant at the times `tau` (1-D) as a float array."""
    values = np.asarray(dense(tau), dtype=float).reshape(-1)
    if values.size != tau.size:
        raise ValueError(
            f"dense(t) returned {values.size} values for {tau.size} times; "
            "it must return one value of x per time"
        )
    if not np.all(np.isfinite(values)):
        raise ValueError("dense(t) returned nan or inf")
    return values


def _resample(t: np.ndarray, x: np.ndarray, tau: np.ndarray, dense: Dense | None) -> np.ndarray:
    """x at the times `tau` (clipped to the history): dense interpolant or linear."""
    tau = np.clip(tau, t[0], t[-1])
    if dense is not None:
        return _dense_values(dense, tau)
    return np.interp(tau, t, x)


def _positive_int(value, what: str, least: int = 1) -> int:
    try:
        valid = not isinstance(value, bool) and int(value) == value and value >= least
    except (TypeError, ValueError, OverflowError):
        valid = False
    if not valid:
        raise ValueError(f"{what} must be an integer >= {least} (got {value!r})")
    return int(value)


def _crossings(
    t: np.ndarray, x: np.ndarray, level: float, direction: int, dense: Dense | None
) -> tuple[np.ndarray, np.ndarray]:
    """Indices i of the sample intervals [t[i], t[i+1]] holding a crossing, and its times.

    A sample exactly at `level` counts as above it, so that upward and downward
    crossings alternate (a touch from below is an upward crossing followed by a
    downward one at the same time; a touch from above is no crossing).
    """
    if direction not in (1, -1):
        raise ValueError(f"direction must be +1 (upward) or -1 (downward) (got {direction!r})")
    y = x - level
    above = y >= 0.0
    if direction > 0:
        index = np.flatnonzero(~above[:-1] & above[1:])
    else:
        index = np.flatnonzero(above[:-1] & ~above[1:])

    # Linear interpolation between the bracketing samples (y changes sign there, so
    # the denominator cannot vanish).
    ya, yb = y[index], y[index + 1]
    times = t[index] + (t[index + 1] - t[index]) * (ya / (ya - yb))
    if dense is None:
        return index, times

    # Refine on the dense interpolant.  Should the interpolant not bracket a root where
    # the samples do (it may differ from the samples by its own error), the linear
    # estimate is kept.
    xtol = _ROOT_XTOL * max(abs(t[0]), abs(t[-1]), t[-1] - t[0])
    a, b = t[index], t[index + 1]
    work = np.flatnonzero(b > a)  # a repeated sample time: the crossing is at that time
    if work.size:
        times[work] = _roots(dense, level, a[work], b[work], times[work], xtol)
    return index, times


def _roots(dense: Dense, level: float, a: np.ndarray, b: np.ndarray, guess: np.ndarray,
           xtol: float) -> np.ndarray:
    """Roots of dense(t) = level in each bracket [a, b], all refined together.

    The Illinois variant of false position, with a bisection wherever a step failed to
    halve the bracket, to within `xtol` (as scipy's brentq, one call of `dense` per
    iteration for every bracket).  Where the interpolant does not change sign over a
    bracket, `guess` is returned for it.
    """
    n = a.size
    ends = _dense_values(dense, np.concatenate((a, b))) - level
    fa, fb = ends[:n], ends[n:]
    root = guess.copy()
    root[fa == 0.0] = a[fa == 0.0]
    root[fb == 0.0] = b[fb == 0.0]
    live = np.flatnonzero((fa != 0.0) & (fb != 0.0) & (np.sign(fa) != np.sign(fb)))
    a, b, fa, fb = a[live].copy(), b[live].copy(), fa[live].copy(), fb[live].copy()
    side = np.zeros(live.size, dtype=int)  # which end moved last: -1 a, +1 b
    for _ in range(_ROOT_ITERATIONS):
        if not live.size:
            break
        width = b - a
        c = b - fb * width / (fb - fa)
        bad = ~((c > a) & (c < b))
        c[bad] = 0.5 * (a[bad] + b[bad])
        fc = _dense_values(dense, c) - level
        left = np.sign(fc) == np.sign(fa)  # the root lies in [c, b]: a moves to c
        # Illinois: an end that stays twice in a row has its value halved.
        fb = np.where(left & (side == -1), 0.5 * fb, fb)
        fa = np.where(~left & (side == 1), 0.5 * fa, fa)
        a, fa = np.where(left, c, a), np.where(left, fc, fa)
        b, fb = np.where(left, b, c), np.where(left, fb, fc)
        side = np.where(left, -1, 1)
        # a bracket that did not halve is bisected next
        slow = (b - a) > 0.5 * width
        if np.any(slow):
            mid = 0.5 * (a[slow] + b[slow])
            fm = _dense_values(dense, mid) - level
            go = np.sign(fm) == np.sign(fa[slow])
            sa, sb, sfa, sfb = a[slow], b[slow], fa[slow], fb[slow]
            a[slow], fa[slow] = np.where(go, mid, sa), np.where(go, fm, sfa)
            b[slow], fb[slow] = np.where(go, sb, mid), np.where(go, sfb, fm)
            side[slow] = 0
        done = (fc == 0.0) | (b - a <= 2.0 * xtol)
        best = np.where(fc == 0.0, c, np.where(np.abs(fa) <= np.abs(fb), a, b))
        root[live[done]] = best[done]
        keep = ~done
        live, a, b, fa, fb, side = live[keep], a[keep], b[keep], fa[keep], fb[keep], side[keep]
    if live.size:  # not converged in _ROOT_ITERATIONS: the best end so far
        root[live] = np.where(np.abs(fa) <= np.abs(fb), a, b)
    return root


def _fourier(values: np.ndarray, periods: int) -> tuple[float, float]:
    """Mean and fundamental amplitude of n + 1 uniform samples covering `periods` periods, both
    ends included: the trapezoidal rule for (1/T) ∫ x(t) e^(−2πi k t/T) dt, k = 0 and `periods`,
    which is the DFT of the first n samples plus (x_n − x_0)/2 (e^(−2πi k) = 1), divided by n
    (exact as the plain DFT where x_n = x_0, a periodic signal; of second order where not)."""
    n = values.size - 1
    # The fundamental is the DFT bin `periods`; amplitude A = 2 |c_1|.
    c1 = (np.fft.rfft(values[:n])[periods] + 0.5 * (values[n] - values[0])) / n
    return _mean(values), float(2.0 * abs(c1))


def _grid_strides(samples_per_period: int) -> list[int]:
    """The strides of the nested grids, coarsest first, in steps of the finest grid (the one of
    `samples_per_period` a period): halving from the coarsest with at least :data:`_COARSEST_GRID`
    samples a period that `samples_per_period` divides into, down to 1."""
    strides = [1]
    while samples_per_period % (2 * strides[-1]) == 0 and samples_per_period // (2 * strides[-1]) >= _COARSEST_GRID:
        strides.append(2 * strides[-1])
    return strides[::-1]


def _window_grid(t, x, window, periods, samples_per_period, dense, rule, grid_rtol):
    """The uniform grid over ``window = (t0, t1)`` (both ends), x on it and ``rule(values)`` there
    (a tuple of numbers: the trapezoidal rule's mean, its fundamental): with `grid_rtol` None, the
    finest grid, of `samples_per_period` a period; with a number, only as fine as the rule needs.

    The grid starts at :data:`_COARSEST_GRID` samples a period and halves its step, the samples
    already taken kept, until the rule's results move by no more than `grid_rtol` of the
    signal's spread from one grid to the next (plus the rounding of the sums), or it reaches
    `samples_per_period`, the finest, whose times every grid shares exactly. A smooth periodic
    signal stops at 64 or 128 samples a period, as the rule is spectrally accurate there; a signal
    with a kink or a jump, or one that drifts, converges only as a power of the step and goes on
    to the finest grid. Returns (times, values, the rule's results)."""
    t0, t1 = window
    n = periods * samples_per_period
    index = np.arange(n + 1)
    values = np.empty(n + 1)
    taken = np.zeros(n + 1, dtype=bool)
    previous = None
    for stride in _grid_strides(samples_per_period) if grid_rtol is not None else [1]:
        new = index[::stride][~taken[::stride]]
        values[new] = _resample(t, x, t0 + (t1 - t0) * (new / n), dense)
        taken[new] = True
        grid = values[::stride]
        result = rule(grid)
        if previous is not None and _settled(result, previous, grid, grid_rtol):
            break
        previous = result
    return t0 + (t1 - t0) * (index[::stride] / n), grid, result


def _settled(result, previous, grid, grid_rtol) -> bool:
    """Whether the rule's `result` on `grid` is within `grid_rtol` of the signal's spread of its
    `previous` on the grid of twice the step, beyond the rounding of a sum of the grid's values."""
    tolerance = grid_rtol * float(np.ptp(grid)) + 16.0 * np.finfo(float).eps * float(np.abs(grid).max())
    return all(abs(a - b) <= tolerance for a, b in zip(result, previous))


def _mean(values: np.ndarray) -> float:
    """The mean of n + 1 uniform samples over a window, both ends included, by the trapezoidal rule
    (:func:`_fourier`'s k = 0)."""
    n = values.size - 1
    return float((np.sum(values[:n]) + 0.5 * (values[n] - values[0])) / n)


# ------------------------------------------------------------------------ public API


def crossing_times(t, x, level, direction=+1, dense=None) -> np.ndarray:
    """Times at which `x` crosses `level` upward (``direction=+1``) or downward (-1).

    Crossings are located as sign changes of ``x - level`` between samples, then each
    is refined with Brent's method on `dense` (to about 1e-14 of the time scale) or, if
    `dense` is None, by linear interpolation between the two samples.
    """
    t, x = _history(t, x)
    return _crossings(t, x, float(level), direction, dense)[1]


def harmonics(t, x, window, periods, dense=None, samples_per_period=512, grid_rtol=None) -> dict:
    """Mean and fundamental amplitude of `x` over ``window = (t0, t1)``.

    The window must hold `periods` whole periods of the signal, i.e. the fundamental
    frequency is ``periods / (t1 - t0)``.  `x` is resampled uniformly with
    `samples_per_period` points per period (both ends included: :func:`_fourier`), or, given
    `grid_rtol`, as few as the mean and the amplitude need to within `grid_rtol` of the
    signal's spread (:func:`_window_grid`).

    Returns ``{"mean": a0, "amplitude": A}`` where ``x ~ a0 + A cos(2 pi f t + phi) + ...``.
    """
    t, x = _history(t, x)
    periods = _positive_int(periods, "periods")
    samples_per_period = _positive_int(samples_per_period, "samples_per_period", least=4)
    t0, t1 = (float(w) for w in window)
    if not t1 > t0:
        raise ValueError(f"the window must have t1 > t0 (got {window!r})")
    slack = _EDGE_SLACK * max(t[-1] - t[0], t1 - t0)
    if t0 < t[0] - slack or t1 > t[-1] + slack:
        raise ValueError(
            f"the window [{t0:.9g}, {t1:.9g}] s is not inside the history "
            f"[{t[0]:.9g}, {t[-1]:.9g}] s"
        )
    _, _, (mean, amplitude) = _window_grid(t, x, (t0, t1), periods, samples_per_period, dense,
                                           lambda values: _fourier(values, periods), grid_rtol)
    return {"mean": mean, "amplitude": amplitude}


def free_oscillation(t, x, reference, dense=None, samples_per_period=512, grid_rtol=None) -> dict:
    """Frequency, amplitude and mean of a free (periodic or nearly periodic) oscillation.

    The level is the time average of `x`; the analysis window runs from the first to
    the last upward crossing of that level (a crossing in the first sample interval is
    skipped, as the start of a history is often a release from or a pass through the
    level), which spans ``n >= 1`` whole periods of length ``T = (t_last - t_first)/n``.
    Over that window the mean and the first-harmonic amplitude are taken from the
    Fourier series at ``f = 1/T`` (see :func:`harmonics`).

    Returns ``{"fundamental_frequency": f [Hz], "fundamental_amplitude": A,
    "mean_offset": mean - reference, "mean": mean, "periods": n, "window": (t0, t1)}``.
    Raises ValueError if fewer than two upward crossings are found.
    """
    t, x = _history(t, x)
    # Time-weighted (trapezoid) average, so uneven solver steps do not bias the level.
    level = float(np.sum(0.5 * (x[1:] + x[:-1]) * np.diff(t)) / (t[-1] - t[0]))
    index, times = _crossings(t, x, level, +1, dense)
    times = times[index > 0]
    if times.size < 2:
        raise ValueError(
            f"free oscillation: found {times.size} upward crossing(s) of the mean level "
            f"{level:.9g} in [{t[0]:.9g}, {t[-1]:.9g}] s, but at least 2 are needed to "
            "cover one whole period; simulate longer or check that the coordinate oscillates"
        )
    periods = times.size - 1
    t0, t1 = float(times[0]), float(times[-1])
    period = (t1 - t0) / periods
    fourier = harmonics(t, x, (t0, t1), periods, dense=dense, samples_per_period=samples_per_period,
                        grid_rtol=grid_rtol)
    return {
        "fundamental_frequency": 1.0 / period,
        "fundamental_amplitude": fourier["amplitude"],
        "mean_offset": fourier["mean"] - float(reference),
        "mean": fourier["mean"],
        "periods": periods,
        "window": (t0, t1),
    }


def _candidates(w: np.ndarray, periods: int) -> np.ndarray:
    """Indices of the grid values `w` that may hold the largest value once refined.

    The grid's local maxima (end points included one-sidedly) close to the grid maximum: on a
    periodic signal every period holds a peak of nearly the same height, and the grid may rank
    them wrongly by its own error.
    """
    best = float(w.max())
    interior = np.flatnonzero((w[1:-1] >= w[:-2]) & (w[1:-1] >= w[2:])) + 1
    ends = [k for k, j in ((0, 1), (w.size - 1, w.size - 2)) if w[k] >= w[j]]
    candidates = np.concatenate([interior, np.array(ends, dtype=int)])
    spread = best - float(w.min())
    samples_per_period = (w.size - 1) / periods
    band = spread * min(1.0, max(1e-3, 10.0 * (np.pi / samples_per_period) ** 2))
    candidates = candidates[w[candidates] >= best - band]
    return candidates[np.argsort(-w[candidates], kind="stable")][: 2 * periods + 4]


def _extremes(dense: Dense | None, tau: np.ndarray, values: np.ndarray, periods: int) -> tuple[float, float]:
    """The largest and the smallest value of x over the uniform grid `tau`.

    With `dense`, the best grid candidates of both (:func:`_candidates`) are refined
    together, each within its neighbouring grid intervals, by successive parabolas through
    three points: first the grid's own, then stencils of 1/32, 1/1024 and 1/32768 of the
    grid step around each vertex (the error of an extremum falls as the fourth power of the
    stencil: from the grid's (w h)^4 to far below rounding, even from a grid of 16 samples
    per period), the largest value met being kept.
    """
    high, low = float(values.max()), float(values.min())
    if dense is None or values.size < 3:
        return high, low
    up, down = _candidates(values, periods), _candidates(-values, periods)
    k = np.concatenate((up, down))
    sign = np.concatenate((np.ones(up.size), -np.ones(down.size)))
    step = tau[1] - tau[0]
    lo = np.maximum(tau[k] - step, tau[0])
    hi = np.minimum(tau[k] + step, tau[-1])
    # the grid's stencil (at the window's ends the first or last three samples)
    inner = np.minimum(np.maximum(k, 1), values.size - 2)
    x = np.array((tau[inner - 1], tau[inner], tau[inner + 1]))
    f = sign * np.array((values[inner - 1], values[inner], values[inner + 1]))
    centre = _vertex(x, f, tau[k])
    met = sign * values[k]
    for width in _EXTREME_STENCILS:
        centre = np.minimum(np.maximum(centre, lo), hi)
        e = width * step
        x = np.minimum(np.maximum(np.array((centre - e, centre, centre + e)), lo), hi)
        f = sign * _dense_values(dense, x.reshape(-1)).reshape(x.shape)
        met = np.maximum(met, f.max(axis=0))
        centre = _vertex(x, f, centre)
    met = np.maximum(met, sign * _dense_values(dense, np.minimum(np.maximum(centre, lo), hi)))
    high = max(high, float(met[:up.size].max()))
    low = min(low, -float(met[up.size:].max()))
    return high, low


def _vertex(x: np.ndarray, f: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """The abscissa of the maximum of the parabola through (x[j], f[j]), j = 0, 1, 2 (rows;
    one parabola per column), or the best of the three points where the parabola is not
    concave or the points are not distinct; `fallback` where they all coincide."""
    x0, x1, x2 = x
    f0, f1, f2 = f
    with np.errstate(divide="ignore", invalid="ignore"):
        # Newton's form f0 + d0 (t - x0) + c (t - x0)(t - x1): its vertex, a maximum where c < 0
        d0 = (f1 - f0) / (x1 - x0)
        c = ((f2 - f1) / (x2 - x1) - d0) / (x2 - x0)
        vertex = 0.5 * (x0 + x1) - 0.5 * d0 / c
    concave = (c < 0.0) & np.isfinite(vertex) & (x0 < x1) & (x1 < x2)
    best = np.where(x2 > x0, x[np.argmax(f, axis=0), np.arange(x.shape[1])], fallback)
    return np.where(concave, vertex, best)


def peak(t, x, reference, dense=None, candidates=8) -> float:
    """The largest excursion |x − reference| over the history. With `dense`, the samples' best
    maxima and minima (`candidates` of each, :func:`_candidates`) are refined on the dense
    interpolant (:func:`_extremes`): a peak between two samples is not flattened (a sine sampled
    at 10 ms is off by up to (ω·5 ms)²/2 of its amplitude at the samples)."""
    t, x = _history(t, x)
    steps = np.diff(t)
    if steps.size and np.allclose(steps, steps[0], rtol=1e-9, atol=0.0):
        tau, values = t, x
    else:                                     # _extremes refines on a uniform grid
        tau = np.linspace(t[0], t[-1], t.size)
        values = _resample(t, x, tau, dense)
    high, low = _extremes(dense, tau, values, candidates)
    return max(high - reference, reference - low)


def steady_state(t, x, period, periods, reference, dense=None, samples_per_period=2048,
                 grid_rtol=None) -> dict:
    """Peak-to-peak and mean of a forced steady state over its last whole periods.

    The window is the last `periods` periods of the excitation (period `period`)
    ending at ``t[-1]``.  `x` is resampled uniformly with `samples_per_period` points
    per period (given `grid_rtol`, as few as the mean needs to within `grid_rtol` of the
    signal's spread, :func:`_window_grid`); the peak-to-peak is max - min over that grid (plus,
    without `dense`, the samples inside the window; with `dense`, the extrema are refined
    on the interpolant).  The mean is the trapezoidal rule over that grid (:func:`_mean`).

    Returns ``{"peak_to_peak": ..., "mean_offset": mean - reference, "mean": ...,
    "window": (t0, t1)}``.  Raises ValueError if the history is shorter than the window.
    """
    t, x = _history(t, x)
    period = float(period)
    if not (np.isfinite(period) and period > 0.0):
        raise ValueError(f"period must be a positive finite number (got {period!r})")
    periods = _positive_int(periods, "periods")
    samples_per_period = _positive_int(samples_per_period, "samples_per_period", least=4)

    t1 = float(t[-1])
    span = periods * period
    t0 = t1 - span
    if t0 < t[0] - _EDGE_SLACK * span:
        raise ValueError(
            f"steady state: the history covers {t1 - t[0]:.9g} s, shorter than the "
            f"{periods} period(s) of {period:.9g} s ({span:.9g} s) to analyse; simulate longer "
            "or analyse fewer periods"
        )
    t0 = max(t0, float(t[0]))  # absorb a rounding error at the start

    tau, values, (mean,) = _window_grid(t, x, (t0, t1), periods, samples_per_period, dense,
                                        lambda values: (_mean(values),), grid_rtol)

    if dense is None:
        # The linear interpolant attains its extrema at sample times: include the
        # samples inside the window so none is missed between grid points.
        inside = x[(t >= t0) & (t <= t1)]
        pool = np.concatenate([values, inside])
        high, low = float(pool.max()), float(pool.min())
    else:
        high, low = _extremes(dense, tau, values, periods)

    return {
        "peak_to_peak": high - low,
        "mean_offset": mean - float(reference),
        "mean": mean,
        "window": (t0, t1),
    }
