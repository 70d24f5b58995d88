"""An absolute tolerance too small for the error norms (they square the errors scaled by atol,
which overflow below about 1e-150): at atol 1e-200 two_bar_2d's DOP853 step size 'collapsed' at
t = 5e-125 s ('approaching a singularity') and scipy's Radau ended in a traceback (ValueError:
array must not contain infs or NaNs, inerter run's exit status 1). Now the reader refuses atol
below 1e-100 in one line, and a Newton matrix that is not finite ends a Radau or BDF run as a
failure, its samples kept (exit status 3), not a traceback.

References: the error text the reader gives every out-of-range field; the run at atol 1e-100
against the tight DOP853 run (rtol 1e-12, atol 1e-14).
"""
from __future__ import annotations

import numpy as np
import pytest

import inerter
from conftest import TWO_BAR
from inerter.cli import main as cli_main
from inerter.common.errors import SceneError, SimulationError
from inerter.engine.integrators import make_solver
from inerter.engine.simulation import _step


def test_an_atol_below_1e_100_is_refused_in_one_line(tmp_path, capsys):
    with pytest.raises(SceneError, match=r"experiment.atol: out of range \(got 1e-200; expected a number ≥ 1e-100\)"):
        inerter.load(TWO_BAR).simulate(atol=1e-200, method="Radau", stop_time=0.1)
    status = cli_main(["run", str(TWO_BAR), "--set", "experiment.method=Radau", "--set", "experiment.atol=1e-200",
                       "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert status == 2 and err.count("\n") == 1 and "experiment.atol" in err


@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_atol_1e_100_runs_to_the_tight_run(method):
    model = inerter.load(TWO_BAR)
    ref = model.simulate(stop_time=0.3, rtol=1e-12, atol=1e-14, metrics=False)
    r = model.simulate(stop_time=0.3, method=method, rtol=1e-8, atol=1e-100, metrics=False)
    assert r.status == "ok"
    assert np.max(np.abs(r["C.r[2]"] - ref["C.r[2]"])) < 1e-6


def test_a_newton_matrix_that_is_not_finite_is_a_run_failure():
    def overflowing(t, y):
        return np.full_like(y, np.inf) if t > 0 else -y
    solver = make_solver("Radau", overflowing, 0.0, np.ones(2), 1.0, 1e-6, 1e-8)
    with pytest.raises(SimulationError, match="Radau integrator failed: its Newton matrix is not finite"):
        _step(solver, "Radau")
