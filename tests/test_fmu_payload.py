"""What an FMU carries (inerter/fmu/payload.py): the modules of `inerter` its slave can import, and
nothing else; and those suffice, which only a run in a process that cannot reach the repository
shows (a build followed by a run in one process would take a missing module from the repository).
"""
from __future__ import annotations

import io
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import grimp
import numpy as np
import pytest

import inerter
from inerter.engine import compiled as engine_compiled
from inerter.engine.compiled import kernel_sources
from inerter.fmu import build as fmu_build

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenarios" / "two_bar_2d.toml"
RUN_TIME = 0.5
RTOL = 1e-10
#: Never imported by the slave; each would be in an FMU that shipped the whole package.
NOT_RUN = ["inerter/cli.py", "inerter/studies/__init__.py", "inerter/studies/sweep.py",
           "inerter/studies/bench.py", "inerter/fmu/build.py", "inerter/fmu/cosim.py",
           "inerter/fmu/run.py", "inerter/fmu/payload.py"]


@pytest.fixture(scope="module")
def fmu(tmp_path_factory) -> Path:
    return fmu_build.build(SCENE, tmp_path_factory.mktemp("fmu"), force=True)


def _module(relative: str) -> str:
    """``inerter/a/b.py`` -> ``inerter.a.b``; ``inerter/a/__init__.py`` -> ``inerter.a``."""
    parts = Path(relative).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_by_the_slave() -> set[str]:
    """The reference, found without inerter.fmu.payload: the modules a fresh interpreter has after
    importing the slave, and everything those import anywhere in their code (grimp's graph, which
    counts imports inside functions), with their parent packages."""
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import inerter_slave; "
            "print(' '.join(m for m in sys.modules if m == 'inerter' or m.startswith('inerter.')))")
    done = subprocess.run([sys.executable, "-c", code, str(ROOT / "fmu_src")], cwd=ROOT,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)), capture_output=True,
                          text=True, check=True)
    graph = grimp.build_graph("inerter", include_external_packages=False)
    found, todo = set(), done.stdout.split()
    while todo:
        name = todo.pop()
        if name not in found:
            found.add(name)
            todo.extend(graph.find_modules_directly_imported_by(name))
            todo.extend(name.rsplit(".", i)[0] for i in range(1, name.count(".") + 1))
    return found


def payload(fmu: Path) -> zipfile.ZipFile:
    """The archive of the package's modules inside the FMU (inerter.fmu.build.write_payload)."""
    with zipfile.ZipFile(fmu) as z:
        assert not [n for n in z.namelist() if n.startswith("resources/inerter/")], \
            "the package's modules are shipped one by one, not in the payload archive"
        return zipfile.ZipFile(io.BytesIO(z.read(f"resources/{fmu_build.PAYLOAD_FILE}")))


def test_the_fmu_carries_the_modules_the_slave_imports_and_no_other(fmu):
    every_name = payload(fmu).namelist()
    assert all(n.endswith(".py") for n in every_name), every_name
    names = [n for n in every_name if n.startswith("inerter/")]
    # pythonfmu's modules, which its builder embeds in resources/pythonfmu/ (every .py file of the
    # package's top folder), are in the archive instead.
    import pythonfmu
    embedded = {"pythonfmu/" + p.name for p in Path(pythonfmu.__file__).parent.glob("*.py")}
    assert set(every_name) - set(names) == embedded
    with zipfile.ZipFile(fmu) as z:
        assert not [n for n in z.namelist() if n.startswith("resources/pythonfmu/")]
    shipped = {_module(n) for n in names}
    # The kernels' sources, loaded from a copy of their file and listed by inerter.elements,
    # are no import statements: the FMU carries them as the kernels' cache key needs them.
    package = Path(inerter.__file__).parent
    kernels = {_module(str(Path("inerter") / p.relative_to(package))) for p in kernel_sources()}
    expected = imported_by_the_slave() | kernels
    assert shipped == expected, (f"shipped but not imported: {sorted(shipped - expected)}; "
                                 f"imported but not shipped: {sorted(expected - shipped)}")
    assert not set(NOT_RUN) & set(names)
    every = {_module(str(p.relative_to(package.parent))) for p in package.rglob("*.py")}
    assert len(every - shipped) >= len(NOT_RUN)


