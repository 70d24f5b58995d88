"""Whether a change to the joints' rows keeps the results: compiled runs and the numpy Mechanism's
joint rows on scenes with every joint kind, of two source trees, compared.

    git archive 82948a8 | (mkdir -p /tmp/inerter-base-joints && tar -x -C /tmp/inerter-base-joints)
    PYTHONPATH=/tmp/inerter-base-joints python benchmarks/joint_rows_identity.py snap /tmp/before.npz
    PYTHONPATH=. python benchmarks/joint_rows_identity.py snap /tmp/after.npz
    python benchmarks/joint_rows_identity.py compare /tmp/before.npz /tmp/after.npz

`snap ... --dense` also keeps every output on the dense output between the first samples and,
for a scene with metrics, the metrics of a whole run (which read the dense output); `compare`
counts them among the outputs.

`snap` (with the tree under test first on PYTHONPATH) runs every scene of scenarios/,
scenarios/hard/ and tests/data/ and seven 3D scenes of the joint tests (cylindrical, planar,
universal, revolute about a tilted axis, prismatic, fixed, a shaken prismatic slider) on the
compiled path, to min(stop_time, 1 s), and keeps the samples' times, every output and the states;
and evaluates ``Mechanism.constraints(q, v)`` (C, C_v, γ) at three random states of each scene
with joints (q0 + 0.3 N(0, 1), v ~ N(0, 1), seeded by 7 and the scene's name). `compare` prints,
per scene, whether the runs are bit-identical (where only outputs differ: the largest
difference, relative to max(1, |before|), and its column) and the largest difference of the numpy
rows, relative to max(1, |before|).
"""
from __future__ import annotations

import glob
import os
import sys
import tempfile
import zlib

import numpy as np


def _scenes(root):
    """(key, path) of every scene compared."""
    sys.path.insert(0, os.path.join(root, "tests"))
    import test_3d_joints as t3d
    import test_joints_more as tjm
    files = sorted(glob.glob(f"{root}/scenarios/*.toml") + glob.glob(f"{root}/scenarios/hard/*.toml")
                   + glob.glob(f"{root}/tests/data/*.toml"))
    out = [(os.path.relpath(f, root), f) for f in files]
    tilted = '[joints.R]\ntype = "revolute"\nbetween = ["O", "T"]\naxis = [0.6, 0.8, 0]\n'
    extra = {"cylindrical": tjm.HEAD.format(name="cyl", dim=3) + tjm.CYLINDRICAL,
             "planar": tjm.HEAD.format(name="pl", dim=3) + tjm.PLANAR,
             "universal": tjm.HEAD.format(name="u", dim=3)
             + tjm._turned(tjm._pendulum(tjm._universal(0.6), (0.6, 0.4)), 0.6, 0.4),
             "revolute3": tjm.HEAD.format(name="r", dim=3) + tjm._turned(tjm._pendulum(tilted, (0.6, 0.4)), 0.6, 0.4),
             "slider3": t3d.SLIDER, "welded3": t3d.WELDED, "shaken3": t3d.SHAKEN}
    tmp = tempfile.mkdtemp()
    for key, text in extra.items():
        path = os.path.join(tmp, f"{key}.toml")
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text)
        out.append((f"{key}.toml", path))
    return out


def snap(out_path):
    import inerter
    root = os.path.dirname(os.path.dirname(os.path.abspath(inerter.__file__)))
    out = {}
    for key, path in _scenes(root):
        model = inerter.load(path)
        mech = model.mechanism
        # seeded by the scene's name, so that a scene added or removed does not move the others' states
        rng = np.random.default_rng([7, zlib.crc32(key.encode())])
        for i in range(3):
            q = mech.q0 + 0.3 * rng.standard_normal(mech.q0.shape)
            v = rng.standard_normal(mech.n)
            if mech.joints:
                for name, x in zip(("C", "Cv", "g"), mech.constraints(q, v)):
                    out[f"{key}|np{i}|{name}"] = x
        r = model.simulate(stop_time=min(model.scene.experiment.stop_time, 1.0), metrics=False)
        out[f"{key}|t"], out[f"{key}|y"], out[f"{key}|states"] = r.time, r._all_values(), r.run.states
        if "--dense" in sys.argv:
            _snap_dense(model, r, key, out)
        print(key, r.status, r.run.extra.get("path"), len(r.time), flush=True)
    np.savez(out_path, **out)


def _snap_dense(model, r, key, out):
    """`--dense`: every output on the run's dense output halfway between its first 30 samples
    (Result.dense), and a run of the whole scene with its metrics (which read the dense output)."""
    mid = 0.5 * (r.time[:30][1:] + r.time[:30][:-1])
    out[f"{key}|dense"] = np.array([r.dense(name)(mid) for name in r.names])
    if model.scene.metrics:
        full = model.simulate()
        values = [np.ravel(np.asarray(full.metrics[m], dtype=float)) for m in sorted(full.metrics)]
        out[f"{key}|metrics"] = np.concatenate(values) if values else np.zeros(0)


def compare(path_a, path_b):
    a, b = np.load(path_a), np.load(path_b)
    keys = sorted({k.split("|")[0] for k in a.files})
    same = states_same = 0
    for key in keys:
        states = all(np.array_equal(a[f"{key}|{s}"], b[f"{key}|{s}"], equal_nan=True) for s in ("t", "states"))
        outputs = np.array_equal(a[f"{key}|y"], b[f"{key}|y"], equal_nan=True)
        states_same += states
        rows = [np.max(np.abs(a[k] - b[k])) / max(1.0, np.max(np.abs(a[k]))) for k in a.files
                if k.startswith(f"{key}|np") and a[k].size]
        numpy = f"{max(rows):.1e}" if rows else "no joints"
        extras = [extra for extra in ("dense", "metrics")      # snap --dense
                  if (f"{key}|{extra}" in a.files or f"{key}|{extra}" in b.files)
                  and not (f"{key}|{extra}" in a.files and f"{key}|{extra}" in b.files
                           and np.array_equal(a[f"{key}|{extra}"], b[f"{key}|{extra}"], equal_nan=True))]
        same += states and outputs and not extras
        run = "bit-identical" if states and outputs and not extras else "DIFFERS"
        if extras:
            run = f"{run}: {' and '.join(extras)} differ"
        if states and not outputs and not extras and a[f"{key}|y"].shape == b[f"{key}|y"].shape:
            # the states the same, some outputs not: the largest difference, relative to
            # max(1, |before|) of its column, and the column (its index in Result.names)
            ya, yb = a[f"{key}|y"], b[f"{key}|y"]
            rel = np.nanmax(np.abs(ya - yb), axis=0) / np.maximum(1.0, np.nanmax(np.abs(ya), axis=0))
            run = f"states same, outputs {np.max(rel):.1e} (column {int(np.argmax(rel))})"
        print(f"{key:50s} run {run:40s} numpy rows {numpy}")
    print(f"{same}/{len(keys)} runs bit-identical (times, every output, states); "
          f"{states_same}/{len(keys)} in times and states")


if __name__ == "__main__":
    if sys.argv[1] == "snap":
        snap(sys.argv[2])
    else:
        compare(sys.argv[2], sys.argv[3])
