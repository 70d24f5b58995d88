"""More cases for RK4's stability watch (kernels.rk4_watch), from an independent check of its final
form: runs that are fine and must not be refused, a numpy-path failure that escaped as a traceback,
and cases the watch misses or misnames, marked xfail(strict=True) so that a change of the rule that
fixes one shows up as an unexpected pass (then drop the mark).

References: closed forms where the scene is linear (the eigenvalues of a chain of masses on sliders,
M⁻¹K by numpy.linalg.eigvals; a pendulum's λ = √(m g l/2 / J_A)), RK4's factor
R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 on them, and DOP853 at rtol 1e-10 (compiled) for the accuracy.
"""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

import inerter
from conftest import ROOT

PATHS = ("numpy", "compiled")
TWO_BAR = ROOT / "scenarios" / "two_bar_2d.toml"
TWO_BAR_3D = ROOT / "scenarios" / "two_bar_2d_as_3d.toml"


def amplification(z: complex) -> float:
    """|R(z)|: RK4's factor per step on a mode of h·λ = z."""
    return abs(1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24)


def line_scene(path, masses, springs, d0, force=None):
    """Masses on sliders along X, each tied to the previous one (the first to the ground point O) by
    a spring of free length 1 m; the mass i displaced by d0[i] from x = i + 1; `force`: (mass,
    amplitude N, frequency Hz) of a sine force along X."""
    lines = ["[scene]", 'name = "line"', 'description = "masses in a line"', "", "[ground.points]", "O = [0, 0]"]
    for i, (m, k) in enumerate(zip(masses, springs)):
        before = "O" if i == 0 else f"P{i - 1}"
        lines += ["", f"[bodies.m{i}]", f"mass = {m!r}", "inertia = 0", f"position = [{i + 1 + d0[i]!r}, 0]",
                  f"points = {{ P{i} = [0, 0] }}", "", f"[joints.s{i}]", 'type = "prismatic"',
                  f'between = ["O", "P{i}"]', "axis = [1, 0]", "", f"[elements.k{i}]", 'type = "spring"',
                  f'between = ["{before}", "P{i}"]', f"k = {k!r}", "length = 1.0"]
    if force:
        j, amplitude, frequency = force
        lines += ["", "[forces.F]", f'point = "P{j}"', "direction = [1, 0]", 'function = "sine"',
                  f"amplitude = {amplitude!r}", f"frequency = {frequency!r}"]
    lines += ["", "[experiment]", "stop_time = 1.0", "output_interval = 0.01", 'method = "DOP853"']
    path.write_text("\n".join(lines) + "\n")
    return path


def chain_matrix(values) -> np.ndarray:
    """The stiffness (or damping) matrix of a line of masses joined by elements of `values`, the
    first to the ground."""
    n = len(values)
    A = np.zeros((n, n))
    for i, v in enumerate(values):
        A[i, i] += v
        if i > 0:
            A[i - 1, i - 1] += v
            A[i - 1, i] -= v
            A[i, i - 1] -= v
    return A


def line_omegas(masses, springs) -> np.ndarray:
    """The chain's natural frequencies: √ of the eigenvalues of M⁻¹K."""
    K = chain_matrix(springs)
    return np.sqrt(np.sort(np.linalg.eigvals(np.diag(1.0 / np.asarray(masses)) @ K).real))


TWO_SCALES = ([1.0, 1e-3], [100.0, 1e5])          # ω ≈ 9.995 and 10005 rad/s


@pytest.mark.parametrize("path", PATHS)
def test_a_stiff_mode_inside_the_region_beside_a_slow_one_runs_on(path, tmp_path):
    """Two masses on sliders, a slow mode (ω₁ = 9.995 rad/s, amplitude 0.1 m) and a stiff one
    (ω₂ = 10005 rad/s, 1e-4 m) at h·ω₂ = 2.8, inside RK4's region (|R(2.8i)| < 1, closed form):
    the stage fit mixes the two modes, and the run must still complete (3600 steps)."""
    omegas = line_omegas(*TWO_SCALES)
    h = 2.8 / omegas[-1]
    assert amplification(2.8j) < 1.0
    model = inerter.load(line_scene(tmp_path / "line.toml", *TWO_SCALES, d0=[0.1, 0.1001]))
    r = model.simulate(method="RK4", step=h, stop_time=1.0, path=path, metrics=False)
    assert r.status == "ok", r.message


