"""Where an FMU run's time goes, stage by stage, against FMUs that do nothing.

    python benchmarks/fmu_stages.py [--scenes lumped_mass_2d,two_bar_2d] [--repeats 7] [--profile]

The stages of `fmpy.simulate_fmu`, made one by one with fmpy's own calls (as simulate_fmu makes
them), for the scene's FMU (compiled path, native steps as shipped) and for the two floors of
benchmarks/fmu_overhead.py (a pythonfmu FMU that does nothing, with as many outputs, and the same
with a C binary that does nothing): reading the model
description, extracting the FMU, loading its binary, instantiating, setupExperiment + enter/exit
initialization mode, the first doStep, the further communication steps (0.01 s up to 20 s) each
followed by a getReal of every output (as simulate_fmu records them), terminate + freeInstance,
deleting the extracted folder. Process CPU milliseconds, best of `--repeats` runs, in one process
after two runs that load everything (the kernels, the modules, the scene's model: what a later
run of an importer pays). For reference, the solver's whole run and the native steps called
directly (the FMU binary's own work, benchmarks/fmu_overhead.py's `native_direct`).

Then the native step's cost of entry: the C function (inerter.engine.kernels.native_step_cfunc)
called through ctypes at a time that is not the current communication point, where it declines at
its first check (after taking the table apart into its arrays, before any copy or step), against a
ctypes call of a C function that does nothing.

`--profile` prints cProfile's view of the fixed stages (instantiate to free) of the scene's FMU.
"""
from __future__ import annotations

import argparse
import cProfile
import pstats
import shutil
import sys
import tempfile
import time
from pathlib import Path

import inerter
from inerter import api
from inerter.fmu.build import build

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fmu_overhead import NATIVE_C, c_floor_fmu, floor_fmu  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
STEP, STOP = 0.01, 20.0
STAGES = ("read description", "extract", "load binary", "instantiate", "initialise", "first doStep",
          "further steps + getReal", "terminate + free", "delete folder")


def stages(fmu: str, profile: cProfile.Profile | None = None) -> dict[str, float]:
    """Process seconds of each stage of one run of `fmu` (the profile on during the fixed ones)."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    out, clock = {}, time.process_time

    def stage(name, fn):
        t0 = clock()
        value = fn()
        out[name] = clock() - t0
        return value

    md = stage("read description", lambda: read_model_description(fmu))
    folder = stage("extract", lambda: extract(fmu))
    slave = stage("load binary", lambda: FMU2Slave(guid=md.guid, unzipDirectory=folder, instanceName="x",
                                                   modelIdentifier=md.coSimulation.modelIdentifier))
    vrs = [v.valueReference for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    if profile:
        profile.enable()
    stage("instantiate", slave.instantiate)
    stage("initialise", lambda: (slave.setupExperiment(startTime=0.0), slave.enterInitializationMode(),
                                 slave.exitInitializationMode()))
    stage("first doStep", lambda: (slave.doStep(0.0, STEP), slave.getReal(vrs)))
    if profile:
        profile.disable()

    def further():
        for k in range(2, int(round(STOP / STEP)) + 1):
            t0, t1 = (k - 1) * STEP, k * STEP          # the communication points as fmpy computes them
            slave.doStep(currentCommunicationPoint=t0, communicationStepSize=t1 - t0)
            slave.getReal(vrs)
    stage("further steps + getReal", further)
    if profile:
        profile.enable()
    stage("terminate + free", lambda: (slave.terminate(), slave.freeInstance()))
    if profile:
        profile.disable()
    stage("delete folder", lambda: shutil.rmtree(folder, ignore_errors=True))
    return out


def solver_reference(scene: Path) -> tuple[float, float]:
    """(the whole run, the native steps called directly) in process seconds."""
    model = inerter.load(scene)
    t0 = time.process_time()
    model.simulate(stop_time=STOP, output_interval=STEP, metrics=False, path="compiled").values()
    whole = time.process_time() - t0
    t0 = time.process_time()
    st = model.stepper(path="compiled", stop_time=STOP)
    st.step(STEP)
    st.outputs()
    table = st.native_table(1e-9)
    fn, address = NATIVE_C(st.native_function().address), table.ctypes.data
    for k in range(2, int(round(STOP / STEP)) + 1):
        t_prev, t_next = (k - 1) * STEP, k * STEP
        if not fn(address, t_prev, t_next - t_prev):
            raise RuntimeError(f"{scene.stem}: the native step declined at step {k}")
    return whole, time.process_time() - t0


def entry_cost(scene: Path, calls: int = 100_000) -> tuple[float, float]:
    """Microseconds per ctypes call: (a C function that does nothing, the native step declining at
    its first check), best of 3."""
    from numba import cfunc, types

    @cfunc(types.int32(types.voidptr, types.float64, types.float64))
    def nothing(table, t, h):
        return 0
    st = inerter.load(scene).stepper(path="compiled", stop_time=STOP)
    st.step(STEP)
    table = st.native_table(1e-9)
    address = table.ctypes.data
    out = []
    for fn in (NATIVE_C(nothing.address), NATIVE_C(st.native_function().address)):
        best = float("inf")
        for _ in range(3):
            t0 = time.process_time()
            for _ in range(calls):
                fn(address, STOP / 2, STEP)           # not the current point: declined at once
            best = min(best, time.process_time() - t0)
        out.append(1e6 * best / calls)
    return out[0], out[1]


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="lumped_mass_2d,two_bar_2d")
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--profile", action="store_true")
    args = ap.parse_args(argv)
    api.warm_up()
    scratch = Path(tempfile.mkdtemp(prefix="inerter_stages_"))
    for name in args.scenes.split(","):
        scene = ROOT / "scenarios" / f"{name}.toml"
        fmu = str(build(scene, scratch / "fmu"))
        floor = floor_fmu(len(inerter.load(scene).output_info()), scratch)
        c_floor = c_floor_fmu(floor, scratch)
        best = {which: dict.fromkeys(STAGES, float("inf")) for which in (fmu, floor, c_floor)}
        reference = [float("inf")] * 2
        for _ in range(2):
            stages(fmu), stages(floor), stages(c_floor), solver_reference(scene)
        for _ in range(args.repeats):              # in turn, so that drifting load weighs on all
            for which in (fmu, floor, c_floor):
                for key, value in stages(which).items():
                    best[which][key] = min(best[which][key], value)
            reference = [min(a, b) for a, b in zip(reference, solver_reference(scene))]
        print(f"\n{name}: process ms, best of {args.repeats}; whole run {1e3 * reference[0]:.1f}, native steps "
              f"called directly {1e3 * reference[1]:.1f}\n\n| stage | FMU | pythonfmu floor | C floor "
              f"| FMU − C floor |\n|---|---|---|---|---|")
        for key in STAGES:
            f, p, c = (1e3 * best[which][key] for which in (fmu, floor, c_floor))
            print(f"| {key} | {f:.2f} | {p:.2f} | {c:.2f} | {f - c:.2f} |")
        fixed = sum(1e3 * (best[fmu][k] - best[c_floor][k]) for k in STAGES if k != "further steps + getReal")
        print(f"| all but the further steps | | | | {fixed:.2f} |")
        nothing, declined = entry_cost(scene)
        print(f"\nctypes call of a C function that does nothing: {nothing:.3f} µs; of the native step "
              f"declining at its first check: {declined:.3f} µs")
        if args.profile:
            profile = cProfile.Profile()
            for _ in range(20):
                stages(fmu, profile)
            pstats.Stats(profile).sort_stats("cumulative").print_stats(30)


if __name__ == "__main__":
    main()
