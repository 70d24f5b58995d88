"""Throughput of a sweep on dask against a serial loop over the same runs, measured side by side.

    python benchmarks/sweep_throughput.py                     # 24 runs, 2 workers; writes docs/sweep_throughput.md
    python benchmarks/sweep_throughput.py --runs 8 --stop-time 5 --workers 2 --model solver

The runs: lumped_mass_2d with y0 evenly spaced from 1.05 to 1.5 m, each with and without the
centripetal correction, to the given stop time at the scene's tolerances: as a serial loop
(``inerter.load(...).simulate(...)`` one run after the other in this process) and as a sweep into a
fresh folder (``run_sweep``: a LocalCluster of N worker processes with one thread each, timed from
the cluster's start to the last row written), in the order serial, sweep, sweep, serial (``--rounds
2``), so that a load from other processes that drifts weighs on both alike. Both give the same
metrics (checked). The machine's load average is printed with the table: other processes on a
shared machine take cores from both measurements. Before them, the same code run in one process and
then in N processes at once, without dask (a Python loop, then 4 of the runs), gives the ceiling N
processes can reach on the machine at that time.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import inerter
from inerter.studies.sweep import DaskClient, Sweep, parse_vary, read_results, run_sweep

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenarios" / "lumped_mass_2d.toml"

SPIN = """import time
t = time.perf_counter()
x = 0
for i in range(20_000_000):
    x += i * i
print(time.perf_counter() - t)"""

SOLVE = """import time, inerter
t = time.perf_counter()
for overrides in {runs!r}:
    inerter.load({scene!r}, **overrides).simulate(stop_time={stop!r})
print(time.perf_counter() - t)"""


def ceiling(code: str, workers: int) -> float:
    """`workers` processes running `code` at once against one alone: 2.0 on two free cores for work that
    scales; less when other processes take cores, or when the work slows itself down (memory, caches)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")  # as dask workers

    def together(n):
        procs = [subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, env=env)
                 for _ in range(n)]
        return max(float(p.communicate()[0]) for p in procs)
    alone = together(1)
    return workers * alone / together(workers)


def serial(sweep: Sweep) -> tuple[float, dict, list[float]]:
    metrics, times = {}, []
    t0 = time.perf_counter()
    for run in sweep.runs():
        t = time.perf_counter()
        if sweep.model == "fmu":
            from inerter.fmu.run import simulate_fmu
            result = simulate_fmu(sweep.scene, run.overrides, stop_time=sweep.stop_time, step=sweep.step)
        else:
            result = inerter.load(sweep.scene, **run.overrides).simulate(stop_time=sweep.stop_time)
        times.append(time.perf_counter() - t)
        metrics[run.key] = {k: v for k, v in result.metrics.items() if isinstance(v, float)}
    return time.perf_counter() - t0, metrics, times


