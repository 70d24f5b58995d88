"""CPU time of whole compiled runs (``compiled.integrate_compiled``: the integration loop alone, no
outputs or metrics), the best of `--repeat` runs after one to warm up, per scene.

    PYTHONPATH=<tree> python benchmarks/compiled_run_timing.py SCENE.toml ... [--repeat 20] [--method RK4]

Run it under two trees alternately to compare them (a shared machine's timings drift: compare
rounds taken side by side, docs/changepoint.md).
"""
from __future__ import annotations

import argparse
import time

import inerter
from inerter.engine import compiled


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--method", default=None)
    args = parser.parse_args()
    for path in args.scenes:
        model = inerter.load(path)
        settings = model.settings(method=args.method)
        compiled.integrate_compiled(model.mechanism, settings)
        best = float("inf")
        for _ in range(args.repeat):
            t0 = time.process_time()
            run = compiled.integrate_compiled(model.mechanism, settings)
            best = min(best, time.process_time() - t0)
        loops = model.mechanism.closed_loops() if hasattr(model.mechanism, "closed_loops") else "?"
        print(f"{model.name}\t{settings.method}\tloops {loops}\tsteps {run.steps}\tstatus {run.status}\t"
              f"best {best * 1e3:.3f} ms", flush=True)


if __name__ == "__main__":
    main()