@pytest.mark.parametrize("path", PATHS)
def test_a_forcing_far_beyond_the_region_from_rest_runs_on(path, tmp_path):
    """One mass (ω = 10 rad/s, h·ω = 0.1) under a sine force of F = 10 N at 600 rad/s from rest,
    h·ω_f = 6: the forcing is no mode of the scene (∂f/∂t enters the stage differences), so nothing
    grows and the run must not be refused. It is not accurate (the step aliases the forcing: 1.7e-2 m
    off DOP853, which stays within 1.7e-3 m), which is the step's accuracy, not its stability: the
    motion stays below the static deflection under the full force, F/k = 0.1 m."""
    model = inerter.load(line_scene(tmp_path / "line.toml", [1.0], [100.0], d0=[0.0],
                                    force=(0, 10.0, 600.0 / (2 * math.pi))))
    r = model.simulate(method="RK4", step=0.01, stop_time=5.0, path=path, metrics=False)
    assert r.status == "ok", r.message
    assert np.max(np.abs(r["P0.r[1]"] - 1.0)) < 0.1


@pytest.mark.parametrize("path", PATHS)
def test_a_run_that_overflows_the_geometry_fails_in_one_line(path):
    """two_bar_2d_as_3d at a 0.1341 s step: its fastest mode, ω = 25.4 rad/s, puts h·λ = 3.41i
    outside RK4's region (|R| = 3.2 a step), the state overflows within 8 steps and the compiled path
    stops with "accelerations are not finite". The numpy path used to raise a ValueError from the
    rotational elements' winding (math.ceil of NaN) out of simulate(), a traceback; now it fails the
    same way, within a step of the compiled path."""
    assert amplification(0.1341j * 25.41) > 3.0
    model = inerter.load(TWO_BAR_3D)
    r = model.simulate(method="RK4", step=0.1341, stop_time=3.0, path=path, metrics=False)
    assert r.status == "failed" and "accelerations are not finite" in r.message, r.message
    assert 1.07 - 1e-9 <= r.time[-1] <= 1.07 + 0.1341


@pytest.mark.parametrize("path", PATHS)
def test_a_stiff_mode_beyond_the_region_growing_from_round_off_is_named(path, tmp_path):
    """The two masses at h·ω₂ = 2.9 (|R(2.9i)| = 1.19 a step, closed form): the stiff mode grows from
    round-off under the slow one; the fit reads the slow mode until the stiff one dominates the
    stages. The run used to end at 0.0246 s with terminals O and P0 meeting, the mode beyond the
    region named nowhere, the watch having counted 24 steps (grown 58 times) and not yet 100.
    Now a step of it changes the energy of the scene, which conserves it, by more than it holds
    (kernels.energy_watch), and the message names the mode the stability watch had counted:
    h·λ = ±2.9i (closed form), with the step that keeps it inside, 2√2/ω₂ rounded down."""
    omegas = line_omegas(*TWO_SCALES)
    h = 2.9 / omegas[-1]
    assert amplification(2.9j) > 1.18
    model = inerter.load(line_scene(tmp_path / "line.toml", *TWO_SCALES, d0=[0.1, 0.1]))
    r = model.simulate(method="RK4", step=h, stop_time=0.05, path=path, metrics=False)
    assert r.status == "failed" and "stability watch had counted" in r.message, r.message
    found = re.search(r"h·λ ≈ (\S+) ± (\S+)i", r.message)
    assert abs(float(found[1])) < 1e-3 and float(found[2]) == pytest.approx(2.9, rel=2e-3), r.message
    advised = float(r.message.split("experiment.step below about ")[1].split(" s")[0])
    assert 0.9 * 2 * math.sqrt(2) / omegas[-1] < advised <= 2 * math.sqrt(2) / omegas[-1]


