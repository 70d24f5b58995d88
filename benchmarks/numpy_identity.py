"""Whether a change to the laws the numpy Mechanism shares with the kernels keeps its results, and
what it costs: ``Mechanism.accelerations``, ``energy`` and every element's outputs at random states
of every scene of benchmarks/joint_rows_identity.py, of two source trees, compared; and the time per
``Mechanism.accelerations`` call on three scenes.

    git archive BASE | (mkdir -p /tmp/inerter-base && tar -x -C /tmp/inerter-base)
    PYTHONPATH=/tmp/inerter-base python benchmarks/numpy_identity.py snap /tmp/np_before.npz
    PYTHONPATH=. python benchmarks/numpy_identity.py snap /tmp/np_after.npz
    python benchmarks/numpy_identity.py compare /tmp/np_before.npz /tmp/np_after.npz
    PYTHONPATH=. python benchmarks/numpy_identity.py time

`snap` evaluates, at three states per scene (q0 + 0.3 N(0, 1), v ~ N(0, 1), inputs ~ N(0, 1),
t = 0.1, seed 11), v̇ and λ, the energy and the outputs of every element. `compare` prints per
scene the largest difference relative to max(1, |before|) of v̇ and λ (a), the energy (E) and
the elements' outputs (y). `time`: µs per
``Mechanism.accelerations(0.1, q0, v0 + 0.1)``, best of 5 × 200 calls.
"""
from __future__ import annotations

import os
import sys
import timeit

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from joint_rows_identity import _scenes  # noqa: E402


def snap(out_path):
    import inerter
    root = os.path.dirname(os.path.dirname(os.path.abspath(inerter.__file__)))
    out = {}
    rng = np.random.default_rng(11)
    for key, path in _scenes(root):
        mech = inerter.load(path).mechanism
        for i in range(3):
            q = mech.q0 + 0.3 * rng.standard_normal(mech.q0.shape)
            q = mech.normalise(q)
            v = rng.standard_normal(mech.n)
            inputs = rng.standard_normal(len(mech.input_names))
            a, lam = mech.accelerations(0.1, q, v, inputs)
            out[f"{key}|{i}|a"] = np.concatenate((a, lam))
            out[f"{key}|{i}|E"] = np.array([mech.energy(q, v)])
            outs = [np.asarray(e.outputs(q, v, a), dtype=float).ravel() for e in mech.elements]
            out[f"{key}|{i}|y"] = np.concatenate(outs) if outs else np.zeros(0)
        print(key, flush=True)
    np.savez(out_path, **out)


def compare(path_a, path_b):
    a, b = np.load(path_a), np.load(path_b)
    parts = ("a", "E", "y")                 # v̇ and λ, the energy, the elements' outputs
    worst = dict.fromkeys(parts, 0.0)
    print(f"{'scene':50s} " + " ".join(f"{p:>8s}" for p in parts))
    for key in sorted({k.split("|")[0] for k in a.files}):
        line = []
        for part in parts:
            rows = [np.max(np.abs(a[k] - b[k])) / max(1.0, np.max(np.abs(a[k]))) for k in a.files
                    if k.startswith(f"{key}|") and k.endswith(f"|{part}") and a[k].size]
            d = max(rows) if rows else 0.0
            worst[part] = max(worst[part], d)
            line.append(f"{d:8.1e}")
        print(f"{key:50s} " + " ".join(line))
    print("largest: " + ", ".join(f"{p} {worst[p]:.1e}" for p in parts))


def time_calls():
    import inerter
    root = os.path.dirname(os.path.dirname(os.path.abspath(inerter.__file__)))
    for name in ("two_bar_2d", "braced_frame_3d", "double_pendulum_3d"):
        m = inerter.load(f"{root}/scenarios/{name}.toml").mechanism
        q, v = m.q0, m.v0 + 0.1
        best = min(timeit.repeat(lambda: m.accelerations(0.1, q, v), number=200, repeat=5)) / 200
        print(f"{name:20s} {best * 1e6:.1f} us")


if __name__ == "__main__":
    if sys.argv[1] == "snap":
        snap(sys.argv[2])
    elif sys.argv[1] == "compare":
        compare(sys.argv[2], sys.argv[3])
    else:
        time_calls()
