"""3D prismatic and fixed joints and ground motion, each against a closed form."""
from __future__ import annotations

import math

import numpy as np
import pytest

import inerter

SLIDER = """
[scene]
name = "slider_3d"
dimension = 3
[parameters]
g = 9.81
[effects]
gravity = [0, 0, "-g"]
[ground.points]
O = [0, 0, 0]
[bodies.block]
mass = 2.0
inertia = [0.1, 0.2, 0.3]
position = [0, 0, 0]
axis = [1, 1, 1]
angle = 0.4
points = { P = [0, 0, 0] }
[joints.slide]
type = "prismatic"
between = ["O", "P"]
axis = [0.6, 0, -0.8]
[experiment]
stop_time = 2.0
output_interval = 0.01
rtol = 1e-11
atol = 1e-13
"""

WELDED = """
[scene]
name = "welded_3d"
dimension = 3
[parameters]
w = 3.0
[ground.points]
O = [0, 0, 0]
[bodies.hub]
mass = 1.0
inertia = [0.5, 0.5, 0.5]
position = [0, 0, 0]
angular_velocity = [0, 0, "w"]
points = { H = [0, 0, 0], J = [1, 0, 0] }
[bodies.arm]
mass = 1.0
inertia = [0.1, 0.1, 0.1]
position = [1, 0, 0]
angular_velocity = [0, 0, "w"]
velocity = [0, "w", 0]
points = { J2 = [0, 0, 0], T = [0.5, 0, 0] }
[joints.pivot]
type = "revolute"
between = ["O", "H"]
axis = [0, 0, 1]
[joints.weld]
type = "fixed"
between = ["J", "J2"]
[experiment]
stop_time = 2.0
output_interval = 0.01
rtol = 1e-11
atol = 1e-13
"""

SHAKEN = """
[scene]
name = "shaken_3d"
dimension = 3
[parameters]
k = 400.0
m = 1.0
[effects]
ground_acceleration = { input = true }
[ground.points]
O = [0, 0, 0]
[bodies.mass]
mass = "m"
inertia = [0.01, 0.01, 0.01]
position = [1, 0, 0]
points = { P = [0, 0, 0] }
[joints.rail]
type = "prismatic"
between = ["O", "P"]
axis = [1, 0, 0]
[elements.spring]
type = "spring"
between = ["O", "P"]
k = "k"
[experiment]
stop_time = 1.0
output_interval = 0.01
rtol = 1e-11
atol = 1e-13
"""


def load(tmp_path, text, **overrides):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return inerter.load(path, **overrides)


def test_prismatic_slider_falls_along_its_axis(tmp_path):
    """Gravity's component along the axis (0.6, 0, −0.8): s(t) = ½ g·0.8 t², no rotation."""
    r = load(tmp_path, SLIDER).simulate(metrics=False)
    assert r.status == "ok", r.message
    s = 0.5 * 9.81 * 0.8 * r.time ** 2
    np.testing.assert_allclose(r["P.r[1]"], 0.6 * s, atol=1e-9)
    np.testing.assert_allclose(r["P.r[3]"], -0.8 * s, atol=1e-9)
    assert np.max(np.abs(r["P.r[2]"])) < 1e-9
    assert r.run.max_drift < 1e-9


def test_fixed_joint_makes_one_rigid_body(tmp_path):
    """A hub spinning about Z with an arm welded to it: the arm's tip turns at the same rate,
    T = 1.5 (cos wt, sin wt, 0)."""
    r = load(tmp_path, WELDED).simulate(metrics=False)
    assert r.status == "ok", r.message
    wt = 3.0 * r.time
    np.testing.assert_allclose(r["T.r[1]"], 1.5 * np.cos(wt), atol=1e-8)
    np.testing.assert_allclose(r["T.r[2]"], 1.5 * np.sin(wt), atol=1e-8)
    assert r.run.max_drift < 1e-9
    e = r["energy"]
    assert np.max(np.abs(e - e[0])) < 1e-9 * e[0]


def test_ground_acceleration_input(tmp_path):
    """A constant ground acceleration a along the rail shifts the spring's equilibrium by −m a/k
    (coordinates are relative to the ground): x(t) = 1 − (m a / k)(1 − cos ωt)."""
    model = load(tmp_path, SHAKEN)
    ground = [i for i in model.input_info() if i["name"].startswith("ground.a[")]
    assert [i["name"] for i in ground] == ["ground.a[1]", "ground.a[2]", "ground.a[3]"]
    assert all(i["unit"] == "m/s2" for i in ground)
    st = model.stepper()
    st.set_input("ground.a[1]", 2.0)
    w = math.sqrt(400.0)
    for k in range(1, 101):
        st.step(0.01 * k)
        x = st.outputs()["P.r[1]"]
        assert x == pytest.approx(1.0 - (2.0 / 400.0) * (1 - math.cos(w * 0.01 * k)), abs=1e-9)
