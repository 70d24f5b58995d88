"""Work-precision diagrams: what each extra digit of accuracy costs, for one scene.

    inerter bench SCENE [--out DIR] [--stop-time T] [--signal C.r[2]] [--paths numpy,compiled,fmu]
                        [--methods DOP853,RK45,Radau,BDF,RK4] [--budget SECONDS] [--quick]

For every method over a range of tolerances (RK4: step sizes), on the numpy path
(``inerter.engine.simulation.integrate``) and the compiled path (``inerter.engine.compiled.integrate_compiled``),
and through the scene's FMU (``--paths fmu``: fmpy, communication step × method × tolerance),
the error against the oracle at tight tolerance (``model.oracle().simulate(rtol=1e-12,
atol=1e-14)``) is plotted against the CPU time of the integration. The error is the largest
deviation over the output samples of the chosen signal (a point coordinate ``P.r[i]``), or by
default of every named point's position. Writes ``work_precision.csv``, ``work_precision.md``
(with the cheapest run reaching 1e-3 … 1e-9) and ``work_precision.png`` into the output directory.
"""
from __future__ import annotations

import argparse
import csv
import datetime
import gc
import math
import sys
import time
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Callable

import numpy as np

from inerter.studies.arguments import Parser
from inerter.common.options import OptionError, output_folder

TARGETS = (1e-3, 1e-6, 1e-9)

#: Tolerances (adaptive methods: rtol, with atol = rtol / 100) and steps (RK4) swept by default.
SWEEPS = {
    "DOP853": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12],
    "RK45": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "Radau": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "BDF": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9],
    "RK4": [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2.5e-4],
}
QUICK = {
    "DOP853": [1e-5, 1e-7, 1e-9, 1e-11],
    "RK45": [1e-5, 1e-7, 1e-9],
    "Radau": [1e-5, 1e-7],
    "BDF": [1e-5, 1e-7],
    "RK4": [5e-3, 1e-3],
}


@dataclass
class Point:
    series: str            # e.g. "compiled DOP853", "scipy 2-angle ODE DOP853", "MuJoCo RK4"
    setting: float         # rtol or step
    error: float
    cpu: float             # s, CPU time of the integration (best of the repeats)
    steps: int = 0
    evaluations: int = 0
    status: str = "ok"


@dataclass
class Study:
    scene: str
    stop_time: float
    signal: str
    points: list[Point] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def best(self, series: str, target: float):
        """The cheapest run of a series reaching the target error (None if none did)."""
        ok = [p for p in self.points if p.series == series and p.status == "ok" and p.error <= target]
        return min(ok, key=lambda p: p.cpu) if ok else None

    def best_of(self, prefix: str, target: float):
        """The cheapest run reaching the target error among the series named `prefix` ... (e.g. "numpy")."""
        found = [b for b in (self.best(name, target) for name in self.series() if name.startswith(prefix + " "))
                 if b]
        return min(found, key=lambda p: p.cpu) if found else None

    def series(self):
        return list(dict.fromkeys(p.series for p in self.points))


def signal_columns(mech, signal: str | None) -> list[tuple[str, int]]:
    """(point, axis from 0) of each column compared with the oracle: the signal ``P.r[i]``, or every
    coordinate of every point on a body (2D or 3D)."""
    names, d = list(mech.point_names), mech.dim
    if signal:
        name, _, rest = signal.partition(".r[")
        axis = rest[:-1] if rest.endswith("]") else ""
        if name not in names or axis not in [str(i) for i in range(1, d + 1)]:
            axes = " or ".join(f"P.r[{i}]" for i in range(1, d + 1))
            raise OptionError("--signal", signal, f"{axes} with P one of {', '.join(names)}", "unknown signal")
        return [(name, int(axis) - 1)]
    return [(name, a) for name in names if mech.points[name].body >= 0 for a in range(d)]


def signal_extractor(mech, signal: str | None) -> Callable[[np.ndarray], np.ndarray]:
    """states (T × (nq + nv)) → positions (T × k) of :func:`signal_columns`, from the mechanism's
    own point kinematics (any dimension, any orientation coordinates)."""
    columns = signal_columns(mech, signal)
    points = [mech.points[name] for name, _ in columns]
    nq = mech.nq

    def extract(states):
        states = np.atleast_2d(states)
        out = np.empty((len(states), len(columns)))
        for k, y in enumerate(states):
            q, v = y[:nq], y[nq:]
            for j, (point, (_, axis)) in enumerate(zip(points, columns)):
                out[k, j] = point.evaluate(q, v)[0][axis]
        return out
    return extract


