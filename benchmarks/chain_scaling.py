"""How the cost grows with the length of a chain, N = 2, 8, 32, 128 links (benchmarks/chain_scene.py),
and how it compares with MuJoCo on the same chain (benchmarks/chain_mujoco.py), all measured in one run.

    flock /tmp/inerter-bench.lock python benchmarks/chain_scaling.py [--out docs/benchmarks] [--links 2,8,32,128]

(`flock` keeps timing runs on a shared machine from overlapping.)

Scaling: CPU time per simulated second (process time, the best of --rounds round-robin rounds over
every N, see interleaved_timings) on the compiled path (RK4 with a fixed 1 ms step: the evaluation
cost alone; DOP853 at rtol 1e-8: including how the step size changes with N), on the numpy path
(RK4, 1 ms, over a shorter span, scaled to one second) and in MuJoCo (RK4, 1 ms, the tip force
applied at every stage), with the growth exponent fitted on log-log between successive N. MuJoCo's
cost per step is also given without the forcing callback (from an initial velocity), and each N
uses the faster of MuJoCo's dense and sparse Jacobians. Target: compiled time per simulated
second grows no faster than N^1.3.

Matched accuracy: reference = compiled DOP853 at rtol 1e-12, atol 1e-14 over 0-2 s (--span);
error = max over the 10 ms samples of |tip position − reference| (m, the free end P_Nb). Sweeps:
MuJoCo RK4, compiled RK4 and, for completeness, MuJoCo's default semi-implicit Euler over the steps
in STEPS, compiled DOP853 over RTOLS (atol = rtol/100);
a sweep goes no finer once its error is below 1e-11 m or a run costs more than --budget CPU s.
Steps that do not divide 10 ms are scored on the 10 ms samples they land on (MuJoCo) or on every
sample (compiled RK4, cubic Hermite between steps). For each accuracy level the cheapest run
reaching it is reported (no interpolation). Before the sweeps, MuJoCo at a 0.1 ms step is checked
against the reference on N ≤ 8 (the two models are the same physics).

Writes docs/benchmarks/chain_scaling.{md,csv,png} and chain_work_precision.{csv,png} (the
diagram at the largest N).
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

from inerter import api
import inerter  # noqa: E402
from inerter.engine import compiled  # noqa: E402
from inerter.engine.simulation import integrate  # noqa: E402
from chain_scene import write_chain  # noqa: E402

STEPS = [2e-2, 1.75e-2, 1.5e-2, 1.25e-2, 1e-2, 5e-3, 2.5e-3, 1e-3, 5e-4, 2.5e-4]
RTOLS = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11]
LEVELS = [1e-4, 1e-6, 1e-8, 1e-10]
FLOOR = 1e-11
INTERVAL = 0.01
SERIES = ("MuJoCo RK4", "MuJoCo Euler", "compiled RK4", "compiled DOP853")
MUJOCO = ("MuJoCo RK4", "MuJoCo Euler")
COMPILED = ("compiled RK4", "compiled DOP853")


def best_of(fn, cpu_of, repeats=3, below=3.0):
    """Run fn(); repeat runs under `below` CPU s and keep the smallest CPU time. (result, cpu)."""
    out = fn()
    cpu = cpu_of(out)
    for _ in range(repeats - 1):
        if cpu >= below:
            break
        cpu = min(cpu, cpu_of(fn()))
    return out, cpu


def exponent(ns, ts):
    return [math.log(ts[i + 1] / ts[i]) / math.log(ns[i + 1] / ns[i]) for i in range(len(ns) - 1)]


def run_compiled(model, **kw):
    s = model.settings(output_interval=INTERVAL, **kw)
    s.max_steps = max(s.max_steps, 10 ** 7)
    return compiled.integrate_compiled(model.mechanism, s)


def interleaved_timings(models, mjs, rounds, log):
    """CPU time per simulated second of the compiled RK4 (1 ms) and DOP853 (rtol 1e-8) runs and of
    MuJoCo RK4 (1 ms), over 1 s, for every N, measured in `rounds` round-robin rounds (every N once
    per round; a MuJoCo run that costs 3 CPU s or more only in the first): the machine's slow and fast
    spells then fall on every N alike, and the growth exponents compare runs taken side by side.
    Returns ({N: {key: best time}}, {N: the last runs}, {key: [per-round times per N]})."""
    span = 1.0
    keys = ("rk4", "dop") + (("mujoco",) if all(mj is not None for mj in mjs.values()) else ())
    best = {n: {} for n in models}
    runs = {n: {} for n in models}
    per_round = {k: [] for k in keys}
    for r in range(rounds):
        times = {k: {} for k in keys}
        for n, model in models.items():
            run4 = run_compiled(model, method="RK4", step=1e-3, stop_time=span)
            rund = run_compiled(model, method="DOP853", rtol=1e-8, atol=1e-10, stop_time=span)
            for x in (run4, rund):
                if x.status != "ok":
                    raise RuntimeError(x.message)
            times["rk4"][n], times["dop"][n] = run4.cpu_time / span, rund.cpu_time / span
            runs[n].update(rk4=run4, dop=rund)
            if "mujoco" in keys and best[n].get("mujoco", 0.0) * span < 3.0:
                _, _, cpu, steps = mjs[n].simulate(span, INTERVAL, 1e-3)
                times["mujoco"][n] = cpu / (steps * 1e-3)
        for k in keys:
            for n, t in times[k].items():
                best[n][k] = min(best[n].get(k, math.inf), t)
            per_round[k].append(times[k])
        log(f"round {r + 1}: " + "; ".join(f"{k} " + ", ".join(f"{n}: {t:.4g}" for n, t in times[k].items())
                                            for k in keys))
    return best, runs, per_round


def scaling_row(n, model, mj, best, runs, numpy_budget, log):
    mech = model.mechanism
    kernel = compiled.compile_mechanism(mech)
    kl, ku, N = kernel.band
    run4, rund = runs["rk4"], runs["dop"]
    # numpy path: one evaluation's cost sets the span so the run stays within the budget
    t0 = time.process_time()
    for _ in range(3):
        mech.accelerations(0.0, mech.q0, mech.v0)
    per_eval = (time.process_time() - t0) / 3
    np_span = min(1.0, max(0.005, numpy_budget / (4000 * per_eval * 1.2)))
    np_span = round(np_span / 1e-3) * 1e-3 or 1e-3
    npy = integrate(mech, model.settings(method="RK4", step=1e-3, stop_time=np_span, max_steps=10 ** 7)).cpu_time
    row = dict(N=n, unknowns=N, band=f"{kl}+{ku}", rk4=best["rk4"], rk4_eval=best["rk4"] / run4.evaluations,
               rk4_step=best["rk4"] / run4.steps, dop=best["dop"], dop_steps=rund.steps, numpy=npy / np_span,
               numpy_span=np_span)
    if mj is not None:
        per_step = best["mujoco"] * 1e-3
        row.update(mujoco=best["mujoco"], mujoco_step=per_step,
                   mujoco_bare=mj.step_cost(max(20, min(1000, int(0.3 / per_step))), forcing=False),
                   jacobian=mj.jacobian, jacobian_costs=mj.jacobian_costs)
    log(f"N = {n}: " + ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in row.items()))
    return row


def mujoco_chain(n):
    """The MuJoCo chain with the faster of the dense and sparse Jacobians (per-step cost, RK4 1 ms)."""
    from chain_mujoco import MujocoChain

    costs = {}
    for jac in ("dense", "sparse"):
        mj = MujocoChain(n, 1e-3, jac)
        probe = mj.step_cost(5)
        costs[jac] = mj.step_cost(max(20, min(2000, int(0.3 / probe))))
    jac = min(costs, key=costs.get)
    mj = MujocoChain(n, 1e-3, jac)
    mj.jacobian, mj.jacobian_costs = jac, costs
    return mj


def accuracy_sweep(n, model, mj, span, budget, log):
    """Reference, equivalence check and the three sweeps for one N: (points, notes)."""
    ref_run = run_compiled(model, method="DOP853", rtol=1e-12, atol=1e-14, stop_time=span)
    if ref_run.status != "ok":
        raise RuntimeError(ref_run.message)
    kernel = compiled._kernel_for(model.mechanism)
    tip_name = f"P{n}b"
    ref = kernel.point_positions(ref_run.states)[tip_name]
    travel = float(np.max(np.linalg.norm(ref - ref[0], axis=1)))
    points, notes = [], []

    def error(idx, tip):
        if idx[-1] >= len(ref) or not np.all(np.isfinite(tip)):
            return math.inf
        return float(np.max(np.linalg.norm(tip - ref[idx], axis=1)))

    def add(series, setting, err, cpu, simulated, steps, evaluations, samples):
        ok = math.isfinite(err)
        points.append(dict(N=n, series=series, setting=setting, error_m=err, cpu_per_s=cpu / simulated,
                           cpu_s=cpu, simulated_s=simulated, steps=steps, evaluations=evaluations,
                           samples=samples, status="ok" if ok else "unstable"))
        log(f"  N {n:4d} {series:16s} {setting:8.3g}  error {err:9.2e}  CPU/s {cpu / simulated:9.4f}"
            f"  steps {steps}")

    if mj is not None and n <= 8:
        idx, tip, _, _ = mj.simulate(span, INTERVAL, 1e-4)
        check = error(idx, tip)
        notes.append(f"N = {n}: MuJoCo RK4 at 0.1 ms vs the reference: max tip deviation {check:.2e} m over 0-{span:g} s "
                     f"(tip travel {travel:.3f} m)")
        log("  " + notes[-1])
        if not check < 1e-8:
            raise SystemExit(f"the MuJoCo chain disagrees with the compiled path by {check:.3g} m")
    notes.append(f"N = {n}: reference DOP853 rtol 1e-12 took {ref_run.steps} steps; tip travel {travel:.3g} m")

    def sweep_steps(series, run_one):
        for dt in STEPS:
            err, cpu, simulated, steps, evals, samples = run_one(dt)
            add(series, dt, err, cpu, simulated, steps, evals, samples)
            if (math.isfinite(err) and err < FLOOR) or cpu > budget:
                break

    if mj is not None:
        for integrator, stages in (("RK4", 4), ("Euler", 1)):
            def mujoco_one(dt):
                (idx, tip, _, steps), cpu = best_of(lambda: mj.simulate(span, INTERVAL, dt, integrator),
                                                    lambda r: r[2])
                return error(idx, tip), cpu, steps * dt, steps, stages * steps, len(idx)
            sweep_steps(f"MuJoCo {integrator}", mujoco_one)

    def compiled_one(dt):
        run, cpu = best_of(lambda: run_compiled(model, method="RK4", step=dt, stop_time=span), lambda r: r.cpu_time)
        if run.status != "ok":
            return math.inf, cpu, span, run.steps, run.evaluations, len(run.states)
        tip = kernel.point_positions(run.states)[tip_name]
        return error(np.arange(len(tip)), tip), cpu, span, run.steps, run.evaluations, len(tip)
    sweep_steps("compiled RK4", compiled_one)

    finest = [p for p in points if p["series"] == "MuJoCo RK4" and p["status"] == "ok"]
    if finest and n > 8:
        f = min(finest, key=lambda p: p["setting"])
        notes.append(f"N = {n}: MuJoCo RK4 at its finest step swept ({f['setting'] * 1e3:g} ms) is within "
                     f"{f['error_m']:.2e} m of the reference")

    for rtol in RTOLS:
        run, cpu = best_of(lambda: run_compiled(model, method="DOP853", rtol=rtol, atol=rtol * 1e-2, stop_time=span),
                           lambda r: r.cpu_time)
        err = math.inf
        if run.status == "ok":
            tip = kernel.point_positions(run.states)[tip_name]
            err = error(np.arange(len(tip)), tip)
        add("compiled DOP853", rtol, err, cpu, span, run.steps, run.evaluations, len(run.states))
        if (math.isfinite(err) and err < FLOOR) or cpu > budget:
            break
    return points, notes


def cheapest(points, n, series, level):
    ok = [p for p in points if p["N"] == n and p["series"] == series and p["status"] == "ok"
          and p["error_m"] <= level]
    return min(ok, key=lambda p: p["cpu_per_s"]) if ok else None


def setting_text(p):
    if not p["series"].endswith("DOP853"):
        return f"{p['setting'] * 1e3:g} ms"
    return f"rtol {p['setting']:g}"


def accuracy_table(points, ns):
    """Markdown rows, and {(N, level, "RK4" or "any"): MuJoCo's cost ÷ the compiled path's} (inf:
    only the compiled path reached the level)."""
    lines = ["| N links | error ≤ (m) | " + " | ".join(SERIES) + " | MuJoCo RK4 ÷ best compiled | "
             "best MuJoCo ÷ best compiled |", "|---" * (len(SERIES) + 4) + "|"]
    verdicts = {}
    for n in ns:
        for level in LEVELS:
            best = {s: cheapest(points, n, s, level) for s in SERIES}
            cells = [f"{b['cpu_per_s']:.4f} ({setting_text(b)})" if b else "not reached" for b in best.values()]
            ours = [best[s]["cpu_per_s"] for s in COMPILED if best[s]]
            for key, names in (("RK4", ("MuJoCo RK4",)), ("any", MUJOCO)):
                theirs = [best[s]["cpu_per_s"] for s in names if best[s]]
                if ours:
                    verdicts[(n, level, key)] = min(theirs) / min(ours) if theirs else math.inf
                r = verdicts.get((n, level, key))
                cells.append("-" if r is None else ("MuJoCo not reached" if r == math.inf else f"{r:.2f}"))
            lines.append(f"| {n} | {level:g} | " + " | ".join(cells) + " |")
    return lines, verdicts


def plot_work_precision(points, n, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:                                     # pragma: no cover
        return
    fig, ax = plt.subplots(figsize=(7, 5))
    for series, style in zip(SERIES, ("s:", "v:", "o-", "^-")):
        pts = sorted((p for p in points if p["N"] == n and p["series"] == series and p["status"] == "ok"
                      and p["error_m"] > 0), key=lambda p: -p["setting"])
        if pts:
            ax.loglog([p["cpu_per_s"] for p in pts], [p["error_m"] for p in pts], style, ms=4, label=series)
            for p in pts:
                ax.annotate(setting_text(p).replace("rtol ", ""), (p["cpu_per_s"], p["error_m"]), fontsize=6,
                            xytext=(3, 2), textcoords="offset points")
    for level in LEVELS:
        ax.axhline(level, color="0.8", lw=0.8, zorder=0)
    ax.set_xlabel("CPU s per simulated s")
    ax.set_ylabel("max |tip − reference| over 10 ms samples (m)")
    ax.set_title(f"{n}-link chain with inerters: work-precision")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def plot_scaling(rows, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:                                     # pragma: no cover
        return
    ns = [r["N"] for r in rows]
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.loglog(ns, [r["rk4"] for r in rows], "o-", label="compiled RK4 1 ms")
    ax.loglog(ns, [r["dop"] for r in rows], "s-", label="compiled DOP853 rtol 1e-8")
    ax.loglog(ns, [r["numpy"] for r in rows], "^--", label="numpy RK4 1 ms")
    if all("mujoco" in r for r in rows):
        ax.loglog(ns, [r["mujoco"] for r in rows], "D:", label="MuJoCo RK4 1 ms")
    ref = rows[0]["rk4"]
    ax.loglog(ns, [ref * (x / ns[0]) ** 1.3 for x in ns], ":", color="0.5", label="∝ N^1.3")
    ax.set_xlabel("links N")
    ax.set_ylabel("CPU s per simulated s")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    p.add_argument("--links", default="2,8,32,128")
    p.add_argument("--accuracy-links", default=None, help="N for the matched-accuracy sweeps (default: --links)")
    p.add_argument("--span", type=float, default=2.0, help="simulated seconds of the matched-accuracy runs")
    p.add_argument("--budget", type=float, default=30.0, help="CPU s per sweep run, at most (then no finer)")
    p.add_argument("--numpy-budget", type=float, default=20.0, help="CPU s per numpy-path run, at most")
    p.add_argument("--rounds", type=int, default=7, help="round-robin rounds of the scaling runs (best kept)")
    a = p.parse_args(argv)
    if not compiled.AVAILABLE:
        raise SystemExit(f"the compiled path is not available: {compiled.WHY_NOT}")
    try:
        import mujoco
        mj_version = mujoco.__version__
    except ImportError as exc:
        mujoco, mj_version = None, None
        print(f"MuJoCo columns skipped: {exc}")
    log = lambda s: print(s, flush=True)  # noqa: E731
    load = os.getloadavg()[0]
    log(f"MuJoCo {mj_version}; load average at start {load:.2f}")
    api.warm_up()
    links = [int(x) for x in a.links.split(",")]
    acc_links = [int(x) for x in (a.accuracy_links or a.links).split(",")]
    tmp = Path(tempfile.mkdtemp())
    rows, points, notes = [], [], []
    models = {n: inerter.load(write_chain(tmp / f"chain_{n}.toml", n)) for n in sorted(set(links) | set(acc_links))}
    mjs = {n: mujoco_chain(n) if mujoco else None for n in models}
    best, runs, per_round = interleaved_timings({n: models[n] for n in links}, {n: mjs[n] for n in links},
                                                a.rounds, log)
    for n in links:
        rows.append(scaling_row(n, models[n], mjs[n], best[n], runs[n], a.numpy_budget, log))
    for n in models:
        model, mj = models[n], mjs[n]
        if n in acc_links:
            pts, nts = accuracy_sweep(n, model, mj, a.span, a.budget, log)
            points += pts
            notes += nts

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    has_mj = bool(rows) and all("mujoco" in r for r in rows)
    ns = [r["N"] for r in rows]
    date = time.strftime("%Y-%m-%d")
    lines = ["# Chain scaling", "",
             f"`flock /tmp/inerter-bench.lock python benchmarks/chain_scaling.py`, {date}, one run"
             f"{f', MuJoCo {mj_version}' if mj_version else ''}, load average {load:.2f} at the start. "
             "N-link planar chain (benchmarks/chain_scene.py: pins, rotational spring + damper at every pin, spring "
             "+ damper + inerter between neighbouring midpoints, sine force at the tip); the same chain in MuJoCo "
             "(benchmarks/chain_mujoco.py: hinges with stiffness and damping, spatial tendons with stiffness, damping "
             "and armature = b, the force applied at every RK4 stage). CPU seconds (process time) per simulated "
             f"second; in the scaling table the best of {a.rounds} round-robin rounds over every N (a MuJoCo run of 3 s or "
             "more once), so that the ratios between N compare runs taken side by side; in the matched-accuracy "
             "table the best of 3 consecutive runs for runs under 3 s.", ""]
    if rows:
        head = ("| N links | unknowns n+m | band kl+ku | compiled RK4 1 ms | per evaluation (µs) | per RK4 step (µs) | "
                "compiled DOP853 rtol 1e-8 (steps/s) | numpy RK4 1 ms (span) |")
        if has_mj:
            head += " MuJoCo RK4 1 ms | MuJoCo per step (µs) | MuJoCo per step without the force callback (µs) | Jacobian |"
        lines += ["## Cost per simulated second", "", head, "|---" * (head.count("|") - 1) + "|"]
        for r in rows:
            line = (f"| {r['N']} | {r['unknowns']} | {r['band']} | {r['rk4']:.4f} | {r['rk4_eval'] * 1e6:.2f} | "
                    f"{r['rk4_step'] * 1e6:.1f} | {r['dop']:.4f} ({r['dop_steps']}) | {r['numpy']:.2f} "
                    f"({r['numpy_span']:g} s) |")
            if has_mj:
                jc = r["jacobian_costs"]
                line += (f" {r['mujoco']:.4f} | {r['mujoco_step'] * 1e6:.1f} | {r['mujoco_bare'] * 1e6:.1f} | "
                         f"{r['jacobian']} (dense {jc['dense'] * 1e6:.1f}, sparse {jc['sparse'] * 1e6:.1f} µs) |")
            lines.append(line)
        fmt = lambda es: ", ".join(f"{x:.2f}" for x in es)  # noqa: E731
        overall = lambda key: math.log(rows[-1][key] / rows[0][key]) / math.log(ns[-1] / ns[0])  # noqa: E731
        e_rk4, e_dop = exponent(ns, [r["rk4"] for r in rows]), exponent(ns, [r["dop"] for r in rows])
        lines += ["", "Growth exponents between successive N (time ∝ N^e):", "",
                  f"* compiled RK4 (fixed step, evaluation cost): {fmt(e_rk4)}; {ns[0]}→{ns[-1]}: {overall('rk4'):.2f}",
                  f"* compiled DOP853 (adaptive): {fmt(e_dop)}; {ns[0]}→{ns[-1]}: {overall('dop'):.2f}",
                  f"* numpy path RK4: {fmt(exponent(ns, [r['numpy'] for r in rows]))}; {ns[0]}→{ns[-1]}: "
                  f"{overall('numpy'):.2f}"]
        if has_mj:
            lines.append(f"* MuJoCo RK4: {fmt(exponent(ns, [r['mujoco'] for r in rows]))}; {ns[0]}→{ns[-1]}: "
                         f"{overall('mujoco'):.2f}")
        spread = []
        for key, what in (("rk4", "compiled RK4"), ("dop", "compiled DOP853")):
            each = [exponent(ns, [rd[n] for n in ns]) for rd in per_round[key] if all(n in rd for n in ns)]
            if each:
                spread.append(f"* {what}, exponent between successive N in each round (the machine's noise): "
                              + "; ".join(fmt(e) for e in each))
        lines += [""] + spread
        lines += ["", f"Target ≤ N^1.3 for the compiled path: fixed step {'met' if max(e_rk4) <= 1.3 else 'NOT met'} "
                  f"(largest {max(e_rk4):.2f}); adaptive {'met' if max(e_dop) <= 1.3 else 'NOT met'} "
                  f"(largest {max(e_dop):.2f}).", "", "![scaling](chain_scaling.png)", ""]
        with open(out / "chain_scaling.csv", "w", newline="") as fh:
            keys = [k for k in rows[0] if k != "jacobian_costs"]
            w = csv.writer(fh)
            w.writerow(keys)
            for r in rows:
                w.writerow([f"{r[k]:.6g}" if isinstance(r[k], float) else r[k] for k in keys])
        plot_scaling(rows, out / "chain_scaling.png")
    if points:
        acc_ns = sorted({p["N"] for p in points})
        table, verdicts = accuracy_table(points, acc_ns)
        lines += ["## Matched accuracy", "",
                  f"Error: max over the 10 ms samples of |tip − reference| (m) over 0-{a.span:g} s; reference: "
                  "compiled DOP853 at rtol 1e-12, atol 1e-14. Cells: CPU s per simulated second of the cheapest run "
                  "reaching the error (its setting); the ratios are MuJoCo's cost over the cheaper of the two "
                  "compiled integrators (> 1: the compiled path is ahead). MuJoCo Euler is MuJoCo's default "
                  "integrator (semi-implicit Euler, joint damping implicit), shown for completeness; the comparison "
                  "asked for is with RK4. Steps swept (both MuJoCo integrators and compiled RK4): "
                  f"{', '.join(f'{s * 1e3:g}' for s in STEPS)} ms (coarser ones that blow up are listed as "
                  "unstable in the CSV); rtol swept: " + ", ".join(f"{r:g}" for r in RTOLS) + ".", ""]
        lines += table
        big = max(acc_ns)
        if mj_version:
            lines.append("")
            for key, what in (("RK4", "MuJoCo RK4"), ("any", "the cheaper of MuJoCo RK4 and Euler")):
                wins = [lv for lv in LEVELS if verdicts.get((big, lv, key), 0) > 1]
                losses = [lv for lv in LEVELS if (big, lv, key) in verdicts and verdicts[(big, lv, key)] <= 1]
                lines.append(f"* At {big} links the compiled path is ahead of {what} at "
                             f"{', '.join(f'{lv:g} m' for lv in wins) or 'no accuracy level'}"
                             + (f"; behind at {', '.join(f'{lv:g} m' for lv in losses)}" if losses else "") + ".")
        lines += ["", f"![work-precision at N = {big}](chain_work_precision.png)", "", "Notes:", ""]
        lines += [f"* {t}" for t in notes]
        lines.append("* Steps that do not divide 10 ms (12.5, 15, 17.5 ms): MuJoCo is scored on the samples its steps "
                     "land on (every 50, 30, 70 ms), the compiled RK4 on every 10 ms sample.")
        with open(out / "chain_work_precision.csv", "w", newline="") as fh:
            keys = list(points[0])
            w = csv.writer(fh)
            w.writerow(keys)
            for pt in points:
                w.writerow([f"{pt[k]:.6g}" if isinstance(pt[k], float) else pt[k] for k in keys])
        plot_work_precision(points, big, out / "chain_work_precision.png")
    (out / "chain_scaling.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
