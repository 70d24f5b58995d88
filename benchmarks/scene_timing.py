"""How long each paper scene takes: fast path and oracle, with and without the centripetal term.

    python benchmarks/scene_timing.py            # prints a markdown table, writes docs/scene_timing.md

CPU time of the integration alone (process time), then of the whole `simulate` (with output
signals and metrics). Timings vary between runs on a shared machine; compare rows of one run.
"""
from __future__ import annotations

import time
from pathlib import Path

import inerter

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("lumped_mass_2d", "two_bar_2d")


def main():
    rows = []
    for name in SCENES:
        path = ROOT / "scenarios" / f"{name}.toml"
        for cen in (True, False):
            for kind in ("fast path", "oracle"):
                model = inerter.load(path, **{"effects.centripetal": cen})
                kw = {}
                if kind == "oracle":
                    model = model.oracle()
                    kw = dict(rtol=inerter.api.ORACLE_RTOL, atol=inerter.api.ORACLE_ATOL)
                t0 = time.process_time()
                result = model.simulate(**kw)
                total = time.process_time() - t0
                s = result.settings
                rows.append((name, "on" if cen else "off", kind, s.stop_time, f"{s.rtol:g}", result.run.steps,
                             result.run.evaluations, result.run.cpu_time, total))
                print(rows[-1], flush=True)
    head = ("| scene | centripetal | path | simulated (s) | rtol | steps | evaluations | integration CPU (s) "
            "| with outputs + metrics (s) |\n|---|---|---|---|---|---|---|---|---|\n")
    body = "".join(f"| {a} | {b} | {c} | {d:g} | {e} | {f} | {g} | {h:.2f} | {i:.2f} |\n"
                   for a, b, c, d, e, f, g, h, i in rows)
    table = head + body
    print(table)
    out = ROOT / "docs" / "scene_timing.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text("# Scene timings\n\nMeasured by `python benchmarks/scene_timing.py` on a 2-core machine.\n\n"
                   + table)


if __name__ == "__main__":
    main()