def reference_states(path, overrides, stop_time, output_interval, origins=None):
    """The oracle's samples at rtol 1e-12, atol 1e-14 (DOP853). `origins`: where each override came
    from, as errors name it (``{"b": "--set b=20"}``)."""
    from inerter.api import Model

    oracle = Model(path, overrides, origins=origins).oracle()
    result = oracle.simulate(stop_time=stop_time, output_interval=output_interval, rtol=1e-12, atol=1e-14,
                             metrics=False)
    if result.status != "ok":
        raise RuntimeError(f"the oracle failed: {result.message}")
    return result.run.states


#: Runs are repeated and the smallest CPU time kept (timings are noisy): (below s, runs). The count
#: follows the best time so far, so a first run slowed by the machine is repeated as its true
#: time asks.
REPEATS = ((0.05, 7), (0.3, 3), (5.0, 2))
REPEATS_TEXT = "best of 7 for runs under 0.05 s, of 3 under 0.3 s, of 2 under 5 s"


def settle():
    """Collect the objects earlier runs left and freeze the survivors, so that the garbage
    collections during the next run traverse that run's own objects only. Call before timing."""
    gc.collect()
    gc.freeze()


def best_time(fn, cpu_of=lambda out: out[1]):
    """Run fn() → out; repeat it as REPEATS says for its CPU time cpu_of(out); (out, smallest time).
    Each run starts settled (:func:`settle`)."""
    def once():
        settle()
        return fn()

    out = once()
    best = cpu_of(out)
    runs = 1
    while runs < next((n for limit, n in REPEATS if best < limit), 1):
        best = min(best, cpu_of(once()))
        runs += 1
    return out, best


def _timed(fn):
    return best_time(fn, lambda run: run.cpu_time)


def sweep(study: Study, model, reference, extract, paths, methods, sweeps, budget, log=print):
    """Add the numpy / compiled path points of every method to the study."""
    from inerter import api
    from inerter.engine import compiled
    from inerter.engine.simulation import integrate

    ref = extract(reference)
    if "compiled" in paths:
        api.warm_up(spatial=model.mechanism.dim == 3)
    for path in paths:
        for method in methods:
            label = f"{path} {method}"
            why_not = compiled.unsupported(model.mechanism) if path == "compiled" else ""
            if why_not:
                study.notes.append(f"{label}: skipped, {why_not}")
                continue
            for setting in sweeps[method]:
                kw = dict(stop_time=study.stop_time, method=method)
                if method == "RK4":
                    kw["step"] = setting
                else:
                    kw.update(rtol=setting, atol=setting * 1e-2)
                s = model.settings(**kw)
                s.max_steps = max(s.max_steps, int(10 * study.stop_time / min(setting, 1e-3)) if method == "RK4"
                                  else s.max_steps)
                if path == "compiled":
                    fn = lambda: compiled.integrate_compiled(model.mechanism, s)  # noqa: E731
                else:
                    fn = lambda: integrate(model.mechanism, s)  # noqa: E731
                run, cpu = _timed(fn)
                err = float(np.max(np.abs(extract(run.states) - ref[:len(run.states)]))) if run.status == "ok" \
                    else float("nan")
                study.points.append(Point(label, setting, err, cpu, run.steps, run.evaluations, run.status))
                log(f"  {label:28s} {setting:8.1e}  error {err:9.2e}  cpu {cpu:8.4f} s  steps {run.steps}")
                if cpu > budget:
                    study.notes.append(f"{label}: stopped after {setting:g} ({cpu:.1f} s > budget {budget:g} s)")
                    break


#: Communication steps (s) of the FMU series, and the methods swept through the FMU by default.
FMU_STEPS = (0.01, 0.002)
FMU_METHODS = ("DOP853", "RK45")


def signal_names(mech, signal: str | None) -> list[str]:
    """The output names of the columns :func:`signal_extractor` gives, in its order."""
    return [f"{name}.r[{axis + 1}]" for name, axis in signal_columns(mech, signal)]


