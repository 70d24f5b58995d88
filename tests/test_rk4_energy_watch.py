"""RK4's energy watch (kernels.energy_watch): in a scene that conserves its energy (no forcing, no
damping, every inerter with its centripetal term: ``Mechanism.conserves_energy``), one RK4 step
that changes the energy by more than the scene holds stops the run, on both paths, in steppers
and through the FMU. RK4 changes a conserved energy by O(h⁵) a step; the reference is that
conservation, E(t) = E(0) for the equations of motion. In a scene that can only lose it (linear
dampers too: ``Mechanism.only_loses_energy``), a rise above its lowest by more than the scene held
there stops it (the damped chain: tests/test_rk4_watch_more.py); the reference is passivity,
dE/dt = −Σ c L̇² ≤ 0.

The case it was built for: snap_through_2d at a 0.105 s step (hω = 1.0 about its equilibrium)
completed with status ok, its energy ×3.7e7 and the mass 2 km away. Single steps across y = 0,
where the inerter's effective mass b y²/(La² + y²) vanishes, multiplied the energy 65 and 6400
times, while every mode RK4's stability watch read from the stages stayed inside the region.
"""
from __future__ import annotations

import glob
import math

import numpy as np
import pytest

import inerter
from conftest import LUMPED, ROOT
from inerter.common.errors import SimulationError
from inerter.engine.kernels import ENERGY_LOST, ENERGY_OFF
from inerter.engine.simulation import energy_watched

SNAP = ROOT / "scenarios" / "hard" / "snap_through_2d.toml"
STIFF = ROOT / "scenarios" / "hard" / "stiff_1dof_2d.toml"
PATHS = ("numpy", "compiled")
SCENES = sorted(glob.glob(str(ROOT / "scenarios" / "*.toml")) + glob.glob(str(ROOT / "scenarios" / "hard" / "*.toml")))
JUMPED = "changed the scene's energy"


def kept_energy_error(r) -> float:
    """The largest |E(t) − E(0)| / E(0) over the samples a run kept."""
    energy = np.asarray(r["energy"])
    return float(np.max(np.abs(energy - energy[0])) / abs(energy[0]))


@pytest.mark.parametrize("path", PATHS)
def test_a_step_across_the_snap_through_stops_the_run(path):
    """snap_through_2d at 0.1049 s: the run stops at the step that jumps, its samples before it
    kept (sampled at RK4's own nodes: between them the cubic Hermite of so coarse a step is off by
    40 % in energy) and within 10 % of E(0), RK4's own loss at this step; DOP853 conserves the
    energy to 1e-6."""
    model = inerter.load(SNAP)
    r = model.simulate(method="RK4", step=0.1049, stop_time=10.0, output_interval=0.1049, path=path,
                       metrics=False)
    assert r.status == "failed" and JUMPED in r.message, r.message
    assert "experiment.step = 0.105 s" in r.message and "too long for the motion" in r.message, r.message
    assert r.time[-1] == pytest.approx(2 * 0.1049) and kept_energy_error(r) < 0.1
    assert kept_energy_error(model.simulate(stop_time=10.0, path=path, metrics=False, rtol=1e-10, atol=1e-12)) < 1e-6


def test_both_paths_stop_at_the_same_step_with_the_same_words():
    runs = [inerter.load(SNAP).simulate(method="RK4", step=0.1049, stop_time=10.0, path=p, metrics=False)
            for p in PATHS]
    assert runs[0].time[-1] == runs[1].time[-1]
    words = [r.message[r.message.index("an RK4 step"):] for r in runs]     # after each path's prefix
    assert words[0] == words[1], words


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("step, stop", [(0.29, 0.29), (0.3, 0.6)])
def test_the_paper_scene_at_steps_past_its_limit_stops(path, step, stop):
    """lumped_mass_2d at 0.29 s (a mode barely beyond RK4's region, |R| = 1.02: the compiled run
    ended with status ok, the mass run off along its line) and 0.3 s (the run stayed bounded,
    moving twice as fast as it should): its second and third step multiply the energy 4.2 and
    3.4 times; the samples up to that step's start are kept."""
    r = inerter.load(LUMPED).simulate(method="RK4", step=step, path=path, metrics=False)
    assert r.status == "failed" and JUMPED in r.message, r.message
    assert r.time[-1] == pytest.approx(stop, abs=1e-9)


