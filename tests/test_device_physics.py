"""An inerter device's effects against physics written out here, on scenes of their own.

References, each named in its test:

* the gyroscope in a gimbal (3D): a carrier A spins about the vertical on a revolute joint (ψ), a
  gimbal B pitches in it about A's y axis (θ), a slider S moves along B's x axis (x) on a spring,
  and a ball-screw device with a Hooke mount (first axis B's y) acts between B's pivot and S. Its
  kinetic energy T = ½ q̇ᵀ M(q) q̇, q = (ψ, θ, x), written here from the bodies' kinematics (ω_B in
  B's frame (−ψ̇ sin θ, θ̇, ψ̇ cos θ), S at x along u = B's x axis, the housing turning with B so
  its spin about u is ω_B·u = −ψ̇ sin θ and the flywheel's ½ J (−ψ̇ sin θ + n ẋ)²), and Lagrange's
  equations M q̈ = ½ q̇ᵀ ∂M/∂q q̇ − Ṁ q̇ − ∂V/∂q solved by scipy. At t = 0 (θ = 0) the pitch
  acceleration is the flywheel's gyroscopic moment over the pitch inertia, −J n ẋ Ω / I_θ, a closed
  form of J ω_flywheel × Ω_carrier;
* a lumped mass (2D, 1 DOF): a mass on a spring with a device whose moving parts translate with it
  is the linear oscillator (m + m_parts + b) ẍ + k x = F0 sin ωt, solved in closed form;
* the series connection with backlash and viscous friction (2D, 1 DOF): the explicit ODE of
  docs/scene_format.md ("Series compliance", "Backlash": F = k_c d + c_c ṡ beyond the gap, clipped
  where it would pull, 0 inside it; b ü = F − c_f u̇, u = L − s), solved by scipy.
"""
from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import inerter

# ------------------------------------------------------------------------------------------------
# The gyroscope in a gimbal
# ------------------------------------------------------------------------------------------------
I_AZ, I_B, M_S, I_S = 0.2, (0.05, 0.08, 0.06), 0.5, 1e-3
K_S, X0, V0, OMEGA = 200.0, 0.3, 0.4, 6.0
J_FW, N_FW = 2e-3, 60.0                  # b = J n² = 7.2 kg; the flywheel spins at n ẋ = 24 rad/s at t = 0
JT_FW, M_FW, C_FW = 3e-4, 0.4, 0.1      # its transverse inertia, mass and centre (from terminal a)

GIMBAL = """
[scene]
name = "gimbal_device_3d"
dimension = 3

[ground.points]
O = [0, 0, 0]

[bodies.A]
mass = 1.0
inertia = [0.1, 0.1, {I_AZ}]
position = [0, 0, 0]
angular_velocity = [0, 0, {OMEGA}]
points = {{ PA = [0, 0, 0] }}

[bodies.B]
mass = 1.0
inertia = [{IBX}, {IBY}, {IBZ}]
position = [0, 0, 0]
angular_velocity = [0, 0, {OMEGA}]
points = {{ QB = [0, 0, 0] }}

[bodies.S]
mass = {M_S}
inertia = [{I_S}, {I_S}, {I_S}]
position = [{X0}, 0, 0]
velocity = [{V0}, {VY}, 0]
angular_velocity = [0, 0, {OMEGA}]
points = {{ SP = [0, 0, 0] }}

[joints.spin]
type = "revolute"
between = ["O", "PA"]
axis = [0, 0, 1]

[joints.pitch]
type = "revolute"
between = ["PA", "QB"]
axis = [0, 1, 0]

[joints.slide]
type = "prismatic"
between = ["QB", "SP"]
axis = [1, 0, 0]

[elements.spring]
type = "spring"
between = ["QB", "SP"]
k = {K_S}
length = {X0}

[elements.dev]
type = "inerter"
between = ["QB", "SP"]

[elements.dev.device.flywheel]
inertia = {J_FW}
ratio = {N_FW}
transverse_inertia = {JT_FW}
mass = {M_FW}
centre = {C_FW}

[elements.dev.device.mount]
axis = [0, 1, 0]

[experiment]
stop_time = 2.0
output_interval = 0.01
method = "DOP853"
rtol = 1e-11
atol = 1e-13
"""


