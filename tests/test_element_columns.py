"""A column of one translational element's output (what a metric or ``result[name]`` reads) is
evaluated for that element alone (kernels.element_signals2/3), and gives the values every signal
evaluated together gives (kernels.signal_history), bit for bit: the same law at the same state and
the same accelerations. Reference: signal_history, the path the FMU's and the whole run's outputs take.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter import elements
from inerter.elements import TRANSLATIONAL, output_suffixes
from inerter.engine import compiled

FAMILY = output_suffixes(TRANSLATIONAL)

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")

ROOT = Path(__file__).resolve().parents[1]
SCENES = ["scenarios/two_bar_2d.toml", "scenarios/braced_frame_3d.toml", "scenarios/two_bar_2d_device.toml",
          "scenarios/hard/backlash_device_2d.toml", "scenarios/series_inerter_2d.toml",
          "tests/data/device_combo_series_3d.toml", "scenarios/double_pendulum_3d.toml"]


@pytest.mark.parametrize("scene", SCENES, ids=lambda s: Path(s).stem)
def test_an_elements_column_alone_is_every_signals_column(scene):
    model = inerter.load(ROOT / scene, **{"experiment.stop_time": 0.5})
    result = model.simulate(metrics=False)
    assert result.status == "ok", result.message
    kernel = compiled.compile_mechanism(model.mechanism)
    alpha = model.settings().alpha
    every, k = kernel.signal_history(model.signals, kernel.signal_order(model.signals), result.time,
                                     result.run.states, None, alpha)
    assert k == len(result.time)
    checked = 0
    for i, name in enumerate(model.signals.names):
        index = kernel.signal_index(name)
        if index is None or kernel.element_slot(index)[0] < 0:
            continue
        alone, k = kernel.signal_column(index, result.time, result.run.states, None, alpha)
        assert k == len(result.time)
        assert np.array_equal(alone, every[:, i], equal_nan=True), name
        checked += 1
    translational = [e for e in model.scene.elements.values() if elements.translational(e.type)]
    assert translational and checked >= len(FAMILY) * len(translational)


@pytest.mark.parametrize("scene", SCENES[:3], ids=lambda s: Path(s).stem)
def test_an_elements_dense_output_alone_is_every_signals(scene):
    """The same between samples: an element's output on the run's dense output (kernels.dense_signal,
    which calls signal_column; through LocalDense's intervals) against every signal at
    the dense output's states."""
    model = inerter.load(ROOT / scene, **{"experiment.stop_time": 0.5})
    result = model.simulate(metrics=False)
    kernel = compiled.compile_mechanism(model.mechanism)
    alpha = model.settings().alpha
    times = np.linspace(0.0, 0.5, 41)[1:-1] + 1e-3
    states = np.asarray(result.run.dense(times)).T
    every, _ = kernel.signal_history(model.signals, kernel.signal_order(model.signals), times, states, None, alpha)
    for i, name in enumerate(model.signals.names):
        index = kernel.signal_index(name)
        if index is None or kernel.element_slot(index)[0] < 0:
            continue
        alone, k = kernel.dense_signal(result.run.dense, index, times, None, alpha)
        assert k == len(times)
        assert np.array_equal(alone, every[:, i], equal_nan=True), name
