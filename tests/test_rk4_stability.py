"""RK4's fixed step beyond the method's stability limit stops the run with a message, on both paths,
through co-simulation and through the FMU. It used to complete with status ok while a mode grew
without bound: lumped_mass_2d at a 0.5 s step grew its energy 5e25 times in 5 s.

The references are closed forms. stiff_1dof_2d (c = 0) is one linear mode,
(m + b) x'' + k (x − L0) = 0, ω = √(k/(m + b)). RK4 multiplies it by |R(ihω)| at every step, with
R(z) = 1 + z + z²/2 + z³/6 + z⁴/24: above 1 beyond hω = 2√2 = 2.828, below 1 short of it. The
watch (kernels.rk4_watch) finds h·λ exactly for one linear mode, undamped (±ihω), damped
(c > 0: hω(−ζ ± i√(1 − ζ²))) or overdamped (real), and its amplitude grows |R(hλ)| per step; so
with every step outside RK4's region, the run stops at the start of step n + 1, where n is the
smallest number of steps with |R|ⁿ ≥ RK4_GROWTH (and at least RK4_MIN_STEPS − 1).
"""
from __future__ import annotations

import math
import re

import numpy as np
import pytest

import inerter
from conftest import LUMPED, ROOT
from inerter.common.errors import SimulationError
from inerter.engine.kernels import RK4_MIN_STEPS
from inerter.engine.simulation import RK4_GROWTH

STIFF = ROOT / "scenarios" / "hard" / "stiff_1dof_2d.toml"
STICK_SLIP = ROOT / "scenarios" / "hard" / "stick_slip_device_2d.toml"
M, B, K, L0 = 1.0e-3, 1.0e3, 1.0e8, 1.0          # stiff_1dof_2d's parameters
OMEGA = math.sqrt(K / (M + B))
PATHS = ("numpy", "compiled")


def amplification(h_omega: float, zeta: float = 0.0) -> float:
    """|R(hλ)|: RK4's factor per step on the mode λ = ω(−ζ + i√(1 − ζ²)) (ζ ≤ 1)."""
    z = h_omega * complex(-zeta, math.sqrt(1.0 - zeta ** 2))
    return abs(1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24)


def steps_to_growth(h_omega: float, zeta: float = 0.0) -> int:
    """The steps after the first one beyond the region at which the watch stops the run: where the
    mode has grown RK4_GROWTH times, and not before RK4_MIN_STEPS steps in a row."""
    return max(math.ceil(math.log(RK4_GROWTH) / math.log(amplification(h_omega, zeta))), RK4_MIN_STEPS - 1)


def amplitudes(r) -> np.ndarray:
    """The mode's amplitude √((x − L0)² + (ẋ/ω)²) at each sample."""
    return np.hypot(r["P.r[1]"] - L0, r["P.v[1]"] / OMEGA)


def stiff_run(h_omega: float, path: str, steps: int = 300):
    h = h_omega / OMEGA
    return h, inerter.load(STIFF).simulate(method="RK4", step=h, stop_time=steps * h, output_interval=h,
                                           path=path, metrics=False)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("h_omega", [2.9, 3.5])
def test_a_step_beyond_the_limit_stops_where_the_closed_form_says(path, h_omega):
    h, r = stiff_run(h_omega, path)
    n = steps_to_growth(h_omega)
    assert r.status == "failed"
    assert "beyond its stability limit" in r.message and f"h·λ ≈ 0 ± {h_omega:.3g}i" in r.message, r.message
    assert f"over the last {n} steps" in r.message, r.message
    # the longest stable step: the region meets the imaginary axis at hω = 2√2
    suggested = float(r.message.split("below about ")[1].split(" s")[0])
    assert suggested == pytest.approx(h * 2 * math.sqrt(2) / h_omega, rel=0.02)
    # the samples up to the start of the step that stopped it are kept, each RK4's own node
    assert r.time[-1] == pytest.approx(n * h, rel=1e-9)
    growth = amplitudes(r)[1:] / amplitudes(r)[:-1]
    np.testing.assert_allclose(growth, amplification(h_omega), rtol=1e-9)


@pytest.mark.parametrize("path", PATHS)
def test_a_pair_beyond_the_real_axis_reach_but_inside_the_region_runs_on(path):
    """hω = 2.81: beyond the region's reach along the negative real axis (2.785), yet inside it on
    the imaginary axis (2.828): the mode decays and the run completes."""
    h_omega = 2.81
    assert h_omega > 2.785 and amplification(h_omega) < 1.0
    h, r = stiff_run(h_omega, path)
    assert r.status == "ok", r.message
    a = amplitudes(r)
    assert a[-1] / a[0] == pytest.approx(amplification(h_omega) ** 300, rel=1e-6)