RUN_SCRIPT = r"""
import importlib.util, json, sys
# Nothing but the FMU may provide the package: no entry of sys.path in the repository, and no
# editable install's finder (it would resolve a module the FMU lacks from the repository). The
# environment's own folders stay, even where it lives inside the repository (make's .venv).
sys.meta_path[:] = [f for f in sys.meta_path if "__editable__" not in getattr(f, "__module__", "")]
sys.path[:] = [p for p in sys.path if not p.startswith(sys.argv[3]) or p.startswith(sys.prefix)]
assert importlib.util.find_spec("inerter") is None, "inerter is importable without the FMU"
from fmpy import extract, simulate_fmu
job = json.loads(sys.argv[1])
folder = extract(job["fmu"], sys.argv[2])
results = {}
for compiled in (True, False):
    r = simulate_fmu(folder, stop_time=job["stop_time"], output_interval=job["output_interval"],
                     start_values={"rtol": job["rtol"], "compiled": compiled}, output=job["outputs"])
    results[str(compiled)] = {n: r[n].tolist() for n in ["time"] + job["outputs"]}
print(json.dumps({"results": results, "folder": str(folder),
                  "files": {m: str(getattr(sys.modules[m], "__file__", None)) for m in list(sys.modules)
                            if m in ("inerter", "pythonfmu") or m.startswith(("inerter.", "inerter_", "pythonfmu."))}}))
"""


