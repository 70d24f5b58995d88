"""Coupled co-simulation: the two-bar FMU + the PD-controller FMU on an fmpy master loop,
against the same system solved as one scene (two_bar_2d_pd.toml).

    python scenarios/cosim_two_bar_pd.py [--out out/cosim]

Prints the largest difference of C_y for several communication steps (it shrinks in proportion
to the step: the zero-order hold of the controller's force) and plots the runs.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

import inerter
from inerter.fmu.cosim import build_controller, run_coupled
from inerter.fmu.build import build

HERE = Path(__file__).resolve().parent


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="out/cosim")
    ap.add_argument("--stop-time", type=float, default=5.0)
    ap.add_argument("--steps", default="0.01,0.005,0.0025")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    reference_scene = inerter.load(HERE / "two_bar_2d_pd.toml")
    p = {k["name"]: k["value"] for k in reference_scene.parameter_info()}
    one = reference_scene.simulate(stop_time=args.stop_time, output_interval=0.0025, rtol=1e-11, atol=1e-13,
                                   metrics=False)
    plant, ctrl = build(HERE / "two_bar_2d.toml"), build_controller()
    rows, runs = [], []
    for h in [float(s) for s in args.steps.split(",")]:
        t, y, F = run_coupled(plant, ctrl, args.stop_time, h, p["kp"], p["kd"], math.sqrt(2.0))
        ref = np.interp(t, one.time, one["C.r[2]"])
        err = float(np.max(np.abs(y - ref)))
        rows.append((h, err))
        runs.append((h, t, y))
        print(f"communication step {h:g} s: max |C_y(co-sim) − C_y(one scene)| = {err:.3e} m")
    for (h1, e1), (h2, e2) in zip(rows, rows[1:]):
        print(f"  error ratio for step {h1:g} → {h2:g}: {e1 / e2:.2f} (first order: {h1 / h2:.2f})")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 3.6))
    ax.plot(one.time, one["C.r[2]"] - math.sqrt(2), "k", lw=1.5, label="one scene (two_bar_2d_pd)")
    for h, t, y in runs:
        ax.plot(t, y - math.sqrt(2), lw=0.8, ls="--", label=f"co-simulation, h = {h:g} s")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("C_y − static (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "cosim_two_bar_pd.png", dpi=110)
    print(f"wrote {out / 'cosim_two_bar_pd.png'}")
    return rows


if __name__ == "__main__":
    main()
