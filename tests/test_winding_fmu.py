"""The FMU of a 3D rotational spring wound past half a turn (tests/test_winding.py has the scene,
its closed form and the solver's paths): its native co-simulation steps through fmpy give the
solver's whole run, and its FMU state got and set again carries the angle's branch."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from test_fmu import fmus, instance, shim_expected, unzipped  # noqa: F401
from test_fmu_native import native_steps

import inerter  # noqa: E402

BAR_3D = Path(__file__).parent / "data" / "winding_bar_3d.toml"


def test_the_fmu_winds_as_the_whole_run(tmp_path, fmus, instance):
    """The FMU of the 3D bar (spun at 20 rad/s: amplitude 6.7 rad), stepped through fmpy every
    10 ms (natively where the binary has its status shim; DOP853 at the scene's tolerances), gives
    the whole run's φ and τ at every point (within 1e-9 rad, 1e-8 N·m), past 2π; its state got near
    φ = 0 and set again after 1.3π repeats the steps exactly."""
    model = inerter.load(BAR_3D, w=20.0)
    whole = model.simulate(stop_time=1.0)
    inst = instance(fmus[BAR_3D])
    inst.initialise(reals={"w": 20.0})
    names = ["torsion.phi_rel", "torsion.tau"]
    got = [inst.get(names)]
    state = None
    for k in range(100):
        inst.fmu.doStep(0.01 * k, 0.01)
        got.append(inst.get(names))
        if k == 0:
            state = inst.fmu.getFMUstate()
    got = np.array(got)
    assert got[:, 0].max() > 2 * math.pi
    assert np.abs(got[:, 0] - whole["torsion.phi_rel"]).max() < 1e-9
    assert np.abs(got[:, 1] - whole["torsion.tau"]).max() < 1e-8
    inst.fmu.setFMUstate(state)
    for k in range(1, 50):
        inst.fmu.doStep(0.01 * k, 0.01)
    assert inst.get(names) == list(got[50])
    if shim_expected():                   # the binary takes the steps natively where it has its shim
        assert native_steps(inst) >= 100


def test_the_fmu_at_coarse_communication_points_follows_the_closed_form(fmus):
    """Through fmpy (simulate_fmu) with communication points 0.1 s and 0.5 s apart, between which
    the bar (θ̇(0) = 40 rad/s, k = 0.01 N·m/rad: amplitude 231 rad) turns by up to 4 and 20 rad:
    the FMU winds at every step of its integrator and reads its outputs there, so φ_rel and τ = kφ
    follow the closed form θ̇(0)/ω sin ωt (tests/test_winding.py) within 1e-6 rad, with no warning."""
    from inerter.fmu.run import simulate_fmu

    k, w = 0.01, 40.0
    omega = math.sqrt(k / (1.0 / 3.0))
    for step in (0.1, 0.5):
        r = simulate_fmu(BAR_3D, {"k": k, "w": w}, stop_time=3.0, step=step, fmu_path=fmus[BAR_3D], metrics=False)
        assert r.status == "ok", r.message
        reference = w / omega * np.sin(omega * r.time)
        assert np.abs(np.diff(reference)).max() > math.pi
        assert np.abs(r["torsion.phi_rel"] - reference).max() < 1e-6
        assert np.abs(r["torsion.tau"] - k * reference).max() < 1e-8
        assert not r.warnings
