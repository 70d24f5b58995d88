"""The 3D compiled kernels (inerter.engine.kernels' 3D section, inerter.engine.compiled_spatial),
called one by one: on a scene with every branch of assemble3, Eq. (33)'s accelerations and
multipliers and the output signals against the oracle (translational elements derived from L(q),
3D rotational elements from their potential and dissipation functions; joints and forces the numpy
Mechanism's, whose code is separate from the kernels'); q̇ = B(q) v against its closed form and the
constraint residual against the numpy Mechanism's joints; at the initial state and at random
states (unnormalised quaternions, joints violated, Baumgarte stabilisation on and off). The shipped
3D scenes' accelerations, outputs and runs against the oracle are in test_engine_vs_oracle.py."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.engine import compiled
from inerter.common.errors import TerminalsMeet
from inerter.engine.outputs import Signals
from inerter.common.rotations import axis_angle_matrix, euler_matrix

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")
if compiled.AVAILABLE:
    from inerter.engine.compiled_spatial import flatten3, signal_layout3
    from inerter.engine.compiled import sparsity
    ck = compiled._k                  # the kernels as the package loads them (their on-disk cache)

ROOT = Path(__file__).resolve().parents[1]
SCENES_3D = [p for p in sorted((ROOT / "scenarios").glob("*_3d.toml"))
             if inerter.load(p).mechanism.orientation.kind == "quaternion"]

#: Accelerations and multipliers against the oracle: largest deviation relative to the largest
#: magnitude (measured 2e-14 on the every-branch scene: round-off of different formulas).
TOL_ACC = 1e-12
#: Signals against the oracle's: relative to max(1, |value|) (measured 4e-15).
TOL_SIG = 1e-12


# ------------------------------------------------------------------------------------------------
# A scene with every branch of assemble3: revolute, prismatic, fixed and spherical joints; springs
# (free length given and from the initial pose), a damper, inerters to the ground and between
# bodies; rotational springs (free angle given and not) and a rotational damper, between bodies
# and to the ground; constant, sine, step, pd and input forces; gravity; a full inertia tensor.
# ------------------------------------------------------------------------------------------------
A1 = ([1, 0, 0], 0.3)
E2 = [0.2, 0.7, -0.4]
A3 = ([0, 1, 1], 0.5)
A4 = ([1, 2, 3], 1.0)
TOP, S1, T2, F2, F3, K3, H4 = ([0, 0, 0.5], [0, 0, -0.5], [0, 0, 0.2], [0.3, 0, 0], [-0.2, 0, 0.1],
                               [0.1, 0.1, 0.1], [0, 0, 0.15])
G = [0.5, 0.5, -1.0]
P4 = [0.1, -0.1, 0.0]


def _vec(x):
    return "[" + ", ".join(repr(float(c)) for c in x) + "]"


def _every_branch_scene(tmp_path) -> Path:
    """Write the scene; the bodies' positions put every joint at its initial pose."""
    M1 = axis_angle_matrix(np.array(A1[0], float) / np.linalg.norm(A1[0]), A1[1])
    M2 = euler_matrix(E2)
    M3 = axis_angle_matrix(np.array(A3[0], float) / np.linalg.norm(A3[0]), A3[1])
    M4 = axis_angle_matrix(np.array(A4[0], float) / np.linalg.norm(A4[0]), A4[1])
    R1 = -M1 @ TOP                                         # revolute at the origin
    rS = R1 + M1 @ S1
    rT = rS + 0.1 * M1 @ np.array([0.0, 0.0, 1.0])        # on the slider's line, 0.1 along it
    R2 = rT - M2 @ T2
    R3 = R2 + M2 @ F2 - M3 @ F3                            # fixed joint F2 = F3
    R4 = R3 + M3 @ K3 - M4 @ H4                            # spherical joint K3 = H4
    text = f"""
[scene]
name = "every_branch_3d"
dimension = 3
orientation = "quaternion"
[parameters]
g = 9.81
[effects]
centripetal = true
gravity = [0, 0, "-g"]
[ground.points]
O = [0, 0, 0]
G = {_vec(G)}
[bodies.arm]
mass = 1.5
inertia = [0.12, 0.11, 0.02]
position = {_vec(R1)}
axis = {_vec(A1[0])}
angle = {A1[1]!r}
angular_velocity = [0.7, 0, 0]
points = {{ top = {_vec(TOP)}, S = {_vec(S1)}, D1 = [0.1, 0, 0], F1 = [0, 0.1, -0.2] }}
[bodies.slider]
mass = 0.8
inertia = [0.05, 0.06, 0.07]
position = {_vec(R2)}
euler = {_vec(E2)}
velocity = [0.1, -0.2, 0.3]
points = {{ T = {_vec(T2)}, F2 = {_vec(F2)}, G2 = [0.1, 0.2, 0] }}
[bodies.block]
mass = 1.2
inertia = [[0.3, 0.01, 0.02], [0.01, 0.2, 0.0], [0.02, 0.0, 0.25]]
position = {_vec(R3)}
axis = {_vec(A3[0])}
angle = {A3[1]!r}
points = {{ F3 = {_vec(F3)}, K3 = {_vec(K3)} }}
[bodies.ball]
mass = 0.6
inertia = [0.01, 0.012, 0.014]
position = {_vec(R4)}
axis = {_vec(A4[0])}
angle = {A4[1]!r}
angular_velocity = [0.5, -1.0, 2.0]
points = {{ H4 = {_vec(H4)}, P4 = {_vec(P4)} }}
[joints.hinge]
type = "revolute"
between = ["O", "top"]
axis = {_vec(A1[0])}
[joints.rail]
type = "prismatic"
between = ["S", "T"]
axis = [0, 0, 1]
[joints.weld]
type = "fixed"
between = ["F2", "F3"]
[joints.ball_joint]
type = "spherical"
between = ["K3", "H4"]
[elements.spring]
type = "spring"
between = ["D1", "P4"]
k = 40.0
length = 0.3
[elements.anchor]
type = "spring"
between = ["G", "G2"]
k = 25.0
[elements.damper]
type = "damper"
between = ["D1", "P4"]
c = 2.0
[elements.ground_inerter]
type = "inerter"
between = ["G", "P4"]
b = 0.7
[elements.body_inerter]
type = "inerter"
between = ["D1", "G2"]
b = 0.4
[elements.hinge_spring]
type = "rotational_spring"
bodies = ["ground", "arm"]
axis = {_vec(A1[0])}
k = 5.0
angle = 0.1
[elements.arm_ball_spring]
type = "rotational_spring"
bodies = ["arm", "ball"]
axis = [0, 1, 0]
k = 3.0
[elements.ball_damper]
type = "rotational_damper"
bodies = ["block", "ball"]
axis = [0, 0, 1]
d = 0.3
[forces.push]
point = "P4"
function = "constant"
direction = [0, 0, 1]
value = 2.0
[forces.shake]
point = "G2"
function = "sine"
direction = [1, 1, 0]
amplitude = 3.0
frequency = 0.7
phase = 0.2
offset = 0.5
[forces.kick]
point = "K3"
function = "step"
direction = [0, 1, 0]
value = 4.0
time = 0.5
initial = -1.0
[forces.servo]
point = "P4"
function = "pd"
direction = [1, 0, 0]
kp = 20.0
kd = 3.0
reference = 0.2
[forces.hand]
point = "F1"
function = "input"
[experiment]
stop_time = 1.0
output_interval = 0.01
"""
    path = tmp_path / "every_branch_3d.toml"
    path.write_text(text)
    return path


