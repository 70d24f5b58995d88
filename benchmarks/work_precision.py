"""Work-precision diagrams of both paper scenes, with the peers measured in the same run.

    python benchmarks/work_precision.py [--quick] [--budget 30] [--out docs/benchmarks]
    python benchmarks/work_precision.py --scenes two_bar_2d --paths default     # the default call only

two_bar_2d, 0-20 s, error = max |C_y − oracle| over 10 ms samples: every method on the numpy
and the compiled path, DOP853 and RK45 through the FMU (fmpy, 10 ms and 2 ms communication steps,
the whole run timed), plus scipy DOP853 on the hand-written 2-angle ODE (peers.TwoAngleODE,
checked against the oracle to 1e-9 m before timing) and MuJoCo (tendon armature = b, RK4,
force at every stage; skipped when mujoco does not import). lumped_mass_2d, 0-20 s, error on
P_y. Writes docs/benchmarks/<scene>/work_precision.{png,csv,md} and docs/benchmarks/work_precision.md
(the targets: the default call to 1e-6 m and 1e-9 m in ≤ 1/4 of the hand-written ODE's time, below;
the FMU's cost above the importer's floor: benchmarks/fmu_overhead.py).

`--paths default` (part of the default set): the default call, ``model.simulate(stop_time=20,
rtol=rtol, atol=rtol/100)`` with the scene's metrics (natural frequency, C_y steady state from the
dense output), timed whole (settings, grid, integration, outputs, metrics; the Model is built
before) side by side with scipy DOP853 on the hand-written ODE at the same tolerances, the two
timed in turn at each tolerance so that both see the same machine; the ratio of the cheapest runs
reaching 1e-6 m and 1e-9 m (target ≤ 1/4), and the call's cost beyond its own integration
(``run.cpu_time``) relative to it (target ≤ 1/5). Written to docs/benchmarks/default_call.md.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

import inerter  # noqa: E402
from inerter.studies import bench  # noqa: E402
from peers import TwoAngleODE, mujoco_two_bar  # noqa: E402

ODE_RTOLS = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
MUJOCO_STEPS = [1e-2, 5e-3, 2.5e-3, 2e-3, 1e-3, 5e-4]


def peers(study, reference_cy, grid, log=print):
    ode = TwoAngleODE()
    y, _, _ = ode.solve(study.stop_time, grid, 1e-12, 1e-14)
    check = float(np.max(np.abs(y - reference_cy)))
    log(f"hand-written 2-angle ODE at rtol 1e-12 vs oracle: {check:.2e} m")
    if check > 1e-9:
        raise SystemExit(f"the hand-written ODE disagrees with the oracle by {check:.3g} m > 1e-9 m")
    study.notes.append(f"hand-written 2-angle ODE (scipy DOP853, rtol 1e-12) agrees with the oracle to {check:.2e} m")
    for rtol in ODE_RTOLS:
        (y, _, nfev), cpu = bench.best_time(lambda: ode.solve(study.stop_time, grid, rtol, rtol * 1e-2))
        err = float(np.max(np.abs(y - reference_cy)))
        study.points.append(bench.Point("scipy 2-angle ODE DOP853", rtol, err, cpu, 0, nfev))
        log(f"  2-angle ODE DOP853 {rtol:8.1e}  error {err:9.2e}  cpu {cpu:8.4f} s")
    try:
        import mujoco
    except ImportError as exc:
        study.notes.append(f"MuJoCo rows skipped: {exc}")
        return
    for dt in MUJOCO_STEPS:
        (y, _, steps), cpu = bench.best_time(lambda: mujoco_two_bar(study.stop_time, grid, dt))
        err = float(np.max(np.abs(y - reference_cy)))
        study.points.append(bench.Point(f"MuJoCo {mujoco.__version__} RK4", dt, err, cpu, steps, 4 * steps))
        log(f"  MuJoCo RK4 {dt:8.1e}  error {err:9.2e}  cpu {cpu:8.4f} s")


#: Tolerances of the default call's comparison (rtol; atol = rtol/100): ODE_RTOLS and the points
#: between them, for both the default call and the hand-written ODE.
DEFAULT_RTOLS = sorted({*ODE_RTOLS, 5e-5, 2e-5, 5e-6, 2e-6, 5e-7, 5e-8, 5e-9, 5e-10}, reverse=True)


def default_call(model, reference_cy, grid, rtols=DEFAULT_RTOLS, log=print):
    """The default call (``model.simulate`` with its metrics, on the default path) and scipy DOP853
    on the hand-written ODE, side by side at each of `rtols`: rows of (rtol, call CPU s, the
    integration's own CPU s in it, error m, steps, ODE CPU s, ODE error m, ODE evaluations, the
    first call on a Model just built CPU s).

    The call is repeated on one Model (as the ODE's solve is), the best kept; the first call on a
    new Model also works out what the Model keeps for later calls (the kernels' arrays, the static
    equilibrium and the natural frequencies of the metrics): measured apart, on Models built
    untimed before each call."""
    from inerter import api

    api.warm_up()
    ode = TwoAngleODE()
    rows = []
    log(f"default call ({model.name}, 0-20 s, with its metrics) vs scipy 2-angle ODE DOP853, CPU s:")
    log(f"  {'rtol':>8s}  {'call':>8s} {'integr.':>8s} {'extra':>6s} {'error':>9s}  {'ODE':>8s} {'error':>9s}  ratio")
    for rtol in rtols:
        integrations = []

        def call():
            t0 = time.process_time()
            result = model.simulate(stop_time=20.0, rtol=rtol, atol=rtol * 1e-2)
            cpu = time.process_time() - t0
            integrations.append(result.run.cpu_time)
            return result, cpu
        (result, _), cpu = bench.best_time(call)
        integration = min(integrations)          # the integration's own time, best over the same repeats
        (y, _, nfev), ode_cpu = bench.best_time(lambda: ode.solve(20.0, grid, rtol, rtol * 1e-2))
        ok = result.status == "ok" and "C_y_peak_to_peak" in result.metrics
        err = float(np.max(np.abs(result["C.r[2]"] - reference_cy))) if ok else float("nan")
        ode_err = float(np.max(np.abs(y - reference_cy)))
        fresh = []
        for _ in range(3):
            new = inerter.load(model.path, **model.overrides)
            bench.settle()
            t0 = time.process_time()
            new.simulate(stop_time=20.0, rtol=rtol, atol=rtol * 1e-2)
            fresh.append(time.process_time() - t0)
        rows.append((rtol, cpu, integration, err, result.run.steps, ode_cpu, ode_err, nfev, min(fresh)))
        log(f"  {rtol:8.1e}  {cpu:8.4f} {integration:8.4f} {(cpu - integration) / integration:6.1%} {err:9.2e}  "
            f"{ode_cpu:8.4f} {ode_err:9.2e}  {cpu / ode_cpu:5.3f}   first call {min(fresh):.4f}")
    return rows


def default_call_report(rows, model) -> list[str]:
    """Markdown: the side-by-side table and, for 1e-6 m and 1e-9 m, the cheapest of each reaching
    it, their ratio (target ≤ 1/4) and the call's extra cost over its integration (target ≤ 1/5)."""
    lines = ["# The default call against scipy on the hand-written ODE", "",
             f"`python benchmarks/work_precision.py --scenes two_bar_2d --paths default`, {time.strftime('%Y-%m-%d')}. "
             f"two_bar_2d, 0-20 s: `model.simulate(stop_time=20, rtol=rtol, atol=rtol/100)` on the default path "
             f"with the scene's metrics ({', '.join(m.kind for m in model.scene.metrics)}), the Model built "
             f"before; scipy DOP853 on the hand-written 2-angle ODE (benchmarks/peers.py) at the same tolerances, "
             f"the two timed in turn at each tolerance. CPU time (process time, {bench.REPEATS_TEXT}); "
             "`integration`: the call's own integration loop (`run.cpu_time`); error: max |C_y − oracle| over the "
             "10 ms samples. `first call`: the same call on a Model just built (best of 3), which also works out "
             "what the Model keeps for later calls (the kernels' arrays, the static equilibrium, the natural "
             "frequencies).", "",
             "| rtol | call (s) | integration (s) | call beyond its integration | error (m) | steps | ODE (s) "
             "| ODE error (m) | ODE evaluations | call / ODE | first call (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for rtol, cpu, integ, err, steps, ode, ode_err, nfev, first in rows:
        lines.append(f"| {rtol:g} | {cpu:.4f} | {integ:.4f} | {(cpu - integ) / integ:.1%} | {err:.3g} | {steps} "
                     f"| {ode:.4f} | {ode_err:.3g} | {nfev} | {cpu / ode:.3f} | {first:.4f} |")
    lines += ["", "## Cheapest run reaching each error", ""]
    for target in (1e-6, 1e-9):
        for grid_name, allowed in (("every tolerance above", set(DEFAULT_RTOLS)), ("decades only", set(ODE_RTOLS))):
            mine = [r for r in rows if r[3] <= target and r[0] in allowed]
            peer = [r for r in rows if r[6] <= target and r[0] in allowed]
            if not mine or not peer:
                lines.append(f"* to {target:g} m ({grid_name}): not reached by "
                             f"{'the default call' if not mine else 'the ODE'}")
                continue
            a, b = min(mine, key=lambda r: r[1]), min(peer, key=lambda r: r[5])
            ratio, extra = a[1] / b[5], (a[1] - a[2]) / a[2]
            lines.append(f"* to {target:g} m ({grid_name}): default call {a[1]:.4f} s (rtol {a[0]:g}, its integration "
                         f"{a[2]:.4f} s, the rest {extra:.1%} of it: target ≤ 20%, "
                         f"{'met' if extra <= 0.2 else 'NOT met'}), scipy ODE {b[5]:.4f} s (rtol {b[0]:g}), ratio "
                         f"{ratio:.3f} (target ≤ 0.25: {'met' if ratio <= 0.25 else 'NOT met'}); the first call on "
                         f"a new Model {a[8]:.4f} s, ratio {a[8] / b[5]:.3f}")
    return lines


def same_run(model, method, point) -> float:
    """CPU seconds of the run an FMU point of `method` stands for, on the compiled solver path: the
    same method, rtol and atol, every output at the same 10 ms points (no metrics), best as
    bench.REPEATS says."""
    def run():
        t0 = time.process_time()
        result = model.simulate(stop_time=20.0, output_interval=0.01, method=method, rtol=point.setting,
                                atol=point.setting * 1e-2, metrics=False, path="compiled")
        return result, time.process_time() - t0
    return bench.best_time(run)[1]


def importer_floor(model) -> float:
    """CPU seconds of fmpy.simulate_fmu (20 s, 10 ms, every output recorded) on an FMU with as many
    outputs as `model` whose C binary does nothing (benchmarks/fmu_overhead.py builds it)."""
    import tempfile

    import fmpy
    from fmu_overhead import c_floor_fmu, floor_fmu

    folder = Path(tempfile.mkdtemp(prefix="inerter_floor_"))
    fmu = c_floor_fmu(floor_fmu(len(model.output_info()), folder), folder)

    def run():
        t0 = time.process_time()
        fmpy.simulate_fmu(fmu, stop_time=20.0, output_interval=0.01)
        return None, time.process_time() - t0
    return bench.best_time(run)[1]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--budget", type=float, default=30.0)
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    p.add_argument("--scenes", default="two_bar_2d,lumped_mass_2d")
    p.add_argument("--paths", default="numpy,compiled,fmu,default,hard",
                   help="some of numpy, compiled, fmu (the sweeps), default (the default call against the "
                        "hand-written ODE, two_bar_2d) and hard (the device hard cases' steps, a section of "
                        "work_precision.md; alone, it replaces that section only)")
    a = p.parse_args(argv)
    out = Path(a.out)
    hard = "hard" in a.paths.split(",")
    paths = [x for x in a.paths.split(",") if x and x not in ("default", "hard")]
    if hard and not paths:
        _replace_hard_section(out / "work_precision.md", hard_section())
        if "default" not in a.paths.split(","):
            return
    if "default" in a.paths.split(",") and "two_bar_2d" in a.scenes.split(","):
        scene = ROOT / "scenarios" / "two_bar_2d.toml"
        model = inerter.load(scene)
        interval = model.scene.experiment.output_interval
        extract = bench.signal_extractor(model.mechanism, "C.r[2]")
        reference = extract(bench.reference_states(scene, {}, 20.0, interval))[:, 0]
        rows = default_call(model, reference, np.arange(len(reference)) * interval,
                            ODE_RTOLS if a.quick else DEFAULT_RTOLS)
        report = default_call_report(rows, model)
        out.mkdir(parents=True, exist_ok=True)
        (out / "default_call.md").write_text("\n".join(report) + "\n")
        print("\n".join(report[report.index("## Cheapest run reaching each error"):]))
        if not paths:
            return
    sweeps = bench.QUICK if a.quick else bench.SWEEPS
    summary = ["# Work-precision of the paper scenes", "",
               f"`python benchmarks/work_precision.py{' --quick' if a.quick else ''}`, "
               f"{time.strftime('%Y-%m-%d')}, one run, CPU time of the integration (process time; "
               f"{bench.REPEATS_TEXT}). Error: max deviation from the oracle (rtol 1e-12) over the 10 ms "
               "samples, 0-20 s. Per-scene tables and diagrams: `<scene>/work_precision.{md,png,csv}`.", ""]
    for name, signal in (("two_bar_2d", "C.r[2]"), ("lumped_mass_2d", "P.r[2]")):
        if name not in a.scenes.split(","):
            continue
        scene = ROOT / "scenarios" / f"{name}.toml"
        study, model, reference, extract = bench.run_study(scene, 20.0, signal, paths,
                                                           list(bench.SWEEPS), sweeps, a.budget)
        if name == "two_bar_2d":
            grid = np.arange(len(reference)) * model.scene.experiment.output_interval
            peers(study, extract(reference)[:, 0], grid)
        md = bench.write_outputs(study, out / name, ratio_to="scipy 2-angle ODE DOP853" if name == "two_bar_2d"
                                 else "compiled DOP853", title=f"{name}, 0-20 s, error on {signal}")
        summary += [f"## {name}", "", f"![{name}]({name}/work_precision.png)", ""]
        summary += md.read_text().split("## Cheapest run reaching each error")[1].split("## All runs")[0].strip() \
            .splitlines()
        summary.append("")
        if name == "two_bar_2d":
            ode = "scipy 2-angle ODE DOP853"
            for t in (1e-6, 1e-9):
                b, r = study.best_of("compiled", t), study.best(ode, t)      # the cheapest compiled setting
                if b and r:
                    verdict = "met" if b.cpu <= r.cpu / 3 else "NOT met"
                    summary.append(f"* to {t:g} m: fast path {b.cpu:.4f} s ({b.series}, {b.setting:g}), hand-written "
                                   f"ODE {r.cpu:.4f} s, ratio {b.cpu / r.cpu:.2f} (target ≤ 0.33: {verdict})")
            fmu_series = {f"FMU {m}, 10 ms step": m for m in bench.FMU_METHODS}
            fmu_runs = []
            for t in (1e-6, 1e-9):
                found = [x for x in (study.best(name, t) for name in fmu_series) if x]
                b = min(found, key=lambda x: x.cpu) if found else None
                r, numpy_best = study.best_of("compiled", t), study.best_of("numpy", t)
                if b and r:
                    same = same_run(model, fmu_series[b.series], b)
                    fmu_runs.append((t, b.cpu, same))
                    verdict = "met" if b.cpu <= 2 * same else "NOT met"
                    line = (f"* to {t:g} m through the FMU at a 10 ms step: {b.cpu:.4f} s ({b.series}, rtol "
                            f"{b.setting:g}, the whole fmpy run, every output recorded); the same run on the compiled "
                            f"solver path (same method and rtol, every output at the same 10 ms points, "
                            f"`Model.simulate`) {same:.4f} s, ratio {b.cpu / same:.2f} (target ≤ 2: {verdict}); "
                            f"the compiled path's cheapest integration to {t:g} m alone, without the outputs, "
                            f"{r.cpu:.4f} s ({r.series}), ratio {b.cpu / r.cpu:.1f}")
                    if numpy_best:
                        line += (f"; numpy solver path ({numpy_best.series}) {numpy_best.cpu:.4f} s, ratio "
                                 f"{b.cpu / numpy_best.cpu:.2f}")
                    summary.append(line)
            floor = importer_floor(model)
            extra = [f"{(cpu - floor) / same:.2f}× the same run at {t:g} m" for t, cpu, same in fmu_runs]
            summary.append(f"* fmpy's own cost: the same `fmpy.simulate_fmu` call on an FMU whose C binary does "
                           f"nothing, with as many outputs (benchmarks/c_floor_fmu.c), {floor:.4f} s a run; the "
                           f"FMU costs {'; '.join(extra)} on top of it")
            summary.append("")
    if hard:
        summary += hard_section()
    (out / "work_precision.md").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))


