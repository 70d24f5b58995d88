"""A body with mass but no moment of inertia about an axis its joints leave free is refused when
the scene is loaded (Mechanism.check_free_spins), naming the file, the body, its inertia field and
value, the axis and the joints; a point mass whose rotation a joint holds still loads.

Reference: the kinetic energy of a rigid body turning at ω about an axis through its centre of
mass at rest is ½ ωᵀJω, zero where J a = 0: with such an axis free, the mass matrix restricted to
the joints' motions is singular. Where an inerter's terminal off the axis carries the spin at
t = 0 the check at t = 0 of M + M_I passed, and the run stopped later with the step size
collapsing (the 3D scene below: at t = 0.106 s on the numpy path, DOP853), naming no body.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import inerter
from conftest import SCENARIOS, TWO_BAR
from inerter.common.errors import SceneError

DOUBLE_PENDULUM = SCENARIOS / "double_pendulum_3d.toml"

WHEEL_2D = """
[scene]
name = "wheel"

[ground.points]
O = [0, 0]
G = [1.0, 0.5]

[bodies.wheel]
{body}
position = [0, 0]
angular_velocity = 2.0
points = {{ C = [0, 0], P = [0.3, 0] }}

[joints.axle]
type = "{joint}"
between = ["O", "C"]
{axis}

[elements.spring]
type = "spring"
between = ["G", "P"]
k = 100.0

[elements.inerter]
type = "inerter"
between = ["G", "P"]
b = 1.0

[experiment]
stop_time = 0.5
output_interval = 0.01
"""

ROD_3D = """
[scene]
name = "rod"
dimension = 3

[effects]
gravity = [0, 0, -9.81]

[ground.points]
O = [0, 0, 0]

[bodies.rod]
mass = 1.0
inertia = {inertia}
position = [{position}]
points = {{ top = [{top}] }}

[joints.pivot]
type = "{joint}"
between = ["O", "top"]
{axis}

[experiment]
stop_time = 0.5
output_interval = 0.01
"""


def _rod(inertia, top="0, 0, 0.5", joint="spherical", axis=""):
    """ROD_3D hanging from O by its point `top` (its centre at −top: the body frame is the world's)."""
    position = ", ".join(str(-float(x) + 0.0) for x in top.split(","))
    return ROD_3D.format(inertia=inertia, top=top, position=position, joint=joint, axis=axis)


def _load(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path, inerter.load(path)


def _refused(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(SceneError) as info:
        inerter.load(path)
    return path, info.value


def test_a_rod_with_no_axial_moment_on_a_spherical_joint_is_refused_naming_it(tmp_path):
    """The double pendulum's rod 2 with J_z = 0 and the inerter's terminal E 5 cm off its axis:
    it loaded (the inerter carried the spin at t = 0) and the run stopped at t = 0.106 s."""
    text = DOUBLE_PENDULUM.read_text().replace('"m2*l^2/12", 1e-3]', '"m2*l^2/12", 0]')
    text = text.replace('E = [0, 0, "-0.5*l"]', 'E = [0.05, 0, "-0.5*l"]')
    path, err = _refused(tmp_path, text)
    message = str(err)
    assert err.field == "bodies.rod2.inertia" and err.value == [1 / 12, 1 / 12, 0.0]
    assert message.startswith(f"{path}: bodies.rod2.inertia: body 'rod2' turns freely with no inertia: "
                              "moment 0 kg.m2 about its axis [0, 0, 1], which its joints (elbow: spherical) "
                              "leave free"), message
    assert "massless = true" in err.expected and "\n" not in message


@pytest.mark.parametrize("inertia, top, axis", [
    ("[0.0833, 0.0833, 0.0]", "0, 0, 0.5", "[0, 0, 1]"),
    # a tiny negative moment passes the reader's positive semi-definite test (1e-12 of max(1, |J|))
    ("[0.0833, 0.0833, -1e-14]", "0, 0, 0.5", "[0, 0, 1]"),
    # the zero moment about an axis that is no body axis: J = 0.1 (I − a aᵀ), a = (1, 1, 0)/√2
    ("[[0.05, -0.05, 0], [-0.05, 0.05, 0], [0, 0, 0.1]]", "0.353553390593274, 0.353553390593274, 0",
     "[0.707107, 0.707107, 0]"),
])
def test_a_zero_or_negative_moment_about_a_free_axis_is_refused_in_3d(tmp_path, inertia, top, axis):
    text = _rod(inertia, top)
    path, err = _refused(tmp_path, text)
    assert err.field == "bodies.rod.inertia" and str(path) in str(err)
    assert f"about its axis {axis}, which its joints (pivot: spherical) leave free" in str(err), str(err)


def test_a_free_body_with_no_inertia_is_refused(tmp_path):
    text = _rod("[0, 0, 0]")
    text = text.replace('[joints.pivot]\ntype = "spherical"\nbetween = ["O", "top"]\n', "")
    _, err = _refused(tmp_path, text)
    assert err.field == "bodies.rod.inertia" and "and no joint holds it" in str(err), str(err)


def test_a_2d_body_with_no_inertia_on_a_revolute_joint_at_its_centre_is_refused(tmp_path):
    """Its spin is carried by the inerter at t = 0 (G-P is not radial), so the check of M + M_I
    at t = 0 passed; the spin's mass vanishes where P passes the line OG."""
    path, err = _refused(tmp_path, WHEEL_2D.format(body="mass = 1.0\ninertia = 0.0", joint="revolute", axis=""))
    assert str(err).startswith(f"{path}: bodies.wheel.inertia: body 'wheel' turns freely with no inertia: "
                               "moment 0 kg.m2, which its joints (axle: revolute) leave free (got 0.0;"), str(err)


def test_a_point_mass_whose_rotation_a_joint_holds_still_loads(tmp_path):
    _, wheel = _load(tmp_path, WHEEL_2D.format(body="mass = 1.0\ninertia = 0.0", joint="prismatic",
                                               axis="axis = [1, 0]"))
    assert wheel.mechanism.M0[2, 2] == 0.0
    for joint, inertia, axis in (("prismatic", "[0, 0, 0]", 'axis = [0, 0, 1]'),
                                 ("revolute", "[0, 0, 0.1]", 'axis = [0, 0, 1]'),     # holds x and y
                                 ("fixed", "[0, 0, 0]", "")):
        _, rod = _load(tmp_path, _rod(inertia, joint=joint, axis=axis))
        assert rod.simulate(metrics=False, path="numpy").status == "ok"


def test_a_zero_inertia_whose_spin_moves_the_centre_of_mass_still_loads(tmp_path):
    """The two-bar's bar 2 with J2 = 0: pinned at its end, its turn moves its centre of mass
    (kinetic energy ½ m (l/2)² θ̇²); a spherical joint off the rod's axis, likewise."""
    assert inerter.load(TWO_BAR, J2=0.0).mechanism.M0[5, 5] == 0.0
    _load(tmp_path, _rod("[0.0833, 0.0833, 0.0]", top="0.1, 0, 0.5"))


def test_massless_true_leaves_the_spin_to_the_inerters(tmp_path):
    """The opt-in of a body carried by inerters (docs/scene_format.md, massless): the wheel's spin
    is the inerter's, the check of M + M_I at t = 0 applies."""
    _, wheel = _load(tmp_path, WHEEL_2D.format(body="massless = true\nmass = 1.0\ninertia = 0.0",
                                               joint="revolute", axis=""))
    assert wheel.scene.bodies["wheel"].massless
    assert math.isclose(wheel.mechanism.M0[0, 0], 1.0)
    assert np.linalg.matrix_rank(wheel.mechanism.M0) == 2
