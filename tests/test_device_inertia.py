"""An inerter device's masses and inertias (inerter.elements.device_inertia) and the screw joint.

References, each named in its test:

* the oracle (inerter.oracle.derivation.DeviceBodies), which derives the device's terms from its
  parts' rigid-body kinetic energy, their rotations built on Jets from the mount's definition, with
  code shared with neither the engine nor the elements;
* a closed form for the screw joint alone: a nut on a vertical screw (3D), a pinion on a vertical
  rack (2D) falls at g/(1 + J(2π/p)²/m) (its kinetic energy ½(m + J(2π/p)²)ż², potential m g z);
  the kernels' screw rows against the numpy joints' (inerter.model.joints) at random states;
* the explicit device: the same scene with the device built from bodies and joints (housing on a
  Hooke joint, rod keyed to it by a prismatic joint and carried by a ball joint, flywheel on a
  revolute bearing and a screw joint), solved by the same engine (tests/data/device_*_explicit);
* the energy: with no dissipation and no applied force, T + V, with the device's kinetic energy
  and its masses' weight, stays at its initial value.
"""
from __future__ import annotations

import math
import re
import zlib
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.common.errors import SceneError
from inerter.elements import layout
from inerter.engine import compiled

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
DOUBLE_PENDULUM = ROOT / "scenarios" / "double_pendulum_3d.toml"
BAR_COMPACT, BAR_EXPLICIT = DATA / "device_bar_2d_compact.toml", DATA / "device_bar_2d_explicit.toml"
PEND_COMPACT, PEND_EXPLICIT = DATA / "device_pendulum_3d_compact.toml", DATA / "device_pendulum_3d_explicit.toml"

#: A device with every part, on the double pendulum's inerter (both terminals on moving bodies).
PARTS = """
[elements.inerter.device.flywheel]
inertia = 2e-4
lead = 0.02
transverse_inertia = 3e-3
mass = 0.4
centre = 0.1

[elements.inerter.device.housing]
mass = 0.7
centre = 0.15
transverse_inertia = 2e-3
axial_inertia = 5e-4

[elements.inerter.device.rod]
mass = 0.3
centre = 0.2
transverse_inertia = 1e-3
axial_inertia = 1e-4
"""
#: The parts without their axial inertias: without a mount the model holds their spin about the
#: device's axis at zero, and an axial inertia there is refused (it would act on nothing).
PARTS_NO_SPIN = PARTS.replace("axial_inertia = 5e-4\n", "").replace("axial_inertia = 1e-4\n", "")
MOUNT = """
[elements.inerter.device.mount]
axis = [1, 0.3, 0.2]
"""


def _pendulum(tmp_path, device, name):
    """The 3D double pendulum with `device` on its inerter (b from the flywheel)."""
    lines, inside = [], False
    for line in DOUBLE_PENDULUM.read_text(encoding="utf-8").splitlines(keepends=True):
        if line.startswith("["):
            inside = line.strip() == "[elements.inerter]"
        if not (inside and re.match(r'b\s*=\s*"b"', line)):
            lines.append(line)
    path = tmp_path / name
    path.write_text("".join(lines) + device, encoding="utf-8")
    return inerter.load(path)


def _states(mech, seed, count=6):
    """The initial state, then states with random velocities and, for half of them, positions
    off the constraints (quaternions off unit length in 3D)."""
    rng = np.random.default_rng(zlib.crc32(seed.encode()))
    out = [(0.0, mech.q0.copy(), mech.v0.copy())]
    for k in range(count):
        q = mech.q0 + (0.05 * rng.standard_normal(mech.nq) if k % 2 else 0.0)
        out.append((float(rng.uniform(0, 2)), q, mech.v0 + 1.5 * rng.standard_normal(mech.n)))
    return out


#: A ground motion on two axes (analytic terms, so that the same text serves 2D and 3D scenes).
SHAKE = ('ground_acceleration = { terms = [{ axis = 1, amplitude = 3.0, frequency = 0.7 }, '
         '{ axis = 2, amplitude = 2.0, frequency = 1.1, phase = 0.5 }] }\n')