# ------------------------------------------------------------------------------------------------
# Helpers
# ------------------------------------------------------------------------------------------------
class Kernel3:
    """The 3D kernels called one by one on compiled.Kernel's arrays."""

    def __init__(self, mech):
        self.mech = mech
        kernel = compiled.Kernel(mech)
        self.flat, self.P, self.kl, self.ku = kernel.flat, kernel.params, kernel.kl, kernel.ku
        self.n, self.m = self.flat["n"], self.flat["m"]
        N = self.n + self.m
        self.AB = ck.band_storage(self.kl, self.ku, N)
        self.rhs = np.empty(N)
        self.gen = np.empty(self.n)
        self.layout = signal_layout3(self.flat)

    def accelerations(self, t, q, v, inputs, alpha):
        """(status, q̈, λ): assemble3, band_solve, un-permuted (as compiled_kernels.accelerations)."""
        inp = np.zeros(0) if inputs is None else np.ascontiguousarray(inputs, dtype=float)
        status = ck.assemble3(float(t), q, v, np.zeros(0), inp, float(alpha), self.P, self.AB, self.rhs, self.gen)
        assert ck.band_solve(self.AB, self.rhs, self.kl)
        perm = self.P[15]
        out = np.empty(self.n + self.m)
        for i in range(len(out)):
            out[i] = self.rhs[perm[i]]
        return status, out[:self.n], out[self.n:]

    def qdot(self, q, v):
        out = np.empty(self.flat["nq"])
        ck.qdot3(q, v, self.P, out)
        return out

    def signals(self, q, v, a, names):
        raw = np.empty(len(self.layout))
        status = ck.signal_values3(q, v, np.zeros(0), np.concatenate((a, np.zeros(self.m))), self.P, raw)
        index = {name: i for i, name in enumerate(self.layout)}
        return status, raw[[index[name] for name in names]]


