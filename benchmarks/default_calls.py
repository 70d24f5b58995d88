"""Two default calls, timed in the tree on PYTHONPATH, to compare trees side by side.

    PYTHONPATH=<tree> python <tree>/benchmarks/default_calls.py

* the braced frame under 60 s of a synthetic 10 ms ground record (the scene and record of
  benchmarks/record_segments.py), ``simulate(rtol=1e-6, atol=1e-6)``: the best wall time of 5 calls,
  each on a freshly loaded model, after one call that loads the kernels;
* scenarios/two_bar_2d.toml, ``simulate(rtol=1e-6, atol=1e-6)``: the best of 7.

Run it for each tree alternately (the machines are noisy); PYTHONPATH is required, or the editable
installation's package is imported whatever the tree.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

TREE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(TREE / "benchmarks"))

import inerter  # noqa: E402
import record_segments as rs  # noqa: E402


def record_call(repeat=5) -> float:
    folder = Path(tempfile.mkdtemp())
    scene = folder / rs.SCENE.name
    shutil.copy(rs.SCENE, scene)
    rs.write_record(folder / rs.RECORD, 60.0, 0.01)
    rs.timed(scene, False, 60.0, 1, rtol=1e-6, atol=1e-6)
    best, _ = rs.timed(scene, False, 60.0, repeat, rtol=1e-6, atol=1e-6)
    shutil.rmtree(folder, ignore_errors=True)
    return best


def two_bar_call(repeat=7) -> float:
    best = np.inf
    for _ in range(repeat):
        model = inerter.load(TREE / "scenarios" / "two_bar_2d.toml")
        start = time.perf_counter()
        result = model.simulate(rtol=1e-6, atol=1e-6)
        best = min(best, time.perf_counter() - start)
        assert result.status == "ok", result.message
    return best


if __name__ == "__main__":
    print(f"{TREE}: record call {record_call():.4f} s, two_bar_2d default call at 1e-6 {two_bar_call() * 1e3:.2f} ms "
          f"(package: {Path(inerter.__file__).parent})")