def parallel(sweep: Sweep, workers: int) -> tuple[float, float, dict, list[float]]:
    """(wall time to the last row written, of which cluster start-up; metrics; run times on the workers)."""
    with tempfile.TemporaryDirectory(prefix="sweep-throughput-") as folder:
        t0 = time.perf_counter()
        with DaskClient(workers) as client:
            client.wait_for_workers(workers)
            startup = time.perf_counter() - t0
            report = run_sweep(sweep, folder, client=client, progress=False)
            wall = time.perf_counter() - t0
        if report.failed:
            raise SystemExit(f"{report.failed} runs of the sweep failed")
        _, metric_names, rows = read_results(Path(folder) / "results.csv")
    metrics = {r["key"]: {k: float(r[k]) for k in metric_names if r.get(k)} for r in rows}
    return wall, startup, metrics, [float(r["run_time_s"]) for r in rows]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--runs", type=int, default=24, help="runs per measurement (even: each y0 with and without)")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--stop-time", type=float, default=10.0)
    p.add_argument("--model", choices=("solver", "fmu"), default="solver")
    p.add_argument("--rounds", type=int, default=2,
                   help="measurements of each, in the order serial, sweep, sweep, serial, ... (drifting load "
                        "from other processes then weighs on both alike)")
    p.add_argument("--out", default=str(ROOT / "docs" / "sweep_throughput.md"))
    args = p.parse_args(argv)
    n = max(1, args.runs // 2)
    sweep = Sweep(SCENE, [parse_vary(f"y0=1.05:1.5:{n}"), ("effects.centripetal", [True, False])],
                  model=args.model, stop_time=args.stop_time)
    runs = len(sweep.runs())
    load_before = os.getloadavg()[0]
    spin = ceiling(SPIN, args.workers)
    plain = ceiling(SOLVE.format(runs=[r.overrides for r in sweep.runs()[:4]], scene=str(SCENE),
                                 stop=args.stop_time), args.workers)
    print(f"{args.workers} processes at once against one alone: {spin:.2f}× (a Python loop), {plain:.2f}× "
          f"(4 of the runs, no dask)", flush=True)
    print(f"{runs} runs of {sweep.name} to t = {args.stop_time:g} s ({args.model}), {args.rounds} rounds", flush=True)
    t_serial = t_sweep = startup = 0.0
    per_serial, per_sweep, same = [], [], True
    order = []
    for r in range(args.rounds):
        order += ["serial", "sweep"] if r % 2 == 0 else ["sweep", "serial"]
    for what in order:
        if what == "serial":
            t, m_serial, per = serial(sweep)
            t_serial += t
            per_serial += per
        else:
            t, up, m_sweep, per = parallel(sweep, args.workers)
            t_sweep += t
            startup += up
            per_sweep += per
        print(f"  {what}: {t:.1f} s", flush=True)
    same = m_serial == m_sweep
    ratio = t_serial / t_sweep
    total = runs * args.rounds
    table = (
        "| | serial loop | sweep (dask) |\n|---|---|---|\n"
        f"| workers | 1 (this process) | {args.workers} processes × 1 thread (LocalCluster) |\n"
        f"| wall time for {total} runs (s) | {t_serial:.1f} | {t_sweep:.1f} (of which cluster start-up {startup:.1f}) |\n"
        f"| throughput (runs/min) | {60 * total / t_serial:.1f} | {60 * total / t_sweep:.1f} |\n"
        f"| mean time of one run (s) | {sum(per_serial) / total:.2f} | {sum(per_sweep) / total:.2f} (on its worker) |\n"
        f"| **sweep / serial throughput** | 1 | **{ratio:.2f}×** |\n"
        f"| ceiling: {args.workers} plain processes at once / one alone, a Python loop | 1 | {spin:.2f}× |\n"
        f"| ceiling: {args.workers} plain processes at once / one alone, 4 of the runs (no dask) | 1 | {plain:.2f}× |\n"
        f"| same metrics in both | | {'yes, exactly' if same else 'NO'} |\n")
    machine = (f"{os.cpu_count()} cores; 1-min load average {load_before:.2f} before, "
               f"{os.getloadavg()[0]:.2f} after")
    print()
    print(table)
    print(machine)
    text = (f"# Sweep throughput\n\n"
            f"Measured by `python benchmarks/sweep_throughput.py --runs {args.runs} --workers {args.workers} "
            f"--stop-time {args.stop_time:g} --model {args.model} --rounds {args.rounds}` on "
            f"{datetime.now(timezone.utc):%Y-%m-%d}: {runs} runs of `{sweep.name}` (y0 from 1.05 to 1.5 m, "
            f"with and without the centripetal correction, {args.stop_time:g} s each) as a serial loop in one "
            f"process and as a sweep on dask.distributed, side by side in one run, {args.rounds} times each "
            f"in the order {', '.join(order)}.\n\n"
            + table + f"\nMachine: {machine}. The load average counts other processes too: on a shared "
            "machine they take cores from both measurements. The two ceiling rows, measured just before, "
            f"run the same code in one process and then in {args.workers} processes at once, without dask: "
            "a Python loop that stays in the caches, and 4 of the solver runs (single-threaded BLAS, as in "
            f"the dask workers). They say what {args.workers} processes can gain on this machine at that "
            "time, whatever the sweep does; the gap between the second and the sweep is the sweep's own "
            "cost (cluster start-up, scheduling, the workers' event loops).\n")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(text)
    print(f"wrote {args.out}")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
