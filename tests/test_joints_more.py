"""Cylindrical, universal and planar joints (3D) and revolute joints with stiffness and damping
(2D and 3D), each against a closed form or an explicit model built from the other joint kinds.

References: a body on a cylindrical joint about Z under gravity falls freely along the axis and
spins at its initial rate, whatever the gravity across the axis (closed form); a body on a planar
joint moves with the in-plane part of gravity and spins freely (closed form); a pendulum on a
universal joint started about one of its axes moves exactly as the same pendulum on a revolute
joint about that axis (explicit model), and in general keeps its two axes at a right angle (the
joint's definition) and its energy; a bar pinned by a revolute joint with stiffness and damping is
the damped oscillator J θ̈ + d θ̇ + k θ = 0 (closed form), and in 3D the same joint equals a
revolute joint plus rotational spring and damper elements declared separately (explicit model).
"""
import math
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.common.errors import SceneError

RTOL, ATOL = 1e-11, 1e-13
ROOT = Path(__file__).resolve().parents[1]
HEAD = """
[scene]
name = "{name}"
dimension = {dim}

[experiment]
stop_time = 2.0
output_interval = 0.01
method = "DOP853"
rtol = 1e-11
atol = 1e-13
"""


def _load(tmp_path, name, body, dim=3):
    path = tmp_path / f"{name}.toml"
    path.write_text(HEAD.format(name=name, dim=dim) + body)
    return inerter.load(path)


def _run(model):
    result = model.simulate(metrics=False)
    assert result.status == "ok", result.message
    return result


CYLINDRICAL = """
[effects]
gravity = [1.5, -0.7, -9.81]

[ground.points]
O = [0, 0, 0]

[bodies.sleeve]
mass = 2.0
inertia = [0.1, 0.12, 0.05]
position = [0, 0, 0]
velocity = [0, 0, 0.8]
angular_velocity = [0, 0, 3.0]
points = { S = [0, 0, 0], P = [0.3, 0, 0] }

[joints.J]
type = "cylindrical"
between = ["O", "S"]
axis = [0, 0, 1]
"""


def test_cylindrical_joint_slides_and_turns_about_its_axis(tmp_path):
    r = _run(_load(tmp_path, "cylindrical", CYLINDRICAL))
    t = r.time
    z = 0.8 * t - 0.5 * 9.81 * t ** 2
    phi = 3.0 * t
    assert np.max(np.abs(r["S.r[1]"])) < 1e-9 and np.max(np.abs(r["S.r[2]"])) < 1e-9
    assert np.max(np.abs(r["S.r[3]"] - z)) < 1e-9
    assert np.max(np.abs(r["P.r[1]"] - 0.3 * np.cos(phi))) < 1e-9
    assert np.max(np.abs(r["P.r[2]"] - 0.3 * np.sin(phi))) < 1e-9
    assert r.summary()["statistics"]["max_constraint_drift"] < 1e-10


PLANAR = """
[effects]
gravity = [1.5, 0, -9.81]

[ground.points]
O = [0, 0, 0]

[bodies.puck]
mass = 0.5
inertia = [0.01, 0.02, 0.03]
position = [0, 0, 0]
velocity = [0, 0.6, 0]
angular_velocity = [0, 0, -2.0]
points = { S = [0, 0, 0], P = [0.2, 0, 0] }

[joints.J]
type = "planar"
between = ["O", "S"]
axis = [0, 0, 1]
"""


def test_planar_joint_keeps_the_body_in_its_plane(tmp_path):
    r = _run(_load(tmp_path, "planar", PLANAR))
    t = r.time
    x, y, phi = 0.75 * t ** 2, 0.6 * t, -2.0 * t
    assert np.max(np.abs(r["S.r[3]"])) < 1e-9 and np.max(np.abs(r["P.r[3]"])) < 1e-9
    assert np.max(np.abs(r["P.r[1]"] - (x + 0.2 * np.cos(phi)))) < 1e-9
    assert np.max(np.abs(r["P.r[2]"] - (y + 0.2 * np.sin(phi)))) < 1e-9