def fmu_sweep(study: Study, scene, overrides, reference, names, interval, methods, sweeps, steps, budget,
              log=print):
    """Add the FMU path: for each communication step × method × tolerance, a whole run through
    ``fmpy.simulate_fmu`` (extraction and instantiation included, every output recorded, the FMU's
    default path: compiled where numba is installed), its error on the same signal against the
    oracle at the oracle's sample times, and the process CPU time of the run (REPEATS_TEXT)."""
    import fmpy

    from inerter.fmu.build import build
    from inerter.fmu.run import solver_item

    fmu = str(build(scene))
    fmpy.simulate_fmu(fmu, stop_time=min(study.stop_time, 0.1), start_values=dict(overrides))   # warm up
    study.notes.append("FMU series: CPU time of the whole fmpy run (extraction, instantiation, every step, every "
                       "output recorded), setting = rtol (atol = rtol/100)")
    for h in steps:
        # compared at the times on both grids (multiples of their least common multiple): every
        # `every`-th FMU point, every `skip`-th oracle sample
        fh, fi = Fraction(h).limit_denominator(10**6), Fraction(interval).limit_denominator(10**6)
        common = Fraction(math.lcm(fh.numerator * fi.denominator, fi.numerator * fh.denominator),
                          fh.denominator * fi.denominator)
        every, skip = int(common / fh), int(common / fi)
        if abs(every * h - skip * interval) > 1e-12 or common > study.stop_time:
            study.notes.append(f"FMU at {h:g} s: skipped, the oracle's {interval:g} s samples are not on its grid")
            continue
        for method in methods:
            label = f"FMU {method}, {1e3 * h:g} ms step"
            for rtol in sweeps[method]:
                start = dict(overrides, solver=solver_item(method), rtol=rtol, atol=rtol * 1e-2)

                def run():
                    t0 = time.process_time()
                    res = fmpy.simulate_fmu(fmu, stop_time=study.stop_time, output_interval=h, start_values=start)
                    return res, time.process_time() - t0
                try:
                    (res, _), cpu = best_time(run)
                except Exception as exc:              # an FMI error status: recorded, the sweep goes on
                    study.points.append(Point(label, rtol, float("nan"), float("nan"), 0, 0, "failed"))
                    study.notes.append(f"{label} at rtol {rtol:g}: failed ({exc})")
                    log(f"  {label:28s} {rtol:8.1e}  failed: {exc}")
                    continue
                ok = abs(res["time"][-1] - study.stop_time) < 1e-9 * max(1.0, study.stop_time)
                got = np.column_stack([res[n] for n in names])[::every]
                ref = reference[::skip][:len(got)]
                err = float(np.max(np.abs(got[:len(ref)] - ref))) if ok else float("nan")
                study.points.append(Point(label, rtol, err, cpu, len(res) - 1, 0, "ok" if ok else "failed"))
                log(f"  {label:28s} {rtol:8.1e}  error {err:9.2e}  cpu {cpu:8.4f} s")
                if cpu > budget:
                    study.notes.append(f"{label}: stopped after {rtol:g} ({cpu:.1f} s > budget {budget:g} s)")
                    break


