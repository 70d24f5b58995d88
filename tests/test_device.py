"""An inerter's device (inerter.elements.device): each effect's law against its closed form, the
scene format and its errors, the ideal limit, the device through the engine against closed forms
(a Coulomb oscillator, a Hunt-Crossley impact, a fluid inerter's dissipation per cycle), the
energy balance with the dissipated power, and the engine against the oracle on a 3D device scene.

Every reference is named in its test: a closed form (with its derivation where it is not a
textbook one), the ideal inerter's own run, or the oracle (inerter.oracle, which derives the
device from its kinetic energy, dissipation function and contact potential on Jets).
"""
from __future__ import annotations

import math
import re
import zlib
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter import elements
from inerter.common.errors import SceneError
from inerter.common.inlined import compiled_copy
from inerter.elements import device as dev
from inerter.elements import dispatch, layout
from inerter.elements import inerter as inerter_law
from inerter.engine import compiled
from test_engine_vs_oracle import _output_scale

ROOT = Path(__file__).resolve().parents[1]
TWO_BAR = ROOT / "scenarios" / "two_bar_2d.toml"
DOUBLE_PENDULUM = ROOT / "scenarios" / "double_pendulum_3d.toml"


def _device(**effects):
    """A Device from {effect: {key: value}}, optional parameters at their defaults."""
    out = []
    for effect in dev.EFFECTS:
        if effect.name in effects:
            given = effects[effect.name]
            out.append((effect.name, tuple((p.key, given.get(p.key, p.default)) for p in effect.parameters)))
    return dev.Device(tuple(out))


def _row(device, b=2.0):
    row = np.zeros(layout.ELEMENT_REAL_COLUMNS)
    row[layout.COEFFICIENT] = b
    row[layout.CENTRIPETAL] = 1.0
    for column, value in device.columns().items():
        row[column] = value
    return row


# ------------------------------------------------------------------------------------------------
# The laws against their closed forms
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("v", [-0.3, -2e-3, -1e-4, 0.0, 5e-5, 1e-3, 0.8])
def test_friction_is_regularised_coulomb_plus_viscous(v):
    """Closed form: F_c tanh(v/v_s) + c_f v, within 2 F_c e^{−2|v|/v_s} of F_c sgn v + c_f v."""
    Fc, cf, vs = 3.0, 0.5, 1e-3
    row = _row(_device(friction=dict(coulomb=Fc, viscous=cf, velocity_scale=vs)))
    for law in (compiled_copy(dev.friction), dev.friction.py_func):
        F = law(row, v)
        assert F == pytest.approx(Fc * math.tanh(v / vs) + cf * v, rel=1e-15, abs=1e-300)
        assert abs(F - (Fc * np.sign(v) + cf * v)) <= 2.0 * Fc * math.exp(-2.0 * abs(v) / vs) + 1e-15
    assert dev.force(row, 1.0, v) == pytest.approx(Fc * math.tanh(v / vs) + cf * v, rel=1e-15, abs=1e-300)


def test_fluid_channel_damping_is_linear_plus_quadratic():
    """Closed form: c₁ v + c₂ v|v| (Swift et al. 2013), odd in v."""
    row = _row(_device(fluid=dict(density=1e3, channel_length=3.0, channel_area=2e-5, piston_area=1e-3,
                                  linear_damping=40.0, quadratic_damping=900.0)))
    for v in (-0.7, -0.01, 0.0, 0.02, 1.3):
        assert dev.fluid_damping(row, v) == pytest.approx(40.0 * v + 900.0 * v * abs(v), rel=1e-15, abs=1e-300)
        assert dev.force(row, 1.0, v) == dev.fluid_damping(row, v)


@pytest.mark.parametrize("n", [1.0, 1.5])
def test_end_stops_hunt_crossley(n):
    """Closed form: past a stop by δ at the rate δ̇, N = max(0, k δⁿ + c δⁿ δ̇); −N at the lower stop,
    +N at the upper; nothing within the stroke; the elastic energy k δⁿ⁺¹/(n+1), whose derivative
    is the elastic force; the dissipated power c δⁿ δ̇² in contact, −k δⁿ δ̇ where the contact lets
    go (never negative)."""
    k, c, Lmin, Lmax = 2e4, 3e5, 0.5, 0.9
    row = _row(_device(end_stops={"min": Lmin, "max": Lmax, "stiffness": k, "damping": c, "exponent": n}))
    for L, Ldot in ((0.7, 0.3), (0.5, -1.0), (0.9, 2.0)):
        assert dev.end_stop(row, L, Ldot) == (0.0, 0.0) and dev.stop_energy(row, L) == 0.0
    for L, Ldot, d, rate, sign in ((0.49, -0.2, 0.01, 0.2, -1.0), (0.91, 0.3, 0.01, 0.3, 1.0),
                                   (0.92, -0.05, 0.02, -0.05, 1.0), (0.48, 0.02, 0.02, -0.02, -1.0)):
        F, p = dev.end_stop(row, L, Ldot)
        N = k * d ** n + c * d ** n * rate
        assert F == pytest.approx(sign * N, rel=1e-9) and N > 0
        assert p == pytest.approx(c * d ** n * rate * rate, rel=1e-9) and p >= 0.0
        E = dev.stop_energy(row, L)
        assert E == pytest.approx(k * d ** (n + 1) / (n + 1), rel=1e-9)
        h = 1e-7
        slope = (dev.stop_energy(row, L + h) - dev.stop_energy(row, L - h)) / (2 * h)
        assert slope == pytest.approx(sign * k * d ** n, rel=1e-6)      # dV/dL = the elastic force
    # leaving fast: k δⁿ + c δⁿ δ̇ < 0, the contact does not pull; its elastic energy is dissipated
    F, p = dev.end_stop(row, Lmax + 0.01, -1.0)
    assert F == 0.0 and p == pytest.approx(k * 0.01 ** n * 1.0, rel=1e-12)