def _states(mech, rng, count=8):
    """The initial state, then random ones: positions moved, quaternions perturbed (not unit),
    random velocities, inputs and times, α = 0 or random."""
    yield 0.0, mech.q0.copy(), mech.v0.copy(), _inputs(mech, rng), 0.0
    for _ in range(count):
        q = mech.q0.copy()
        for k in mech.q_index:
            q[k:k + 3] += 0.2 * rng.standard_normal(3)
            q[k + 3:k + 7] += 0.1 * rng.standard_normal(4)
        v = 2.0 * rng.standard_normal(mech.n)
        alpha = float(rng.choice([0.0, rng.uniform(0.0, 50.0)]))
        yield float(rng.uniform(0.0, 2.0)), q, v, _inputs(mech, rng), alpha


def _inputs(mech, rng):
    return 5.0 * rng.standard_normal(len(mech.input_names)) if mech.input_names else None


def _qdot_closed_form(mech, q, v):
    """q̇ = B(q) v written out: ṙ = v for each body's position and, for its quaternion p (unit or
    not), the kinematic equation ṗ = ½ p ⊗ (0, ω) with ω in the body frame (Hamilton product;
    J. Diebel, Representing attitude, 2006, Sec. 6), computed here from the product's definition."""
    out = np.empty(mech.nq)
    for k, j in zip(mech.q_index, mech.v_index):
        out[k:k + 3] = v[j:j + 3]
        w, x = q[k + 3], q[k + 4:k + 7]
        omega = v[j + 3:j + 6]
        out[k + 3] = -0.5 * float(np.dot(x, omega))
        out[k + 4:k + 7] = 0.5 * (w * omega + np.cross(x, omega))
    return out


def _load(path, centripetal):
    """A fresh mechanism (with its ground motion, where the scene has one)."""
    return inerter.load(path, **{"effects.centripetal": centripetal}).mechanism


def _compare(path, centripetal, seed, count=8):
    """Every kernel over `_states`: accelerations, multipliers and signals against the oracle,
    q̇ against its closed form and the constraint residual against the numpy Mechanism's joints;
    returns the largest deviations."""
    model = inerter.load(path, **{"effects.centripetal": centripetal})
    mech = model.mechanism
    oracle = model.oracle().mechanism
    kern = Kernel3(mech)
    signals = Signals(oracle)
    assert set(kern.layout) == set(signals.names) and len(kern.layout) == len(signals.names)
    rng = np.random.default_rng(seed)
    worst = dict(acc=0.0, qdot=0.0, residual=0.0, signals=0.0)
    for t, q, v, inputs, alpha in _states(mech, rng, count):
        a_ref, lam_ref = oracle.accelerations(t, q, v, inputs, alpha)
        status, a, lam = kern.accelerations(t, q, v, inputs, alpha)
        assert status == ck.OK
        ref = np.concatenate((a_ref, lam_ref))
        dev = np.max(np.abs(np.concatenate((a, lam)) - ref)) / np.max(np.abs(ref)) if np.any(ref) else \
            np.max(np.abs(np.concatenate((a, lam))))
        assert dev <= TOL_ACC, (t, alpha, dev)
        worst["acc"] = max(worst["acc"], dev)

        qd_ref = _qdot_closed_form(mech, q, v)
        dev = np.max(np.abs(kern.qdot(q, v) - qd_ref)) / max(1.0, np.max(np.abs(qd_ref)))
        assert dev <= 1e-14
        worst["qdot"] = max(worst["qdot"], dev)

        res = ck.constraint_residual3(q, kern.P)
        assert res == pytest.approx(mech.constraint_residual(q), rel=1e-12, abs=1e-15)
        worst["residual"] = max(worst["residual"], abs(res - mech.constraint_residual(q)))

        sig_ref = signals.values(t, q, v, a_ref)
        status, sig = kern.signals(q, v, a_ref, signals.names)
        assert status == ck.OK
        dev = np.abs(sig - sig_ref) / np.maximum(1.0, np.abs(sig_ref))
        assert np.max(dev) <= TOL_SIG, signals.names[int(np.argmax(dev))]
        worst["signals"] = max(worst["signals"], float(np.max(dev)))
    return worst


# ------------------------------------------------------------------------------------------------
# Tests
# ------------------------------------------------------------------------------------------------
def test_scenes_found():
    """The 3D quaternion scenes of scenarios/ are the ones the comparisons below run on."""
    assert {p.stem for p in SCENES_3D} >= {"double_pendulum_3d", "spherical_pendulum_3d", "two_bar_2d_as_3d",
                                           "gimbal_lock_3d", "braced_frame_3d"}


