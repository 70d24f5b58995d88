"""The kernels a run enters from Python, built ahead of time (inerter.engine.ahead).

Reference: numba's dispatchers of the same kernels, which every other test checks against the
oracle. A build compiles the same code for the same argument types and this machine's CPU, so a
run through the builds must give the dispatchers' results bit for bit: states, every output at
every sample, metrics, status and message, on every shipped scene.
"""
from __future__ import annotations

import importlib.util
import pickle
import sys
import textwrap

import numpy as np
import pytest

import inerter
from conftest import SCENARIOS
from inerter.engine import ahead, compiled

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason="numba is not available")

SCENES = sorted(SCENARIOS.glob("*.toml")) + sorted((SCENARIOS / "hard").glob("*.toml"))

#: The longest run (s): each scene runs to its own stop time, this at most.
LENGTH = 60.0


def test_the_setup_built_both_dimensions():
    """`inerter compile` (the set-up: Makefile) builds each dimension's entry kernels for this
    machine, every kernel of ENTRY_KERNELS in each."""
    for dimension in (2, 3):
        assert ahead.built(compiled._k, dimension), f"no {dimension}D build: run `inerter compile`"
    builds = ahead.load_builds(compiled._k)
    assert set(builds) == set(ahead.ENTRY_KERNELS)
    assert all(len(signatures) == 2 for signatures in builds.values())     # one per dimension


def _run(model, stop_time):
    result = model.simulate(stop_time=stop_time)
    return result, result._all_values() if result.status == "ok" or len(result.time) else None


@pytest.mark.parametrize("scene", SCENES, ids=lambda p: p.stem)
def test_a_run_through_the_builds_equals_the_dispatchers_bit_for_bit(scene):
    """Each shipped scene, both ways in one process: the builds, then numba's dispatchers
    (ENTRIES.dispatchers_only). The integrator loop is the build's where the scene runs it."""
    model = inerter.load(scene)
    stop_time = min(LENGTH, model.settings().stop_time)
    built, built_values = _run(model, stop_time)
    loop = compiled.ENTRIES.integrate_rk
    with compiled.ENTRIES.dispatchers_only():
        jit, jit_values = _run(model, stop_time)
        if model.settings().method in compiled._RK_CODE:        # no build: the dispatcher itself, no choice per call
            assert compiled.ENTRIES.integrate_rk is compiled._k.integrate_rk
    assert (built.status, built.message) == (jit.status, jit.message)
    assert np.array_equal(built.time, jit.time)
    assert np.array_equal(built.run.states, jit.run.states)
    if built_values is not None:
        assert np.array_equal(built_values, jit_values, equal_nan=True)
    assert built.metrics.keys() == jit.metrics.keys()
    for key, value in built.metrics.items():
        assert value == jit.metrics[key] or (value != value and jit.metrics[key] != jit.metrics[key]), key
    if model.settings().method in compiled._RK_CODE:
        assert any(target is not loop.dispatcher for target in loop._chosen.values())


# ----------------------------------------------------------------------------------------------
# The mechanism on a small module of its own: build, load, choose
# ----------------------------------------------------------------------------------------------
TOY = textwrap.dedent('''
    from numba import njit

    @njit(cache=False)
    def twice(x):
        return 2.0 * x

    @njit(cache=False)
    def total(a, scale):
        s = 0.0
        for v in a:
            s += twice(v)
        return s * scale
''')


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    """A kernels module `inerter_kernels_toy` with `total` compiled for a float array and built
    ahead of time (dimension 2)."""
    folder = tmp_path_factory.mktemp("toy")
    path = folder / "inerter_kernels_toy.py"
    path.write_text(TOY)
    spec = importlib.util.spec_from_file_location("inerter_kernels_toy", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    module.total(np.arange(3.0), 1.0)
    assert ahead.build(module, 2, names=("total",)) is not None
    yield module
    sys.modules.pop(spec.name, None)


def test_a_build_serves_the_types_it_was_made_for_and_the_dispatcher_the_others(toy):
    """The float-array call goes to the build, an int-array call (another type: a build would
    unbox it as floats) to numba's dispatcher; both give the closed form 2 Σ a · scale."""
    builds = ahead.load_builds(toy)
    assert list(builds) == ["total"] and len(builds["total"]) == 1
    entry = ahead.Entry(toy.total, builds["total"])
    assert entry(np.arange(4.0), 0.5) == 2 * 6.0 * 0.5
    assert entry(np.arange(4), 0.5) == 2 * 6.0 * 0.5
    targets = list(entry._chosen.values())
    assert len(targets) == 2 and targets[1] is toy.total and targets[0] is not toy.total
    assert entry(np.arange(4.0)[::2], 1.0) == 2 * (0.0 + 2.0)         # a strided array: another type
    assert entry._chosen[list(entry._chosen)[-1]] is toy.total


def test_no_build_where_its_table_is_unreadable_or_they_are_turned_off(toy, monkeypatch):
    """A damaged table of exports, one naming an export its module lacks, or INERTER_AHEAD=0: no
    builds, every call to the dispatcher."""
    module_path, table = ahead._paths(toy, 2)
    monkeypatch.setenv("INERTER_AHEAD", "0")
    assert ahead.load_builds(toy) == {}
    monkeypatch.delenv("INERTER_AHEAD")
    good = table.read_bytes()
    try:
        table.write_bytes(good[: len(good) // 2])
        assert ahead.load_builds(toy) == {}
        assert ahead.Entry(toy.total, {})(np.arange(3.0), 1.0) == 6.0
        exports = pickle.loads(good)
        table.write_bytes(pickle.dumps({"total": [(argtypes, "absent") for argtypes, _ in exports["total"]]}))
        assert ahead.load_builds(toy) == {}              # a table naming what its module lacks
    finally:
        table.write_bytes(good)
    assert pickle.loads(table.read_bytes()).keys() == {"total"}


def test_a_build_is_named_for_this_machine_and_the_kernels_source(toy):
    """The module's name carries the kernels module's name (its source's hash) and the platform's
    tag (the interpreter, numpy, numba, the CPU and its features): another machine sharing the
    cache folder, or another version of the kernels, does not load it."""
    name = ahead.module_name(toy, 2)
    assert name.startswith("inerter_kernels_toy_ahead2d_") and name.endswith(ahead.platform_tag())
    assert ahead.module_name(toy, 3) != name
