"""What the README tells a user to type works as written: every ``inerter`` line of its shell
blocks runs (short stop times added with --set), and ``make demo`` / ``make test`` each do the
whole set-up from nothing, the demo without the test extras."""
from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess

import pytest

from inerter.cli import main
from conftest import ROOT

README = ROOT / "README.md"


def shell_lines(text: str) -> list[str]:
    """The commands of the ```sh blocks: comments cut, continued lines joined."""
    lines, current = [], ""
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for raw in block.splitlines():
            line = raw.split(" #", 1)[0].rstrip() if not raw.lstrip().startswith("#") else ""
            if line.endswith("\\"):
                current += line[:-1] + " "
                continue
            line, current = (current + line).strip(), ""
            if line:
                lines.append(line)
    return lines


COMMANDS = [c for c in shell_lines(README.read_text()) if c.startswith("inerter ")]
SHORT = {"run": ["--set", "experiment.stop_time=0.5"], "compare": ["--set", "experiment.stop_time=0.5"]}


def test_the_readme_has_commands_to_run():
    words = {shlex.split(c)[1] for c in COMMANDS}
    assert {"run", "describe", "compare", "build-fmu"} <= words, COMMANDS
    assert {c for c in shell_lines(README.read_text()) if not c.startswith("inerter ")} == {"make demo", "make test"}


@pytest.mark.parametrize("command", COMMANDS)
def test_a_readme_command_runs_as_written(command, tmp_path, monkeypatch, capsys):
    """Run from a folder holding the repository's scenarios/ (and build/, so that an FMU the
    suite built is reused), as a user in a clone would."""
    (tmp_path / "scenarios").symlink_to(ROOT / "scenarios")
    (ROOT / "build").mkdir(exist_ok=True)
    (tmp_path / "build").symlink_to(ROOT / "build")
    monkeypatch.chdir(tmp_path)
    argv = shlex.split(command)[1:]
    code = main(argv + SHORT.get(argv[0], []))
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "Traceback" not in captured.err


@pytest.mark.skipif(shutil.which("make") is None, reason="no make")
@pytest.mark.parametrize("target, extras", [("demo", False), ("test", True)])
def test_make_sets_up_everything_from_nothing(tmp_path, target, extras):
    """``make -n`` in a fresh copy (no .venv): the target creates the environment, installs the
    package, compiles the kernels and runs; only ``make test`` installs the test extras."""
    for name in ("Makefile", "pyproject.toml"):
        shutil.copy(ROOT / name, tmp_path / name)
    env = {k: v for k, v in os.environ.items() if k not in ("MAKELEVEL", "MAKEFLAGS", "MFLAGS")}  # as a shell runs it
    plan = subprocess.run(["make", "-n", target], cwd=tmp_path, capture_output=True, text=True, check=True,
                          env=env).stdout
    steps = ["-m venv .venv", "pip install --quiet -e .", "inerter compile",
             "inerter paper" if target == "demo" else "-m pytest"]
    positions = [plan.find(step) for step in steps]
    assert -1 not in positions and positions == sorted(positions), plan
    assert ('-e ".[test]"' in plan) == extras, plan


def test_the_readme_scene_runs(tmp_path, capsys):
    """The scene of "The scene format by example", as printed (its y0 in mm), runs; it is
    lumped_mass_2d trimmed, so it starts where that scene does."""
    (block,) = re.findall(r"```toml\n(.*?)```", README.read_text(), flags=re.S)
    path = tmp_path / "readme_scene.toml"
    path.write_text(block)
    out = tmp_path / "out"
    assert main(["run", str(path), "--set", "experiment.stop_time=0.5", "--out", str(out)]) == 0, capsys.readouterr().err
    first = (out / "lumped_mass_2d.csv").read_text().splitlines()[1].split(",")
    header = (out / "lumped_mass_2d.csv").read_text().splitlines()[0].split(",")
    assert float(first[header.index("P.r[2] (m)")]) == 1.5            # the header carries units
