"""The device study (inerter/studies/device_effects.py, ``inerter device-study``) on short runs.

The study's scenes are written from the paper's scenes and devices/ballscrew_device.toml;
its ideal row is checked against the paper's scene itself (an independent path: the plain inerter
b, no device), each row's FMU against its solver run, and the device's geometry against
b = J (2π/p)² (Smith 2002). The runs are shortened to STOP seconds (10 periods of the two-bar's
steady-state window fit in it) and three rows, so that the file takes well under a minute.
"""
from __future__ import annotations

import csv
import math

import pytest

import inerter
from conftest import SCENARIOS, TWO_BAR
from inerter.studies import device_effects as de

pytest.importorskip("fmpy")
pytest.importorskip("pythonfmu")

STOP = 12.0
#: masses (with the 3D mount), all (every effect of a ball-screw device: in 2D with the masses,
#: friction, series spring, backlash, stops and the screw's efficiency, in series; in 3D the same
#: without the mount).
ROWS = ("ideal", "masses", "all")
BRACED = SCENARIOS / "braced_frame_3d.toml"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study's rows on both scenes, by the solver and through the FMU (built once here)."""
    out = tmp_path_factory.mktemp("device_study")
    results = de.device_study(out, rows=ROWS, stop_time=STOP)
    return out, results


def _row(results, scene, row):
    return {r.metric: r for r in results if (r.scene, r.row) == (scene, row)}


@pytest.mark.parametrize("scene, path", [("two_bar_2d", TWO_BAR), ("braced_frame_3d", BRACED)])
def test_the_ideal_row_is_the_paper_scene(study, scene, path):
    """The ideal row (a flywheel of J = b (p/2π)² on a lead p) against the scene's own ideal
    inerter b, run by the solver for the same time: 1e-9 relative (J (2π/p)² rounds b by an ulp,
    so the two runs differ by round-off amplified over the run, far below 1e-9)."""
    _, results = study
    plain = inerter.load(path, **{"experiment.stop_time": STOP}).simulate()
    ideal = _row(results, scene, "ideal")
    assert set(ideal) == set(de.read_device_data()[1][scene].metrics)
    for metric, r in ideal.items():
        assert r.solver == pytest.approx(plain.metrics[metric], rel=1e-9, abs=0), metric


def test_every_row_through_the_fmu_equals_the_solver(study):
    """Each row's FMU value (fmpy, communication step 0.01 s) against its solver value.

    - Against the solver's metric: the FMU's metrics read its own dense output (a second instance
      stepped to the times they read, inerter.fmu.dense), and the FMU integrates the same equations
      with the same method and tolerances, so the two differ by at most the integrators' global
      errors, bounded by 1000 (rtol |value| + atol) as in tests/test_shipped_scenes.py
      (TOLERANCE_FACTOR; rtol, atol the scene's).
    - The solver's metric computed from a cubic spline through its samples at the same 0.01 s, as the
      FMU's were before, against its dense output's: the spline's error is O(h⁴) at a smooth extremum
      (≈ 1e-8 of the value here), up to 1e-4 of the value where an end-stop impact bends the signal
      within one sample interval (8e-5 measured on the two-bar's end-stop row at 60 s,
      docs/device_study.md): 2e-4 relative.
    """
    _, results = study
    assert {(r.scene, r.row) for r in results} == {(s, row) for s in de.SCENES for row in ROWS}
    for r in results:
        model = inerter.load(SCENARIOS / de.read_device_data()[1][r.scene].scene.name)
        rtol, atol = model.experiment["rtol"], model.experiment["atol"]
        assert r.fmu is not None, (r.scene, r.row, r.metric)
        assert abs(r.fmu - r.solver) <= 1000.0 * (rtol * abs(r.solver) + atol), (r.scene, r.row, r.metric)
        assert r.solver_sampled == pytest.approx(r.solver, rel=2e-4, abs=0), (r.scene, r.row, r.metric)


def test_the_device_is_scaled_to_the_scenes_inertance(study):
    """Each row scene's inerters have the paper scene's b: b = J (2π/p)² (Smith 2002) with J from
    the data file's lead, to round-off; the device's mass is b / 90 (the specific inertance)."""
    out, _ = study
    for scene, b in (("two_bar_2d", 10.0), ("braced_frame_3d", 500.0)):
        for row in ROWS:
            model = inerter.load(out / "scenes" / f"{scene}_dev_{row}.toml")
            p = model.scene.parameters
            assert p["dev_J"].value * (2 * math.pi / p["dev_lead"].value) ** 2 == pytest.approx(b, rel=1e-14)
            mass = p["dev_m_fw"].value + p["dev_m_h"].value + p["dev_m_r"].value
            assert mass == pytest.approx(b / 90.0, rel=1e-14)