def test_the_fmu_runs_on_what_it_carries_in_a_process_without_the_repository(fmu, tmp_path):
    """Both integration paths run (the compiled one loads the kernels from their shipped source)
    and every module of `inerter` they import comes from the FMU's resources/."""
    model = inerter.load(SCENE)
    dt = model.experiment["output_interval"]
    outputs = [o["name"] for o in model.output_info()]
    job = dict(fmu=str(fmu), stop_time=RUN_TIME, output_interval=dt, rtol=RTOL, outputs=outputs)
    repository = str(Path(inerter.__file__).resolve().parents[1])
    cache = tmp_path / "cache"
    # The set-up's kernels (`inerter compile`), where an FMU on this machine finds them: copied into
    # the empty cache with their timestamps (numba's index checks its source's), so that the run
    # loads what it would otherwise compile for minutes. A cold compile from another copy of the
    # package: test_compiled.py::test_kernels_compiled_once_are_found_from_another_copy_of_the_package.
    warm = Path(engine_compiled._k.__file__).parent
    shutil.copytree(warm, cache / "kernels" / warm.name)
    proc = subprocess.run([sys.executable, "-I", "-c", RUN_SCRIPT, json.dumps(job),
                           str(tmp_path / "unzipped"), repository],
                          cwd=tmp_path, env={"PATH": os.environ.get("PATH", ""),
                                             "INERTER_CACHE_DIR": str(cache)},
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    resources = Path(out["folder"]).resolve() / "resources"
    # The payload is unpacked once, into the cache, in a folder named by the archive's hash.
    unpacked = [p for p in (cache / "fmu-payload").iterdir()]
    assert len(unpacked) == 1 and not unpacked[0].name.startswith("."), unpacked
    # The compiled engine imports its kernels from a copy of kernels.py in the kernel cache.
    kernels = [m for m in out["files"] if m.startswith("inerter_kernels_")]
    assert len(kernels) == 1 and "inerter.engine.compiled" in out["files"], sorted(out["files"])
    assert Path(out["files"].pop(kernels[0])).read_bytes() == payload(fmu).read("inerter/engine/kernels.py")
    shipped = {resources, unpacked[0].resolve()}
    outside = {m: f for m, f in out["files"].items()
               if not shipped & set(Path(f).resolve().parents)}
    assert not outside, f"imported from outside the FMU: {outside}"
    modules = {m for m, f in out["files"].items() if unpacked[0].resolve() in Path(f).resolve().parents}
    assert "inerter.engine.compiled" in modules, sorted(out["files"])
    assert "pythonfmu.fmi2slave" in modules, sorted(out["files"])          # from the payload too
    for compiled, result in out["results"].items():
        path = "compiled" if compiled == "True" else "numpy"
        ref = model.simulate(stop_time=RUN_TIME, output_interval=dt, rtol=RTOL, metrics=False,
                             path=path)
        assert np.allclose(result["time"], ref.time, rtol=0, atol=1e-12)
        worst = max(np.max(np.abs(np.array(result[n]) - ref[n])) for n in outputs if ".r[" in n)
        assert worst <= 1e-9, f"{path} path: FMU and solver differ by {worst:.3g} m"


def test_the_requirements_the_fmu_states_are_the_packages(fmu):
    """resources/requirements.txt: numpy, scipy and numba with pyproject.toml's lower bounds, and a
    note naming the Python version pyproject.toml requires."""
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    bounds = {d.split(">=")[0]: d.split(">=")[1] for d in project["dependencies"] if ">=" in d}
    with zipfile.ZipFile(fmu) as z:
        text = z.read("resources/requirements.txt").decode()
    lines = [line for line in text.splitlines() if line and not line.startswith("#")]
    assert lines == [f"numpy>={bounds['numpy']}", f"scipy>={bounds['scipy']}", f"numba>={bounds['numba']}"]
    note = " ".join(line for line in text.splitlines() if line.startswith("#"))
    assert f"({project['requires-python'].removeprefix('>=')} or later)" in note


def test_the_files_found_are_kept_while_the_sources_stand_and_found_again_when_they_change(tmp_path, monkeypatch):
    """package_files follows the imports once per state of the sources (inerter/fmu/payload.py):
    asked again with nothing changed it does not parse a module; a slave that imports one more
    module is a new state, and its answer holds that module."""
    from inerter.fmu import payload
    slave = tmp_path / "slave.py"
    slave.write_text("import inerter.scene.reader\n")
    first = payload.package_files(slave)
    assert payload.PACKAGE_DIR / "scene" / "reader.py" in first
    assert payload.PACKAGE_DIR / "fmu" / "run.py" not in first

    def no_parsing(*_):
        raise AssertionError("the imports were followed again with no source changed")
    monkeypatch.setattr(payload, "closure", no_parsing)
    assert payload.package_files(slave) == first
    monkeypatch.undo()

    slave.write_text("import inerter.scene.reader\nimport inerter.fmu.run\n")
    second = payload.package_files(slave)
    assert payload.PACKAGE_DIR / "fmu" / "run.py" in second
    assert set(first) < set(second)


def test_a_new_process_reads_the_files_found_from_their_record(tmp_path, monkeypatch):
    """The answer is recorded in the kernels' cache folder under a hash of the sources, so a new
    process (here: the in-process answers forgotten) does not parse again; a record that cannot
    be read is found again by parsing."""
    from inerter.fmu import payload
    monkeypatch.setenv("INERTER_CACHE_DIR", str(tmp_path / "cache"))
    slave = tmp_path / "slave.py"
    slave.write_text("import inerter.scene.reader\n")
    monkeypatch.setattr(payload, "_FOUND", {})
    found = payload.package_files(slave)
    records = list((tmp_path / "cache" / "fmu-files").glob("*.json"))
    assert len(records) == 1

    def no_parsing(*_):
        raise AssertionError("the imports were followed again though their record was there")
    monkeypatch.setattr(payload, "_FOUND", {})
    with monkeypatch.context() as m:
        m.setattr(payload, "closure", no_parsing)
        assert payload.package_files(slave) == found

    records[0].write_text("not json")
    monkeypatch.setattr(payload, "_FOUND", {})
    assert payload.package_files(slave) == found
