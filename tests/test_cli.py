"""The command line: files written, overrides applied, errors reported."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from inerter.cli import main, parse_set
from conftest import LUMPED, SCENARIOS, TWO_BAR, one_line_error


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
    assert data["time_s"][-1] == 5.0                   # genfromtxt reads "time (s)" as time_s
    assert abs(data["Pr2_m"][0] - 1.2) < 1e-12        # and "P.r[2] (m)" as Pr2_m
    assert (out / "lumped_mass_2d.png").stat().st_size > 10_000
    # every metric carries its unit: frequencies in Hz, P.r[2]'s in m, the inerter force's in N
    assert summary["metric_units"] == {
        "natural_frequency": "Hz", "natural_frequencies": "Hz", "fundamental_frequency": "Hz",
        "fundamental_amplitude": "m", "mean_offset": "m", "inerter_force_mean": "N",
        "inerter_force_amplitude": "N"}
    console = capsys.readouterr().out
    assert f"fundamental_frequency = {summary['metrics']['fundamental_frequency']} Hz" in console
    assert f"inerter_force_amplitude = {summary['metrics']['inerter_force_amplitude']} N" in console


def test_set_switches_the_correction_off(tmp_path):
    out = tmp_path / "off"
    assert main(["run", str(LUMPED), "--set", "effects.centripetal=false", "--stop-time", "5",
                 "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["effects"]["centripetal"] is False


def test_run_on_either_path_writes_the_oracles_figures(tmp_path):
    """`--path numpy` and `--path compiled` (both offered on the command line): the summary says
    which path ran and each CSV holds the samples of the scene's grid. Reference: the oracle's run
    (element forces derived from L(q) on Jets, DOP853 at rtol 1e-12, atol 1e-14); each path's
    C.r[2] at rtol 1e-11 is within 1e-9 m of it at every sample, the bound these runs were held to
    against each other (each run's global error is at most ~N·rtol·|y| over its N = 134 steps;
    measured 3e-13 m on either path)."""
    pytest.importorskip("numba")
    import inerter
    oracle = inerter.load(TWO_BAR).oracle().simulate(stop_time=2.0, rtol=1e-12, atol=1e-14, metrics=False)
    for path in ("numpy", "compiled"):
        out = tmp_path / path
        assert main(["run", str(TWO_BAR), "--path", path, "--stop-time", "2", "--rtol", "1e-11",
                     "--out", str(out)]) == 0
        summary = json.loads((out / "summary.json").read_text())
        assert summary["statistics"]["path"] == path
        data = np.genfromtxt(out / "two_bar_2d.csv", delimiter=",", names=True)
        assert len(data) == len(oracle.time) and np.max(np.abs(data["time_s"] - oracle.time)) <= 1e-12, path
        worst = float(np.max(np.abs(data["Cr2_m"] - oracle["C.r[2]"])))
        assert worst <= 1e-9, (path, worst)


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


def test_model_describe_is_what_the_command_prints(capsys):
    """`model.describe()` (the Python API) returns the text `inerter describe` prints, overrides
    included; it did not exist (AttributeError). Reference: the command's own output."""
    import inerter
    model = inerter.load(LUMPED, y0={"value": 1200, "unit": "mm"})
    text = model.describe()
    assert main(["describe", str(LUMPED), "--set", 'y0={value = 1200, unit = "mm"}']) == 0
    assert capsys.readouterr().out == text + "\n"
    assert "y0 = 1.2 m (given as 1200 mm)" in text and "inerter.f" in text.splitlines()[-1]


def test_describe_of_a_scene_without_descriptions_has_no_trailing_separators(tmp_path):
    """A scene without a description and a parameter without one: `describe` printed "bare: " and
    "k = 400  " (the separators of the missing texts). Reference: the lines as written by hand."""
    import inerter
    scene = tmp_path / "bare.toml"
    scene.write_text('[scene]\nname = "bare"\n[parameters]\nk = 400\n[ground.points]\nO = [0, 0]\n'
                     '[bodies.mass]\nmass = 1\ninertia = 0.1\nposition = [1, 0]\npoints = { P = [0, 0] }\n'
                     '[elements.spring]\ntype = "spring"\nbetween = ["O", "P"]\nk = "k"\nlength = 0.5\n')
    lines = inerter.load(scene).describe().splitlines()
    assert lines[0] == "bare" and "  k = 400" in lines
    assert all(line == line.rstrip() for line in lines)


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
    """The option names the experiment field it overrides; the scene reader checks it (--step, the
    FMU's communication step, with --model fmu: without, it is refused as such, test_cli_polish.py)."""
    out = tmp_path / "out"
    fmu = ["--model", "fmu"] if option == "--step" else []
    assert main(["run", str(TWO_BAR), option, value, "--out", str(out)] + fmu) == 2
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


