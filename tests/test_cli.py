"""The command line: files written, overrides applied, errors reported."""
from __future__ import annotations

import json

import numpy as np
import pytest

from inerter.cli import main, parse_set
from conftest import LUMPED, SCENARIOS, TWO_BAR


def test_run_writes_csv_summary_and_plot(tmp_path, capsys):
    out = tmp_path / "lm"
    code = main(["run", str(LUMPED), "--set", "y0=1.2", "--set", "experiment.rtol=1e-8",
                 "--stop-time", "5", "--out", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "lumped_mass_2d"
    assert summary["settings"]["parameters"]["y0"] == 1.2
    assert summary["settings"]["rtol"] == 1e-8
    assert set(summary["metrics"]) >= {"natural_frequency", "fundamental_frequency", "fundamental_amplitude",
                                       "mean_offset", "inerter_force_mean", "inerter_force_amplitude"}
    data = np.genfromtxt(out / "lumped_mass_2d.csv", delimiter=",", names=True)
    assert data["time"][-1] == 5.0
    assert abs(data["Pr2"][0] - 1.2) < 1e-12          # genfromtxt strips '.[]' from "P.r[2]"
    assert (out / "lumped_mass_2d.png").stat().st_size > 10_000
    assert "fundamental_frequency" in capsys.readouterr().out


def test_set_switches_the_correction_off(tmp_path):
    out = tmp_path / "off"
    assert main(["run", str(LUMPED), "--set", "effects.centripetal=false", "--stop-time", "5",
                 "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["effects"]["centripetal"] is False


def test_run_on_the_compiled_path_gives_the_numpy_paths_figures(tmp_path):
    """`--path compiled`: the summary says which path ran; DOP853 at rtol 1e-11 on both paths agrees
    to 1e-9 m (both within the tolerance of the same solution; the compiled loop takes scipy's steps)."""
    pytest.importorskip("numba")
    runs = {}
    for path in ("numpy", "compiled"):
        out = tmp_path / path
        assert main(["run", str(TWO_BAR), "--path", path, "--stop-time", "2", "--rtol", "1e-11",
                     "--out", str(out)]) == 0
        summary = json.loads((out / "summary.json").read_text())
        assert summary["statistics"]["path"] == path
        runs[path] = np.genfromtxt(out / "two_bar_2d.csv", delimiter=",", names=True)
    assert np.max(np.abs(runs["compiled"]["Cr2"] - runs["numpy"]["Cr2"])) <= 1e-9


def test_parse_set_reads_toml_values():
    assert parse_set(["b=20", "effects.centripetal=false", "experiment.method=Radau", "g=[0, -9.81]"]) == {
        "b": 20, "effects.centripetal": False, "experiment.method": "Radau", "g": [0, -9.81]}


def test_describe_lists_compiled_terms(capsys):
    assert main(["describe", str(TWO_BAR)]) == 0
    out = capsys.readouterr().out
    assert "with centripetal term (Eq. 9)" in out
    assert "gravity: not declared, not computed" in out
    assert "C.r[2]" in out
    assert main(["describe", str(TWO_BAR), "--set", "effects.centripetal=false"]) == 0
    assert "without centripetal term (Eq. 8)" in capsys.readouterr().out


def test_unknown_override_is_a_clear_error(tmp_path, capsys):
    assert main(["run", str(TWO_BAR), "--set", "bb=3", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "bb" in err and "unknown name" in err and "two_bar_2d.toml" in err


def test_a_ground_motion_scene_writes_plain_json(tmp_path, capsys):
    """The braced frame's ground motion is an object in the scene; its summary holds its description."""
    scene = SCENARIOS / "braced_frame_3d.toml"

    def refuse(constant):
        raise AssertionError(f"{constant} is not JSON")
    assert main(["run", str(scene), "--stop-time", "0.05", "--out", str(tmp_path / "run")]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text(), parse_constant=refuse)
    motion = summary["settings"]["effects"]["ground_acceleration"]
    assert isinstance(motion, str) and "records/synthetic_bidirectional.csv" in motion
    assert main(["compare", str(scene), "--stop-time", "0.05", "--out", str(tmp_path / "compare")]) == 0
    runs = json.loads((tmp_path / "compare" / "summary.json").read_text(), parse_constant=refuse)["runs"]
    assert runs["oracle"]["settings"]["effects"]["ground_acceleration"] == motion


@pytest.mark.parametrize("option, value, field, expected", [
    ("--stop-time", "-1", "experiment.stop_time", "a number > 0"),
    ("--stop-time", "nan", "experiment.stop_time", "a finite number"),
    ("--rtol", "0", "experiment.rtol", "a number ≥ 1e-14"),
    ("--method", "Euler", "experiment.method", "one of: DOP853"),
    ("--step", "0", "experiment.communication_step", "a number > 0"),
])
def test_a_bad_option_is_a_one_line_error_before_anything_runs(tmp_path, capsys, option, value, field, expected):
    """The option names the experiment field it overrides; the scene reader checks it."""
    out = tmp_path / "out"
    assert main(["run", str(TWO_BAR), option, value, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"inerter: error: {option}: {TWO_BAR}: {field}: "), err
    assert value in err and expected in err, err
    assert not out.exists()


def test_an_output_folder_that_cannot_be_made_is_a_one_line_error(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["run", str(TWO_BAR), "--stop-time", "0.1", "--out", str(blocker / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--out" in err and str(blocker / "out") in err, err
