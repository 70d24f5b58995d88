"""The package as a user installs it: a wheel built from a copy of the repository, installed with its
dependencies in a new virtual environment, used from a folder outside the repository. Export needs
the FMU sources and the scenes, which live beside the package in the repository (fmu_src/,
scenarios/); the wheel carries copies (setup.py), and these tests use nothing else.

The dependencies come from the package index (pip's cache makes a repeated run fast), pinned to
the versions of the environment running the tests, so that numba finds the kernels this machine
compiled. Without the index the fixture fails and says why: nothing here is skipped.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.fmu import build as fmu_build

ROOT = Path(__file__).resolve().parents[1]
#: Not part of a source tree a user would build from.
NOT_SOURCE = (".git", "build", "out", "*.egg-info", "__pycache__", ".pytest_cache", ".venv", "*.pyc")


def _run(command, cwd, env, timeout=300, check=True) -> subprocess.CompletedProcess:
    proc = subprocess.run([str(c) for c in command], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)
    if check:
        assert proc.returncode == 0, (f"{' '.join(map(str, command))} ended with exit status "
                                      f"{proc.returncode}:\n{proc.stdout[-2000:]}\n{proc.stderr[-3000:]}")
    return proc


def _pins() -> str:
    """name==version for every distribution here, as pip constraints (the tests' own package and
    anything not installed from an index left out)."""
    done = _run([sys.executable, "-m", "pip", "freeze", "--exclude-editable"], ROOT, dict(os.environ))
    return "\n".join(line for line in done.stdout.splitlines()
                     if re.fullmatch(r"[A-Za-z0-9._-]+==[^\s;@]+", line)
                     and not line.lower().startswith("inerter=="))


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(python, environment, work folder) of a new virtual environment with the wheel installed."""
    base = tmp_path_factory.mktemp("wheel")
    t0 = time.perf_counter()
    source = base / "source"
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(*NOT_SOURCE))
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", base / "dist", "."],
         source, env)
    (wheel,) = (base / "dist").glob("inerter-*.whl")
    venv = base / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", venv], base, env)
    python = venv / "bin" / "python"
    (base / "pins.txt").write_text(_pins())
    _run([sys.executable, "-m", "pip", "--python", python, "install", "-q",
          "-c", base / "pins.txt", wheel], base, env, timeout=900)
    work = base / "work"
    work.mkdir()
    venv_env = {"PATH": f"{venv / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
                "HOME": os.environ.get("HOME", str(base))}
    print(f"wheel built and installed in {time.perf_counter() - t0:.1f} s")
    return python, venv_env, work


def test_the_installed_package_reads_nothing_from_the_repository(installed):
    python, env, work = installed
    code = ("import json, inerter; from inerter.common import locations as l; "
            "print(json.dumps([inerter.__file__, str(l.fmu_sources()), str(l.scenarios()), str(l.devices())]))")
    package, sources, scenes, devices = map(Path, json.loads(_run([python, "-c", code], work, env).stdout))
    site = python.parents[1].resolve()
    for path in (package, sources, scenes, devices):
        assert site in path.resolve().parents, f"{path} is not in the new environment"
    assert (sources / "inerter_slave.py").read_bytes() == (ROOT / "fmu_src" / "inerter_slave.py").read_bytes()
    shipped = sorted(p.relative_to(scenes).as_posix() for p in scenes.rglob("*.toml"))
    assert shipped == sorted(p.relative_to(ROOT / "scenarios").as_posix()
                             for p in (ROOT / "scenarios").rglob("*.toml"))
    assert sorted(p.name for p in devices.glob("*.toml")) == sorted(p.name for p in (ROOT / "devices").glob("*.toml"))


def test_the_installed_package_builds_and_runs_an_fmu(installed, tmp_path):
    """`inerter build-fmu` and `inerter run --model fmu` with the installed scene: the FMU holds
    the same files as one built from the repository, and runs as the solver does here."""
    python, env, work = installed
    scenes = Path(_run([python, "-c", "from inerter.common.locations import scenarios; print(scenarios())"],
                       work, env).stdout.strip())
    inerter_cli = python.with_name("inerter")
    done = _run([inerter_cli, "build-fmu", scenes / "two_bar_2d.toml"], work, env)
    assert "built: build/fmu/two_bar_2d.fmu" in done.stdout
    reference = fmu_build.build(ROOT / "scenarios" / "two_bar_2d.toml", tmp_path, force=True)
    with zipfile.ZipFile(work / "build" / "fmu" / "two_bar_2d.fmu") as z, zipfile.ZipFile(reference) as r:
        assert sorted(n for n in z.namelist() if n.startswith("resources/")) == \
            sorted(n for n in r.namelist() if n.startswith("resources/"))
        assert z.read("resources/inerter_slave.py") == r.read("resources/inerter_slave.py")

    _run([inerter_cli, "run", scenes / "two_bar_2d.toml", "--model", "fmu", "--stop-time", "0.5",
          "--out", "out"], work, env)
    csv = work / "out" / "two_bar_2d.csv"
    header = csv.read_text().splitlines()[0].split(",")
    data = np.loadtxt(csv, delimiter=",", skiprows=1)
    model = inerter.load(ROOT / "scenarios" / "two_bar_2d.toml")
    ref = model.simulate(stop_time=0.5, output_interval=model.scene.experiment.communication_step,
                         metrics=False)
    assert np.allclose(data[:, header.index("time (s)")], ref.time, rtol=0, atol=1e-12)
    # The CSV holds 12 significant digits.
    assert np.allclose(data[:, header.index("C.r[2] (m)")], ref["C.r[2]"], rtol=1e-11, atol=0)


def test_the_installed_paper_command_finds_its_scenes(installed):
    python, env, work = installed
    assert "--scenarios" in _run([python.with_name("inerter"), "paper", "--help"], work, env).stdout
    code = "import json; from inerter.cli import paper_scenes; print(json.dumps([str(p) for p in paper_scenes()]))"
    scenes = [Path(p) for p in json.loads(_run([python, "-c", code], work, env).stdout)]
    assert [p.name for p in scenes] == ["lumped_mass_2d.toml", "two_bar_2d.toml"]
    assert all(p.is_file() and python.parents[1].resolve() in p.resolve().parents for p in scenes)
    # A folder without them: a one-line error before anything runs.
    done = _run([python.with_name("inerter"), "paper", "--scenarios", work / "none"], work, env, check=False)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip().count("\n") == 0 and "--scenarios" in done.stderr


def test_the_installed_package_builds_the_coupled_system(installed, tmp_path):
    """`inerter build-system`: the controller's source and the scenes come from the installed
    package; the system files are those built from the repository."""
    from inerter.fmu import cosim

    python, env, work = installed
    _run([python.with_name("inerter"), "build-system", "-o", "system"], work, env)
    reference = cosim.build_system(tmp_path)
    for role in ("osp", "ssd"):
        assert (work / "system" / reference[role].name).read_bytes() == reference[role].read_bytes()
    for role in ("plant", "controller"):
        assert zipfile.is_zipfile(work / "system" / reference[role].name)
