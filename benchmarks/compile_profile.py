"""Where compiling the kernels goes: every kernel numba compiles while the set-up's warm-up runs
(``api.warm_up``) for one dimension, with the time its compilation took, alone and with the kernels
it compiled inside it (numba's ``numba:compile`` events, nested where one kernel's compilation
compiles another's).

    python benchmarks/compile_profile.py 3 [--json out.json] [--top 40] [--cache DIR]

By default the kernels compile into an empty temporary cache (``INERTER_CACHE_DIR``), so that every
kernel is compiled; ``--cache DIR`` compiles into that one instead (the user's, to fill it at the same
time: ``--cache ~/.cache/inerter``). Run the two dimensions in two processes at once, as ``inerter
compile`` does, to time them as it does. "self" is a compilation less the compilations nested in it:
numba types, lowers and optimises a kernel once per signature, and a kernel inlined into another
(``inline="always"``, an overload) is compiled again inside each one that inlines it, so that its
time shows up in theirs.
"""
from __future__ import annotations

import argparse
import collections
import json
import os
import sys
import tempfile
import time

from numba.core import event


class CompileTimes(event.Listener):
    """Listens to numba's ``numba:compile`` events: (kernel, inclusive s, self s) per compilation."""

    def __init__(self):
        super().__init__()
        self.open = []          # [start, seconds of nested compilations] of each compilation under way
        self.rows = []

    def on_start(self, event):
        self.open.append([time.perf_counter(), 0.0])

    def on_end(self, event):
        start, nested = self.open.pop()
        seconds = time.perf_counter() - start
        if self.open:
            self.open[-1][1] += seconds
        dispatcher = event.data["dispatcher"]
        name = getattr(getattr(dispatcher, "py_func", None), "__qualname__", str(dispatcher))
        self.rows.append((name, seconds, seconds - nested))

    def by_kernel(self):
        """{kernel: [compilations, inclusive s, self s]}, summed over its signatures."""
        totals = collections.defaultdict(lambda: [0, 0.0, 0.0])
        for name, seconds, alone in self.rows:
            entry = totals[name]
            entry[0] += 1
            entry[1] += seconds
            entry[2] += alone
        return dict(totals)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dim", type=int, choices=(2, 3))
    parser.add_argument("--json", help="write every compilation (kernel, inclusive s, self s) there")
    parser.add_argument("--top", type=int, default=40)
    parser.add_argument("--cache", help="the kernel cache to compile into (default: an empty temporary one)")
    args = parser.parse_args(argv)
    os.environ["INERTER_CACHE_DIR"] = os.path.expanduser(args.cache) if args.cache else \
        tempfile.mkdtemp(prefix="inerter_compile_profile_")

    times = CompileTimes()
    event.register("numba:compile", times)

    from inerter.api import warm_up
    from inerter.engine import compiled
    compiled.NOTICE.enabled = False
    start = time.perf_counter()
    warm_up(dims=(args.dim,))
    total = time.perf_counter() - start
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"dim": args.dim, "seconds": total, "compilations": times.rows}, f)
    totals = sorted(times.by_kernel().items(), key=lambda item: -item[1][2])
    print(f"{args.dim}D kernels: {total:.0f} s wall, {len(times.rows)} compilations "
          f"(cache {os.environ['INERTER_CACHE_DIR']})")
    print("| kernel | compilations | self (s) | with nested (s) |\n|---|---:|---:|---:|")
    for name, (count, seconds, alone) in totals[:args.top]:
        print(f"| `{name}` | {count} | {alone:.1f} | {seconds:.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
