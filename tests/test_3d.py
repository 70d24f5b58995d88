"""3D mechanisms (paper Secs. 2.2–2.3, 3.2, App. B): the two-bar as a 3D scene, the coordinate
forms of Eqs. (10) and (11), energy and drift, gimbal lock, and the 3D scenes through their FMUs."""
from __future__ import annotations

import math

import numpy as np
import pytest

import inerter
from conftest import SCENARIOS, TWO_BAR
from inerter.common.errors import SceneError
from inerter.oracle.jets import Jet

AS_3D = SCENARIOS / "two_bar_2d_as_3d.toml"
SPHERICAL = SCENARIOS / "spherical_pendulum_3d.toml"
DOUBLE = SCENARIOS / "double_pendulum_3d.toml"
GIMBAL = SCENARIOS / "gimbal_lock_3d.toml"
FRAME = SCENARIOS / "braced_frame_3d.toml"
SCENES_3D = [AS_3D, SPHERICAL, DOUBLE, GIMBAL, FRAME]
TIGHT = dict(rtol=1e-11, atol=1e-13)


@pytest.mark.parametrize("centripetal", [True, False], ids=["corrected", "uncorrected"])
def test_two_bar_as_3d_follows_the_2d_scene(runs, centripetal):
    """Spatial bodies with revolute joints along Z reproduce the planar model: every point
    position agrees to 1e-9 m over 10 s at tight tolerance (the issue asks for 1e-6 m on the
    figures; the trajectories themselves agree three orders tighter)."""
    r2 = runs(TWO_BAR, centripetal, stop_time=10.0, **TIGHT, metrics=False)
    r3 = runs(AS_3D, centripetal, stop_time=10.0, **TIGHT, metrics=False)
    assert r3.status == "ok", r3.message
    for name in (n for n in r2.names if ".r[" in n):
        assert np.max(np.abs(r3[name] - r2[name])) <= 1e-9, name
    assert np.max(np.abs(r3["C.r[3]"])) <= 1e-12
    assert r3.run.max_drift < 1e-9


@pytest.mark.parametrize("centripetal", [True, False], ids=["corrected", "uncorrected"])
def test_two_bar_as_3d_gives_the_2d_figures(runs, centripetal):
    """The paper's Fig. 12 figures from the 3D scene equal the 2D scene's to 1e-6 m (60 s)."""
    r2 = runs(TWO_BAR, centripetal, rtol=1e-8, atol=1e-10)
    r3 = runs(AS_3D, centripetal, rtol=1e-8, atol=1e-10)
    for key in ("C_y_peak_to_peak", "C_y_mean_offset"):
        assert abs(r3.metrics[key] - r2.metrics[key]) <= 1e-6, key


# -- Eqs. (10) and (11) against the general implementation ------------------------------------
def _free_point_model(b, centripetal=True):
    """The spherical pendulum's bob: a free body carrying point P, an inerter from O to P."""
    return inerter.Model(SPHERICAL, {"b": b, "effects.centripetal": centripetal})


def _inerter_force(model, r, rdot, rddot):
    """The general model's inerter force with the bob (point P at its centre of mass) at r, ṙ, r̈."""
    mech = model.mechanism
    q = mech.q0.copy()
    v = np.zeros(mech.n)
    a = np.zeros(mech.n)
    q[0:3], v[0:3], a[0:3] = r, rdot, rddot
    v[3:6] = [0.3, -0.7, 1.1]          # the bob's own spin is irrelevant to a point at its centre
    inert = next(e for e in mech.elements if e.kind == "inerter")
    return inert.outputs(q, v, a)[2]


def test_eq10_cartesian_form_agrees_with_the_general_model():
    rng = np.random.default_rng(10)
    b = 3.7
    model = _free_point_model(b)
    for _ in range(50):
        (x, y, z), (xd, yd, zd), (xdd, ydd, zdd) = rng.normal(size=(3, 3))
        rho2 = x * x + y * y + z * z
        dot = xd * x + yd * y + zd * z
        eq10 = b / math.sqrt(rho2) * ((xdd * x + ydd * y + zdd * z) + (xd * xd + yd * yd + zd * zd) - dot * dot / rho2)
        general = _inerter_force(model, (x, y, z), (xd, yd, zd), (xdd, ydd, zdd))
        assert general == pytest.approx(eq10, rel=1e-12, abs=1e-12 * b)


def test_eq11_spherical_form_is_b_rho_ddot():
    """Eq. (11): in spherical coordinates F = b ρ̈. Random smooth motions ρ(t), θ(t), φ(t),
    differentiated exactly (Jets), against the general model with and without the correction
    (without it the force is b(ρ̈ − |ṙ⊥|²/ρ))."""
    rng = np.random.default_rng(11)
    b = 2.5
    corrected, uncorrected = _free_point_model(b, True), _free_point_model(b, False)
    for _ in range(30):
        rho, th, ph = (Jet(v, d1, d2, np.zeros(1)) for v, d1, d2 in
                       zip((1.0 + rng.random(), 0.3 + 2.5 * rng.random(), 6 * rng.random()),
                           rng.normal(size=3), rng.normal(size=3)))
        from inerter.oracle.jets import jcos, jsin
        pos = [rho * jsin(th) * jcos(ph), rho * jsin(th) * jsin(ph), rho * jcos(th)]
        r = [p.v for p in pos]
        rd = [p.d1 for p in pos]
        rdd = [p.d2 for p in pos]     # second derivative along the motion (ρ̈, θ̈, φ̈ seeded in d2)
        F = _inerter_force(corrected, r, rd, rdd)
        assert F == pytest.approx(b * rho.d2, rel=1e-11, abs=1e-11)
        perp2 = sum(x * x for x in rd) - (sum(a * c for a, c in zip(rd, r)) / rho.v) ** 2
        F_unc = _inerter_force(uncorrected, r, rd, rdd)
        assert F_unc == pytest.approx(b * (rho.d2 - perp2 / rho.v), rel=1e-11, abs=1e-11)


