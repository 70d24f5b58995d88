"""Terminals that pass through each other after long steps (tests/data/terminals_pass_3d.toml):
two bodies joined by an inerter alone close at a constant speed v, L(t) = L0 − v t (closed form:
no relative acceleration along the line), so the terminals meet at t* = L0/v. The compiled loops
stop at the start of the step that crosses the meeting, which after long steps of this smooth
motion lies well before it (t = 0.16 s of 0.5 s): the message says where that step starts and
ends, so that the user sees the meeting lies between (it gave the last sample's time and distance)."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

import inerter

SCENE = Path(__file__).parent / "data" / "terminals_pass_3d.toml"
L0, V = 1.0, 2.0
T_MEET = L0 / V                                   # the closed form's meeting time


@pytest.mark.parametrize("method", ["DOP853", "RK45", "RK4"])
def test_the_compiled_loops_name_the_step_that_crosses_the_meeting(method):
    """The compiled loops stop at the start of the step that crosses the meeting (kernels.terminals_meet):
    the message gives that start, the distance there (L0 − v t, the closed form) and the step's end,
    which the closed form's meeting time lies between."""
    r = inerter.load(SCENE).simulate(method=method)
    assert r.status == "failed"
    found = re.search(r"^at t = ([0-9.e+-]+) s: .*element 'inerter': its terminals A and C meet within a step of "
                      r"t = ([0-9.e+-]+) s \(where they were ([0-9.e+-]+) m apart\).*the step to t = ([0-9.e+-]+) s "
                      r"crosses the meeting", r.message)
    assert found, r.message
    start, said, gap, end = (float(g) for g in found.groups())
    assert said == start
    assert gap == pytest.approx(L0 - V * start, rel=2e-3)       # printed to 3 significant digits
    assert start < T_MEET <= end
