"""The ``inerter`` command: one function per command (``cmd_run`` ...), the parser, and ``main``,
which turns every error a user can cause into one line on stderr and exit status 2."""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from inerter.common.errors import InerterError, SceneError
from inerter.studies.arguments import Parser as _Parser
from inerter.common.options import OptionError, output_path, unwritable
from inerter.scene.overrides import parse_set, read_value, set_origins
from inerter.scene.reader import METHODS
from inerter.scene.units import for_reading

PAPER_SCENES = ("lumped_mass_2d", "two_bar_2d")

#: The solver options of ``run`` and ``compare``: each is the experiment field it overrides, read
#: and checked by the scene reader like the scene's own value (one function for both).
OPTIONS = {"stop_time": ("--stop-time", "experiment.stop_time"),
           "method": ("--method", "experiment.method"),
           "rtol": ("--rtol", "experiment.rtol"),
           "step": ("--step", "experiment.communication_step")}


def overrides_of(args) -> dict:
    """``--set`` and the solver options as the overrides of one load: ``--stop-time 5`` is
    ``experiment.stop_time = 5``, its text read as a ``--set`` value is (a number or an expression)."""
    overrides = parse_set(getattr(args, "set", None))
    for attr, (_, key) in OPTIONS.items():
        text = getattr(args, attr, None)
        if text is not None:
            overrides[key] = read_value(text)
    return overrides


def _step_with_fmu(args):
    """--step without --model fmu: refused by the check sweeps and studies use (one message)."""
    from inerter.studies.sweep import check_fmu_step
    check_fmu_step(getattr(args, "step", None), args.model)


def origins_of(args) -> dict:
    """Where each override of :func:`overrides_of` came from, as an error names it: ``--set
    lead=0`` as typed, ``--stop-time`` for ``experiment.stop_time`` (its value is the field's)."""
    origins = set_origins(getattr(args, "set", None))
    for attr, (option, key) in OPTIONS.items():
        if getattr(args, attr, None) is not None:
            origins[key] = option
    return origins


def _load(args, overrides: dict | None = None):
    """The scene of `args` with its overrides, a refused value named by the option that gave it."""
    from inerter.api import Model
    return Model(args.scene, overrides_of(args) if overrides is None else overrides, origins=origins_of(args))


def _option_for(args, exc: SceneError) -> str | None:
    """The option that gave the field of `exc` its value, where the scene reader did not name it
    (an error of the FMU's start values): ``--stop-time`` for ``experiment.stop_time``, ``--set b=2``
    for ``parameters.b`` (and ``parameters.b.unit``)."""
    origins = origins_of(args)
    head = str(exc).split(f"{exc.field}:", 1)[0]
    if any(origin in head for origin in origins.values()):
        return None                                   # the scene reader named it
    for key, origin in origins.items():
        for path in (key, f"parameters.{key}"):
            if exc.field == path or exc.field.startswith((path + ".", path + "[")):
                return origin
    return None


def _out_dir(path) -> Path:
    """The output folder, made before anything is computed."""
    out = output_path(path)
    if out.exists() and not out.is_dir():
        raise OptionError("--out", str(path), "a folder (or a path where one can be made)",
                          "names an existing file")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OptionError("--out", str(path), "a folder that can be created and written",
                          f"cannot create the output folder: {exc.strerror or exc}") from None
    return out


def _write(result, out: Path, stem: str, label: str | None = None, summary: dict | None = None):
    """Write `result`'s CSV and its summary (`summary`, else ``result.summary()``) to `out`."""
    out.mkdir(parents=True, exist_ok=True)
    result.write_csv(out / f"{stem}.csv")
    summary = summary if summary is not None else result.summary()
    if label:
        summary["label"] = label
    (out / f"{stem}.summary.json").write_text(json.dumps(summary, indent=2))
    return summary


def simulate(scene, overrides, model_kind, path="compiled", model=None):
    """Run one scene through the solver, the oracle or its FMU; returns a Result. `model`: the
    scene already loaded with `overrides` (solver and oracle)."""
    from inerter.api import ORACLE_ATOL, ORACLE_RTOL, load
    if model_kind == "fmu":
        from inerter.fmu.run import simulate_fmu
        return simulate_fmu(scene, overrides)
    model = model or load(scene, **overrides)
    if model_kind == "oracle":
        rtol = None if "experiment.rtol" in overrides else ORACLE_RTOL
        return model.oracle().simulate(rtol=rtol, atol=ORACLE_ATOL, method="DOP853")
    return model.simulate(path=path)


