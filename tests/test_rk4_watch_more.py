"""More cases for RK4's stability watch (kernels.rk4_watch), from an independent check of its final
form: runs that are fine and must not be refused, a numpy-path failure that escaped as a traceback,
and cases the watch misses or misnames, marked xfail(strict=True) so that a change of the rule that
fixes one shows up as an unexpected pass (then drop the mark).

References: closed forms where the scene is linear (the eigenvalues of a chain of masses on sliders,
M⁻¹K by numpy.linalg.eigvals; a pendulum's λ = √(m g l/2 / J_A)), RK4's factor
R(z) = 1 + z + z²/2 + z³/6 + z⁴/24 on them, and DOP853 at rtol 1e-10 (compiled) for the accuracy.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import inerter
from conftest import ROOT

PATHS = ("numpy", "compiled")
TWO_BAR_3D = ROOT / "scenarios" / "two_bar_2d_as_3d.toml"


def amplification(z: complex) -> float:
    """|R(z)|: RK4's factor per step on a mode of h·λ = z."""
    return abs(1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24)


def line_scene(path, masses, springs, d0, force=None):
    """Masses on sliders along X, each tied to the previous one (the first to the ground point O) by
    a spring of free length 1 m; the mass i displaced by d0[i] from x = i + 1; `force`: (mass,
    amplitude N, frequency Hz) of a sine force along X."""
    lines = ["[scene]", 'name = "line"', 'description = "masses in a line"', "", "[ground.points]", "O = [0, 0]"]
    for i, (m, k) in enumerate(zip(masses, springs)):
        before = "O" if i == 0 else f"P{i - 1}"
        lines += ["", f"[bodies.m{i}]", f"mass = {m!r}", "inertia = 0", f"position = [{i + 1 + d0[i]!r}, 0]",
                  f"points = {{ P{i} = [0, 0] }}", "", f"[joints.s{i}]", 'type = "prismatic"',
                  f'between = ["O", "P{i}"]', "axis = [1, 0]", "", f"[elements.k{i}]", 'type = "spring"',
                  f'between = ["{before}", "P{i}"]', f"k = {k!r}", "length = 1.0"]
    if force:
        j, amplitude, frequency = force
        lines += ["", "[forces.F]", f'point = "P{j}"', "direction = [1, 0]", 'function = "sine"',
                  f"amplitude = {amplitude!r}", f"frequency = {frequency!r}"]
    lines += ["", "[experiment]", "stop_time = 1.0", "output_interval = 0.01", 'method = "DOP853"']
    path.write_text("\n".join(lines) + "\n")
    return path


def line_omegas(masses, springs) -> np.ndarray:
    """The chain's natural frequencies: √ of the eigenvalues of M⁻¹K."""
    n = len(masses)
    K = np.zeros((n, n))
    for i, k in enumerate(springs):
        K[i, i] += k
        if i > 0:
            K[i - 1, i - 1] += k
            K[i - 1, i] -= k
            K[i, i - 1] -= k
    return np.sqrt(np.sort(np.linalg.eigvals(np.diag(1.0 / np.asarray(masses)) @ K).real))


@pytest.mark.parametrize("path", PATHS)
def test_a_run_that_overflows_the_geometry_fails_in_one_line(path):
    """two_bar_2d_as_3d at a 0.1341 s step: its fastest mode, ω = 25.4 rad/s, puts h·λ = 3.41i
    outside RK4's region (|R| = 3.2 a step), the state overflows within 8 steps and the compiled path
    stops with "accelerations are not finite". The numpy path used to raise a ValueError from the
    rotational elements' winding (math.ceil of NaN) out of simulate(), a traceback; now it fails the
    same way, within a step of the compiled path."""
    assert amplification(0.1341j * 25.41) > 3.0
    model = inerter.load(TWO_BAR_3D)
    r = model.simulate(method="RK4", step=0.1341, stop_time=3.0, path=path, metrics=False)
    assert r.status == "failed" and "accelerations are not finite" in r.message, r.message
    assert 1.07 - 1e-9 <= r.time[-1] <= 1.07 + 0.1341