def test_device_inertance_from_flywheel_and_fluid():
    """Closed forms: b = J (2π/p)² for a ball screw of lead p (Smith 2002), J n² for a gear ratio n,
    ρ ℓ A_p²/A_c for a helical channel (Swift et al. 2013)."""
    J, p = 2.5e-5, 0.01
    assert _device(flywheel=dict(inertia=J, lead=p)).inertance() == pytest.approx(J * (2 * math.pi / p) ** 2,
                                                                                     rel=1e-15)
    assert _device(flywheel=dict(inertia=J, ratio=300.0)).inertance() == pytest.approx(J * 300.0 ** 2, rel=1e-15)
    assert _device(fluid=dict(density=870.0, channel_length=3.3, channel_area=7e-5, piston_area=1.8e-3)).inertance() \
        == pytest.approx(870.0 * 3.3 * 1.8e-3 ** 2 / 7e-5, rel=1e-15)
    assert _device(friction=dict(viscous=1.0)).inertance() is None


def test_inerter_law_adds_the_device_and_its_outputs():
    """The inerter's law with a device: b (a_n·r̂ + |ṙ⊥|²/L) plus the device's force (Eq. 9 and the
    closed forms above); energy ½ b L̇² plus the stops' k δⁿ⁺¹/(n+1); the outputs in the order the
    scene names them (w_flywheel, f_friction, f_fluid, f_stop, p_loss), through the kernels'
    dispatch and uncompiled."""
    d = _device(flywheel=dict(inertia=1e-4, lead=0.02),
                friction=dict(coulomb=2.0, viscous=0.3, velocity_scale=1e-2),
                end_stops={"max": 1.0, "stiffness": 1e4, "damping": 50.0},
                )
    row = _row(d, b=d.inertance())
    b = d.inertance()
    L, Ldot, an, perp2 = 1.02, 0.4, -0.7, 0.09
    stop, stop_loss = 1e4 * 0.02 + 50.0 * 0.02 * 0.4, 50.0 * 0.02 * 0.4 ** 2
    friction = 2.0 * math.tanh(40.0) + 0.3 * 0.4
    code = elements.CODE["inerter"]
    for force in (compiled_copy(inerter_law.force), inerter_law.force.py_func):
        assert force(row, L, Ldot, an, perp2) == pytest.approx(b * (an + perp2 / L) + friction + stop, rel=1e-13)
    assert compiled_copy(dispatch.force)(code, row, L, Ldot, an, perp2) == inerter_law.force.py_func(row, L, Ldot, an, perp2)
    assert inerter_law.energy(row, L, Ldot) == pytest.approx(0.5 * b * Ldot ** 2 + 0.5 * 1e4 * 0.02 ** 2, rel=1e-13)
    names = [s for s, _, _ in d.outputs()]
    assert names == ["w_flywheel", "f_friction", "f_stop", "p_loss"]
    expected = [2 * math.pi / 0.02 * Ldot, friction, stop, friction * Ldot + stop_loss]
    none = np.zeros(0)                               # no internal states
    gq = 0.3                                         # gᵀq̈: read only by a screw efficiency's outputs
    for extra in (lambda out: compiled_copy(dispatch.extra_outputs)(code, row, L, Ldot, an, perp2, gq, none, out, 0),
                  lambda out: inerter_law.extra_outputs.py_func(row, L, Ldot, an, perp2, gq, none, out, 0)):
        out = np.full(6, np.nan)
        assert extra(out) == 4
        np.testing.assert_allclose(out[:4], expected, rtol=1e-13)
    ideal = _row(dev.Device(()))
    ideal[layout.DEVICE] = 0.0
    assert dispatch.extra_outputs(code, ideal, L, Ldot, an, perp2, gq, np.zeros(0), np.zeros(1), 3) == 3