# -- the command line as a whole (issue 23, item 6) ----------------------------------------------
def _parsers():
    """Every command's parser: the built-in ones and those of the delegated commands."""
    from inerter.cli import DELEGATED, build_parser
    from inerter.studies.bench import bench_parser
    from inerter.studies.builtin import study_parser
    from inerter.studies.device_effects import device_study_parser
    from inerter.studies.sweep import sweep_parser, sweep_plot_parser
    top = build_parser()
    commands = dict(next(a for a in top._actions if a.dest == "command").choices)
    delegated = {"bench": bench_parser(), "sweep": sweep_parser(), "study": study_parser(),
                 "sweep-plot": sweep_plot_parser(), "device-study": device_study_parser()}
    assert set(delegated) == set(DELEGATED)
    commands.update(delegated)
    return top, commands


def test_help_lists_every_command_in_plain_text(capsys):
    top, commands = _parsers()
    with pytest.raises(SystemExit) as info:
        main(["--help"])
    assert info.value.code == 0
    text = capsys.readouterr().out
    assert "``" not in text and ":mod:" not in text
    for name in commands:
        assert re.search(rf"^\s+{re.escape(name)}\s+\S", text, flags=re.M), (name, text)
    assert set(commands) == {"run", "compare", "describe", "build-fmu", "build-system", "paper", "compile", "bench",
                             "sweep", "study", "sweep-plot", "device-study"}


def test_every_option_of_every_command_has_a_help_line():
    top, commands = _parsers()
    for name, parser in [("inerter", top), *commands.items()]:
        for action in parser._actions:
            if action.dest in ("help", "command"):
                continue
            assert action.help, f"inerter {name}: {action.option_strings or action.dest} has no help line"
    from inerter.scene.reader import METHODS
    method = next(a for a in commands["run"]._actions if "--method" in a.option_strings)
    assert all(m in method.help for m in METHODS)


def test_version(capsys):
    import inerter
    with pytest.raises(SystemExit) as info:
        main(["--version"])
    assert info.value.code == 0 and capsys.readouterr().out.strip() == f"inerter {inerter.__version__}"


def test_set_takes_the_expressions_a_scene_takes(tmp_path):
    """b=2*pi is 2π, as `b = "2*pi"` in the scene file would be; an expression over other
    parameters too (b=2*m is twice the mass, 5 kg; m·sqrt(La² + Lb²)/La is a mass, 5√2 kg)."""
    for text, expected in (("b=2*pi", 2 * np.pi), ("b=2*m", 10.0), ("b=m*sqrt(La^2 + Lb^2)/La", 5.0 * np.sqrt(2.0))):
        out = tmp_path / text.replace("*", "x").replace("^", "p").replace("(", "").replace(")", "").replace(" ", "")
        assert main(["run", str(LUMPED), "--set", text, "--stop-time", "0.5", "--out", str(out)]) == 0
        summary = json.loads((out / "summary.json").read_text())
        assert summary["settings"]["parameters"]["b"] == pytest.approx(expected, rel=1e-15)


