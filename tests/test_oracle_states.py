"""The oracle's inerter device with internal states (inerter.oracle.series): its free series
oscillator against the closed form of the 2-DOF system, its energy balance with the dissipated
energy as a state, backlash's unilateral contact against the definition, and the refusals it keeps
(its screw efficiency: tests/test_oracle_efficiency.py).

References: the closed form `two_dof` (tests/test_device_states.py: the modes of the linear 2-DOF
system), the initial energy, and the device's definitions written out in each test.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.engine.simulation import integrate
from test_device import _load
from test_device_states import two_dof

ROOT = Path(__file__).resolve().parents[1]
SERIES = ROOT / "scenarios" / "series_inerter_2d.toml"
BACKLASH = ROOT / "scenarios" / "hard" / "backlash_device_2d.toml"


def _oracle_run(model, **settings):
    oracle = model.oracle()
    run = integrate(oracle.mechanism, model.settings(method="DOP853", **settings), None)
    assert run.status == "ok", run.message
    return oracle.mechanism, run


def test_the_oracles_series_oscillator_has_the_two_dof_closed_form():
    """Closed form (two_dof: 0.869 and 4.120 Hz): the oracle's own run of the shipped series scene
    (its extended system in (x, s), DOP853 at the scene's rtol 1e-10, atol 1e-12) follows x(t) to
    1e-9 m over 5 s (the tolerance the engine is held to in test_device_states), s = x − y starts
    at 0 and the element's force is k_c s."""
    model = inerter.load(SERIES)
    mech, run = _oracle_run(model, rtol=1e-10, atol=1e-12)
    x_ref, f_closed, _ = two_dof(1.0, 100.0, 2.0, 400.0, 0.1, run.time)
    np.testing.assert_allclose(f_closed, [0.8695, 4.1201], atol=1e-4)
    x = run.states[:, 0]                                                 # P.r[1]: the body's x
    assert np.max(np.abs(x - x_ref)) <= 1e-9, np.max(np.abs(x - x_ref))
    signals = model.oracle().signals
    names = signals.names
    nv = mech.nq + mech.n
    y = run.states[len(run.time) // 3]
    out = signals.evaluate(run.time[len(run.time) // 3], y[:mech.nq], y[mech.nq:nv], z=y[nv:])
    s = out[names.index("inerter.s_series")]
    assert run.states[0, nv] == 0.0 and abs(s) > 1e-3
    assert out[names.index("inerter.f")] == pytest.approx(400.0 * s, rel=1e-14)


def test_the_oracles_energy_and_dissipated_energy_sum_to_the_initial_energy(tmp_path):
    """Reference: the initial energy ½ k x0² = 0.5 J. With series damping c_c = 5 N·s/m and the
    dissipated energy as a state (ż = p_loss = c_c ṡ²), the oracle's energy (½ m ẋ² + ½ k x² +
    ½ b u̇² + ½ k_c s²) + e_loss stays 0.5 J to 1e-9 relative over 3 s (DOP853 at rtol 1e-10),
    while e_loss grows past 0.1 J."""
    text = SERIES.read_text(encoding="utf-8") + "\n[elements.inerter.device.dissipated_energy]\n"
    model = _load(tmp_path, text, name="series_loss.toml", cc=5.0)
    mech, run = _oracle_run(model, rtol=1e-10, atol=1e-12, stop_time=3.0)
    nq, nv = mech.nq, mech.nq + mech.n
    total = np.array([mech.energy(y[:nq], y[nq:nv], y[nv:]) + y[-1] for y in run.states])
    assert np.max(np.abs(total - 0.5)) <= 1e-9 * 0.5, np.max(np.abs(total - 0.5))
    assert run.states[-1, -1] > 0.1


def test_backlash_contact_is_unilateral_as_defined():
    """The definition (inerter.elements.device, "Backlash"): inside the gap |s| < Δ/2 no force;
    engaged, F = k_c d + c_c ṡ with d = s ∓ Δ/2, but 0 where that would pull the sides apart
    (F·d < 0), the spring's energy ½ k_c d² then lost at the rate −k_c d ṡ; else the damping
    dissipates c_c ṡ². Written out with the scene's k_c = 1e4 N/m, c_c = 20 N·s/m, Δ = 2 mm."""
    mech = inerter.load(BACKLASH).oracle().mechanism
    series = next(e for e in mech.elements if e.name == "inerter").series
    kc, cc, half = 1e4, 20.0, 1e-3
    assert series.force(0.5e-3, 3.0)[:2] == (0.0, 0.0)                  # in the gap
    F, engaged, _ = series.force(1.5e-3, 0.01)                           # pushing: k_c d + c_c ṡ
    assert engaged == 1.0 and F == pytest.approx(kc * (1.5e-3 - half) + cc * 0.01, rel=1e-15)
    assert series.loss(1.5e-3, 0.01) == pytest.approx(cc * 0.01 ** 2, rel=1e-12)
    assert series.force(1.5e-3, -1.0)[:2] == (0.0, 1.0)                 # it would pull: released
    assert series.loss(1.5e-3, -1.0) == pytest.approx(kc * (1.5e-3 - half) * 1.0, rel=1e-12)
    F, _, _ = series.force(-1.2e-3, -0.002)
    assert F == pytest.approx(kc * (-1.2e-3 + half) + cc * -0.002, rel=1e-15)


def test_what_the_oracle_does_not_derive_is_refused_by_name():
    """A mount beside a compliance or beside a screw efficiency (the mount's gyroscopic terms spin
    the flywheel with L̇ and b; the series connection turns it with u̇, the efficiency scales b to
    b_eff): the scene reader refuses both (check_device, for the engine too), and the oracle's device,
    built from such a device directly, refuses each by a one-line error naming the field."""
    from inerter.oracle.derivation import OracleDevice
    from test_device import _device
    fly, mount = dict(inertia=1e-4, lead=0.01), dict(axis=(0.0, 0.0, 1.0))
    for extra, field in ((dict(compliance=dict(stiffness=1e4)), "mount"),
                         (dict(efficiency=dict(forward=0.9, backward=0.8)), "efficiency")):
        with pytest.raises(inerter.SceneError) as err:
            OracleDevice(_device(flywheel=fly, mount=mount, **extra), "scene.toml", "dev")
        assert str(err.value).startswith(f"scene.toml: elements.dev.device.{field}: "), str(err.value)
        assert "\n" not in str(err.value)


@pytest.mark.parametrize("scene", ["device_combo_efficiency_series_3d", "device_combo_efficiency_pair_3d"])
def test_the_oracles_refusal_names_the_file_and_the_field(scene, capsys, tmp_path):
    """The oracle takes a screw efficiency now (inerter.oracle.efficiency); what it still refuses of
    such a scene, a 3D scene in Z-X-Z Euler angles (its Jets are written on quaternions), is refused as
    every scene error: the file, the field, the value and what was expected (through the API and
    `inerter run --model oracle`, which exits with status 2 and that line)."""
    from inerter.cli import main
    from conftest import one_line_error
    path = ROOT / "tests" / "data" / f"{scene}.toml"
    with pytest.raises(inerter.SceneError) as err:
        inerter.load(path, **{"scene.orientation": "euler_zxz"}).oracle()
    message = str(err.value)
    assert message.startswith(f"{path}: scene.orientation: ")
    assert "expected orientation = \"quaternion\" for the oracle" in message
    assert main(["run", str(path), "--model", "oracle", "--set", "scene.orientation=euler_zxz",
                 "--out", str(tmp_path)]) == 2
    one_line_error(capsys, f"{scene}.toml: scene.orientation: ", "(got 'euler_zxz'")
