"""The 3D scenes on the numpy path and on the compiled path, side by side.

    python benchmarks/spatial_timing.py        # prints a markdown table, writes docs/benchmarks/spatial_timing.md

Each scene with its own experiment (method, tolerances, stop time, output interval). CPU: process
time of the integration (best of 3 for runs under 1 s; the kernels are compiled beforehand).
Deviation: max |P.r[i]| difference between the two paths over every point coordinate and output
sample (both at the scene's tolerance, so it measures the integration error's difference, not a
bound on either). Scenes with Z-X-Z Euler angles run the numpy path on both rows and are left out.
"""
from __future__ import annotations

import datetime
import gc
from pathlib import Path

import numpy as np

from inerter import api
import inerter
from inerter.engine import compiled

ROOT = Path(__file__).resolve().parents[1]


def timed(model, path):
    best = None
    for _ in range(3):
        gc.collect()
        result = model.simulate(path=path, metrics=False)
        if best is None or result.run.cpu_time < best.run.cpu_time:
            best = result
        if result.run.cpu_time > 1.0:
            break
    return best


def main():
    if not compiled.AVAILABLE:
        raise SystemExit(f"numba is not available: {compiled.WHY_NOT}")
    warm = api.warm_up(spatial=True)
    rows = []
    for path in sorted((ROOT / "scenarios").glob("*_3d.toml")):
        model = inerter.load(path)
        if compiled.unsupported(model.mechanism):
            continue
        model.simulate(path="compiled", stop_time=0.05, metrics=False)        # compile for this scene's arrays
        fast = timed(model, "compiled")
        slow = timed(model, "numpy")
        assert fast.run.extra["path"] == "compiled", fast.run.extra["path"]
        names = [n for n in fast.names if ".r[" in n]
        dev = max(float(np.max(np.abs(fast[n] - slow[n]))) for n in names)
        s = fast.settings
        rows.append((path.stem, s.method, s.rtol, s.stop_time, model.mechanism.n, model.mechanism.m, fast.run.steps,
                     slow.run.steps, slow.run.cpu_time, fast.run.cpu_time, dev))
        print(rows[-1], flush=True)
    head = ("| scene | method | rtol | simulated (s) | n | m | steps compiled / numpy | numpy CPU (s) "
            "| compiled CPU (s) | numpy ÷ compiled | max deviation of the paths (m) |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|\n")
    body = "".join(f"| {a} | {b} | {c:g} | {d:g} | {n} | {m} | {f} / {g} | {h:.3f} | {i:.4f} | {h / i:.0f} | {j:.1e} |\n"
                   for a, b, c, d, n, m, f, g, h, i, j in rows)
    text = (f"# 3D scenes: numpy path and compiled path\n\n`python benchmarks/spatial_timing.py`, "
            f"{datetime.date.today()}, one run (kernels loaded in {warm:.1f} s before it). Each scene's own "
            "experiment; CPU: process time of the integration, best of 3 under 1 s. n, m: velocity "
            "coordinates and constraint rows.\n\n" + head + body)
    print(text)
    out = ROOT / "docs" / "benchmarks" / "spatial_timing.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)


if __name__ == "__main__":
    main()