def test_fmu_runs_take_the_output_interval_and_expressions(tmp_path):
    """--model fmu: experiment.output_interval is the communication step; b=2*pi reaches the FMU as
    the number 2π: its outputs equal the solver's with b = 6.283185307179586 written out."""
    fmu_out, solver_out = tmp_path / "fmu", tmp_path / "solver"
    assert main(["run", str(LUMPED), "--model", "fmu", "--set", "experiment.output_interval=0.25",
                 "--set", "b=2*pi", "--stop-time", "2", "--out", str(fmu_out)]) == 0
    fmu = np.genfromtxt(fmu_out / "lumped_mass_2d.csv", delimiter=",", names=True)
    np.testing.assert_allclose(fmu["time_s"], np.arange(9) * 0.25, rtol=0, atol=1e-12)
    summary = json.loads((fmu_out / "summary.json").read_text())
    assert summary["settings"]["communication_step"] == 0.25
    assert main(["run", str(LUMPED), "--set", "experiment.output_interval=0.25", "--set", f"b={2 * np.pi!r}",
                 "--stop-time", "2", "--out", str(solver_out)]) == 0
    solver = np.genfromtxt(solver_out / "lumped_mass_2d.csv", delimiter=",", names=True)
    scale = np.max(np.abs(solver["Pr2_m"]))
    assert np.max(np.abs(fmu["Pr2_m"] - solver["Pr2_m"])) <= 1e-6 * scale


def test_a_setting_the_fmu_cannot_take_is_a_one_line_error(tmp_path, capsys):
    assert main(["run", str(LUMPED), "--model", "fmu", "--set", "experiment.constraint=projection",
                 "--stop-time", "0.5", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "experiment.constraint" in err and "not settable on the FMU" in err, err


def test_build_fmu_writes_into_out(tmp_path, capsys):
    out = tmp_path / "fmus"
    assert main(["build-fmu", str(LUMPED), "--out", str(out)]) == 0
    assert (out / "lumped_mass_2d.fmu").is_file()
    assert f"built: {out / 'lumped_mass_2d.fmu'}" in capsys.readouterr().out


def test_build_fmu_refuses_a_bad_scene_in_one_line_as_run_does(tmp_path, capsys):
    """A scene build-fmu cannot read (missing; a misspelt field) is the one-line error every command
    gives, ``inerter: error: FILE: FIELD: ...``, with exit status 2 (it began with "error: " only)."""
    bad = tmp_path / "bad.toml"
    bad.write_text(LUMPED.read_text().replace("[bodies.mass]\n", "[bodies.mass]\nmas = 1\n", 1))
    for scene, field in ((tmp_path / "missing.toml", "missing.toml"), (bad, "bodies.mass.mas: unknown field")):
        assert main(["build-fmu", str(scene), "--out", str(tmp_path / "fmus")]) == 2
        err = one_line_error(capsys, field)
        assert err.startswith(f"inerter: error: {scene}"), err


def test_compare_says_why_a_metric_was_not_computed(tmp_path, capsys):
    """compare prints a metric it could not compute with the reason, as run does (its table was
    left empty without a word). The lumped mass's free-oscillation metric needs more periods than
    0.3 s holds (its natural frequency, 1.5 Hz, is computed)."""
    assert main(["compare", str(LUMPED), "--stop-time", "0.3", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    summary = json.loads((tmp_path / "summary.json").read_text())
    reasons = summary["runs"]["corrected"]["metric_errors"]
    assert reasons
    for key, why in reasons.items():
        assert f"{key}: not computed (corrected, uncorrected, oracle): {why}" in out, out


def test_metrics_from_too_few_samples_are_left_out_with_the_reason(tmp_path, capsys):
    out = tmp_path / "coarse"
    assert main(["run", str(LUMPED), "--set", "experiment.output_interval=10", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary["metrics"]) == {"natural_frequency", "natural_frequencies"}
    reasons = summary["metric_errors"]
    assert len(reasons) == 2 and all("3 sample(s)" in r and "at least 5" in r for r in reasons.values()), reasons
    assert "not computed: 3 sample(s)" in capsys.readouterr().out


def test_sweep_plot_writes_beside_its_results_without_out(tmp_path, capsys):
    results = tmp_path / "results.csv"
    rows = [(1.1, "true", 1.51), (1.2, "true", 1.50), (1.1, "false", 1.52), (1.2, "false", 1.53)]
    results.write_text("key,scene,model,y0,effects.centripetal,status,error,fundamental_frequency,run_time_s\n" + "".join(
        f"k{i},lumped_mass_2d,solver,{y0},{cen},ok,,{f},0.1\n" for i, (y0, cen, f) in enumerate(rows)))
    assert main(["sweep-plot", str(results), "--x", "y0", "--y", "fundamental_frequency",
                 "--hue", "effects.centripetal"]) == 0
    assert (tmp_path / "fundamental_frequency_vs_y0.png").stat().st_size > 5000
