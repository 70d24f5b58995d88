"""The laws of a point's kinematics, a point force and a rotational element's angle
(inerter.elements.kinematics, inerter.elements.twist), run uncompiled as the numpy model runs them,
against references that do not use them:

* ṙ = dr/dt and, at v̇ = 0, acc = d²r/dt² by central differences along the exact motion
  (2D: q(t) = q + t v; 3D: R(t) = R + t Ṙ, A(t) = A exp(t ω̄̃) with constant body-frame ω̄), δt = 1e-4
  (error O(δt²) ≈ 1e-8, round-off ≈ 1e-12 / δt² ≈ 1e-4 × |r| for the second difference: tolerance
  1e-7 on ṙ, 1e-5 on acc);
* Hᵀ F against the virtual work F·(r(q + εδ) − r(q − εδ))/(2ε) of a finite displacement δ
  (ε = 1e-6, tolerance 1e-8);
* the PD magnitude and the gyroscopic term against their closed forms (numpy dot and cross, 1e-14);
* a body's energy T + V against T = ½ m |Ṙ|² + ½ J θ̇² (2D) or ½ m |Ṙ|² + ½ ω̄ᵀJω̄ (3D) and
  V = −m g·R written out by hand for a body with round numbers (exact in binary: 1e-14), and
  against ½ vᵀ diag(m I, J) v − m g·R at a random state (numpy, 1e-12);
* the twist's gradient g against a central difference of φ under a small global rotation of body b
  (ε = 1e-6, tolerance 1e-8), and φ̇ = g·(ω_b − ω_a) by its definition.
"""
from __future__ import annotations

import numpy as np
import pytest

from inerter.common.rotations import axis_angle_matrix
from inerter.elements import kinematics, twist

planar_point = kinematics.planar_point.py_func
spatial_point = kinematics.spatial_point.py_func
planar_point_force = kinematics.planar_point_force.py_func
spatial_point_force = kinematics.spatial_point_force.py_func
spatial_turn_row = kinematics.spatial_turn_row.py_func
pd_magnitude = kinematics.pd_magnitude.py_func
gyroscopic = kinematics.gyroscopic.py_func
planar_body_energy = kinematics.planar_body_energy.py_func
spatial_body_energy = kinematics.spatial_body_energy.py_func
spatial_twist = twist.spatial_twist.py_func

DT = 1e-4
RNG = np.random.default_rng(3)


def _turn(v):
    """exp(ṽ): the rotation by |v| about v (the identity for v = 0)."""
    angle = float(np.linalg.norm(v))
    return np.eye(3) if angle == 0.0 else axis_angle_matrix(v, angle)


def _nine(A):
    return tuple(np.asarray(A).ravel().tolist())


def _random_rotation():
    return _turn(RNG.normal(size=3))


@pytest.mark.parametrize("seed", range(5))
def test_planar_point_rates_are_the_derivatives_of_its_position(seed):
    rng = np.random.default_rng(seed)
    q, v, local = rng.normal(size=3), rng.normal(size=3), rng.normal(size=2)

    def at(t):
        x = q + t * v
        return np.array(planar_point(*x, *v, *local)[:2])

    out = planar_point(*q, *v, *local)
    r, rdot, acc = out[:2], out[2:4], out[6:8]
    c, s = np.cos(q[2]), np.sin(q[2])
    assert np.array(r) == pytest.approx(q[:2] + np.array(((c, -s), (s, c))) @ local, abs=1e-14)   # Eq. 15
    assert np.array(rdot) == pytest.approx((at(DT) - at(-DT)) / (2 * DT), abs=1e-7)
    assert np.array(acc) == pytest.approx((at(DT) - 2 * at(0.0) + at(-DT)) / DT**2, abs=1e-5)


@pytest.mark.parametrize("seed", range(5))
def test_spatial_point_rates_are_the_derivatives_of_its_position(seed):
    rng = np.random.default_rng(seed)
    A = _random_rotation()
    R, V, w, local = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)

    def at(t):
        return R + t * V + (A @ _turn(t * w)) @ local

    out = spatial_point(_nine(A), *R, *V, *w, *local)
    assert np.array(out[:3]) == pytest.approx(at(0.0), abs=1e-14)
    assert np.array(out[3:6]) == pytest.approx((at(DT) - at(-DT)) / (2 * DT), abs=1e-7)
    assert np.array(out[6:9]) == pytest.approx((at(DT) - 2 * at(0.0) + at(-DT)) / DT**2, abs=1e-5)


@pytest.mark.parametrize("seed", range(5))
def test_planar_point_force_is_the_virtual_work_of_its_force(seed):
    rng = np.random.default_rng(seed)
    q, local, F, delta = rng.normal(size=3), rng.normal(size=2), rng.normal(size=2), rng.normal(size=3)
    eps = 1e-6

    def r(x):
        return np.array(planar_point(*x, 0.0, 0.0, 0.0, *local)[:2])

    work = F @ (r(q + eps * delta) - r(q - eps * delta)) / (2 * eps)
    assert np.array(planar_point_force(q[2], *local, *F)) @ delta == pytest.approx(work, abs=1e-8)


@pytest.mark.parametrize("seed", range(5))
def test_spatial_point_force_is_the_virtual_work_of_its_force(seed):
    """δ = (δR, δφ̄): R + εδR, A exp(ε δφ̄̃) (a body-frame turn, as ω̄ is a body-frame rate)."""
    rng = np.random.default_rng(seed)
    A = _random_rotation()
    R, local, F, delta = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3), rng.normal(size=6)
    eps = 1e-6

    def r(s):
        return R + s * delta[:3] + (A @ _turn(s * delta[3:])) @ local

    work = F @ (r(eps) - r(-eps)) / (2 * eps)
    assert np.array(spatial_point_force(_nine(A), *local, *F)) @ delta == pytest.approx(work, abs=1e-8)