def _pendulum(joint, angles=("a", 0.0)):
    """A rod hanging from the ground at O on `joint`, turned by angles about X then about Y."""
    ax, ay = angles
    return f"""
[parameters]
a = {{ value = 0.6, unit = "rad", description = "initial turn" }}

[effects]
gravity = [0, 0, -9.81]

[ground.points]
O = [0, 0, 0]

[bodies.rod]
mass = 1.3
inertia = [0.11, 0.07, 0.004]
position = ["-0.5*sin({ay})", "0.5*sin({ax})*cos({ay})", "-0.5*cos({ax})*cos({ay})"]
euler = [0, 0, 0]
points = {{ T = [0, 0, 0.5], Q = [0, 1, 0.5], Tip = [0, 0, -0.5] }}

{joint}
"""


def _turned(text, ax, ay):
    """The rod's initial rotation R_x(ax) R_y(ay) as Z-X-Z Euler angles (scene field `euler`)."""
    from inerter.common.rotations import euler_from_matrix
    c, s = math.cos, math.sin
    Rx = np.array(((1, 0, 0), (0, c(ax), -s(ax)), (0, s(ax), c(ax))))
    Ry = np.array(((c(ay), 0, s(ay)), (0, 1, 0), (-s(ay), 0, c(ay))))
    e = euler_from_matrix(Rx @ Ry)
    return text.replace("euler = [0, 0, 0]", f"euler = [{float(e[0])!r}, {float(e[1])!r}, {float(e[2])!r}]")


def _universal(ax):
    """A universal joint at O: axis X fixed in the ground, axis2 the rod's own Y (which the initial
    rotation R_x(ax) R_y(ay) carries to (0, cos ax, sin ax)), so that A = R_x(α) R_y(β)."""
    return f"""[joints.U]
type = "universal"
between = ["O", "T"]
axis = [1, 0, 0]
axis2 = [0, {math.cos(ax)!r}, {math.sin(ax)!r}]
"""


@pytest.mark.parametrize("about", ["x", "y"])
def test_universal_joint_started_about_one_axis_is_a_revolute_joint(tmp_path, about):
    ax, ay = (0.6, 0.0) if about == "x" else (0.0, 0.6)
    axis = "[1, 0, 0]" if about == "x" else "[0, 1, 0]"
    revolute = f'[joints.R]\ntype = "revolute"\nbetween = ["O", "T"]\naxis = {axis}\n'
    u = _run(_load(tmp_path, "universal", _turned(_pendulum(_universal(ax), (ax, ay)), ax, ay)))
    rv = _run(_load(tmp_path, "revolute", _turned(_pendulum(revolute, (ax, ay)), ax, ay)))
    for name in ("Tip.r[1]", "Tip.r[2]", "Tip.r[3]"):
        assert np.max(np.abs(u[name] - rv[name])) < 1e-8, name


def test_universal_joint_keeps_its_axes_square_and_its_energy(tmp_path):
    ax, ay = 0.6, 0.4
    r = _run(_load(tmp_path, "universal2", _turned(_pendulum(_universal(ax), (ax, ay)), ax, ay)))
    # axis2 is the body's local Y (T → Q); it stays perpendicular to the ground's X (axis)
    assert np.max(np.abs(r["Q.r[1]"] - r["T.r[1]"])) < 1e-9
    assert np.max(np.abs(r["T.r[1]"]) + np.abs(r["T.r[2]"]) + np.abs(r["T.r[3]"])) < 1e-9
    energy = r["energy"]
    assert np.max(np.abs(energy - energy[0])) < 1e-8 * max(1.0, abs(energy[0]))
    assert np.ptp(r["Tip.r[1]"]) > 0.1 and np.ptp(r["Tip.r[2]"]) > 0.1     # it moves about both axes


def test_universal_axes_must_be_perpendicular(tmp_path):
    bad = _universal(0.0).replace("axis2 = [0, 1.0, 0.0]", "axis2 = [0.6, 0.8, 0]")
    with pytest.raises(SceneError, match=r"joints\.U\.axis2"):
        _load(tmp_path, "bad", _pendulum(bad))


BAR_2D = """
[ground.points]
O = [0, 0]

[bodies.bar]
mass = 3.0
inertia = 0.25
position = ["0.5*cos(0.2)", "0.5*sin(0.2)"]
angle = 0.2
velocity = ["-0.5*sin(0.2)*1.5", "0.5*cos(0.2)*1.5"]
angular_velocity = 1.5
points = {{ A = [-0.5, 0], B = [0.5, 0] }}

[joints.pin]
type = "revolute"
between = ["O", "A"]
{extra}
"""


