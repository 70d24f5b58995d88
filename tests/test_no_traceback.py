"""No input ends in a traceback: one test per class of bad input (issue 23, item 9). Each asserts
exit status 2, one line on stderr naming the file, the field, the value and what was expected,
and no "Traceback"; a run that overflows after a valid start ends with status 3 and its reason."""
from __future__ import annotations

import os
import re
import resource
import subprocess
import sys

import pytest

from inerter.cli import main
from conftest import LUMPED, ROOT, SCENARIOS, TWO_BAR, one_line_error

BRACED = SCENARIOS / "braced_frame_3d.toml"



def scene_with(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


# -- where the output goes ---------------------------------------------------------------------
def test_out_naming_an_existing_file(tmp_path, capsys):
    blocker = tmp_path / "results"
    blocker.write_text("not a folder")
    assert main(["run", str(LUMPED), "--stop-time", "0.1", "--out", str(blocker)]) == 2
    one_line_error(capsys, "--out", repr(str(blocker)), "names an existing file", "expected a folder")
    assert blocker.read_text() == "not a folder"
    assert main(["build-fmu", str(LUMPED), "--out", str(blocker)]) == 2
    one_line_error(capsys, "--out", repr(str(blocker)), "names an existing file")


# -- command-line values: the scene reader's checks, the scene reader's words ----------------------
@pytest.mark.parametrize("option, text, field, scene_value, expected", [
    ("--stop-time", "nan", "experiment.stop_time", "nan", "a finite number"),
    ("--stop-time", "inf", "experiment.stop_time", "inf", "a finite number"),
    ("--stop-time", "-1", "experiment.stop_time", "-1.0", "a number > 0"),
    ("--rtol", "1", "experiment.rtol", "1.0", "a relative tolerance in [1e-14, 0.1]"),
    ("--method", "Euler", "experiment.method", '"Euler"', "one of: DOP853, RK45, Radau, BDF, LSODA, RK4"),
])
def test_a_command_line_value_is_checked_as_the_scene_field_it_replaces(tmp_path, capsys, option, text, field,
                                                                          scene_value, expected):
    """The option's error is the error the same value gives written into the scene file, with the
    option in front: one validator for both."""
    out = tmp_path / "out"
    assert main(["run", str(LUMPED), option, text, "--out", str(out)]) == 2
    from_option = one_line_error(capsys, f"inerter: error: {option}: {LUMPED}: {field}: ", expected)
    assert not out.exists()

    key = field.split(".")[1]
    scene, count = re.subn(rf"(?m)^{key} = .*$", f"{key} = {scene_value}", LUMPED.read_text())
    assert count == 1
    written = scene_with(tmp_path, scene)
    assert main(["run", str(written), "--out", str(out)]) == 2
    from_scene = one_line_error(capsys, f"{written}: {field}: ")
    assert from_option.split(f"{LUMPED}: ", 1)[1] == from_scene.split(f"{written}: ", 1)[1]

    assert main(["run", str(LUMPED), "--set", f"{field}={text}", "--out", str(out)]) == 2
    from_set = one_line_error(capsys, f"{LUMPED}: {field}: ")
    assert from_set.split(f"{LUMPED}: ", 1)[1] == from_scene.split(f"{written}: ", 1)[1]


def test_a_communication_step_longer_than_the_run(tmp_path, capsys):
    assert main(["run", str(LUMPED), "--model", "fmu", "--stop-time", "1", "--step", "2",
                 "--out", str(tmp_path)]) == 2
    one_line_error(capsys, "--step: ", "experiment.communication_step", "2.0", "at most stop_time = 1 s")


def test_an_output_grid_too_fine_to_hold(tmp_path, capsys):
    """stop_time / output_interval samples are allocated: more than a million is refused."""
    assert main(["run", str(LUMPED), "--set", "experiment.output_interval=1e-9", "--out", str(tmp_path)]) == 2
    one_line_error(capsys, str(LUMPED), "experiment.output_interval", "1e-09", "at most 1,000,000 samples")


@pytest.mark.parametrize("item, problem", [("b", "missing '='"), ("=3", "missing name")])
def test_a_set_without_a_name_or_value(capsys, item, problem):
    assert main(["describe", str(LUMPED), "--set", item]) == 2
    one_line_error(capsys, "--set", repr(item), problem, "NAME=VALUE")


def test_a_usage_error_is_one_line(capsys):
    with pytest.raises(SystemExit) as info:
        main(["run", str(LUMPED), "--model", "simulink"])
    assert info.value.code == 2
    one_line = capsys.readouterr().err.strip()
    assert "\n" not in one_line and "--model" in one_line and "simulink" in one_line and "-h" in one_line


@pytest.mark.parametrize("argv, fragment", [
    (["study", "fig10"], "invalid choice: 'fig10'"),
    (["sweep", str(LUMPED), "--vary", "b=1,2"], "required: --out"),
    (["sweep-plot", "results.csv"], "required: --x, --y"),
    (["bench", str(LUMPED), "--pathz", "numpy"], "unrecognized arguments: --pathz numpy"),
    (["device-study", "--rowz", "1"], "unrecognized arguments: --rowz 1"),
])
def test_a_usage_error_of_a_study_command_is_one_line_too(capsys, argv, fragment):
    """The commands handed over to the studies parse their own options: their usage errors read as
    run's, one line naming the command and its -h (they printed argparse's whole usage first)."""
    with pytest.raises(SystemExit) as info:
        main(argv)
    assert info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith(f"inerter {argv[0]}: error: "), err
    assert fragment in err and err.endswith(f"(see inerter {argv[0]} -h)"), err


# -- magnitudes whose arithmetic overflows -----------------------------------------------------------
@pytest.mark.parametrize("how, field", [
    (["--set", "y0=1e300"], "parameters.y0"),
    (["--set", "k=-1e300"], "parameters.k"),
])
def test_a_value_too_large_for_a_step(tmp_path, capsys, how, field):
    assert main(["run", str(LUMPED), *how, "--out", str(tmp_path)]) == 2
    one_line_error(capsys, str(LUMPED), field, "e+300", "magnitude at most 1e+15")


def test_an_initial_position_of_1e300_in_the_scene(tmp_path, capsys):
    path = scene_with(tmp_path, LUMPED.read_text().replace('position = ["La", "y0"]', 'position = ["La", 1e300]', 1))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    one_line_error(capsys, str(path), "bodies.mass.position[2]", "1e+300", "magnitude at most 1e+15")


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_an_overflow_during_a_run_ends_it_with_its_reason(tmp_path, capsys, monkeypatch):
    """Past the bound on magnitudes (lifted here), a state that overflows ends the run: status 3, a
    message, the files written, no traceback (the compiled loop's division by zero included)."""
    import inerter.scene.expressions as expressions
    monkeypatch.setattr(expressions, "MAX_MAGNITUDE", float("inf"))
    for value in ("k=1e300", "y0=1e300"):
        assert main(["run", str(LUMPED), "--set", value, "--out", str(tmp_path / value)]) == 3
        captured = capsys.readouterr()
        assert "Traceback" not in captured.err
        assert "lumped_mass_2d: failed (" in captured.out
        assert (tmp_path / value / "summary.json").is_file()


# -- the size of what is read ------------------------------------------------------------------------
def _limited(limit_bytes=3 * 2**30):
    def apply():
        resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))
    return apply