def _gimbal_scene(tmp_path):
    text = GIMBAL.format(I_AZ=I_AZ, IBX=I_B[0], IBY=I_B[1], IBZ=I_B[2], M_S=M_S, I_S=I_S, X0=X0, V0=V0,
                         VY=OMEGA * X0, OMEGA=OMEGA, K_S=K_S, J_FW=J_FW, N_FW=N_FW, JT_FW=JT_FW, M_FW=M_FW,
                         C_FW=C_FW)
    path = tmp_path / "gimbal_device_3d.toml"
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def gimbal_mass(q):
    """M(q) of T = ½ q̇ᵀ M q̇, q = (ψ, θ, x): A about z; B with ω_B = (−ψ̇ s, θ̇, ψ̇ c) in its frame;
    S (and the flywheel's centre at C_FW) on u, whose rate has |u̇|² = ψ̇² c² + θ̇²; the flywheel's
    transverse inertia on |u̇|²; its spin −ψ̇ s + n ẋ (the housing turns with B)."""
    _, th, x = q
    s, c = np.sin(th), np.cos(th)
    lateral = M_S * x ** 2 + JT_FW + M_FW * C_FW ** 2
    return np.array([
        [I_AZ + I_B[0] * s ** 2 + I_B[2] * c ** 2 + I_S + lateral * c ** 2 + J_FW * s ** 2, 0.0, -J_FW * N_FW * s],
        [0.0, I_B[1] + I_S + lateral, 0.0],
        [-J_FW * N_FW * s, 0.0, M_S + J_FW * N_FW ** 2]])


def gimbal_rates(t, y):
    """Lagrange's equations of T = ½ q̇ᵀ M(q) q̇, V = ½ k (x − x0)²: ∂M/∂q by a complex step."""
    q, v = y[:3], y[3:]
    dM = []
    for i in range(3):
        dq = np.zeros(3, dtype=complex)
        dq[i] = 1e-30j
        dM.append(gimbal_mass(q + dq).imag / 1e-30)
    Mdot = sum(dM[i] * v[i] for i in range(3))
    force = np.array([0.5 * v @ dM[i] @ v for i in range(3)]) - Mdot @ v - np.array([0.0, 0.0, K_S * (q[2] - X0)])
    return np.concatenate((v, np.linalg.solve(gimbal_mass(q), force)))


def test_a_flywheel_carried_round_exerts_its_gyroscopic_moment(tmp_path):
    """Reference: the gimbal's Lagrange equations (module docstring), DOP853 at rtol 1e-12. The
    engine's pitch θ, slide x and spin rate ψ̇ follow them within 1e-9 over 2 s (measured 3e-12 rad,
    2e-12 m, 2e-11 rad/s; compiled and numpy paths); θ swings through 0.6 rad, and without the
    gyroscopic term (the flywheel's spin n ẋ alone) the model would leave θ at 0. At t = 0 the
    explicit pitch acceleration is the closed form −J n ẋ Ω / I_θ. No dissipation: the energy
    output stays within 1e-9 J of its start (measured 5e-11 J) and equals T + V."""
    path = _gimbal_scene(tmp_path)
    y0 = np.array([0.0, 0.0, X0, OMEGA, 0.0, V0])
    i_theta = I_B[1] + I_S + M_S * X0 ** 2 + JT_FW + M_FW * C_FW ** 2
    assert gimbal_rates(0.0, y0)[4] == pytest.approx(-J_FW * N_FW * V0 * OMEGA / i_theta, rel=1e-14)
    model = inerter.load(path)
    ref = None
    for route in ("compiled", "numpy"):
        r = model.simulate(path=route, metrics=False)
        assert r.status == "ok", r.message
        if ref is None:
            ref = solve_ivp(gimbal_rates, (0.0, r.time[-1]), y0, t_eval=r.time, method="DOP853", rtol=1e-12,
                            atol=1e-13)
        pos = np.stack([r[f"SP.r[{i}]"] for i in (1, 2, 3)])
        x = np.linalg.norm(pos, axis=0)
        theta = -np.arcsin(pos[2] / x)
        assert np.ptp(ref.y[1]) > 0.5
        assert np.max(np.abs(theta - ref.y[1])) < 1e-9
        assert np.max(np.abs(x - ref.y[2])) < 1e-9
        assert np.max(np.abs(r["B.w[3]"] - ref.y[3])) < 1e-9
        energy = np.array([0.5 * y[3:] @ gimbal_mass(y[:3]) @ y[3:] + 0.5 * K_S * (y[2] - X0) ** 2 for y in ref.y.T])
        assert np.ptp(r["energy"]) < 1e-9
        assert np.max(np.abs(r["energy"] - energy)) < 1e-9


