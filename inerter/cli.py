"""Command line: ``inerter run | compare | describe | build-fmu | build-system | paper | compile``."""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from inerter.common.errors import InerterError
from inerter.scene.overrides import parse_set  # noqa: F401  (the CLI's --set)

PAPER_SCENES = ("lumped_mass_2d", "two_bar_2d")


class OptionError(InerterError):
    """A command-line option has a value the command cannot use; the message reads
    ``<option>: <problem> (got <value>; expected <expected>)``, like a scene error's."""

    def __init__(self, option: str, value, expected: str, problem: str = "out of range"):
        super().__init__(f"{option}: {problem} (got {value!r}; expected {expected})")


def _check_options(args):
    """The solver options, checked before anything runs (the scene's own fields are checked by
    its reader, with the same ranges)."""
    from inerter.scene.reader import METHODS
    for option, name, unit in (("--stop-time", "stop_time", "s"), ("--step", "step", "s")):
        value = getattr(args, name, None)
        if value is not None and not (math.isfinite(value) and value > 0):
            raise OptionError(option, value, f"a finite number > 0 ({unit})")
    rtol = getattr(args, "rtol", None)
    if rtol is not None and not (math.isfinite(rtol) and 1e-14 <= rtol <= 0.1):
        raise OptionError("--rtol", rtol, "a relative tolerance in [1e-14, 0.1]")
    method = getattr(args, "method", None)
    if method is not None and method not in METHODS:
        raise OptionError("--method", method, "one of: " + ", ".join(METHODS), "unknown value")


def _out_dir(path) -> Path:
    """The output folder, made before anything is computed."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OptionError("--out", str(path), "a folder that can be created and written",
                          f"cannot create the output folder: {exc.strerror or exc}") from None
    return out


def _write(result, out: Path, stem: str, label: str | None = None):
    out.mkdir(parents=True, exist_ok=True)
    result.write_csv(out / f"{stem}.csv")
    summary = result.summary()
    if label:
        summary["label"] = label
    (out / f"{stem}.summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def simulate(scene, overrides, model_kind, args):
    """Run one scene through the solver, the oracle or its FMU; returns a Result."""
    from inerter.api import ORACLE_ATOL, ORACLE_RTOL, load
    kw = dict(stop_time=args.stop_time, method=args.method, rtol=args.rtol)
    if model_kind == "fmu":
        from inerter.fmu.run import simulate_fmu
        solver = {f"experiment.{k}": getattr(args, k) for k in ("method", "rtol") if getattr(args, k, None)}
        return simulate_fmu(scene, dict(overrides, **solver), stop_time=args.stop_time, step=args.step)
    model = load(scene, **overrides)
    if model_kind == "oracle":
        model = model.oracle()
        kw.update(rtol=args.rtol or ORACLE_RTOL, atol=ORACLE_ATOL, method="DOP853")
    else:
        kw["path"] = getattr(args, "path", "numpy")
    return model.simulate(**kw)


def cmd_run(args):
    _animation(args)
    overrides = parse_set(args.set)
    out = _out_dir(args.out)
    t0 = time.perf_counter()
    result = simulate(args.scene, overrides, args.model, args)
    wall = time.perf_counter() - t0
    for warning in result.model.scene.warnings:
        print(f"inerter: warning: {warning}", file=sys.stderr)
    stem = result.model.name
    summary = _write(result, out, stem)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    from inerter.studies.plotting import plot_runs
    plot_runs([(args.model, result, {})], out / f"{stem}.png", f"{stem} ({args.model})")
    print(f"{stem}: {result.status} ({result.message}); {len(result.time)} samples to t = "
          f"{result.time[-1]:.6g} s in {wall:.2f} s wall; path: {summary['statistics']['path']}")
    units = summary.get("metric_units", {})
    for k, v in summary["metrics"].items():
        print(f"  {k} = {_with_unit(v, units.get(k))}")
    for k, v in summary.get("metric_errors", {}).items():
        print(f"  {k}: not computed: {v}")
    print(f"  max constraint drift = {summary['statistics']['max_constraint_drift']:.3g}")
    print(f"wrote {out / (stem + '.csv')}, {out / 'summary.json'}, {out / (stem + '.png')}")
    _animation(args, result, out / f"{stem}.{args.animate}")
    return 0 if result.status == "ok" else 3


# -- run --animate --------------------------------------------------------------------------------
def _animation_options(sp):
    sp.add_argument("--animate", nargs="?", const="gif", choices=("gif", "html"), default=None,
                    help="also write an animation of the run beside its CSV: <scene>.gif (the default) or "
                         "<scene>.html, a self-contained page")
    sp.add_argument("--fps", type=float, default=None, help="the animation's frames per second (default 25)")
    sp.add_argument("--duration", type=float, default=None,
                    help="the animation's length in seconds (default: the run's own; at most 300 frames, "
                         "played faster if more are asked for)")
    sp.add_argument("--magnify", type=float, default=None,
                    help="draw displacements from the initial pose this many times (default 1)")


def _animation(args, result=None, path: Path | None = None):
    """With --animate: the animation of `result` at `path` (inerter.studies.animation); without a
    result, the options checked before the run."""
    from inerter.studies.animation import DEFAULT_FPS, animate, check_options
    if args.animate is None:
        for option in ("fps", "duration", "magnify"):
            if getattr(args, option) is not None:
                raise OptionError(f"--{option}", getattr(args, option), "--animate beside it", "no animation asked for")
        return
    if result is None:
        return check_options(DEFAULT_FPS if args.fps is None else args.fps, args.duration,
                             1.0 if args.magnify is None else args.magnify,
                             {"fps": "--fps", "duration": "--duration", "magnify": "--magnify"})
    print(f"inerter: drawing the animation {path.name}...", file=sys.stderr, flush=True)
    frames = animate(result, path, fps=DEFAULT_FPS if args.fps is None else args.fps, duration=args.duration,
                     magnify=1.0 if args.magnify is None else args.magnify)
    print(f"wrote {path}: {frames.describe()}" + "".join(f"; {note}" for note in frames.notes))
# ----------------------------------------------------------------------------------------------------


def _with_unit(value, unit) -> str:
    """A metric's value for the console, with its unit (none for a dimensionless one)."""
    return f"{value} {unit}" if unit and unit != "1" else str(value)