# ------------------------------------------------------------------------------------------------
# The scene format
# ------------------------------------------------------------------------------------------------
def _with_device(text: str, device: str, element: str = "inerter", drop_b: bool = False) -> str:
    """A scene's text with `device` (TOML tables under [elements.ELEMENT.device]) appended, and the
    element's ``b`` line removed where the device gives the inertance."""
    if drop_b:
        lines, inside = [], False
        for line in text.splitlines(keepends=True):
            if line.startswith("["):
                inside = line.strip() == f"[elements.{element}]"
            if not (inside and re.match(r'b\s*=\s*"b"', line)):
                lines.append(line)
        text = "".join(lines)
    return text + "\n" + device.replace("DEVICE", f"elements.{element}.device")


def _load(tmp_path, text, name="scene.toml", **overrides):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return inerter.load(path, **overrides)


ZERO_DEVICE = """
[DEVICE.friction]
coulomb = 0.0
viscous = 0.0
velocity_scale = 1e-3

[DEVICE.end_stops]
min = 0.1
max = 2.0
stiffness = 0.0
damping = 0.0
"""


@pytest.mark.parametrize("device, field, expected", [
    ("[DEVICE.brake]\ntorque = 1.0\n", "elements.inerter.device.brake", "one of: flywheel, friction, end_stops, fluid"),
    ("[DEVICE.friction]\ncoulomb = 2.0\n", "elements.inerter.device.friction.velocity_scale", "velocity scale"),
    ("[DEVICE.friction]\ncoulomb = -2.0\nvelocity_scale = 1e-3\n", "elements.inerter.device.friction.coulomb", "≥ 0"),
    ("[DEVICE.friction]\nviscous = 1.0\nvelocity_scale = 0.0\n", "elements.inerter.device.friction.velocity_scale",
     "> 0"),
    ("[DEVICE.end_stops]\nmin = 0.9\nmax = 0.8\nstiffness = 1e4\n", "elements.inerter.device.end_stops.max",
     "> min = 0.9 m"),
    ("[DEVICE.end_stops]\nmax = 0.8\nstiffness = 1e4\nexponent = 4.0\n", "elements.inerter.device.end_stops.exponent",
     "≤ 3"),
    ("[DEVICE.end_stops]\nstiffness = 1e4\n", "elements.inerter.device.end_stops.min", "min (m) or max (m)"),
    ("[DEVICE.flywheel]\ninertia = 1e-4\nlead = 0.01\nratio = 600.0\n", "elements.inerter.device.flywheel.ratio",
     "exactly one of lead or ratio"),
])
def test_device_errors_name_the_field_value_and_expectation(tmp_path, device, field, expected):
    text = _with_device(TWO_BAR.read_text(encoding="utf-8"), device)
    with pytest.raises(SceneError) as err:
        _load(tmp_path, text)
    assert err.value.field == field and expected in err.value.expected, str(err.value)
    assert str(tmp_path / "scene.toml") in str(err.value)


@pytest.mark.parametrize("exponent", ["4.0", "0.5"])
def test_a_stop_exponent_out_of_range_reads_as_other_field_errors(tmp_path, exponent):
    """The exponent's range [1, 3] (inerter.elements.device.END_STOPS) reads as the reader writes a
    field's: "a number ≥ 1 and ≤ 3", the dimensionless unit "1" not written (it read
    "a number ≥ 1 and ≤ 3 (1)" above the range and "a number ≥ 1" below it)."""
    text = _with_device(TWO_BAR.read_text(encoding="utf-8"),
                        f"[DEVICE.end_stops]\nmax = 0.8\nstiffness = 1e4\nexponent = {exponent}\n")
    with pytest.raises(SceneError) as err:
        _load(tmp_path, text)
    assert err.value.field == "elements.inerter.device.end_stops.exponent"
    assert f"elements.inerter.device.end_stops.exponent: out of range (got {exponent}; expected a number ≥ 1 " \
           "and ≤ 3)" in str(err.value), str(err.value)
    assert str(err.value).startswith(str(tmp_path / "scene.toml"))


def test_inertance_given_twice_is_an_error(tmp_path):
    """A flywheel gives b: the element's own b as well is an error naming both."""
    text = _with_device(TWO_BAR.read_text(encoding="utf-8"), "[DEVICE.flywheel]\ninertia = 1e-4\nlead = 0.01\n")
    with pytest.raises(SceneError) as err:
        _load(tmp_path, text)
    assert err.value.field == "elements.inerter.b" and "device.flywheel gives the inertance" in err.value.expected
    both = _with_device(TWO_BAR.read_text(encoding="utf-8"),
                        "[DEVICE.flywheel]\ninertia = 1e-4\nlead = 0.01\n[DEVICE.fluid]\ndensity = 1e3\n"
                        "channel_length = 1.0\nchannel_area = 1e-4\npiston_area = 1e-3\n", drop_b=True)
    with pytest.raises(SceneError) as err:
        _load(tmp_path, both)
    assert err.value.field == "elements.inerter.device.fluid" and "one source of the inertance" in err.value.expected


