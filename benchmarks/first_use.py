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

``--warm`` times only the warm rows, against a kernel cache already filled (``--cache``, by default
the user's: ``$INERTER_CACHE_DIR`` or ``~/.cache/inerter``), so that nothing compiles; each row is
run ``--repeat`` times (after one untimed run that writes the bytecode) and its median and fastest
wall times are given, with the median CPU time of the whole process. The "first result" is the
line a run prints: the API script's ``ok <samples>``, the CLI's summary (``<scene>: ok ...``); the
time until that line reaches stdout is its own row (the process then exits; the CLI first writes
the CSV and draws the PNG). ``--nice N`` runs the subprocesses at that scheduling priority, so that
a shared machine's other jobs take less of their wall time. ``--before CHECKOUT`` times the same
rows with the package of another checkout too (a copy of its ``inerter``), the two alternating,
for a side-by-side comparison in one run.

    python benchmarks/first_use.py --warm [--cache DIR] [--before /path/to/checkout] [--repeat 7] [--nice -10]

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
import resource
import shutil
import statistics
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


def snapshot(folder: Path, root: Path = ROOT) -> Path:
    """A copy of the package of the checkout `root` (and links to the scenes warm_up reads and to
    pyproject.toml, which marks the folder as a checkout for inerter.common.locations) in `folder`."""
    shutil.copytree(root / "inerter", folder / "inerter", ignore=shutil.ignore_patterns("__pycache__"))
    (folder / "scenarios").symlink_to(ROOT / "scenarios")
    (folder / "pyproject.toml").symlink_to(ROOT / "pyproject.toml")
    return folder


def environment(cache, source) -> dict:
    """The subprocesses' environment: the kernel cache `cache`, the package from `source`; bytecode
    written and read as in an installed package (pip compiles it), stdout unbuffered so that the
    time a line reaches it is the time it was printed."""
    env = dict(os.environ, INERTER_CACHE_DIR=str(cache), PYTHONUNBUFFERED="1",
               PYTHONPATH=os.pathsep.join([str(source)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


#: The scheduling priority (nice value) of the timed subprocesses; None: this process's own.
PRIORITY = None


def _prioritised():
    if PRIORITY is not None:
        os.setpriority(os.PRIO_PROCESS, 0, PRIORITY)


def timed(cmd, cache, source, first_line=None):
    """(wall seconds, notice lines, exit status, CPU seconds) of one subprocess with the kernel
    cache `cache`, importing the package from `source`; with `first_line`, the wall seconds are
    those until a line of stdout starting with it was printed (None where none was). The CPU
    seconds (user + system, the whole process) depend less on what else the machine runs."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    seen = None
    with tempfile.TemporaryFile("w+") as err, subprocess.Popen(
            cmd, cwd=source, env=environment(cache, source), stdout=subprocess.PIPE, stderr=err, text=True,
            preexec_fn=_prioritised) as proc:
        out = []
        for line in proc.stdout:
            if seen is None and first_line is not None and line.startswith(first_line):
                seen = time.perf_counter() - t0
            out.append(line)
        proc.wait()
        wall = time.perf_counter() - t0 if first_line is None else seen
        err.seek(0)
        stderr = err.read()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    said = [line for line in stderr.splitlines() if line.startswith("inerter: ")]
    for line in said:
        print("    " + line, file=sys.stderr)
    if proc.returncode != 0:
        print("".join(out), stderr, file=sys.stderr)
    return wall, sum(line.startswith("inerter: compiling") for line in said), proc.returncode, cpu


def default_cache() -> Path:
    """The user's kernel cache (inerter.engine.compiled.cache_root, without importing it)."""
    if os.environ.get("INERTER_CACHE_DIR"):
        return Path(os.environ["INERTER_CACHE_DIR"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "inerter"


def warm(args) -> int:
    """The warm rows only, against the filled cache `args.cache`, `args.repeat` times each, for this
    checkout and (``--before``) another, alternating; prints (and writes) the table."""
    work = Path(tempfile.mkdtemp(prefix="inerter_first_use_"))
    sources = {"after": snapshot(work / "after")}
    if args.before:
        sources = {"before": snapshot(work / "before", args.before.resolve()), **sources}
    cache = args.cache or default_cache()
    cli = [INERTER, "run", SCENE_2D, "--out", str(work / "run")]
    api2, api3 = ([sys.executable, "-c", API.format(scene=scene)] for scene in (SCENE_2D, SCENE_3D))
    rows = [("`import inerter`, whole process", [sys.executable, "-c", "import inerter"], None),
            ("`import inerter; load; simulate` (2D, compiled, metrics) to its printed result", api2, "ok "),
            ("`import inerter; load; simulate` (2D), whole process (with its exit)", api2, None),
            ("`import inerter; load; simulate` (3D, compiled, metrics) to its printed result", api3, "ok "),
            ("`import inerter; load; simulate` (3D), whole process (with its exit)", api3, None),
            ("2D CLI run (`inerter run scenarios/two_bar_2d.toml`) to its printed summary", cli, "two_bar_2d: "),
            ("2D CLI run, whole process (CSV, summary.json and PNG written)", cli, None)]
    times = {(label, which): [] for label, _, _ in rows for which in sources}
    load = os.getloadavg()[0]
    for label, cmd, first_line in rows:
        for source in sources.values():
            timed(cmd, cache, source, first_line)                  # writes the bytecode; not timed
        for _ in range(args.repeat):
            for which, source in sources.items():
                wall, notices, status, cpu = timed(cmd, cache, source, first_line)
                if notices or status or wall is None:
                    print(f"{label} ({which}): notice {notices}, exit {status}: the cache {cache} is not warm "
                          "or the run failed", file=sys.stderr)
                    return 1
                times[label, which].append((wall, cpu))
        print(label, {w: f"{statistics.median(t[0] for t in times[label, w]):.2f}" for w in sources},
              file=sys.stderr, flush=True)
    load_end = os.getloadavg()[0]
    return report(args, warm_table(rows, sources, times), load, load_end, warm_rows=True)


def warm_table(rows, sources, times) -> str:
    """The warm rows' table: per checkout the median and fastest wall time and the median CPU time."""
    head = " | ".join(f"{w}: wall median | {w}: wall fastest | {w}: CPU median" for w in sources)
    lines = [f"| warm process, one subprocess each (s) | {head} | target | met (after, median wall) |",
             "| --- |" + " ---: |" * (3 * len(sources) + 1) + " --- |"]
    for label, _, first_line in rows:
        cells = []
        for w in sources:
            walls, cpus = [t[0] for t in times[label, w]], [t[1] for t in times[label, w]]
            cpu = "" if first_line else f"{statistics.median(cpus):.2f}"       # CPU: whole processes only
            cells.append(f"{statistics.median(walls):.2f} | {min(walls):.2f} | {cpu}")
        target = TARGETS["warm"] if first_line else None                 # the first result's rows
        after = statistics.median(t[0] for t in times[label, "after"])
        met = "" if target is None else ("yes" if after <= target else "no")
        lines.append(f"| {label} | {' | '.join(cells)} | {f'{target:g} s' if target else ''} | {met} |")
    return "\n".join(lines)


def report(args, table, load, load_end, warm_rows=False) -> int:
    """Print the table and the machine; with ``--write``, write them with the date and command."""
    try:
        import numba
        numba_version = numba.__version__
    except ImportError:                                              # pragma: no cover
        numba_version = "missing"
    machine = (f"{os.cpu_count()} cores, {platform.python_implementation()} {platform.python_version()}, "
               f"numba {numba_version}; load average {load:.1f} at the start, {load_end:.1f} at the end")
    print(table)
    print(machine)
    if not args.write:
        return 0
    command = "python benchmarks/first_use.py" + (" --warm" if warm_rows else "")
    if warm_rows:
        command += f" --repeat {args.repeat}" + (f" --before {args.before}" if args.before else "")
        command += f" --nice {args.nice}" if args.nice is not None else ""
        command += f" --cache {args.cache}" if args.cache else ""
    command += f" --write {args.write}"
    args.write.parent.mkdir(parents=True, exist_ok=True)
    if warm_rows:                  # a dated section after the earlier measurements, which stay
        earlier = args.write.read_text() if args.write.is_file() else "# First use: time to the first result\n"
        args.write.write_text(
            earlier.rstrip("\n") + f"\n\n## Warm process, {datetime.date.today().isoformat()}\n\n"
            f"- **Command:** `{command}`\n"
            f"- **Machine:** {machine}\n\n"
            "Each row is a whole subprocess, wall clock, on a kernel cache filled before (nothing compiles: "
            f"no notice line); median and fastest of {args.repeat} runs each" +
            (", the two checkouts alternating" if args.before else "") +
            (f", at nice {args.nice}" if args.nice is not None else "") + ".\n\n" + table + "\n")
        return 0
    args.write.write_text(
        "# First use: time to the first result, with and without ahead-of-time compilation\n\n"
        f"- **Date:** {datetime.date.today().isoformat()}\n"
        f"- **Command:** `{command}`\n"
        f"- **Machine:** {machine}\n\n"
        "Each row is a whole subprocess, wall clock; \"no AOT\" rows share one empty kernel cache, "
        "the others another one that `inerter compile` fills first. `inerter run` takes the "
        "compiled path by default; `--path numpy` compiles nothing.\n\n" + table + "\n")
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--write", type=Path, help="also write the table, with the date and command, here")
    p.add_argument("--warm", action="store_true", help="only the warm rows, on a filled kernel cache (--cache)")
    p.add_argument("--cache", type=Path, help="with --warm: the filled kernel cache (default: the user's)")
    p.add_argument("--before", type=Path, help="with --warm: another checkout to time side by side")
    p.add_argument("--repeat", type=int, default=5, help="with --warm: runs per row (default 5)")
    p.add_argument("--nice", type=int, help="run the timed subprocesses at this nice value (below 0 needs root: "
                                            "shields them from other jobs on a shared machine)")
    args = p.parse_args(argv)
    global PRIORITY
    PRIORITY = args.nice
    if args.nice is not None:      # this process too: it reads the lines as they are printed, and times them
        os.setpriority(os.PRIO_PROCESS, 0, args.nice)
    if args.warm:
        return warm(args)

    rows = []
    work = Path(tempfile.mkdtemp(prefix="inerter_first_use_"))
    source = snapshot(work / "source")

    def row(label, cmd, cache, target=None):
        wall, notices, status, _ = timed(cmd, cache, source)
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
    return report(args, "\n".join(lines), load, load_end)

if __name__ == "__main__":
    sys.exit(main())