def _shaken(tmp_path, path):
    """The scene at `path` with its ground shaken by SHAKE (coordinates relative to the ground)."""
    text = path.read_text(encoding="utf-8")
    assert "centripetal = true\n" in text
    out = tmp_path / f"shaken_{path.name}"
    out.write_text(text.replace("centripetal = true\n", "centripetal = true\n" + SHAKE, 1), encoding="utf-8")
    return out


def _cases(tmp_path):
    return {"2d-bar": inerter.load(BAR_COMPACT), "3d-pendulum-ground-mount": inerter.load(PEND_COMPACT),
            "2d-bar-shaken": inerter.load(_shaken(tmp_path, BAR_COMPACT)),
            "3d-pendulum-shaken": inerter.load(_shaken(tmp_path, PEND_COMPACT)),
            "3d-moving-mount": _pendulum(tmp_path, PARTS + MOUNT, "mount.toml"),
            "3d-no-mount": _pendulum(tmp_path, PARTS_NO_SPIN, "no_mount.toml")}


@pytest.mark.parametrize("case", ["2d-bar", "3d-pendulum-ground-mount", "3d-moving-mount", "3d-no-mount",
                                  "2d-bar-shaken", "3d-pendulum-shaken"])
def test_engine_and_readable_path_equal_the_oracle(tmp_path, case):
    """Reference: the oracle (the parts' rigid-body kinetic energy on Jets). The kernels' and the
    numpy evaluators' accelerations and multipliers (Eq. 33) at the initial state and at random
    states, within 1e-12 of the largest (the tolerance of test_engine_vs_oracle; the shaken cases
    at times where the ground accelerates, so the parts' inertial force −m a_g is in), and the energy
    output (T + V with the device's kinetic energy and its masses' weight) within 1e-12 relative."""
    model = _cases(tmp_path)[case]
    mech, oracle = model.mechanism, model.oracle()
    kernel = compiled.compile_mechanism(mech)
    order = kernel.signal_order(model.signals)
    energy = model.signals.index["energy"]
    for t, q, v in _states(mech, case):
        y = np.concatenate(oracle.mechanism.accelerations(t, q, v))
        scale = max(1.0, np.max(np.abs(y)))
        assert np.max(np.abs(np.concatenate(kernel.accelerations(t, q, v)) - y)) <= 1e-12 * scale
        assert np.max(np.abs(np.concatenate(mech.accelerations(t, q, v)) - y)) <= 1e-12 * scale
        E = kernel.signal_values(model.signals, order, t, q, v)[energy]
        E_ref = oracle.signals.evaluate(t, q, v)[energy]
        assert E == pytest.approx(E_ref, rel=1e-12, abs=1e-12)


def test_engine_run_equals_the_oracle_run(tmp_path):
    """Reference: the oracle's DOP853 run. The double pendulum with every part and a mount on a
    moving body (its rod 1), 1 s at rtol 1e-12 both: every point's position within 2·N·rtol of
    its range, N the steps (the bound test_engine_vs_oracle derives for two runs at rtol)."""
    model = _pendulum(tmp_path, PARTS + MOUNT, "mount.toml")
    settings = model.settings(method="DOP853", stop_time=1.0, rtol=1e-12, atol=1e-14)
    from inerter.engine.simulation import integrate
    ref = integrate(model.oracle().mechanism, settings)
    run = compiled.integrate_compiled(model.mechanism, settings)
    assert run.status == ref.status == "ok" and np.array_equal(run.time, ref.time)
    bound = 2.0 * max(run.steps, ref.steps) * 1e-12
    mech = model.mechanism
    for k in mech.q_index:                             # each body's centre
        a, b = run.states[:, k:k + 3], ref.states[:, k:k + 3]
        assert np.max(np.abs(a - b)) <= bound * max(1.0, np.max(np.abs(b)))