def test_a_device_on_another_kind_is_an_unknown_field(tmp_path):
    text = _with_device(TWO_BAR.read_text(encoding="utf-8"), ZERO_DEVICE, element="damper")
    with pytest.raises(SceneError) as err:
        _load(tmp_path, text)
    assert err.value.field == "elements.damper.device"


def test_describe_and_outputs_list_the_device(tmp_path):
    """`describe` (Model.terms) lists each declared effect with its parameters and the inertance the
    flywheel gives; the outputs are the declared effects' (no f_fluid without a fluid channel)."""
    text = _with_device(TWO_BAR.read_text(encoding="utf-8"),
                        ZERO_DEVICE + "[DEVICE.flywheel]\ninertia = 2.533e-5\nlead = 0.01\n", drop_b=True)
    model = _load(tmp_path, text)
    line = next(t for t in model.terms() if "device:" in t)
    for part in ("flywheel (inertia = 2.533e-05 kg.m2, lead = 0.01 m)", "friction (coulomb = 0 N",
                 "end_stops (min = 0.1 m, max = 2 m", "b = 9.99988 kg"):
        assert part in line, line
    names = [o["name"] for o in model.output_info()]
    assert [n for n in names if n.startswith("inerter.")] == [
        "inerter.s_rel", "inerter.v_rel", "inerter.f", "inerter.power", "inerter.energy",
        "inerter.w_flywheel", "inerter.f_friction",
        "inerter.f_stop", "inerter.p_loss"]
    assert model.mechanism.elements[-1].coefficient == pytest.approx(2.533e-5 * (2 * math.pi / 0.01) ** 2, rel=1e-15)


# ------------------------------------------------------------------------------------------------
# The ideal limit: every effect at zero gives the ideal element's results
# ------------------------------------------------------------------------------------------------
IDEAL_VARIANTS = {
    "b-given": (ZERO_DEVICE, False),
    # b = ρ ℓ A_p²/A_c = b · 1 · 1²/1, exactly (ρ = 1.0·b: the factor 1 m⁻³ a plain number, which
    # the units check lets a product carry)
    "fluid": (ZERO_DEVICE + '[DEVICE.fluid]\ndensity = "1.0*b"\nchannel_length = 1.0\nchannel_area = 1.0\n'
              'piston_area = 1.0\nlinear_damping = 0.0\nquadratic_damping = 0.0\n', True),
    # b = J (2π/p)² with p = 2π: J, exactly (J = 1.0·b, the factor 1 m² a plain number)
    "flywheel": (ZERO_DEVICE + '[DEVICE.flywheel]\ninertia = "1.0*b"\nlead = "2*pi"\n', True),
}


@pytest.mark.parametrize("variant", list(IDEAL_VARIANTS))
@pytest.mark.parametrize("scene, stop_time", [(TWO_BAR, 10.0), (DOUBLE_PENDULUM, 5.0)],
                         ids=["2d-two-bar", "3d-double-pendulum"])
def test_a_device_with_every_effect_at_zero_is_the_ideal_inerter(tmp_path, scene, stop_time, variant):
    """Reference: the ideal scene's own compiled DOP853 run. Friction, channel damping and end-stop
    contact all zero (the stops' stroke wider than the motion too), the inertance given, or from a
    fluid channel or a flywheel that give it exactly: every output the two share agrees to 1e-12
    of its range, and the device's forces and dissipated power are zero."""
    device, drop_b = IDEAL_VARIANTS[variant]
    ideal = inerter.load(scene).simulate(stop_time=stop_time, metrics=False)
    model = _load(tmp_path, _with_device(scene.read_text(encoding="utf-8"), device, drop_b=drop_b))
    assert model.mechanism.elements[-1].device is not None
    real = model.simulate(stop_time=stop_time, metrics=False)
    assert real.run.extra["path"] == ideal.run.extra["path"] == "compiled"
    assert np.array_equal(real.time, ideal.time)
    for name in ideal.names:
        scale = max(1.0, float(np.max(np.abs(ideal[name]))))
        assert np.max(np.abs(real[name] - ideal[name])) <= 1e-12 * scale, name
    for name in ("inerter.f_friction", "inerter.f_stop", "inerter.p_loss") + (
            ("inerter.f_fluid",) if variant == "fluid" else ()):
        assert np.max(np.abs(real[name])) == 0.0, name
    if variant == "flywheel":
        np.testing.assert_allclose(real["inerter.w_flywheel"], real["inerter.v_rel"], rtol=1e-15, atol=0)


# ------------------------------------------------------------------------------------------------
# Closed forms through the engine
# ------------------------------------------------------------------------------------------------
#: A mass on the X axis, its point P joined to the ground point O by a spring (free length 1 m, so
#: x = 0 is the equilibrium) and an inerter with a device: L = 1 + x, L̇ = ẋ, effective mass m + b.
OSCILLATOR = """
[scene]
name = "device_1dof"

[parameters]
m = 1.0
b = 1.0
k = 100.0
x0 = 0.25
v0 = 0.0

[ground.points]
O = [-1.0, 0.0]

[bodies.mass]
mass = "m"
inertia = 1.0
position = ["x0", 0.0]
velocity = ["v0", 0.0]
points = { P = [0, 0] }

[elements.spring]
type = "spring"
between = ["O", "P"]
k = "k"
length = 1.0

[elements.inerter]
type = "inerter"
between = ["O", "P"]
b = "b"
"""


