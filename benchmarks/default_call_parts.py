"""Where the default call's time beyond its integration goes, part by part.

    PYTHONPATH=<tree> python <tree>/benchmarks/default_call_parts.py [scene.toml] [--rtol R] [--repeat N]

``model.simulate(stop_time=20, rtol=R, atol=R/100)`` with the scene's metrics (the call
``benchmarks/work_precision.py --paths default`` times; default rtol 5e-5, the cheapest reaching 1e-6 m
on two_bar_2d), repeated on one Model; each part's CPU time (``time.process_time``, as the integration's
own) is read around the functions that do it, and the table gives each part's fastest and median over the repeats (ms) and its share of the
integration's own time (``run.cpu_time``, fastest). The parts nest: the metrics hold the
steady-state metric, which holds the dense output's evaluation at the metric's grid and
refinements (``metrics._dense_values``).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

TREE = Path(__file__).resolve().parents[1]

import inerter  # noqa: E402
from inerter import api  # noqa: E402
from inerter.engine import compiled, metrics  # noqa: E402

#: (module or class, function, label), outermost first
PARTS = ((api.Model, "settings", "settings (the experiment with the call's overrides)"),
         (compiled, "integrate_compiled", "integrate_compiled (Python around the loop included)"),
         (api, "compute_metrics", "metrics"),
         (metrics, "steady_state", "  steady-state metric"),
         (metrics, "_dense_values", "    its dense-output evaluations"))


def timed_parts(spent):
    """Wrap each of PARTS so that its CPU time adds up in `spent[label]`."""
    for owner, name, label in PARTS:
        function = getattr(owner, name)

        def wrapper(*args, _function=function, _label=label, **kwargs):
            start = time.process_time()
            try:
                return _function(*args, **kwargs)
            finally:
                spent[_label] = spent.get(_label, 0.0) + time.process_time() - start
        setattr(owner, name, wrapper)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default=str(TREE / "scenarios" / "two_bar_2d.toml"))
    parser.add_argument("--rtol", type=float, default=5e-5)
    parser.add_argument("--repeat", type=int, default=100)
    args = parser.parse_args(argv)
    model = inerter.load(args.scene)
    call = dict(stop_time=20.0, rtol=args.rtol, atol=args.rtol * 1e-2)
    spent: dict[str, float] = {}
    timed_parts(spent)
    for _ in range(5):                                   # kernels loaded, the Model's caches filled
        model.simulate(**call)
    rows: dict[str, list[float]] = {}
    for _ in range(args.repeat):
        spent.clear()
        start = time.process_time()
        result = model.simulate(**call)
        spent["the whole call"] = time.process_time() - start
        spent["integration (run.cpu_time)"] = result.run.cpu_time
        for label, seconds in spent.items():
            rows.setdefault(label, []).append(seconds)
    integration = min(rows["integration (run.cpu_time)"])
    print(f"{Path(args.scene).name}, rtol {args.rtol:g}, {args.repeat} calls; {inerter.__file__}")
    print(f"| part | fastest (ms) | median (ms) | ÷ integration (fastest) |\n|---|---:|---:|---:|")
    labels = ["the whole call", "integration (run.cpu_time)"] + [label for _, _, label in PARTS]
    for label in labels:
        values = rows.get(label, [0.0])
        print(f"| {label} | {min(values) * 1e3:.3f} | {np.median(values) * 1e3:.3f} | "
              f"{min(values) / integration:.1%} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
