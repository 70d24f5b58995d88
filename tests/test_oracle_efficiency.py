"""The oracle's screw efficiency (inerter.oracle.efficiency): the oracle alone against the closed
forms of tests/test_device_efficiency.py (the 1-DOF mass on a spring with such an inerter, 2D and
3D, the exact switch; in series with a spring, against the explicit ODE), its energy balance with
the efficiency's loss, its resolution of the modes by trying every assignment, the engine against
it where the scenes of tests/test_engine_vs_oracle.py leave a combination out (2D rigid with v_s > 0,
2D series and 3D rigid with the exact switch), and what it still refuses.

References: the closed form `efficiency_closed_form`, the explicit ODE `series_reference` (both
tests/test_device_efficiency.py), the initial energy, and the definition written out in a test.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from inerter.common.errors import SceneError, SimulationError
from inerter.oracle import efficiency as oracle_efficiency
from inerter.oracle.derivation import OracleDevice
from test_device import _device
from test_device_efficiency import (B, ETA_B, ETA_F, K, PEAK_SPEED, SERIES_VS, X0, _oscillator, _series, _x,
                                    assert_follows_the_exact_switch, series_reference)


def _oracle_run(model, stop_time):
    r = model.oracle().simulate(stop_time=stop_time, metrics=False)
    assert r.status == "ok", r.message
    return r


# ------------------------------------------------------------------------------------------------
# The oracle alone against the closed forms
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("dim", [2, 3])
def test_the_oracle_follows_the_closed_form_of_the_exact_switch(tmp_path, dim):
    """Closed form (efficiency_closed_form): m = 1 kg, b = 1 kg, k = 100 N/m, x0 = 0.25 m, η_f = 0.8,
    η_b = 0.6, v_s = 0. The oracle's own run (DOP853 at the scene's rtol 1e-10, 1 s: two
    turnarounds) gives x(t) to 1e-7 x0 (the bound the engine is held to there), in 2D and 3D along
    u = (1, 2, 2)/3; its E.mode is 1 while |x| falls and 0 while it grows (wherever |ẋ| > 1e-6 m/s),
    and its E.p_loss is the closed form's (b_eff − b) ẍ ẋ with ẍ = −k x/(m + b_eff) at the run's own
    (x, ẋ), to 1e-12 · ½ k x0² (round-off)."""
    r = _oracle_run(_oscillator(tmp_path, dim), 1.0)
    assert_follows_the_exact_switch(r, dim)


@pytest.mark.parametrize("vs", [0.0, 1e-2 * PEAK_SPEED], ids=["switch", "vs"])
def test_the_oracles_energy_plus_the_efficiency_loss_is_the_initial_energy(tmp_path, vs):
    """Reference: the initial energy ½ k x0². With dissipated_energy declared, the oracle's energy
    (½ m ẋ² + ½ b ẋ² + ½ k x²) + E.e_loss stays ½ k x0² to 1e-9 relative over 1 s (DOP853, rtol
    1e-10), the exact switch and v_s = 1e-2 of the peak speed, while the energy falls by more than
    a tenth; E.p_loss ≥ 0 (to 1e-12 of ½ k x0²)."""
    r = _oracle_run(_oscillator(tmp_path, loss=True, vs=vs if vs else None), 1.0)
    E0 = 0.5 * K * X0 ** 2
    assert np.max(np.abs(r["energy"] + r["inerter.e_loss"] - E0)) <= 1e-9 * E0
    assert r["energy"][-1] < 0.9 * E0
    assert np.min(r["inerter.p_loss"]) >= -1e-12 * E0


@pytest.mark.parametrize("dim, vs", [(2, 0.0), (2, SERIES_VS), (3, SERIES_VS)], ids=["2d-switch", "2d-vs", "3d-vs"])
def test_in_series_the_oracle_follows_the_explicit_ode(tmp_path, dim, vs):
    """Reference: the explicit ODE (series_reference) of [x, ẋ, u, u̇], m = 1 kg, k = 100 N/m, b = 1 kg,
    k_c = 400 N/m, c_c = 2 N.s/m, η_f = 0.8, η_b = 0.6, from x0 = 0.25 m at 0.5 m/s, over 1 s (at
    least two turnarounds of u̇). The oracle (its extended system in (x, s), the modes σ = sign(ü)
    by trying both, DOP853 at rtol 1e-12) gives x and s = x − u to 1e-8 m (the bound the engine is
    held to there), and its E.p_loss less c_c ṡ² is the ODE's b λ ü u̇ to 1e-6 W."""
    model = _series(tmp_path, dim, vs=vs)
    r = _oracle_run(model, 1.0)
    Y, screw = series_reference(r.time, vs=vs)
    assert np.max(np.abs(_x(r, dim) - Y[:, 0])) <= 1e-8
    assert np.max(np.abs(r["inerter.s_series"] - (Y[:, 0] - Y[:, 2]))) <= 1e-8
    assert int(np.sum(np.diff(np.sign(Y[:, 3])) != 0)) >= 2
    damper = 2.0 * (Y[:, 1] - Y[:, 3]) ** 2
    assert np.max(np.abs(r["inerter.p_loss"] - damper - screw)) <= 1e-6
    if vs == 0.0:
        assert set(np.unique(r["inerter.mode"])) == {0.0, 1.0}


