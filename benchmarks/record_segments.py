"""What restarting the integrator at a ground record's samples buys.

    python benchmarks/record_segments.py [--scene scenarios/braced_frame_3d.toml] [--stop-time 3]

A ground acceleration record is interpolated linearly, so the right-hand side's slope jumps at
every sample. The solver restarts its integrator there (``Mechanism.discontinuities``, as at a step
force's switching time), so that every step integrates a smooth right-hand side. This script runs
the same scene side by side with those restarts and without them (the record's samples taken out
of ``discontinuities``, the integrator stepping across them under its error control), at several
tolerances, and compares both with the oracle (with restarts, rtol 1e-12, atol 1e-14). Error: max
|P.r[i] − oracle| over every point coordinate and every output sample. CPU: process time of the
integration. Writes docs/benchmarks/record_segments.md.
"""
from __future__ import annotations

import argparse
import datetime
from pathlib import Path

import numpy as np

import inerter

ROOT = Path(__file__).resolve().parents[1]
RTOLS = (1e-6, 1e-8, 1e-10)


def run(model, restarts: bool, **kw):
    if not restarts:
        record_times = set(float(t) for t in model.mechanism.ground_motion.record[0])
        model.mechanism.discontinuities = [t for t in model.mechanism.discontinuities if t not in record_times]
    return model.simulate(metrics=False, **kw)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default=str(ROOT / "scenarios" / "braced_frame_3d.toml"))
    p.add_argument("--stop-time", type=float, default=3.0)
    a = p.parse_args(argv)
    base = inerter.load(a.scene)
    if base.mechanism.ground_motion is None or base.mechanism.ground_motion.record is None:
        raise SystemExit(f"{a.scene}: the scene has no ground acceleration record")
    ref = run(base.oracle(), True, stop_time=a.stop_time, rtol=inerter.api.ORACLE_RTOL,
              atol=inerter.api.ORACLE_ATOL)
    names = [n for n in ref.names if ".r[" in n]
    print(f"oracle: {ref.run.steps} steps, {ref.run.cpu_time:.2f} s")
    rows = []
    for rtol in RTOLS:
        pair = {}
        for restarts in (True, False):
            r = run(inerter.load(a.scene), restarts, stop_time=a.stop_time, rtol=rtol)
            assert r.status == "ok", r.message
            err = max(float(np.max(np.abs(r[n] - ref[n]))) for n in names)
            pair[restarts] = (r.run.steps, r.run.evaluations, r.run.cpu_time, err)
        rows.append((rtol, pair))
        print(rtol, pair, flush=True)
    head = ("| rtol | restarts at samples: steps | evaluations | CPU (s) | error (m) | across samples: steps "
            "| evaluations | CPU (s) | error (m) | CPU across ÷ CPU with restarts |\n"
            "|---|---|---|---|---|---|---|---|---|---|\n")
    body = "".join(f"| {rtol:g} | {w[0]} | {w[1]} | {w[2]:.2f} | {w[3]:.2g} | {o[0]} | {o[1]} | {o[2]:.2f} "
                   f"| {o[3]:.2g} | {o[2] / w[2]:.1f} |\n" for rtol, (w, o) in ((r, (p[True], p[False]))
                                                                          for r, p in rows))
    scene = Path(a.scene).stem
    text = (f"# Restarts at a ground record's samples\n\n`python benchmarks/record_segments.py`, "
            f"{datetime.date.today()}, one run. {scene}, 0-{a.stop_time:g} s, numpy path, DOP853 (the "
            f"scene's method), atol as the scene states. Error: max |P.r[i] − oracle| over every point "
            f"coordinate and output sample; oracle with restarts at rtol 1e-12 ({ref.run.steps} steps, "
            f"{ref.run.cpu_time:.1f} s). CPU: process time of the integration.\n\n" + head + body)
    print(text)
    out = ROOT / "docs" / "benchmarks" / "record_segments.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text)


if __name__ == "__main__":
    main()