def test_revolute_stiffness_and_damping_make_the_damped_oscillator(tmp_path):
    k, d = 40.0, 1.5
    r = _run(_load(tmp_path, "column", BAR_2D.format(extra=f"stiffness = {k}\ndamping = {d}"), dim=2))
    J = 0.25 + 3.0 * 0.5 ** 2                            # about the pin
    w0, zeta = math.sqrt(k / J), d / (2 * math.sqrt(k * J))
    wd = w0 * math.sqrt(1 - zeta ** 2)
    t = r.time
    theta = 0.2 + 1.5 / wd * np.exp(-zeta * w0 * t) * np.sin(wd * t)     # free angle: the initial one
    assert np.max(np.abs(r["B.r[2]"] - np.sin(theta))) < 1e-9
    assert np.max(np.abs(r["pin_spring.tau"] - k * (r["pin_spring.phi_rel"] - 0.2))) < 1e-9
    assert np.max(np.abs(r["pin_damper.tau"] - d * r["pin_damper.w_rel"])) < 1e-9


def test_joint_elements_may_not_clash_with_declared_ones(tmp_path):
    text = BAR_2D.format(extra="stiffness = 1.0") + """
[elements.pin_spring]
type = "rotational_damper"
bodies = ["ground", "bar"]
d = 1.0
"""
    with pytest.raises(SceneError, match=r"joints\.pin\.stiffness"):
        _load(tmp_path, "clash", text, dim=2)


def test_revolute_stiffness_in_3d_equals_declared_rotational_elements(tmp_path):
    joint = '[joints.R]\ntype = "revolute"\nbetween = ["O", "T"]\naxis = [1, 0, 0]\n'
    sugar = _run(_load(tmp_path, "sugar", _turned(_pendulum(joint + "stiffness = 30.0\ndamping = 0.4\n", ("a", 0.0)),
                                                   0.6, 0.0)))
    explicit = joint + """
[elements.s]
type = "rotational_spring"
bodies = ["ground", "rod"]
axis = [1, 0, 0]
k = 30.0

[elements.d]
type = "rotational_damper"
bodies = ["ground", "rod"]
axis = [1, 0, 0]
d = 0.4
"""
    plain = _run(_load(tmp_path, "explicit", _turned(_pendulum(explicit, ("a", 0.0)), 0.6, 0.0)))
    for name in ("Tip.r[1]", "Tip.r[2]", "Tip.r[3]"):
        assert np.max(np.abs(sugar[name] - plain[name])) < 1e-12, name
    assert np.max(np.abs(sugar["R_spring.tau"] - plain["s.tau"])) < 1e-9


def test_the_new_joints_run_on_the_oracle_too(tmp_path):
    """The model layer's joints (in the oracle's mechanism, with its element forces derived from
    L(q)) and the kernels' rows give the same run (1e-9 m, as the numpy path did before)."""
    model = _load(tmp_path, "cylindrical", CYLINDRICAL)
    fast, slow = _run(model), model.oracle().simulate(metrics=False)
    assert slow.status == "ok"
    assert np.max(np.abs(fast["P.r[1]"] - slow["P.r[1]"])) < 1e-9


def test_initial_velocities_are_moved_onto_the_joints_by_the_minimum_norm_correction():
    """As docs/scene_format.md says: the bodies' initial velocities are moved onto the joints'
    velocity constraints C_q v = 0 by v − C_qᵀ(C_q C_qᵀ)⁻¹C_q v (the explicit formula, the reference
    here), so a body's rate alone may be given (tests/data/parallelogram_2d.toml: its crank's
    ω = 3 rad/s), and velocities the joints allow (scenarios/hard/two_bar_free_2d.toml) are kept."""
    mech = inerter.load(ROOT / "tests" / "data" / "parallelogram_2d.toml").mechanism
    given = np.asarray(mech._bodies(mech.scene)[1], dtype=float)
    _, Cq, _ = mech.constraints(mech.q0, np.zeros(mech.n))
    assert np.max(np.abs(Cq @ given)) > 0.1                               # not allowed as given
    assert mech.v0 == pytest.approx(given - Cq.T @ np.linalg.solve(Cq @ Cq.T, Cq @ given), abs=1e-12)
    assert np.max(np.abs(Cq @ mech.v0)) < 1e-12
    free = inerter.load(ROOT / "scenarios" / "hard" / "two_bar_free_2d.toml").mechanism
    assert free.v0 == pytest.approx(np.asarray(free._bodies(free.scene)[1], dtype=float), abs=1e-14)
