"""Tests of inerter.engine.metrics against closed-form signals."""
import math

import numpy as np
import pytest

from inerter.engine.metrics import crossing_times, free_oscillation, harmonics, steady_state

F0 = 1.7  # Hz
W0 = 2.0 * math.pi * F0


def periodic(t):
    """0.3 + 2 cos(w t) + 0.1 cos(2 w t): mean 0.3, fundamental amplitude 2."""
    t = np.asarray(t, dtype=float)
    return 0.3 + 2.0 * np.cos(W0 * t) + 0.1 * np.cos(2.0 * W0 * t)


@pytest.fixture
def periodic_history():
    t = np.arange(0.0, 10.0 + 1e-9, 1e-3)  # 1 kHz sampling
    return t, periodic(t)


# ----------------------------------------------------------------- crossing_times


def test_crossings_with_dense_are_exact():
    # sin(2 pi t) crosses 0.5 upward at 1/12 + k and downward at 5/12 + k.
    f = lambda t: np.sin(2.0 * np.pi * np.asarray(t))
    t = np.arange(0.0, 3.0 + 1e-9, 0.0137)  # coarse, incommensurate step
    up = crossing_times(t, f(t), 0.5, +1, dense=f)
    down = crossing_times(t, f(t), 0.5, -1, dense=f)
    np.testing.assert_allclose(up, 1.0 / 12.0 + np.arange(3), rtol=0, atol=1e-13)
    np.testing.assert_allclose(down, 5.0 / 12.0 + np.arange(3), rtol=0, atol=1e-13)


def test_crossings_linear_interpolation():
    f = lambda t: np.sin(2.0 * np.pi * np.asarray(t))
    t = np.arange(0.0, 3.0 + 1e-9, 1e-3)
    up = crossing_times(t, f(t), 0.5, +1)
    # Linear interpolation errs by about h^2/8 |x''|/|x'| = 1e-6/8 * 19.7/5.44, i.e.
    # about 5e-7 s at 1 kHz sampling.
    np.testing.assert_allclose(up, 1.0 / 12.0 + np.arange(3), rtol=0, atol=1e-6)


def test_crossing_at_a_sample_and_touching():
    t = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    x = np.array([-1.0, 0.0, 1.0, 0.0, 1.0])
    np.testing.assert_array_equal(crossing_times(t, x, 0.0, +1), [1.0])
    np.testing.assert_array_equal(crossing_times(t, x, 0.0, -1), [])
    # A touch from below is an upward then a downward crossing at the same time.
    x = np.array([-1.0, 0.0, -1.0, -2.0, -1.0])
    np.testing.assert_array_equal(crossing_times(t, x, 0.0, +1), [1.0])
    np.testing.assert_array_equal(crossing_times(t, x, 0.0, -1), [1.0])


def test_crossing_bad_input():
    with pytest.raises(ValueError, match="direction"):
        crossing_times([0.0, 1.0], [0.0, 1.0], 0.5, direction=0)
    with pytest.raises(ValueError, match="same length"):
        crossing_times([0.0, 1.0], [0.0, 1.0, 2.0], 0.5)
    with pytest.raises(ValueError, match="non-decreasing"):
        crossing_times([1.0, 0.0], [0.0, 1.0], 0.5)


# -------------------------------------------------------------- free_oscillation


def test_free_oscillation_with_dense(periodic_history):
    t, x = periodic_history
    result = free_oscillation(t, x, reference=0.25, dense=periodic)
    assert result["fundamental_frequency"] == pytest.approx(F0, rel=1e-10)
    assert result["fundamental_amplitude"] == pytest.approx(2.0, abs=1e-10)
    assert result["mean"] == pytest.approx(0.3, abs=1e-10)
    assert result["mean_offset"] == pytest.approx(0.05, abs=1e-10)
    # 10 s of a 1.7 Hz signal: 17 upward crossings, the window spans 16 periods.
    assert result["periods"] == 16
    t0, t1 = result["window"]
    assert (t1 - t0) == pytest.approx(16 / F0, rel=1e-12)


def test_free_oscillation_samples_only(periodic_history):
    t, x = periodic_history
    result = free_oscillation(t, x, reference=0.0)
    # Without the dense interpolant, x between samples is interpolated linearly.  That
    # attenuates a sinusoid by about (w h)^2 / 12 = 9.5e-6 (relative) at 1 kHz, which
    # bounds the amplitude error.  The errors of the two window-edge crossings (h^2
    # times the curvature at the crossing) are below 1e-6 s and are divided by the
    # 9.4 s window for the frequency; the mean of a linear interpolant loses only
    # terms of order (w h)^2 times the small second harmonic.
    assert result["fundamental_frequency"] == pytest.approx(F0, rel=1e-7)
    assert result["fundamental_amplitude"] == pytest.approx(2.0, rel=5e-5)
    assert result["mean"] == pytest.approx(0.3, abs=1e-7)
    assert result["periods"] == 16