def _span(result) -> str:
    """How far a run got, for the one-line report."""
    if len(result.time) == 0:
        return "no samples"
    return f"{len(result.time)} samples to t = {result.time[-1]:.6g} s"


def _report_stop(result, scene, out, label: str = "") -> int:
    """Exit status of a run: 0 if it reached its stop time; else 3, with one line on stderr saying
    where and why it stopped and where its results up to then are (the full report is on stdout)."""
    if result.status == "ok":
        return 0
    reached = f"t = {result.time[-1]:.6g} s" if len(result.time) else "no sample"
    reason = " ".join(str(result.message).split())           # one line, whatever the message holds
    print(f"inerter: error: {scene}: {label}the run stopped before its stop time ({reason}); "
          f"results up to {reached} written in {out}", file=sys.stderr)
    return 3


def cmd_run(args):
    _animation(args)                                  # its options checked before the run
    _step_with_fmu(args)
    overrides = overrides_of(args)
    model = _load(args, overrides)                   # every value checked before --out is made
    out = _out_dir(args.out)
    t0 = time.perf_counter()
    result = simulate(args.scene, overrides, args.model, args.path, model)
    wall = time.perf_counter() - t0
    for warning in result.warnings:
        print(f"inerter: warning: {warning}", file=sys.stderr)
    stem = result.model.name
    # Every output at every sample first: one undefined at a sample ends the result there, and the
    # summary says so. Then the result on the terminal, then the files: the CSV's text and the plot
    # (matplotlib's import) take about 0.6 s of a warm process (docs/benchmarks/first_use.md).
    result.values()
    summary = result.summary()
    print(f"{stem}: {result.status} ({result.message}); {_span(result)} in {wall:.2f} s wall; "
          f"path: {summary['statistics']['path']}")
    units = summary.get("metric_units", {})
    for k, v in summary["metrics"].items():
        print(f"  {k} = {_with_unit(v, units.get(k))}")
    for k, v in summary.get("metric_errors", {}).items():
        print(f"  {k}: not computed: {v}")
    print(f"  max constraint drift = {summary['statistics']['max_constraint_drift']:.3g}", flush=True)
    _write(result, out, stem, summary=summary)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    written = [out / (stem + ".csv"), out / "summary.json"]
    if len(result.time):              # the plot after the result is on the terminal (matplotlib loads slowly)
        from inerter.studies.plotting import plot_runs
        written.append(plot_runs([(args.model, result, {})], out / f"{stem}.png", f"{stem} ({args.model})"))
    print("wrote " + ", ".join(str(w) for w in written))
    if len(result.time):
        _animation(args, result, out / f"{stem}.{args.animate}")
    return _report_stop(result, args.scene, out)


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
    if args.animate is None:
        for option in ("fps", "duration", "magnify"):
            if getattr(args, option) is not None:
                raise OptionError(f"--{option}", getattr(args, option), "--animate beside it", "no animation asked for")
        return
    from inerter.studies.animation import DEFAULT_FPS, animate, check_options
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
    return f"{value} {for_reading(unit)}" if for_reading(unit) else str(value)