@pytest.mark.parametrize("path", PATHS)
def test_a_baumgarte_mode_split_by_the_motion_is_named(path):
    """two_bar_2d at h = 0.0559 s with α = 48.3 1/s (α·h = 2.7, inside the region's reach 2.785): the
    joints' violation mode, λ = −α twice for C alone, is split by the bars' motion (the linearisation
    along the DOP853 run has real h·λ down to −2.83), and the watch stops the run at 0.83 s with
    h·λ ≈ −3.46 (the run without the watch overflows at 1.06 s). With α = 10 1/s at the same step the
    run completes within 3.2e-4 m of DOP853: the constraints' correction is the cause, and the message
    says so (simulation.baumgarte_text: the scene's linearisation where it stopped, at α and at α/2;
    a rule on α·h, or on the fit's h·λ near −α·h, missed it)."""
    r = inerter.load(TWO_BAR, **{"experiment.baumgarte": 48.3}).simulate(
        method="RK4", step=0.0559, stop_time=2.0, path=path, metrics=False)
    assert r.status == "failed" and "beyond its stability limit" in r.message, r.message
    assert "Baumgarte" in r.message, r.message


def test_a_chain_at_a_step_just_beyond_its_fastest_mode_is_not_ok(tmp_path):
    """The 8-link benchmark chain (benchmarks/chain_scene.py) at an 18 ms step: its fastest mode at
    the start, λ = −13.9 ± 166i (linearised), has h·λ = −0.25 ± 2.99i, |R| = 1.18 a step, outside the
    region (the longest step inside: 17.6 ms). At 17.5 ms the run is within 1.4e-6 m of DOP853 at the
    tip. At 18 ms it completed with status ok, 1.2e-2 m off: the mode grew and saturated, the fit
    alternating between modes and the watch's count restarted at every step read inside. A count
    that only 3 full steps inside in a row restart (kernels.RK4_PATIENCE) stops it at 1.35 s, its
    samples before within 1e-3 m of DOP853."""
    import sys
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from chain_scene import write_chain
    model = inerter.load(write_chain(tmp_path / "chain8.toml", 8))
    ref = model.simulate(method="DOP853", rtol=1e-12, atol=1e-14, stop_time=2.0, path="compiled", metrics=False)

    def tip_error(r):
        n = len(r.time)
        return np.max(np.hypot(r["P8b.r[1]"] - ref["P8b.r[1]"][:n], r["P8b.r[2]"] - ref["P8b.r[2]"][:n]))
    r = model.simulate(method="RK4", step=0.0175, stop_time=2.0, path="compiled", metrics=False)
    assert r.status == "ok" and tip_error(r) < 1e-5, (r.status, tip_error(r))
    r = model.simulate(method="RK4", step=0.018, stop_time=2.0, path="compiled", metrics=False)
    assert r.status == "failed" and "beyond its stability limit" in r.message, r.message
    assert tip_error(r) < 1e-3


def test_the_step_a_chain_is_advised_is_inside_the_region(tmp_path):
    """The 32-link benchmark chain at 17.5 ms: its fastest mode at the start, λ = −18.7 ± 192.6i
    (linearised), has h·λ = −0.33 ± 3.37i (|R| = 2.7), and the longest step with every mode inside the
    region is 15.2 ms. The watch stops the run at 0.0525 s, reading h·λ ≈ −2.94 (a real mode) and
    advising a step below about 0.016 s, which is still outside (h·λ = −0.30 ± 3.08i, |R| = 1.49): at
    16 ms the run completes with status ok and the tip 6e-2 m off DOP853 (8e-8 m at 15 ms). The
    advice now comes from the scene's linearisation where the run stopped (simulation.rk4_advice),
    every mode of it judged, not from the fit: the step it gives keeps the tip within 1e-4 m."""
    import re
    import sys
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from chain_scene import write_chain
    model = inerter.load(write_chain(tmp_path / "chain32.toml", 32))
    stopped = model.simulate(method="RK4", step=0.0175, stop_time=2.0, path="compiled", metrics=False)
    assert stopped.status == "failed" and "beyond its stability limit" in stopped.message, stopped.message
    advised = float(re.search(r"below about ([0-9.e-]+) s", stopped.message).group(1))
    ref = model.simulate(method="DOP853", rtol=1e-12, atol=1e-14, stop_time=2.0, path="compiled", metrics=False)
    r = model.simulate(method="RK4", step=advised, stop_time=2.0, path="compiled", metrics=False)
    tip = np.hypot(r["P32b.r[1]"] - ref["P32b.r[1]"], r["P32b.r[2]"] - ref["P32b.r[2]"])
    assert r.status == "ok" and np.max(tip) < 1e-4, (advised, r.status, np.max(tip))


