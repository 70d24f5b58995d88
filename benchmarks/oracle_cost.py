"""The oracle's cost per evaluation of Eq. (33): `Mechanism.accelerations` of `model.oracle()` at
each scene's initial pose with velocities v0 + 0.1 m/s (rad/s) and unit inputs, best of 7 repeats
of 200 calls, on the scenes whose oracle runs are the slowest in tests/test_engine_vs_oracle.py
and on scenes with 2D joints, point forces, gravity and a ground motion, and (with ż, the state
rates, where the scene has internal states) on inerter devices with a series connection. The scenes are read from
the checkout of the `inerter` that is imported, so that two checkouts compare by PYTHONPATH:

    PYTHONPATH=. python benchmarks/oracle_cost.py
"""
import time
from pathlib import Path

import numpy as np

import inerter

ROOT = Path(inerter.__file__).resolve().parents[1]
SCENES = ("tests/data/twisted_pair_3d.toml", "scenarios/two_bar_2d_as_3d.toml", "scenarios/braced_frame_3d.toml",
          "scenarios/double_pendulum_3d.toml", "scenarios/two_bar_2d_pd.toml", "scenarios/shear_building_tmdi_2d.toml",
          "scenarios/series_inerter_2d.toml", "scenarios/hard/backlash_device_2d.toml",
          "tests/data/device_combo_series_3d.toml")


def per_call(mech, calls=200, repeats=7):
    q, v = mech.q0, mech.v0 + 0.1
    u = np.ones(len(mech.input_names)) if mech.input_names else None
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            a, _ = mech.accelerations(0.1, q, v, u)
            if len(mech.z0):
                mech.state_rates(q, v, mech.z0, a)
        best = min(best, (time.perf_counter() - t0) / calls)
    return best


def main():
    print(f"{'scene':26s} oracle ms/call")
    for rel in SCENES:
        print(f"{Path(rel).stem:26s} {per_call(inerter.load(ROOT / rel).oracle().mechanism) * 1e3:8.3f}")


if __name__ == "__main__":
    main()
