"""The FMUs in OMSimulator, OpenModelica's FMI/SSP simulator (its Python API, 3.0): a 2D and a 3D
scene loaded, simulated over 2 s at a 10 ms step and compared with fmpy and with the solver.

Skipped where OMSimulator cannot be imported: the PyPI package is an sdist that downloads its binary
from build.openmodelica.org when it is installed. Built from source (OpenModelica/OMSimulator with
its 3rdParty submodule, cmake), put its install's lib/x86_64-linux-gnu on PYTHONPATH.

OMSimulator's calls: fmi2Instantiate with logging on, fmi2SetupExperiment with its system's
relative tolerance (1e-4 unless set) and no stop time, the fixed-step master's doSteps, a CSV result
file of 12 significant digits (each time written twice, the same values). So the FMU's own `rtol`
is set to the scene's, and fmpy runs without a stop time too (set_stop_time=False): the outputs are
then fmpy's to the file's digits and round-off. The solver's run ends its last step at the stop time, the FMU run
without one does not: they agree within the integrator's tolerance.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from test_fmu import fmus  # noqa: F401

import inerter

OMSimulator = pytest.importorskip("OMSimulator")
fmpy = pytest.importorskip("fmpy")

ROOT = Path(__file__).resolve().parents[1]
STOP, H = 2.0, 0.01


def omsimulator_run(fmu, name: str, rtol: float, folder) -> dict:
    """name -> values of every column of OMSimulator's result file, one row per time."""
    from OMSimulator import SSP, CRef
    model = SSP(temp_dir=str(folder / "ssp"))
    model.addResource(str(fmu), new_name=f"resources/{name}.fmu")
    model.addComponent(CRef("default", name), f"resources/{name}.fmu")
    run = model.instantiate()
    result = folder / f"{name}.csv"
    run.setResultFile(str(result))
    run.setStopTime(STOP)
    run.setFixedStepSize(H)
    run.setLoggingInterval(H)
    run.setValue(CRef("default", name, "rtol"), rtol)
    run.initialize()
    run.simulate()
    run.terminate()
    run.delete()
    rows = list(csv.reader(result.open()))
    data = np.array([[float(x) for x in row] for row in rows[1:]])
    keep = np.r_[np.diff(data[:, 0]) != 0, True]                 # each time written twice
    assert np.array_equal(data[~keep], data[np.flatnonzero(~keep) + 1], equal_nan=True)
    return {column.split(f"default.{name}.", 1)[-1]: data[keep, i] for i, column in enumerate(rows[0])}


@pytest.mark.parametrize("scene", ["two_bar_2d", "braced_frame_3d"])
def test_omsimulator_runs_the_fmu_as_fmpy_and_the_solver(fmus, scene, tmp_path):  # noqa: F811
    path = ROOT / "scenarios" / f"{scene}.toml"
    model = inerter.load(path)
    rtol = model.settings().rtol
    oms = omsimulator_run(fmus[path], scene, rtol, tmp_path)
    outputs = [o["name"] for o in model.output_info()]
    ours = fmpy.simulate_fmu(str(fmus[path]), stop_time=STOP,
                             output_interval=H, output=outputs, set_stop_time=False,
                             start_values={"rtol": rtol})
    solver = model.simulate(stop_time=STOP, output_interval=H, metrics=False)
    assert np.allclose(oms["time"], solver.time, rtol=0, atol=1e-12)
    for name in outputs:
        scale = float(np.max(np.abs(solver[name]))) + 1e-300
        # the file's 12 significant digits; OMSimulator's communication points are sums of steps
        # (fmpy's start + n h): a few ulps apart, which moves a sample by round-off of its scale,
        # or of the order of 1e-16 for a coordinate that stays at zero (two_bar_2d's A.r[1])
        assert np.allclose(oms[name], ours[name], rtol=1e-11, atol=1e-13 * scale + 1e-15), name
        assert np.max(np.abs(oms[name] - solver[name])) <= 100 * rtol * scale + 1e-12, name
