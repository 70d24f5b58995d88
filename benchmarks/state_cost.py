"""What the engine's internal states (y = [q, v, z]) cost the scenes that declare none: the ideal
scenes against the package before them, side by side in one run.

    git archive c6678e6 | (mkdir -p /tmp/inerter-base-states && tar -x -C /tmp/inerter-base-states)
    python benchmarks/state_cost.py --base /tmp/inerter-base-states [--out docs/benchmarks]

The measurement of benchmarks/device_cost.py (RK4 with a fixed 1 ms step, CPU time per evaluation
of the right-hand side, best of its REPEATS runs, a fresh process per tree and round, ROUNDS rounds
taken in turn) and its check that a DOP853 run's states are bit-identical.
"""
from __future__ import annotations

import argparse
import datetime
from pathlib import Path

from device_cost import REPEATS, ROOT, ROUNDS, SCENES, measure


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", required=True, help="the package's source tree before the internal states")
    ap.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated, some of " + ", ".join(SCENES))
    ap.add_argument("--rounds", type=int, default=ROUNDS)
    args = ap.parse_args(argv)
    scenes = {n: SCENES[n] for n in args.scenes.split(",")}
    cost = {"base": {n: [] for n in scenes}, "now": {n: [] for n in scenes}}
    hashes = {}
    for k in range(args.rounds):
        order = [("base", Path(args.base)), ("now", ROOT)]
        for label, tree in (order if k % 2 == 0 else order[::-1]):
            for name, (c, digest) in measure(tree, scenes).items():
                cost[label][name].append(c)
                hashes.setdefault(name, {})[label] = digest
        print(f"round {k + 1}/{args.rounds}: " + ", ".join(
            f"{n} {min(cost['now'][n]) / min(cost['base'][n]):.3f}" for n in scenes))
    lines = ["# What the internal states cost a scene without any", "",
             f"`python benchmarks/state_cost.py --base /tmp/inerter-base-states`, {datetime.date.today().isoformat()}: "
             f"µs per evaluation of the right-hand side (RK4 1 ms, best of {REPEATS} runs and of {args.rounds} rounds "
             "taken in turn, each tree in a fresh process), the package before the state y = [q, v, z] (commit "
             "c6678e6) and with it; DOP853 states over 5 s compared by their SHA-256.", "",
             "| scene | before (µs/eval) | now (µs/eval) | now / before | DOP853 states |", "|---|---|---|---|---|"]
    for name in scenes:
        b, n = min(cost["base"][name]), min(cost["now"][name])
        same = "bit-identical" if hashes[name]["base"] == hashes[name]["now"] else "DIFFER"
        lines.append(f"| {name} | {b:.3f} | {n:.3f} | {n / b:.2f} | {same} |")
    lines += ["", "A scene without internal states has z empty: the right-hand side never calls the states' "
              "rates, and each element's law tests `el_int[e, STATES]` in a branch marked rarely taken. "
              "Ratios within a few per cent are timing noise on a shared 2-core machine."]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "state_cost.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