# ------------------------------------------------------------------------------------------------
# 1-DOF scenes: a mass on a spring along X, the device between the ground point O and the mass's P
# ------------------------------------------------------------------------------------------------
ONE_DOF = """
[scene]
name = "{name}"

[ground.points]
O = [-1.0, 0.0]

[bodies.mass]
mass = {m}
inertia = 1.0
position = [0.0, 0.0]
points = {{ P = [0, 0] }}

[elements.spring]
type = "spring"
between = ["O", "P"]
k = {k}
length = 1.0

[elements.inerter]
type = "inerter"
between = {between}
{b}
{device}

[forces.F]
point = "P"
direction = [1, 0]
function = "sine"
amplitude = {F0}
frequency = {f}

[experiment]
stop_time = {stop}
output_interval = {out}
method = "DOP853"
rtol = 1e-10
atol = 1e-12
"""


def _one_dof(tmp_path, name, device, b=None, reverse=False, m=1.0, k=100.0, F0=5.0, f=1.0, stop=5.0, out=0.001):
    text = ONE_DOF.format(name=name, m=m, k=k, between='["P", "O"]' if reverse else '["O", "P"]',
                          b="" if b is None else f"b = {b}", device=device, F0=F0, f=f, stop=stop, out=out)
    path = tmp_path / f"{name}.toml"
    path.write_text(text, encoding="utf-8")
    return inerter.load(path)


FLYWHEEL_PARTS = """
[elements.inerter.device.flywheel]
inertia = 2.533e-5
lead = 0.01
mass = 0.3
centre = 0.1
transverse_inertia = 0.005

[elements.inerter.device.housing]
mass = 0.4
centre = 0.2
transverse_inertia = 0.02

[elements.inerter.device.rod]
mass = 0.7
centre = 0.3
transverse_inertia = 0.01
"""


@pytest.mark.parametrize("reverse", [False, True], ids=["rod_moves", "housing_moves"])
def test_device_parts_on_a_straight_stroke_are_a_lumped_mass(tmp_path, reverse):
    """Reference: closed form. The terminal that moves carries its parts (terminal b: the rod;
    terminal a: the housing and the flywheel), the other's stay on the ground, and on a stroke
    that does not turn the transverse inertias do nothing: (m + m_parts + b) ẍ + k x = F0 sin ωt,
    b = J (2π/p)², from rest: x = F0/(k − M ω²) (sin ωt − (ω/ω_n) sin ω_n t). Within 1e-9 m
    (measured 1e-11 m at rtol 1e-10), and `energy` = ½ M ẋ² + ½ k x² to 1e-12 J."""
    b = 2.533e-5 * (2.0 * math.pi / 0.01) ** 2
    mass = 1.0 + b + ((0.4 + 0.3) if reverse else 0.7)
    w, wn, k, F0 = 2.0 * math.pi, math.sqrt(100.0 / mass), 100.0, 5.0
    model = _one_dof(tmp_path, "parts_" + ("a" if reverse else "b"), FLYWHEEL_PARTS, reverse=reverse, stop=3.0,
                     out=0.01)
    for route in ("compiled", "numpy"):
        r = model.simulate(path=route, metrics=False)
        t = r.time
        x = F0 / (k - mass * w ** 2) * (np.sin(w * t) - (w / wn) * np.sin(wn * t))
        v = F0 / (k - mass * w ** 2) * w * (np.cos(w * t) - np.cos(wn * t))
        assert np.max(np.abs(r["P.r[1]"] - x)) < 1e-9
        assert np.max(np.abs(r["energy"] - (0.5 * mass * r["P.v[1]"] ** 2 + 0.5 * k * r["P.r[1]"] ** 2))) < 1e-12
        assert np.max(np.abs(r["P.v[1]"] - v)) < 1e-8


SERIES = """
[elements.inerter.device.compliance]
stiffness = {kc}
damping = {cc}

[elements.inerter.device.backlash]
gap = {gap}

[elements.inerter.device.friction]
viscous = {cf}

[elements.inerter.device.dissipated_energy]
"""


