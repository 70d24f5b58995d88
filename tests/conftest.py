"""Shared, expensive simulations: each is computed once per test session."""
from __future__ import annotations

from pathlib import Path

import pytest

import inerter

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
LUMPED = SCENARIOS / "lumped_mass_2d.toml"
TWO_BAR = SCENARIOS / "two_bar_2d.toml"


def one_line_error(capsys, *fragments):
    """A command's stderr: one line, starting as every error does, holding each fragment."""
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    assert "\n" not in err and err.startswith("inerter: error: "), err
    for fragment in fragments:
        assert fragment in err, (fragment, err)
    return err


def _cached(cache, key, fn):
    if key not in cache:
        cache[key] = fn()
    return cache[key]


@pytest.fixture(scope="session")
def runs():
    """runs(scene_path, centripetal, **simulate_kwargs) → Result, shared across the session."""
    cache = {}

    def get(scene, centripetal=True, oracle=False, **kw):
        key = (str(scene), centripetal, oracle, tuple(sorted(kw.items())))

        def compute():
            model = inerter.load(scene, **{"effects.centripetal": centripetal})
            if oracle:
                model = model.oracle()
            return model.simulate(**kw)
        return _cached(cache, key, compute)
    return get


@pytest.fixture(scope="session")
def fmu_runs():
    """fmu_runs(scene_path, **overrides, stop_time=..., step=...) → FMU result (fmpy), shared."""
    from inerter.fmu.run import simulate_fmu
    cache = {}

    def get(scene, stop_time=None, step=None, metrics=True, **overrides):
        key = (str(scene), stop_time, step, metrics, tuple(sorted(overrides.items())))
        return _cached(cache, key, lambda: simulate_fmu(scene, overrides, stop_time=stop_time, step=step,
                                                        metrics=metrics))
    return get
