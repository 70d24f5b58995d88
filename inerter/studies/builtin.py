"""Built-in studies: ``inerter study fig9 | two_bar_b | two_bar_f --out DIR``.

Each study is a sweep (module `sweep`: same machinery, same ``results.csv``, resumable) of one
parameter of a paper scene, with and without the centripetal correction, followed by one figure:

- ``fig9``: the paper's Fig. 9. The lumped mass released from rest at y0 = 1.05 ... 1.5 m:
  (a) amplitude of the fundamental harmonic, (b) fundamental frequency, (c) mean position offset.
  With the correction the frequency falls from the natural frequency (1.518 Hz) and the mean
  offset falls (more negative) as y0 grows; without it both rise. The range stops at 1.5 m, the
  paper's example: released above y0 = sqrt((2·sqrt(2) − 1)² − 1) ≈ 1.531 m, the corrected
  (energy-conserving) model has more energy than the spring's barrier at y = 0 (compressed to
  La, ½k(sqrt(2) − 1)² ≈ 858 J), so the mass snaps through to the mirror well at y = −Lb and the
  metrics describe that other, inter-well, oscillation (mean offset −Lb); ``--range 1.05:1.8``
  shows it.
- ``two_bar_b``: the two-bar mechanism's steady-state peak-to-peak and mean offset of C along Y
  against the inertance b (0 ... 40 kg; with b = 0 both models are the same).
- ``two_bar_f``: the same against the excitation frequency f.
"""
from __future__ import annotations

import argparse
import math
from dataclasses import dataclass, field
from pathlib import Path

from inerter.studies.arguments import Parser
from inerter.studies.sweep import (SweepError, Sweep, _number, add_run_arguments, check_run_arguments, parse_vary,
                                   print_report, read_results, run_sweep, status_code)

from inerter.common.locations import scenarios as _shipped_scenarios
from inerter.common.options import OptionError

#: The shipped scenes: the repository's scenarios/, or their copy in an installed package.
REPO_SCENARIOS = _shipped_scenarios()
CORRECTION = "effects.centripetal"


@dataclass(frozen=True)
class Panel:
    metric: str
    label: str
    scale: float = 1.0                 # plotted value = metric × scale


@dataclass(frozen=True)
class Study:
    name: str
    scene: str                         # file name in scenarios/
    x: str                             # the varied parameter
    start: float
    stop: float
    points: int
    xlabel: str
    title: str
    panels: tuple[Panel, ...]
    fixed: dict = field(default_factory=dict)
    paper_x: float | None = None       # the value of the paper's example run, marked on the plot


STUDIES = {
    "fig9": Study(
        "fig9", "lumped_mass_2d.toml", "y0", 1.05, 1.5, 16, "initial position $y_0$ (m)",
        "Lumped mass (Zhu et al. 2022, Fig. 9): responses against the initial position",
        (Panel("fundamental_amplitude", "(a) amplitude of fundamental harmonic (m)"),
         Panel("fundamental_frequency", "(b) fundamental frequency (Hz)"),
         Panel("mean_offset", r"(c) mean position offset $\Delta\bar{y}$ (mm)", 1e3)),
        paper_x=1.5),
    "two_bar_b": Study(
        "two_bar_b", "two_bar_2d.toml", "b", 0.0, 40.0, 9, "inertance $b$ (kg)",
        "Two-bar mechanism: steady state of C along Y against the inertance",
        (Panel("C_y_peak_to_peak", "peak-to-peak of C along Y (mm)", 1e3),
         Panel("C_y_mean_offset", "mean offset of C along Y (mm)", 1e3)),
        fixed={"experiment.rtol": 1e-8}, paper_x=10.0),
    "two_bar_f": Study(
        "two_bar_f", "two_bar_2d.toml", "f", 0.5, 3.0, 11, "excitation frequency $f$ (Hz)",
        "Two-bar mechanism: steady state of C along Y against the excitation frequency",
        (Panel("C_y_peak_to_peak", "peak-to-peak of C along Y (mm)", 1e3),
         Panel("C_y_mean_offset", "mean offset of C along Y (mm)", 1e3)),
        fixed={"experiment.rtol": 1e-8}, paper_x=1.0),
}


def scene_path(study: Study, scenarios=None) -> Path:
    for folder in ([Path(scenarios)] if scenarios else [Path("scenarios"), REPO_SCENARIOS]):
        if (folder / study.scene).is_file():
            return folder / study.scene
    raise SweepError(f"{study.scene}: not found in {scenarios or 'scenarios/ nor ' + str(REPO_SCENARIOS)}"
                     " (give the folder with --scenarios)")


def make_sweep(study: Study, scenarios=None, points=None, span=None, fixed=None, model="solver",
               stop_time=None, step=None, path="compiled", origins=None) -> Sweep:
    n = points or study.points
    start, stop = span or (study.start, study.stop)
    _, xs = parse_vary(f"{study.x}={start}:{stop}:{n}")
    return Sweep(scene_path(study, scenarios), [(study.x, xs), (CORRECTION, [True, False])],
                 {**study.fixed, **(fixed or {})}, model, stop_time, step, path, origins=dict(origins or {}))


