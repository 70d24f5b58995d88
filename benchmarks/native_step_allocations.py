"""Memory allocations of the compiled kernels per communication step: the FMU's native step against
the solver's whole run.

    python benchmarks/native_step_allocations.py [--scenes lumped_mass_2d,two_bar_2d]

Counts numba's allocations (its runtime's statistics, NUMBA_NRT_STATS=1, set here before numba is
imported) over the native steps of 20 s at 0.01 s called directly through ctypes (as
benchmarks/fmu_stages.py calls them), over 100 native steps that take no integration step (the
communication point inside the last step: the state from its dense output and the outputs only),
and over the solver's whole run with its outputs (``Run.values``). Counts, not times: they do not
depend on the machine's load.
"""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ["NUMBA_NRT_STATS"] = "1"

import inerter  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fmu_overhead import NATIVE_C  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
STEP, STOP = 0.01, 20.0


def allocations(fn) -> int:
    """numba's allocations during fn()."""
    from numba.core.runtime import rtsys
    before = rtsys.get_allocation_stats().alloc
    fn()
    return rtsys.get_allocation_stats().alloc - before


def count(scene: Path) -> dict[str, float]:
    model = inerter.load(scene)
    model.simulate(stop_time=STOP, output_interval=STEP, metrics=False, path="compiled").values()   # loads
    whole = allocations(lambda: model.simulate(stop_time=STOP, output_interval=STEP, metrics=False,
                                               path="compiled").values())
    steps = round(STOP / STEP)
    result = {"whole run, per communication point": whole / steps}
    for label, h, calls in (("native step", STEP, steps - 1), ("native step taking no integration step", 1e-7, 100)):
        st = model.stepper(path="compiled", stop_time=STOP)
        st.step(STEP)
        st.outputs()
        table = st.native_table(1e-9)
        fn, address = NATIVE_C(st.native_function().address), table.ctypes.data

        def run():
            for k in range(calls):
                if fn(address, STEP + k * h, h) != 1:
                    raise RuntimeError(f"{scene.stem}: the native step declined at call {k}")
        result[f"{label}, per call"] = allocations(run) / calls
    return result


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="lumped_mass_2d,two_bar_2d")
    args = parser.parse_args(argv)
    print(f"numba allocations, {STOP:g} s at {STEP:g} s (compiled path, default tolerances)\n")
    print("| scene | what | allocations |")
    print("|---|---|---|")
    for name in args.scenes.split(","):
        for label, value in count(ROOT / "scenarios" / f"{name}.toml").items():
            print(f"| {name} | {label} | {value:.2f} |")


if __name__ == "__main__":
    main()