# ------------------------------------------------------------------------------------------------
# The resolution of the modes
# ------------------------------------------------------------------------------------------------
def test_the_law_is_the_definition():
    """The definition (inerter.elements.device, "Efficiency") written out: λ(1) = α = 1/η_f − 1 and
    λ(−1) = −β = η_b − 1 (b/η_f driven, b η_b back-driving, to 1e-15), τ = σ sgn(ẋ) with +1 at
    ẋ = 0 for v_s = 0, σ tanh(ẋ/v_s) for v_s > 0 (b_eff = b at rest), and the loss b λ ẍ ẋ ≥ 0
    wherever σ = sign(ẍ)."""
    exact = oracle_efficiency.ScrewEfficiency(dict(forward=ETA_F, backward=ETA_B, velocity_scale=None))
    smooth = oracle_efficiency.ScrewEfficiency(dict(forward=ETA_F, backward=ETA_B, velocity_scale=1e-3))
    assert 1.0 + exact.excess(1.0) == pytest.approx(1.0 / ETA_F, rel=1e-15)
    assert 1.0 + exact.excess(-1.0) == pytest.approx(ETA_B, rel=1e-15)
    assert exact.direction(-1.0, 0.0) == 1.0 and exact.direction(-1.0, 0.2) == -1.0
    assert exact.direction(-1.0, -0.2) == 1.0 and exact.direction(1.0, -0.2) == -1.0
    assert smooth.factor(-1.0, 0.0) == 1.0
    assert smooth.direction(1.0, 2e-3) == pytest.approx(math.tanh(2.0), rel=1e-15)
    for law in (exact, smooth):
        for rate in (-0.3, -1e-3, 0.0, 2e-4, 0.5):
            for accel in (-2.0, 3.0):
                assert law.loss(B, math.copysign(1.0, accel), rate, accel) >= 0.0


class _Screw:
    mode = None


def test_the_modes_are_the_one_assignment_that_agrees():
    """resolve (inerter.oracle.efficiency) on a made-up system of two screws whose solved ẍ are given
    per assignment: it keeps the assignment whose signs agree, leaves its modes set; a tie (ẍ = 0)
    takes σ = +1; no agreeing assignment, or two with different solutions, is an error naming the
    elements (the oracle's own check: neither happens for b_eff > 0, the module's proof)."""
    screws = [_Screw(), _Screw()]

    def system(table):
        def solve():
            x = table[tuple(s.mode for s in screws)]
            return (np.array(x, dtype=float),), [(xi, 1.0) for xi in x]
        return solve
    agree = {(1.0, 1.0): (2.0, -1.0), (1.0, -1.0): (1.5, -0.5), (-1.0, 1.0): (-1.0, -2.0), (-1.0, -1.0): (1.0, 1.0)}
    assert resolve_modes(screws, system(agree)) == ((1.5, -0.5), (1.0, -1.0))
    tie = {(1.0, 1.0): (0.0, -1.0), (1.0, -1.0): (0.0, -1.0), (-1.0, 1.0): (0.0, -1.0), (-1.0, -1.0): (0.0, -1.0)}
    assert resolve_modes(screws, system(tie)) == ((0.0, -1.0), (1.0, -1.0))
    none = {m: (-m[0], 1.0) for m in agree}
    with pytest.raises(SimulationError, match="no modes .* of a, b"):
        resolve_modes(screws, system(none))
    two = {(1.0, 1.0): (1.0, 1.0), (1.0, -1.0): (1.0, -2.0), (-1.0, 1.0): (1.0, 2.0), (-1.0, -1.0): (2.0, 2.0)}
    with pytest.raises(SimulationError, match="two sets of modes .* of a, b"):
        resolve_modes(screws, system(two))