def test_a_scene_that_is_dev_zero(tmp_path):
    """Read with a cap: refused at 4 MiB, in a process whose memory is bounded (it would fill it)."""
    proc = subprocess.run([sys.executable, "-m", "inerter.cli", "run", "/dev/zero", "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=120, preexec_fn=_limited(),
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    assert proc.returncode == 2, proc.stderr
    err = proc.stderr.strip()
    assert "Traceback" not in err and "\n" not in err, err
    assert err.startswith("inerter: error: /dev/zero: (file): too large") and "at most 4 MiB" in err, err


def _record_scene(tmp_path, record):
    text = BRACED.read_text().replace("records/synthetic_bidirectional.csv", str(record), 1)
    assert str(record) in text
    return scene_with(tmp_path, text)


def test_a_record_that_is_dev_zero(tmp_path, capsys):
    path = _record_scene(tmp_path, "/dev/zero")
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    one_line_error(capsys, str(path), "effects.ground_acceleration.file", "'/dev/zero'", "at most 64 MiB")


def test_a_ten_million_row_record_is_refused_at_once(tmp_path, capsys):
    """10 000 000 rows (80 MB): refused by its size before it is parsed (the documented limit)."""
    record = tmp_path / "long.csv"
    with open(record, "w") as fh:
        for _ in range(100):
            fh.write("0,0,0,0\n" * 100_000)
    path = _record_scene(tmp_path, record)
    try:
        assert main(["describe", str(path)]) == 2
        one_line_error(capsys, str(path), "effects.ground_acceleration.file", str(record), "at most 64 MiB")
    finally:
        record.unlink()


def test_a_record_with_more_samples_than_the_limit(tmp_path, capsys):
    """1 000 001 samples fit in 64 MiB but pass the sample limit: refused, naming it."""
    record = tmp_path / "dense.csv"
    n = 1_000_001
    with open(record, "w") as fh:
        fh.writelines(f"{i * 1e-4:.4f},0,0,0\n" for i in range(n))
    path = _record_scene(tmp_path, record)
    try:
        assert main(["describe", str(path)]) == 2
        one_line_error(capsys, str(path), "effects.ground_acceleration.file", "1,000,001", "at most 1,000,000 samples")
    finally:
        record.unlink()


def test_an_unreadable_record(tmp_path, capsys):
    record = tmp_path / "words.csv"
    record.write_text("time,x,y,z\nsoon,1,2,3\n")
    path = _record_scene(tmp_path, record)
    assert main(["describe", str(path)]) == 2
    one_line_error(capsys, str(path), "effects.ground_acceleration.file", str(record), "numeric CSV columns")


# -- names that become file names ----------------------------------------------------------------------
def test_a_scene_name_too_long_for_a_file_name(tmp_path, capsys):
    name = "a" * 300
    path = scene_with(tmp_path, LUMPED.read_text().replace('name = "lumped_mass_2d"', f'name = "{name}"', 1))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    one_line_error(capsys, str(path), "scene.name", "'aaaa", "at most 100 characters")
    assert not (tmp_path / "out").exists()


def test_a_file_stem_too_long_for_a_scene_name(tmp_path, capsys):
    text = re.sub(r'\nname = "lumped_mass_2d".*\n', "\n", LUMPED.read_text(), count=1)
    path = scene_with(tmp_path, text, name="b" * 120 + ".toml")
    assert main(["describe", str(path)]) == 2
    one_line_error(capsys, str(path), "scene.name (the file's stem)", "at most 100 characters")


def test_every_message_quotes_a_long_value_on_one_short_line(tmp_path, capsys):
    """A whole table given where a number belongs is quoted cut short, on one line."""
    table = "{ " + ", ".join(f"k{i} = {i}" for i in range(200)) + " }"
    path = scene_with(tmp_path, TWO_BAR.read_text().replace('mass = "M1"', f"mass = {table}", 1))
    assert main(["describe", str(path)]) == 2
    err = one_line_error(capsys, str(path), "bodies.bar1.mass")
    assert len(err) < 600
