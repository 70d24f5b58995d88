"""The units of a sweep's columns: sweep.json beside results.csv states them, and sweep-plot labels
its axes with them. Reference: the scene file's own units (lumped_mass_2d: k in N/m, y0 in m, read
in SI as --set takes them), docs/usage.md's rule for metrics (frequencies in Hz, every other metric
in its signal's unit: P.r[2] in m, inerter.f in N) and the experiment fields' units (stop_time in s).
Before, neither results.csv nor sweep.json held a unit and the plot's axes were the bare names."""
from __future__ import annotations

import json

import pytest

from conftest import LUMPED
from inerter.studies import sweep as sw

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


@pytest.fixture(scope="module")
def sweep():
    """Nothing is run: the units come from the scene, as the columns do."""
    return sw.Sweep(LUMPED, [("y0", [1.1, 1.2]), ("effects.centripetal", [True, False]),
                             ("experiment.stop_time", [2.0, 3.0])], {"k": 2e4})


def test_sweep_json_states_the_unit_of_each_column(sweep, tmp_path):
    units = sweep.describe()["units"]
    assert {k: units[k] for k in ("k", "y0", "experiment.stop_time", "run_time_s")} == {
        "k": "N/m", "y0": "m", "experiment.stop_time": "s", "run_time_s": "s"}
    assert {k: units[k] for k in sweep.metric_columns} == {
        "natural_frequency": "Hz", "fundamental_frequency": "Hz", "fundamental_amplitude": "m",
        "mean_offset": "m", "inerter_force_mean": "N", "inerter_force_amplitude": "N"}
    assert "effects.centripetal" not in units                  # a switch has no unit
    for column in units:                                        # every unit names a column of results.csv
        assert column in sweep.parameter_columns + sweep.metric_columns + ["run_time_s", "natural_frequencies"]


def test_sweep_plot_labels_its_axes_with_the_units(sweep, tmp_path):
    (tmp_path / "sweep.json").write_text(json.dumps(sweep.describe()))
    rows = ["key,scene,model,y0,effects.centripetal,status,error,fundamental_frequency,run_time_s",
            "a,lumped_mass_2d,solver,1.1,true,ok,,1.51,0.1", "b,lumped_mass_2d,solver,1.2,true,ok,,1.50,0.1"]
    (tmp_path / "results.csv").write_text("\n".join(rows) + "\n")
    fig, ax = plt.subplots()
    sw.plot_results(tmp_path / "results.csv", "y0", "fundamental_frequency", None, ax=ax)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("y0 (m)", "fundamental_frequency (Hz)")
    (tmp_path / "sweep.json").unlink()                         # a results file alone: the bare names
    fig, ax = plt.subplots()
    sw.plot_results(tmp_path / "results.csv", "y0", "fundamental_frequency", None, ax=ax)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("y0", "fundamental_frequency")
    plt.close("all")


def test_a_second_sweep_into_the_folder_keeps_the_units_of_the_first(sweep, tmp_path):
    """A second sweep of the same scene varying other parameters: results.csv keeps the rows of both
    (resuming is by run key); sweep.json describes the last, and keeps the units of the columns only
    the first had (b and La of lumped_mass_2d, in kg and m). A sweep of another scene into the folder
    is refused (tests/test_sweep_folder.py)."""
    (tmp_path / "sweep.json").write_text(json.dumps({"units": {"b": "kg", "La": "m"}}))
    sw.write_description(sweep, tmp_path)
    units = json.loads((tmp_path / "sweep.json").read_text())["units"]
    assert units["b"] == "kg" and units["La"] == "m" and units["y0"] == "m"
    assert json.loads((tmp_path / "sweep.json").read_text())["vary"]["y0"] == [1.1, 1.2]


def test_the_natural_frequency_of_a_sweep_follows_its_closed_form(tmp_path):
    """Each grid point's row (run_one, as a worker runs it) against the linearisation of
    lumped_mass_2d (the paper's Eq. A.6, docs/results.md): about y = Lb the spring and the inerter
    act along the mass's line with cos²θ = Lb²/(La² + Lb²) = 1/2, so f = sqrt(k/2 / (m + b/2)) / 2π;
    and each row's metrics equal inerter.load(scene, **point).simulate(stop_time=...).metrics."""
    import math

    import inerter
    from inerter import __version__
    grid = sw.Sweep(LUMPED, [("k", [5e3, 2e4]), ("b", [0.0, 100.0]), ("m", [1.0, 5.0])], {"experiment.rtol": 1e-8},
                    stop_time=1.0)
    for run in grid.runs():
        task = dict(key=run.key, name=grid.name, model="solver", overrides=run.overrides, version=__version__,
                    stop_time=1.0, step=None, fmu_path=None, path="compiled", scene_path=str(grid.scene),
                    scene_digest=grid.digest, scene_content=grid.content)
        row = sw.run_one(task)
        k, b, m = (run.overrides[n] for n in ("k", "b", "m"))
        closed = math.sqrt(k / 2 / (m + b / 2)) / (2 * math.pi)
        assert row["status"] == "ok" and row["natural_frequency"] == pytest.approx(closed, rel=1e-8), (run, row)
        alone = inerter.load(LUMPED, **run.overrides).simulate(stop_time=1.0).metrics
        assert {c: row.get(c) for c in grid.metric_columns} == {c: alone.get(c) for c in grid.metric_columns}