def test_spatial_turn_rows_are_hs_rotational_block():
    """Row i of H's ω̄-block is −A ũ's (the matrix form of ∂ṙ/∂ω̄ = A(· × ū), Eq. 22)."""
    A, local = _random_rotation(), RNG.normal(size=3)
    skew = np.array(((0.0, -local[2], local[1]), (local[2], 0.0, -local[0]), (-local[1], local[0], 0.0)))
    rows = np.array([spatial_turn_row(_nine(A), *local, *e) for e in np.eye(3)])
    assert rows == pytest.approx(-A @ skew, abs=1e-14)


def test_pd_magnitude_and_gyroscopic_term_are_their_closed_forms():
    d = RNG.normal(size=3)
    d /= np.linalg.norm(d)
    r, v = RNG.normal(size=3), RNG.normal(size=3)
    kp, kd, ref = 3.0, 0.5, 0.2
    assert pd_magnitude(*d, ref, kp, kd, *r, *v) == pytest.approx(-(kp * (d @ r - ref) + kd * (d @ v)), abs=1e-14)
    J = RNG.normal(size=(3, 3))
    J = J @ J.T
    w = RNG.normal(size=3)
    assert np.array(gyroscopic(_nine(J), 0, *w)) == pytest.approx(np.cross(w, J @ w), abs=1e-14)


def test_planar_body_energy_is_its_kinetic_energy_and_its_weights_potential():
    """m = 2 kg, J = 0.5 kg m², Ṙ = (3, −1) m/s, θ̇ = 4 rad/s, R = (1, 2) m, g = (0, −9.75) m/s²:
    T = ½·2·(9 + 1) + ½·0.5·16 = 14 J and V = −m g·R = −2·(−9.75)·2 = 39 J; without gravity V = 0."""
    m, J = 2.0, 0.5
    assert planar_body_energy(m, J, 3.0, -1.0, 4.0, 0.0, -m * 9.75, 1.0, 2.0) == pytest.approx(14.0 + 39.0, abs=1e-14)
    assert planar_body_energy(m, J, 3.0, -1.0, 4.0, 0.0, 0.0, 1.0, 2.0) == pytest.approx(14.0, abs=1e-14)


def test_spatial_body_energy_is_its_kinetic_energy_and_its_weights_potential():
    """m = 3 kg, J = [[2, 0.5, 0], [0.5, 1, 0], [0, 0, 4]] kg m² (in J[2:11] of a longer array, as
    the kernels store it), Ṙ = (1, 2, −2) m/s, ω̄ = (1, −2, 0.5) rad/s, R = (0.5, −1, 2) m,
    g = (0, 0, −9.75) m/s²: T = ½·3·9 + ½ ω̄ᵀJω̄ = 13.5 + ½(2 − 2 + 4 + 1) = 16 J (ω̄ᵀJω̄ = 2·1 +
    2·0.5·(1·−2) + 1·4 + 4·0.25 = 5) and V = −3·(−9.75)·2 = 58.5 J; then at a random state against
    ½ vᵀ diag(m I, J) v − m g·R (numpy)."""
    J = np.array(((2.0, 0.5, 0.0), (0.5, 1.0, 0.0), (0.0, 0.0, 4.0)))
    stored = np.concatenate(((7.0, 7.0), J.ravel()))
    weight = (0.0, 0.0, -3.0 * 9.75)
    E = spatial_body_energy(3.0, stored, 2, 1.0, 2.0, -2.0, 1.0, -2.0, 0.5, *weight, 0.5, -1.0, 2.0)
    assert E == pytest.approx(16.0 + 58.5, abs=1e-14)
    J = RNG.normal(size=(3, 3))
    J = J @ J.T
    m, v, R, g = 1.7, RNG.normal(size=6), RNG.normal(size=3), RNG.normal(size=3)
    M = np.diag((m, m, m, 0.0, 0.0, 0.0))
    M[3:, 3:] = J
    expected = 0.5 * v @ M @ v - m * g @ R
    assert spatial_body_energy(m, _nine(J), 0, *v, *(m * g), *R) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_twist_gradient_is_the_angles_derivative(seed):
    """dφ/dε of φ with A_b turned by exp(ε δ̃) in the global frame (A_b → exp(εδ̃) A_b) is g·δ,
    off the axis (the relative rotation swings by up to a radian); φ̇ = g·(A_b ω̄_b − A_a ω̄_a)."""
    rng = np.random.default_rng(seed)
    Aa, Ab, rel0 = _random_rotation(), _random_rotation(), _random_rotation()
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    wa, wb, delta = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    eps = 1e-6

    def phi(s):
        return spatial_twist(_nine(Aa), _nine(_turn(s * delta) @ Ab), _nine(rel0), 0, *n, 0.0, 0, 0, 0, 0, 0, 0)[0]

    angle, w, *g = spatial_twist(_nine(Aa), _nine(Ab), _nine(rel0), 0, *n, 0.0, *wa, *wb)
    assert np.array(g) @ delta == pytest.approx((phi(eps) - phi(-eps)) / (2 * eps), abs=1e-8)
    assert w == pytest.approx(np.array(g) @ (Ab @ wb - Aa @ wa), abs=1e-14)
