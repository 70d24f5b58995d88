"""What fmpy's extraction of an FMU costs, file by file and byte by byte: copies of a built FMU
rewritten with fewer files or bytes, each extracted as ``fmpy.simulate_fmu`` does it (its
``extract``) and deleted again.

    python benchmarks/fmu_extract.py [--scene lumped_mass_2d] [--rounds 5] [--repeats 20]

The variants, each a copy of the scene's FMU (built if stale):

- as shipped;
- the package payload (``resources/inerter_payload.zip``, its members deflated) as one tar.xz of
  the same members;
- and the slave module (``resources/inerter_slave.py``) inside that archive, one file fewer;
- and the Python bridge (``binaries/linux64/<model>.bridge.so``) left out, as if it were merged
  into the status shim (the copies are not run: only extracted).

Process milliseconds of ``fmpy.extract`` and of deleting the folder (``shutil.rmtree``): the best
and the median of `--repeats` runs in each of `--rounds` rounds, the variants taken in turn in
every round. No FMU is changed: the figures say what such changes to the FMU's layout would save
(docs/performance.md, FMU overhead).
"""
from __future__ import annotations

import argparse
import io
import shutil
import statistics
import tarfile
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _tar_xz(members) -> bytes:
    """(name, bytes) pairs as one tar.xz, in order."""
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:xz") as archive:
        for name, data in members:
            info = tarfile.TarInfo(name)
            info.size = len(data)
            archive.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


def variants(fmu: Path) -> dict[str, list[tuple[str, bytes]]]:
    """The FMU's members as shipped and as each variant would have them."""
    with zipfile.ZipFile(fmu) as z:
        shipped = [(info.filename, z.read(info)) for info in z.infolist()]
    files = dict(shipped)
    payload_name = next(name for name in files if name.endswith("inerter_payload.zip"))
    with zipfile.ZipFile(io.BytesIO(files[payload_name])) as payload:
        members = [(info.filename, payload.read(info)) for info in payload.infolist()]
    slave_name = next(name for name in files if name.endswith("inerter_slave.py"))
    as_xz = _tar_xz(members)
    with_slave = _tar_xz(members + [("inerter_slave.py", files[slave_name])])
    in_xz = [(n, as_xz if n == payload_name else d) for n, d in shipped]
    slave_in = [(n, with_slave if n == payload_name else d) for n, d in shipped if n != slave_name]
    return {
        "as shipped": shipped,
        "payload as tar.xz": in_xz,
        "and the slave module in it": slave_in,
        "and no bridge file": [(n, d) for n, d in slave_in if not n.endswith(".bridge.so")],
    }


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default="lumped_mass_2d")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--repeats", type=int, default=20)
    args = ap.parse_args(argv)
    from fmpy import extract

    from inerter.fmu.build import build
    scratch = Path(tempfile.mkdtemp(prefix="inerter_extract_"))
    try:
        fmu = Path(build(ROOT / "scenarios" / f"{args.scene}.toml", scratch))
        paths = {}
        for k, (label, members) in enumerate(variants(fmu).items()):
            paths[label] = scratch / f"variant{k}.fmu"
            with zipfile.ZipFile(paths[label], "w", zipfile.ZIP_STORED) as out:
                for name, data in members:
                    out.writestr(name, data)
        times = {label: ([], []) for label in paths}
        for _ in range(args.rounds):
            for label, path in paths.items():
                for _ in range(args.repeats):
                    t0 = time.process_time()
                    folder = extract(path)
                    t1 = time.process_time()
                    shutil.rmtree(folder)
                    times[label][0].append(t1 - t0)
                    times[label][1].append(time.process_time() - t1)
        print(f"{args.scene}: process ms, best (median) of {args.rounds} × {args.repeats}\n")
        print("| FMU | files | KB | extract | delete |\n|---|---|---|---|---|")
        for label, path in paths.items():
            with zipfile.ZipFile(path) as z:
                count, size = len(z.infolist()), sum(i.file_size for i in z.infolist()) / 1024
            ex, de = times[label]
            print(f"| {label} | {count} | {size:.0f} | {min(ex) * 1e3:.2f} ({statistics.median(ex) * 1e3:.2f}) "
                  f"| {min(de) * 1e3:.2f} ({statistics.median(de) * 1e3:.2f}) |")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    main()
