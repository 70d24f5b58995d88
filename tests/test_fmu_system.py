"""The coupled example (two-bar FMU + PD-controller FMU) as system-structure files, run by libcosim
(the Open Simulation Platform's engine) from each file, against the project's own master loops
(inerter/fmu/cosim.py).

What is compared, at every communication point of a 2 s run with h = 10 ms:
- libcosim's fixed-step algorithm is parallel (Jacobi): run from OspSystemStructure.xml and from
  SystemStructure.ssd it gives the plant's C.r[2], C.v[2] and the force its input C.f[2] held over
  each step bit for bit as the project's parallel loop does;
- the one step's delay of that coupling, exactly: in the parallel runs the force held over
  [t_k, t_k+1] is the controller's law at t_k-1 (k >= 1), in the sequential loop the law at t_k,
  each compared bit for bit with the law evaluated here;
- what the delay costs: the parallel and sequential runs differ by a first-order term, which
  halves when h halves, as each run's difference from the one-scene solution does.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

import inerter
from inerter.fmu import cosim
from inerter.fmu.build import FmuBuildError


ROOT = Path(__file__).resolve().parents[1]
STOP, STEP = 2.0, 0.01

#: Runs a system-structure file in libcosim, one step at a time, and prints per step: time (ns),
#: the plant's C.r[2], C.v[2], C.f[2] (the force it held over the step) and the controller's F.
LIBCOSIM = r"""
import json, sys
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver
log_output_level(CosimLogLevel.WARNING)
path, steps = sys.argv[1], int(sys.argv[2])
if path.endswith(".ssd"):
    execution = CosimExecution.from_ssp_file(path)
else:
    execution = CosimExecution.from_osp_config_file(path)
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
index = {n: execution.slave_index_from_instance_name(n) for n in ("plant", "controller")}
vr = {n: {v.name.decode(): v.reference for v in execution.slave_variables(i)} for n, i in index.items()}
rows = []
for _ in range(steps):
    assert execution.step()
    plant = observer.last_real_values(index["plant"], [vr["plant"][n] for n in ("C.r[2]", "C.v[2]", "C.f[2]")])
    (force,) = observer.last_real_values(index["controller"], [vr["controller"]["F"]])
    rows.append([execution.status().current_time, *plant, force])
print(json.dumps(rows))
"""


@pytest.fixture(scope="module")
def system(tmp_path_factory):
    return cosim.build_system(tmp_path_factory.mktemp("system"), step=STEP)


@pytest.fixture(scope="module")
def gains():
    return cosim.controller_gains()


def law(gains, y, v):
    """The controller's law, in the order of operations of fmu_src/pd_controller.py."""
    return -gains["kp"] * (y - gains["reference"]) - gains["kd"] * v


def run_libcosim(path: Path, steps: int, cwd: Path) -> np.ndarray:
    proc = subprocess.run([sys.executable, "-I", "-c", LIBCOSIM, str(path), str(steps)], cwd=cwd,
                          env={"PATH": os.environ.get("PATH", "")}, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return np.array(json.loads(proc.stdout.strip().splitlines()[-1]))


@pytest.fixture(scope="module")
def loops(system, gains):
    return {c: cosim.run_system(system["plant"], system["controller"], STOP, STEP, gains, c)
            for c in cosim.COUPLINGS}


def test_the_gains_are_the_one_scene_actuators():
    scene = inerter.load(ROOT / "scenarios" / "two_bar_2d_pd.toml")
    p = {q["name"]: q["value"] for q in scene.parameter_info()}
    assert cosim.controller_gains() == {"kp": p["kp"], "kd": p["kd"], "reference": 2 ** 0.5}


def test_the_ssd_is_valid_ssp_1_0(system):
    """Against the SSP 1.0 schema fmpy carries (fmpy reads .ssp archives only, so the file is
    checked here directly)."""
    from fmpy.ssp.ssd import validate_tree
    validate_tree(etree.parse(str(system["ssd"])).getroot(), "SystemStructureDescription.xsd")


@pytest.mark.parametrize("kind", ["osp", "ssd"])
def test_libcosim_runs_the_system_file_as_the_parallel_loop_bit_for_bit(system, loops, kind, tmp_path):
    steps = len(loops["parallel"].t) - 1
    rows = run_libcosim(system[kind], steps, tmp_path)
    par = loops["parallel"]
    assert np.array_equal(rows[:, 0], np.arange(1, steps + 1) * round(STEP * 1e9))
    assert np.array_equal(rows[:, 1], par.y[1:])
    assert np.array_equal(rows[:, 2], par.v[1:])
    assert np.array_equal(rows[:, 3], par.F[:-1])
    # libcosim's own data shows the delay: the plant holds over step k what the controller gave
    # after step k - 1.
    assert np.array_equal(rows[1:, 3], rows[:-1, 4])


def test_the_parallel_loop_holds_the_law_one_step_late_and_the_sequential_one_does_not(loops, gains):
    par, seq = loops["parallel"], loops["sequential"]
    assert np.array_equal(par.F[1:], law(gains, par.y[:-1], par.v[:-1]))
    assert par.F[0] == law(gains, par.y[0], par.v[0])
    assert np.array_equal(seq.F, law(gains, seq.y, seq.v))
    assert par.y[0] == seq.y[0] and par.F[0] == seq.F[0]
    assert par.y[1] == seq.y[1]                          # the first step holds the same force
    assert not np.array_equal(par.y, seq.y)


def test_the_delay_costs_a_first_order_term(system, gains):
    """max |C_y(parallel) - C_y(sequential)| halves with h, as each run's distance from the
    one-scene solution (two_bar_2d_pd.toml) does."""
    one = inerter.load(ROOT / "scenarios" / "two_bar_2d_pd.toml")
    ref = one.simulate(stop_time=STOP, output_interval=0.0025, rtol=1e-11, atol=1e-13, metrics=False)
    gaps, errors = [], {c: [] for c in cosim.COUPLINGS}
    for h in (0.01, 0.005):
        runs = {c: cosim.run_system(system["plant"], system["controller"], STOP, h, gains, c)
                for c in cosim.COUPLINGS}
        gaps.append(np.max(np.abs(runs["parallel"].y - runs["sequential"].y)))
        for c, run in runs.items():
            errors[c].append(np.max(np.abs(run.y - np.interp(run.t, ref.time, ref["C.r[2]"]))))
    assert 1.8 < gaps[0] / gaps[1] < 2.2
    for c in cosim.COUPLINGS:
        assert 1.8 < errors[c][0] / errors[c][1] < 2.2, c
    assert errors["sequential"][1] < errors["parallel"][1] < 5e-3


def test_a_step_libcosim_cannot_count_is_refused(tmp_path):
    with pytest.raises(FmuBuildError, match=r"step: 1e-12: expected a communication step of at least 1e-9 s"):
        cosim.build_system(tmp_path, step=1e-12)
