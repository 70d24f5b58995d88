"""Stiffness and damping on prismatic joints (2D and 3D): a spring and a damper along the joint's
axis, on the signed slide s = ê·(r_b − r_a), ê fixed in the first point's body.

References: a mass on a prismatic joint with spring k and damper c, started at s = 0 with a speed
v0, is the damped oscillator m s̈ + c ṡ + k s = 0, s(t) = v0/ω_d e^(−ζω_n t) sin ω_d t (closed
form; the slide passes through 0, where a spring between the two points would lose its direction);
a slider on a spinning, swinging arm (the axis turns with the arm) against the oracle, which
differentiates s(q) = (A_a(q) n̄)·r(q) on Jets: accelerations at the initial state and at random
states near it (off the joints' manifold too, to 1e-12), and whole runs at rtol 1e-12.
"""
import math

import numpy as np
import pytest

import inerter
from inerter.common.errors import SceneError
from inerter.engine import compiled

K, C, MASS, V0 = 80.0, 1.2, 2.0, 1.0

OSCILLATOR = """
[scene]
name = "slider_{dim}d"
dimension = {dim}

[ground.points]
A0 = {origin}

[bodies.mass]
mass = {mass}
inertia = {inertia}
position = {origin}
velocity = {velocity}
points = {{ P = {origin} }}

[joints.slide]
type = "prismatic"
between = ["A0", "P"]
axis = {axis}
stiffness = {k}
damping = {c}

[experiment]
stop_time = 3.0
output_interval = 0.01
rtol = 1e-11
atol = 1e-13
"""


def _oscillator(tmp_path, dim):
    axis = [0.6, 0.8] if dim == 2 else [0.0, 0.6, 0.8]
    text = OSCILLATOR.format(dim=dim, origin=[0.0] * dim, mass=MASS, inertia=0.1 if dim == 2 else [0.1, 0.2, 0.3],
                             velocity=[V0 * a for a in axis], axis=axis, k=K, c=C)
    path = tmp_path / f"slider_{dim}d.toml"
    path.write_text(text)
    return inerter.load(path), np.array(axis)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_prismatic_stiffness_and_damping_make_the_damped_oscillator(tmp_path, dim, path):
    model, axis = _oscillator(tmp_path, dim)
    assert any(t.startswith("element slide_spring: spring, k = 80 along the prismatic joint's axis")
               for t in model.terms())                                         # inerter describe
    r = model.simulate(metrics=False, path=path)
    assert r.status == "ok", r.message
    wn, zeta = math.sqrt(K / MASS), C / (2.0 * math.sqrt(K * MASS))
    wd = wn * math.sqrt(1.0 - zeta ** 2)
    t = r.time
    s = V0 / wd * np.exp(-zeta * wn * t) * np.sin(wd * t)
    sdot = V0 * np.exp(-zeta * wn * t) * (np.cos(wd * t) - zeta * wn / wd * np.sin(wd * t))
    assert np.min(s) < -0.05 and np.max(s) > 0.05                       # through s = 0 both ways
    position = np.column_stack([r[f"P.r[{i + 1}]"] for i in range(dim)])
    assert np.max(np.abs(position - np.outer(s, axis))) < 1e-9
    assert np.max(np.abs(r["slide_spring.s_rel"] - s)) < 1e-9
    assert np.max(np.abs(r["slide_damper.v_rel"] - sdot)) < 1e-9
    assert np.max(np.abs(r["slide_spring.f"] - K * s)) < 1e-7               # tension positive: k (s − s0)
    assert np.max(np.abs(r["slide_damper.f"] - C * sdot)) < 1e-9
    energy = 0.5 * MASS * sdot ** 2 + 0.5 * K * s ** 2
    assert np.max(np.abs(r["energy"] - energy)) < 1e-8


ARM = """
[scene]
name = "arm_slider_{dim}d"
dimension = {dim}

[effects]
gravity = {gravity}

[ground.points]
O = {origin}

[bodies.arm]
mass = 3.0
inertia = {arm_inertia}
position = {arm_position}
angular_velocity = {spin}
points = {{ pivot = {pivot}, rail = {pivot} }}

[bodies.slider]
mass = 0.8
inertia = {slider_inertia}
position = {slider_position}
velocity = {slider_velocity}
angular_velocity = {spin}
points = {{ S = [0, 0{z}] }}

[joints.pin]
type = "revolute"
between = ["O", "pivot"]
{pin_axis}

[joints.slide]
type = "prismatic"
between = ["rail", "S"]
axis = [1, 0{z}]
stiffness = 40.0
damping = 0.7

[experiment]
stop_time = 2.0
output_interval = 0.01
rtol = 1e-12
atol = 1e-14
"""