@pytest.mark.parametrize("path", SCENES_3D, ids=lambda p: p.stem)
def test_scene_kinematics_match_the_closed_form_and_the_joints(path):
    """At the states of `_states` of every 3D quaternion scene: q̇ = B(q) v (qdot3) against its
    closed form (`_qdot_closed_form`; the numpy Mechanism's q̇ calls the kernels' own quaternion
    rate uncompiled, so it is no reference), 1e-14 relative to max(1, |q̇|) as before; and the
    constraint residual (constraint_residual3) against the numpy Mechanism's joints
    (inerter.model.joints, whose rows are the kernels' own laws, inerter.elements.joint_rows, run
    uncompiled: this checks the kernels' point kinematics and their reading of the joint tables;
    the rows themselves are checked in tests/test_joint_rows.py; the oracle takes its joints from
    that same Mechanism, so it would be the same reference), 1e-12 relative, 1e-15 absolute."""
    mech = _load(path, True)
    kern = Kernel3(mech)
    for _, q, v, _, _ in _states(mech, np.random.default_rng(11)):
        qd_ref = _qdot_closed_form(mech, q, v)
        assert np.max(np.abs(kern.qdot(q, v) - qd_ref)) <= 1e-14 * max(1.0, np.max(np.abs(qd_ref)))
        assert ck.constraint_residual3(q, kern.P) == pytest.approx(mech.constraint_residual(q), rel=1e-12,
                                                                   abs=1e-15)


@pytest.mark.parametrize("centripetal", [True, False])
def test_every_branch_matches_the_oracle(tmp_path, centripetal):
    """Reference: the oracle of a scene with every term assemble3 has (revolute, prismatic, fixed
    and spherical joints, springs, a damper, inerters to the ground and between bodies, rotational
    springs and a damper, constant/sine/step/pd/input forces, gravity, a full inertia tensor), at
    times before and after the step force switches."""
    path = _every_branch_scene(tmp_path)
    mech = _load(path, centripetal)
    assert [j.kind for j in mech.joints] == ["revolute", "prismatic", "fixed", "spherical"]
    assert mech.input_names == ["F1.f[1]", "F1.f[2]", "F1.f[3]"]
    worst = _compare(path, centripetal, seed=3 if centripetal else 4, count=16)
    assert worst["acc"] <= TOL_ACC


def test_every_branch_without_inputs_and_at_the_step(tmp_path):
    """Reference: the oracle. No inputs given (the input force is then absent on both sides), and
    the step force exactly at its switching time (t ≥ time: the new value)."""
    model = inerter.load(_every_branch_scene(tmp_path))
    mech, oracle = model.mechanism, model.oracle().mechanism
    kern = Kernel3(mech)
    for t in (0.0, 0.5, 0.5 - 1e-9, 1.5):
        ref = np.concatenate(oracle.accelerations(t, mech.q0, mech.v0, None, 3.0))
        status, a, lam = kern.accelerations(t, mech.q0, mech.v0, None, 3.0)
        assert status == ck.OK
        assert np.max(np.abs(np.concatenate((a, lam)) - ref)) <= TOL_ACC * np.max(np.abs(ref))


def test_parameter_tuple_matches_planar_contract(tmp_path):
    """Reference: the planar kernel's P (compiled.Kernel on two_bar_2d): the same slots with the
    same dtypes, dimensions and C-contiguity (the FMU's native table holds both), and one more,
    `spatial`, by whose presence the kernels compile the 3D code only for 3D scenes;
    dims = [n, m, kl, ku, has_gravity, 3, nq, ground mode, input offset, the Euler-output sequence's
    three axes (Z-Y-X by default), the count of elements with a screw efficiency (none here), of
    calls whose efficiency modes did not settle (none yet) and of the closed loops of its joints
    (none: each joint carries a body of its own)]; the flat dict has the planar keys."""
    planar_mech = inerter.load(ROOT / "scenarios" / "two_bar_2d.toml").mechanism
    planar = compiled.Kernel(planar_mech).params
    mech = _load(_every_branch_scene(tmp_path), True)
    kernel = compiled.Kernel(mech)
    P, flat = kernel.params, kernel.flat
    assert len(P) == len(planar) + 1 == len(ck.PARAMS) + 1       # the slot `spatial` picks the 3D kernels
    assert ck.is_spatial(P) and not ck.is_spatial(planar)
    for a, b in zip(P, planar):
        assert a.dtype == b.dtype and a.ndim == b.ndim and a.flags.c_contiguous
    assert list(P[ck.DIMS]) == [flat["n"], flat["m"], kernel.kl, kernel.ku, 1, 3, flat["nq"], ck.GROUND_NONE, 0,
                                2, 1, 0, 0, 0, 0]
    assert flat["n"] == mech.n and flat["m"] == mech.m and flat["nq"] == mech.nq and flat["dim"] == 3
    assert set(compiled.flatten(planar_mech)) <= set(flat)


