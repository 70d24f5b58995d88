"""The joint-row laws (inerter.elements.joint_rows), which the kernels compile in and the readable
joints run as written: each row's C_v and γ against finite differences of its C along a motion.

Reference: the definitions themselves. Along a motion at constant velocities (v̇ = 0: each body's
Ṙ and body-frame ω̄ held, A(t) = A exp(t ω̄~)), Ċ = C_v v and C̈ = −γ (Eq. 26). C is evaluated
on the exact motion and differentiated with five-point central differences (step 2e-3, where the
largest difference from the rows' rates over these states is 1e-8, the truncation and the
round-off of C̈'s stencil balanced); the rows' rates are held to 1e-7 absolute, on rows of order 1
to 10.
"""
import math

import numpy as np
import pytest

from inerter.elements.joint_rows import dot1_row, dot2_row, screw_row, screw_turn_2d, slider_rows_2d

H, TOL = 2e-3, 1e-7


def _skew(w):
    return np.array(((0.0, -w[2], w[1]), (w[2], 0.0, -w[0]), (-w[1], w[0], 0.0)))


def _rotation(axis_angle):
    """exp(φ~) (Rodrigues' formula)."""
    a = np.asarray(axis_angle, dtype=float)
    th = np.linalg.norm(a)
    K = _skew(a / th)
    return np.eye(3) + math.sin(th) * K + (1.0 - math.cos(th)) * K @ K


class Body:
    """A body moving at constant Ṙ and body-frame ω̄: R(t) = R + t Ṙ, A(t) = A exp(t ω̄~)."""

    def __init__(self, R, A, Rdot, w):
        self.R, self.A, self.Rdot, self.w = (np.asarray(x, dtype=float) for x in (R, A, Rdot, w))

    def at(self, t):
        return self.R + t * self.Rdot, self.A @ _rotation(t * self.w) if t else self.A

    def point(self, u):
        """(r, ṙ, acc) of a point ū: acc = A(ω̄ × (ω̄ × ū)), r̈ at v̇ = 0."""
        wu = np.cross(self.w, u)
        return self.R + self.A @ u, self.Rdot + self.A @ wu, self.A @ np.cross(self.w, wu)

    def a9(self, t=0.0):
        return tuple(self.at(t)[1].ravel())


def _derivatives(f):
    """(f'(0), f''(0)) by five-point central differences."""
    f2, f1, f0, g1, g2 = f(-2 * H), f(-H), f(0.0), f(H), f(2 * H)
    d1 = (f2 - 8 * f1 + 8 * g1 - g2) / (12 * H)
    d2 = (-f2 + 16 * f1 - 30 * f0 + 16 * g1 - g2) / (12 * H * H)
    return d1, d2


def _bodies(seed):
    rng = np.random.default_rng(seed)

    def make():
        return Body(rng.normal(size=3), _rotation(rng.normal(size=3)), rng.normal(size=3), rng.normal(size=3))
    return rng, make(), make()


def _relative(a, b, ua, ub, t):
    """r = r_b − r_a of points ū_a, ū_b at time t."""
    (Ra, Aa), (Rb, Ab) = a.at(t), b.at(t)
    return Rb + Ab @ ub - Ra - Aa @ ua


def _kinematics(a, b, ua, ub):
    ra, va, acc_a = a.point(ua)
    rb, vb, acc_b = b.point(ub)
    return rb - ra, vb - va, acc_b - acc_a


@pytest.mark.parametrize("seed", range(4))
def test_dot1_row_rates_are_the_derivatives_of_its_residual(seed):
    rng, a, b = _bodies(seed)
    sa, sb = rng.normal(size=3), rng.normal(size=3)

    def C(t):
        return dot1_row(a.a9(t), 0, 0, 0, *sa, b.a9(t), 0, 0, 0, *sb)[0]

    c, ax, ay, az, bx, by, bz, gamma = dot1_row(a.a9(), *a.w, *sa, b.a9(), *b.w, *sb)
    d1, d2 = _derivatives(C)
    assert c == pytest.approx(C(0.0), abs=1e-15)
    assert abs(np.dot((ax, ay, az), a.w) + np.dot((bx, by, bz), b.w) - d1) < TOL
    assert abs(-gamma - d2) < TOL


@pytest.mark.parametrize("seed", range(4))
def test_dot2_row_rates_are_the_derivatives_of_its_residual(seed):
    rng, a, b = _bodies(seed)
    sa, ua, ub = rng.normal(size=3), rng.normal(size=3), rng.normal(size=3)
    r, rdot, an = _kinematics(a, b, ua, ub)

    def C(t):
        return dot2_row(a.a9(t), 0, 0, 0, *sa, *_relative(a, b, ua, ub, t), 0, 0, 0, 0, 0, 0)[0]

    c, sx, sy, sz, ax, ay, az, gamma = dot2_row(a.a9(), *a.w, *sa, *r, *rdot, *an)
    d1, d2 = _derivatives(C)
    # Ċ = s·ṙ (the translational coefficient on H) + the turn's coefficient · ω̄_a
    assert abs(np.dot((sx, sy, sz), rdot) + np.dot((ax, ay, az), a.w) - d1) < TOL
    assert abs(-gamma - d2) < TOL