def test_the_oracle_comparison_can_fail(tmp_path):
    """Guard: the engine with the mount's axis turned by 1e-6 rad (the housing's spin and the
    gyroscopic moments change with it) is far from the oracle of the scene."""
    model = _pendulum(tmp_path, PARTS + MOUNT, "mount.toml")
    wrong = _pendulum(tmp_path, PARTS + MOUNT.replace("0.2]", "0.200001]"), "wrong.toml")
    kernel = compiled.compile_mechanism(wrong.mechanism)
    omech = model.oracle().mechanism
    q, v = omech.q0, omech.v0 + 0.7
    y = np.concatenate(omech.accelerations(0.0, q, v))
    assert np.max(np.abs(np.concatenate(kernel.accelerations(0.0, q, v)) - y)) > 1e3 * 1e-12 * np.max(np.abs(y))


def test_a_device_without_masses_has_no_kinetic_block(tmp_path):
    """Absent, not computed: a flywheel with its axial inertia and lead only leaves column INERTIA
    at 0 (the kernels never call the block); any of the new fields sets it."""
    plain = _pendulum(tmp_path, "[elements.inerter.device.flywheel]\ninertia = 2e-4\nlead = 0.02\n", "plain.toml")
    assert not plain.scene.elements["inerter"].device.inertia()
    assert layout.INERTIA not in plain.scene.elements["inerter"].device.columns()
    full = _pendulum(tmp_path, PARTS_NO_SPIN, "full.toml")
    assert full.scene.elements["inerter"].device.columns()[layout.INERTIA] == 1.0


def test_describe_lists_the_parts_and_the_mount(tmp_path):
    text = "\n".join(_pendulum(tmp_path, PARTS + MOUNT, "mount.toml").terms())
    assert "housing (mass = 0.7 kg, centre = 0.15 m" in text
    assert "rod (mass = 0.3 kg" in text and "transverse_inertia = 0.003 kg.m2" in text
    assert "mount (axis = [" in text and "gyroscopic moments (Hooke mount)" in text


@pytest.mark.parametrize("device, field, expected", [
    ("[elements.inerter.device.housing]\ncentre = 0.1\n", "elements.inerter.device.housing.mass", "missing"),
    ("[elements.inerter.device.rod]\nmass = -1.0\n", "elements.inerter.device.rod.mass", "≥ 0"),
    ("[elements.inerter.device.mount]\naxis = [0, 0, 0]\n", "elements.inerter.device.mount.axis", "non-zero"),
    ("[elements.inerter.device.flywheel]\ninertia = 1e-4\nlead = 0.01\nmass = -2\n",
     "elements.inerter.device.flywheel.mass", "≥ 0")])
def test_device_part_errors_name_the_field(tmp_path, device, field, expected):
    with pytest.raises(SceneError) as err:
        _pendulum(tmp_path, device, "bad.toml")
    assert field in str(err.value) and expected in str(err.value)


def test_a_mount_in_2d_is_refused_with_the_reason(tmp_path):
    text = BAR_COMPACT.read_text(encoding="utf-8") + "\n[elements.device.device.mount]\naxis = [0, 0, 1]\n"
    path = tmp_path / "bar_mount.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError) as err:
        inerter.load(path)
    assert "elements.device.device.mount" in str(err.value) and "planar constraint" in str(err.value)


def test_a_mount_beside_a_series_connection_is_refused_with_the_reason(tmp_path):
    """The mount's gyroscopic terms spin the flywheel with dL/dt; in series it follows u = L − s."""
    text = PEND_COMPACT.read_text(encoding="utf-8") + "\n[elements.device.device.compliance]\nstiffness = 1e5\n"
    path = tmp_path / "pendulum_series.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SceneError) as err:
        inerter.load(path)
    message = str(err.value)
    assert "elements.device.device.mount" in message and "compliance" in message and "\n" not in message


