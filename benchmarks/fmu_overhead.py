"""Per-communication-step cost of a scene's FMU through fmpy, against the solver called directly.

    python benchmarks/fmu_overhead.py [--stop-time 20] [--step 0.01]

Three ways to advance the same scene over the same communication points, measured side by side
(process CPU time, one run each, in this order): the solver's whole-run integration
(`Model.simulate`, one adaptive integration), the solver's co-simulation stepper called directly
(`Model.stepper().step`, restarted at each communication point as the FMU does), and the FMU
through `fmpy.simulate_fmu`. Writes docs/fmu_overhead.md.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import inerter
from inerter.fmu_build import build

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--stop-time", type=float, default=20.0)
    ap.add_argument("--step", type=float, default=0.01)
    args = ap.parse_args(argv)
    import fmpy
    rows = []
    for name in ("lumped_mass_2d", "two_bar_2d"):
        scene = ROOT / "scenarios" / f"{name}.toml"
        fmu = build(scene)
        model = inerter.load(scene)
        n = int(round(args.stop_time / args.step))

        t0 = time.process_time()
        whole = model.simulate(stop_time=args.stop_time, output_interval=args.step, metrics=False)
        t_whole = time.process_time() - t0

        st = model.stepper()
        t0 = time.process_time()
        for k in range(1, n + 1):
            st.step(k * args.step)
            st.outputs()
        t_stepper = time.process_time() - t0

        t0 = time.process_time()
        res = fmpy.simulate_fmu(str(fmu), stop_time=args.stop_time, output_interval=args.step)
        t_fmu = time.process_time() - t0
        assert abs(res["time"][-1] - args.stop_time) < 1e-9
        diff = float(np.max(np.abs(res["C.r[2]" if name == "two_bar_2d" else "P.r[2]"]
                                   - whole["C.r[2]" if name == "two_bar_2d" else "P.r[2]"])))
        rows.append((name, n, t_whole, t_stepper, t_fmu, diff))
    head = (f"Communication step {args.step:g} s, {args.stop_time:g} s simulated, default scene tolerances.\n\n"
            "| scene | steps | solver, whole run (s) | solver stepper (s) | FMU via fmpy (s) | FMU per step (ms) "
            "| FMU / whole run | FMU / stepper | max difference FMU vs whole run (m) |\n"
            "|---|---|---|---|---|---|---|---|---|\n")
    body = "".join(f"| {a} | {b} | {c:.2f} | {d:.2f} | {e:.2f} | {1e3 * e / b:.3f} | {e / c:.2f} | {e / d:.2f} "
                   f"| {f:.2e} |\n" for a, b, c, d, e, f in rows)
    print(head + body)
    (ROOT / "docs").mkdir(exist_ok=True)
    (ROOT / "docs" / "fmu_overhead.md").write_text(
        "# FMU overhead\n\nMeasured by `python benchmarks/fmu_overhead.py` on a 2-core machine.\n\n" + head + body)


if __name__ == "__main__":
    main()
