"""Inerter devices on cases at the edge of their range: a Hooke mount at its singularity, devices
on very heavy bodies held by joints, and scenes that combine effects.

References, each named in its test:

* the geometry of the mount (inerter.elements.device_inertia, "The mount"): it is singular where
  the device's axis lies along the Hooke joint's first axis a₁;
* closed forms: a storey of mass m on a joint, a spring k and a fluid inerter b along its one
  freedom, x(t) = x₀ cos(ωt) with ω = √(k/(m + b)) (the inerter adds b to the mass; Smith 2002);
* the energy: with no applied force, the energy plus the device's dissipated energy (its state
  e_loss) stays at the initial energy.
"""
from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.common.errors import SceneError

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
PEND_COMPACT = DATA / "device_pendulum_3d_compact.toml"


# ------------------------------------------------------------------------------------------------
# The Hooke mount's singularity
# ------------------------------------------------------------------------------------------------
def test_a_mount_along_the_initial_axis_is_a_one_line_scene_error(tmp_path):
    """Geometry: at alpha = π/2 the pendulum's rod lies along +X, the mount's first axis a₁ = X, so
    the housing's spin (a division by |a₁ × u|) is undefined at t = 0: the scene is refused, naming
    the mount's axis, through the API and through `inerter describe` (exit status 2, one line)."""
    with pytest.raises(SceneError) as err:
        inerter.load(PEND_COMPACT, alpha="pi/2")
    text = str(err.value)
    assert "elements.device.device.mount.axis" in text and "along the device's axis at t = 0" in text
    assert str(PEND_COMPACT.name) in text
    proc = subprocess.run([sys.executable, "-m", "inerter.cli", "describe", str(PEND_COMPACT), "--set",
                           "alpha=pi/2"], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2
    lines = [line for line in proc.stderr.splitlines() if not line.startswith("inerter: compiling")
             and not line.startswith("inerter: ...")]
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith("inerter: error: ") and "mount.axis" in lines[0]


@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_a_run_through_the_mount_singularity_names_the_mount(path):
    """Geometry: the pendulum starts 0.3 rad above the horizontal +X, the mount's first axis, at rest,
    so it swings down through it (u ∥ a₁ in the XZ plane): the run stops there, and its message
    names the device and the mount's singularity (not only a singular mass matrix)."""
    model = inerter.load(PEND_COMPACT, alpha="pi/2 + 0.3", F=0.0)
    r = model.simulate(stop_time=1.0, path=path, metrics=False)
    assert r.status == "failed"
    assert "device mount near its singularity" in r.message and "device (its axis" in r.message, r.message
    # it stopped where the rod passes the horizontal: |u_z| small (the rod from O to P)
    uz = r["P.r[3]"][-1] / math.hypot(r["P.r[1]"][-1], r["P.r[3]"][-1])
    assert abs(uz) < 0.1, uz


# ------------------------------------------------------------------------------------------------
# Heavy bodies on joints
# ------------------------------------------------------------------------------------------------
STOREY = """
[scene]
name = "heavy_storey"
dimension = DIM

[parameters]
m = { value = 1.0e6, unit = "kg", description = "the storey's mass" }
k = { value = 4.0e7, unit = "N/m", description = "the storey's lateral stiffness" }
x0 = { value = 0.05, unit = "m", description = "initial drift" }

[ground.points]
O = ZERO

[bodies.floor]
mass = "m"
inertia = INERTIA
position = POSITION
points = { P = ZERO }

[joints.slide]
type = "prismatic"
between = ["O", "P"]
axis = XAXIS

[elements.spring]
type = "spring"
between = ["O", "P"]
k = "k"
length = 5.0

[elements.brace]
type = "inerter"
between = ["O", "P"]

[elements.brace.device.fluid]      # b = ρ ℓ A_p²/A_c = 1000 · 50 · 0.15² / 1e-3 = 1.125e6 kg
density = 1000.0
channel_length = 50.0
channel_area = 1.0e-3
piston_area = 0.15

[experiment]
stop_time = 3.0
output_interval = 0.01
rtol = 1e-11
atol = 1e-13
"""


@pytest.mark.parametrize("dim", [2, 3])
def test_a_heavy_storey_on_a_joint_loads_and_follows_the_closed_form(tmp_path, dim):
    """Closed form: a 1e6 kg storey on a prismatic joint, k = 4e7 N/m and a fluid inerter of
    b = 1.125e6 kg along it: x(t) = x₀ cos(ωt), ω = √(k/(m + b)), to 1e-9 of x₀. Its mass matrix with
    the joint's rows has singular values from ~1e7 to ~1e-7 (‖M‖ and ‖C‖²/‖M‖), which the check at
    t = 0 took for a singular matrix before it was scaled."""
    text = STOREY.replace("DIM", str(dim))
    if dim == 2:
        text = (text.replace("ZERO", "[0, 0]").replace("INERTIA", "1.0e7").replace("XAXIS", "[1, 0]")
                .replace("POSITION", '["x0", 0]').replace("O = [0, 0]", "O = [-5, 0]", 1))
    else:
        text = (text.replace("ZERO", "[0, 0, 0]").replace("INERTIA", "[1.0e7, 1.0e7, 1.0e7]")
                .replace("XAXIS", "[1, 0, 0]").replace("POSITION", '["x0", 0, 0]')
                .replace("O = [0, 0, 0]", "O = [-5, 0, 0]", 1))
    path = tmp_path / "storey.toml"
    path.write_text(text, encoding="utf-8")
    r = inerter.load(path).simulate(metrics=False)
    assert r.status == "ok", r.message
    b = 1000.0 * 50.0 * 0.15 ** 2 / 1.0e-3
    w = math.sqrt(4.0e7 / (1.0e6 + b))
    x = r["P.r[1]"]
    assert np.max(np.abs(x - 0.05 * np.cos(w * r.time))) <= 1e-9 * 0.05


# ------------------------------------------------------------------------------------------------
# Bad input
# ------------------------------------------------------------------------------------------------
def test_an_empty_friction_table_is_an_error(tmp_path):
    """`[...device.friction]` with no field would run as no friction at all (viscous defaults to 0):
    it is refused, naming the effect and its fields, as an effect with a missing field is."""
    text = PEND_COMPACT.read_text(encoding="utf-8") + "\n[elements.device.device.friction]\n"
    path = tmp_path / "empty_friction.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError) as err:
        inerter.load(path)
    text = str(err.value)
    assert "empty_friction.toml: elements.device.device.friction: empty effect" in text
    assert "coulomb, viscous, velocity_scale" in text


# ------------------------------------------------------------------------------------------------
# A device under the small-displacement law
# ------------------------------------------------------------------------------------------------
SMALL_DISPLACEMENT = """
[scene]
name = "small_displacement_stops"
dimension = DIM

[effects]
small_displacement = true
gravity = GRAVITY

[ground.points]
O = ZERO

[bodies.m]
mass = 2.0
inertia = INERTIA
position = POSITION
velocity = VELOCITY
points = { P = ZERO }

[elements.spring]
type = "spring"
between = ["O", "P"]
k = 300.0
length = 0.95

[elements.dev]
type = "inerter"
between = ["O", "P"]
b = 0.5

[elements.dev.device.end_stops]   # undamped: the stops store k_s δ²/2 and give it back
min = 0.98
max = 1.10
stiffness = 1e4

[experiment]
stop_time = 2.0
output_interval = 0.01
rtol = 1e-10
atol = 1e-12
"""


def _small_displacement_scene(tmp_path, dim):
    fields = {2: dict(GRAVITY="[0, -9.81]", ZERO="[0, 0]", INERTIA="0.01", POSITION="[0.3, -1.0]",
                      VELOCITY="[1.5, -0.5]"),
              3: dict(GRAVITY="[0, 0, -9.81]", ZERO="[0, 0, 0]", INERTIA="[0.01, 0.01, 0.01]",
                      POSITION="[0.3, 0.1, -1.0]", VELOCITY="[1.5, 0.4, -0.5]")}[dim]
    text = SMALL_DISPLACEMENT.replace("DIM", str(dim))
    for key, value in fields.items():
        text = text.replace(key, value)
    path = tmp_path / f"sd_{dim}d.toml"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("dim", [2, 3])
def test_under_the_small_displacement_law_the_device_reads_the_stroke_along_e0(tmp_path, dim):
    """The oracle (DistanceProbe: s = ê0·r, its device's laws and potential of s) and the energy:
    a mass swinging on a spring and a small-displacement inerter whose device has undamped end
    stops on its stroke. The stops act along ê0, so their law must read s = ê0·r, not |r|: with
    |r| their force did work they did not store (the energy drifted by ~2 J in 2 s, the run
    ~0.5 m from the oracle's). Engine (compiled and numpy) against the oracle to 1e-6 m, the energy
    kept to 1e-7 of the stops' largest stored energy scale, s_rel still the terminal distance |r|."""
    model = inerter.load(_small_displacement_scene(tmp_path, dim))
    oracle = model.oracle().simulate(metrics=False)
    assert oracle.status == "ok", oracle.message
    for path in ("compiled", "numpy"):
        r = model.simulate(path=path, metrics=False)
        assert r.status == "ok", r.message
        assert np.max(np.abs(r["dev.f_stop"])) > 100.0         # the stops are reached
        for name in [n for n in r.names if n.startswith("P.r[")]:
            assert np.max(np.abs(r[name] - oracle[name])) <= 1e-6, (path, name)
        assert np.ptp(r["energy"]) <= 1e-6, path
        distance = np.sqrt(sum(r[f"P.r[{i + 1}]"] ** 2 for i in range(dim)))
        np.testing.assert_allclose(r["dev.s_rel"], distance, rtol=1e-12, atol=0)


# ------------------------------------------------------------------------------------------------
# Effects combined, the energy balance
# ------------------------------------------------------------------------------------------------
#: Scenes that combine a device's effects as no shipped scene does (tests/data/device_combo_*).
COMBOS = ["device_combo_mount_stops_3d", "device_combo_series_3d", "device_combo_efficiency_series_3d",
          "device_combo_ground_slider_2d", "device_combo_two_devices_2d"]


@pytest.mark.parametrize("name", COMBOS)
def test_combined_effects_balance_the_energy(name):
    """The energy: no applied force, so energy + Σ e_loss (each device's dissipated energy, a state)
    stays at its initial value, to 1e-6 J (the runs at rtol 1e-9 to 1e-10 keep it to 2.4e-7 J or
    better, on energies of 8 to 17 J and a dissipated 0.4 to 5.3 J); and something is dissipated."""
    r = inerter.load(DATA / f"{name}.toml").simulate(metrics=False)
    assert r.status == "ok", r.message
    losses = [n for n in r.names if n.endswith(".e_loss")]
    total = r["energy"] + sum(r[n] for n in losses)
    assert np.max(np.abs(total - total[0])) <= 1e-6
    assert sum(r[n][-1] for n in losses) > 0.1
    assert not np.isnan(r.values()).any()


def test_a_device_on_a_tilted_3d_screw_joint_follows_the_closed_form():
    """Closed form: a nut (mass m, isotropic inertia J_n) on a screw of lead p along the unit axis a
    = (0.6, 0, 0.8) through the origin, a flywheel device (J on lead p_f, b = J (2π/p_f)²) and
    viscous friction c from T = 2a on the axis: the stroke is the advance s along a, so
    M s̈ = m g·a − c ṡ with M = m + J_n (2π/p)² + b, from rest: s = (m g·a/c)(t − τ(1 − e^(−t/τ))),
    τ = M/c. The device's length 2 − s to 1e-12 m, and its dissipated energy equals the energy
    lost to 1e-12 J."""
    r = inerter.load(DATA / "device_helical_nut_3d.toml").simulate(metrics=False)
    m, Jn, p, J, pf, c = 0.5, 2e-4, 0.02, 1e-5, 0.01, 3.0
    M = m + Jn * (2 * math.pi / p) ** 2 + J * (2 * math.pi / pf) ** 2
    ga, tau = -9.81 * 0.8, M / c
    s = (m * ga / c) * (r.time - tau * (1.0 - np.exp(-r.time / tau)))
    assert np.max(np.abs(r["dev.s_rel"] - (2.0 - s))) <= 1e-12
    assert np.max(np.abs(r["dev.e_loss"] + r["energy"])) <= 1e-12
