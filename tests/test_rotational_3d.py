"""A 3D rotational spring or damper whose bodies swing off its axis (inerter.model.evaluators
``SpatialRotationalElement``, the kernels' ``_rotational3``; docs/scene_format.md).

Its angle φ is the twist about the axis n̄ (fixed in body a) of the relative rotation since t = 0
(the swing-twist decomposition), its torque acts along φ's gradient, its rate is φ̇. References:

* the decomposition's closed forms: a rotation by θ about n̄ is a twist of θ; a rotation about an
  axis normal to n̄ is a swing, of twist 0; a swing after a twist keeps the twist;
* the definition of the rate: w_rel = dφ/dt, against a central difference of φ along the motion
  q(t) (q̇ = B(q) v) at random states off the axis;
* the energy balance: on tests/data/twisted_pair_3d.toml (two rods on spherical joints, springs
  about a vertical and a tilted axis), without the damper the energy (kinetic, gravity, the springs'
  ½k(φ − φ0)²) is conserved, and with it the energy lost equals ∫ d φ̇² dt of the damper.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.model.spatial import axis_angle_matrix, quat_from_matrix

PAIR = Path(__file__).parent / "data" / "twisted_pair_3d.toml"
#: The tilted axis of torsion2 (rod1 → rod2), in rod1's frame.
TILTED = np.array([0.36, 0.48, 0.8])


def _pair_element(model, name):
    return next(e for e in model.mechanism.elements if e.name == name)


def _turned(model, rotation):
    """The pair's initial pose with rod2 turned by `rotation` (a matrix in rod1's frame, which is
    the initial relative rotation's frame) relative to rod1, velocities zero."""
    mech = model.mechanism
    q = mech.q0.copy()
    k1, k2 = mech.q_index
    A1 = mech.orientation.matrix(q[k1 + 3:k1 + 7])
    A2 = mech.orientation.matrix(q[k2 + 3:k2 + 7])
    q[k2 + 3:k2 + 7] = quat_from_matrix(A1 @ rotation @ A1.T @ A2)
    return q, np.zeros(mech.n)


@pytest.mark.parametrize("theta", [0.3, -2.0, 3.0])
def test_the_angle_is_the_twist_about_the_axis(theta):
    """φ = θ for a turn θ about n̄, 0 for a swing about an axis normal to n̄, θ for that swing
    after the turn (to 1e-12 rad)."""
    model = inerter.load(PAIR)
    e = _pair_element(model, "torsion2")
    n = TILTED / np.linalg.norm(TILTED)
    normal = np.cross(n, [1.0, 0.0, 0.0])
    normal /= np.linalg.norm(normal)
    twist = axis_angle_matrix(n * theta, abs(theta))
    swing = axis_angle_matrix(normal * 1.1, 1.1)
    for rotation, expected in ((twist, theta), (swing, 0.0), (swing @ twist, theta)):
        q, v = _turned(model, rotation)
        assert e.geometry(q, v)[0] == pytest.approx(expected, abs=1e-12)


def test_the_rate_is_the_angles_derivative_off_the_axis():
    """w_rel = dφ/dt along q̇ = B(q) v at random states where rod2 swings off the tilted axis:
    against a central difference with δt = 1e-6 s (error O(δt²) ≈ 1e-11, round-off 1e-10)."""
    model = inerter.load(PAIR)
    mech = model.mechanism
    e = _pair_element(model, "torsion2")
    rng = np.random.default_rng(7)
    dt = 1e-6
    for _ in range(20):
        q, _ = _turned(model, _random_rotation(rng))
        v = rng.normal(size=mech.n)
        qdot = mech.qdot(q, v)
        phi_plus = e.geometry(q + dt * qdot, v)[0]
        phi_minus = e.geometry(q - dt * qdot, v)[0]
        assert e.geometry(q, v)[1] == pytest.approx((phi_plus - phi_minus) / (2 * dt), abs=1e-8)


def _random_rotation(rng):
    axis = rng.normal(size=3)
    angle = rng.uniform(0.2, 2.0)
    return axis_angle_matrix(axis / np.linalg.norm(axis) * angle, angle)


@pytest.fixture(scope="module", params=["compiled", "numpy"])
def swinging(request):
    """The pair over 2 s at rtol 1e-10 without the damper and with it (sampled every 0.5 ms: the
    damper's time scale J/d on rod2's axial inertia is 5 ms), on each path."""
    free = inerter.load(PAIR, d2=0.0).simulate(metrics=False, path=request.param)
    damped = inerter.load(PAIR).simulate(metrics=False, path=request.param, output_interval=5e-4)
    assert free.status == "ok" and damped.status == "ok"
    return request.param, free, damped


def test_without_the_damper_the_energy_is_conserved(swinging):
    """|E(t) − E(0)| ≤ 1e-8 of the energy's scale (the gravity's and springs' terms, 8 J): the
    springs' torques are the gradient of their energy, though the rods swing off both axes (the
    relative rotations' twist quaternions' w² + x² go down to 0.62). rtol 1e-10 over 200 steps."""
    path, free, _ = swinging
    e = free["energy"]
    assert np.max(np.abs(e - e[0])) <= 1e-8 * 8.0


def test_the_damper_dissipates_what_its_rate_says(swinging):
    """E(0) − E(T) = ∫ d φ̇² dt over the damper's rate w_rel (its power, −τ φ̇ with τ = d φ̇), the
    integral by Simpson's rule over the 0.5 ms samples (error (h/5 ms)⁴/180 ≈ 1e-6 of it), to 1e-5."""
    path, _, damped = swinging
    d = inerter.load(PAIR).scene.parameters["d2"].value
    w = damped["twist_damper.w_rel"]
    t = damped.time
    h = t[1] - t[0]
    n = len(t) - 1 if (len(t) - 1) % 2 == 0 else len(t) - 2
    loss = d * h / 3.0 * (w[0] ** 2 + 4 * np.sum(w[1:n:2] ** 2) + 2 * np.sum(w[2:n - 1:2] ** 2) + w[n] ** 2)
    e = damped["energy"]
    assert loss > 1e-3
    assert e[0] - e[n] == pytest.approx(loss, rel=1e-5)
