"""How the cost grows with the length of a chain: N = 2, 8, 32, 128 links (benchmarks/chain_scene.py).

    python benchmarks/chain_scaling.py [--out docs/benchmarks] [--links 2,8,32,128]

CPU time per simulated second on the compiled path (RK4 with a fixed 1 ms step: the evaluation
cost alone; DOP853 at rtol 1e-8: including how the step size changes with N) and on the numpy
path (RK4, 1 ms, over a shorter span, scaled to one second), with the growth exponent fitted on
log-log between successive N. Target: compiled time per simulated second grows no faster than N^1.3.
"""
from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

import inerter  # noqa: E402
from inerter import compiled  # noqa: E402
from inerter.simulation import integrate  # noqa: E402
from chain_scene import write_chain  # noqa: E402


def per_second(fn, span, repeats=3):
    best = math.inf
    run = None
    for _ in range(repeats):
        run = fn()
        best = min(best, run.cpu_time)
        if best > 1.0:
            break
    if run.status != "ok":
        raise RuntimeError(run.message)
    return best / span, run


def exponent(ns, ts):
    return [math.log(ts[i + 1] / ts[i]) / math.log(ns[i + 1] / ns[i]) for i in range(len(ns) - 1)]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    p.add_argument("--links", default="2,8,32,128")
    p.add_argument("--numpy-budget", type=float, default=20.0, help="CPU s per numpy-path run, at most")
    a = p.parse_args(argv)
    if not compiled.AVAILABLE:
        raise SystemExit(f"the compiled path is not available: {compiled.WHY_NOT}")
    compiled.warm_up()
    links = [int(x) for x in a.links.split(",")]
    rows = []
    tmp = Path(tempfile.mkdtemp())
    for n in links:
        model = inerter.load(write_chain(tmp / f"chain_{n}.toml", n))
        mech = model.mechanism
        kernel = compiled.compile_mechanism(mech)
        kl, ku, N = kernel.band
        span = 1.0
        rk4, run4 = per_second(lambda: compiled.integrate_compiled(mech, model.settings(
            method="RK4", step=1e-3, stop_time=span, max_steps=10 ** 7)), span)
        dop, rund = per_second(lambda: compiled.integrate_compiled(mech, model.settings(
            method="DOP853", rtol=1e-8, atol=1e-10, stop_time=span, max_steps=10 ** 7)), span)
        # numpy path: one evaluation's cost sets the span so the run stays within the budget
        t0 = time.process_time()
        for _ in range(3):
            mech.accelerations(0.0, mech.q0, mech.v0)
        per_eval = (time.process_time() - t0) / 3
        np_span = min(1.0, max(0.005, a.numpy_budget / (4000 * per_eval * 1.2)))
        np_span = round(np_span / 1e-3) * 1e-3 or 1e-3
        npy, _ = per_second(lambda: integrate(mech, model.settings(method="RK4", step=1e-3, stop_time=np_span,
                                                                  max_steps=10 ** 7)), np_span, repeats=1)
        rows.append(dict(N=n, unknowns=N, band=f"{kl}+{ku}", rk4=rk4, rk4_eval=rk4 * span / run4.evaluations,
                         dop=dop, dop_steps=rund.steps, numpy=npy, numpy_span=np_span))
        print(rows[-1], flush=True)
    ns = [r["N"] for r in rows]
    e_rk4 = exponent(ns, [r["rk4"] for r in rows])
    e_dop = exponent(ns, [r["dop"] for r in rows])
    e_np = exponent(ns, [r["numpy"] for r in rows])
    overall = lambda key: math.log(rows[-1][key] / rows[0][key]) / math.log(ns[-1] / ns[0])  # noqa: E731
    lines = ["# Chain scaling", "",
             f"`python benchmarks/chain_scaling.py`, {time.strftime('%Y-%m-%d')}, one run. N-link planar chain "
             "(benchmarks/chain_scene.py: pins, rotational spring + damper at every pin, spring + damper + "
             "inerter between neighbouring midpoints, sine force at the tip). CPU seconds per simulated second.",
             "", "| N links | unknowns n+m | band kl+ku | compiled RK4 1 ms | per evaluation (µs) | compiled DOP853 "
             "rtol 1e-8 (steps/s) | numpy RK4 1 ms (span) |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['N']} | {r['unknowns']} | {r['band']} | {r['rk4']:.4f} | {r['rk4_eval'] * 1e6:.2f} | "
                     f"{r['dop']:.4f} ({r['dop_steps']}) | {r['numpy']:.2f} ({r['numpy_span']:g} s) |")
    fmt = lambda es: ", ".join(f"{x:.2f}" for x in es)  # noqa: E731
    lines += ["", "Growth exponents between successive N (time ∝ N^e):", "",
              f"* compiled RK4 (fixed step, evaluation cost): {fmt(e_rk4)}; {ns[0]}→{ns[-1]}: {overall('rk4'):.2f}",
              f"* compiled DOP853 (adaptive): {fmt(e_dop)}; {ns[0]}→{ns[-1]}: {overall('dop'):.2f}",
              f"* numpy path RK4: {fmt(e_np)}; {ns[0]}→{ns[-1]}: {overall('numpy'):.2f}", "",
              f"Target ≤ N^1.3 for the compiled path: fixed step {'met' if max(e_rk4) <= 1.3 else 'NOT met'} "
              f"(largest {max(e_rk4):.2f}); adaptive {'met' if max(e_dop) <= 1.3 else 'NOT met'} "
              f"(largest {max(e_dop):.2f})."]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "chain_scaling.md").write_text("\n".join(lines) + "\n")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        ax.loglog(ns, [r["rk4"] for r in rows], "o-", label="compiled RK4 1 ms")
        ax.loglog(ns, [r["dop"] for r in rows], "s-", label="compiled DOP853 rtol 1e-8")
        ax.loglog(ns, [r["numpy"] for r in rows], "^--", label="numpy RK4 1 ms")
        ref = rows[0]["rk4"]
        ax.loglog(ns, [ref * (x / ns[0]) ** 1.3 for x in ns], ":", color="0.5", label="∝ N^1.3")
        ax.set_xlabel("links N")
        ax.set_ylabel("CPU s per simulated s")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(out / "chain_scaling.png", dpi=120)
        plt.close(fig)
    except ImportError:
        pass
    print("\n".join(lines))


if __name__ == "__main__":
    main()