def test_free_oscillation_skips_crossing_in_first_interval():
    # Starting just below the mean and rising: the first-interval crossing is skipped.
    f = lambda t: np.sin(2.0 * np.pi * (np.asarray(t) - 0.0005))
    t = np.arange(0.0, 3.0 + 1e-9, 1e-3)
    result = free_oscillation(t, f(t), reference=0.0, dense=f)
    assert result["window"][0] == pytest.approx(1.0005, abs=1e-12)
    assert result["fundamental_frequency"] == pytest.approx(1.0, rel=1e-10)


def test_free_oscillation_needs_two_crossings():
    t = np.linspace(0.0, 1.0, 1001)
    with pytest.raises(ValueError, match="at least 2"):
        free_oscillation(t, np.cos(2.0 * np.pi * 0.7 * t), reference=0.0)
    with pytest.raises(ValueError, match="upward crossing"):
        free_oscillation(t, np.exp(-t), reference=0.0)


# --------------------------------------------------------------------- harmonics


def test_harmonics_over_given_window(periodic_history):
    t, x = periodic_history
    window = (1.0, 1.0 + 5.0 / F0)  # five whole periods, starting at an arbitrary phase
    result = harmonics(t, x, window, 5, dense=periodic)
    assert result["mean"] == pytest.approx(0.3, abs=1e-12)
    assert result["amplitude"] == pytest.approx(2.0, abs=1e-12)
    with pytest.raises(ValueError, match="not inside the history"):
        harmonics(t, x, (5.0, 11.0), 3)


DRIFT = 0.02  # per second: a signal that does not repeat over its window


def drifting(t):
    """0.3 + DRIFT t + 2 cos(w t): over a window [t0, t1] of whole periods its mean is
    0.3 + DRIFT (t0 + t1)/2 and its fundamental's coefficient (1/W) ∫ x e^(−iw(t − t0)) dt is
    e^(i w t0) + i DRIFT W/(2π k) (W = t1 − t0 = k periods), both in closed form."""
    t = np.asarray(t, dtype=float)
    return 0.3 + DRIFT * t + 2.0 * np.cos(W0 * t)


def test_harmonics_of_a_signal_that_does_not_repeat():
    # The trapezoidal rule over both ends of the window: the mean of the linear drift exactly
    # (a sum without the window's end point is off by DRIFT h/2, 3e-6 here); the coefficient
    # to second order in the grid step h = W/2560: the leading term of its error is w DRIFT h^2/12
    # on c1 (5e-8 on the amplitude 2|c1|), allowed half again for the terms of higher order.
    t0, periods = 1.0, 5
    t1 = t0 + periods / F0
    t = np.arange(0.0, 5.0 + 1e-9, 1e-3)
    result = harmonics(t, drifting(t), (t0, t1), periods, dense=drifting)
    assert result["mean"] == pytest.approx(0.3 + DRIFT * (t0 + t1) / 2.0, abs=1e-12)
    c1 = np.exp(1j * W0 * t0) + 1j * DRIFT * (t1 - t0) / (2.0 * math.pi * periods)
    h = (t1 - t0) / (periods * 512)
    assert result["amplitude"] == pytest.approx(2.0 * abs(c1), abs=2.0 * W0 * DRIFT * h ** 2 / 12.0 * 1.5)


def test_steady_state_mean_of_a_signal_that_does_not_repeat():
    # As above: the window's mean by the trapezoidal rule, exact for the drift.
    t = np.arange(0.0, 5.0 + 1e-9, 1e-3)
    result = steady_state(t, drifting(t), 1.0 / F0, 5, reference=0.0, dense=drifting)
    t0, t1 = result["window"]
    assert result["mean"] == pytest.approx(0.3 + DRIFT * (t0 + t1) / 2.0, abs=1e-12)


# ------------------------------------------------------------------ steady_state

F1 = 1.3  # Hz, excitation frequency
W1 = 2.0 * math.pi * F1


def forced(t):
    """Steady part 0.5 + sin(w t) + 0.5 sin(2 w t) plus a transient dying as exp(-3 t).

    f(th) = sin th + sin(2 th)/2 has f' = cos th + cos 2th = 0 at cos th = 1/2, so its
    extrema are +-3 sqrt(3)/4 and the peak-to-peak is 3 sqrt(3)/2.
    """
    t = np.asarray(t, dtype=float)
    return 0.5 + np.sin(W1 * t) + 0.5 * np.sin(2.0 * W1 * t) + 5.0 * np.exp(-3.0 * t) * np.sin(7.0 * t)


PEAK_TO_PEAK = 1.5 * math.sqrt(3.0)


@pytest.fixture
def forced_history():
    t = np.arange(0.0, 20.0 + 1e-9, 1e-3)  # transient is exp(-3*16) ~ 1e-21 in the window
    return t, forced(t)


def test_steady_state_with_dense(forced_history):
    t, x = forced_history
    result = steady_state(t, x, 1.0 / F1, 5, reference=0.4, dense=forced)
    assert result["peak_to_peak"] == pytest.approx(PEAK_TO_PEAK, abs=1e-12)
    assert result["mean"] == pytest.approx(0.5, abs=1e-12)
    assert result["mean_offset"] == pytest.approx(0.1, abs=1e-12)
    t0, t1 = result["window"]
    assert t1 == 20.0 and t0 == pytest.approx(20.0 - 5.0 / F1, abs=1e-12)


