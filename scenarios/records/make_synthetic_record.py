"""Writes synthetic_bidirectional.csv: a synthetic two-component ground acceleration (not a
recorded earthquake): sums of sines under a build-up / strong-motion / decay envelope; and
synthetic_x.csv, its X component alone for planar scenes (time, a_x, a_y = 0).

    python scenarios/records/make_synthetic_record.py
"""
from pathlib import Path

import numpy as np

t = np.arange(0.0, 15.0 + 1e-9, 0.01)
env = np.where(t < 2.0, (t / 2.0) ** 2, np.where(t < 6.0, 1.0, np.exp(-(t - 6.0) / 2.0)))
ax = env * (3.0 * np.sin(2 * np.pi * 1.2 * t) + 1.5 * np.sin(2 * np.pi * 2.7 * t + 0.4)
            + 0.8 * np.sin(2 * np.pi * 4.1 * t + 1.3))
ay = env * (2.5 * np.sin(2 * np.pi * 1.0 * t + 1.0) + 1.8 * np.sin(2 * np.pi * 2.2 * t + 2.1)
            + 0.6 * np.sin(2 * np.pi * 3.6 * t + 0.2))
out = Path(__file__).with_name("synthetic_bidirectional.csv")
np.savetxt(out, np.column_stack((t, ax, ay, np.zeros_like(t))), delimiter=",", fmt="%.6f",
           header="time (s), a_x (m/s2), a_y (m/s2), a_z (m/s2): synthetic, not a recorded earthquake")
print(f"wrote {out} ({len(t)} rows)")
planar = Path(__file__).with_name("synthetic_x.csv")
np.savetxt(planar, np.column_stack((t, ax, np.zeros_like(t))), delimiter=",", fmt="%.6f",
           header="time (s), a_x (m/s2), a_y (m/s2): the X component of synthetic_bidirectional.csv, "
                  "synthetic, not a recorded earthquake")
print(f"wrote {planar} ({len(t)} rows)")
