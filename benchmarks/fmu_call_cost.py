"""What one `simulate_fmu` call costs a process that has made one before: the check that the FMU is
current (`inerter.fmu.build.build` on a built scene), then the whole call with the scene's metrics
(the run through fmpy and the FMU's dense output, docs/fmu.md). CPU seconds, best of `--repeats`.

    PYTHONPATH=<tree> python <tree>/benchmarks/fmu_call_cost.py [--scenes two_bar_2d,...] [--repeats 3]

Run it for two trees in turn to compare them (each builds its FMUs into its own build/fmu).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from inerter.fmu.build import build
from inerter.fmu.run import simulate_fmu

ROOT = Path(__file__).resolve().parents[1]


def best(fn, repeats: int) -> float:
    """The fewest CPU seconds of `repeats` calls of fn."""
    out = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        fn()
        out = min(out, time.process_time() - t0)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", default="two_bar_2d,lumped_mass_2d,braced_frame_3d")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    print(f"{'scene':18s} {'current-FMU check (s)':>22s} {'simulate_fmu with metrics (s)':>30s}")
    for scene in args.scenes.split(","):
        path = ROOT / "scenarios" / f"{scene}.toml"
        simulate_fmu(path, {})                     # builds the FMU, loads the kernels
        check = best(lambda: build(path), args.repeats)
        call = best(lambda: simulate_fmu(path, {}), args.repeats)
        print(f"{scene:18s} {check:22.3f} {call:30.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
