"""Bad arguments of sweep, sweep-plot, study and bench: each is one line on stderr naming the option,
its value and what was expected, exit status 2, before any run (and before any folder is made).
Before these checks an --out inside a file ended in a traceback (FileExistsError, exit 1), a negative
--max-runs ran nothing and exited 0, a --stop-time every run refuses failed each run (exit 3), a
--step without --model fmu was taken and did nothing, --stop-time beside a varied
experiment.stop_time ran every run to --stop-time under the varied value's label, START:STOP:NUM with START = STOP ran one run
for NUM, a --scheduler that is no address was a ValueError traceback, and bench read a bad --signal only after its oracle reference, with a traceback."""
from __future__ import annotations

import os

import pytest

from inerter.cli import main
from conftest import LUMPED, one_line_error


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A working folder holding one file, `afile`, and nothing else."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("not a folder\n")
    return tmp_path


SWEEP = ["sweep", str(LUMPED), "--vary", "y0=1.1,1.2", "--no-progress"]


@pytest.mark.parametrize("argv, fragments", [
    (SWEEP + ["--out", "afile"], ["--out: names an existing file (got 'afile'"]),
    (SWEEP + ["--out", "afile/sweep"], ["--out: afile is a file, not a folder (got 'afile/sweep'"]),
    (SWEEP + ["--out", "s", "--max-runs", "-1"], ["--max-runs: out of range (got -1; expected a whole number ≥ 0)"]),
    (SWEEP + ["--out", "s", "--workers", "0"], ["--workers: out of range (got 0; expected a whole number ≥ 1)"]),
    (SWEEP + ["--out", "s", "--stop-time", "-1"], ["--stop-time: ", "experiment.stop_time: out of range (got -1.0"]),
    (SWEEP + ["--out", "s", "--stop-time", "nan"], ["--stop-time: ", "experiment.stop_time: is not finite"]),
    (SWEEP + ["--out", "s", "--step", "0.01"], ["--step: the FMU's communication step, without --model fmu (got "
                                                 "0.01; expected --model fmu beside it", "experiment.output_interval"]),
    (SWEEP + ["--out", "s", "--scheduler", "nonsense"],
     ["--scheduler: not an address: missing port number in address 'nonsense' (got 'nonsense'"]),
    (["sweep", str(LUMPED), "--vary", "experiment.stop_time=2,6", "--stop-time", "4", "--out", "s"],
     ["--stop-time: experiment.stop_time is also given with --vary"]),
    (SWEEP + ["--out", "s", "--model", "fmu", "--step", "0.02", "--set", "experiment.output_interval=0.01"],
     ["--step: experiment.output_interval is also given with --set"]),
    (["sweep", str(LUMPED), "--vary", "y0=1.2:1.2:4", "--out", "s"],
     ["--vary: y0: empty range (got '1.2:1.2:4'; expected START ≠ STOP for NUM = 4 values"]),
    (["sweep-plot", "results.csv", "--x", "y0", "--y", "peak", "--out", "afile/plot.png"],
     ["--out: afile is a file, not a folder (got 'afile/plot.png'"]),
    (["sweep-plot", "results.csv", "--x", "y0", "--y", "peak", "--out", "."], ["--out: names a folder (got '.'"]),
    (["study", "fig9", "--no-progress", "--out", "afile"], ["--out: names an existing file (got 'afile'"]),
    (["study", "fig9", "--no-progress", "--out", "s", "--range", "1.2:1.2"], ["--range: empty range (got '1.2:1.2'"]),
    (["study", "fig9", "--no-progress", "--out", "s", "--range", "nan:1.5"], ["--range: out of range (got 'nan:1.5'"]),
    (["study", "fig9", "--no-progress", "--out", "s", "--max-runs", "-2"], ["--max-runs: out of range (got -2"]),
    (["bench", str(LUMPED), "--out", "afile"], ["--out: names an existing file (got 'afile'"]),
    (["bench", str(LUMPED), "--out", "s", "--budget", "-1"], ["--budget: out of range (got -1.0"]),
    (["bench", str(LUMPED), "--out", "s", "--signal", "Q.r[2]"],
     ["--signal: unknown signal (got 'Q.r[2]'; expected P.r[1] or P.r[2] with P one of O, G, P)"]),
])
def test_a_bad_argument_is_one_line_and_exit_2_before_anything_runs(folder, capsys, argv, fragments):
    assert main(argv) == 2
    one_line_error(capsys, *fragments)
    assert sorted(os.listdir(folder)) == ["afile"]          # no folder made, no run written


@pytest.mark.parametrize("text, values", [
    ("effects.gravity=[0, -9.81],[0,0]", [[0, -9.81], [0, 0]]),
    ('y0={value = 1100, unit = "mm"},1.2', [{"value": 1100, "unit": "mm"}, 1.2]),
    ("b=max(1, m),2*m", ["max(1, m)", "2*m"]),
    ("experiment.method=RK4,DOP853", ["RK4", "DOP853"]),
])
def test_vary_splits_its_values_at_the_commas_between_them(text, values):
    """Each value is read as --set reads it (a vector, a table with a unit, an expression): the
    commas inside one are not separators. Before, `[0, -9.81],[0,0]` was split into '[0', ' -9.81]',
    ... and refused ('wrong shape (got '[0'...)')."""
    from inerter.scene.overrides import parse_set
    from inerter.studies.sweep import parse_vary
    name, got = parse_vary(text)
    assert got == values
    assert got == [parse_set([f"{name}={v}"])[name] for v in
                   ({"y0": ['{value = 1100, unit = "mm"}', "1.2"], "b": ["max(1, m)", "2*m"],
                     "effects.gravity": ["[0, -9.81]", "[0,0]"], "experiment.method": ["RK4", "DOP853"]}[name])]


def test_the_step_check_is_one_message_for_run_compare_sweep_and_study(folder, capsys):
    """--step without --model fmu is refused by one check (inerter.studies.sweep.check_fmu_step),
    so run, compare, sweep and study say the same thing. Before, run and compare said
    ``--step: the FMU's communication step, without --model fmu (got '0.1'; expected ...)`` and sweep
    ``--step 0.1: the FMU's communication step, without --model fmu (expected ...)``."""
    messages = []
    for argv in (["run", str(LUMPED), "--step", "0.1", "--out", "o"],
                 ["compare", str(LUMPED), "--model", "oracle", "--step", "0.1", "--out", "o"],
                 ["sweep", str(LUMPED), "--vary", "y0=1.1,1.2", "--step", "0.1", "--out", "o"],
                 ["study", "fig9", "--no-progress", "--step", "0.1", "--out", "o"]):
        assert main(argv) == 2
        err = one_line_error(capsys, "inerter: error: --step: the FMU's communication step, without --model fmu "
                             "(got ", "0.1", "; expected --model fmu beside it; the solver's samples are set by "
                             "--set experiment.output_interval=SECONDS)")
        messages.append(err.replace("'", ""))                # the typed text ('0.1') or the number (0.1)
    assert len(set(messages)) == 1, messages
    assert sorted(os.listdir(folder)) == ["afile"]