@pytest.mark.parametrize("seed", range(4))
def test_screw_row_rates_are_the_derivatives_of_its_residual(seed):
    """b turns about a's axis relative to a (the row's condition): its initial relative rotation and
    relative angular velocity are about the axis."""
    rng, a, _ = _bodies(seed)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    rel0 = _rotation(rng.normal(size=3))
    phi, lam, ratio = 0.4, 1.3, 2.0 * math.pi / 0.7
    M = _rotation(phi * n) @ rel0                                # A_aᵀA_b
    b = Body(rng.normal(size=3), a.A @ M, rng.normal(size=3), M.T @ (a.w + lam * n))
    ua, ub = rng.normal(size=3), rng.normal(size=3)
    r, rdot, an = _kinematics(a, b, ua, ub)
    x0 = float((a.A @ n) @ r) - 0.1                              # C is then φ − 0.1 ρ, away from ±π

    def C(t):
        return screw_row(a.a9(t), 0, 0, 0, b.a9(t), 0, 0, 0, *n, rel0.ravel(), ratio, x0,
                         *_relative(a, b, ua, ub, t), 0, 0, 0, 0, 0, 0)[0]

    c, tx, ty, tz, cx, cy, cz, nx, ny, nz, bx, by, bz, gamma = screw_row(
        a.a9(), *a.w, b.a9(), *b.w, *n, rel0.ravel(), ratio, x0, *r, *rdot, *an)
    assert c == pytest.approx(math.remainder(phi - 0.1 * ratio, 2 * math.pi), abs=1e-12)
    d1, d2 = _derivatives(C)
    rate = np.dot((tx, ty, tz), rdot) + np.dot((cx + nx, cy + ny, cz + nz), a.w) + np.dot((bx, by, bz), b.w)
    assert abs(rate - d1) < TOL
    assert abs(-gamma - d2) < TOL


def _planar(theta, u):
    c, s = math.cos(theta), math.sin(theta)
    return np.array((c * u[0] - s * u[1], s * u[0] + c * u[1]))


@pytest.mark.parametrize("seed", range(4))
def test_2d_slider_and_screw_rows_rates_are_the_derivatives_of_their_residuals(seed):
    """Bodies in the plane at constant (Ṙ, θ̇): the slider's rows and the 2D screw's first row."""
    rng = np.random.default_rng(100 + seed)
    Ra, Rb, Va, Vb, ua, ub, nbar = (rng.normal(size=2) for _ in range(7))
    tha, thb, wa, wb = rng.normal(size=4)
    phi0, ratio = 0.3, 2.0 * math.pi / 0.5

    def r_at(t):
        return Rb + t * Vb + _planar(thb + t * wb, ub) - Ra - t * Va - _planar(tha + t * wa, ua)

    r = r_at(0.0)
    def perp(x):
        return np.array((-x[1], x[0]))
    rdot = Vb + wb * perp(_planar(thb, ub)) - Va - wa * perp(_planar(tha, ua))
    an = -wb * wb * _planar(thb, ub) + wa * wa * _planar(tha, ua)

    def rows(t, rates=False):
        w = (wa, wb, r_at(0.0), rdot, an) if rates else (0.0, 0.0, r_at(t), (0.0, 0.0), (0.0, 0.0))
        c1, cd1, c2, nx, ny, turn, g2 = slider_rows_2d(True, tha + t * wa, thb + t * wb, w[0], w[1], phi0,
                                                       *nbar, *w[2], *w[3], *w[4])
        s1, tx, ty, tturn, g1 = screw_turn_2d(ratio, 0.2, c1, nx, ny, w[0], *w[2], *w[3], *w[4])
        return c1, cd1, c2, nx, ny, turn, g2, s1, tx, ty, tturn, g1

    c1, cd1, c2, nx, ny, turn, g2, s1, tx, ty, tturn, g1 = rows(0.0, rates=True)
    d1, _ = _derivatives(lambda t: rows(t)[0])
    assert abs(cd1 - d1) < TOL
    d1, d2 = _derivatives(lambda t: rows(t)[2])
    assert abs(nx * rdot[0] + ny * rdot[1] + turn * wa - d1) < TOL
    assert abs(-g2 - d2) < TOL
    d1, d2 = _derivatives(lambda t: rows(t)[7])
    assert abs(cd1 - ratio * (tx * rdot[0] + ty * rdot[1] + tturn * wa) - d1) < TOL
    assert abs(-g1 - d2) < TOL