# ------------------------------------------------------------------------------------------------
# The screw joint
# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("dim", [3, 2])
def test_screw_nut_falls_at_the_closed_form(path, dim):
    """Closed form: a nut of mass m and axial inertia J on a vertical screw of lead p falls at
    a = g/(1 + J(2π/p)²/m) (Lagrange with T = ½(m + J(2π/p)²)ż², V = m g z) and turns at
    (2π/p) ż (the screw's lead positive: right-handed, the nut turns about +z as it rises); in 2D
    the same for a pinion on a vertical rack (the 2D screw joint), its angle (2π/p) y."""
    model = inerter.load(DATA / f"screw_nut_{dim}d.toml")
    result = model.simulate(path=path)
    m, J, p, g = 0.5, 2e-4, 0.02, 9.81
    n = 2.0 * math.pi / p
    a = g / (1.0 + J * n * n / m)
    t = result.time
    assert np.max(np.abs(result[f"N.r[{dim}]"] + 0.5 * a * t * t)) <= 1e-12
    if dim == 3:
        assert np.max(np.abs(result["nut.w[3]"] + n * a * t)) <= 1e-9
    else:
        assert np.max(np.abs(result["N.v[2]"] + a * t)) <= 1e-11
        mech = model.mechanism
        angle = result.run.states[:, mech.q_index[0] + 2]
        assert np.max(np.abs(angle + 0.5 * n * a * t * t)) <= 1e-9
    assert result["constraint_residual"].max() <= 1e-9


@pytest.mark.parametrize("edit, field, expected", [
    (('lead = "p"', 'lead = 0.0'), "joints.screw.lead", "non-zero lead"),
    (('lead = "p"', 'lead = "p"\ncoupling_only = 1'), "joints.screw.coupling_only", "true or false"),
    (('lead = "p"\n', ''), "joints.screw.lead", "missing")])
def test_screw_joint_errors_name_the_field(tmp_path, edit, field, expected):
    path = tmp_path / "nut.toml"
    path.write_text((DATA / "screw_nut_3d.toml").read_text(encoding="utf-8").replace(*edit), encoding="utf-8")
    with pytest.raises(SceneError) as err:
        inerter.load(path)
    assert field in str(err.value) and expected in str(err.value)


def test_2d_screw_on_a_moving_rack_kernels_equal_the_oracle(tmp_path):
    """The 2D screw's rows where the rack turns (its body a pinned to the ground and swinging):
    the kernels' (kernels._screw2) against the oracle's mechanism, whose joints are the model
    layer's (joints.Prismatic2D: the same row laws, inerter.elements.joint_rows, placed by code
    separate from the kernels'; the rows' rates are checked in tests/test_joint_rows.py) and whose
    element forces are derived from L(q): accelerations and multipliers at random states, within 1e-12 of the largest
    (as against the numpy Mechanism before)."""
    text = (DATA / "screw_nut_2d.toml").read_text(encoding="utf-8")
    text = text.replace('[bodies.pinion]', '[bodies.rack]\nmass = 2.0\ninertia = 0.3\nposition = [0.4, 0]\n'
                        'angle = 0.0\npoints = { R0 = [-0.4, 0], R = [0.1, 0.05] }\n\n[joints.pivot]\n'
                        'type = "revolute"\nbetween = ["S", "R0"]\n\n[bodies.pinion]')
    text = text.replace('between = ["S", "N"]', 'between = ["R", "N"]').replace("position = [0, 0]\npoints",
                                                                            "position = [0.5, 0.2]\npoints")
    path = tmp_path / "rack.toml"
    path.write_text(text, encoding="utf-8")
    model = inerter.load(path)
    mech = model.mechanism
    kernel = compiled.compile_mechanism(mech)
    oracle = model.oracle().mechanism
    for t, q, v in _states(mech, "rack-2d"):
        y = np.concatenate(oracle.accelerations(t, q, v, alpha=0.0))
        x = np.concatenate(kernel.accelerations(t, q, v))
        assert np.max(np.abs(x - y)) <= 1e-12 * max(1.0, np.max(np.abs(y)))
    # γ is C's second derivative: along a run (the rack swinging, the pinion falling and turning)
    # the joints hold to the integrator's tolerance
    result = model.simulate(metrics=False)
    assert result.status == "ok" and np.ptp(result["N.r[2]"]) > 0.5
    assert result["constraint_residual"].max() <= 1e-9