@pytest.mark.parametrize("path", PATHS)
@pytest.mark.parametrize("zeta, h_lambda", [(0.54, 2.75), (1.0, 2.9)])
def test_a_damped_mode_outside_the_region_stops_with_its_h_lambda(path, zeta, h_lambda):
    """A damped pair (ζ = 0.54: h·λ = −1.485 ± 2.315i, where RK4's region reaches only |hλ| = 2.62,
    inside the 2.785 of the negative real axis) and a real mode (ζ = 1: h·λ = −2.9) outside the
    region: the watch finds h·λ from the step's stages and stops where |R(hλ)|ⁿ ≥ RK4_GROWTH."""
    omega = OMEGA if zeta < 1.0 else 1e5                    # ζ = 1: c = 1e8, the fast root −1e5 /s
    c = 2 * zeta * math.sqrt(K * (M + B)) if zeta < 1.0 else 1e8
    h = h_lambda / omega
    z = h_lambda * complex(-zeta, math.sqrt(1.0 - zeta ** 2))
    n = steps_to_growth(h_lambda, zeta)
    r = inerter.load(STIFF, c=c, d0=1e-9).simulate(method="RK4", step=h, stop_time=(n + 30) * h,
                                                    output_interval=h, path=path, metrics=False)
    assert r.status == "failed" and "beyond its stability limit" in r.message, r.message
    found = re.search(r"h·λ ≈ (\S+)(?: ± (\S+)i)? \(", r.message)
    assert found, r.message
    assert complex(float(found[1]), float(found[2] or 0.0)) == pytest.approx(z, rel=5e-3)   # 3 digits
    assert "Baumgarte" not in r.message, r.message          # the slider's h·α is 3e-4 (α = 10 1/s)
    # A damped pair's amplitude measure swings with its phase by up to ((1 + |cos φ|)/(1 − |cos φ|))^½
    # (φ the angle of λ; kernels.rk4_watch), which moves the stop by up to that many steps' growth;
    # a real mode's has no phase.
    cos = abs(z.real) / abs(z)
    slack = 0 if zeta >= 1.0 else math.ceil(0.5 * math.log((1 + cos) / (1 - cos)) / math.log(amplification(h_lambda, zeta)))
    steps = int(re.search(r"over the last (\d+) steps", r.message)[1])
    assert abs(steps - n) <= slack, (steps, n, slack)
    assert r.time[-1] == pytest.approx(steps * h, rel=1e-9)


@pytest.mark.parametrize("path", PATHS)
def test_a_mode_bounded_by_its_nonlinearity_is_not_refused(path):
    """stick_slip_device_2d at 4 ms: the friction's tanh switch (v_s = 1 mm/s) puts the sticking
    mode beyond the bound, and its saturation keeps the run bounded: it completes, close to the
    DOP853 run at rtol 1e-10 (a check that linearised at t = 0 refused it)."""
    model = inerter.load(STICK_SLIP)
    r = model.simulate(method="RK4", step=4e-3, path=path, metrics=False)
    reference = model.simulate(path=path, metrics=False)
    assert r.status == "ok", r.message
    assert np.max(np.abs(r["P.r[1]"] - reference["P.r[1]"])) < 1e-3


@pytest.mark.parametrize("path", PATHS)
def test_the_paper_scene_at_a_half_second_step_stops(path):
    """lumped_mass_2d (ω ≈ 9.8 rad/s) at a 0.5 s step, the reported case (energy ×5e25 in 5 s):
    the scene conserves its energy (no damping, no forcing), and the first step multiplies it
    93 times, so RK4's energy watch (kernels.energy_watch; tests/test_rk4_energy_watch.py) stops
    the run there, before the stability watch has its 4 steps in a row; the initial sample is
    kept. At 0.28 s, inside RK4's region, the run completes. (Its motion is not the true one: so
    coarse a step may carry the mass over to the mirror equilibrium, y = −1 m.)"""
    model = inerter.load(LUMPED)
    r = model.simulate(method="RK4", step=0.5, stop_time=5.0, path=path, metrics=False)
    assert r.status == "failed" and "an RK4 step (experiment.step = 0.5 s) changed the scene's energy" in r.message, r.message
    assert len(r.time) == 1 and np.all(np.isfinite(r["P.r[2]"]))
    r = model.simulate(method="RK4", step=0.28, stop_time=20.0, path=path, metrics=False)
    assert r.status == "ok", r.message
    assert np.all(np.isfinite(r["P.r[2]"])) and np.max(np.abs(r["P.r[2]"])) < 5.0