def _coulomb_closed_form(t, x0, M, k, Fc):
    """x(t) of M ẍ + k x + F_c sgn ẋ = 0 from rest at x0: half cycles of π/ω (ω = √(k/M)) about
    ±F_c/k, each turning point 2F_c/k nearer the origin than the last (4F_c/k per cycle), until a
    turning point lies in the dead band |x| ≤ F_c/k, where it stays. Returns x(t), the rest
    position, the time it is reached and the turning points."""
    w = math.sqrt(k / M)
    x, t0, segments, turns = x0, 0.0, [], [x0]
    while abs(x) > Fc / k:
        centre = math.copysign(Fc / k, x)
        segments.append((t0, x, centre))
        x = 2.0 * centre - x
        t0 += math.pi / w
        turns.append(x)
    out = np.full(len(t), x)
    for start, xs, centre in segments:
        sel = (t >= start) & (t < start + math.pi / w)
        out[sel] = centre + (xs - centre) * np.cos(w * (t[sel] - start))
    return out, x, t0, turns


def test_coulomb_oscillator_converges_as_the_velocity_scale_shrinks(tmp_path):
    """Closed form (_coulomb_closed_form): m = b = 1 kg, k = 100 N/m, F_c = 2 N from x0 = 0.25 m:
    turning points 0.25, −0.21, 0.17, −0.13, 0.09, −0.05 m (4F_c/k = 0.08 m lost per cycle), at
    rest at 0.01 m, inside the dead band |x| ≤ F_c/k = 0.02 m, from t = 3 T = 2.67 s.

    The regularised law's error: once stuck at x_s the mass creeps as an overdamped oscillator of
    damping F_c/v_s, x_s e^{−k v_s (t − t_s)/F_c}, so by t = 4 s it is off by x_s k v_s (4 s − t_s)/F_c
    = 0.67 s · v_s, plus the transitions at the turning points: measured 0.70-0.73 s · v_s. The
    bound is 1 s · v_s, and the error falls tenfold with v_s. Radau (implicit: a sticking phase has
    the eigenvalue −F_c/((m + b) v_s)) at rtol 1e-10 takes no more steps at v_s = 1e-6 m/s than at
    1e-3 m/s: the step size does not collapse (docs/benchmarks/coulomb_convergence.md gives the
    table at rtol 1e-12)."""
    text = OSCILLATOR.replace('[parameters]\n', '[parameters]\nFc = 2.0\nvs = 1e-3\n') + \
        '\n[elements.inerter.device.friction]\ncoulomb = "Fc"\nvelocity_scale = "vs"\n' \
        '\n[experiment]\nstop_time = 4.0\noutput_interval = 0.001\n'
    M, k, Fc, x0 = 2.0, 100.0, 2.0, 0.25
    errors, steps = [], []
    for vs in (1e-3, 1e-4, 1e-5, 1e-6):
        r = _load(tmp_path, text, vs=vs).simulate(method="Radau", rtol=1e-10, atol=1e-12, metrics=False)
        assert r.run.status == "ok", r.run.message
        x = r["P.r[1]"]
        exact, rest, t_rest, turns = _coulomb_closed_form(r.time, x0, M, k, Fc)
        assert turns == pytest.approx([0.25, -0.21, 0.17, -0.13, 0.09, -0.05, 0.01], abs=1e-15)
        err = float(np.max(np.abs(x - exact)))
        assert err <= 1.0 * vs, (vs, err)
        assert abs(x[-1]) <= Fc / k and abs(x[-1] - rest) <= 1.0 * vs
        errors.append(err)
        steps.append(r.run.steps)
    assert all(a > 8.0 * b for a, b in zip(errors, errors[1:])), errors       # first order in v_s
    assert steps[-1] <= steps[0], steps