def test_screw_joint_kernels_equal_the_oracle(tmp_path):
    """The kernels' screw row (and the rest of the explicit device's joints) against the oracle's
    mechanism, whose joints are the model layer's (inerter.model.joints.Screw: the kernels' row law,
    joint_rows.screw_row, placed by code of its own) and whose element forces are derived from
    L(q): accelerations and multipliers at random states of the explicit 3D device, within 1e-12 of the largest (as against the numpy Mechanism before)."""
    model = inerter.load(PEND_EXPLICIT)
    mech = model.mechanism
    kernel = compiled.compile_mechanism(mech)
    oracle = model.oracle().mechanism
    for t, q, v in _states(mech, "screw-joint"):
        y = np.concatenate(oracle.accelerations(t, q, v, alpha=0.0))
        x = np.concatenate(kernel.accelerations(t, q, v))
        assert np.max(np.abs(x - y)) <= 1e-12 * max(1.0, np.max(np.abs(y)))


# ------------------------------------------------------------------------------------------------
# The explicit cross-check and the energy
# ------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def cross_runs():
    cache = {}

    def get(path, **overrides):
        key = (str(path), tuple(sorted(overrides.items())))
        if key not in cache:
            cache[key] = inerter.load(path, **overrides).simulate(metrics=False)
        return cache[key]
    return get


def _gap(a, b, point, dims):
    return max(np.max(np.abs(a[f"{point}.r[{i + 1}]"] - b[f"{point}.r[{i + 1}]"])) for i in range(dims))


@pytest.mark.parametrize("compact, explicit, point, dims", [
    (BAR_COMPACT, BAR_EXPLICIT, "T", 2), (PEND_COMPACT, PEND_EXPLICIT, "P", 3)], ids=["2d-bar", "3d-pendulum"])
def test_compact_device_under_ground_motion_equals_the_explicit_device(cross_runs, tmp_path, compact, explicit,
                                                                        point, dims):
    """Reference: the explicit device (bodies, whose −m a_g the engine has always applied) under the
    same ground motion (SHAKE), solved by the same engine at rtol 1e-12: the compact device's parts
    feel the ground's acceleration as those bodies do, to 1e-8 m over 10 s. Guard: the ground motion
    moves the tip by more than 1 mm, so a compact device whose parts ignored it would fail."""
    a, b = cross_runs(_shaken(tmp_path, compact)), cross_runs(_shaken(tmp_path, explicit))
    assert a.status == b.status == "ok" and np.array_equal(a.time, b.time)
    assert _gap(a, b, point, dims) <= 1e-8, _gap(a, b, point, dims)
    assert _gap(a, cross_runs(compact), point, dims) > 1e-3


@pytest.mark.parametrize("compact, explicit, point, dims", [
    (BAR_COMPACT, BAR_EXPLICIT, "T", 2), (PEND_COMPACT, PEND_EXPLICIT, "P", 3)], ids=["2d-bar", "3d-pendulum"])
def test_compact_device_equals_the_explicit_device(cross_runs, compact, explicit, point, dims):
    """Reference: the explicit device (module docstring), solved by the same engine at rtol 1e-12.
    The device's terminal b agrees to 1e-8 m over 10 s. 2D: the compact planar device against the
    explicit one built in 3D, held in the plane by the bar's revolute joint and the Hooke joint
    whose first axis is the plane's normal. 3D: a spherical pendulum pushed sideways, the device's
    axis sweeping round while its stroke changes, its flywheel's gyroscopic moments carried by the
    Hooke mount."""
    a, b = cross_runs(compact), cross_runs(explicit)
    assert a.status == b.status == "ok"
    assert np.array_equal(a.time, b.time) and a.time[-1] == pytest.approx(10.0)
    stroke = a["device.s_rel"]
    assert stroke.max() - stroke.min() > 0.05                       # the stroke changes
    assert _gap(a, b, point, dims) <= 1e-8, _gap(a, b, point, dims)
    if dims == 3:
        azimuth = np.unwrap(np.arctan2(a["P.r[2]"], a["P.r[1]"]))
        assert azimuth.max() - azimuth.min() > math.pi / 2         # the axis sweeps round


