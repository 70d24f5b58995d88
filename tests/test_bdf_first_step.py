"""BDF from a state at rest under a force that is zero at t = 0: scipy's initial step, probed at
the interval's end, spanned the whole run, and BDF's first step (order 1, the right-hand side
evaluated at its end only) saw a zero force there too (a sine over a whole number of half
periods): the step was a fixed point, accepted with a zero error estimate, and the run stayed at
rest, status ok. two_bar_2d_pd.toml (Fa sin(2π t), f = 1 Hz, the actuator holding C at rest at
t = 0) to 0.5 s at rtol 1e-9 was 0.042 m off, on both paths.

Reference: the same scene by compiled DOP853 at rtol 1e-12, atol 1e-14 (the tight run).
"""
from __future__ import annotations

import numpy as np
import pytest

import inerter
from conftest import SCENARIOS

PD = SCENARIOS / "two_bar_2d_pd.toml"


@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("stop_time", [0.5, 1.0])
def test_bdf_follows_a_force_that_is_zero_at_both_ends(path, stop_time):
    model = inerter.load(PD)
    ref = model.simulate(stop_time=stop_time, method="DOP853", rtol=1e-12, atol=1e-14, metrics=False)
    assert np.ptp(ref["C.r[2]"]) > 0.03                      # the force does move C
    for rtol in (1e-8, 1e-9):
        r = model.simulate(stop_time=stop_time, method="BDF", rtol=rtol, atol=rtol * 1e-2, path=path,
                           metrics=False)
        assert r.status == "ok"
        err = np.max(np.abs(r["C.r[2]"] - ref["C.r[2]"]))
        assert err < 100 * rtol, (rtol, err)                 # measured 1e-9 and 1e-10 m