def cmd_compare(args):
    """With and without the centripetal correction (and the oracle, and the FMU with --model fmu)."""
    _step_with_fmu(args)
    overrides = overrides_of(args)
    _load(args, overrides)                           # every value checked before --out is made
    out = _out_dir(args.out)
    runs, summaries = [], {}
    variants = [("corrected", True), ("uncorrected", False)]
    for label, cen in variants:
        ov = dict(overrides, **{"effects.centripetal": cen})
        res = simulate(args.scene, ov, args.model, args.path)
        runs.append((f"{label} ({args.model})", res, {"lw": 1.2}))
        summaries[label] = _write(res, out, f"{res.model.name}_{label}", label)
    if args.model == "oracle":                # its corrected run is the oracle's: not run a second time
        oracle = runs[0][1]
        summaries["oracle"] = summaries["corrected"]
    else:
        oracle = simulate(args.scene, dict(overrides, **{"effects.centripetal": True}), "oracle")
        summaries["oracle"] = _write(oracle, out, f"{oracle.model.name}_oracle", "oracle")
        runs.append(("oracle (corrected)", oracle, {"lw": 0.8, "ls": "--", "color": "k"}))
    name = runs[0][1].model.name
    corrected = runs[0][1]
    diff = max_difference(corrected, oracle)
    summaries["max_difference_to_oracle_m"] = (diff if math.isfinite(diff) and args.model != "oracle"
                                               else None)                           # JSON has no NaN
    (out / "summary.json").write_text(json.dumps({"scene": name, "runs": summaries}, indent=2))
    from inerter.studies.plotting import plot_runs
    png = (plot_runs(runs, out / f"{name}_compare.png", f"{name}: with and without the centripetal term")
           if all(len(r.time) for _, r, _ in runs) else "no plot (a run has no samples)")
    print(f"{name}:")
    keys = sorted(set(summaries["corrected"]["metrics"]) | set(summaries["uncorrected"]["metrics"]))
    units = {**summaries["uncorrected"].get("metric_units", {}), **summaries["corrected"].get("metric_units", {})}
    print(f"  {'metric':32s} {'unit':>6s} {'corrected':>16s} {'uncorrected':>16s} {'oracle':>16s}")
    for k in keys:
        vals = [summaries[v]["metrics"].get(k) for v in ("corrected", "uncorrected", "oracle")]
        if any(isinstance(v, list) for v in vals):
            continue
        print(f"  {k:32s} {for_reading(units.get(k)):>6s} "
              + " ".join(f"{v:16.6g}" if v is not None else f"{'-':>16s}" for v in vals))
    errors = {}                                # a metric not computed: why, and in which runs (as run says)
    for variant in ("corrected", "uncorrected", "oracle"):
        for k, why in summaries[variant].get("metric_errors", {}).items():
            errors.setdefault(k, (why, []))[1].append(variant)
    for k, (why, where) in errors.items():
        print(f"  {k}: not computed ({', '.join(where)}): {why}")
    if args.model != "oracle":
        print(f"  largest |{args.model} − oracle| over point positions: "
              + (f"{diff:.3g} m" if math.isfinite(diff) else "not computed (the runs' time grids differ)"))
    print(f"wrote {png} and {out / 'summary.json'}")
    stopped = [(label.split(" (")[0], result) for label, result, _ in runs if result.status != "ok"]
    if not stopped:
        return 0
    more = f" (and {', '.join(label for label, _ in stopped[1:])})" if len(stopped) > 1 else ""
    return _report_stop(stopped[0][1], args.scene, out, f"{stopped[0][0]}{more}: ")


def max_difference(a, b) -> float:
    """Largest difference of point positions between two results on the same time grid."""
    n = min(len(a.time), len(b.time))
    if n == 0 or not np.allclose(a.time[:n], b.time[:n], rtol=0, atol=1e-9):
        return float("nan")
    names = [k for k in a.names if ".r[" in k]
    return float(max(np.max(np.abs(a[k][:n] - b[k][:n])) for k in names))


def cmd_describe(args):
    print(_load(args, parse_set(args.set)).describe())
    return 0


def cmd_build_fmu(args):
    from inerter.fmu import build
    out = _out_dir(args.out)
    failed = build.run(argparse.Namespace(scenes=args.scenes, out_dir=str(out), force=args.force))
    return 2 if failed else 0          # a scene that cannot be built: its error is on stderr


def cmd_build_system(args):
    """The coupled example as system-structure files beside its two FMUs."""
    from inerter.fmu.cosim import build_system
    output_path(args.out_dir, "--out-dir")
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
    output_path(args.out)
    for scene in paper_scenes(args.scenarios):
        ns = argparse.Namespace(scene=str(scene), set=[], out=str(Path(args.out) / scene.stem),
                                model=args.model, stop_time=None, method=None, rtol=None, step=None,
                                path="compiled")
        status |= cmd_compare(ns)
    return status