def write_outputs(study: Study, out: Path, ratio_to: str | None = None, title: str | None = None) -> Path:
    out.mkdir(parents=True, exist_ok=True)
    stem = out / "work_precision"
    with open(f"{stem}.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["series", "setting", "error_m", "cpu_s", "steps", "evaluations", "status"])
        for p in study.points:
            w.writerow([p.series, f"{p.setting:g}", f"{p.error:.6g}", f"{p.cpu:.6g}", p.steps, p.evaluations, p.status])
    lines = [f"# Work-precision: {study.scene}", "",
             f"`python benchmarks/work_precision.py`, {datetime.date.today()}, on a 2-core machine. "
             f"Simulated 0-{study.stop_time:g} s; error = max |{study.signal} - oracle| over the output samples "
             "(oracle: DOP853 on the element forces from d²L/dt², rtol 1e-12, atol 1e-14); CPU time of the "
             f"integration ({REPEATS_TEXT}). Settings: rtol (atol = rtol/100), RK4 and MuJoCo: step (s).",
             "", "## Cheapest run reaching each error", ""]
    head = "| series | " + " | ".join(f"≤ {t:g} m: CPU s (setting)" for t in TARGETS)
    if ratio_to:
        head += " | " + " | ".join(f"× {ratio_to} at {t:g}" for t in TARGETS[1:])
    lines += [head + " |", "|" + "---|" * (1 + len(TARGETS) + (len(TARGETS) - 1 if ratio_to else 0))]
    for s in study.series():
        cells = []
        for t in TARGETS:
            b = study.best(s, t)
            cells.append(f"{b.cpu:.4f} ({b.setting:g})" if b else "not reached")
        if ratio_to:
            for t in TARGETS[1:]:
                b, r = study.best(s, t), study.best(ratio_to, t)
                cells.append(f"{b.cpu / r.cpu:.2f}" if b and r else "-")
        lines.append(f"| {s} | " + " | ".join(cells) + " |")
    lines += ["", "## All runs", "", "| series | setting | error (m) | CPU (s) | steps | evaluations | status |",
              "|---|---|---|---|---|---|---|"]
    for p in study.points:
        lines.append(f"| {p.series} | {p.setting:g} | {p.error:.3g} | {p.cpu:.4f} | {p.steps} | {p.evaluations} "
                     f"| {p.status} |")
    if study.notes:
        lines += ["", "Notes:", ""] + [f"* {n}" for n in study.notes]
    Path(f"{stem}.md").write_text("\n".join(lines) + "\n")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(8, 5.5))
        for s in study.series():
            pts = sorted((p for p in study.points if p.series == s and p.status == "ok" and p.error > 0),
                         key=lambda p: p.setting)
            if not pts:
                continue
            style = {"compiled": "-", "numpy": "--", "FMU": "-."}.get(s.split()[0], ":")
            ax.loglog([p.cpu for p in pts], [p.error for p in pts], style, marker="o", ms=3, label=s)
        for t in TARGETS:
            ax.axhline(t, color="0.8", lw=0.8, zorder=0)
        ax.set_xlabel("CPU time of the integration (s)")
        ax.set_ylabel(f"max |{study.signal} − oracle| (m)")
        ax.set_title(title or f"{study.scene}, 0–{study.stop_time:g} s")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
        fig.tight_layout()
        fig.savefig(f"{stem}.png", dpi=120)
        plt.close(fig)
    except ImportError:                                     # pragma: no cover
        pass
    return Path(f"{stem}.md")


def run_study(scene, stop_time=None, signal=None, paths=("numpy", "compiled"), methods=tuple(SWEEPS),
              sweeps=None, budget=30.0, overrides=None, log=print, origins=None):
    """Reference + sweeps for one scene. Returns (study, model, reference states, extractor).
    `origins`: where each override came from, as errors name it (:func:`reference_states`)."""
    from inerter.api import Model

    overrides = dict(overrides or {})
    model = Model(scene, overrides, origins=origins)
    stop = float(stop_time if stop_time is not None else model.scene.experiment.stop_time)
    interval = model.scene.experiment.output_interval
    extract = signal_extractor(model.mechanism, signal)          # a bad --signal before the reference
    t0 = time.perf_counter()
    reference = reference_states(scene, overrides, stop, interval, origins)
    log(f"{model.name}: oracle reference over 0-{stop:g} s in {time.perf_counter() - t0:.1f} s")
    study = Study(model.name, stop, signal or "every point's position")
    solver_paths = [p for p in paths if p != "fmu"]
    sweep(study, model, reference, extract, solver_paths, list(methods), sweeps or SWEEPS, budget, log)
    if "fmu" in paths:
        fmu_methods = [m for m in methods if m in FMU_METHODS] or list(FMU_METHODS)
        fmu_sweep(study, scene, overrides, extract(reference), signal_names(model.mechanism, signal), interval,
                  fmu_methods, sweeps or SWEEPS, FMU_STEPS, budget, log)
    return study, model, reference, extract


#: The inerter devices' hard cases (scenarios/hard/; docs/hard_cases.md): stick-slip of a small
#: velocity scale, backlash impacts, end-stop contact.
HARD_DEVICE_CASES = ("stick_slip_device_2d", "backlash_device_2d", "end_stop_device_2d")
HARD_RTOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-13)
HARD_METHODS = {"DOP853": HARD_RTOLS, "Radau": (1e-4, 1e-6, 1e-8, 1e-10)}