def cmd_compare(args):
    """With and without the centripetal correction (and the oracle, and the FMU with --model fmu)."""
    overrides = parse_set(args.set)
    out = _out_dir(args.out)
    runs, summaries = [], {}
    variants = [("corrected", True), ("uncorrected", False)]
    for label, cen in variants:
        ov = dict(overrides, **{"effects.centripetal": cen})
        res = simulate(args.scene, ov, args.model, args)
        runs.append((f"{label} ({args.model})", res, {"lw": 1.2}))
        summaries[label] = _write(res, out, f"{res.model.name}_{label}", label)
    oracle = simulate(args.scene, dict(overrides, **{"effects.centripetal": True}), "oracle", args)
    summaries["oracle"] = _write(oracle, out, f"{oracle.model.name}_oracle", "oracle")
    runs.append(("oracle (corrected)", oracle, {"lw": 0.8, "ls": "--", "color": "k"}))
    name = runs[0][1].model.name
    corrected = runs[0][1]
    diff = max_difference(corrected, oracle)
    summaries["max_difference_to_oracle_m"] = diff if math.isfinite(diff) else None   # JSON has no NaN
    (out / "summary.json").write_text(json.dumps({"scene": name, "runs": summaries}, indent=2))
    from inerter.studies.plotting import plot_runs
    png = plot_runs(runs, out / f"{name}_compare.png", f"{name}: with and without the centripetal term")
    print(f"{name}:")
    keys = sorted(set(summaries["corrected"]["metrics"]) | set(summaries["uncorrected"]["metrics"]))
    units = {**summaries["uncorrected"].get("metric_units", {}), **summaries["corrected"].get("metric_units", {})}
    print(f"  {'metric':32s} {'unit':>6s} {'corrected':>16s} {'uncorrected':>16s} {'oracle':>16s}")
    for k in keys:
        vals = [summaries[v]["metrics"].get(k) for v in ("corrected", "uncorrected", "oracle")]
        if any(isinstance(v, list) for v in vals):
            continue
        print(f"  {k:32s} {units.get(k, ''):>6s} "
              + " ".join(f"{v:16.6g}" if v is not None else f"{'-':>16s}" for v in vals))
    print(f"  largest |{args.model} − oracle| over point positions: "
          + (f"{diff:.3g} m" if math.isfinite(diff) else "not computed (the runs' time grids differ)"))
    print(f"wrote {png} and {out / 'summary.json'}")
    return 0 if all(r.status == "ok" for _, r, _ in runs) else 3


