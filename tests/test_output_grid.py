"""A run's output samples when the output interval does not divide the stop time: 0, h, 2h, ...
and the stop time, always the last sample (inerter.engine.simulation.output_grid), on the compiled
path, the numpy path and the oracle alike, as an importer's communication points are (fmpy steps
0, h, 2h, ... and a shorter last step to the stop time). Before, a remainder under h/2 was dropped:
stop_time = 1 s with h = 0.3 s ended the run at t = 0.9 s (and its CSV, metrics and summary with
it), while the FMU of the same scene ran to 1 s.

Reference for the state at the stop time: the same integration (the same method, tolerances and
steps: the output grid only samples the integrator's dense output) on an interval that divides the
stop time, whose last sample is t = 1 s."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.engine.simulation import output_grid

ROOT = Path(__file__).resolve().parents[1]
LUMPED = ROOT / "scenarios" / "lumped_mass_2d.toml"


@pytest.mark.parametrize("stop, h, expected", [
    (1.0, 0.3, [0.0, 0.3, 0.6, 0.9, 1.0]),      # remainder 0.1 < h/2: was dropped
    (1.0, 0.6, [0.0, 0.6, 1.0]),                # remainder 0.4 ≥ h/2
    (1.0, 0.25, [0.0, 0.25, 0.5, 0.75, 1.0]),   # h divides the stop time: no extra sample
    (20.0, 0.01, None)])                        # 2000 steps: the last multiple is the stop time
def test_the_grid_ends_at_the_stop_time(stop, h, expected):
    grid = output_grid(stop, h)
    assert grid[-1] == stop and grid[0] == 0.0 and np.all(np.diff(grid) > 0.5 * h * 1e-9)
    assert np.all(np.diff(grid)[:-1] == pytest.approx(h, rel=1e-9))
    if expected is not None:
        assert grid == pytest.approx(expected, rel=1e-12, abs=1e-15)
    else:
        assert len(grid) == round(stop / h) + 1


@pytest.mark.parametrize("who", ["compiled", "numpy", "oracle"])
def test_a_run_whose_interval_does_not_divide_the_stop_time_reaches_it(who):
    model = inerter.load(LUMPED)
    if who == "oracle":
        model = model.oracle()

    def run(h):
        return model.simulate(stop_time=1.0, output_interval=h, metrics=False,
                              path="numpy" if who == "numpy" else "compiled")
    short, whole = run(0.3), run(0.1)
    assert short.status == "ok", short.message
    assert short.time == pytest.approx([0.0, 0.3, 0.6, 0.9, 1.0], rel=1e-12, abs=1e-15)
    assert short.time[-1] == 1.0 and whole.time[-1] == 1.0
    # the state and the outputs at t = 1 s are those of the run sampled every 0.1 s
    assert np.allclose(short.run.states[-1], whole.run.states[-1], rtol=1e-12, atol=1e-12)
    assert short["P.r[2]"][-1] == pytest.approx(whole["P.r[2]"][-1], rel=1e-12)
    assert short["P.r[2]"][3] == pytest.approx(whole["P.r[2]"][9], rel=1e-12)
