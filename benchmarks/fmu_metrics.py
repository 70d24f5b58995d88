"""An FMU run's metrics: from the FMU's own dense output (what `simulate_fmu` computes) against a
cubic spline through its samples (what it computed before), both against the solver's metrics
from its integrator's dense output, and what each costs.

    PYTHONPATH=. python benchmarks/fmu_metrics.py

Scenes at their own settings (10 ms communication step): two_bar_2d (60 s, steady state of C_y),
lumped_mass_2d (10 s, a free oscillation's frequency, amplitude, mean), braced_frame_3d (60 s of
ground record, three peaks). Prints, per metric, |FMU − solver| with each way of reading between
the samples, and the CPU seconds the metrics took each way (process time, one run each).
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import inerter
from inerter.api import compute_metrics
from inerter.fmu.run import simulate_fmu

SCENES = Path(__file__).resolve().parents[1] / "scenarios"
CASES = (("two_bar_2d", None), ("lumped_mass_2d", 10.0), ("braced_frame_3d", None))


def timed_metrics(model, fmu, dense: bool):
    keep = fmu.fmu_dense
    if not dense:
        fmu.fmu_dense = None
    t0 = time.process_time()
    try:
        return compute_metrics(model, fmu), time.process_time() - t0
    finally:
        fmu.fmu_dense = keep
        fmu.close()


def main():
    print(f"{'scene':16} {'metric':28} {'solver':>14} {'|FMU dense - solver|':>21} {'|spline - solver|':>18}")
    costs = []
    for name, stop in CASES:
        path = SCENES / f"{name}.toml"
        solver = inerter.load(path).simulate(**({"stop_time": stop} if stop else {}))
        fmu = simulate_fmu(path, stop_time=stop, metrics=False)
        dense, t_dense = timed_metrics(solver.model, fmu, True)
        spline, t_spline = timed_metrics(solver.model, fmu, False)
        for key, value in solver.metrics.items():
            if key.endswith("natural_frequencies") or key.endswith("natural_frequency"):
                continue            # from the linearisation, no time history
            print(f"{name:16} {key:28} {value:14.9g} {abs(dense[key] - value):21.2e} {abs(spline[key] - value):18.2e}")
        costs.append((name, t_dense, t_spline, fmu.fmu_dense.steps, fmu.fmu_dense.restores, fmu.run.cpu_time))
    print(f"\n{'scene':16} {'metrics, FMU dense (s)':>23} {'metrics, spline (s)':>20} {'doSteps':>8} "
          f"{'restores':>9} {'the FMU run (s)':>16}")
    for name, t_dense, t_spline, steps, restores, run in costs:
        print(f"{name:16} {t_dense:23.3f} {t_spline:20.3f} {steps:8d} {restores:9d} {run:16.3f}")


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
