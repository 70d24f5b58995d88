"""Where a warm process's time to its first result goes: ``import inerter; load; simulate`` on the
compiled path, with the kernels already in the cache, split into stages, CPU seconds of this process
(``time.process_time``, which depends less than the wall clock on what else the machine runs).

    python benchmarks/warm_breakdown.py [scene.toml] [--repeat 5]

The package imported is the one on PYTHONPATH (else the installed one): ``PYTHONPATH=/other/checkout``
measures another version the same way.

Each repetition is a fresh subprocess (a warm process is a new one); the table gives each stage's
median over them. The stages, in the order a run meets them: numpy, numba, the rest of ``import
inerter``, ``inerter.engine.compiled`` (the kernels' module and the numba registries it imports
ahead), the registries numba loads with the first kernel taken from the cache (forced here, so
that they are not counted in the first load), reading the scene, the run up to its metrics (the
integrator loop's load from the cache and the integration), the metrics (the outputs' kernels'
loads and their evaluation). Under "loads": each kernel taken from numba's cache, and the time it
took (counted in its stage too).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

STAGES = r"""
import json, sys, time
T = [time.process_time()]
stages, loads = {}, {}
def lap(name):
    T.append(time.process_time()); stages[name] = T[-1] - T[-2]
import numpy; lap("numpy")
import numba; lap("numba")
import inerter; lap("rest of import inerter")
from inerter.engine import compiled; lap("inerter.engine.compiled")
from numba.core.registry import cpu_target
cpu_target.target_context.refresh(); lap("numba registries (first cache load)")
from numba.core import caching
load_overload = caching.Cache.load_overload
def traced(self, sig, ctx):
    t = time.process_time(); out = load_overload(self, sig, ctx)
    loads[self._name.split()[1]] = time.process_time() - t; return out
caching.Cache.load_overload = traced
model = inerter.load(sys.argv[1]); lap("load the scene")
import inerter.api as api
compute_metrics = api.compute_metrics
def timed_metrics(*args):
    lap("simulate: kernel loads and integration"); out = compute_metrics(*args); lap("metrics"); return out
api.compute_metrics = timed_metrics
result = model.simulate(path="compiled")
assert result.status == "ok", result.message
print(json.dumps({"stages": stages, "loads": loads, "total": T[-1] - T[0]}))
"""


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default=str(ROOT / "scenarios" / "two_bar_2d.toml"))
    p.add_argument("--repeat", type=int, default=5)
    args = p.parse_args(argv)
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)           # bytecode as an installed package has it
    runs = []
    for _ in range(args.repeat + 1):                   # the first writes the bytecode: not counted
        # run from a folder of its own: `-c` puts the working folder first on sys.path, ahead of PYTHONPATH
        done = subprocess.run([sys.executable, "-c", STAGES, str(Path(args.scene).resolve())], env=env,
                              cwd=tempfile.gettempdir(), capture_output=True, text=True)
        if done.returncode:
            print(done.stderr, file=sys.stderr)
            return 1
        runs.append(json.loads(done.stdout))
    runs = runs[1:]
    print(f"| stage (CPU s, median of {args.repeat}) | {Path(args.scene).name} |")
    print("| --- | ---: |")
    for stage in runs[0]["stages"]:
        print(f"| {stage} | {statistics.median(r['stages'][stage] for r in runs):.3f} |")
    print(f"| **total (interpreter start-up not included)** | {statistics.median(r['total'] for r in runs):.3f} |")
    for name in runs[0]["loads"]:
        print(f"| load from the cache: `{name}` | {statistics.median(r['loads'].get(name, 0.0) for r in runs):.3f} |")
    print(f"load average {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
