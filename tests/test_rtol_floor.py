"""An rtol the reader takes (down to 1e-14) but scipy's integrators do not (below 100 ε = 2.22e-14):
scipy raised it itself with a two-line UserWarning from inside the engine, once per solver, and
the result did not say so. Now the engine passes scipy the floor and Result.warnings (inerter run:
one 'inerter: warning:' line) says what ran; the compiled DOP853 and RK45 loops take 1e-14 as given.

Reference: the run at rtol = 100 ε, which is what scipy runs for any smaller rtol (its
validate_tol): the states must be bit-identical.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

import inerter
from conftest import LUMPED
from inerter.cli import main as cli_main
from inerter.engine.simulation import SCIPY_RTOL_FLOOR


@pytest.mark.parametrize("path, method", [("numpy", "DOP853"), ("compiled", "Radau")])
def test_an_rtol_below_scipys_floor_runs_at_the_floor_and_says_so(path, method):
    model = inerter.load(LUMPED)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                       # scipy's UserWarning would raise here
        r = model.simulate(stop_time=0.1, method=method, rtol=1e-14, atol=1e-16, path=path, metrics=False)
    floor = model.simulate(stop_time=0.1, method=method, rtol=SCIPY_RTOL_FLOOR, atol=1e-16, path=path,
                           metrics=False)
    assert r.status == "ok"
    assert np.array_equal(r["P.r[2]"], floor["P.r[2]"])
    notes = [w for w in r.warnings if "experiment.rtol" in w]
    assert len(notes) == 1 and "1e-14" in notes[0] and "2.22e-14" in notes[0]


def test_the_compiled_loop_takes_1e_14_as_given():
    r = inerter.load(LUMPED).simulate(stop_time=0.1, rtol=1e-14, atol=1e-16, metrics=False)
    assert r.status == "ok" and not [w for w in r.warnings if "experiment.rtol" in w]


def test_inerter_run_says_it_in_one_line(tmp_path, capsys):
    status = cli_main(["run", str(LUMPED), "--path", "numpy", "--set", "experiment.rtol=1e-14",
                       "--set", "experiment.stop_time=0.1", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert status == 0
    assert err.count("\n") == 1 and err.startswith("inerter: warning: ") and "experiment.rtol" in err