def test_sparsity_covers_the_augmented_matrix(tmp_path):
    """Reference: the numpy Mechanism's augmented matrix [[M + M_I, C_vᵀ], [C_v, 0]] at random
    states: every non-zero lies in sparsity's pattern (so the band after ordering holds it)."""
    paths = SCENES_3D + [_every_branch_scene(tmp_path)]
    rng = np.random.default_rng(5)
    for path in paths:
        mech = _load(path, True)
        S = sparsity(flatten3(mech))
        for _, q, v, _, _ in _states(mech, rng, 3):
            K = np.zeros((mech.n + mech.m,) * 2)
            K[:mech.n, :mech.n] = mech.mass_matrix(q, v)
            if mech.m:
                Cq = mech.constraints(q, v)[1]
                K[:mech.n, mech.n:] = Cq.T
                K[mech.n:, :mech.n] = Cq
            assert not np.any((K != 0) & ~S), path.stem


def test_terminals_meet_is_reported(tmp_path):
    """Reference: the numpy element's TerminalsMeet (elements.py): with the ground inerter's
    terminals G and P4 together, assemble3 and signal_values3 return TERMINALS_MEET."""
    mech = _load(_every_branch_scene(tmp_path), True)
    kern = Kernel3(mech)
    q = mech.q0.copy()
    k = mech.q_index[mech.body_index["ball"]]
    A = np.asarray(mech.orientation.matrix(q[k + 3:k + 7]))
    q[k:k + 3] = np.asarray(G) - A @ np.asarray(P4)
    with pytest.raises(TerminalsMeet):
        mech.accelerations(0.0, q, mech.v0)
    status = ck.assemble3(0.0, q, mech.v0, np.zeros(0), np.zeros(3), 0.0, kern.P, kern.AB, kern.rhs, kern.gen)
    assert status == ck.TERMINALS_MEET
    raw = np.empty(len(kern.layout))
    assert ck.signal_values3(q, mech.v0, np.zeros(0), np.zeros(kern.n + kern.m), kern.P, raw) == ck.TERMINALS_MEET


def test_flatten3_takes_3d_scenes_of_either_orientation():
    """flatten3 refuses a planar scene; Z-X-Z Euler angles give 6 coordinates per body, quaternions 7."""
    with pytest.raises(ValueError):
        flatten3(inerter.load(ROOT / "scenarios" / "two_bar_2d.toml").mechanism)
    euler = inerter.load(ROOT / "scenarios" / "gimbal_lock_3d.toml", **{"scene.orientation": "euler_zxz"})
    quaternion = inerter.load(ROOT / "scenarios" / "gimbal_lock_3d.toml")
    assert flatten3(euler.mechanism)["nq"] == 6 and flatten3(quaternion.mechanism)["nq"] == 7


def test_signal_layout3_order():
    """The layout is points (r, v: 6 each), translational elements, rotational elements (5 each:
    elements.FAMILY_OUTPUTS), bodies
    (quaternion, Euler angles, ω: 10 each), then energy and constraint_residual (the order
    signal_values3 writes)."""
    mech = _load(ROOT / "scenarios" / "two_bar_2d_as_3d.toml", True)
    layout = signal_layout3(flatten3(mech))
    first = mech.point_names[0]
    assert layout[:6] == [f"{first}.r[1]", f"{first}.r[2]", f"{first}.r[3]", f"{first}.v[1]", f"{first}.v[2]",
                          f"{first}.v[3]"]
    assert layout[-2:] == ["energy", "constraint_residual"]
    bodies = 10 * len(mech.body_names)
    assert layout[-7 - bodies:-2 - bodies] == ["kr.phi_rel", "kr.w_rel", "kr.tau", "kr.power", "kr.energy"]
    last = mech.body_names[-1]
    assert layout[-12:-2] == [f"{last}.{x}" for x in ("q[1]", "q[2]", "q[3]", "q[4]", "euler[1]", "euler[2]",
                                                        "euler[3]", "w[1]", "w[2]", "w[3]")]
    assert len(layout) == 6 * len(mech.point_names) + 5 * len(mech.elements) + bodies + 2