@pytest.mark.parametrize("path", PATHS)
def test_cosimulation_keeps_the_watch_across_communication_steps(path):
    """Two RK4 steps per communication step: the watch's count carries across them, and the
    stepper stops where the whole run does."""
    h_omega = 2.9
    h = h_omega / OMEGA
    n = steps_to_growth(h_omega)
    stepper = inerter.load(STIFF, **{"experiment.method": "RK4", "experiment.step": h}).stepper(path=path)
    with pytest.raises(SimulationError) as caught:
        for k in range(1, 200):
            stepper.step(2 * k * h)
    assert "beyond its stability limit" in str(caught.value) and f"over the last {n} steps" in str(caught.value)
    assert caught.value.time == pytest.approx(n * h, rel=1e-9)     # the start of the RK4 step that stopped it


def test_the_fmu_reports_it_as_fmi2error(tmp_path):
    """Through fmpy: the FMU's step fails with the same text, the samples before it kept."""
    from inerter.fmu.build import build
    from inerter.fmu.run import simulate_fmu

    h_omega = 2.9
    h = h_omega / OMEGA
    scene = tmp_path / "stiff_rk4.toml"
    text = STIFF.read_text()
    experiment = text.index("[experiment]")
    scene.write_text(text[:experiment] + f"[experiment]\nstop_time = {300 * h!r}\noutput_interval = {2 * h!r}\n"
                     f"method = \"RK4\"\nstep = {h!r}\n")
    r = simulate_fmu(scene, stop_time=300 * h, step=2 * h, fmu_path=build(scene, tmp_path / "fmu"),
                     metrics=False)
    assert r.status == "failed"
    assert "beyond its stability limit" in r.message and f"h·λ ≈ 0 ± {h_omega:.3g}i" in r.message, r.message
    n = steps_to_growth(h_omega)
    assert r.time[-1] == pytest.approx(2 * (n // 2) * h, rel=1e-9)


@pytest.mark.parametrize("path", PATHS)
def test_steps_a_ground_record_shortens_are_judged_at_their_own_length(path):
    """shear_building_tmdi_2d's record has a kink every 0.01 s, where RK4's steps end: with
    experiment.step = 0.2 s every step taken is 0.01 s long (h·|λ| ≤ 0.62 for its fastest mode,
    62 rad/s), the same steps as at experiment.step = 0.01 s, so the run is that one, sample for
    sample. The watch used to judge each step at 0.2 s (h·|λ| ≈ 5.3) and stopped it at 0.49 s, the
    building's response to the record growing from rest."""
    model = inerter.load(ROOT / "scenarios" / "shear_building_tmdi_2d.toml")
    taken = model.simulate(method="RK4", step=0.01, path=path, metrics=False)
    r = model.simulate(method="RK4", step=0.2, path=path, metrics=False)
    assert r.status == "ok", r.message
    np.testing.assert_allclose(r["Jd.r[1]"], taken["Jd.r[1]"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("path", PATHS)
def test_a_stepper_whose_communication_steps_are_shorter_is_judged_at_them(path):
    """The same record through a stepper with experiment.step = 0.2 s and communication steps of
    0.05 s: every step ends at a kink (0.01 s), and the stepper runs to the end."""
    stepper = inerter.load(ROOT / "scenarios" / "shear_building_tmdi_2d.toml",
                           **{"experiment.method": "RK4", "experiment.step": 0.2}).stepper(path=path)
    for k in range(1, 201):
        stepper.step(0.05 * k)


@pytest.mark.parametrize("path", PATHS)
def test_a_failure_of_a_coarse_rk4_run_says_the_step_may_be_the_cause(path):
    """backlash_device_2d at a 0.05 s step: its terminals meet at 0.185 s, on both paths and in a
    stepper, a state the step's growth drives it to without a mode outside the region (at 1 ms, and
    with DOP853, the run completes). The message says so; the same scene's failure with another
    method would not (rk4_hint)."""
    scene = ROOT / "scenarios" / "hard" / "backlash_device_2d.toml"
    assert inerter.load(scene).simulate(method="RK4", step=1e-3, path=path, metrics=False).status == "ok"
    r = inerter.load(scene).simulate(method="RK4", step=0.05, path=path, metrics=False)
    assert r.status == "failed" and "terminals O and P meet" in r.message, r.message
    assert r.message.endswith("a shorter experiment.step, or DOP853, shows whether it does"), r.message
    stepper = inerter.load(scene, **{"experiment.method": "RK4", "experiment.step": 0.05}).stepper(path=path)
    with pytest.raises(SimulationError) as caught:
        for k in range(1, 100):
            stepper.step(0.05 * k)
    assert str(caught.value).count("a step too long for the motion") == 1, caught.value


@pytest.mark.parametrize("path", PATHS)
def test_runs_inside_the_region_from_rest_under_a_forcing_run_on(path, tmp_path):
    """Every shipped scene at RK4's default step (1 ms) for 0.2 s, and the benchmarks' 32-link
    chain (a sine force at its free end from rest; benchmarks/chain_scene.py) for 1 s: each fastest
    mode inside RK4's region (hω ≤ 0.8 here), so nothing stops them. At the chain's first steps
    from rest the fitted h·λ is spurious (715i, then a forced response's): the watch stopped it at
    1 ms before it asked for RK4_MIN_STEPS steps in a row. The numpy path runs the same watch
    (its py_func): its chain runs 0.25 s, past those first steps (1 s of it took 20 s of the
    suite, 0.25 s takes 6 s; AMD EPYC host, 2026-11-28)."""
    import glob
    import sys
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from chain_scene import write_chain
    finally:
        sys.path.pop(0)
    scenes = sorted(glob.glob(str(ROOT / "scenarios" / "*.toml")) + glob.glob(str(ROOT / "scenarios" / "hard" / "*.toml")))
    for scene in scenes:
        r = inerter.load(scene).simulate(method="RK4", step=1e-3, stop_time=0.2, path=path, metrics=False)
        assert "stability limit" not in r.message and "changed the scene's energy" not in r.message, (scene, r.message)
    chain = inerter.load(write_chain(tmp_path / "chain32.toml", 32))
    r = chain.simulate(method="RK4", step=1e-3, stop_time=1.0 if path == "compiled" else 0.25, path=path,
                       metrics=False)
    assert r.status == "ok", r.message


#: Where RK4's region meets the negative real axis: the real root of R(x) = 1, x ≠ 0, i.e. of
#: 1 + x/2 + x²/6 + x³/24 = 0 (closed form by Cardano's rule, to 1e-12).
REAL_REACH = 2.785293563405282


@pytest.mark.parametrize("path", PATHS)
def test_a_baumgarte_correction_beyond_the_region_is_named(path):
    """two_bar_2d's joints corrected at α = 300 1/s, RK4 at 0.01 s: a violation C of the joints obeys
    C'' + 2αC' + α²C = 0, λ = −α twice, so h·λ = −3 lies beyond the region's reach along the
    negative real axis (2.785, the closed form REAL_REACH; |R(−3)| = 1.375), while the bars' own
    modes stay well inside (at the scene's α = 10 the run completes and names nothing). The
    violation grows until the watch stops the run, and the message names Baumgarte's correction
    (halving α lengthens the limit of the scene's linearisation where it stopped) with the α that
    keeps that linearisation's modes inside the region, rounded down. That limit is local: the
    motion moves the mode along the run (the linearisation reads −3.08 here; at α·h = 2.7 the watch
    read −2.82 later on), so at 90 % of the advised α the run completes. (A real mode beyond the
    region that is not the correction's names none: the overdamped stiff_1dof_2d above, its
    slider's h·α = 3e-4.)"""
    scene, h = ROOT / "scenarios" / "two_bar_2d.toml", 0.01
    assert abs(amplification(REAL_REACH, zeta=1.0) - 1.0) < 1e-12         # R(−2.785…) = 1
    coarse = inerter.load(scene, **{"experiment.baumgarte": 300.0})
    r = coarse.simulate(method="RK4", step=h, stop_time=5.0, path=path, metrics=False)
    assert r.status == "failed" and "beyond its stability limit" in r.message, r.message
    h_lambda = complex(re.search(r"h·λ ≈ (\S+)", r.message).group(1).replace("−", "-"))
    # The scene's motion moves the violation's mode as RK4 sees it: −3.11 here against −α·h = −3.
    assert h_lambda.imag == 0.0 and h_lambda.real == pytest.approx(-3.0, rel=0.05), r.message
    assert "this mode is the joints' Baumgarte correction" in r.message and "(h·α = 3)" in r.message, r.message
    local = float(re.search(r"the motion moves to h·λ ≈ (\S+);", r.message).group(1))
    assert local == pytest.approx(-3.0, rel=0.05), r.message
    advised = float(r.message.split("experiment.baumgarte below about ")[1].split(" 1/s")[0])
    assert 0.9 * 300.0 * REAL_REACH / abs(local) < advised <= 300.0 * REAL_REACH / abs(local), r.message
    r = inerter.load(scene, **{"experiment.baumgarte": 0.9 * advised}).simulate(method="RK4", step=h, stop_time=5.0,
                                                                                 path=path, metrics=False)
    assert r.status == "ok", r.message
    r = inerter.load(scene).simulate(method="RK4", step=h, stop_time=5.0, path=path, metrics=False)
    assert r.status == "ok" and r.run.max_drift < 1e-7 and "Baumgarte" not in r.message, r.message