def _arm(tmp_path, dim):
    """An arm pivoted at O (revolute: about Z in 3D) with a slider on it, started off its spring's
    free slide and both spinning: the axis the slider moves along turns with the arm."""
    z = ", 0" if dim == 3 else ""
    text = ARM.format(dim=dim, z=z, gravity="[0, -9.81]" if dim == 2 else "[0, -9.81, 0]",
                      origin=[0.0] * dim, arm_inertia=0.3 if dim == 2 else [0.01, 0.3, 0.3],
                      arm_position=[0.5, 0.0] + ([0.0] if dim == 3 else []),
                      spin=1.5 if dim == 2 else [0.0, 0.0, 1.5],
                      pivot=[-0.5, 0.0] + ([0.0] if dim == 3 else []),
                      slider_inertia=0.02 if dim == 2 else [0.02, 0.02, 0.02],
                      slider_position=[0.6, 0.0] + ([0.0] if dim == 3 else []),
                      slider_velocity=[0.4, 0.9] + ([0.0] if dim == 3 else []),
                      pin_axis="" if dim == 2 else "axis = [0, 0, 1]")
    path = tmp_path / f"arm_{dim}d.toml"
    path.write_text(text)
    return inerter.load(path)


@pytest.mark.parametrize("dim", [2, 3])
def test_slider_on_a_turning_arm_against_the_oracle(tmp_path, dim):
    model = _arm(tmp_path, dim)
    oracle = model.oracle()
    kernel = compiled.compile_mechanism(model.mechanism)
    assert kernel.compiled
    q0, v0 = model.mechanism.q0, model.mechanism.v0
    rng = np.random.default_rng(7)
    for k in range(4):
        q = q0 if k == 0 else q0 + 1e-3 * rng.standard_normal(len(q0))     # off the constraint manifold too
        v = v0 if k == 0 else v0 + 0.5 * rng.standard_normal(len(v0))
        fast = np.concatenate(kernel.accelerations(0.0, q, v, None, 10.0))
        ref = np.concatenate(oracle.mechanism.accelerations(0.0, q, v, None, 10.0))
        # to rounding at every state, on the constraint manifold and off it: the kernels' generalised
        # force −F gᵀ includes the axis's turn, g = Hᵀê + ∂ê/∂q·r, as the oracle's −F ∇s does (they
        # once differed off the manifold by F (∂ê/∂θ_a)·r, 0.02 to 0.08 times the residual here)
        assert k == 0 or model.mechanism.constraint_residual(q) > 1e-4       # off the manifold indeed
        assert np.max(np.abs(fast - ref)) <= 1e-12 * max(1.0, np.max(np.abs(ref))), k
    run = model.simulate(metrics=False)
    ref = oracle.simulate(metrics=False, rtol=1e-12, atol=1e-14)
    assert run.status == ref.status == "ok"
    assert np.max(np.abs(run["slide_spring.s_rel"] - run["slide_spring.s_rel"][0])) > 0.05     # it slides
    for name in ("S.r[1]", "S.r[2]", "slide_spring.s_rel", "slide_spring.f", "slide_damper.f", "energy"):
        scale = max(1.0, np.max(np.abs(ref[name])))
        assert np.max(np.abs(run[name] - ref[name])) < 1e-10 * scale, name       # measured ≤ 5e-12


def test_prismatic_stiffness_errors_are_one_line(tmp_path):
    model, _ = _oscillator(tmp_path, 2)
    text = (tmp_path / "slider_2d.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(f"stiffness = {K}", "stiffness = -1.0"))
    with pytest.raises(SceneError, match=r"joints\.slide\.stiffness.*out of range"):
        inerter.load(bad)
    bad.write_text("[parameters]\nk = { value = 80, unit = \"N.m/rad\" }\n"
                   + text.replace(f"stiffness = {K}", 'stiffness = "k"'))
    with pytest.raises(SceneError, match=r"joints\.slide\.stiffness.*N/m"):
        inerter.load(bad)
    bad.write_text(text + '\n[elements.slide_damper]\ntype = "damper"\nbetween = ["A0", "P"]\nc = 1.0\n')
    with pytest.raises(SceneError, match=r"joints\.slide\.damping.*name clash"):
        inerter.load(bad)
