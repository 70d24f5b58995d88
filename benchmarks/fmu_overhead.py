"""What a scene costs through its FMU, against the solver called directly, on both paths.

    python benchmarks/fmu_overhead.py [--stop-time 20] [--step 0.01] [--repeats 3] [--chains 8,32]

For each paper scene and each path (numpy; compiled, numba), and for N-link chains
(benchmarks/chain_scene.py, compiled path only), ways to produce the same outputs at the same
communication points, measured side by side (process CPU time, best of `--repeats` rounds taken
in turn, so drifting load weighs on all alike):

- the solver's whole run (`Model.simulate(path=...)`: one integration sampled every step, every
  output evaluated at every sample, no metrics);
- the solver's co-simulation stepper called directly (`Model.stepper(path=...)`, as the FMU calls it:
  one integration running across the communication points, outputs evaluated after each step);
- the FMU through `fmpy.simulate_fmu` (extraction, instantiation, every step, every output
  recorded), with its parameter `compiled` set accordingly. On the compiled path twice: as shipped
  (the FMU's binary takes the steps natively, inerter/fmu/native.py) and with native steps off
  (INERTER_FMU_NATIVE=0: every step through pythonfmu into the slave);
- two floors, through the same `fmpy.simulate_fmu` call with as many outputs: a pythonfmu FMU whose
  doStep does nothing (what fmpy and pythonfmu cost per step), and the same FMU with its binary
  replaced by benchmarks/c_floor_fmu.c, a C binary that does nothing, alone in the FMU (what fmpy
  alone costs, extraction included; no FMU driven by fmpy can cost less);
- the fixed cost of a run: the FMU and the C floor over a single communication step;
- on the compiled path, the FMU binary's own work without an importer: the stepper's first step,
  then the native step's C function (inerter.engine.kernels.native_step_cfunc) called through
  ctypes for every further step, on the table the slave gives the FMU's binary (its lengths at the
  stop time must equal the stepper's, bit for bit).

braced_frame_3d runs a second time with RK4 (1 ms steps; `--no-rk4-frame` leaves it out): its ground
record puts a kink at every communication point, where RK4 ends a step, in the native step too.
RK4 in co-simulation restarts at each communication point, the whole run ends a step at each record
sample and runs on: the two are the same times up to rounding, so their lengths differ by round-off
(about 1e-14 m).

A second table runs the compiled-path FMUs (at their scenes' own solver) and the C floor through
libcosimpy (the Open Simulation Platform's C++ engine, when installed) with a last-value observer,
which reads every variable of the FMU at every step; its process time includes the engine's worker
threads.

The compiled kernels are loaded once before timing (their one-off compilation, cached on disk, is
in the README). Writes docs/fmu_overhead.md.
"""
from __future__ import annotations

import argparse
import ctypes
import os
import shlex
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from inerter import api
import inerter
from inerter.engine import compiled
from inerter.studies.bench import settle
from inerter.fmu.build import build
from inerter.fmu.run import solver_item

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from chain_scene import write_chain  # noqa: E402


def cpu(fn):
    """(process time of fn(), its value), settled first (inerter.studies.bench.settle): the garbage
    collections during fn() traverse fn's own objects only, not the results of every row before it."""
    settle()
    t0 = time.process_time()
    value = fn()
    return time.process_time() - t0, value


FLOOR_SLAVE = """
from pythonfmu import Fmi2Slave, Real
from pythonfmu.enums import Fmi2Causality, Fmi2Variability, Fmi2Initial


class {name}(Fmi2Slave):
    \"\"\"{n} outputs held at 0; do_step does nothing.\"\"\"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.values = [0.0] * {n}
        for i in range({n}):
            self.register_variable(Real(f"y{{i}}", causality=Fmi2Causality.output,
                                        variability=Fmi2Variability.continuous,
                                        initial=Fmi2Initial.exact, getter=lambda i=i: self.values[i]))

    def get_real(self, vrs):
        return [self.values[vr] for vr in vrs]

    def do_step(self, current_time, step_size):
        return True
"""


def floor_fmu(n_outputs: int, folder: Path) -> str:
    """A pythonfmu FMU with `n_outputs` Real outputs and a doStep that does nothing."""
    from pythonfmu.builder import FmuBuilder
    name = f"inerter_floor_{n_outputs}"
    script = folder / f"{name}.py"
    script.write_text(FLOOR_SLAVE.format(name=name, n=n_outputs))
    return str(FmuBuilder.build_FMU(script, dest=folder))


