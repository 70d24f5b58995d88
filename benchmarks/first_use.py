"""First use on a fresh machine: how long until the first result, with and without compiling the
engine's kernels ahead of time (``inerter compile``, which the set-up runs: Makefile).

    python benchmarks/first_use.py [--write docs/benchmarks/first_use.md]

Every row is one whole subprocess, timed by the wall clock, with its own empty kernel cache
(a temporary ``INERTER_CACHE_DIR``) where it says so:

1. without ahead-of-time compilation, in one empty cache: the first ``inerter run`` of the 2D
   scene (the default, compiled path), then the first of the 3D scene (it compiles the 3D kernels);
2. in another empty cache: ``inerter compile`` (the set-up's cost), then the same two runs, then a
   warm process: the CLI run again, and Python's ``import inerter; load; simulate`` (the compiled
   path, metrics included) to its first result;
3. the numpy path (no kernels) for reference.

"notice" counts the lines the runs write on stderr while the kernels compile
(inerter.engine.compiled.CompileNotice); a warm process writes none. Every subprocess runs a copy
of the package taken at the start (PYTHONPATH), so that an edit of the kernels made meanwhile in the
working tree does not change their cache's key half-way.
"""
from __future__ import annotations

import argparse
import datetime
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BIN = Path(sys.executable).parent
INERTER = str(BIN / "inerter")
SCENE_2D = str(ROOT / "scenarios" / "two_bar_2d.toml")
SCENE_3D = str(ROOT / "scenarios" / "spherical_pendulum_3d.toml")
#: The targets of the first use (seconds to the first result).
TARGETS = {"2D": 15.0, "3D": 20.0, "warm": 1.0}

API = """
import inerter
model = inerter.load({scene!r})
result = model.simulate(path="compiled")
print(result.status, len(result.time))
"""


def snapshot(folder: Path) -> Path:
    """A copy of the package (and links to the scenes warm_up reads and to pyproject.toml, which
    marks the folder as a checkout for inerter.common.locations) in `folder`."""
    shutil.copytree(ROOT / "inerter", folder / "inerter", ignore=shutil.ignore_patterns("__pycache__"))
    (folder / "scenarios").symlink_to(ROOT / "scenarios")
    (folder / "pyproject.toml").symlink_to(ROOT / "pyproject.toml")
    return folder


def timed(cmd, cache, source):
    """(wall seconds, notice lines, exit status) of one subprocess with the kernel cache `cache`,
    importing the package from `source`."""
    env = dict(os.environ, INERTER_CACHE_DIR=str(cache),
               PYTHONPATH=os.pathsep.join([str(source)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=source, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    said = [line for line in done.stderr.splitlines() if line.startswith("inerter: ")]
    for line in said:
        print("    " + line, file=sys.stderr)
    if done.returncode != 0:
        print(done.stdout, done.stderr, file=sys.stderr)
    return wall, sum(line.startswith("inerter: compiling") for line in said), done.returncode


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--write", type=Path, help="also write the table, with the date and command, here")
    args = p.parse_args(argv)

    rows = []
    work = Path(tempfile.mkdtemp(prefix="inerter_first_use_"))
    source = snapshot(work / "source")

    def row(label, cmd, cache, target=None):
        wall, notices, status = timed(cmd, cache, source)
        verdict = "" if target is None else ("yes" if wall <= target else "no")
        rows.append((label, wall, notices, status, f"{target:g} s" if target else "", verdict))
        print(f"{label:72s} {wall:7.1f} s  notice {notices}  exit {status}", file=sys.stderr, flush=True)

    def run(scene, out, path=None):
        return [INERTER, "run", scene, "--out", str(work / out)] + (["--path", path] if path else [])

    def api(scene):
        return [sys.executable, "-c", API.format(scene=scene)]

    load = os.getloadavg()[0]
    cold = work / "cache_cold"
    row("first 2D run, no AOT (`inerter run scenarios/two_bar_2d.toml`)", run(SCENE_2D, "a2"), cold, TARGETS["2D"])
    row("first 3D run, no AOT (`inerter run scenarios/spherical_pendulum_3d.toml`)", run(SCENE_3D, "a3"), cold, TARGETS["3D"])
    aot = work / "cache_aot"
    row("set-up: `inerter compile` (2D and 3D kernels), empty cache", [INERTER, "compile"], aot)
    row("first 2D run after AOT", run(SCENE_2D, "b2"), aot, TARGETS["2D"])
    row("first 3D run after AOT", run(SCENE_3D, "b3"), aot, TARGETS["3D"])
    row("warm process: 2D CLI run again", run(SCENE_2D, "c2"), aot, TARGETS["warm"])
    row("warm process: `import inerter; load; simulate` (2D, compiled)", api(SCENE_2D), aot, TARGETS["warm"])
    row("warm process: `import inerter; load; simulate` (3D, compiled)", api(SCENE_3D), aot, TARGETS["warm"])
    row("numpy path (`--path numpy`, no kernels): 2D CLI run", run(SCENE_2D, "d2", "numpy"), aot)
    row("numpy path (`--path numpy`, no kernels): 3D CLI run", run(SCENE_3D, "d3", "numpy"), aot)
    load_end = os.getloadavg()[0]

    lines = ["| what (one subprocess each) | wall (s) | notice lines | exit | target | met |",
             "| --- | ---: | ---: | ---: | ---: | --- |"]
    lines += [f"| {label} | {wall:.1f} | {notices} | {status} | {target} | {verdict} |"
              for label, wall, notices, status, target, verdict in rows]
    try:
        import numba
        numba_version = numba.__version__
    except ImportError:                                              # pragma: no cover
        numba_version = "missing"
    machine = (f"{os.cpu_count()} cores, {platform.python_implementation()} {platform.python_version()}, "
               f"numba {numba_version}; load average {load:.1f} at the start, {load_end:.1f} at the end")
    table = "\n".join(lines)
    print(table)
    print(machine)
    if args.write:
        command = "python benchmarks/first_use.py" + (f" --write {args.write}" if args.write else "")
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(
            "# First use: time to the first result, with and without ahead-of-time compilation\n\n"
            f"- **Date:** {datetime.date.today().isoformat()}\n"
            f"- **Command:** `{command}`\n"
            f"- **Machine:** {machine}\n\n"
            "Each row is a whole subprocess, wall clock; \"no AOT\" rows share one empty kernel cache, "
            "the others another one that `inerter compile` fills first. `inerter run` takes the "
            "compiled path by default; `--path numpy` compiles nothing.\n\n" + table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