def cmd_compile(args):
    """Compile the engine's kernels ahead of time into the kernel cache, so that no later run, sweep
    worker or FMU instance on this machine compiles them, and the package's bytecode
    (:func:`write_bytecode`); the set-up runs it (Makefile)."""
    from inerter.api import warm_up
    from inerter.engine import compiled
    if not compiled.AVAILABLE:
        write_bytecode()
        print(f"inerter compile: no kernels to compile: {compiled.WHY_NOT}")
        return 0
    dims = (2,) if args.planar else (2, 3)
    parallel = (os.cpu_count() or 1) > 1           # 2D and 3D side by side (warm_up)
    label = " and ".join(f"{d}D" for d in dims)
    expected = (max if parallel else sum)(compiled.AOT_SECONDS[d] for d in dims)
    print(f"inerter: compiling the engine's {label} kernels for this machine where the cache lacks them "
          f"(once per version of the kernels; about {expected} s on 2 cores)...", file=sys.stderr, flush=True)
    compiled.NOTICE.enabled = False                 # said once here, not per kernel
    before = compiled.NOTICE.seconds
    try:
        seconds = warm_up(spatial=not args.planar, parallel=parallel)
    finally:
        compiled.NOTICE.enabled = True
    fresh = compiled.NOTICE.seconds > before        # some kernel was not in the cache
    print(f"inerter: ... done in {seconds:.0f} s" + ("" if fresh else " (all were in the cache)"), file=sys.stderr)
    print(f"{label} kernels {'compiled' if fresh else 'loaded'} in {seconds:.1f} s; cache: "
          f"{Path(compiled._k.__file__).parent}")
    _build_ahead(dims, parallel)
    if not write_bytecode():
        print("inerter compile: the package's bytecode could not be written beside its sources "
              "(each process compiles them when it starts)", file=sys.stderr)
    return 0


