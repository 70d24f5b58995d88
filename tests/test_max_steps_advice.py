"""A run that takes more than experiment.max_steps steps says what to do: with an explicit method
(DOP853, RK45) its small steps are likely stiffness, and Radau or BDF are the advice; with Radau or
BDF themselves that advice was given too ("the scene may be stiff for Radau; try method = "Radau"
or "BDF""), which sends the user back to the method that failed. Reference: the backlash device
(scenarios/hard), whose impacts hold every method's steps small; 200 steps do not reach 1 s."""
from __future__ import annotations

import pytest

import inerter
from conftest import SCENARIOS

BACKLASH = SCENARIOS / "hard" / "backlash_device_2d.toml"


@pytest.mark.parametrize("path", ["numpy", "compiled"])
@pytest.mark.parametrize("method, advice", [
    ("DOP853", 'the scene may be stiff for DOP853; try method = "Radau" or "BDF"'),
    ("Radau", "raise experiment.max_steps, or loosen experiment.rtol"),
    ("BDF", "raise experiment.max_steps, or loosen experiment.rtol"),
])
def test_the_advice_after_max_steps_fits_the_method(method, advice, path):
    r = inerter.load(BACKLASH, **{"experiment.max_steps": 200}).simulate(method=method, stop_time=1.0, path=path,
                                                                         metrics=False)
    assert r.status == "failed" and "more than max_steps = 200 integrator steps" in r.message, r.message
    assert r.message.endswith(advice), r.message
    if method != "DOP853":
        assert "try method" not in r.message
