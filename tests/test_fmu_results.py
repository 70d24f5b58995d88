"""The paper's figures and the oracle's trajectories, out of the FMUs (through fmpy)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from conftest import LUMPED, SCENARIOS, TWO_BAR
from test_oracle import TIGHT
from test_paper import TWO_BAR_PAPER, lumped_closed_form_frequency


@pytest.mark.parametrize("centripetal", [True, False], ids=["corrected", "uncorrected"])
def test_two_bar_fmu_reproduces_fig12(fmu_runs, centripetal):
    # One FMU, the correction switched by its Boolean parameter effects.centripetal.
    result = fmu_runs(TWO_BAR, **{"effects.centripetal": centripetal})
    assert result.status == "ok", result.message
    assert result.time[-1] == pytest.approx(60.0, abs=1e-9)
    assert result.communication_step == 0.01
    p2p, mean = TWO_BAR_PAPER[centripetal]
    # within 1 mm of the paper (the bound); metrics from the 10 ms samples
    assert abs(result.metrics["C_y_peak_to_peak"] - p2p) <= 1e-3
    assert abs(result.metrics["C_y_mean_offset"] - mean) <= 1e-3


def test_lumped_mass_fmu_natural_frequency_and_trends(fmu_runs):
    """A free oscillation of 1 mm through the FMU oscillates at the linearised frequency of
    Eq. (A.6) (amplitude effects are of order 1e-6 relative there); at y0 = 1.5 m the corrected
    model is slower and the uncorrected one faster than that (Fig. 9b), with mean offsets of
    opposite signs (Fig. 9c)."""
    fn = lumped_closed_form_frequency()
    small = fmu_runs(LUMPED, stop_time=10.0, y0=1.001)
    assert small.metrics["fundamental_frequency"] == pytest.approx(fn, rel=1e-4)
    cor = fmu_runs(LUMPED, stop_time=10.0, **{"effects.centripetal": True})
    unc = fmu_runs(LUMPED, stop_time=10.0, **{"effects.centripetal": False})
    assert cor.metrics["fundamental_frequency"] < fn < unc.metrics["fundamental_frequency"]
    assert cor.metrics["mean_offset"] < 0 < unc.metrics["mean_offset"]
    assert cor.metrics["fundamental_amplitude"] > unc.metrics["fundamental_amplitude"]


@pytest.mark.parametrize("scene", [LUMPED, TWO_BAR], ids=["lumped_mass", "two_bar"])
@pytest.mark.parametrize("centripetal", [True, False], ids=["corrected", "uncorrected"])
def test_fmu_against_oracle(runs, fmu_runs, scene, centripetal):
    """At the scene's default communication step and solver settings, every point position of
    the FMU is within 1e-6 m of the oracle (solved at rtol 1e-11, shared with test_oracle)."""
    fmu = fmu_runs(scene, stop_time=10.0, metrics=False, **{"effects.centripetal": centripetal})
    ref = runs(scene, centripetal, oracle=True, stop_time=10.0, **TIGHT, metrics=False)
    assert fmu.status == "ok", fmu.message
    assert np.allclose(fmu.time, ref.time, rtol=0, atol=1e-9)
    worst = max(np.max(np.abs(fmu[n] - ref[n])) for n in fmu.names if ".r[" in n)
    assert worst <= 1e-6


def test_coupled_cosimulation_converges_to_the_one_scene_solution():
    """Two-bar FMU + PD-controller FMU on an fmpy master loop against two_bar_2d_pd solved as
    one scene: the only difference is the zero-order hold of the force, so the error halves
    when the communication step halves (first order), and is small at 5 ms."""
    import inerter
    from inerter.fmu.cosim import build_controller, run_coupled
    from inerter.fmu.build import build

    one = inerter.load(SCENARIOS / "two_bar_2d_pd.toml")
    p = {k["name"]: k["value"] for k in one.parameter_info()}
    ref = one.simulate(stop_time=2.0, output_interval=0.005, rtol=1e-11, atol=1e-13, metrics=False)
    plant, ctrl = build(TWO_BAR), build_controller()
    errors = []
    for h in (0.01, 0.005):
        t, y, _ = run_coupled(plant, ctrl, 2.0, h, p["kp"], p["kd"], math.sqrt(2.0))
        errors.append(np.max(np.abs(y - np.interp(t, ref.time, ref["C.r[2]"]))))
    assert 1.8 < errors[0] / errors[1] < 2.2
    assert errors[1] < 2e-3
