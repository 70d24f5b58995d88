"""A 1-DOF oscillator with an inerter device's Coulomb friction against the closed form, as the
friction's velocity scale v_s shrinks: the error and the integrator's steps.

    python benchmarks/coulomb_convergence.py [--out docs/benchmarks]

The scene is tests/test_device.py's: m = b = 1 kg, k = 100 N/m, F_c = 2 N, released from
x0 = 0.25 m, 4 s. The closed form (tests/test_device._coulomb_closed_form): half cycles about
±F_c/k, 4F_c/k = 0.08 m lost per cycle, at rest at 0.01 m (inside |x| ≤ F_c/k) from 2.67 s.
Radau (implicit) at rtol 1e-10 and 1e-12, DOP853 at 1e-10 (it stops where its stiffness test
fires: a sticking phase has the eigenvalue −F_c/((m + b) v_s)).
"""
from __future__ import annotations

import argparse
import datetime
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import inerter  # noqa: E402
from test_device import OSCILLATOR, _coulomb_closed_form  # noqa: E402

SCALES = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
RUNS = (("Radau", 1e-10), ("Radau", 1e-12), ("DOP853", 1e-10))


def scene(folder: Path) -> Path:
    text = OSCILLATOR.replace('[parameters]\n', '[parameters]\nFc = 2.0\nvs = 1e-3\n') + \
        '\n[elements.inerter.device.friction]\ncoulomb = "Fc"\nvelocity_scale = "vs"\n' \
        '\n[experiment]\nstop_time = 4.0\noutput_interval = 0.001\n'
    path = folder / "coulomb_1dof.toml"
    path.write_text(text, encoding="utf-8")
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    args = ap.parse_args(argv)
    path = scene(Path(tempfile.mkdtemp()))
    rows = []
    for method, rtol in RUNS:
        for vs in SCALES:
            model = inerter.load(path, vs=vs)
            t0 = time.perf_counter()
            r = model.simulate(method=method, rtol=rtol, atol=rtol * 1e-2, metrics=False)
            wall = time.perf_counter() - t0
            x = r["P.r[1]"]
            exact, rest, _, _ = _coulomb_closed_form(r.time, 0.25, 2.0, 100.0, 2.0)
            err = float(np.max(np.abs(x - exact)))
            status = "ok" if r.run.status == "ok" else f"stopped at {r.time[-1]:.3f} s (stiff)"
            rows.append((vs, method, rtol, status, r.run.steps, r.run.evaluations, err, err / vs, x[-1],
                         wall))
            print(f"v_s {vs:g} {method} rtol {rtol:g}: {status}, {r.run.steps} steps, error {err:.3e} m "
                  f"({err / vs:.3f} s·v_s), final x {x[-1]:.6f} m, {wall:.2f} s")
    lines = [
        "# Coulomb friction: convergence as the velocity scale shrinks", "",
        f"`python benchmarks/coulomb_convergence.py`, {datetime.date.today().isoformat()}. A mass (m = 1 kg) "
        "with an inerter device (b = 1 kg) and a spring (k = 100 N/m) on the X axis; the device's friction F_c tanh(L̇/v_s), "
        "F_c = 2 N; released from 0.25 m, 4 s. Error: max over the samples (1 ms) of |x − x_exact|, x_exact the "
        "closed form of M ẍ + k x + F_c sgn ẋ = 0 (turning points 0.25, −0.21, 0.17, −0.13, 0.09, −0.05 m; at rest "
        "at 0.01 m, inside the dead band |x| ≤ F_c/k = 0.02 m, from 2.67 s).", "",
        "| v_s (m/s) | method | rtol | status | steps | evaluations | error (m) | error / v_s (s) | final x (m) "
        "| wall (s) |",
        "|---|---|---|---|---|---|---|---|---|---|"]
    for vs, method, rtol, status, steps, evals, err, ratio, xf, wall in rows:
        lines.append(f"| {vs:g} | {method} | {rtol:g} | {status} | {steps} | {evals} | {err:.3e} | {ratio:.3f} | "
                     f"{xf:.7f} | {wall:.2f} |")
    lines += ["", "The error is first order in v_s: once stuck at x_s the regularised law lets the mass creep as an "
              "overdamped oscillator of damping F_c/v_s, x_s e^{−k v_s (t − t_s)/F_c}, which by 4 s is off by "
              "x_s k v_s (4 s − t_s)/F_c = 0.67 s·v_s, plus the transitions at the turning points. Radau's steps do "
              "not grow as v_s shrinks (they fall: the sticking phase is one stiff, smooth decay). DOP853 stops "
              "with the stiffness message once the sticking phase's eigenvalue −F_c/((m + b) v_s) leaves its "
              "stability region (v_s ≤ 1e-4 m/s here); its error up to there is small, but it cannot go on."]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "coulomb_convergence.md").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"wrote {out / 'coulomb_convergence.md'}")


if __name__ == "__main__":
    main()