def max_difference(a, b) -> float:
    """Largest difference of point positions between two results on the same time grid."""
    n = min(len(a.time), len(b.time))
    if n == 0 or not np.allclose(a.time[:n], b.time[:n], rtol=0, atol=1e-9):
        return float("nan")
    names = [k for k in a.names if ".r[" in k]
    return float(max(np.max(np.abs(a[k][:n] - b[k][:n])) for k in names))


def cmd_describe(args):
    from inerter.api import load
    model = load(args.scene, **parse_set(args.set))
    print(f"{model.name}: {model.scene.description}")
    print("compiled terms:")
    for line in model.terms():
        print("  " + line)
    print("parameters:")
    for p in model.parameter_info():
        print(f"  {p['name']} = {p['value']:g} {p['unit']}  {p['description']}")
    print("inputs: " + (", ".join(i["name"] for i in model.input_info()) or "none"))
    print("outputs: " + ", ".join(o["name"] for o in model.output_info()))
    return 0


def cmd_build_fmu(args):
    from inerter.fmu.build import main as build_main
    return build_main(args.scenes + (["--force"] if args.force else []))


def cmd_build_system(args):
    """The coupled example as system-structure files beside its two FMUs."""
    from inerter.fmu.cosim import build_system
    paths = build_system(args.out_dir, step=args.step or 0.01)
    for role in ("plant", "controller", "osp", "ssd"):
        print(f"{role}: {paths[role]}")
    return 0


def paper_scenes(folder=None) -> list[Path]:
    """The paper's scene files in `folder`, by default the scenes shipped with inerter (the
    repository's scenarios/, or their copy in an installed package); both checked before any run."""
    from inerter.common.locations import scenarios
    root = Path(folder) if folder else scenarios()
    paths = [root / f"{name}.toml" for name in PAPER_SCENES]
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise OptionError("--scenarios", str(root), "a folder holding " + " and ".join(p.name for p in paths),
                          "no " + " nor ".join(missing) + " there")
    return paths


def cmd_paper(args):
    """The main job: both paper scenes end to end, with and without the correction."""
    status = 0
    for scene in paper_scenes(args.scenarios):
        ns = argparse.Namespace(scene=str(scene), set=[], out=str(Path(args.out) / scene.stem),
                                model=args.model, stop_time=None, method=None, rtol=None, step=None)
        status |= cmd_compare(ns)
    return status


def cmd_compile(args):
    """Compile the engine's kernels ahead of time into the kernel cache, so that no later run, sweep
    worker or FMU instance on this machine compiles them (the set-up runs it: Makefile)."""
    from inerter.api import warm_up
    from inerter.engine import compiled
    if not compiled.AVAILABLE:
        print(f"inerter compile: nothing to compile: {compiled.WHY_NOT}")
        return 0
    dims = (2,) if args.planar else (2, 3)
    label = " and ".join(f"{d}D" for d in dims)
    print(f"inerter: compiling the engine's {label} kernels for this machine where the cache lacks them "
          f"(once per version of the kernels; about {sum(compiled.AOT_SECONDS[d] for d in dims)} s on 2 "
          f"cores)...", file=sys.stderr, flush=True)
    compiled.NOTICE.enabled = False                 # said once here, not per kernel
    before = compiled.NOTICE.seconds
    try:
        seconds = warm_up(spatial=not args.planar)
    finally:
        compiled.NOTICE.enabled = True
    fresh = compiled.NOTICE.seconds > before        # some kernel was not in the cache
    print(f"inerter: ... done in {seconds:.0f} s" + ("" if fresh else " (all were in the cache)"), file=sys.stderr)
    print(f"{label} kernels {'compiled' if fresh else 'loaded'} in {seconds:.1f} s; cache: "
          f"{Path(compiled._k.__file__).parent}")
    return 0


