"""First use: the notice while the kernels compile (inerter.engine.compiled.CompileNotice), and the
ahead-of-time `inerter compile`. Nothing here compiles the engine's kernels: the notice is fed
numba's events by hand, or a one-line kernel compiles in a subprocess."""
from __future__ import annotations

import importlib.util
import io
import os
import shutil
import subprocess
import sys
import textwrap
import types as pytypes
from pathlib import Path

import pytest

compiled = pytest.importorskip("inerter.engine.compiled")
if not compiled.AVAILABLE:                                   # pragma: no cover
    pytest.skip(compiled.WHY_NOT, allow_module_level=True)

from numba.core import types  # noqa: E402

from inerter import cli  # noqa: E402
from inerter.engine import ahead  # noqa: E402

KERNELS = compiled._k


def _event(name, args, module=KERNELS.__name__):
    """A numba:compile event of kernel `name` with argument types `args`."""
    func = pytypes.SimpleNamespace(__name__=name, __module__=module)
    return pytypes.SimpleNamespace(data={"dispatcher": pytypes.SimpleNamespace(py_func=func), "args": args})


def _params(dim):
    """The numba type of a scene's P: 2D, or 3D with its `spatial` slot."""
    arrays = [types.Array(types.float64, 1, "C")] * len(KERNELS.PARAMS)
    if dim == 3:
        arrays.append(types.Array(types.int64, 1, "C"))
    return types.Tuple(arrays)


def test_notice_when_a_kernel_compiles():
    out = io.StringIO()
    notice = compiled.CompileNotice(stream=out)
    outer = _event("integrate_rk", (types.int64, _params(2)))
    inner = _event("assemble", (_params(2),))
    numba_own = _event("impl", (types.float64,), module="numba.np.arrayobj")
    notice.on_start(outer)
    assert "compiling the engine's 2D kernels for this machine" in out.getvalue()
    for event in (inner, numba_own):                 # compiled inside the outer one: not said again
        notice.on_start(event)
        notice.on_end(event)
    assert out.getvalue().count("inerter:") == 1
    notice.on_end(outer)
    assert out.getvalue().splitlines()[-1].startswith("inerter: ... done in")
    # a second compilation of the same dimension is said only once it has taken LATE seconds
    notice.on_start(_event("max_residual", (types.float64, _params(2))))
    notice.on_end(_event("max_residual", (types.float64, _params(2))))
    assert out.getvalue().count("inerter:") == 2
    # the other dimension is said at once
    notice.on_start(_event("signal_history", (_params(3),)))
    notice.on_end(_event("signal_history", (_params(3),)))
    assert "3D kernels" in out.getvalue()


def test_a_long_compilation_is_said_while_it_happens():
    out = io.StringIO()
    notice = compiled.CompileNotice(stream=out)
    notice.LATE = 0.05
    notice._announced.add(2)
    event = _event("signal_history", (_params(2),))
    notice.on_start(event)
    notice._timer.join()                             # the compilation goes on past LATE
    assert "compiling the engine's 2D kernels: the outputs" in out.getvalue()
    notice.on_end(event)
    assert "done in" in out.getvalue()


def test_silenced():
    out = io.StringIO()
    notice = compiled.CompileNotice(stream=out)
    notice.enabled = False
    event = _event("integrate_rk", (_params(2),))
    notice.on_start(event)
    notice.on_end(event)
    assert out.getvalue() == "" and notice.seconds > 0.0