DAMPED_CHAIN = {"masses": [1.0, 1.0, 1.0], "springs": [1e4, 1e4, 1e4], "dampers": [5.0, 30.0, 80.0],
                "d0": [0.01, -0.02, 0.005]}
#: 1.05 times the chain's longest step inside RK4's region (16.36 ms, damped_chain_modes)
DAMPED_CHAIN_STEP = 0.01716
ENERGY_ROSE = "raised the scene's energy"


def damped_chain(tmp_path):
    """Three 1 kg masses on sliders, springs of 1e4 N/m between neighbours (the first to the
    ground) with dampers of 5, 30 and 80 N·s/m beside them (line_scene and a damper per spring)."""
    c = DAMPED_CHAIN
    path_toml = line_scene(tmp_path / "line3.toml", c["masses"], c["springs"], d0=c["d0"])
    text = path_toml.read_text().replace("[experiment]", "".join(
        f'[elements.c{i}]\ntype = "damper"\nbetween = ["{"O" if i == 0 else f"P{i - 1}"}", "P{i}"]\nc = {v!r}\n\n'
        for i, v in enumerate(c["dampers"])) + "[experiment]")
    path_toml.write_text(text)
    return path_toml


def damped_chain_modes() -> np.ndarray:
    """The eigenvalues of the chain's first-order system [[0, I], [−M⁻¹K, −M⁻¹C]] (numpy), linear
    while its springs keep their direction: −2.11 ± 44.7i, −32.2 ± 135.3i, −78.2 ± 140.3i."""
    c = DAMPED_CHAIN
    K, C, n = chain_matrix(c["springs"]), chain_matrix(c["dampers"]), len(c["masses"])
    M_inv = np.diag(1.0 / np.array(c["masses"]))
    return np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-M_inv @ K, -M_inv @ C]]))


def longest_step_inside(modes) -> float:
    """The longest step h with |R(h·λ)| ≤ 1 for every mode, to 1e-6 s (each mode's ray from 0)."""
    h = 0.0
    while all(amplification((h + 1e-6) * lam) <= 1.0 for lam in modes):
        h += 1e-6
    return h


@pytest.mark.parametrize("path", PATHS)
def test_a_damped_three_mass_chain_beyond_the_region_stops_with_the_step_to_take(path, tmp_path):
    """The damped chain (damped_chain) at 1.05 times its longest step inside RK4's region (16.36 ms
    from its eigenvalues, numpy): its top mode has h·λ = −1.34 ± 2.41i and |R| = 1.17 a step. It
    used to end with status ok after 400 steps on both paths, its energy from 8.1 J to 2.3e3 J
    (compiled) and 2.6e3 J (numpy), the masses up to 0.7 m off DOP853: the stability watch's count
    restarted every few steps, its fit alternating between the modes, and something nonlinear (stage
    states passing springs through zero length) bounded the top mode. The chain can only lose
    energy (dampers, no forcing), so RK4's energy watch stops it once its energy rose above its
    lowest by what the chain held there; the message gives the step from the chain's linearisation
    where it stopped, two digits down of the closed form's 16.36 ms."""
    h = DAMPED_CHAIN_STEP
    modes = damped_chain_modes()
    assert amplification(h * max(modes, key=abs)) == pytest.approx(1.17, abs=0.01)
    limit = longest_step_inside(modes)
    assert limit == pytest.approx(0.01636, abs=1e-5) and h == pytest.approx(1.05 * limit, rel=2e-3)
    r = inerter.load(damped_chain(tmp_path)).simulate(method="RK4", step=h, stop_time=400 * h, path=path,
                                                      metrics=False)
    assert r.status == "failed" and ENERGY_ROSE in r.message, (r.status, r.message)
    advised = float(re.search(r"below about ([0-9.e-]+) s", r.message).group(1))
    assert advised == pytest.approx(0.016) and advised <= limit, r.message


