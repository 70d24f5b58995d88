"""Functions written once for the kernels and the readable path (inerter.common.inlined): the kernels
compile them in, Python runs them as written, all the way down.

Before, a law whose ``.py_func`` called another law went through that law's numba dispatcher, which
compiled itself on first use: the numpy path of a device scene compiled a few laws in the middle of
a run, on a fresh installation (measured: inerter.elements.device.state_force, state_rates, settle,
device_inertia._axis/_part/_gram/_housing_spin, inerter.inertance/convective)."""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
from numba import njit

from conftest import ROOT
from inerter.common.inlined import KernelFunction, compiled_copy, inlined, not_inlined

#: numpy-path runs that reach every nested law of the device, the inertance and the prismatic spring
#: (the scenes of the measurement above).
SCENES = ["scenarios/braced_frame_3d.toml", "scenarios/series_inerter_2d.toml",
          "tests/data/device_bar_2d_compact.toml", "tests/data/device_combo_ground_slider_2d.toml",
          "tests/data/device_combo_mount_stops_3d.toml", "tests/data/device_combo_series_3d.toml"]

PROBE = """
import json, sys
from numba.core import event
import inerter
compiled = []
class Listener(event.Listener):
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        compiled.append(f"{f.__module__}.{f.__name__}")
    def on_end(self, ev):
        pass
event.register("numba:compile", Listener())
for scene in sys.argv[1:]:
    inerter.load(scene).simulate(stop_time=0.01, path="numpy", metrics=False)
print(json.dumps(compiled))
"""


def test_the_numpy_path_compiles_nothing_on_an_empty_cache(tmp_path):
    """A fresh numba cache (NUMBA_CACHE_DIR empty): numpy-path runs of the scenes above fire no
    numba compilation at all."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba"))
    done = subprocess.run([sys.executable, "-c", PROBE, *SCENES], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.strip().splitlines()[-1]) == []


@inlined
def _square(x):
    return x * x


@inlined
def _hypotenuse(x, y):
    return math.sqrt(_square(x) + _square(y))


@not_inlined
def _scaled_hypotenuse(x, y, s):
    return s * _hypotenuse(x, y)


@njit
def _kernel(x, y):
    return _hypotenuse(x, y) + _scaled_hypotenuse(x, y, 2.0)


def test_a_kernel_function_runs_as_written_from_python_and_compiles_into_a_kernel():
    """Closed form: hypot(3, 4) = 5. From Python the function (and those it calls) run uncompiled:
    no dispatcher of theirs gets a compiled signature; in a kernel they compile in (inlined or
    called) and give the same value; compiled_copy compiles one on its own."""
    assert isinstance(_hypotenuse, KernelFunction) and isinstance(_scaled_hypotenuse, KernelFunction)
    assert _hypotenuse(3.0, 4.0) == 5.0 and _scaled_hypotenuse(3.0, 4.0, 2.0) == 10.0
    assert _square.signatures == [] and _hypotenuse.signatures == [] and _scaled_hypotenuse.signatures == []
    assert _kernel(3.0, 4.0) == 15.0
    assert _scaled_hypotenuse.signatures != []          # compiled on its own, called by the kernel
    assert compiled_copy(_hypotenuse)(np.float64(6.0), 8.0) == 10.0


def test_every_law_of_the_layers_below_the_engine_is_a_kernel_function():
    """No plain numba dispatcher is left where the numpy path runs code written for the kernels: the
    element kinds, the rotation math and the ground motion's terms."""
    import importlib
    import pkgutil

    import inerter.elements
    from numba.core.dispatcher import Dispatcher
    modules = [importlib.import_module(f"inerter.elements.{m.name}") for m in pkgutil.iter_modules(inerter.elements.__path__)]
    modules += [importlib.import_module("inerter.common.rotations"), importlib.import_module("inerter.scene.ground_motion")]
    plain = [f"{m.__name__}.{name}" for m in modules for name, value in vars(m).items()
             if isinstance(value, Dispatcher) and not isinstance(value, KernelFunction)]
    assert plain == []