def resolve_modes(screws, solve):
    solution = oracle_efficiency.resolve(screws, solve, ["a", "b"], 0.0)
    return tuple(float(x) for x in solution[0]), tuple(s.mode for s in screws)


@pytest.mark.parametrize("dim, series, vs", [(2, False, 1e-2 * PEAK_SPEED), (2, True, 0.0), (3, False, 0.0)],
                         ids=["2d-rigid-vs", "2d-series-switch", "3d-rigid-switch"])
def test_the_engine_equals_the_oracle_where_the_scenes_leave_a_combination_out(tmp_path, dim, series, vs):
    """The engine (compiled kernels, flip-and-resolve; in series its explicit σ = sign(F − F_d))
    against the oracle (every assignment tried) on the 1-DOF scenes, in 2D rigid with v_s = 1e-2 of
    the peak speed and in series with the exact switch, in 3D rigid with the exact switch: q̈, ż and
    every output (E.mode, E.p_loss with the screw's loss) at 40 states, positions (in 3D quaternions,
    off unit length) and velocities random about the initial ones and the series states random (mm,
    m/s), to 1e-12 relative to 1 + |value| (test_engine_vs_oracle's TOL_ACC and TOL_OUT; E.mode over
    its slope 1/(2 v_s) there)."""
    from inerter.engine import compiled
    model = _series(tmp_path, vs=vs) if series else _oscillator(tmp_path, dim, vs=vs or None, loss=True)
    oracle = model.oracle()
    kernel = compiled.compile_mechanism(model.mechanism)
    assert kernel.compiled
    order = kernel.signal_order(model.signals)
    scale = np.ones(len(model.signals.names))
    if vs:
        scale[model.signals.names.index("inerter.mode")] = 0.5 / vs
    mech, omech = model.mechanism, oracle.mechanism
    rng = np.random.default_rng(11)
    modes = set()
    for _ in range(40):
        q = mech.q0 + 0.1 * rng.standard_normal(mech.nq)
        v = mech.v0 + (rng.standard_normal(mech.n) if series else 0.03 * rng.standard_normal(mech.n))
        z = np.zeros(len(mech.z0))
        if series:
            z[:2] = (1e-3 * rng.standard_normal(), rng.standard_normal())
        a, lam = kernel.accelerations(0.3, q, v, None, 0.0, z=z)
        b, _ = omech.accelerations(0.3, q, v, None, 0.0, z=z)
        assert np.max(np.abs(a - b)) <= 1e-12 * (1.0 + np.max(np.abs(b)))
        dy = kernel.derivative(None, 0.0)(0.3, np.concatenate((q, v, z)))[mech.nq + mech.n:]
        dz = omech.state_rates(q, v, z, b)
        assert np.max(np.abs(dy - dz)) <= 1e-12 * (1.0 + np.max(np.abs(dz)))
        out = kernel.signal_values(model.signals, order, 0.3, q, v, None, 0.0, z=z) / scale
        ref = oracle.signals.evaluate(0.3, q, v, None, 0.0, z=z) / scale
        assert np.max(np.abs(out - ref) / (1.0 + np.abs(ref))) <= 1e-12
        k = model.signals.names.index("inerter.mode")
        modes.add(float(ref[k] * scale[k]) > 0.5)
    assert modes == {True, False}


# ------------------------------------------------------------------------------------------------
# What stays refused
# ------------------------------------------------------------------------------------------------
def test_a_mount_beside_an_efficiency_stays_refused():
    """A mount beside a screw efficiency (its gyroscopic terms spin the flywheel with b, not b_eff):
    the scene reader refuses it (check_device, for the engine too: test_device_efficiency), and the
    oracle's device, built from such a device directly, refuses it by a one-line error naming
    elements.NAME.device.efficiency and the mount."""
    device = _device(flywheel=dict(inertia=1e-4, lead=0.01), mount=dict(axis=(0.0, 0.0, 1.0)),
                     efficiency=dict(forward=0.9, backward=0.8))
    with pytest.raises(SceneError, match="mount") as err:
        OracleDevice(device, "scene.toml", "dev")
    assert str(err.value).startswith("scene.toml: elements.dev.device.efficiency: ")
    assert "\n" not in str(err.value)
