"""Pieces of an FMU run's fixed cost, each alone (docs/benchmarks/fmu_overhead_paper_scenes.md).

    python benchmarks/fmu_fixed_cost.py [--scenes lumped_mass_2d,two_bar_2d] [--rounds 7]

For each scene's FMU as built: fmpy reading its model description (as built; without schema
validation; without indentation; with ``dependenciesKind="dependent ..."`` on every Unknown, as
built before), fmpy extracting it and deleting the folder (as built; the same ten names holding
one byte each; the description and the Linux binary alone), and the native step's table built on
a fresh stepper (``CompiledStepper.native_table(start=True)``, as the slave arms the link at the
end of initialisation). Process milliseconds per call, best of `--rounds`.
"""
from __future__ import annotations

import argparse
import io
import re
import shutil
import tempfile
import time
import zipfile
from pathlib import Path

import inerter
from inerter import api
from inerter.fmu.build import build

ROOT = Path(__file__).resolve().parents[1]


def best(fn, calls: int, rounds: int) -> float:
    """Process ms per call of `fn`, best of `rounds` rounds of `calls` calls."""
    out = float("inf")
    for _ in range(rounds):
        t0 = time.process_time()
        for _ in range(calls):
            fn()
        out = min(out, (time.process_time() - t0) / calls)
    return 1e3 * out


def archive(entries) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as z:
        for name, data in entries:
            z.writestr(name, data)
    return buffer.getvalue()


def with_kinds(xml: bytes) -> bytes:
    """The description with every Unknown's dependenciesKind written out ("dependent" each)."""
    def add(m):
        deps = m.group(1).split()
        kinds = f' dependenciesKind="{" ".join(["dependent"] * len(deps))}"' if deps else ""
        return m.group(0) + kinds.encode()
    return re.sub(rb'dependencies="([^"]*)"', add, xml)


def main(argv=None):
    from fmpy import extract, read_model_description
    ap = argparse.ArgumentParser()
    ap.add_argument("--scenes", default="lumped_mass_2d,two_bar_2d")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args(argv)
    api.warm_up()
    scratch = Path(tempfile.mkdtemp(prefix="inerter_fixed_cost_"))
    for name in args.scenes.split(","):
        scene = ROOT / "scenarios" / f"{name}.toml"
        fmu = build(scene, scratch / "fmu")
        with zipfile.ZipFile(fmu) as z:
            entries = [(i.filename, z.read(i)) for i in z.infolist()]
        xml = dict(entries)["modelDescription.xml"]
        print(f"\n{name}: process ms per call, best of {args.rounds}\n\n| what | bytes | ms |\n|---|---|---|")
        for label, text, validate in (("description as built", xml, True),
                                      ("... without schema validation", xml, False),
                                      ("... without indentation", re.sub(rb">\s+<", b"><", xml), True),
                                      ("... with dependenciesKind", with_kinds(xml), True)):
            data = archive([("modelDescription.xml", text)])
            ms = best(lambda: read_model_description(io.BytesIO(data), validate=validate), 100, args.rounds)
            print(f"| {label} | {len(text)} | {ms:.3f} |")
        binary = next(n for n, _ in entries if n.startswith("binaries/linux64/") and n.count(".") == 1)
        for label, variant in (("extract + delete, as built", entries),
                               ("... the same names, one byte each", [(n, b"x") for n, _ in entries]),
                               ("... the description and the Linux binary alone",
                                [(n, d) for n, d in entries if n in ("modelDescription.xml", binary)])):
            path = scratch / "variant.fmu"
            path.write_bytes(archive(variant))
            ms = best(lambda: shutil.rmtree(extract(str(path))), 20, args.rounds)
            print(f"| {label} | {sum(len(d) for _, d in variant)} | {ms:.3f} |")
        model = inerter.load(scene)

        def arm():
            stepper = model.stepper(path="compiled", stop_time=20.0)
            stepper.native_table(1e-9, start=True)
        fresh = best(lambda: model.stepper(path="compiled", stop_time=20.0), 100, args.rounds)
        print(f"| native table at initialisation (a fresh stepper's cost, {fresh:.3f} ms, "
              f"taken off) | | {best(arm, 100, args.rounds) - fresh:.3f} |")
    shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