def hard_case_rows(folder: Path, cases=HARD_DEVICE_CASES, methods=HARD_METHODS, log=print) -> list[dict]:
    """Work-precision rows of the device hard cases, tolerance by tolerance down to the tightest
    (atol = rtol/100): status, accepted steps, right-hand side evaluations, CPU time of the
    integration (best of REPEATS) and the largest deviation of the points' positions from the
    case's own DOP853 run at rtol 1e-13 (the tightest; its convergence is the check)."""
    import inerter
    rows = []
    for name in cases:
        model = inerter.load(folder / f"{name}.toml")
        ref = model.simulate(method="DOP853", rtol=1e-13, atol=1e-15, metrics=False)
        columns = [n for n in ref.names if ".r[" in n]
        for method, rtols in methods.items():
            for rtol in rtols:
                run, cpu = best_time(lambda: model.simulate(method=method, rtol=rtol, atol=rtol * 1e-2,
                                                            metrics=False), lambda r: r.run.cpu_time)
                error = max(float(np.max(np.abs(run[c] - ref[c][:len(run.time)]))) for c in columns)
                rows.append(dict(case=name, method=method, rtol=rtol, status=run.status, steps=run.run.steps,
                                 evaluations=run.run.evaluations, cpu=cpu, error=error,
                                 events=len(run.events()), message=run.message))
                log(f"{name} {method} {rtol:g}: {run.status} {run.run.steps} steps, error {error:.2e}")
    return rows


def hard_case_table(rows) -> str:
    """The rows of :func:`hard_case_rows` as a Markdown table."""
    lines = ["| case | method | rtol | status | steps | evaluations | events | CPU s | max error (m) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['method']} | {r['rtol']:g} | {r['status']} | {r['steps']} | "
                     f"{r['evaluations']} | {r['events']} | {r['cpu']:.4f} | {r['error']:.2e} |")
    return "\n".join(lines)


def bench_parser() -> argparse.ArgumentParser:
    """The options of ``inerter bench``."""
    p = Parser(prog="inerter bench", description="Work-precision diagram of a scene: error "
               "against the oracle versus CPU time, per method, on the numpy and compiled "
               "paths and through the FMU.")
    p.add_argument("scene", help="the scene file (TOML)")
    p.add_argument("--out", default=None, help="output directory (default out/bench/<scene>)")
    p.add_argument("--stop-time", type=float, default=None, help="stop time of every run (s; default: the scene's)")
    p.add_argument("--signal", default=None, help="a point coordinate, e.g. C.r[2] (default: every point)")
    p.add_argument("--paths", default="numpy,compiled,fmu",
                   help="some of numpy, compiled, fmu (the FMU through fmpy at 10 ms and 2 ms communication "
                        "steps, DOP853 and RK45)")
    p.add_argument("--methods", default=",".join(SWEEPS),
                   help="comma-separated, some of " + ", ".join(SWEEPS) + " (default: all)")
    p.add_argument("--budget", type=float, default=30.0,
                   help="stop a method's sweep after a run takes longer than this (CPU s)")
    p.add_argument("--quick", action="store_true", help="fewer tolerances per method")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                   help="override a parameter, effects.NAME or experiment.NAME, as inerter run --set (repeatable)")
    return p


def main_bench(argv=None) -> int:
    from inerter.common.errors import InerterError
    from inerter.scene.overrides import parse_set, set_origins
    p = bench_parser()
    a = p.parse_args(argv)
    methods = [m.strip() for m in a.methods.split(",") if m.strip()]
    bad = [m for m in methods if m not in SWEEPS]
    if bad:
        p.error(f"unknown method(s) {', '.join(bad)}; expected some of {', '.join(SWEEPS)}")
    paths = [x.strip() for x in a.paths.split(",") if x.strip()]
    if any(x not in ("numpy", "compiled", "fmu") for x in paths):
        p.error("--paths: expected some of numpy, compiled, fmu")
    try:
        return _bench(a, paths, methods, parse_set(a.set), set_origins(a.set))
    except InerterError as exc:
        print(f"inerter: error: {exc}", file=sys.stderr)
        return 2


def _bench(a, paths, methods, overrides, origins=None) -> int:
    if a.out is not None:
        output_folder(a.out)                   # before the runs
    if not a.budget > 0:
        raise OptionError("--budget", a.budget, "a positive number of CPU seconds")
    study, model, _, _ = run_study(a.scene, a.stop_time, a.signal, paths, methods, QUICK if a.quick else SWEEPS,
                                   a.budget, overrides, origins=origins)
    out = Path(a.out) if a.out is not None else Path("out") / "bench" / model.name
    md = write_outputs(study, out, ratio_to="compiled DOP853" if "compiled" in paths else None)
    print(md.read_text().split("## All runs")[0])
    print(f"wrote {md}, {md.with_suffix('.csv')}, {md.with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main_bench())
