"""What winding the 3D rotational elements' angles costs: compiled whole runs of two source trees,
side by side, alternating.

    python benchmarks/winding_cost.py TREE_BEFORE TREE_AFTER [ROUNDS]

Each round runs, for each tree in turn, a fresh interpreter with that tree first on sys.path
(`--one TREE`), which loads its kernels (compiled beforehand: a first round that compiles is not
counted; run once more) and times the compiled whole run of each scene (process time of the
integration, ``run.cpu_time``, best of 5) and hashes its samples and outputs. Printed: a markdown
table of the median CPU time of each tree over the rounds, their ratio, and whether the two trees'
samples and outputs are bit-identical.
"""
from __future__ import annotations

import hashlib
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# (scene, overrides): 3D with a rotational spring (the paper's two-bar mechanism in 3D, a bar wound
# past half a turn), 3D without one, 2D with one
SCENES = [("scenarios/two_bar_2d_as_3d.toml", {}), ("tests/data/winding_bar_3d.toml", {}),
          ("scenarios/double_pendulum_3d.toml", {}), ("scenarios/spherical_pendulum_3d.toml", {}),
          ("scenarios/braced_frame_3d.toml", {}), ("scenarios/two_bar_2d.toml", {})]


def one(tree: str):
    """Time every scene with the package of `tree`; prints one JSON line."""
    import inerter

    out = {}
    for scene, overrides in SCENES:
        model = inerter.load(Path(tree) / scene if (Path(tree) / scene).exists() else ROOT / scene, **overrides)
        model.simulate(stop_time=0.05, metrics=False)
        best, digest = None, None
        for _ in range(5):
            r = model.simulate(metrics=False)
            assert r.run.extra["path"] == "compiled", r.run.extra["path"]
            best = r.run.cpu_time if best is None else min(best, r.run.cpu_time)
        h = hashlib.sha256(r.run.states.tobytes())
        h.update(r.values().tobytes())
        out[scene] = (best, h.hexdigest()[:16], r.run.steps)
    print(json.dumps(out))


def main(before: str, after: str, rounds: int):
    times = {tree: {s: [] for s, _ in SCENES} for tree in (before, after)}
    digests = {}
    for k in range(rounds):
        for tree in (before, after) if k % 2 == 0 else (after, before):
            env = dict(os.environ, PYTHONPATH=tree)
            text = subprocess.run([sys.executable, __file__, "--one", tree], env=env, check=True,
                                  capture_output=True, text=True).stdout
            result = json.loads(text.strip().splitlines()[-1])
            for scene, (cpu, digest, steps) in result.items():
                times[tree][scene].append(cpu)
                digests[tree, scene] = (digest, steps)
        print(f"round {k + 1} done", file=sys.stderr, flush=True)
    print("| scene | steps | before CPU (s) | after CPU (s) | after ÷ before | samples and outputs |")
    print("|---|---|---|---|---|---|")
    for scene, _ in SCENES:
        a, b = statistics.median(times[before][scene]), statistics.median(times[after][scene])
        same = "bit-identical" if digests[before, scene][0] == digests[after, scene][0] else "differ"
        print(f"| {Path(scene).stem} | {digests[after, scene][1]} | {a:.4f} | {b:.4f} | {b / a:.3f} | {same} |")


if __name__ == "__main__":
    if sys.argv[1] == "--one":
        one(sys.argv[2])
    else:
        main(sys.argv[1], sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 5)
