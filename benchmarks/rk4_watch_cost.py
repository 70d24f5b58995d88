"""What RK4's watches cost (kernels.rk4_watch, kernels.energy_watch): compiled RK4 at 1 ms on scenes
with and without the energy watch, and on the benchmark chains, for two trees of the package side by
side, each round one process per tree, alternating (docs/performance.md).

    python benchmarks/rk4_watch_cost.py BEFORE_TREE AFTER_TREE [--rounds 3] [--calls 5]

Each tree's kernels are compiled for it on its first use (`PYTHONPATH=TREE inerter compile` first
keeps that out of the timings). Prints, per scene, the best of `--calls` calls of
``inerter.load(scene).simulate(method="RK4", step=1e-3, stop_time=T, metrics=False)`` in each round
(wall ms, after a first call that loads the kernels), then each tree's best round.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: (label, scene, simulated seconds); "chainN" is benchmarks/chain_scene.py's N-link chain.
CASES = (("lumped_mass_2d", "scenarios/lumped_mass_2d.toml", 20.0),
         ("snap_through_2d", "scenarios/hard/snap_through_2d.toml", 10.0),
         ("spherical_pendulum_3d", "scenarios/spherical_pendulum_3d.toml", 20.0),
         ("two_bar_2d", "scenarios/two_bar_2d.toml", 20.0),
         ("portal_frame_brace_2d", "scenarios/portal_frame_brace_2d.toml", 20.0),
         ("double_pendulum_3d", "scenarios/double_pendulum_3d.toml", 20.0),
         ("chain32", "chain32", 1.0), ("chain128", "chain128", 1.0))

CHILD = """
import sys, time, inerter
for label, scene, stop in {cases!r}:
    m = inerter.load(scene)
    m.simulate(method="RK4", step=1e-3, stop_time=0.01, metrics=False)
    best = min(_time(m, stop) for _ in range({calls}))
    print(label, best)
"""
TIMER = """
def _time(m, stop):
    t = time.perf_counter()
    m.simulate(method="RK4", step=1e-3, stop_time=stop, metrics=False)
    return time.perf_counter() - t
"""


def scenes(folder: Path) -> list[tuple[str, str, float]]:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from chain_scene import write_chain
    out = []
    for label, scene, stop in CASES:
        path = (str(write_chain(folder / f"{scene}.toml", int(scene[5:]))) if scene.startswith("chain")
                else str(ROOT / scene))
        out.append((label, path, stop))
    return out


def one_round(tree: str, cases, calls: int) -> dict[str, float]:
    code = "import time\n" + TIMER + CHILD.format(cases=cases, calls=calls)
    env = dict(os.environ, PYTHONPATH=tree)
    # from a folder of its own: `-c` puts the working folder first on sys.path, ahead of PYTHONPATH
    # (run from a checkout, both rows would time that checkout's package)
    lines = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True,
                           cwd=tempfile.gettempdir()).stdout.split("\n")
    return {label: float(value) for label, value in (line.split() for line in lines if line.strip())}


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--calls", type=int, default=5)
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        cases = scenes(Path(folder))
        best = {args.before: {}, args.after: {}}
        for r in range(args.rounds):
            for tree in (args.before, args.after):
                times = one_round(tree, cases, args.calls)
                print(f"round {r + 1} {tree}: " + ", ".join(f"{k} {1e3 * v:.1f} ms" for k, v in times.items()),
                      flush=True)
                for k, v in times.items():
                    best[tree][k] = min(best[tree].get(k, v), v)
    print("\n| | " + " | ".join(label for label, _, _ in cases) + " |")
    print("|---" * (len(cases) + 1) + "|")
    for tree in (args.before, args.after):
        print(f"| {tree} | " + " | ".join(f"{1e3 * best[tree][label]:.1f}" for label, _, _ in cases) + " |")


if __name__ == "__main__":
    main()
