"""A translational element's terminal geometry (inerter.elements.terminals), compiled and uncompiled,
against closed forms: L = |r| and ê = r/|r|; the stroke ê₀·r along a fixed ê₀; the slide (A n̄)·r
along an axis fixed in body a; the terminals meeting below MIN_LENGTH; and the turning axis' terms,
c̄ = ∂L/∂φ̄_a against n̄ × A_aᵀ r (written independently here with numpy), and the corrected ṙ
against a central difference of L(t) = (A_a(t) n̄)·r(t) along a motion.

Tolerances: 1e-14 relative for the closed forms (a few roundings apart); 1e-8 for the central
difference (step 1e-5, error O(h²) of a smooth L(t)).
"""
import math

import numpy as np
import pytest

from inerter.common.inlined import compiled_copy
from inerter.common.errors import MIN_LENGTH
from inerter.common.rotations import axis_angle_matrix, planar_matrix9
from inerter.elements import layout, terminals


def _versions(name):
    law = getattr(terminals, name)
    return [compiled_copy(law), law.py_func]


def _row(fixed=None, slider=None):
    row = np.zeros(layout.ELEMENT_REAL_COLUMNS)
    if fixed is not None:
        row[layout.FIXED_DIRECTION] = 1.0
        row[layout.DIRECTION:layout.DIRECTION + 3] = fixed
    if slider is not None:
        row[layout.SLIDER] = 1.0
        row[layout.DIRECTION:layout.DIRECTION + 3] = slider
    return row


R = np.array([0.3, -1.2, 0.7])
A3 = axis_angle_matrix(np.array([1.0, 2.0, -0.5]) / math.sqrt(5.25), 0.9)
N = np.array([0.0, 0.6, 0.8])


@pytest.mark.parametrize("version", [0, 1])
def test_line_along_r_and_the_terminals_meeting(version):
    acting_line = _versions("acting_line")[version]
    row = _row()
    L, ex, ey, ez, meets = acting_line(row, terminals.IDENTITY, *R, float(np.linalg.norm(R)))
    assert not meets
    assert L == pytest.approx(np.linalg.norm(R), rel=1e-14)
    assert np.allclose((ex, ey, ez), R / np.linalg.norm(R), rtol=1e-14, atol=0)
    tiny = R * 1e-12
    L, ex, ey, ez, meets = acting_line(row, terminals.IDENTITY, *tiny, float(np.linalg.norm(tiny)))
    assert meets and L == MIN_LENGTH                     # held there: nothing divides by zero


@pytest.mark.parametrize("version", [0, 1])
def test_fixed_direction_reads_the_stroke(version):
    acting_line, reported = _versions("acting_line")[version], _versions("reported_distance")[version]
    e0 = np.array([0.6, 0.0, 0.8])
    row = _row(fixed=e0)
    distance = float(np.linalg.norm(R))
    L, ex, ey, ez, meets = acting_line(row, A3.ravel(), *R, distance)      # A is not read
    assert not meets and (ex, ey, ez) == tuple(e0)
    assert L == pytest.approx(e0 @ R, rel=1e-14)
    assert reported(row, L, distance) == distance                       # s_rel stays |r|
    assert reported(_row(), distance, distance) == distance


@pytest.mark.parametrize("version", [0, 1])
def test_slider_axis_turns_with_body_a(version):
    acting_line, turns = _versions("acting_line")[version], _versions("turns_with_a")[version]
    row = _row(slider=N)
    assert turns(row) and not turns(_row()) and not turns(_row(fixed=N))
    L, ex, ey, ez, meets = acting_line(row, tuple(A3.ravel()), *R, 0.0)   # the slide is defined at |r| = 0
    assert not meets
    assert np.allclose((ex, ey, ez), A3 @ N, rtol=1e-14, atol=1e-15)
    assert L == pytest.approx((A3 @ N) @ R, rel=1e-14)


@pytest.mark.parametrize("version", [0, 1])
def test_turning_axis_3d(version):
    turning_axis = _versions("turning_axis")[version]
    e = A3 @ N
    w = np.array([0.4, -1.1, 2.0])              # body-frame angular velocity of a
    rd = np.array([0.2, 0.5, -0.3])
    cx, cy, cz, *rd_new = turning_axis(tuple(A3.ravel()), *e, *R, *w, *rd)
    c = np.cross(N, A3.T @ R)                   # ∂L/∂φ̄ of L = (A n̄)·r under δA = A[δφ̄]×
    assert np.allclose((cx, cy, cz), c, rtol=1e-14, atol=1e-15)
    # L̇ = ê·ṙ_new against a central difference of L(t) = (A(t) n̄)·r(t), Ȧ = A[ω̄]×
    h = 1e-5

    def L(t):
        At = A3 @ axis_angle_matrix(w / np.linalg.norm(w), np.linalg.norm(w) * t)
        return (At @ N) @ (R + rd * t)
    assert e @ np.array(rd_new) == pytest.approx((L(h) - L(-h)) / (2 * h), rel=1e-8)


@pytest.mark.parametrize("version", [0, 1])
def test_turning_axis_2d(version):
    acting_line, turning_axis = _versions("acting_line")[version], _versions("turning_axis")[version]
    theta, thetadot = 0.7, -1.3
    n2, r2, rd2 = np.array([0.6, 0.8, 0.0]), np.array([1.5, -0.4, 0.0]), np.array([0.3, 0.9, 0.0])
    A = compiled_copy(planar_matrix9)(theta) if version == 0 else planar_matrix9.py_func(theta)
    L, ex, ey, ez, _ = acting_line(_row(slider=n2), A, *r2, 0.0)
    cx, cy, cz, *rd_new = turning_axis(A, ex, ey, ez, *r2, 0.0, 0.0, thetadot, *rd2)
    # closed form: ∂L/∂θ = (A_θ n̄)·r, A_θ n̄ the axis turned by +90°
    assert (cx, cy) == (0.0, 0.0)
    assert cz == pytest.approx(-ey * r2[0] + ex * r2[1], rel=1e-14)
    h = 1e-5

    def L_of(t):
        c, s = math.cos(theta + thetadot * t), math.sin(theta + thetadot * t)
        return (c * n2[0] - s * n2[1]) * (r2[0] + rd2[0] * t) + (s * n2[0] + c * n2[1]) * (r2[1] + rd2[1] * t)
    assert ex * rd_new[0] + ey * rd_new[1] == pytest.approx((L_of(h) - L_of(-h)) / (2 * h), rel=1e-8)
    assert rd_new[2] == 0.0
