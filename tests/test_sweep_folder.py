"""A sweep's folder (inerter.studies.sweep.run_sweep, ``inerter sweep``): one scene per folder, its
lock file gone when the sweep ends, and the parameter columns of results.csv in the SI unit
sweep.json states.

The runs are the workers' own function (:func:`run_one`), called in this process one after another
instead of on a dask cluster (the dask path is tests/test_sweep.py's): what is checked here is
what the sweep does with its folder, before, around and after the runs.

Before: a sweep of another scene into the same folder appended its rows to the same results.csv;
``results.csv.lock`` stayed in the folder after every sweep; a value given as a table with a unit
(``y0={value = 1100, unit = "mm"}``) or an expression (``b=2*m``) was written to results.csv as
typed (``{'value': 1100, 'unit': 'mm'}``), so sweep-plot could not plot that column.
"""
from __future__ import annotations

import csv
import json
import shutil

import pytest

from conftest import LUMPED, TWO_BAR, one_line_error
from inerter.studies import sweep as sw

SHORT = ["--stop-time", "0.5", "--no-progress"]


def rows_of(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


class NoCluster:
    """In place of DaskClient: no cluster; the runs go through :func:`serial`."""

    def __init__(self, *args, **kwargs):
        pass

    def __enter__(self):
        return None

    def __exit__(self, *exc):
        return False


def serial(client, tasks, results, sweep, report, bar):
    """_run_tasks without dask: each task run by run_one here, its row recorded as _record does."""
    for task in tasks:
        row = sw.run_one(task)
        results.append(row, parameters=sweep.parameter_columns)
        report.rows.append(row)
        report.ok += row["status"] == "ok"
        report.failed += row["status"] != "ok"


@pytest.fixture
def in_process(monkeypatch):
    monkeypatch.setattr(sw, "DaskClient", NoCluster)
    monkeypatch.setattr(sw, "_run_tasks", serial)


def no_run(*args, **kwargs):
    raise AssertionError("a run was started")


# -- one scene per folder -------------------------------------------------------------------------
def test_a_sweep_of_another_scene_into_the_folder_is_refused_before_any_run(tmp_path, in_process, capsys,
                                                                            monkeypatch):
    out = tmp_path / "s"
    assert sw.main_sweep([str(LUMPED), "--vary", "y0=1.2,1.3", *SHORT, "--out", str(out)]) == 0
    capsys.readouterr()
    before = {name: (out / name).read_bytes() for name in ("results.csv", "sweep.json")}
    monkeypatch.setattr(sw, "_run_tasks", no_run)
    assert sw.main_sweep([str(TWO_BAR), "--vary", "b=1,2", *SHORT, "--out", str(out)]) == 2
    one_line_error(capsys, f"--out: holds the sweep of another scene, {LUMPED} (its sweep.json) (got '{out}'; "
                   f"expected a folder without results.csv, or one holding a sweep of {TWO_BAR})")
    assert {name: (out / name).read_bytes() for name in before} == before         # nothing written
    # without sweep.json, results.csv's rows name their scene
    (out / "sweep.json").unlink()
    assert sw.main_sweep([str(TWO_BAR), "--vary", "b=1,2", *SHORT, "--out", str(out)]) == 2
    one_line_error(capsys, "--out: holds the sweep of another scene, lumped_mass_2d (the scene column of "
                   "results.csv)", f"one holding a sweep of {TWO_BAR})")
    assert (out / "results.csv").read_bytes() == before["results.csv"]


def test_the_same_scene_resumes_and_extends_its_folder(tmp_path, in_process, capsys):
    """The same scene file (or a copy of its content elsewhere: the run keys follow the content)
    goes on in its folder: the finished runs skipped, another varied parameter added."""
    out = tmp_path / "s"
    argv = [str(LUMPED), "--vary", "y0=1.2,1.3", *SHORT, "--out", str(out)]
    assert sw.main_sweep(argv) == 0
    assert sw.main_sweep(argv) == 0
    assert "0 run now (0 failed), 2 already in" in capsys.readouterr().out
    copy = tmp_path / "elsewhere" / LUMPED.name
    copy.parent.mkdir()
    shutil.copy(LUMPED, copy)
    assert sw.main_sweep([str(copy), "--vary", "y0=1.2,1.3,1.4", *SHORT, "--out", str(out)]) == 0
    assert "1 run now (0 failed), 2 already in" in capsys.readouterr().out
    assert sw.main_sweep([str(LUMPED), "--vary", "k=2e4", *SHORT, "--out", str(out)]) == 0
    assert len(rows_of(out / "results.csv")) == 4


# -- the lock file ---------------------------------------------------------------------------------
def _raising(exc):
    def run(*args, **kwargs):
        raise exc
    return run


@pytest.mark.parametrize("how, exc, status", [
    ("normally", None, 0),
    ("by Ctrl-C", KeyboardInterrupt(), 130),
    ("by SIGTERM", sw.Terminated(), 143),
    ("by an error", sw.SweepError("no dask worker for 120 s"), 2),
])
def test_the_lock_file_is_removed_when_the_sweep_ends(tmp_path, in_process, monkeypatch, capsys, how, exc, status):
    out = tmp_path / "s"
    if exc is not None:
        monkeypatch.setattr(sw, "_run_tasks", _raising(exc))
    assert sw.main_sweep([str(LUMPED), "--vary", "y0=1.2,1.3", *SHORT, "--out", str(out)]) == status, how
    assert sorted(p.name for p in out.iterdir()) == ["results.csv", "sweep.json"], how


def test_the_lock_file_is_removed_when_results_csv_cannot_be_used(tmp_path, capsys):
    out = tmp_path / "s"
    out.mkdir()
    (out / "results.csv").write_text("key,b\nk1,2\n")          # rows, but no status column
    assert sw.main_sweep([str(LUMPED), "--vary", "y0=1.2,1.3", *SHORT, "--out", str(out)]) == 2
    one_line_error(capsys, "not a results file of inerter sweep")
    assert sorted(p.name for p in out.iterdir()) == ["results.csv"]


def test_a_busy_folder_is_refused_and_a_lock_left_by_a_killed_sweep_is_not(tmp_path):
    path = tmp_path / "results.csv"
    first = sw.ResultsFile(path).open(["b"])
    with pytest.raises(sw.SweepError, match="another sweep is writing this file"):
        sw.ResultsFile(path).open(["b"])
    assert (tmp_path / "results.csv.lock").exists()
    first.close()
    assert not (tmp_path / "results.csv.lock").exists()
    (tmp_path / "results.csv.lock").write_text("")            # a sweep killed by SIGKILL leaves it unlocked
    again = sw.ResultsFile(path).open(["b"])
    with pytest.raises(sw.SweepError, match="another sweep is writing this file"):
        sw.ResultsFile(path).open(["b"])
    again.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]