@pytest.mark.parametrize("path", PATHS)
def test_a_damped_chain_inside_the_region_near_its_edge_is_told_of_its_fastest_mode(path, tmp_path):
    """At the advised 16 ms (98 % of the limit) every mode is inside the region, but RK4's factor on
    the fastest, λ = −78.2 ± 140.3i, is 0.99 a step where the motion's is e^(h·Re λ) = 0.29: RK4
    keeps it alive, the chain's energy rises (from 5.34 J to 10.7 J at 0.096 s), and the masses are
    1.9e-2 m off DOP853 (they start 2e-2 m out). The run stops, and its message gives that mode and
    both factors (closed form: the eigenvalues, numpy; R(z)). At 90 % of the advice (14.4 ms) the
    run completes, its energy damped out as the chain's slowest mode says: below e^(2·Re λ·T) =
    2.6e-13 of the start (measured 1e-15); step by step it still rises at times (2.530 to 2.547 J at
    the third step), by far less than the watch's limit."""
    model = inerter.load(damped_chain(tmp_path))
    top = 0.016 * max(damped_chain_modes(), key=abs)
    r = model.simulate(method="RK4", step=0.016, stop_time=400 * DAMPED_CHAIN_STEP, path=path, metrics=False)
    assert r.status == "failed" and ENERGY_ROSE in r.message, (r.status, r.message)
    assert "every mode of the scene is inside RK4's region" in r.message, r.message
    assert (f"|R(h·λ)| = {amplification(top):.3g}" in r.message
            and f"|e^(h·λ)| = {math.exp(top.real):.3g}" in r.message), (amplification(top), r.message)
    step = 0.9 * 0.016
    ok = model.simulate(method="RK4", step=step, stop_time=400 * DAMPED_CHAIN_STEP, path=path, metrics=False)
    energy = np.asarray(ok["energy"])
    slowest = min(damped_chain_modes(), key=lambda lam: -lam.real)
    assert ok.status == "ok" and energy[-1] < math.exp(2 * slowest.real * ok.time[-1]) * energy[0], \
        (ok.status, energy[-1], slowest)


@pytest.mark.parametrize("path", PATHS)
def test_a_damped_chain_stepped_stops_where_its_whole_run_does(path, tmp_path):
    """Communication steps of two RK4 steps: the same steps as the whole run, and the lowest energy
    carried from one communication step to the next (nothing changed between them), so the stepper
    stops at the whole run's time, with its words."""
    h = DAMPED_CHAIN_STEP
    scene = damped_chain(tmp_path)
    whole = inerter.load(scene).simulate(method="RK4", step=h, stop_time=400 * h, path=path, metrics=False)
    stepper = inerter.load(scene, **{"experiment.method": "RK4", "experiment.step": h}).stepper(path=path)
    with pytest.raises(inerter.SimulationError) as caught:
        for k in range(1, 201):
            stepper.step(2 * h * k)
    said = str(caught.value)
    stopped = float(re.search(r"t = ([0-9.e-]+) s", whole.message).group(1))       # to 6 digits
    assert whole.status == "failed" and caught.value.time == pytest.approx(stopped, rel=1e-5), (said, whole.message)
    assert said[said.index(ENERGY_ROSE):] == whole.message[whole.message.index(ENERGY_ROSE):]


def test_a_damped_chain_through_the_fmu_stops_with_the_same_words(tmp_path):
    """Through fmpy at communication steps of two RK4 steps: the FMU's step fails with the words of
    the whole run, within the communication step where the whole run stopped."""
    from inerter.fmu.build import build
    from inerter.fmu.run import simulate_fmu

    h = DAMPED_CHAIN_STEP
    scene = damped_chain(tmp_path)
    scene.write_text(scene.read_text().replace('method = "DOP853"', f'method = "RK4"\nstep = {h!r}'))
    whole = inerter.load(scene).simulate(stop_time=400 * h, output_interval=2 * h, metrics=False)
    r = simulate_fmu(scene, stop_time=400 * h, step=2 * h, fmu_path=build(scene, tmp_path / "fmu"), metrics=False)
    assert whole.status == "failed" and ENERGY_ROSE in whole.message, whole.message
    assert r.status == "failed" and ENERGY_ROSE in r.message, r.message
    said = r.message[r.message.index(ENERGY_ROSE):]
    assert whole.message[whole.message.index(ENERGY_ROSE):] in said, (said, whole.message)
    assert r.time[-1] == pytest.approx(whole.time[-1]), (r.time[-1], whole.time[-1])