# -- conservation, drift and the conical motion ----------------------------------------------
@pytest.fixture(scope="module")
def long_runs():
    """Undamped, unforced 3D scenes, 100 s at oracle tolerance (rtol 1e-12)."""
    out = {}
    out["spherical"] = inerter.load(SPHERICAL).simulate(stop_time=100.0, rtol=1e-12, atol=1e-14,
                                                         output_interval=0.05, metrics=False)
    out["double"] = inerter.load(DOUBLE, c=0.0).simulate(stop_time=100.0, rtol=1e-12, atol=1e-14,
                                                          output_interval=0.05, metrics=False)
    return out


@pytest.mark.parametrize("name", ["spherical", "double"])
def test_undamped_3d_scenes_conserve_energy_and_constraints(long_runs, name):
    r = long_runs[name]
    assert r.status == "ok", r.message
    e = r["energy"]
    assert np.max(np.abs(e - e[0])) / abs(e[0]) < 1e-8
    assert r.run.max_drift < 1e-9


def test_conical_motion_needs_the_correction(runs):
    """Sec. 2.1 in 3D: steady conical motion keeps L constant, so F = b L̈ = 0 and the motion
    stays conical; the uncorrected force −b|ṙ⊥|²/L is not zero and the rod length changes."""
    cor = runs(SPHERICAL, True)
    unc = runs(SPHERICAL, False)
    assert np.max(np.abs(cor["inerter.f"])) < 1e-6
    assert np.max(np.abs(cor["spring.s_rel"] - 1.0)) < 1e-9
    # At t = 0 without the correction, F = b a_r with a_r = r̈·r̂ from the bob's radial balance
    # m a_r = −T + m g cos α − F, T = m g / cos α: a_r = −m g sin²α / (cos α (m + b)).
    m, b, alpha, g = 1.0, 2.0, math.pi / 6, 9.81
    expected = -b * m * g * math.sin(alpha) ** 2 / (math.cos(alpha) * (m + b))
    assert unc["inerter.f"][0] == pytest.approx(expected, rel=1e-9)
    assert np.max(np.abs(unc["spring.s_rel"] - 1.0)) > 1e-3


# -- gimbal lock ---------------------------------------------------------------------------------
def test_gimbal_lock_quaternion_passes_euler_fails_clearly():
    r = inerter.load(GIMBAL).simulate()
    assert r.status == "ok"
    a = 0.5 - 2.0 * r.time                                     # closed form: steady spin about X
    assert np.max(np.abs(r["P.r[2]"] - np.cos(a))) < 1e-8
    assert np.max(np.abs(r["P.r[3]"] - np.sin(a))) < 1e-8
    euler = inerter.load(GIMBAL, **{"scene.orientation": "euler_zxz"}).simulate()
    assert euler.status == "failed"
    assert "spinner" in euler.message and "singularity" in euler.message and "t = " in euler.message
    assert 0.0 < euler.time[-1] < 0.25                          # results kept up to the last good step
    assert np.all(np.isfinite(euler["P.r[2]"]))
    assert np.max(np.abs(euler["P.r[2]"] - np.cos(0.5 - 2.0 * euler.time))) < 1e-8


def test_orientation_override_is_validated():
    with pytest.raises(SceneError, match="orientation"):
        inerter.load(GIMBAL, **{"scene.orientation": "euler_xyz"})
    with pytest.raises(SceneError, match="orientation"):
        inerter.load(TWO_BAR, **{"scene.orientation": "quaternion"})


# -- the braced frame ------------------------------------------------------------------------
def test_braced_frame_responds_to_both_components():
    r = inerter.load(FRAME).simulate(stop_time=3.0)
    assert r.status == "ok", r.message
    assert r.metrics["drift_x_peak"] > 1e-3 and r.metrics["drift_y_peak"] > 1e-3
    assert "ground motion" in "\n".join(inerter.load(FRAME).terms())


# -- FMUs of the 3D scenes against the oracle --------------------------------------------------
@pytest.mark.parametrize("scene", SCENES_3D, ids=[p.stem for p in SCENES_3D])
def test_3d_fmu_against_oracle(fmu_runs, runs, scene):
    """At the scene's default communication step and settings, the FMU's point positions
    (including P.r[3]) are within 1e-6 m of the oracle (rtol 1e-11) over 2 s; 1 s for the braced
    frame, whose piecewise-linear ground record makes the tight-tolerance oracle end a step at
    every 10 ms sample (the bound is the same, the window shorter to keep the suite fast)."""
    stop = 1.0 if scene == FRAME else 2.0
    fmu = fmu_runs(scene, stop_time=stop, metrics=False)
    ref = runs(scene, True, oracle=True, stop_time=stop, **TIGHT, metrics=False)
    assert fmu.status == "ok", fmu.message
    names = [n for n in fmu.names if ".r[" in n]
    assert any(n.endswith("[3]") for n in names)
    worst = max(np.max(np.abs(fmu[n] - ref[n])) for n in names)
    assert worst <= 1e-6