@pytest.mark.parametrize("n", [1.0, 1.5])
def test_an_undamped_end_stop_returns_the_mass_after_the_hertz_contact_time(tmp_path, n):
    """Closed form: a mass M = m + b = 2 kg at v0 = 0.5 m/s reaches the upper stop (0.1 m away) at
    t₁ = 0.2 s; in contact M δ̈ = −k δⁿ, so it leaves at −v0 (energy) after
    t_c = 2 (δ_max/v0) ∫₀¹ (1 − s^{n+1})^{−1/2} ds = 2 (δ_max/v0) Γ(1/p) Γ(1/2)/(p Γ(1/p + 1/2)),
    p = n + 1, δ_max = (p M v0²/(2k))^{1/p} (n = 1: t_c = π √(M/k)); then L(t) = L_max − v0 (t − t₁ −
    t_c). DOP853 at rtol 1e-12; the stop force is never negative (it pushes the terminals back
    together, tension positive) and the stored energy returns whole."""
    M, v0, k, Lmax = 2.0, 0.5, 2e4, 1.1
    p = n + 1.0
    d_max = (p * M * v0 ** 2 / (2.0 * k)) ** (1.0 / p)
    t_c = 2.0 * d_max / v0 * math.gamma(1.0 / p) * math.gamma(0.5) / (p * math.gamma(1.0 / p + 0.5))
    if n == 1.0:
        assert t_c == pytest.approx(math.pi * math.sqrt(M / k), rel=1e-13)
    text = OSCILLATOR.replace('k = 100.0', 'k = 0.0').replace('x0 = 0.25', 'x0 = 0.0').replace('v0 = 0.0', 'v0 = 0.5') \
        + f'\n[elements.inerter.device.end_stops]\nmax = {Lmax}\nstiffness = {k}\nexponent = {n}\n' \
        + '\n[experiment]\nstop_time = 0.4\noutput_interval = 0.001\n'
    r = _load(tmp_path, text).simulate(method="DOP853", rtol=1e-12, atol=1e-14, metrics=False)
    assert r.run.status == "ok"
    after = r.time >= 0.2 + t_c + 1e-3
    np.testing.assert_allclose(r["inerter.s_rel"][after], Lmax - v0 * (r.time[after] - 0.2 - t_c), rtol=0, atol=1e-9)
    np.testing.assert_allclose(r["P.v[1]"][after], -v0, rtol=0, atol=1e-9)
    assert np.min(r["inerter.f_stop"]) >= 0.0 and np.max(r["inerter.f_stop"]) > 0.5 * k * d_max ** n
    assert np.max(r["inerter.s_rel"]) <= Lmax + d_max * (1 + 1e-6)


def _simpson(t, y):
    """Composite Simpson's rule on an even number of equal intervals."""
    h = t[1] - t[0]
    assert len(t) % 2 == 1 and np.allclose(np.diff(t), h, rtol=1e-9, atol=0)
    return h / 3.0 * (y[0] + y[-1] + 4.0 * np.sum(y[1:-1:2]) + 2.0 * np.sum(y[2:-1:2]))


def test_a_damped_end_stop_dissipates_what_the_mass_loses_and_never_pulls(tmp_path):
    """Reference: the kinetic energy the mass loses in the impact, ½ M (v0² − v_out²), against the
    integral of the device's p_loss over the contact (Simpson on 10 µs samples; p_loss is
    continuous, with kinks where the contact starts and lets go: measured 1.8e-9 of the loss, bound
    1e-7). Damping c_s = 3e5 N.s/m² at v0 = 0.5 m/s makes the
    contact let go before the spring has returned its energy (k δ + c δ δ̇ < 0 on the way out): the
    stop force stays ≥ 0, and the rebound is slower than the impact."""
    M, v0 = 2.0, 0.5
    text = OSCILLATOR.replace('k = 100.0', 'k = 0.0').replace('x0 = 0.25', 'x0 = 0.0').replace('v0 = 0.0', 'v0 = 0.5') \
        + '\n[elements.inerter.device.end_stops]\nmax = 1.1\nstiffness = 2e4\ndamping = 3e5\n' \
        + '\n[experiment]\nstop_time = 0.4\noutput_interval = 1e-5\n'
    r = _load(tmp_path, text).simulate(method="DOP853", rtol=1e-12, atol=1e-14, metrics=False)
    assert r.run.status == "ok"
    v_out = r["P.v[1]"][-1]
    assert -v0 < v_out < 0.0
    assert np.min(r["inerter.f_stop"]) >= 0.0
    loss = 0.5 * M * (v0 ** 2 - v_out ** 2)
    assert _simpson(r.time, r["inerter.p_loss"]) == pytest.approx(loss, rel=1e-7)
    assert v_out == pytest.approx(-0.0666, abs=1e-3)       # it leaves at about k_s/c_s = 0.067 m/s
    assert np.min(r["inerter.p_loss"]) >= 0.0