def test_the_all_row_has_the_efficiency_in_series(study):
    """The "all" row's inerters declare the screw efficiency beside the series spring and its
    backlash (the efficiency then acts on the inerter's own stroke, inerter.elements.device), with
    friction and end stops; in 3D without the mount, which the engine refuses beside a series
    connection; and the row reports the efficiency's mode."""
    out, _ = study
    cases = de.read_device_data()[1]
    for scene in de.SCENES:
        model = inerter.load(out / "scenes" / f"{scene}_dev_all.toml")
        for name in cases[scene].inerters:
            device = model.scene.elements[name].device
            assert all(device.has(e) for e in ("efficiency", "compliance", "backlash", "friction", "end_stops")), name
            assert not device.has("mount"), name
            assert f"{name}.mode" in [o["name"] for o in model.output_info()], name


def test_every_device_value_has_a_source_and_assumed_ones_say_so():
    device, cases = de.read_device_data()
    sourced = ("Smith 2002", "Madhamshetty", "Appl. Sci.", "thin solid disc", "numerical choice", "geometry")
    values = list(device.values()) + [v for c in cases.values() for v in c.values.values()]
    assert len(values) == len(de.DEVICE_VALUES) + sum(len(c.values) for c in cases.values())
    for v in values:
        assert "representative, assumed" in v.source or any(s in v.source for s in sourced), v.source


def test_a_value_without_a_source_is_a_one_line_error(tmp_path):
    text = de.device_data_path().read_text()
    bad = tmp_path / "devices" / "bad.toml"
    bad.parent.mkdir()
    bad.write_text(text.replace('source = "representative, assumed: 0.5 mm total free play of the nut and the two '
                                'mounts"', ""))
    with pytest.raises(de.DeviceStudyError) as info:
        de.read_device_data(bad)
    message = str(info.value)
    assert "\n" not in message and str(bad) in message and "device.backlash_gap.source" in message, message


def test_the_command_writes_the_table_and_the_figure(tmp_path, capsys):
    from inerter.cli import main
    out = tmp_path / "study"
    assert main(["device-study", "--out", str(out), "--scenes", "two_bar_2d", "--rows", "ideal", "friction",
                 "--stop-time", str(STOP), "--no-fmu"]) == 0
    with open(out / "device_study.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [(r["row"], r["metric"]) for r in rows] == [
        ("ideal", "C_y_peak_to_peak"), ("ideal", "C_y_mean_offset"),
        ("friction", "C_y_peak_to_peak"), ("friction", "C_y_mean_offset")]
    ideal = {r["metric"]: float(r["solver"]) for r in rows if r["row"] == "ideal"}
    for r in rows:   # the change is the row's value less the ideal row's (the file's 12 significant digits)
        assert float(r["solver_change"]) == pytest.approx(float(r["solver"]) - ideal[r["metric"]], abs=1e-12)
    md = (out / "device_study.md").read_text()
    assert "REPRESENTATIVE, ASSUMED" in md and "inerter device-study" in md
    assert (out / "device_study.png").stat().st_size > 0
    assert main(["device-study", "--out", str(out), "--rows", "nonsense", "--no-fmu"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--rows" in err and "nonsense" in err and "ideal" in err, err


@pytest.mark.parametrize("stop, scenes, fragment", [
    ("3", [], "expected at least 10 s: two_bar_2d's C_y_peak_to_peak, C_y_mean_offset read the last 10 periods "
              "of 1 s of its run"),
    ("9.99", ["--scenes", "two_bar_2d"], "expected at least 10 s"),
    ("1e9", ["--scenes", "braced_frame_3d"], "the study's samples every 0.01 s"),
])
def test_a_stop_time_that_cannot_work_is_refused_before_anything_runs(tmp_path, capsys, monkeypatch, stop, scenes,
                                                                      fragment):
    """two_bar_2d's steady-state metrics read its last 10 periods of 1/f = 1 s (the scene file: f = 1 Hz,
    periods = 10), so a run shorter than 10 s computes none of them. Before, --stop-time 3 ran the
    first row (its scene written, the solver run for 3 s) and then stopped with 'metrics: not computed'."""
    from inerter.cli import main
    monkeypatch.setattr(de, "run_row", lambda *a, **k: pytest.fail("a row was run"))
    out = tmp_path / "study"
    assert main(["device-study", "--out", str(out), "--stop-time", stop, "--no-fmu", *scenes]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("inerter: error: --stop-time: ") and fragment in err, err
    assert not out.exists()
    assert main(["device-study", "--out", str(out), "--rows", "nonsense", "--no-fmu"]) == 2
    assert not out.exists()                                     # (it was made before --rows was read)


def test_the_least_stop_time_is_the_steady_state_window():
    """10 s (10 periods of 1 s) is enough for the two-bar's window; the braced frame's peak metrics
    read any run, so 3 s is enough for it."""
    _, cases = de.read_device_data()
    de.check_stop_time(10.0, [cases["two_bar_2d"]])
    de.check_stop_time(3.0, [cases["braced_frame_3d"]])
    with pytest.raises(de.DeviceStudyError, match="too short"):
        de.check_stop_time(9.999, [cases["two_bar_2d"]])
