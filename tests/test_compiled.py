"""The compiled fast path (inerter.compiled): the kernel against Mechanism.accelerations, the
compiled integrators against the oracle. No timing assertions (timings: benchmarks/)."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter import compiled
from inerter.simulation import integrate

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "scenarios").glob("*.toml"))
PLANAR = [p for p in SCENES if inerter.load(p).scene.dimension == 2]
PAPER = [ROOT / "scenarios" / "lumped_mass_2d.toml", ROOT / "scenarios" / "two_bar_2d.toml"]

needs_numba = pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")


def test_numba_missing_falls_back_to_numpy():
    """Without numba the kernel is the numpy path (and says so); with it, the compiled one."""
    model = inerter.load(PAPER[1])
    kernel = compiled.compile_mechanism(model.mechanism)
    assert kernel.compiled == compiled.AVAILABLE
    if not compiled.AVAILABLE:
        pytest.skip(f"numba missing, numpy path used: {compiled.WHY_NOT}")


def _random_states(mech, rng, count=12):
    for _ in range(count):
        q = mech.q0 + 0.2 * rng.standard_normal(mech.n)
        v = 2.0 * rng.standard_normal(mech.n)
        inputs = 5.0 * rng.standard_normal(len(mech.input_names)) if mech.input_names else None
        yield float(rng.uniform(0.0, 10.0)), q, v, inputs, float(rng.choice([0.0, rng.uniform(0.0, 50.0)]))


@needs_numba
@pytest.mark.parametrize("path", PLANAR, ids=lambda p: p.stem)
@pytest.mark.parametrize("centripetal", [True, False])
def test_kernel_matches_numpy_path(path, centripetal):
    model = inerter.load(path, **{"effects.centripetal": centripetal})
    mech = model.mechanism
    kernel = compiled.compile_mechanism(mech)
    rng = np.random.default_rng(7)
    for t, q, v, inputs, alpha in _random_states(mech, rng):
        a_ref, lam_ref = mech.accelerations(t, q, v, inputs, alpha)
        a, lam = kernel.accelerations(t, q, v, inputs, alpha)
        ref = np.concatenate((a_ref, lam_ref))
        got = np.concatenate((a, lam))
        assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref)), (t, alpha)
        assert kernel.constraint_residual(q) == pytest.approx(mech.constraint_residual(q), rel=1e-12, abs=1e-15)


@needs_numba
def test_gravity_and_step_force_and_chain(tmp_path):
    """Terms the paper scenes lack: gravity, constant/step forces, dampers, rotational dampers
    between bodies, a long chain (band solve after reordering)."""
    import sys
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from chain_scene import write_chain
    finally:
        sys.path.pop(0)
    for links, gravity in ((3, True), (12, False)):
        path = write_chain(tmp_path / f"chain{links}.toml", links, gravity=gravity, extra_forces=True)
        model = inerter.load(path)
        mech = model.mechanism
        kernel = compiled.compile_mechanism(mech)
        if links == 12:
            kl, ku, N = kernel.band
            assert kl + ku < N // 2
        rng = np.random.default_rng(links)
        for t, q, v, inputs, alpha in _random_states(mech, rng, 6):
            ref = np.concatenate(mech.accelerations(t, q, v, inputs, alpha))
            got = np.concatenate(kernel.accelerations(t, q, v, inputs, alpha))
            assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref))


@needs_numba
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_compiled_integrator_takes_scipys_steps(method):
    """Same error control, step-size rule and dense output as scipy: same step count, and the
    samples agree far below the tolerance."""
    model = inerter.load(PAPER[1])
    s = model.settings(method=method, stop_time=2.0, rtol=1e-8, atol=1e-10)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(model.mechanism, s)
    assert a.status == "ok" and a.steps == b.steps
    assert a.states.shape == b.states.shape
    assert np.max(np.abs(a.states - b.states)) < 1e-8


@needs_numba
def test_compiled_rk4_matches_numpy_rk4():
    model = inerter.load(PAPER[1])
    s = model.settings(method="RK4", stop_time=1.0, step=2e-3)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(model.mechanism, s)
    assert a.steps == b.steps and a.evaluations == b.evaluations
    assert np.max(np.abs(a.states - b.states)) < 1e-11


@needs_numba
@pytest.mark.parametrize("path", PAPER, ids=lambda p: p.stem)
@pytest.mark.parametrize("centripetal", [True, False])
def test_compiled_integration_against_oracle(path, centripetal):
    """Compiled DOP853 at tight tolerance within 1e-9 m of the oracle (positions of all points)."""
    model = inerter.load(path, **{"effects.centripetal": centripetal})
    stop = 2.0
    run = compiled.integrate_compiled(model.mechanism, model.settings(method="DOP853", stop_time=stop, rtol=1e-11,
                                                                      atol=1e-13))
    oracle = model.oracle()
    ref = integrate(oracle.mechanism, oracle.settings(stop_time=stop, rtol=1e-12, atol=1e-14))
    assert run.status == "ok" and len(run.time) == len(ref.time)
    kernel = compiled.compile_mechanism(model.mechanism)
    pa, pb = kernel.point_positions(run.states), kernel.point_positions(ref.states)
    err = max(np.max(np.abs(pa[k] - pb[k])) for k in pa)
    assert err <= 1e-9


@needs_numba
def test_scipy_methods_and_projection_on_compiled_rhs():
    model = inerter.load(PAPER[0])
    s = model.settings(method="Radau", stop_time=0.5, rtol=1e-8, atol=1e-10)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(model.mechanism, s)
    assert a.status == "ok" and np.max(np.abs(a.states - b.states)) < 1e-9
    s = model.settings(method="DOP853", constraint="projection", stop_time=0.2, rtol=1e-9, atol=1e-11)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(model.mechanism, s)
    assert a.status == "ok" and np.max(np.abs(a.states - b.states)) < 1e-9


@needs_numba
def test_failure_is_reported_not_raised():
    model = inerter.load(PAPER[1])
    settings = dataclasses.replace(model.settings(stop_time=5.0, rtol=1e-10, atol=1e-12), max_steps=10)
    run = compiled.integrate_compiled(model.mechanism, settings)
    assert run.status == "failed" and "max_steps" in run.message
    assert 1 <= len(run.time) < 501


@needs_numba
def test_bench_writes_table_csv_and_png(tmp_path):
    from inerter.bench import main_bench
    code = main_bench([str(PAPER[0]), "--out", str(tmp_path), "--stop-time", "0.5", "--paths", "compiled",
                       "--methods", "DOP853,RK4", "--quick"])
    assert code == 0
    for ext in ("md", "csv", "png"):
        assert (tmp_path / f"work_precision.{ext}").stat().st_size > 0
    assert "compiled DOP853" in (tmp_path / "work_precision.md").read_text()