def test_notice_on_a_cache_miss_only(tmp_path):
    """A kernel compiled by numba says so on stderr; the next process loads it from numba's cache
    and says nothing."""
    (tmp_path / "inerter_kernels_probe.py").write_text(textwrap.dedent("""
        from numba import njit

        @njit(cache=True)
        def probe(P):
            return P[0].shape[0]
    """))
    script = textwrap.dedent("""
        import numpy as np
        import inerter.engine.compiled as compiled
        import inerter_kernels_probe as k
        P = tuple(np.zeros(1) for _ in compiled._k.PARAMS)
        print(k.probe(P))
    """)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path)] + sys.path))

    def run():
        done = subprocess.run([sys.executable, "-c", script], env=env, cwd=tmp_path, capture_output=True,
                              text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        return done.stderr

    first, second = run(), run()
    assert "inerter: compiling the engine's 2D kernels" in first and "done in" in first
    assert "inerter:" not in second


def test_compile_command(monkeypatch, capsys):
    """`inerter compile` says once what it compiles, with the kernels' notice silenced meanwhile."""
    import inerter.api

    def fake_warm_up(spatial=False, parallel=False):
        assert not compiled.NOTICE.enabled and spatial
        return 0.5
    monkeypatch.setattr(inerter.api, "warm_up", fake_warm_up)
    wrote = []
    monkeypatch.setattr(cli, "write_bytecode", lambda: wrote.append(True) or True)
    monkeypatch.setattr(ahead, "built", lambda kernels, dimension: True)
    assert cli.main(["compile"]) == 0
    assert wrote == [True]
    captured = capsys.readouterr()
    assert "compiling the engine's 2D and 3D kernels" in captured.err
    assert "(all were in the cache)" in captured.err and "loaded in 0.5 s" in captured.out
    assert "building" not in captured.err                   # both dimensions' builds are there
    assert compiled.NOTICE.enabled


def test_compile_builds_the_entry_kernels_and_says_what_it_could_not(monkeypatch, capsys):
    """`inerter compile` then builds the kernels a run enters ahead of time (inerter.api.build_ahead)
    where this machine lacks them, saying so with its expected time; a dimension that cannot be built
    is named with the reason, and the command still succeeds (its kernels load from numba's cache)."""
    import inerter.api
    monkeypatch.setattr(inerter.api, "warm_up", lambda spatial=False, parallel=False: 0.5)
    monkeypatch.setattr(cli, "write_bytecode", lambda: True)
    monkeypatch.setattr(ahead, "built", lambda kernels, dimension: False)
    asked = []

    def fake_build_ahead(dims, parallel):
        asked.append(tuple(dims))
        return {2: None, 3: "error: command 'gcc' failed: No such file or directory"}
    monkeypatch.setattr(inerter.api, "build_ahead", fake_build_ahead)
    assert cli.main(["compile"]) == 0
    err = capsys.readouterr().err
    assert asked == [(2, 3)]
    assert "building the kernels a run enters from Python" in err and f"about {ahead.BUILD_SECONDS} s" in err
    assert "the 3D kernels could not be built ahead of time (error: command 'gcc' failed" in err
    assert "2D kernels could not" not in err


def test_compile_writes_the_bytecode_where_imports_write_none(tmp_path, monkeypatch):
    """`inerter compile` writes the package's bytecode (cli.write_bytecode) with
    PYTHONDONTWRITEBYTECODE set, and a process started with it set then reads the modules from that
    bytecode instead of compiling their sources (``python -v`` names the code object's origin)."""
    package = tmp_path / "inerter"
    shutil.copytree(Path(cli.__file__).parent, package, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(sys, "dont_write_bytecode", True)
    assert cli.write_bytecode(package)
    sources = sorted(package.rglob("*.py"))
    assert sources and all(Path(importlib.util.cache_from_source(str(f))).is_file() for f in sources)
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1", "PYTHONPATH": str(tmp_path)}
    done = subprocess.run([sys.executable, "-v", "-c", "import inerter.scene.reader"], env=env, cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    origins = [line for line in done.stderr.splitlines() if line.startswith("# code object from") and str(package) in line]
    reader = importlib.util.cache_from_source(str(package / "scene" / "reader.py"))
    assert f"# code object from '{reader}'" in origins
    assert all(".pyc" in line for line in origins), [line for line in origins if ".pyc" not in line]


def test_compile_says_so_when_its_scenes_are_missing(monkeypatch, tmp_path, capsys):
    """warm_up compiles on the shipped two-bar scene; where it cannot find it, `inerter compile`
    fails with one line instead of reporting success having compiled nothing."""
    import inerter.common.locations as locations
    monkeypatch.setattr(locations, "scenarios", lambda: tmp_path)
    for args in (["compile", "--planar"], ["compile"]):     # the second with its 3D process alongside
        assert cli.main(args) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) >= 1 and "two_bar_2d.toml" in err[-1] and "missing" in err[-1]


def test_kernel_registries_load_without_scipy_linalg():
    """A warm process: the registries numba loads with the first cached kernel
    (inerter.engine.compiled._blas_check_without_scipy_linalg) leave scipy.linalg unimported, and numba
    still knows BLAS is there (its flag as numba's own check sets it, from the scipy installed
    here); np.dot compiled afterwards imports scipy.linalg and agrees with numpy to rounding (1e-15)."""
    script = textwrap.dedent("""
        import sys
        import numpy as np
        import inerter.engine.compiled
        from numba.core.registry import cpu_target
        cpu_target.target_context.refresh()          # what loading the first cached kernel does
        import numba.np.arraymath as arraymath
        print("scipy.linalg" in sys.modules, arraymath._HAVE_BLAS)
        import scipy.linalg.cython_blas               # numba's own check, now
        from numba import njit
        a = np.array([[1.0, 2.0], [3.0, 4.0]])
        b = np.array([[0.5, -1.0], [2.0, 0.25]])
        print(float(np.max(np.abs(njit(lambda x, y: np.dot(x, y))(a, b) - a @ b))))
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    imported, have_blas, difference = done.stdout.split()
    assert imported == "False" and have_blas == "True"
    assert float(difference) <= 1e-15


def test_kernels_copy_has_its_bytecode_where_python_writes_none(tmp_path):
    """The kernels' copy in the cache gets its bytecode once, also under PYTHONDONTWRITEBYTECODE
    (inerter.engine.compiled._write_bytecode), so that no later process compiles its source; the
    bytecode is what the import system would have written (importlib.util.cache_from_source)."""
    import importlib.util
    env = dict(os.environ, INERTER_CACHE_DIR=str(tmp_path), PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.pathsep.join(sys.path))
    script = "import inerter.engine.compiled as c; print(c._k.__file__)"
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    source = done.stdout.strip()
    assert source.startswith(str(tmp_path))
    cached = importlib.util.cache_from_source(source)
    assert os.path.isfile(cached)
    with open(cached, "rb") as fh:
        assert fh.read(4) == importlib.util.MAGIC_NUMBER


CALLED_FROM_PYTHON = r"""
import inspect, json, pathlib, re, sys
from numba.core.dispatcher import Dispatcher
from inerter.api import warm_up
from inerter.engine import compiled
warm_up(spatial=True, parallel=True)      # as `inerter compile` runs it
root = pathlib.Path(compiled.__file__).resolve().parents[1]
names = set()
for path in [*root.rglob("*.py"), *root.parent.glob("fmu_src/*.py")]:
    text = path.read_text()
    names |= {n for n in re.findall(r"\b_k\.(\w+)", text) if not re.search(rf"_k\.{n}\.py_func", text)}
    names |= set(re.findall(r"\bENTRIES\.(\w+)\(", text))     # through their builds, else these
found = {}
for name in sorted(names):
    kernel = getattr(compiled._k, name, None)
    if isinstance(kernel, Dispatcher):
        takes_scene = "P" in inspect.signature(kernel.py_func).parameters
        found[name] = [len(kernel.signatures), takes_scene]
print(json.dumps(found))
"""


def test_the_ahead_of_time_compilation_covers_every_kernel_called_from_python():
    """Every kernel the package calls from Python (`_k.NAME` and `ENTRIES.NAME` in its sources, the FMU's slave too) is
    compiled or loaded by `inerter compile`'s warm-up, for 2D and 3D where it takes a scene's tables
    P: else a fresh installation compiles it in the middle of a run (an FMU's initialisation, a failed
    run's message, an RK4 co-simulation step, scipy's methods on the kernels). In a fresh process,
    after the warm-up alone (the kernels load from the cache the set-up filled)."""
    import json
    done = subprocess.run([sys.executable, "-c", CALLED_FROM_PYTHON], capture_output=True, text=True, timeout=1200)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout.strip().splitlines()[-1])
    assert {"signal_values", "rk4_cosim_step", "constraint_residual", "_rhs", "integrate_rk"} <= set(found)
    # wind moves 3D rotational elements' angles on (scipy's methods), windings_along and
    # windings_between read them along a dense output's steps; 2D has nothing to wind
    one_dimension = {"wind", "windings_along", "windings_between"}
    missing = {name: count for name, (count, takes_scene) in found.items()
               if count < (2 if takes_scene and name not in one_dimension else 1)}
    assert missing == {}
