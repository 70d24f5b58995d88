"""What an FMU carries and what its first instance costs.

    python benchmarks/fmu_footprint.py [--scene scenarios/two_bar_2d.toml] [--write docs/benchmarks/fmu_footprint.md]

Sizes: the scene's FMU as built now, carrying the modules of ``inerter`` its slave can import
(inerter/fmu/payload.py), against the same build carrying the whole package in ``resources/``, as
every build did before.

Times: a first instance in a fresh process (fmpy's FMU2Slave, `python -I`, only PATH, HOME and
INERTER_CACHE_DIR in the environment), wall clock: ``instantiate`` (the FMU's Python module is
imported: inerter, numpy, scipy, numba), ``exitInitializationMode`` (the scene is loaded and the
stepper made: on the compiled path the kernels are loaded from the kernel cache, or compiled into
it), and the first ``doStep`` (on the compiled path it compiles the native step's C function when
the cache lacks it). "empty" is a new temporary INERTER_CACHE_DIR; "warm" is the one the empty run
filled, used again by the next processes (best of --repeat). The user's own cache is not touched.
"""
from __future__ import annotations

import argparse
import datetime
import io
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from inerter.fmu import build as fmu_build  # noqa: E402

INSTANCE = r"""
import json, sys, time
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
fmu, folder, compiled = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
md = read_model_description(fmu)
vr = {v.name: v.valueReference for v in md.modelVariables}
slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(fmu, folder),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="first")
t0 = time.perf_counter()
slave.instantiate(loggingOn=True)
t1 = time.perf_counter()
slave.setupExperiment(startTime=0.0)
slave.enterInitializationMode()
slave.setBoolean([vr["compiled"]], [compiled])
slave.exitInitializationMode()
t2 = time.perf_counter()
slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
t3 = time.perf_counter()
slave.terminate()
slave.freeInstance()
print(json.dumps({"instantiate": t1 - t0, "init": t2 - t1, "step": t3 - t2}))
"""


def whole_package_files() -> list[Path]:
    """Every file of the package, as builds shipped before inerter/fmu/payload.py."""
    package = fmu_build.PACKAGE_DIR
    return sorted(p for p in package.rglob("*")
                  if p.is_file() and "__pycache__" not in p.parts and p.suffix not in (".pyc", ".pyo"))


def build_both(scene: Path, out: Path) -> dict[str, Path]:
    fmus = {"after": fmu_build.build(scene, out / "after", force=True)}
    slim = fmu_build._shipped_package_files
    fmu_build._shipped_package_files = whole_package_files
    try:
        fmus["before"] = fmu_build.build(scene, out / "before", force=True)
    finally:
        fmu_build._shipped_package_files = slim
    return fmus


def sizes(fmu: Path) -> dict:
    with zipfile.ZipFile(fmu) as z:
        package = [i for i in z.infolist() if i.filename.startswith("resources/inerter/")]
        if not package and f"resources/{fmu_build.PAYLOAD_FILE}" in z.namelist():
            # Built since the package's modules travel in one archive: count what it holds.
            package = zipfile.ZipFile(io.BytesIO(z.read(f"resources/{fmu_build.PAYLOAD_FILE}"))).infolist()
        return {"archive": fmu.stat().st_size, "entries": len(z.infolist()),
                "package_files": len(package), "package_bytes": sum(i.file_size for i in package)}