#: Subcommands whose arguments their own module parses.
DELEGATED = {
    "bench": ("studies.bench", "main_bench", "work-precision diagrams: error against the oracle vs CPU time"),
    "sweep": ("studies.sweep", "main_sweep", "parameter sweeps on dask, resumable"),
    "study": ("studies.builtin", "main_study", "built-in studies: fig9, two_bar_b, two_bar_f"),
    "sweep-plot": ("studies.sweep", "main_sweep_plot", "plot a metric of a sweep's results against a parameter"),
}


def build_parser():
    p = argparse.ArgumentParser(prog="inerter", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)

    def common(sp, out_default="out"):
        sp.add_argument("--set", action="append", metavar="NAME=VALUE",
                        help="override a parameter, effects.NAME or experiment.NAME (repeatable)")
        sp.add_argument("--out", default=out_default, help="output folder")
        sp.add_argument("--model", choices=("solver", "oracle", "fmu"), default="solver")
        sp.add_argument("--stop-time", type=float, default=None)
        sp.add_argument("--method", default=None)
        sp.add_argument("--rtol", type=float, default=None)
        sp.add_argument("--step", type=float, default=None, help="FMU communication step (s)")
        sp.add_argument("--path", choices=("numpy", "compiled"), default="compiled",
                        help="the solver's path: compiled (the default: numba kernels and integrator loops, 2D "
                             "and 3D; falls back to numpy where it cannot take the scene, Z-X-Z Euler angles) or "
                             "numpy (the readable reference)")

    r = sub.add_parser("run", help="simulate a scene: CSV, summary.json and a PNG")
    r.add_argument("scene")
    common(r)
    _animation_options(r)
    r.set_defaults(func=cmd_run)
    c = sub.add_parser("compare", help="with and without the centripetal correction, and the oracle")
    c.add_argument("scene")
    common(c)
    c.set_defaults(func=cmd_compare)
    d = sub.add_parser("describe", help="what a scene compiles to: terms, parameters, inputs, outputs")
    d.add_argument("scene")
    d.add_argument("--set", action="append", metavar="NAME=VALUE")
    d.set_defaults(func=cmd_describe)
    b = sub.add_parser("build-fmu", help="build FMI 2.0 co-simulation FMUs (only when stale)")
    b.add_argument("scenes", nargs="+")
    b.add_argument("--force", action="store_true")
    b.set_defaults(func=cmd_build_fmu)
    y = sub.add_parser("build-system", help="the two-bar FMU and the PD-controller FMU coupled, as an OSP "
                                           "system structure and an SSP SystemStructure.ssd (libcosim reads both)")
    y.add_argument("-o", "--out-dir", default="build/system", help="where the FMUs and the files go (default: %(default)s)")
    y.add_argument("--step", type=float, default=None, help="communication step (s; default 0.01)")
    y.set_defaults(func=cmd_build_system)
    for name, (module, func, text) in DELEGATED.items():
        sub.add_parser(name, help=text + f" (inerter {name} -h)")
    pp = sub.add_parser("paper", help="both paper scenes end to end (the main job)")
    pp.add_argument("--out", default="out/paper")
    pp.add_argument("--scenarios", default=None,
                    help="folder holding lumped_mass_2d.toml and two_bar_2d.toml (default: the scenes "
                         "shipped with inerter)")
    pp.add_argument("--model", choices=("solver", "fmu"), default="solver")
    pp.set_defaults(func=cmd_paper)
    k = sub.add_parser("compile", help="compile the engine's kernels ahead of time (the set-up does it once)")
    k.add_argument("--planar", action="store_true", help="only the 2D kernels")
    k.set_defaults(func=cmd_compile)
    return p


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in DELEGATED:
        import importlib
        module, func, _ = DELEGATED[argv[0]]
        return getattr(importlib.import_module(f"inerter.{module}"), func)(argv[1:])
    args = build_parser().parse_args(argv)
    try:
        _check_options(args)
        return args.func(args)
    except InerterError as exc:
        print(f"inerter: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:            # an output file that cannot be written
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"inerter: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