def series_rates(kc, cc, gap, cf, m=1.0, b=1.0, k=100.0, F0=5.0, w=4.0 * math.pi):
    """The explicit series connection with a dead zone ±Δ/2 (module docstring), y = (x, ẋ, s, ṡ, W, E):
    W the force's work, E the dissipated energy (the series damper's and the friction's power, and
    the spring's stored ½ k_c d² where the clip releases it)."""
    h = 0.5 * gap

    def rates(t, y):
        x, v, s, sd = y[:4]
        d = s - math.copysign(h, s) if abs(s) > h else 0.0
        F = kc * d + cc * sd if d else 0.0
        F = max(F, 0.0) if d > 0 else min(F, 0.0)
        ud = v - sd
        a = (F0 * math.sin(w * t) - k * x - F) / m
        loss = (F - kc * d) * sd if F else -kc * d * sd
        return [v, a, sd, a - (F - cf * ud) / b, F0 * math.sin(w * t) * v, loss + cf * ud * ud]
    return rates


def test_series_backlash_and_friction_follow_their_explicit_ode(tmp_path):
    """Reference: the explicit ODE (series_rates), DOP853 at rtol 1e-12 with steps ≤ 0.1 ms (no
    events: its steps cross the gap's edges). The mass and the series deflection within 1e-9 m
    (measured 3e-11 m, 6e-11 m), the dissipated energy output within 1e-8 J of the ODE's, and
    energy + e_loss − E0 within 1e-8 J of the force's work (0.26 J, 0.17 J dissipated; measured 4e-10 J:
    no stored energy is lost unaccounted, the clip's included)."""
    kc, cc, gap, cf = 2000.0, 5.0, 4e-3, 0.7
    model = _one_dof(tmp_path, "series_backlash", SERIES.format(kc=kc, cc=cc, gap=gap, cf=cf), b=1.0, f=2.0,
                     stop=2.5, out=0.005)
    ref = None
    for route in ("compiled", "numpy"):
        r = model.simulate(path=route, metrics=False)
        if ref is None:
            ref = solve_ivp(series_rates(kc, cc, gap, cf), (0.0, r.time[-1]), np.zeros(6), t_eval=r.time,
                            method="DOP853", rtol=1e-12, atol=1e-14, max_step=1e-4)
        s = r["inerter.s_series"]
        assert s.max() > 0.5 * gap and s.min() < -0.5 * gap and set(r["inerter.engaged"]) == {0.0, 1.0}
        assert np.max(np.abs(r["P.r[1]"] - ref.y[0])) < 1e-9
        assert np.max(np.abs(r["inerter.s_series"] - ref.y[2])) < 1e-9
        assert np.max(np.abs(r["inerter.e_loss"] - ref.y[5])) < 1e-8
        balance = r["energy"] + r["inerter.e_loss"] - r["energy"][0] - ref.y[4]
        assert np.max(np.abs(balance)) < 1e-8


STOPS = """
[elements.inerter.device.end_stops]
min = {low}
max = {high}
stiffness = 1e5
"""


@pytest.mark.parametrize("low, high, field", [(1.1, 1.2, "min"), (0.5, 0.9, "max"), (1.0, 1.2, None),
                                              (0.9, 1.1, None)])
def test_a_device_that_starts_past_its_stop_is_noted(tmp_path, low, high, field):
    """Reference: the geometry (the terminal distance is 1 m at t = 0). A stop on the wrong side of
    it presses the device in from the start (a 1e4 N contact force here): allowed (a device may
    rest on its stop) and run, but `Result.warnings` (printed by `inerter run`, in summary.json)
    names the stop, by how much and the force; a start at the stop or between them is not noted."""
    model = _one_dof(tmp_path, f"stops_{field}", STOPS.format(low=low, high=high), b=1.0, stop=0.05)
    r = model.simulate(metrics=False)
    assert r.status == "ok"
    notes = [n for n in r.warnings if "end_stops" in n]
    if field is None:
        assert notes == [] and r["inerter.f_stop"][0] == 0.0
        return
    [note] = notes
    force = r["inerter.f_stop"][0]
    assert abs(force) == pytest.approx(1e5 * 0.1, rel=1e-12)
    assert note.startswith(f"{model.source}: elements.inerter.device.end_stops.{field}: the device starts past "
                           "its stop, pressed in by 0.1 m (terminal distance 1 m at t = 0")
    assert f"contact force {force:.3g} N" in note
