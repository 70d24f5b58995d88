"""A 3D rotational spring winds on past half a turn (inerter.elements.winding).

The scene: a bar (m = 1 kg, length 1 m, J = m l²/3 = 1/3 kg·m² about its end) pinned to the
ground about z through a rotational spring k = 3 N·m/rad, tests/data/winding_bar_3d.toml, a linear
torsional oscillator J θ̈ = −k(θ − θ0) whose closed form is

    θ(t) = θ0 + (θ(0) − θ0) cos ωt + θ̇(0)/ω sin ωt,   ω = √(k/J) = 3 rad/s,

with amplitude θ̇(0)/ω = 3.33 rad (θ̇(0) = 10 rad/s) or |θ0| (θ0 = ±3π/2), past π either way.
References: that closed form, the planar twin (tests/data/winding_bar_2d.toml, whose angle
θ_b − θ_a has no branch: another code path of the engine, which never winds), the energy
E = ½Jθ̇² + ½k(θ − θ0)² of the initial state, and the oracle at a state past π.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.cli import main
from inerter.elements.winding import wound

DATA = Path(__file__).parent / "data"
BAR_3D = DATA / "winding_bar_3d.toml"
BAR_2D = DATA / "winding_bar_2d.toml"
J, K = 1.0 / 3.0, 3.0
OMEGA = math.sqrt(K / J)
# (initial angular velocity, free angle): wound past π by the initial velocity, or by a free angle
# three quarters of a turn away either way
CASES = {"spun": (10.0, 0.0), "free_angle_ahead": (0.0, 1.5 * math.pi), "free_angle_behind": (2.0, -1.5 * math.pi)}


def closed_form(t, w0, phi0):
    """θ(t) of J θ̈ = −k(θ − θ0) from θ(0) = 0, θ̇(0) = w0."""
    return phi0 - phi0 * np.cos(OMEGA * t) + w0 / OMEGA * np.sin(OMEGA * t)


def run(scene, case, **kw):
    w0, phi0 = CASES[case]
    return inerter.load(scene, w=w0, phi0=phi0).simulate(**kw)


def test_the_unwrap_picks_the_branch_nearest_the_reference():
    """wound(φ_ref, reading) = reading + 2πk within (φ_ref − π, φ_ref + π]: worked by hand."""
    assert wound(0.0, 0.5) == 0.5
    assert wound.py_func(3.0, -3.0) == pytest.approx(-3.0 + 2 * math.pi, abs=1e-15)
    assert wound.py_func(-3.0, 3.0) == pytest.approx(3.0 - 2 * math.pi, abs=1e-15)
    assert wound.py_func(20.0, 1.0) == pytest.approx(1.0 + 6 * math.pi, abs=1e-14)
    assert wound.py_func(0.0, math.pi) == math.pi                    # half a turn goes forward
    assert wound.py_func(2 * math.pi, -math.pi) == pytest.approx(3 * math.pi, abs=1e-15)


@pytest.mark.parametrize("path", ["numpy", "compiled"])
@pytest.mark.parametrize("case", CASES)
def test_the_3d_spring_winds_as_its_planar_twin_and_the_closed_form(path, case):
    """φ and τ of the 3D bar equal the 2D twin's and the closed form at every sample, past π
    (rtol 1e-10: the runs agree to 1e-8 rad, the closed form to 1e-8 rad; τ = kφ to 1e-7 N·m)."""
    r3 = run(BAR_3D, case, path=path)
    r2 = run(BAR_2D, case, path=path)
    assert r3.run.status == "ok" and r2.run.status == "ok"
    assert path == "numpy" or r3.run.extra["path"] == "compiled"
    w0, phi0 = CASES[case]
    phi, tau = r3["torsion.phi_rel"], r3["torsion.tau"]
    reference = closed_form(r3.time, w0, phi0)
    assert np.abs(reference).max() > math.pi + 0.1                    # it does wind past half a turn
    assert np.abs(phi - r2["torsion.phi_rel"]).max() < 1e-8
    assert np.abs(tau - r2["torsion.tau"]).max() < 1e-7
    assert np.abs(phi - reference).max() < 1e-8
    assert np.abs(tau - K * (reference - phi0)).max() < 1e-7
    assert not r3.warnings


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_energy_is_conserved_through_the_wrap(path):
    """Spring and kinetic energy (the `energy` output) stay at E = ½Jθ̇(0)² + ½kθ0² within 1e-8
    relative, through two passes of ±π (spun and wound by the free angle at once)."""
    w0, phi0 = 6.0, 1.5 * math.pi
    r = inerter.load(BAR_3D, w=w0, phi0=phi0).simulate(path=path)
    E0 = 0.5 * J * w0 ** 2 + 0.5 * K * phi0 ** 2
    assert np.abs(r["torsion.phi_rel"] - closed_form(r.time, w0, phi0)).max() < 1e-8
    assert np.abs(r["energy"] - E0).max() < 1e-8 * E0


@pytest.mark.parametrize("path", ["numpy", "compiled"])
@pytest.mark.parametrize("method", ["Radau", "BDF", "LSODA", "RK45", "RK4"])
def test_each_method_winds(path, method):
    """Every integrator moves φ_ref on after its accepted steps: the closed form within 2e-4 rad
    (rtol 1e-8 for the adaptive methods; RK4's step 1e-3 s: error ~(ωh)⁴)."""
    w0, phi0 = CASES["spun"]
    r = inerter.load(BAR_3D, w=w0, phi0=phi0, **{"experiment.step": 1e-3}).simulate(
        path=path, method=method, rtol=1e-8, atol=1e-10)
    assert r.run.status == "ok", r.run.message
    assert np.abs(r["torsion.phi_rel"] - closed_form(r.time, w0, phi0)).max() < 2e-4


@pytest.mark.parametrize("path", ["numpy", "compiled", "compiled-built-where-read"])
def test_the_dense_output_reads_the_wound_angle_between_samples(path):
    """The dense output of φ and τ (DOP853's polynomials) at times between samples in a window
    late in the run where φ > π throughout (its first time more than half a turn from φ = 0)
    equals the closed form within 1e-8 rad (1e-7 N·m)."""
    from inerter.api import Result
    from inerter.engine import compiled

    w0, phi0 = CASES["spun"]
    model = inerter.load(BAR_3D, w=w0, phi0=phi0)
    settings = model.settings()
    if path == "compiled-built-where-read":     # no dense output kept: each interval read is integrated again
        result = model.simulate(metrics=False)
        run = result.run
        assert isinstance(run.dense, compiled.LocalDense)
    else:
        run = (compiled.integrate_compiled(model.mechanism, settings, dense=True) if path == "compiled"
               else model.simulate(path="numpy", metrics=False).run)
        result = Result(model, settings, run)
    assert path == "numpy" or run.extra["path"] == "compiled"
    t = np.linspace(2.55, 2.7, 16)                # φ > π throughout: 3.33 sin 3t
    reference = closed_form(t, w0, phi0)
    assert reference.min() > math.pi
    assert np.abs(result.dense("torsion.phi_rel")(t) - reference).max() < 1e-8
    assert np.abs(result.dense("torsion.tau")(t) - K * (reference - phi0)).max() < 1e-7


def bar_state(model, theta, rate):
    """The bar's state (q, v) at angle θ about z, turning at θ̇ (quaternion orientation)."""
    q = np.array([0.5 * math.cos(theta), 0.5 * math.sin(theta), 0.0,
                  math.cos(theta / 2), 0.0, 0.0, math.sin(theta / 2)])
    v = np.array([-0.5 * rate * math.sin(theta), 0.5 * rate * math.cos(theta), 0.0, 0.0, 0.0, rate])
    assert model.mechanism.nq == 7 and model.mechanism.n == 6
    return q, v


def test_the_engine_equals_the_oracle_past_half_a_turn():
    """At θ = 1.2π + 2π (a turn and more: the reading is −0.8π), on the branch of φ_ref = 3π: the
    compiled kernels' accelerations equal the oracle's (the oracle given the branch) and the closed
    form θ̈ = −k(θ − θ0)/J, to 1e-9 relative; with φ_ref = 0 they would read θ − 4π."""
    from inerter.engine.compiled import compile_mechanism

    model = inerter.load(BAR_3D, phi0=0.5)
    oracle = model.oracle()
    theta, rate = 3.2 * math.pi, 2.0
    q, v = bar_state(model, theta, rate)
    kernel = compile_mechanism(model.mechanism)
    kernel.windings[:] = 3.0 * math.pi
    oracle.mechanism.windings = [3.0 * math.pi]
    a_engine, _ = kernel.accelerations(0.0, q, v)
    a_oracle, _ = oracle.mechanism.accelerations(0.0, q, v)
    expected = -K * (theta - 0.5) / J
    assert a_engine[5] == pytest.approx(expected, rel=1e-9)
    assert a_oracle[5] == pytest.approx(expected, rel=1e-9)
    assert np.allclose(a_engine, a_oracle, rtol=0, atol=1e-9 * abs(expected))
    kernel.windings[:] = 0.0


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_a_stepper_rolled_back_winds_as_before(path):
    """A co-simulation stepper (spun at 20 rad/s: amplitude 6.7 rad) saved near φ = 0, stepped past
    1.3π, restored and stepped again gives the same φ, the whole run's (within 1e-8 rad)."""
    model = inerter.load(BAR_3D, w=20.0)
    stepper = model.stepper(path=path)
    stepper.step(0.01)
    saved = stepper.get_state()
    for k in range(2, 51):
        stepper.step(0.01 * k)
    first = stepper.outputs()["torsion.phi_rel"]
    stepper.set_state(saved)
    for k in range(2, 51):
        stepper.step(0.01 * k)
    again = stepper.outputs()["torsion.phi_rel"]
    assert first > 1.3 * math.pi
    assert again == first
    assert first == pytest.approx(float(closed_form(0.5, 20.0, 0.0)), abs=1e-8)


def test_a_whole_run_between_two_steps_leaves_a_numpy_stepper_on_its_branch():
    """A numpy-path stepper on a model (spun at 20 rad/s) stepped past 1.3π, then a whole run of the
    same model (which winds its angles from the initial pose, and ends near 0 after 0.2 s), then
    the stepper on to 0.5 s: the same φ as a stepper not interrupted, bit for bit, the closed
    form's (within 1e-8 rad)."""
    def stepped(interrupt):
        model = inerter.load(BAR_3D, w=20.0)
        stepper = model.stepper(path="numpy")
        for k in range(1, 51):
            stepper.step(0.01 * k)
            if interrupt and k == 25:
                assert stepper.outputs()["torsion.phi_rel"] > 1.3 * math.pi
                model.simulate(stop_time=0.05, path="numpy", metrics=False)
        return stepper.outputs()["torsion.phi_rel"]

    alone = stepped(False)
    assert stepped(True) == alone
    assert alone == pytest.approx(float(closed_form(0.5, 20.0, 0.0)), abs=1e-8)


@pytest.mark.parametrize("angle", ["3.5", "-3.2", "4*pi"])
def test_a_3d_free_angle_may_be_any_number_of_turns(tmp_path, angle):
    """The free angle is no longer limited to (−π, π): the scene loads and the bar, released from
    rest, swings about it (its torque at t = 0 is −k·φ0)."""
    model = inerter.load(BAR_3D, w=0.0, phi0=angle)
    r = model.simulate(stop_time=0.05)
    phi0 = {"3.5": 3.5, "-3.2": -3.2, "4*pi": 4 * math.pi}[angle]
    assert r["torsion.tau"][0] == pytest.approx(-K * phi0, rel=1e-12)
    assert main(["describe", str(BAR_3D), "--set", f"phi0={angle}"]) == 0


def test_a_rotor_spun_past_half_a_turn_reports_its_wound_angle(tmp_path, capsys):
    """A rotor spinning at ω = 10 rad/s on a spring too weak to slow it (k = 1e-9 N·m/rad; closed
    form: uniform rotation, φ = 10 t) passes π at t = π/10 s: its φ_rel goes on to 10 rad at 1 s
    (within 1e-6 rad) and the run warns of nothing."""
    import csv
    scene = tmp_path / "rotor.toml"
    scene.write_text(ROTOR_3D)
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out)]) == 0
    assert "±π" not in capsys.readouterr().err
    with open(out / "rotor.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(row["time (s)"]) for row in rows])
    phi = np.array([float(row["torsion.phi_rel (rad)"]) for row in rows])
    assert np.abs(phi - 10.0 * t).max() < 1e-6 and phi[-1] > 3 * math.pi


ROTOR_3D = """
[scene]
name = "rotor"
dimension = 3

[bodies.rotor]
mass = 1.0
inertia = [0.1, 0.1, 0.1]
position = [0, 0, 0]
angular_velocity = [0, 0, 10]
points = { P = [0, 0, 0] }

[ground.points]
O = [0, 0, 0]

[joints.hub]
type = "revolute"
between = ["O", "P"]
axis = [0, 0, 1]

[elements.torsion]
type = "rotational_spring"
bodies = ["ground", "rotor"]
axis = [0, 0, 1]
k = 1e-9

[experiment]
stop_time = 1.0
output_interval = 0.01
"""


# Slow and fast oscillators spun past many turns between two output samples: (k in N·m/rad,
# θ̇(0) in rad/s, output interval in s). k = 0.01: ω = 0.173 rad/s, amplitude θ̇(0)/ω = 231 rad at
# 40 rad/s, turning by up to 4 rad in 0.1 s and 20 rad in 0.5 s; k = 3: ω = 3 rad/s, amplitude
# 3.3 rad, up to 5 rad in 0.5 s.
COARSE = {"slow_0.1s": (0.01, 40.0, 0.1), "slow_0.5s": (0.01, 40.0, 0.5), "backwards_0.5s": (0.01, -25.0, 0.5),
          "fast_0.5s": (3.0, 10.0, 0.5)}


def oscillator(k, w, t):
    """θ(t) of J θ̈ = −kθ from θ(0) = 0, θ̇(0) = w (the closed form of the module's docstring)."""
    omega = math.sqrt(k / J)
    return w / omega * np.sin(omega * t)


def coarse_run(case, stop_time=3.0, **kw):
    k, w, interval = COARSE[case]
    model = inerter.load(BAR_3D, k=k, w=w)
    return model.simulate(stop_time=stop_time, output_interval=interval, metrics=False, **kw), k, w


def assert_closed_form(r, k, w, phi_abs, tau_abs, energy_rel=1e-8):
    """φ_rel, τ = kφ and the energy ½Jθ̇(0)² (within `energy_rel`) of the run at its samples against
    the closed form, where the bar turns by more than half a turn between two samples."""
    assert r.run.status == "ok", r.run.message
    reference = oscillator(k, w, r.time)
    assert np.abs(np.diff(reference)).max() > math.pi            # more than half a turn between samples
    assert np.abs(r["torsion.phi_rel"] - reference).max() < phi_abs
    assert np.abs(r["torsion.tau"] - k * reference).max() < tau_abs
    E0 = 0.5 * J * w ** 2
    assert np.abs(r["energy"] - E0).max() < energy_rel * E0
    assert not r.warnings


@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("case", COARSE)
def test_samples_any_number_of_turns_apart_follow_the_closed_form(path, case):
    """Each sample's angle is recorded by the integrator from the end of the step that covers it
    (run.extra["windings"]) and its outputs read wound from it, not from the sample before: samples
    up to 20 rad apart give φ_rel,
    τ and the energy of the closed form (DOP853 at the scene's rtol 1e-10: within 1e-6 rad of an
    amplitude of 231 rad, as samples 0.01 s apart), with no warning."""
    r, k, w = coarse_run(case, path=path)
    assert path == "numpy" or r.run.extra["path"] == "compiled"
    assert r.run.extra["windings"].shape == (len(r.time), 1)
    assert_closed_form(r, k, w, 1e-6, 1e-8)
    values = r.values()                                            # every output at once: the same
    assert np.array_equal(values[:, r.names.index("torsion.phi_rel")], r["torsion.phi_rel"])


@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("method", ["RK45", "RK4", "Radau"])
def test_each_method_records_its_windings_at_coarse_samples(path, method):
    """RK45 (the compiled loop's other tableau), RK4 (its samples from the steps' cubic Hermite) and
    Radau (scipy's, on the compiled right-hand side on the compiled path) record each sample's
    angle from the step covering it: samples 0.5 s (20 rad) apart follow the closed form within 2e-5 rad
    of 231 rad, the energy within 1e-6 relative (rtol 1e-8: measured 5.6e-6 rad and 1.7e-7 for
    RK45, 2e-7 rad for Radau; RK4's step 1e-3 s, error ~(θ̇h)⁴ per unit time: 1.0e-5 rad, 3.1e-7)."""
    r, k, w = coarse_run("slow_0.5s", path=path, method=method, rtol=1e-8, atol=1e-10)
    assert_closed_form(r, k, w, 2e-5, 2e-7, 1e-6)


def test_a_projected_run_reads_its_samples_on_their_branch():
    """The projection treatment (scipy's DOP853 on the compiled right-hand side, restarted at each
    sample) records each sample's angle too: the closed form within 1e-6 rad at 0.5 s."""
    r, k, w = coarse_run("slow_0.5s", constraint="projection")
    assert r.run.extra["path"] == "scipy integrator, compiled right-hand side"
    assert_closed_form(r, k, w, 1e-6, 1e-8)


@pytest.mark.parametrize("path", ["numpy", "compiled", "compiled-kept", "Radau", "RK4"])
def test_the_dense_output_reads_each_time_on_its_branch(path):
    """The dense output of φ_rel and τ at times in no order, spread over the run (0.5 s samples,
    20 rad apart), each read from the step that gives it (run.dense.windings_at, or from the φ_ref
    at the end of scipy's step, run.extra["step_windings"]): the closed form within 1e-6 rad (Radau at
    rtol 1e-8: 2e-5 rad; RK4 at its 1e-3 s step: 2e-5 rad, as its samples in
    test_each_method_records_its_windings_at_coarse_samples). Kept by the compiled loop
    (DenseOutput), integrated again interval by interval from each sample's recorded φ_ref
    (LocalDense; RK4Dense, measured 1.0e-5 rad: a compiled RK4 run read a cubic spline through
    the samples instead, 1.6e-4 rad off), or scipy's."""
    from inerter.api import Result
    from inerter.engine import compiled

    k, w, interval = COARSE["slow_0.5s"]
    model = inerter.load(BAR_3D, k=k, w=w)
    if path == "compiled-kept":
        settings = model.settings(output_interval=interval)
        result = Result(model, settings, compiled.integrate_compiled(model.mechanism, settings, dense=True))
        assert isinstance(result.run.dense, compiled.DenseOutput)
    elif path == "Radau":
        result = model.simulate(output_interval=interval, method="Radau", rtol=1e-8, atol=1e-10, metrics=False)
    elif path == "RK4":
        result = model.simulate(output_interval=interval, method="RK4", metrics=False)
        assert isinstance(result.run.dense, compiled.RK4Dense)
    else:
        result = model.simulate(output_interval=interval, metrics=False, path=path)
    assert path != "compiled" or isinstance(result.run.dense, compiled.LocalDense)
    t = np.random.default_rng(3).permutation(np.linspace(0.03, 2.97, 37))
    reference = oscillator(k, w, t)
    bound = 2e-5 if path in ("Radau", "RK4") else 1e-6
    assert np.abs(result.dense("torsion.phi_rel")(t) - reference).max() < bound
    assert np.abs(result.dense("torsion.tau")(t) - k * reference).max() < k * bound


@pytest.mark.parametrize("scene", [BAR_3D, DATA.parent.parent / "scenarios" / "two_bar_2d_as_3d.toml"])
def test_a_signal_that_does_not_read_the_branch_is_read_without_it(scene):
    """Kernel.reads_windings: a point's coordinate, and a translational element's output evaluated
    without the accelerations, do not depend on the 3D rotational elements' branch, so the dense
    output does not work out each time's (DenseOutput.windings_at, most of what a point's coordinate
    cost in 3D): their values without it equal, bit for bit, those with the windings the steps give,
    at times in no order over the whole run (the bar: 0.5 s samples, 20 rad apart). Every other
    signal reads them (those of the rotational elements among them)."""
    from inerter.engine import compiled

    k, w, interval = COARSE["slow_0.5s"]
    model = inerter.load(scene, k=k, w=w) if scene == BAR_3D else inerter.load(scene)
    settings = model.settings(output_interval=interval if scene == BAR_3D else None)
    run = compiled.integrate_compiled(model.mechanism, settings, dense=True)
    kernel, sol = run.extra["kernel"], run.dense
    assert isinstance(sol, compiled.DenseOutput) and len(kernel.windings)
    t = np.random.default_rng(5).permutation(np.linspace(run.time[0], run.time[-1], 41))
    windings = sol.windings_at(t)
    rotational = {name for name, e in model.scene.elements.items() if e.type.startswith("rotational")}
    skipped = set()
    for name in model.signals.names:
        index = kernel.signal_index(name)
        if index is None or kernel.reads_windings(index):
            continue
        assert name.split(".")[0] not in rotational
        skipped.add(name.split(".")[0] if "." in name else name)
        alone, n_alone = kernel.dense_signal(sol, index, t)
        given, n_given = kernel.dense_signal(sol, index, t, windings=windings)
        assert n_alone == n_given == len(t)
        np.testing.assert_array_equal(alone, given)
    translational = set(model.scene.elements) - rotational
    assert set(model.scene.points) <= skipped                   # every point's coordinates
    assert translational <= skipped                              # some outputs of each such element


def test_a_peak_of_phi_rel_is_refined_on_its_branch(tmp_path):
    """A peak metric of φ_rel (the fast oscillator: amplitude θ̇(0)/ω = 10/3 rad at t = π/6 s),
    samples 0.5 s apart (5 rad), refined on the dense output integrated again between the samples
    around it (LocalDense, from each sample's recorded angle): the closed form's amplitude within
    1e-8 rad."""
    scene = tmp_path / "winding_peak.toml"
    scene.write_text(BAR_3D.read_text() + '\n[[metrics]]\nkind = "peak"\nsignal = "torsion.phi_rel"\n'
                     'reference = 0\nprefix = "phi"\n')
    k, w, interval = COARSE["fast_0.5s"]
    r = inerter.load(scene, k=k, w=w).simulate(output_interval=interval)
    assert r.metric_errors == {}
    assert r.metrics["phi_peak"] == pytest.approx(w / math.sqrt(k / J), abs=1e-8)


@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("interval", [0.01, 0.5])
def test_steps_longer_than_half_a_turn_wind_on(path, interval, tmp_path):
    """An adaptive method's step may turn the relative rotation by more than half a turn where no
    force depends on the branch: the rotor of ROTOR_3D (10 rad/s, k = 1e-9 N·m/rad) under DOP853 at
    rtol 1e-3 takes steps of 0.55 s (5.5 rad). Each step's end is read on the branch nearest the
    angle its end rates carry it to (the trapezoidal rule, kernels.wind3_step), so φ_rel follows
    the closed form (φ = 10/ω sin ωt, ω = 1e-4 rad/s) within 0.05 rad (the run's own error at rtol
    1e-3: 0.012 rad), at samples 0.01 s and 0.5 s apart."""
    from inerter.engine import compiled

    scene = tmp_path / "rotor.toml"
    scene.write_text(ROTOR_3D)
    model = inerter.load(scene)
    settings = model.settings(rtol=1e-3, atol=1e-6, stop_time=2.0, output_interval=interval)
    kept = compiled.integrate_compiled(model.mechanism, settings, dense=True)
    assert 10.0 * np.diff(kept.dense.ts).max() > math.pi                 # a step of more than half a turn
    r = model.simulate(rtol=1e-3, atol=1e-6, stop_time=2.0, output_interval=interval, metrics=False, path=path)
    assert np.abs(r["torsion.phi_rel"] - 1e5 * np.sin(1e-4 * r.time)).max() < 0.05
    assert r["torsion.phi_rel"][-1] > 6 * math.pi


@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_rk4_steps_longer_than_half_a_turn_are_warned_of(path, capsys, tmp_path):
    """What remains: within a step, the stages read the angle on the branch nearest φ_ref at the
    step's start, so a stage more than half a turn from it reads a spring's torque whole turns off.
    The adaptive methods' error control rejects such a step where the torque matters; RK4's fixed
    step is known and warned of. The rotor of ROTOR_3D (10 rad/s, J = 0.1 kg·m², k = 1e-9 N·m/rad:
    the oscillator's closed form φ = 10/ω sin ωt, ω = 1e-4 rad/s) with RK4's default step (1e-3 s)
    follows it within 1e-8 rad and warns of nothing; with experiment.step = 0.4 s (4 rad a step) the
    result says so, naming the element and the step to take (below π/max|ω_rel| = π/10 s), in
    Result.warnings, summary.json and on stderr. Its φ_rel loses no turn (the torque is too weak to
    matter, and each step's end is wound from its rates): within 1 rad of the closed form, RK4's own
    phase error at 4 rad a step (0.069 rad a step, 0.69 rad at 4 s), a lost turn being 2π."""
    scene = tmp_path / "rotor.toml"
    scene.write_text(ROTOR_3D)
    model = inerter.load(scene)
    fine = model.simulate(stop_time=4.0, output_interval=0.4, method="RK4", metrics=False, path=path)
    assert np.abs(fine["torsion.phi_rel"] - 1e5 * np.sin(1e-4 * fine.time)).max() < 1e-8
    assert fine.warnings == []
    coarse = model.simulate(stop_time=4.0, output_interval=0.4, method="RK4", step=0.4, metrics=False, path=path)
    assert np.abs(coarse["torsion.phi_rel"] - 1e5 * np.sin(1e-4 * coarse.time)).max() < 1.0
    [note] = coarse.warnings
    assert note.startswith(f"{scene}: elements.torsion: its relative rotation turns by up to 4 rad in one RK4 "
                           f"step of experiment.step = 0.4 s")
    assert "below pi/max|w_rel| = 0.314 s" in note and coarse.summary()["warnings"] == [note]
    assert main(["run", str(scene), "--set", "experiment.method=RK4", "--set", "experiment.step=0.4",
                 "--path", path, "--out", str(tmp_path / "out")]) == 0
    assert "inerter: warning: " in capsys.readouterr().err
