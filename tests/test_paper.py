"""The paper's figures, from the stand-alone solver (Zhu et al. 2022, Secs. 2.4 and 3.4)."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import inerter
from conftest import LUMPED, TWO_BAR

# Two-bar: 60 s from rest, last 10 periods. The paper reports whole millimetres (Sec. 3.4); the
# issue asks for agreement within 1 mm. rtol 1e-8 is far tighter than that (the fast path against
# the oracle at 1e-12 differs by < 1e-7 m at this setting).
TWO_BAR_PAPER = {True: (0.162, 0.023), False: (0.140, 0.072)}


@pytest.mark.parametrize("centripetal", [True, False], ids=["corrected", "uncorrected"])
def test_two_bar_reproduces_fig12(runs, centripetal):
    result = runs(TWO_BAR, centripetal, rtol=1e-8, atol=1e-10)
    assert result.status == "ok"
    p2p, mean = TWO_BAR_PAPER[centripetal]
    assert abs(result.metrics["C_y_peak_to_peak"] - p2p) <= 1e-3
    assert abs(result.metrics["C_y_mean_offset"] - mean) <= 1e-3
    # constraint drift under Baumgarte stabilisation at this tolerance
    assert result.run.max_drift < 1e-8


def test_two_bar_static_equilibrium_is_the_unloaded_pose():
    # Paper notes: the static equilibrium is the unloaded configuration, C = (0, √2).
    model = inerter.load(TWO_BAR)
    assert model.static_value("C.r[1]") == pytest.approx(0.0, abs=1e-12)
    assert model.static_value("C.r[2]") == pytest.approx(math.sqrt(2.0), abs=1e-12)


def lumped_closed_form_frequency(m=5.0, b=100.0, k=1e4, La=1.0, Lb=1.0):
    """Appendix A, Eq. (A.6): m_e = m + (Lb/L0)² b, k_e = k (Lb/L0)²."""
    L0 = math.hypot(La, Lb)
    return math.sqrt(k * (Lb / L0) ** 2 / (m + (Lb / L0) ** 2 * b)) / (2 * math.pi)


def test_lumped_mass_natural_frequency_appendix_a():
    model = inerter.load(LUMPED)
    f = model.natural_frequencies()[0]
    assert round(f, 3) == 1.517 or round(f, 3) == 1.518   # paper: 1.518 Hz (rounded from 1.5175)
    assert f == pytest.approx(lumped_closed_form_frequency(), rel=1e-8)
    # and for other parameters, against the same closed form
    model = inerter.load(LUMPED, b=37.0, La=0.7, Lb=1.3, k=5e3)
    assert model.natural_frequencies()[0] == pytest.approx(
        lumped_closed_form_frequency(b=37.0, La=0.7, Lb=1.3, k=5e3), rel=1e-8)


def test_lumped_mass_trends_of_fig8_and_fig9(runs):
    """Sec. 2.4: with the correction the fundamental frequency drops below the natural frequency,
    the amplitude is larger and the mean offset negative; without it, the frequency rises and the
    mean offset is small and positive."""
    fn = lumped_closed_form_frequency()
    cor = runs(LUMPED, True).metrics
    unc = runs(LUMPED, False).metrics
    assert cor["fundamental_frequency"] < fn < unc["fundamental_frequency"]
    assert cor["fundamental_amplitude"] > unc["fundamental_amplitude"]
    assert cor["mean_offset"] < 0 < unc["mean_offset"]
    assert unc["mean_offset"] < abs(cor["mean_offset"])
    assert cor["inerter_force_amplitude"] > unc["inerter_force_amplitude"]
    # F = b·d²L/dt² averages to zero over whole periods of a periodic motion
    assert abs(cor["inerter_force_mean"]) < 1e-6 * cor["inerter_force_amplitude"]
    assert unc["inerter_force_mean"] < 0        # the uncorrected law adds −b|ṙ⊥|²/L on average


def quadrature_period(y0=1.5, m=5.0, b=100.0, k=1e4, La=1.0, Lb=1.0):
    """The corrected model is Lagrangian: T = ½(m + b y²/(La²+y²)) ẏ², V = ½k(√(La²+y²) − L0)².
    Released from rest at y0, the period is 2∫ dy/ẏ between the turning points."""
    L0 = math.hypot(La, Lb)
    V = lambda y: 0.5 * k * (math.hypot(La, y) - L0) ** 2
    meff = lambda y: m + b * y * y / (La * La + y * y)
    E = V(y0)
    y_min = brentq(lambda y: V(y) - E, 1e-9, Lb) if y0 > Lb else y0
    y_max = y0 if y0 > Lb else brentq(lambda y: V(y) - E, Lb, 10 * Lb)
    # 1/ẏ = sqrt(meff / (2(E − V))) with square-root singularities at both ends: integrate
    # g(y) (y − y_min)^(-1/2) (y_max − y)^(-1/2) with the algebraic weight of QUADPACK.
    dV = lambda y: k * (math.hypot(La, y) - L0) * y / math.hypot(La, y)

    def g(y):
        if y <= y_min or y >= y_max:      # QUADPACK samples the ends: use the limit E − V ≈ −V'·(y − y_end)
            return math.sqrt(meff(y) * (y_max - y_min) / (2 * abs(dV(y))))
        return math.sqrt(meff(y) * (y - y_min) * (y_max - y) / (2 * (E - V(y))))
    half, err = quad(g, y_min, y_max, weight="alg", wvar=(-0.5, -0.5), epsabs=0, epsrel=1e-13, limit=200)
    return 2 * half


def test_lumped_mass_period_against_energy_quadrature(runs):
    result = runs(LUMPED, True)
    T_sim = 1.0 / result.metrics["fundamental_frequency"]
    assert T_sim == pytest.approx(quadrature_period(), rel=1e-6)


def test_lumped_mass_inerter_force_is_eq12(runs):
    """Eq. (12): F_I = b y ÿ/L + b La² ẏ²/L³ (L = √(La²+y²)), checked on the time history."""
    result = runs(LUMPED, True)
    model = result.model
    n = model.mechanism.n
    y, ydot = result["P.r[2]"], result["P.v[2]"]
    acc = np.array([model.mechanism.accelerations(t, s[:n], s[n:])[0][1]
                    for t, s in zip(result.time[::50], result.run.states[::50])])
    y, ydot = y[::50], ydot[::50]
    L = np.hypot(1.0, y)
    eq12 = 100.0 * y * acc / L + 100.0 * ydot**2 / L**3
    assert np.max(np.abs(result["inerter.f"][::50] - eq12)) < 1e-9 * np.max(np.abs(eq12))


def test_lumped_mass_corrected_energy_is_conserved(runs):
    # The corrected model is conservative (T includes ½bL̇²); at rtol 1e-10 the energy stays
    # constant to far better than 1e-8 relative over 20 s. The uncorrected model has no energy.
    e = runs(LUMPED, True)["energy"]
    assert np.max(np.abs(e - e[0])) / e[0] < 1e-8
    e_unc = runs(LUMPED, False)["energy"]
    assert np.max(np.abs(e_unc - e_unc[0])) / e_unc[0] > 1e-3
