"""A 1-DOF oscillator with a screw-efficiency inerter against its closed form: the error and how
the integrator's error control meets the force's jump at each turnaround, exact or regularised.

    python benchmarks/efficiency_steps.py [--out docs/benchmarks]

The scene is tests/test_device_efficiency.py's: m = b = 1 kg, k = 100 N/m, released from
x0 = 0.25 m, 3 s. With η_f = η_b = 1 the inerter is ideal (harmonic at √(k/(m + b))). With
η_f = 0.8, η_b = 0.6 (the closed form, tests/test_device_efficiency.efficiency_closed_form) the
effective mass is m + b/η_f while |x| falls and m + b η_b while it grows: q̈ is continuous where x
crosses 0 (L̈ = 0 there) and jumps at every peak (L̇ = 0: b η_b → b/η_f), 6 times in 3 s. DOP853
has no event there: its error control rejects and shortens the steps that straddle a jump. With
the regularisation's velocity scale v_s > 0 (``device.efficiency.velocity_scale``, given here as a
fraction of the first quarter's peak speed ω₁ x0 = 1.667 m/s) b_eff is smooth in L̇ and changes over
a time ~ v_s/|L̈| about each peak. The table gives the steps and evaluations (those rejected
included), the smallest step within 0.02 s of a peak against the median step, and the largest
error against the exact switch's closed form.
"""
from __future__ import annotations

import argparse
import datetime
import math
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import inerter  # noqa: E402
from test_device import OSCILLATOR, _with_device  # noqa: E402
from test_device_efficiency import efficiency_closed_form  # noqa: E402

CASES = ((1.0, 1.0), (0.8, 0.6), (0.5, 0.5))
RTOLS = (1e-8, 1e-10, 1e-12)
#: η_f = 0.8, η_b = 0.6 regularised: v_s as a fraction of the peak speed ω₁ x0
PEAK_SPEED = 0.25 * math.sqrt(100.0 / (1.0 + 1.0 / 0.8))
SCALES = (1e-2, 1e-3, 1e-4)


def scene(folder: Path) -> Path:
    text = _with_device(OSCILLATOR.replace("[parameters]\n", "[parameters]\netaf = 0.8\netab = 0.6\nvs = 0.0\n"),
                        '[DEVICE.efficiency]\nforward = "etaf"\nbackward = "etab"\nvelocity_scale = "vs"\n')
    text += ('\n[experiment]\nstop_time = 3.0\noutput_interval = 0.001\n'
             '\n[[metrics]]\nkind = "peak"\nsignal = "P.r[1]"\nreference = 0.0\n')   # keeps the dense output
    path = folder / "efficiency_1dof.toml"
    path.write_text(text, encoding="utf-8")
    return path


def measure(path: Path, etaf: float, etab: float, rtol: float, scale: float = 0.0) -> dict:
    """One run at v_s = scale · PEAK_SPEED (0: the exact switch)."""
    r = inerter.load(path, etaf=etaf, etab=etab, vs=scale * PEAK_SPEED).simulate(method="DOP853", rtol=rtol,
                                                                              atol=rtol * 1e-2)
    assert r.status == "ok", r.message
    exact, peaks, _, _ = efficiency_closed_form(r.time, 0.25, 1.0, 1.0, 100.0, etaf, etab)
    ts = np.asarray(r.run.dense.ts)
    h = np.diff(ts)
    near = np.zeros(len(h), dtype=bool)
    for tn, _ in peaks:
        near |= (ts[1:] > tn - 0.02) & (ts[:-1] < tn + 0.02)
    return dict(etaf=etaf, etab=etab, scale=scale, rtol=rtol, steps=r.run.steps, evaluations=r.run.evaluations,
                near=int(near.sum()), h_near=float(h[near].min()), h_median=float(np.median(h)),
                error=float(np.max(np.abs(r["P.r[1]"] - exact))),
                unsettled=r.run.extra["kernel"].unsettled)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, help="write efficiency_steps.md there")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = scene(Path(tmp))
        rows = [measure(path, f, b, rtol) for f, b in CASES for rtol in RTOLS]
        rows += [measure(path, 0.8, 0.6, rtol, scale) for scale in SCALES for rtol in RTOLS]
    lines = [f"# Screw efficiency: steps at the turnarounds ({datetime.date.today().isoformat()})", "",
             "`python benchmarks/efficiency_steps.py --out docs/benchmarks` (DOP853, atol = rtol·1e-2, 3 s, "
             "6 turnarounds; error: max |x − closed form| over the 1 ms samples)", "",
             "| η_f | η_b | v_s / (ω₁ x0) | rtol | steps | evaluations | steps within 0.02 s of a peak | "
             "smallest there (s) | median step (s) | smallest / median | max error (m) | unsettled calls |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    notes = ["", "With η < 1 the acceleration jumps at each peak (L̇ = 0: b η_b → b/η_f). DOP853 meets each jump by "
             "its error control: it rejects the steps that straddle it and shrinks them (the smallest step near a "
             "peak column) until the jump lies in one it accepts, then grows them again; most of the run's steps "
             "are those near the peaks, and the error stays at the tolerance, as in the ideal rows. No event is "
             "needed: the state stays continuous. Where x crosses 0, L̈ changes sign at L̇ ≠ 0 and the force is "
             "continuous. Every call settled its mode (one efficiency element: at most two solves).",
             "", "With `velocity_scale` v_s > 0 (the rows with v_s / (ω₁ x0) > 0) b_eff changes smoothly over "
             "|L̇| ≲ v_s, a time ~ v_s/|L̈| about each peak (0.15 s · v_s/(ω₁ x0) at the first): the steps there shrink to "
             "resolve it, in proportion to v_s at most, not to the round-off of the jump (smallest / median ≥ 1e-2 "
             "in every such row, where the exact switch's is 3.5e-9 ... 7.6e-6). The run takes about as many steps "
             "as the exact switch's (177-205 against 238 at rtol 1e-8, 454-472 against 434 at 1e-12: the smoothed "
             "change still has to be followed), with fewer evaluations (fewer steps rejected), and its error is the regularisation's own, the same at every rtol and tenfold "
             "smaller for each tenfold smaller v_s: first order, ≈ 0.037 s · v_s "
             "(tests/test_device_efficiency.py checks the order). Where x crosses 0 the sign of L̈, and with it "
             "b_eff, flips at L̇ ≠ 0 in both models: q̈ is continuous, its rate is not."]
    for w in rows:
        lines.append(f"| {w['etaf']:g} | {w['etab']:g} | {w['scale']:g} | {w['rtol']:g} | {w['steps']} | "
                     f"{w['evaluations']} | {w['near']} | {w['h_near']:.2e} | {w['h_median']:.2e} | "
                     f"{w['h_near'] / w['h_median']:.1e} | {w['error']:.1e} | {w['unsettled']} |")
    text = "\n".join(lines + notes) + "\n"
    print(text)
    if args.out:
        (args.out / "efficiency_steps.md").write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
