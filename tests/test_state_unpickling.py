"""A stepper's state is unpickled restricted (inerter.engine.simulation.load_state): bytes handed back
to ``set_state`` (an importer's fmi2DeSerializeFMUstate) may name only the globals a state holds
(STATE_GLOBALS), so a crafted pickle runs nothing; the states every method makes on both paths
still restore bit for bit. tests/test_fmu_refusals.py has the FMU's refusal (fmi2Error at
fmi2DeSerializeFMUstate)."""
from __future__ import annotations

import io
import os
import pickle
import re
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.engine.simulation import STATE_GLOBALS, load_state

ROOT = Path(__file__).resolve().parents[1]
#: A 2D scene with an input force (the state holds the held inputs), and the 3D bar whose spring
#: winds past half a turn (the state holds its φ_ref).
INPUT_SCENE, INPUT = ROOT / "scenarios" / "two_bar_2d.toml", "C.f[2]"
BAR_3D = ROOT / "tests" / "data" / "winding_bar_3d.toml"
METHODS = ["DOP853", "RK45", "RK4", "Radau", "BDF", "LSODA"]
STEP = 0.01


class _Recorder(pickle.Unpickler):
    """Unpickles as pickle does, noting every global the bytes name."""

    def __init__(self, blob):
        super().__init__(io.BytesIO(blob))
        self.names = set()

    def find_class(self, module, name):
        self.names.add((module, name))
        return super().find_class(module, name)


class _Runs:
    """A pickle whose loading would call `fn(*args)` (pickle's __reduce__)."""

    def __init__(self, fn, *args):
        self.fn, self.args = fn, args

    def __reduce__(self):
        return self.fn, self.args


def _stepped(model, path, method, until):
    st = model.stepper(method=method, path=path, stop_time=1.0)
    for k in range(1, until + 1):
        if k == 5 and INPUT in st.input_index:
            st.set_input(INPUT, 2.0)          # the integration restarts: its state is a new one
        st.step(k * STEP)
    return st


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("path", ["numpy", "compiled"])
@pytest.mark.parametrize("scene", [INPUT_SCENE, BAR_3D], ids=lambda p: p.stem)
def test_every_methods_state_restores_bit_for_bit_naming_only_admitted_globals(scene, path, method):
    """A state taken mid-run (the running integration: scipy's solver objects on the numpy path and
    for Radau/BDF on the compiled one, the compiled loop's arrays for DOP853/RK45) names only
    globals of STATE_GLOBALS, and a fresh stepper it is restored into steps on as the stepper it
    was taken from, bit for bit (states and outputs)."""
    model = inerter.load(scene, **({"w": 20.0} if scene == BAR_3D else {}))
    st = _stepped(model, path, method, 12)
    blob = st.get_state()
    recorder = _Recorder(blob)
    recorder.load()
    assert all(name in STATE_GLOBALS.get(module, ()) for module, name in recorder.names), recorder.names
    other = model.stepper(method=method, path=path, stop_time=1.0)
    other.set_state(blob)
    for k in range(13, 31):
        st.step(k * STEP)
        other.step(k * STEP)
        assert np.array_equal(other.y, st.y) and other.output_values() == st.output_values(), k


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_a_pickle_that_would_run_code_is_refused_and_runs_nothing(tmp_path, path):
    """set_state of bytes whose unpickling would call os.system (create a file), open a file
    (io.open; builtins.eval, a builtin not one a state holds; numpy.save, numpy's but no array
    reconstruction) or import a module refuses them with
    pickle.UnpicklingError naming the global, before anything runs: no file is made, and the
    stepper steps on as before."""
    model = inerter.load(INPUT_SCENE)
    st = _stepped(model, path, "DOP853", 3)
    before = st.get_state()
    marker = tmp_path / "ran"
    payloads = [_Runs(os.system, f"touch {marker}"), _Runs(open, str(marker), "w"),
                _Runs(eval, f"open({str(marker)!r}, 'w')"), _Runs(__import__, "subprocess"),
                _Runs(np.save, str(marker), np.zeros(1))]
    for payload in payloads:
        blob = pickle.dumps((0.0, payload))
        named = re.escape(f"it names {payload.fn.__module__}.{payload.fn.__name__}, which no stepper state holds")
        with pytest.raises(pickle.UnpicklingError, match=named):
            st.set_state(blob)
        with pytest.raises(pickle.UnpicklingError, match=named):
            load_state(blob)
        assert not marker.exists() and not marker.with_suffix(".npy").exists()
    assert st.get_state() == before
