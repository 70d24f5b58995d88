"""What a scene's FMU costs per communication step through fmpy, recording every output or all but
some, on the compiled path with native steps on and off (process CPU time, best of `--repeats`).

    PYTHONPATH=TREE python benchmarks/fmu_output_cost.py TREE/scenarios/two_bar_2d.toml
    PYTHONPATH=TREE python benchmarks/fmu_output_cost.py SCENE --leave-out .power,.energy

The FMU is built from the `inerter` package on PYTHONPATH, so two versions of the code are compared
by running this once for each, in turn (a fresh process each, alternating, so that drifting load
weighs on both alike). `fmpy.simulate_fmu` records every output variable unless told which:
`--leave-out` records all but the outputs whose names end with one of the given suffixes, which
separates what more outputs cost the importer from what computing them costs the FMU.
"""
from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import fmpy

import inerter
from inerter import api
from inerter.fmu.build import build
from inerter.studies.bench import settle


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", type=Path)
    ap.add_argument("--stop-time", type=float, default=20.0)
    ap.add_argument("--step", type=float, default=0.01)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--leave-out", default="", help="comma-separated suffixes of outputs not recorded")
    args = ap.parse_args(argv)
    fmu = str(build(args.scene, Path(tempfile.mkdtemp(prefix="inerter_fmu_output_cost_"))))
    api.warm_up()
    suffixes = tuple(s for s in args.leave_out.split(",") if s)
    outputs = [v.name for v in fmpy.read_model_description(fmu).modelVariables
               if v.causality == "output" and not (suffixes and v.name.endswith(suffixes))]

    def run(native):
        os.environ["INERTER_FMU_NATIVE"] = "1" if native else "0"
        r = fmpy.simulate_fmu(fmu, stop_time=args.stop_time, output_interval=args.step,
                              start_values={"compiled": True}, output=outputs)
        assert abs(r["time"][-1] - args.stop_time) < 1e-9, "the FMU stopped early"
        return r

    run(True)                                       # the kernels loaded inside the FMU once
    steps = round(args.stop_time / args.step)
    line = [f"package {Path(inerter.__file__).parents[1]}", f"{len(outputs)} outputs recorded"]
    for native in (True, False):
        best = math.inf
        for _ in range(args.repeats):
            settle()
            t0 = time.process_time()
            run(native)
            best = min(best, time.process_time() - t0)
        line.append(f"native steps {'on' if native else 'off'}: {best:.4f} s, {1e6 * best / steps:.1f} µs/step")
    print(" | ".join(line), flush=True)


if __name__ == "__main__":
    main()
