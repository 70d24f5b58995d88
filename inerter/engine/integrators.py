"""Time integrators, all behind scipy's `OdeSolver` interface (`step()`, `t`, `y`, `dense_output()`).

* ``DOP853``: explicit Runge–Kutta of order 8(5,3), adaptive (Hairer); the default, for smooth,
  non-stiff scenes at tight tolerance.
* ``RK45``: explicit Runge–Kutta 5(4), adaptive (Dormand–Prince).
* ``Radau``: implicit Runge–Kutta (Radau IIA, order 5), adaptive; for stiff scenes.
* ``BDF``, ``LSODA``: variable-order multistep methods, adaptive; stiff / auto-switching.
* ``RK4``: classical fixed-step Runge–Kutta of order 4, for real-time-style co-simulation;
  its step is the experiment's ``step`` (the tolerances do not apply).
"""
from __future__ import annotations

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK45, DenseOutput, OdeSolver, Radau

from inerter.engine.simulation import SCIPY_RTOL_FLOOR


class Hermite(DenseOutput):
    """Cubic Hermite interpolation over one step (matches RK4's order 4 only at the nodes)."""

    def __init__(self, t_old, t, y_old, y, f_old, f):
        super().__init__(t_old, t)
        self.h = t - t_old
        self.y_old, self.y, self.f_old, self.f = y_old, y, f_old, f

    def _call_impl(self, t):
        s = (np.atleast_1d(t) - self.t_old) / self.h
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        out = (np.outer(self.y_old, h00) + np.outer(self.f_old, h10 * self.h)
               + np.outer(self.y, h01) + np.outer(self.f, h11 * self.h))
        return out[:, 0] if np.ndim(t) == 0 else out


class RK4(OdeSolver):
    """Classical Runge–Kutta, order 4, fixed step `step` (the last step is shortened to land on
    t_bound)."""

    def __init__(self, fun, t0, y0, t_bound, step=1e-3, vectorized=False, **extraneous):
        super().__init__(fun, t0, y0, t_bound, vectorized)
        self.h = float(step)
        self.f = self.fun(self.t, self.y)
        self.y_old = self.f_old = None
        self.midpoints = None       # the last step's stages k2, k3 (RK4's stability watch reads them)

    def _step_impl(self):
        t, y, h = self.t, self.y, min(self.h, abs(self.t_bound - self.t))
        y_new, f_new, self.midpoints = rk4_step(self.fun, t, y, self.f, h)   # left as it was where it raises
        self.y_old, self.f_old = y, self.f
        self.y, self.t, self.f = y_new, t + h, f_new
        return True, None

    def _dense_output_impl(self):
        return Hermite(self.t_old, self.t, self.y_old, self.y, self.f_old, self.f)


def rk4_step(fun, t, y, f, h):
    """One classical RK4 step of length h from (t, y) with derivative f: (y_new, f_new, its
    midpoint stages (k2, k3))."""
    k2 = fun(t + h / 2, y + h / 2 * f)
    k3 = fun(t + h / 2, y + h / 2 * k2)
    k4 = fun(t + h, y + h * k3)
    y_new = y + h / 6 * (f + 2 * k2 + 2 * k3 + k4)
    return y_new, fun(t + h, y_new), (k2, k3)


SOLVERS = {"DOP853": DOP853, "RK45": RK45, "Radau": Radau, "BDF": BDF, "LSODA": LSODA, "RK4": RK4}


#: BDF's first step where scipy's initial step would span the whole interval: this fraction of it
BDF_FIRST_FRACTION = 1e-3


def make_solver(method, fun, t0, y0, t_bound, rtol, atol, step=1e-3, first_step=None):
    cls = SOLVERS[method]
    if cls is RK4:
        return RK4(fun, t0, y0, t_bound, step=step)
    kwargs = {}
    rtol = max(rtol, SCIPY_RTOL_FLOOR)      # scipy raises it there itself, with a UserWarning per call
    if first_step is not None and first_step > 0.0:
        # A restart (co-simulation step) goes on with the step size the error control proposed,
        # clipped to the interval as the integrator would clip it, rather than a fresh guess.
        kwargs["first_step"] = min(first_step, abs(t_bound - t0))
    solver = cls(fun, t0, y0, t_bound, rtol=rtol, atol=atol, **kwargs)
    if cls is BDF and not kwargs and solver.h_abs >= abs(t_bound - t0) > 0.0:
        # BDF's first step (order 1) evaluates the right-hand side at its end only, and scipy's
        # initial step, probed there too, may span the whole interval: a state at rest whose
        # forcing is zero at both ends (a sine over a whole number of half periods) is then a
        # fixed point of the step, accepted with a zero error estimate, and the run stays at rest
        # (two_bar_2d_pd.toml to 0.5 s at rtol 1e-9: 0.042 m off). A shorter first step sees the
        # forcing inside the interval; the error control lengthens the steps from there.
        solver = cls(fun, t0, y0, t_bound, rtol=rtol, atol=atol,
                     first_step=BDF_FIRST_FRACTION * abs(t_bound - t0))
    return solver