def study_table(study: Study, sweep: Sweep, results_csv) -> dict:
    """{centripetal (bool): [(x, {metric: value}), ...]} for the runs of this sweep that are ok."""
    _, _, rows = read_results(results_csv)
    by_key = {r["key"]: r for r in rows}
    table = {True: [], False: []}
    for run in sweep.runs():
        row = by_key.get(run.key)
        if row is None or row.get("status") != "ok":
            continue
        values = {p.metric: _number(row.get(p.metric, "")) for p in study.panels}
        values["natural_frequency"] = _number(row.get("natural_frequency", ""))
        table[bool(run.overrides[CORRECTION])].append((float(run.overrides[study.x]), values))
    for v in table.values():
        v.sort(key=lambda item: item[0])
    return table


def plot_study(study: Study, table: dict, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = len(study.panels)
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n, 4.0), squeeze=False)
    styles = {True: dict(color="C0", ls="-", marker="o", label="with centripetal correction (Eq. 9)"),
              False: dict(color="C3", ls="--", marker="s", label="without correction (Eq. 8)")}
    for ax, panel in zip(axes[0], study.panels):
        for corrected in (True, False):
            rows = table[corrected]
            if rows:
                xs = [x for x, _ in rows]
                ys = [v[panel.metric] * panel.scale for _, v in rows]
                ax.plot(xs, ys, ms=4, lw=1.4, **styles[corrected])
        if panel.metric == "fundamental_frequency":
            fn = [v["natural_frequency"] for rows in table.values() for _, v in rows]
            if fn:
                ax.axhline(fn[0], color="0.4", lw=0.8, ls=":", label=f"natural frequency {fn[0]:.4f} Hz")
        if study.paper_x is not None:
            ax.axvline(study.paper_x, color="0.7", lw=0.8, ls="-.", zorder=0)
        ax.set_xlabel(study.xlabel)
        ax.set_title(panel.label, fontsize=10)
        ax.grid(alpha=0.3)
    handles, labels = [], []
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=9, frameon=False)
    fig.suptitle(study.title + (f" (dash-dot: the paper's example, {study.x} = {study.paper_x:g})"
                                if study.paper_x is not None else ""), fontsize=11)
    fig.tight_layout(rect=(0, 0.07, 1, 0.95))
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=130)
    plt.close(fig)
    return Path(out)


def print_table(study: Study, table: dict):
    """The study's metrics, with (on) and without (off) the correction, one line per value of x."""
    sides = {"on": dict(table[True]), "off": dict(table[False])}
    columns = [(p.metric, side) for p in study.panels for side in sides]
    print(f"  {study.x:>8s}" + "".join(f" {f'{m} ({side})':>28s}" for m, side in columns))
    for x in sorted(set(sides["on"]) | set(sides["off"])):
        cells = [sides[side].get(x, {}).get(m) for m, side in columns]
        print(f"  {x:8.4g}" + "".join(f" {v:28.6g}" if v is not None else f" {'-':>28s}" for v in cells))


def study_parser() -> argparse.ArgumentParser:
    """The options of ``inerter study``."""
    p = Parser(prog="inerter study", description="Built-in studies: a sweep with and "
               "without the centripetal correction, then one figure. " + ", ".join(
                   f"{s.name}: {s.x} of {s.scene}" for s in STUDIES.values()))
    p.add_argument("study", choices=sorted(STUDIES), help="the study: " + ", ".join(sorted(STUDIES)))
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder of results.csv and the figure (default out/study/NAME); resumed if present")
    p.add_argument("--points", type=int, default=None, help="number of values of the varied parameter")
    p.add_argument("--range", default=None, metavar="START:STOP", help="range of the varied parameter")
    p.add_argument("--scenarios", default=None, help="folder of the scene files (default scenarios/)")
    add_run_arguments(p)
    return p


def main(argv=None) -> int:
    from inerter.scene.overrides import parse_set, set_origins
    args = study_parser().parse_args(argv)
    study = STUDIES[args.study]
    span = None
    if args.range:
        try:
            a, b = (float(v) for v in args.range.split(":"))
        except ValueError:
            raise SweepError(f"--range {args.range}: expected START:STOP, e.g. 1.05:1.8") from None
        if not (math.isfinite(a) and math.isfinite(b)) or a == b:
            raise OptionError("--range", args.range, "finite START ≠ STOP, e.g. 1.05:1.8",
                              "empty range" if a == b else "out of range")
        span = (a, b)
    if args.points is not None and args.points < 2:
        raise SweepError(f"--points {args.points}: expected at least 2")
    if args.out is None:
        args.out = str(Path("out") / "study" / study.name)
    check_run_arguments(args)
    out = Path(args.out)
    sweep = make_sweep(study, args.scenarios, args.points, span, parse_set(args.set), args.model,
                       args.stop_time, args.step, args.path, origins=set_origins(args.set))
    report = run_sweep(sweep, out, workers=args.workers, scheduler=args.scheduler,
                       progress=not args.no_progress, max_runs=args.max_runs, retry_failed=args.retry_failed,
                       dashboard=args.dashboard)
    print_report(report, sweep)
    table = study_table(study, sweep, out / "results.csv")
    print_table(study, table)
    if table[True] or table[False]:
        png = plot_study(study, table, out / f"{study.name}.png")
        print(f"wrote {png}")
    return status_code(report)


def main_study(argv=None) -> int:
    """``inerter study NAME``: a built-in study (module `studies`)."""
    from inerter.studies.sweep import _guarded
    return _guarded(main, argv)