def test_energy_plus_dissipated_work_is_the_initial_energy(tmp_path):
    """Reference: the initial energy. A free oscillation from x = 0.25 m at 1 m/s through friction
    (v_s = 10 mm/s), channel damping and both end stops (b = 1 kg from the channel), no forcing:
    energy(t) (½ m v² + ½ b L̇² + ½ k x² + the stops' k_s δⁿ⁺¹/(n+1)) plus ∫₀ᵗ p_loss stays
    energy(0), every 0.2 s. DOP853 at rtol 1e-11; the integral by Simpson on 20 µs samples. The
    error is the quadrature's (the friction's tanh turns over 0.2 ms at each reversal, the contacts
    start with a kink): 4e-8, 2e-9 and 7e-10 of energy(0) on 100, 50 and 20 µs samples; the bound
    is 5e-9."""
    text = OSCILLATOR + """
[elements.inerter.device.friction]
coulomb = 0.5
viscous = 0.2
velocity_scale = 1e-2

[elements.inerter.device.end_stops]
min = 0.85
max = 1.27
stiffness = 5e4
damping = 2e4
exponent = 1.5

[elements.inerter.device.fluid]
density = 1.0
channel_length = 1.0
channel_area = 1.0
piston_area = 1.0
linear_damping = 0.1
quadratic_damping = 2.0

[experiment]
stop_time = 2.0
output_interval = 2e-5
"""
    r = _load(tmp_path, text.replace('b = "b"\n', ""), v0=1.0).simulate(method="DOP853", rtol=1e-11, atol=1e-13,
                                                                       metrics=False)
    assert r.run.status == "ok"
    E, p = r["energy"], r["inerter.p_loss"]
    assert np.max(r["inerter.f_stop"]) > 0 and np.min(r["inerter.f_stop"]) < 0      # both stops were hit
    worst = 0.0
    for j in range(10000, len(r.time), 10000):
        worst = max(worst, abs(E[j] + _simpson(r.time[:j + 1], p[:j + 1]) - E[0]))
    assert worst <= 5e-9 * E[0], worst / E[0]
    assert E[-1] < 0.5 * E[0]


def test_fluid_inerter_dissipates_its_equivalent_viscous_energy_per_cycle(tmp_path):
    """Closed form: under the stroke X sin ωt, c₂ L̇|L̇| dissipates ∮ = c₂ X³ ω³ ∫₀ᵀ|cos ωt|³ dt
    = (8/3) c₂ ω² X³ per cycle, which is π c_eq ω X² with c_eq = 8/(3π) c₂ ω X; c₁ L̇ dissipates
    π c₁ ω X². The stroke is prescribed (states q = X sin ωt, v = X ω cos ωt), the outputs come
    from the compiled kernels and from the readable evaluators, and ∮ p_loss dt by Gauss-Legendre
    on each quarter period (where |cos| is smooth: exact to round-off)."""
    X, f, c1, c2 = 0.03, 1.7, 15.0, 400.0
    w = 2 * math.pi * f
    text = OSCILLATOR.replace('b = "b"\n', "") + f"""
[elements.inerter.device.fluid]
density = 1000.0
channel_length = 2.0
channel_area = 3e-5
piston_area = 1.2e-3
linear_damping = {c1}
quadratic_damping = {c2}
"""
    model = _load(tmp_path, text)
    assert model.mechanism.elements[-1].coefficient == pytest.approx(1000.0 * 2.0 * 1.2e-3 ** 2 / 3e-5, rel=1e-15)
    nodes, weights = np.polynomial.legendre.leggauss(20)
    quarter = 0.25 / f
    times = np.concatenate([(i + 0.5) * quarter + 0.5 * quarter * nodes for i in range(4)])
    mech = model.mechanism
    states = np.zeros((len(times), mech.nq + mech.n))
    states[:, 0] = X * np.sin(w * times)
    states[:, mech.nq] = X * w * np.cos(w * times)
    kernel = compiled.compile_mechanism(mech)
    order = kernel.signal_order(model.signals)
    values, k = kernel.signal_history(model.signals, order, times, states)
    assert k == len(times)
    index = model.signals.index
    numpy_values = np.array([model.signals.evaluate(t, y[:mech.nq], y[mech.nq:]) for t, y in zip(times, states)])
    c_eq = 8.0 / (3.0 * math.pi) * c2 * w * X
    for table in (values, numpy_values):
        per_cycle = 0.5 * quarter * float(np.tile(weights, 4) @ table[:, index["inerter.p_loss"]])
        assert per_cycle == pytest.approx(math.pi * (c1 + c_eq) * w * X ** 2, rel=1e-13)
        fluid = table[:, index["inerter.f_fluid"]]
        v = states[:, mech.nq]
        assert np.max(np.abs(fluid - (c1 * v + c2 * v * np.abs(v)))) <= 1e-13 * np.max(np.abs(fluid))
    assert (8.0 / 3.0) * c2 * w ** 2 * X ** 3 == pytest.approx(math.pi * c_eq * w * X ** 2, rel=1e-15)


# ------------------------------------------------------------------------------------------------
# The engine against the oracle on a 3D device scene
# ------------------------------------------------------------------------------------------------
def _device_pendulum(tmp_path, coulomb=1.5):
    """The 3D double pendulum with a fluid inerter device between its rods (b = 0.5 kg from the
    channel), friction and end stops: the lower 2 mm beyond the initial distance L0 (it starts in
    contact, then the distance grows), the upper at 1.05 L0 (reached at 0.5 s)."""
    base = inerter.load(DOUBLE_PENDULUM)
    L0 = float(base.signals.function("inerter.s_rel")(0.0, base.mechanism.q0, base.mechanism.v0))
    device = f"""
[DEVICE.friction]
coulomb = {coulomb}
viscous = 0.3
velocity_scale = 2e-2

[DEVICE.end_stops]
min = {L0 + 2e-3}
max = {1.05 * L0}
stiffness = 3e3
damping = 1e4
exponent = 1.5

[DEVICE.fluid]
density = "b"
channel_length = 2.0
channel_area = 1e-4
piston_area = 5e-3
linear_damping = 0.2
quadratic_damping = 1.0
"""
    text = _with_device(DOUBLE_PENDULUM.read_text(encoding="utf-8"), device, drop_b=True)
    text = text.replace('density = "b"', 'density = "b/(2.0*(5e-3)^2/1e-4)"')       # b = ρ ℓ A_p²/A_c
    return _load(tmp_path, text, name=f"pendulum_{coulomb}.toml")