def c_floor_fmu(python_floor: str, folder: Path) -> str:
    """An FMU with `python_floor`'s modelDescription.xml and c_floor_fmu.c as its only binary
    (stored, not deflated, as the project's FMUs are)."""
    import fmpy
    identifier = fmpy.read_model_description(python_floor).coSimulation.modelIdentifier
    binary = folder / f"{identifier}_c.so"
    subprocess.run(["gcc", "-shared", "-fPIC", "-O2", "-I", str(ROOT / "fmu_src"), "-o", str(binary),
                    str(Path(__file__).with_name("c_floor_fmu.c"))], check=True)
    target = folder / (Path(python_floor).stem + "_c.fmu")
    with zipfile.ZipFile(python_floor) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_STORED) as zout:
        zout.writestr("modelDescription.xml", zin.read("modelDescription.xml"))
        zout.write(binary, f"binaries/linux64/{identifier}.so")
    return str(target)


COSIM_RUN = r"""
import sys, time
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
log_output_level(CosimLogLevel.ERROR)
fmu, stop, step, repeats = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
best = float("inf")
for _ in range(repeats + 1):                      # the first run loads the kernels
    t0 = time.process_time()
    execution = CosimExecution.from_step_size(step_size=round(step * 1e9))
    execution.add_local_slave(CosimLocalSlave(fmu_path=fmu, instance_name="fmu"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    assert execution.simulate_until(target_time=round(stop * 1e9))
    best = min(best, time.process_time() - t0)
    del observer, execution                    # torn down here, not while the interpreter finalizes
print(best)
"""


def _or_dash(x: float, fmt: str) -> str:
    """x in `fmt`, or a dash where it was not measured (inf)."""
    return format(x, fmt) if np.isfinite(x) else "–"


#: The native step's C signature: int32 (const int64 *table, double t, double h).
NATIVE_C = ctypes.CFUNCTYPE(ctypes.c_int32, ctypes.c_void_p, ctypes.c_double, ctypes.c_double)