def test_the_cross_check_can_fail(cross_runs, tmp_path):
    """Guards: the explicit 3D device with its screw turned the other way (the flywheel's spin,
    and so its gyroscopic moments, reversed; its axial inertia unchanged), and the compact device
    without its mount (the housing's spin and the gyroscopic moments left out: the model of the
    ideal inerter's flywheel), are each far from the compact device: the cross-check sees the
    gyroscopic terms."""
    compact = cross_runs(PEND_COMPACT)
    text = PEND_EXPLICIT.read_text(encoding="utf-8").replace('lead = "-lead"', 'lead = "lead"')
    flipped = tmp_path / "flipped.toml"
    flipped.write_text(text, encoding="utf-8")
    assert _gap(compact, inerter.load(flipped).simulate(metrics=False), "P", 3) > 1e-5
    text = PEND_COMPACT.read_text(encoding="utf-8").split("[elements.device.device.mount]")[0] + \
        PEND_COMPACT.read_text(encoding="utf-8").split("never along the rod)\n")[1]
    # without the mount the parts' axial inertias go too: they would act on nothing, and are refused
    text = text.replace('axial_inertia = "Ja_h"\n', "").replace('axial_inertia = "Ja_r"\n', "")
    no_mount = tmp_path / "no_mount.toml"
    no_mount.write_text(text, encoding="utf-8")
    assert _gap(compact, inerter.load(no_mount).simulate(metrics=False), "P", 3) > 1e-5


@pytest.mark.parametrize("scene, overrides", [(BAR_COMPACT, {}), (PEND_COMPACT, {"F": 0.0, "v0": 1.5})],
                         ids=["2d-bar", "3d-pendulum"])
def test_energy_with_the_device_is_conserved(cross_runs, scene, overrides):
    """No dissipation, no applied force (the 3D scene's push set to 0, the bob started sideways
    instead, so that the device's axis sweeps round): the energy output, which
    includes the device's kinetic energy (masses, transverse and axial inertia, spin) and its
    masses' weight, stays at its initial value within 1e-9 of the motion's energy scale over
    10 s at rtol 1e-12 (DOP853's local errors, 1e-12 relative per step, summed over the ~10³
    steps)."""
    result = cross_runs(scene, **overrides)
    E = result["energy"]
    swing = np.max(np.abs(result[f"{'T' if scene == BAR_COMPACT else 'P'}.v[1]"]))
    scale = max(1.0, float(np.max(np.abs(E))))
    assert swing > 0.3
    if scene == PEND_COMPACT:
        azimuth = np.unwrap(np.arctan2(result["P.r[2]"], result["P.r[1]"]))
        assert azimuth.max() - azimuth.min() > 2 * math.pi
    assert np.max(np.abs(E - E[0])) <= 1e-9 * scale, np.max(np.abs(E - E[0]))


def test_fmu_of_a_device_with_masses_validates_and_matches_the_solver(tmp_path):
    """The 2D compact device's FMU (its masses, centres and inertias FMU parameters, tunable as
    the device's other numbers: engine.tables.tunable_field) validates with fmpy, and its outputs
    over 2 s match the solver's run of the same scene to 1e-9 m (the same compiled integrator
    behind the FMU, its steps ending at the communication points)."""
    from fmpy.validation import validate_fmu

    from inerter.engine.tables import tunable_field
    from inerter.fmu.build import build
    from inerter.fmu.run import simulate_fmu
    from fmpy import read_model_description
    fmu = build(BAR_COMPACT, tmp_path, force=True)
    assert validate_fmu(str(fmu)) == []
    model = inerter.load(BAR_COMPACT)
    assert tunable_field(model.scene, "elements.device.device")
    variables = {v.name: v for v in read_model_description(str(fmu)).modelVariables}
    for name in ("m_h", "h_h", "It_h", "m_r", "h_r", "It_r", "Jt_fw", "m_fw", "h_fw", "J_fw"):
        assert variables[name].causality == "parameter" and variables[name].variability == "tunable", name
    run = simulate_fmu(BAR_COMPACT, stop_time=2.0, fmu_path=fmu, metrics=False)
    ref = model.simulate(stop_time=2.0, metrics=False)
    assert run.status == "ok", run.message
    assert np.allclose(run.time, ref.time, rtol=0, atol=1e-9)
    assert max(np.max(np.abs(run[n] - ref[n])) for n in ("T.r[1]", "T.r[2]")) <= 1e-9