# -- values with a unit ----------------------------------------------------------------------------
def test_a_value_with_a_unit_is_written_in_the_si_unit_sweep_json_states(tmp_path, in_process, capsys):
    """y0 of lumped_mass_2d is in m, b in kg and k in N/m (the scene file's units; --set and --vary
    read a bare number as SI): 1100 mm is 1.1 m, 2*m is 10 kg (m = 5 kg), 20 kN/m is 20000 N/m."""
    out = tmp_path / "s"
    assert sw.main_sweep([str(LUMPED), "--vary", 'y0={value = 1100, unit = "mm"},1.2', "--vary", "b=2*m,50",
                          "--set", 'k={value = 20, unit = "kN/m"}', *SHORT, "--out", str(out)]) == 0
    rows = rows_of(out / "results.csv")
    assert [(r["y0"], r["b"], r["k"]) for r in rows] == [
        ("1.1", "10.0", "20000.0"), ("1.1", "50", "20000.0"), ("1.2", "10.0", "20000.0"), ("1.2", "50", "20000.0")]
    units = json.loads((out / "sweep.json").read_text())["units"]
    assert (units["y0"], units["b"], units["k"]) == ("m", "kg", "N/m")
    assert sw.main_sweep_plot([str(out / "results.csv"), "--x", "y0", "--y", "fundamental_frequency",
                               "--hue", "b", "--out", str(out / "f.png")]) == 0
    assert (out / "f.png").stat().st_size > 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots()
    sw.plot_results(out / "results.csv", "y0", "fundamental_frequency", None, hue="b", ax=ax)
    assert [list(line.get_xdata()) for line in ax.lines] == [[1.1, 1.2], [1.1, 1.2]]     # (it was NaN, 1.2)
    assert ax.get_xlabel() == "y0 (m)"
    plt.close(fig)
    # the runs are keyed by the values as given: the same command again runs nothing
    assert sw.main_sweep([str(LUMPED), "--vary", 'y0={value = 1100, unit = "mm"},1.2', "--vary", "b=2*m,50",
                          "--set", 'k={value = 20, unit = "kN/m"}', *SHORT, "--out", str(out)]) == 0
    assert "0 run now (0 failed), 4 already in" in capsys.readouterr().out