def first_instance(fmu: Path, cache: Path, compiled: bool, work: Path) -> dict:
    folder = Path(tempfile.mkdtemp(dir=work, prefix="unzipped_"))
    env = {"PATH": os.environ.get("PATH", ""), "HOME": os.environ.get("HOME", str(work)),
           "INERTER_CACHE_DIR": str(cache)}
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-I", "-c", INSTANCE, str(fmu), str(folder), "1" if compiled else "0"],
                          cwd=work, env=env, capture_output=True, text=True, timeout=1800)
    wall = time.perf_counter() - t0
    if done.returncode != 0:
        raise SystemExit(f"the first instance of {fmu} failed (exit status {done.returncode}): "
                         f"{done.stderr[-2000:]}")
    out = json.loads(done.stdout.strip().splitlines()[-1])
    said = done.stdout + done.stderr
    out["path"] = next((p for p in ("compiled", "numpy") if f"{p} path" in said), "?")
    out["process"] = wall
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", type=Path, default=ROOT / "scenarios" / "two_bar_2d.toml")
    p.add_argument("--repeat", type=int, default=3, help="warm runs per row, best kept (default 3)")
    p.add_argument("--write", type=Path, help="also write the tables, with the date and command, here")
    args = p.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="inerter_fmu_footprint_"))
    try:
        return measure(args, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def measure(args, work: Path) -> int:
    fmus = build_both(args.scene, work / "fmu")
    size = {k: sizes(v) for k, v in fmus.items()}
    size_lines = ["| FMU | archive (bytes) | entries | files of `inerter` | their bytes |",
                  "| --- | ---: | ---: | ---: | ---: |"]
    for label, key in (("before: the whole package", "before"), ("after: what the slave imports", "after")):
        s = size[key]
        size_lines.append(f"| {label} | {s['archive']:,} | {s['entries']} | {s['package_files']} | "
                          f"{s['package_bytes']:,} |")
    print("\n".join(size_lines), flush=True)

    load = os.getloadavg()[0]
    rows = []

    def row(label, fmu_key, cache, compiled, repeat=1):
        best = min((first_instance(fmus[fmu_key], cache, compiled, work) for _ in range(repeat)),
                   key=lambda r: r["process"])
        rows.append((label, best))
        print(f"{label:60s} {json.dumps(best)}", file=sys.stderr, flush=True)

    cache = work / "cache"
    row("after, empty kernel cache, compiled path", "after", cache, True)
    row("after, warm kernel cache, compiled path", "after", cache, True, args.repeat)
    row("before, warm kernel cache, compiled path", "before", cache, True, args.repeat)
    row("after, empty kernel cache, numpy path (`compiled` false)", "after", work / "cache_numpy", False)
    load_end = os.getloadavg()[0]

    time_lines = ["| first instance in a fresh process | path | instantiate (s) | exitInitializationMode (s) "
                  "| first doStep (s) | whole process (s) |",
                  "| --- | --- | ---: | ---: | ---: | ---: |"]
    time_lines += [f"| {label} | {r['path']} | {r['instantiate']:.2f} | {r['init']:.2f} | {r['step']:.2f} | "
                   f"{r['process']:.2f} |" for label, r in rows]
    import numba
    machine = (f"{os.cpu_count()} cores, {platform.python_implementation()} {platform.python_version()}, "
               f"numba {numba.__version__}; load average {load:.1f} at the start, {load_end:.1f} at the end")
    print("\n".join(time_lines))
    print(machine)
    if args.write:
        scene = args.scene.resolve()
        shown = scene.relative_to(ROOT) if ROOT in scene.parents else scene
        command = f"python benchmarks/fmu_footprint.py --scene {shown} --write {args.write}"
        args.write.parent.mkdir(parents=True, exist_ok=True)
        args.write.write_text(
            "# What an FMU carries, and what its first instance costs\n\n"
            f"- **Date:** {datetime.date.today().isoformat()}\n"
            f"- **Command:** `{command}`\n"
            f"- **Machine:** {machine}\n\n"
            f"The FMU of `{shown}`, built twice: with the modules of `inerter` its slave can import "
            "(`inerter/fmu/payload.py`; the build today) and with the whole package (the build "
            "before). The archive is stored without compression.\n\n" + "\n".join(size_lines) + "\n\n"
            "A first instance in a fresh process (fmpy's `FMU2Slave`, `python -I`), wall clock. "
            "\"empty\": a new `INERTER_CACHE_DIR`; \"warm\": the one the empty run filled, best of "
            f"{args.repeat} processes. Both FMUs carry the same kernel sources, so they share the "
            "cache.\n\n" + "\n".join(time_lines) + "\n\n"
            "Where an empty cache's time goes: the slave's constructor (`instantiate`) evaluates the "
            "scene's start outputs with the default stepper, the compiled one, so it compiles the "
            "kernels that stepper needs first, even when the importer then sets `compiled` false; "
            "`exitInitializationMode` finds them loaded; the first `doStep` on the compiled path "
            "compiles the integrator loop and the native step's C function.\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