def cosim_cpu(fmu: str, args, native: bool) -> float:
    """Best process time of a libcosimpy run of `fmu` (in a process of its own: libcosim keeps
    worker threads), with native steps on or off."""
    env = dict(os.environ, INERTER_FMU_NATIVE="1" if native else "0")
    proc = subprocess.run([sys.executable, "-c", COSIM_RUN, fmu, str(args.stop_time), str(args.step),
                           str(args.repeats)], env=env, capture_output=True, text=True, timeout=600)
    if proc.returncode:
        raise RuntimeError(f"libcosimpy run of {fmu} (native steps {'on' if native else 'off'}) ended with exit "
                           f"status {proc.returncode}; its output: {proc.stdout[-500:]!r}; its errors: "
                           f"{proc.stderr[-2000:]}")
    return float(proc.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--stop-time", type=float, default=20.0)
    ap.add_argument("--step", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--chains", default="8,32", help="links of the chain scenes ('' for none)")
    ap.add_argument("--no-rk4-frame", dest="rk4_frame", action="store_false",
                    help="leave out braced_frame_3d with RK4 (1 ms steps, a ground record sample at every point)")
    args = ap.parse_args(argv)
    import fmpy
    if not compiled.AVAILABLE:
        raise SystemExit(f"the compiled path is not available: {compiled.WHY_NOT}")
    api.warm_up()
    rows, cosim_rows, fixed_rows = [], [], []
    try:
        import libcosimpy  # noqa: F401
        has_cosim = True
    except ImportError:
        has_cosim = False
    scratch = Path(tempfile.mkdtemp(prefix="inerter_floor_"))
    # (label, solver path, native steps in the FMU)
    both = (("numpy", "numpy", False), ("compiled, steps in Python", "compiled", False),
            ("compiled, native steps", "compiled", True))
    # (scene, paths, solver: None for the scene's own)
    cases = [(ROOT / "scenarios" / f"{name}.toml", both, None) for name in ("lumped_mass_2d", "two_bar_2d")]
    cases += [(write_chain(scratch / f"chain_{links}.toml", links), both[1:], None)
              for links in (int(x) for x in args.chains.split(",") if x.strip())]
    # RK4 through a ground record's samples (a kink at every communication point)
    cases += [(ROOT / "scenarios" / "braced_frame_3d.toml", both[1:], "RK4")] if args.rk4_frame else []
    for scene, paths, solver in cases:
        name = scene.stem if solver is None else f"{scene.stem}, {solver}"
        fmu = str(build(scene, scratch / "fmu"))
        model = inerter.load(scene, **({} if solver is None else {"experiment.method": solver}))
        solver_start = {} if solver is None else {"solver": solver_item(solver)}
        n = int(round(args.stop_time / args.step))
        lengths = [o["name"] for o in model.output_info() if o["unit"] == "m"]
        floor = floor_fmu(len(model.output_info()), scratch)
        c_floor = c_floor_fmu(floor, scratch)

        def whole(path):
            result = model.simulate(stop_time=args.stop_time, output_interval=args.step, metrics=False, path=path)
            result.values()                     # every output at every sample, as the FMU gives them
            return result

        def stepper(path):
            st = model.stepper(path=path, stop_time=args.stop_time)
            assert st.path == path, st.path
            for k in range(1, n + 1):
                st.step(k * args.step)
                st.outputs()
            return st

        def fmu_run(path, native):
            os.environ["INERTER_FMU_NATIVE"] = "1" if native else "0"
            try:
                res = fmpy.simulate_fmu(fmu, stop_time=args.stop_time, output_interval=args.step,
                                        start_values={"compiled": path == "compiled", **solver_start})
            finally:
                del os.environ["INERTER_FMU_NATIVE"]
            assert abs(res["time"][-1] - args.stop_time) < 1e-9
            return res

        def native_direct():
            st = model.stepper(path="compiled", stop_time=args.stop_time)
            st.step(args.step)
            st.outputs()
            table = st.native_table(1e-9)
            fn = NATIVE_C(st.native_function().address)
            address = table.ctypes.data
            for k in range(2, n + 1):       # the communication points as fmpy computes them
                t0, t1 = (k - 1) * args.step, k * args.step
                if not fn(address, t0, t1 - t0):
                    raise RuntimeError(f"{name}: the native step declined at step {k}")
            return st

        def floor_run(which):
            return fmpy.simulate_fmu(which, stop_time=args.stop_time, output_interval=args.step)

        fmu_run("compiled", True)                             # load the kernels inside the FMU once
        # The fixed cost of a run: one communication step (extraction, instantiation, loading the scene,
        # initialisation, one step, termination, clean-up), the FMU against the C floor's.
        one = [np.inf, np.inf]
        for _ in range(args.repeats):
            one[0] = min(one[0], cpu(lambda: fmpy.simulate_fmu(fmu, stop_time=args.step, output_interval=args.step,
                                                               start_values=solver_start))[0])
            one[1] = min(one[1], cpu(lambda: fmpy.simulate_fmu(c_floor, stop_time=args.step,
                                                               output_interval=args.step))[0])
        fixed_rows.append((name, *one))
        if has_cosim and solver is None:
            whole_cpu = cpu(lambda: whole("compiled"))[0]
            native, python, cosim_floor = (cosim_cpu(fmu, args, True), cosim_cpu(fmu, args, False),
                                           cosim_cpu(c_floor, args, True))
            whole_cpu = min(whole_cpu, cpu(lambda: whole("compiled"))[0])    # before and after, drift alike
            cosim_rows.append((name, whole_cpu, native, python, cosim_floor))
            print(cosim_rows[-1], flush=True)
        for label, path, native in paths:
            best = {"whole": np.inf, "stepper": np.inf, "fmu": np.inf, "floor": np.inf, "c_floor": np.inf,
                    "direct": np.inf}
            for _ in range(args.repeats):
                t, reference = cpu(lambda: whole(path))
                best["whole"] = min(best["whole"], t)
                t, stepped = cpu(lambda: stepper(path))
                best["stepper"] = min(best["stepper"], t)
                t, res = cpu(lambda: fmu_run(path, native))
                best["fmu"] = min(best["fmu"], t)
                if native:
                    t, direct = cpu(native_direct)
                    best["direct"] = min(best["direct"], t)
                    direct.native_sync()                    # the native steps' last outputs, as the FMU's
                    last, expected = direct.outputs(), stepped.outputs()
                    direct_diff = max(abs(last[s] - expected[s]) for s in lengths)
                    if direct_diff != 0.0:
                        raise RuntimeError(f"{name}: native steps called directly differ from the stepper "
                                           f"by {direct_diff:.3e} m at the stop time")
                best["floor"] = min(best["floor"], cpu(lambda: floor_run(floor))[0])
                best["c_floor"] = min(best["c_floor"], cpu(lambda: floor_run(c_floor))[0])
                if path == "numpy" and best["whole"] > 2.0:
                    break                                    # the numpy path is slow: one round is enough
            diff = max(float(np.max(np.abs(res[s] - reference[s]))) for s in lengths)
            rows.append((name, label, n, best["whole"], best["stepper"], best["fmu"], best["floor"],
                         best["c_floor"], diff, best["direct"]))
            print(rows[-1], flush=True)
    head = (f"Communication step {args.step:g} s, {args.stop_time:g} s simulated, default scene tolerances, "
            f"process CPU seconds, best of {args.repeats} rounds.\n\n"
            "| scene | path | steps | solver, whole run (s) | solver stepper (s) | FMU via fmpy (s) "
            "| FMU per step (µs) | floor: pythonfmu FMU doing nothing (s) | floor: C FMU doing nothing (s) "
            "| **FMU / whole run** | FMU / stepper | (FMU − C floor) / whole run "
            "| (FMU − pythonfmu floor) / whole run "
            "| native steps called directly (s) | native steps called directly / whole run "
            "| largest difference of a length, FMU vs whole run (m) |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    body = "".join(f"| {a} | {p} | {b} | {c:.3f} | {d:.3f} | {e:.3f} | {1e6 * e / b:.0f} | {g:.3f} | {cf:.3f} "
                   f"| **{e / c:.2f}** | {e / d:.2f} | {(e - cf) / c:.2f} | {(e - g) / c:.2f} | {_or_dash(x, '.3f')} "
                   f"| {_or_dash(x / c, '.2f')} "
                   f"| {f:.2e} |\n" for a, p, b, c, d, e, g, cf, f, x in rows)
    body += ("\nThe fixed cost of a run: `fmpy.simulate_fmu` over one communication step (extraction, "
             "instantiation, loading the scene, initialisation, one step, termination, clean-up), the FMU with "
             f"native steps against the C floor, best of {args.repeats}:\n\n"
             "| scene | FMU, one step (s) | C floor, one step (s) | FMU − C floor (s) |\n|---|---|---|---|\n")
    body += "".join(f"| {a} | {o:.4f} | {f:.4f} | {o - f:.4f} |\n" for a, o, f in fixed_rows)
    if cosim_rows:
        body += ("\nThrough libcosimpy (last-value observer: every variable read at every step), compiled path, "
                 "process CPU seconds, best of {r}:\n\n"
                 "| scene | solver, whole run (s) | FMU, native steps (s) | FMU, steps in Python (s) "
                 "| floor: C FMU doing nothing (s) | **FMU / whole run** | steps in Python / whole run "
                 "| (FMU − C floor) / whole run |\n|---|---|---|---|---|---|---|---|\n").format(r=args.repeats)
        body += "".join(f"| {a} | {w:.3f} | {n:.3f} | {p:.3f} | {f:.3f} | **{n / w:.2f}** | {p / w:.2f} "
                        f"| {(n - f) / w:.2f} |\n" for a, w, n, p, f in cosim_rows)
        body += ("\nlibcosim's worker threads wait for each other actively, so its process time varies a lot from "
                 "run to run (its floor has ranged from 0.01 s to 0.11 s for the same FMU): read this table for "
                 "the contrast between native steps and steps in Python, measured in the same process.\n")
    print(head + body)
    (ROOT / "docs").mkdir(exist_ok=True)
    (ROOT / "docs" / "fmu_overhead.md").write_text(
        "# FMU overhead\n\n"
        f"- **Date:** {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, on a 2-core machine.\n"
        f"- **Command:** `python benchmarks/fmu_overhead.py {shlex.join(argv if argv is not None else sys.argv[1:])}`"
        "\n\n" + head + body
        + "\nEach row produces the same outputs at the same communication points. The whole run integrates once "
          "and samples its dense output. On the compiled path the stepper and the FMU keep one integration "
          "running across the communication points (it restarts only where an input changes), so they take "
          "the whole run's steps and give its results bit for bit (difference 0); so does the numpy stepper, "
          "which keeps scipy's integrator running in the same way. RK4 restarts at each communication point "
          "(the braced frame's whole run at each record sample, the same times up to rounding): there the "
          "difference is round-off. "
          "As shipped, the FMU's binary takes those steps itself in compiled code and serves the outputs "
          "(inerter/fmu/native.py); with native steps off, every doStep and getReal goes through pythonfmu "
          "into the slave. The two floors are FMUs that do nothing, driven by the same fmpy call: with "
          "pythonfmu's binary (fmpy's and pythonfmu's cost per step) and with a C binary "
          "(benchmarks/c_floor_fmu.c: fmpy's own cost, recording every output at every step). "
          "The (FMU − C floor) column is what the FMU itself costs, against the whole run; the (FMU − pythonfmu "
          "floor) column counts pythonfmu's own cost per step as the importer's too, which the native steps "
          "do not pay; the native steps called directly are the FMU binary's own work, without an importer.\n")

if __name__ == "__main__":
    main()