def test_steady_state_samples_only(forced_history):
    t, x = forced_history
    result = steady_state(t, x, 1.0 / F1, 5, reference=0.0)
    # Linear interpolation cuts peaks by at most |x''| h^2 / 8 = 2e2 * 1e-6 / 8, about
    # 3e-5 per extremum; the mean is that of a linear interpolant (error ~ (w h)^2 times
    # the end-point mismatch), far below 1e-7.
    assert result["peak_to_peak"] == pytest.approx(PEAK_TO_PEAK, abs=1e-4)
    assert result["peak_to_peak"] <= PEAK_TO_PEAK + 1e-12
    assert result["mean"] == pytest.approx(0.5, abs=1e-7)


def test_steady_state_history_too_short(forced_history):
    t, x = forced_history
    with pytest.raises(ValueError, match="shorter than"):
        steady_state(t, x, 1.0 / F1, 100, reference=0.0)


# ------------------------------------------------------------ the grid's refinement


class Counted:
    """A dense interpolant `f` that counts the times it is asked for."""

    def __init__(self, f):
        self.f, self.times = f, 0

    def __call__(self, t):
        self.times += np.size(t)
        return self.f(t)


def test_a_smooth_periodic_signal_settles_on_a_coarse_grid(forced_history):
    # The steady part is a trigonometric polynomial of degree 2, which the trapezoidal rule
    # integrates exactly on any grid of more than 2 samples a period: given a grid_rtol, the grid
    # of 64 samples a period and that of 128 agree to rounding, and the metric stops there instead
    # of sampling 2048 a period (10 241 times over five periods, as it does without one).
    # Closed forms as in test_steady_state_with_dense.
    t, x = forced_history
    dense = Counted(forced)
    result = steady_state(t, x, 1.0 / F1, 5, reference=0.4, dense=dense, grid_rtol=1e-12)
    assert result["peak_to_peak"] == pytest.approx(PEAK_TO_PEAK, abs=1e-12)
    assert result["mean"] == pytest.approx(0.5, abs=1e-12)
    grid = 5 * 128 + 1
    extremes = 2 * (2 * 5 + 4) * (3 * 3 + 1)      # at most 2 periods + 4 candidates each way, 3 stencils + vertex
    assert dense.times <= grid + extremes


def rectified(t):
    """|sin(w t)|, kinked at its zeros: its mean over whole periods is 2/π."""
    return np.abs(np.sin(W1 * np.asarray(t, dtype=float)))


def test_a_kinked_signal_is_sampled_on_the_finest_grid():
    # A kink makes the trapezoidal rule converge as h², so the grids never agree to the run's share
    # and the metric samples its finest grid (2048 a period), on exactly that grid's times: its
    # mean is the trapezoidal rule there, written out here, and within the rule's error bound of
    # 2/π: a kink inside a cell costs at most |jump of x'| h²/8 (halfway through it), the smooth
    # pieces beside it |Δx'| h²/12 (Euler-Maclaurin), with x' jumping by 2w at each of two kinks a
    # period: (1/8 + 1/12) 2w h² 2F = (5/6) w h² F on the mean.
    periods, n = 5, 5 * 2048
    t = np.arange(0.0, 20.0 + 1e-9, 1e-3)
    dense = Counted(rectified)
    result = steady_state(t, rectified(t), 1.0 / F1, periods, reference=0.0, dense=dense, grid_rtol=1e-9)
    t0, t1 = result["window"]
    x = rectified(t0 + (t1 - t0) * (np.arange(n + 1) / n))
    assert result["mean"] == ((np.sum(x[:n]) + 0.5 * (x[n] - x[0])) / n)
    h = (t1 - t0) / n
    assert result["mean"] == pytest.approx(2.0 / math.pi, abs=5.0 / 6.0 * W1 * h ** 2 * F1)
    assert dense.times >= n + 1


def test_the_grid_stops_at_the_callers_share():
    # A drift makes the fundamental's trapezoidal rule converge as h² (test_harmonics_of_a_signal_
    # that_does_not_repeat; its mean is exact on every grid): without a grid_rtol the metric
    # samples its finest grid;
    # at a looser share it stops sooner, and its amplitude stays within that share (times 4/3,
    # the estimate of a second-order rule's error from two grids) of the finest grid's.
    t0, periods = 1.0, 5
    t1 = t0 + periods / F0
    t = np.arange(0.0, 5.0 + 1e-9, 1e-3)
    fine, loose = Counted(drifting), Counted(drifting)
    strict = harmonics(t, drifting(t), (t0, t1), periods, dense=fine)
    quick = harmonics(t, drifting(t), (t0, t1), periods, dense=loose, grid_rtol=1e-6)
    assert fine.times == periods * 512 + 1
    assert loose.times < fine.times / 2
    spread = np.ptp(drifting(np.linspace(t0, t1, 5001)))
    assert quick["amplitude"] == pytest.approx(strict["amplitude"], abs=4.0 / 3.0 * 1e-6 * spread)
    assert quick["mean"] == pytest.approx(strict["mean"], abs=1e-12)