@pytest.mark.parametrize("path", PATHS)
def test_steppers_and_the_whole_run_stop_alike(path):
    """Communication steps of 0.05 s, half RK4's step, so the stepper's RK4 steps are 0.05 s long
    (RK4 restarts at each communication point): it stops where the whole run at 0.05 s does, with
    its message; the watch starts again at each communication point (from the state there)."""
    whole = inerter.load(SNAP).simulate(method="RK4", step=0.05, stop_time=10.0, path=path, metrics=False)
    stepper = inerter.load(SNAP, **{"experiment.method": "RK4", "experiment.step": 0.1049}).stepper(path=path)
    with pytest.raises(SimulationError) as caught:
        for k in range(1, 200):
            stepper.step(0.05 * k)
    assert JUMPED in str(caught.value), caught.value
    assert whole.status == "failed" and caught.value.time == pytest.approx(whole.time[-1]) == pytest.approx(0.2)
    said = str(caught.value)
    assert said[said.index(JUMPED):] == whole.message[whole.message.index(JUMPED):]


def test_the_fmu_reports_it(tmp_path):
    """Through fmpy: the FMU's step fails with the energy watch's words, the samples before it kept
    (at 0.05 s communication steps RK4 restarts at each, so the steps are 0.05 s: the whole run at
    that step stops at 0.2 s too)."""
    from inerter.fmu.build import build
    from inerter.fmu.run import simulate_fmu

    scene = tmp_path / "snap_rk4.toml"
    text = SNAP.read_text()
    experiment = text.index("[experiment]")
    scene.write_text(text[:experiment] + "[experiment]\nstop_time = 10.0\nmethod = \"RK4\"\nstep = 0.1049\n")
    r = simulate_fmu(scene, stop_time=10.0, step=0.05, fmu_path=build(scene, tmp_path / "fmu"), metrics=False)
    assert r.status == "failed" and JUMPED in r.message, r.message
    assert r.time[-1] == pytest.approx(0.2) and kept_energy_error(r) < 0.01
    whole = inerter.load(SNAP).simulate(method="RK4", step=0.05, stop_time=10.0, output_interval=0.05, metrics=False)
    assert whole.status == "failed" and whole.time[-1] == pytest.approx(0.2)


def test_scenes_said_to_conserve_energy_do():
    """Each shipped scene that ``conserves_energy`` says conserves it (lumped_mass_2d,
    snap_through_2d, massless_inerter_2d, spherical_pendulum_3d, gimbal_lock_3d: no damper, force,
    device or ground motion in their files): DOP853 at rtol 1e-10 over 1 s keeps E(t) = E(0) to
    1e-6 of what the scene holds; RK4 at 1 ms (O(h⁴)) runs through."""
    checked = []
    for scene in SCENES:
        model = inerter.load(scene)
        if not model.mechanism.conserves_energy():
            continue
        r = model.simulate(stop_time=1.0, rtol=1e-10, atol=1e-12, metrics=False)
        energy = np.asarray(r["energy"])
        held = model.mechanism.energy_held(model.mechanism.q0, model.mechanism.v0)[1]
        assert np.max(np.abs(energy - energy[0])) < 1e-6 * held, scene
        r = model.simulate(method="RK4", step=1e-3, stop_time=1.0, metrics=False)
        assert r.status == "ok", (scene, r.message)
        checked.append(scene.split("/")[-1])
    assert len(checked) == 5, checked