def _build_ahead(dims, parallel):
    """The kernels a run enters, built ahead of time for this machine where it lacks them
    (:func:`inerter.api.build_ahead`); a dimension that cannot be built is said, not fatal."""
    from inerter.api import build_ahead
    from inerter.engine import ahead, compiled
    if all(ahead.built(compiled._k, d) for d in dims):
        return
    expected = ahead.BUILD_SECONDS * (1 if parallel else len(dims))
    print(f"inerter: building the kernels a run enters from Python for this machine, so that a process loads "
          f"them at once (about {expected} s on 2 cores)...", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    outcome = build_ahead(dims, parallel)
    print(f"inerter: ... done in {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    for d, why in outcome.items():
        if why is not None:
            print(f"inerter compile: the {d}D kernels could not be built ahead of time ({why}); each process "
                  "loads them from numba's cache instead, about 0.4 s more to its first result", file=sys.stderr)


def write_bytecode(package: Path | None = None) -> bool:
    """The package's bytecode beside its sources, written even where the import system writes none
    (``PYTHONDONTWRITEBYTECODE``, set in many containers): a process otherwise compiles every
    module it imports from source, at each start (``import inerter`` 0.15 s slower, the median of 8
    side-by-side pairs on 2026-11-28). An installed wheel has it already; an
    editable installation, as the set-up's, does not. `package`: this package's folder by default.
    False where some could not be written."""
    import compileall
    package = package or Path(__file__).resolve().parent
    return bool(compileall.compile_dir(str(package), quiet=2))


#: Subcommands whose arguments their own module parses.
DELEGATED = {
    "bench": ("studies.bench", "main_bench", "work-precision diagrams: error against the oracle vs CPU time"),
    "sweep": ("studies.sweep", "main_sweep", "parameter sweeps on dask, resumable"),
    "study": ("studies.builtin", "main_study", "built-in studies: fig9, two_bar_b, two_bar_f"),
    "sweep-plot": ("studies.sweep", "main_sweep_plot", "plot a metric of a sweep's results against a parameter"),
    "device-study": ("studies.device_effects", "main_device_study",
                     "each effect of a ball-screw inerter against the ideal one, by the solver and the FMU"),
}


DESCRIPTION = """\
Simulate planar and spatial mechanisms with springs, dampers and inerters from TOML scene files,
with and without the inerter's centripetal term; build FMI 2.0 co-simulation FMUs from the same
files. Exit status: 0 ok, 2 a bad scene, option or file (one line on stderr), 3 a run that
stopped before its stop time."""

EPILOG = "inerter COMMAND -h lists a command's options. Scene format: docs/scene_format.md."


def build_parser():
    from inerter import __version__
    p = _Parser(prog="inerter", description=DESCRIPTION, epilog=EPILOG,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"inerter {__version__}")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)

    def scene_argument(sp):
        sp.add_argument("scene", help="the scene file (TOML)")

    def set_option(sp):
        sp.add_argument("--set", action="append", metavar="NAME=VALUE",
                        help="override a parameter (b=20, in SI; b=2*pi; b={value=20, unit=\"kg\"}), "
                             "effects.NAME or experiment.NAME, VALUE written as in the scene file (repeatable)")

    def common(sp, out_default="out"):
        set_option(sp)
        sp.add_argument("--out", default=out_default, metavar="DIR", help="output folder (default: %(default)s)")
        sp.add_argument("--model", choices=("solver", "oracle", "fmu"), default="solver",
                        help="the stand-alone solver (default), the oracle (DOP853 at rtol 1e-12) or the "
                             "scene's FMU through fmpy")
        sp.add_argument("--stop-time", metavar="SECONDS", help="experiment.stop_time (s)")
        sp.add_argument("--method", metavar="METHOD",
                        help="experiment.method: one of " + ", ".join(METHODS))
        sp.add_argument("--rtol", metavar="RTOL", help="experiment.rtol, in [1e-14, 0.1]")
        sp.add_argument("--step", metavar="SECONDS",
                        help="experiment.communication_step: the FMU's communication step (s), at most "
                             "the stop time; with --model fmu")
        sp.add_argument("--path", choices=("numpy", "compiled"), default="compiled",
                        help="the solver's path: compiled (the default: numba kernels and integrator loops, 2D "
                             "and 3D; the implicit methods, Radau, BDF and LSODA, and the projection treatment "
                             "run scipy's integrators on the compiled right-hand side) or numpy (the readable "
                             "reference)")

    r = sub.add_parser("run", help="simulate a scene: CSV, summary.json and a PNG")
    scene_argument(r)
    common(r)
    _animation_options(r)
    r.set_defaults(func=cmd_run)
    c = sub.add_parser("compare", help="with and without the centripetal correction, and the oracle")
    scene_argument(c)
    common(c)
    c.set_defaults(func=cmd_compare)
    d = sub.add_parser("describe", help="what a scene compiles to: terms, parameters, inputs, outputs")
    scene_argument(d)
    set_option(d)
    d.set_defaults(func=cmd_describe)
    b = sub.add_parser("build-fmu", help="build FMI 2.0 co-simulation FMUs (only when stale)")
    b.add_argument("scenes", nargs="+", metavar="SCENE", help="scene files (TOML)")
    b.add_argument("--out", default="build/fmu", metavar="DIR", help="where the FMUs go (default: %(default)s)")
    b.add_argument("--force", action="store_true", help="rebuild even when an FMU is current")
    b.set_defaults(func=cmd_build_fmu)
    y = sub.add_parser("build-system", help="the two-bar FMU and the PD-controller FMU coupled, as an OSP "
                                           "system structure and an SSP SystemStructure.ssd (libcosim reads both)")
    y.add_argument("-o", "--out-dir", default="build/system", help="where the FMUs and the files go (default: %(default)s)")
    y.add_argument("--step", type=float, default=None, help="communication step (s; default 0.01)")
    y.set_defaults(func=cmd_build_system)
    for name, (module, func, text) in DELEGATED.items():
        sub.add_parser(name, help=text + f" (inerter {name} -h)", add_help=False)
    pp = sub.add_parser("paper", help="both paper scenes end to end (the main job: make demo)")
    pp.add_argument("--out", default="out/paper", metavar="DIR", help="output folder (default: %(default)s)")
    pp.add_argument("--scenarios", default=None, metavar="DIR",
                    help="folder of lumped_mass_2d.toml and two_bar_2d.toml (default: the scenes shipped "
                         "with inerter)")
    pp.add_argument("--model", choices=("solver", "fmu"), default="solver",
                    help="run the stand-alone solver (default) or each scene's FMU")
    pp.set_defaults(func=cmd_paper)
    k = sub.add_parser("compile", help="compile the engine's kernels ahead of time, and the package's bytecode "
                                       "(the set-up does it once)")
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
        return args.func(args)
    except SceneError as exc:
        option = _option_for(args, exc)
        print(f"inerter: error: {option + ': ' if option else ''}{exc}", file=sys.stderr)
        return 2
    except InerterError as exc:
        print(f"inerter: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:           # stdout's reader left (inerter describe ... | head): stop quietly
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())   # nothing more to flush at exit
        return 141                    # 128 + SIGPIPE, the status of a tool the signal ended
    except OSError as exc:            # an output file that cannot be written
        print(f"inerter: error: {unwritable(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