def test_engine_equals_the_oracle_on_a_3d_device(tmp_path):
    """Reference: the oracle (device from its kinetic energy, dissipation function and contact
    potential, kinematics by Jets). Accelerations and every output at the initial state, along the
    oracle's run and at random states (1e-12 relative; forces over the inertance, the device's
    outputs over their laws' slopes: test_engine_vs_oracle._output_scale); DOP853 runs at rtol
    1e-12 over 2 s within 2·N·rtol of each output's range (N: the steps; see below); the run
    reaches both stops."""
    model = _device_pendulum(tmp_path)
    oracle = model.oracle()
    mech, omech = model.mechanism, oracle.mechanism
    assert mech.elements[-1].coefficient == pytest.approx(0.5, rel=1e-15) == omech.elements[-1].coefficient
    kernel = compiled.compile_mechanism(mech)
    order = kernel.signal_order(model.signals)
    settings = model.settings(method="DOP853", stop_time=2.0, rtol=1e-12, atol=1e-14)
    from inerter.engine.simulation import integrate
    ref = integrate(omech, settings)
    run = compiled.integrate_compiled(mech, settings)
    assert run.status == ref.status == "ok" and np.array_equal(run.time, ref.time)
    scale = _output_scale(model)
    a, _ = kernel.signal_history(model.signals, order, run.time, run.states)
    b = np.array([oracle.signals.evaluate(t, y[:mech.nq], y[mech.nq:]) for t, y in zip(ref.time, ref.states)])
    stops = b[:, model.signals.index["inerter.f_stop"]]
    assert stops.max() > 0 and stops.min() < 0
    dev_run = np.abs(a - b) / scale / np.maximum(1.0, np.max(np.abs(b / scale), axis=0))
    # The bound TOL_RUN of test_engine_vs_oracle derives: two DOP853 runs at rtol each keep a step's
    # local error below rtol·|y|, so over N steps they differ by at most 2·N·rtol of the motion.
    # TOL_RUN = 2e-10 is what the shipped scenes measure where both runs take the same steps; here
    # the friction's and the contacts' steep laws make the error estimates, and so the steps, differ
    # (364 against 372), and the runs differ by their global errors (measured 2.5e-10 to 3.4e-10 of
    # the range): the derived bound itself, 2·N·rtol = 7.4e-10, is the tolerance.
    bound = 2.0 * max(run.steps, ref.steps) * 1e-12
    assert dev_run.max() <= bound, (model.signals.names[int(np.argmax(dev_run.max(axis=0)))], dev_run.max(), bound)
    rng = np.random.default_rng(zlib.crc32(b"device-3d"))
    states = [(float(t), y[:mech.nq].copy(), y[mech.nq:].copy()) for t, y in zip(ref.time[::40], ref.states[::40])]
    for _ in range(8):
        q = mech.q0.copy()
        for k in mech.q_index:
            q[k:k + 3] += 0.2 * rng.standard_normal(3)
            q[k + 3:k + 7] += 0.1 * rng.standard_normal(4)
        states.append((float(rng.uniform(0, 2)), q, 2.0 * rng.standard_normal(mech.n)))
    for t, q, v in states:
        x = np.concatenate(kernel.accelerations(t, q, v))
        y = np.concatenate(omech.accelerations(t, q, v))
        assert np.max(np.abs(x - y)) <= 1e-12 * max(1.0, np.max(np.abs(y)))
        out = kernel.signal_values(model.signals, order, t, q, v) / scale
        ref_out = oracle.signals.evaluate(t, q, v) / scale
        assert np.max(np.abs(out - ref_out) / (1.0 + np.abs(ref_out) + np.max(np.abs(y)))) <= 1e-12


def test_the_device_comparison_can_fail(tmp_path):
    """Guard: the engine with F_c one part in 10⁶ larger is far from the oracle of the scene."""
    model = _device_pendulum(tmp_path)
    wrong = _device_pendulum(tmp_path, coulomb=1.5 * (1 + 1e-6))
    omech = model.oracle().mechanism
    kernel = compiled.compile_mechanism(wrong.mechanism)
    q, v = omech.q0, omech.v0 + 0.3
    x = np.concatenate(kernel.accelerations(0.0, q, v))
    y = np.concatenate(omech.accelerations(0.0, q, v))
    assert np.max(np.abs(x - y)) > 1e3 * 1e-12 * np.max(np.abs(y))