def test_scenes_said_to_only_lose_energy_do():
    """Each shipped scene that ``only_loses_energy`` and does not conserve it says so truly: DOP853
    at rtol 1e-10 over 1 s never raises E(t) above its lowest before by more than 1e-6 of what the
    scene holds (passivity, dE/dt ≤ 0); RK4 at 1 ms runs through, its watch on."""
    checked = []
    for scene in SCENES:
        model = inerter.load(scene)
        mech = model.mechanism
        if mech.conserves_energy() or not mech.only_loses_energy():
            continue
        assert energy_watched(mech) == ENERGY_LOST, scene
        r = model.simulate(stop_time=1.0, rtol=1e-10, atol=1e-12, metrics=False)
        energy = np.asarray(r["energy"])
        held = mech.energy_held(mech.q0, mech.v0)[1]
        assert np.max(energy - np.minimum.accumulate(energy)) < 1e-6 * held, scene
        assert energy[-1] < energy[0], scene
        r = model.simulate(method="RK4", step=1e-3, stop_time=1.0, metrics=False)
        assert r.status == "ok", (scene, r.message)
        checked.append(scene.split("/")[-1])
    assert checked, "no shipped scene only loses energy"


@pytest.mark.parametrize("scene, why", [("two_bar_2d.toml", "a force"), ("hard/stiff_1dof_2d.toml", "a damper"),
                                        ("hard/step_force_1dof_2d.toml", "a force"),
                                        ("shear_building_tmdi_2d.toml", "ground motion")])
def test_scenes_with_forcing_or_damping_do_not_conserve_energy(scene, why):
    mech = inerter.load(ROOT / "scenarios" / scene).mechanism
    assert not mech.conserves_energy(), why
    assert mech.only_loses_energy() == (why == "a damper"), why
    assert energy_watched(mech) == (ENERGY_LOST if why == "a damper" else ENERGY_OFF), why


def test_an_inerter_without_its_centripetal_term_is_not_watched():
    """Eq. (8), F = b r̈·r̂, does work that ½bL̇² does not account for (Sec. 2.2): lumped_mass_2d
    with it does not conserve the energy, so the watch stays off."""
    model = inerter.load(LUMPED, **{"effects.centripetal": False})
    assert not model.mechanism.conserves_energy()
    r = model.simulate(stop_time=5.0, rtol=1e-10, atol=1e-12, metrics=False)
    assert kept_energy_error(r) > 1e-3


@pytest.mark.parametrize("path", PATHS)
def test_a_retune_that_raises_the_energy_is_not_taken_for_a_rise(path):
    """stiff_1dof_2d (a damper at c = 0: it can only lose energy) stepped with RK4 at 1e-4 s (hω =
    0.03), retuned at its turning point (the spring stretched, all its energy in it) from k = 1e8
    to 4e8 N/m: the energy jumps to 4 times what it was, which the watch would read as a rise of 3
    times what the scene held at its lowest. A retune starts the lowest again (the energy changed
    between steps, not in them), so the stepper runs on, and from there conserves the new energy
    (c = 0) to RK4's error."""
    model = inerter.load(STIFF, **{"experiment.method": "RK4", "experiment.step": 1e-4})
    tuned = inerter.load(STIFF, k=4e8, **{"experiment.method": "RK4", "experiment.step": 1e-4})
    mech = model.mechanism
    half_period = math.pi * math.sqrt((1e-3 + 1e3) / 1e8)
    st = model.stepper(path=path)
    st.step(half_period)                        # at the other turning point
    before = mech.energy(st.y[:mech.nq], st.y[mech.nq:mech.nq + mech.n])
    st.retune(tuned.mechanism, tuned.signals)
    after = tuned.mechanism.energy(st.y[:mech.nq], st.y[mech.nq:mech.nq + mech.n])
    assert after == pytest.approx(4 * before, rel=1e-3)
    energies = []
    for k in range(1, 21):
        st.step(half_period * (1 + 0.1 * k))
        energies.append(tuned.mechanism.energy(st.y[:mech.nq], st.y[mech.nq:mech.nq + mech.n]))
    assert np.max(np.abs(np.array(energies) - after)) < 1e-6 * after