HARD_TITLE = "## Device hard cases"


def hard_section() -> list[str]:
    """The device hard cases' work-precision (steps, evaluations, events, CPU, error at each tolerance
    down to the tightest; inerter.studies.bench.hard_case_rows) as a section of work_precision.md."""
    rows = bench.hard_case_rows(ROOT / "scenarios" / "hard")
    failed = [f"- {r['case']} {r['method']} rtol {r['rtol']:g}: {r['message']}" for r in rows if r["status"] != "ok"]
    return [HARD_TITLE, "",
            f"`python benchmarks/work_precision.py --paths hard` (this section alone), {time.strftime('%Y-%m-%d')}: "
            "5 s of each scene of scenarios/hard/ (stick-slip of a tanh friction "
            "with v_s = 1 mm/s, backlash impacts of a 2 mm gap, Hunt-Crossley end stops), atol = rtol/100, "
            "compiled right-hand side (DOP853: the compiled loop; Radau: scipy's). Error: the largest deviation "
            "of the points' positions from the same scene's DOP853 run at rtol 1e-13, over the 10 ms samples. "
            f"CPU: the integration's process time, {bench.REPEATS_TEXT}. Events: end-stop contacts and releases, "
            "backlash engagements and releases (Result.events). Discussion: [../hard_cases.md](../hard_cases.md).",
            "", bench.hard_case_table(rows), ""] + (["Failed runs:", ""] + failed + [""] if failed else [])


def _replace_hard_section(path: Path, section: list[str]):
    """work_precision.md with its hard-case section (the last) replaced by `section`."""
    text = path.read_text(encoding="utf-8") if path.is_file() else "# Work-precision of the paper scenes\n"
    head = text.split(HARD_TITLE)[0].rstrip("\n")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(head + "\n\n" + "\n".join(section) + "\n", encoding="utf-8")
    print("\n".join(section))


if __name__ == "__main__":
    main()
