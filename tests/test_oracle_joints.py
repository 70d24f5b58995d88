"""The oracle's joints (inerter.oracle.joints), point forces, weight and ground motion
(inerter.oracle.mechanism), derived on Jets from their definitions, against the model's closed
forms (inerter.model.joints: Eqs. 18-19, 25 and the dot-1/dot-2 rows) and the compiled engine.

* C, C_v and γ of each joint, the same rows on both sides, agree at random states (off the
  constraint manifold, 3D quaternions off unit length), and so do the projectors onto the row
  spaces of C_v (the directions of the constraint forces): reference the model's closed forms;
* q̈ and the constraint forces C_vᵀλ of the OracleMechanism against the compiled kernels on the
  test scenes with joints (the shipped scenes are compared in tests/test_engine_vs_oracle.py);
* the comparison can fail: an engine whose joint axis is off by 1e-6 rad is far from the oracle;
* γ against a central finite difference of C_v v along the motion (2D and 3D).

A 3D screw joint's row is φ − ρ·advance with the rate of the turn φ defined as the relative
angular velocity about the axis (inerter.oracle.joints); that rate is φ's own derivative on the
joint's manifold, which test_screw_turn_rate_is_the_angles_derivative_on_the_manifold checks
against the Jets of φ itself.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.engine import compiled
from inerter.oracle import OracleMechanism
from inerter.oracle.joints import OracleJoint

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"

#: Scenes with joints: the shipped ones and the test scenes, every joint kind they use (2D revolute,
#: slider, rack and pinion; 3D spherical, revolute, prismatic, universal, screw).
JOINT_SCENES = sorted(p for folder in (ROOT / "scenarios", ROOT / "scenarios" / "hard", DATA)
                      for p in folder.glob("*.toml") if "[joints." in p.read_text())

#: Row by row, relative to 1 + the largest |entry| of the quantity at that state: both sides
#: evaluate the same rows in double precision by different formulas (closed forms, Jets); measured
#: worst 6e-15 (C: a 3D screw's angle, device_pendulum_3d_explicit), 2e-16 (C_v), 2e-15 (γ);
#: the projectors 1e-14 (device_helical_nut_3d).
TOL_ROWS = 1e-12

#: Accelerations, λ and C_vᵀλ, relative as in tests/test_engine_vs_oracle.py (TOL_ACC, ACC_FLOOR):
#: measured worst 1.5e-14 (screw_nut_3d).
TOL_ACC = 1e-12
ACC_FLOOR = 1e-2


def _states(mech, rng, count=5, on_manifold=False):
    """(q, v): the initial pose, then poses moved by 0.1 per coordinate (3D: 0.1 m, quaternions by
    0.05, off unit length), with random velocities; projected onto the joints where asked."""
    out = [(mech.q0.copy(), mech.v0 + rng.standard_normal(mech.n))]
    for _ in range(count):
        q = mech.q0.copy()
        if mech.dim == 2:
            q += 0.1 * rng.standard_normal(mech.nq)
        else:
            for k in mech.q_index:
                q[k:k + 3] += 0.1 * rng.standard_normal(3)
                q[k + 3:k + 3 + mech.orientation.size] += 0.05 * rng.standard_normal(mech.orientation.size)
        v = rng.standard_normal(mech.n)
        if on_manifold:
            q, v = mech.project(q, v)
            v = v + rng.standard_normal(mech.n)           # velocities off the tangent space too
        out.append((q, v))
    return out


def _projector(Cq):
    """The orthogonal projector onto the row space of C_v (the constraint forces' directions)."""
    U, s, Vt = np.linalg.svd(Cq, full_matrices=False)
    rank = int(np.sum(s > 1e-10 * s[0]))
    return Vt[:rank].T @ Vt[:rank]


@pytest.mark.parametrize("path", JOINT_SCENES, ids=lambda p: p.stem)
def test_joint_rows_equal_the_models(path):
    """Per joint: the oracle's C, C_v, γ (Jets) equal the model's (closed forms) row by row, and
    the projectors onto the row spaces of the stacked C_v are equal, within TOL_ROWS, at random
    states off the manifold."""
    mech = inerter.load(path).mechanism
    derived = [OracleJoint(spec, mech, mech.initial_q) for spec in mech.scene.joints.values()]
    rng = np.random.default_rng(7)
    for q, v in _states(mech, rng):
        for model_joint, joint in zip(mech.joints, derived):
            assert joint.rows == model_joint.rows and list(joint.dofs) == list(model_joint.dofs)
            for a, b, what in zip(model_joint.evaluate(q, v), joint.evaluate(q, v), ("C", "C_v", "γ")):
                err = float(np.max(np.abs(a - b)))
                assert err <= TOL_ROWS * (1.0 + float(np.max(np.abs(a)))), (path.stem, joint.name, what, err)
        Cq = mech.constraints(q, v)[1]
        Cq_oracle = np.zeros_like(Cq)
        row = 0
        for joint in derived:
            Cq_oracle[row:row + joint.rows, joint.dofs] = joint.evaluate(q, v)[1]
            row += joint.rows
        assert np.max(np.abs(_projector(Cq) - _projector(Cq_oracle))) <= TOL_ROWS, path.stem


def _oracle_takes(path):
    try:
        inerter.load(path).oracle()
    except inerter.InerterError:            # an inerter device with a screw efficiency: not derived
        return False
    return True


ENGINE_SCENES = [p for p in JOINT_SCENES if p.parent == DATA and _oracle_takes(p)]


@pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")
@pytest.mark.parametrize("path", ENGINE_SCENES, ids=lambda p: p.stem)
def test_accelerations_and_constraint_forces_equal_the_engines(path):
    """q̈, λ and the constraint forces C_vᵀλ of Eq. (33) from the compiled kernels equal the
    OracleMechanism's (TOL_ACC, relative to the largest |value| at the state or ACC_FLOOR of the
    scene's largest), with Baumgarte α = 0 and 20/s, at the states of test_joint_rows_equal_the_models."""
    model = inerter.load(path)
    oracle = model.oracle().mechanism
    assert isinstance(oracle, OracleMechanism)
    kernel = compiled.compile_mechanism(model.mechanism)
    rng = np.random.default_rng(11)
    inputs = rng.standard_normal(len(oracle.input_names)) if oracle.input_names else None
    pairs = []
    for q, v in _states(model.mechanism, rng):
        for alpha in (0.0, 20.0):
            a, lam = kernel.accelerations(0.3, q, v, inputs, alpha)
            b, mu = oracle.accelerations(0.3, q, v, inputs, alpha)
            Cq = oracle.constraints(q, v)[1]
            pairs.append((np.concatenate((a, lam, Cq.T @ lam)), np.concatenate((b, mu, Cq.T @ mu))))
    scale = max(float(np.max(np.abs(b))) for _, b in pairs)
    for a, b in pairs:
        bound = TOL_ACC * max(float(np.max(np.abs(b))), ACC_FLOOR * scale)
        assert float(np.max(np.abs(a - b))) <= bound, (path.stem, float(np.max(np.abs(a - b))), bound)


@pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")
def test_a_joint_axis_off_by_a_micro_radian_fails(tmp_path):
    """Guard against a comparison that cannot fail: an engine whose revolute joint `a` turns about
    an axis tilted by 1e-6 rad (the oracle's joint from the scene as written) gives accelerations
    far beyond TOL_ACC from the oracle's (measured 6e-8 of max|q̈|, asserted above 1e3 TOL_ACC)."""
    path = DATA / "parallelogram_3d.toml"
    text = path.read_text()
    head, joint_a = text.split("[joints.a]")
    tilted = head + "[joints.a]" + joint_a.replace("axis = [0, 0, 1]", "axis = [0, 1e-6, 1]", 1)
    assert tilted.count("axis = [0, 1e-6, 1]") == 1
    (tmp_path / path.name).write_text(tilted)
    oracle = inerter.load(path).oracle().mechanism
    engine = compiled.compile_mechanism(inerter.load(tmp_path / path.name).mechanism)
    rng = np.random.default_rng(3)
    q, v = oracle.q0, oracle.v0 + rng.standard_normal(oracle.n)
    b = oracle.accelerations(0.0, q, v)[0]
    a = engine.accelerations(0.0, q, v, None, 0.0)[0]
    assert np.max(np.abs(a - b)) > 1e3 * TOL_ACC * np.max(np.abs(b))


def _along(mech, q, v, h):
    """The pose at time h along the motion from q with constant velocity coordinates v: R + h Ṙ,
    and in 3D p ⊗ (cos |ω|h/2, sin |ω|h/2 ω/|ω|) (constant body-frame ω)."""
    if mech.dim == 2:
        return q + h * v
    out = q.copy()
    for k, j in zip(mech.q_index, mech.v_index):
        out[k:k + 3] += h * v[j:j + 3]
        w = v[j + 3:j + 6]
        angle = float(np.linalg.norm(w)) * h
        e = np.concatenate(([np.cos(angle / 2)], np.sin(angle / 2) * w / np.linalg.norm(w)))
        p = q[k + 3:k + 7]
        out[k + 3:k + 7] = (p[0] * e[0] - p[1:] @ e[1:],
                            *(p[0] * e[1:] + e[0] * p[1:] + np.cross(p[1:], e[1:])))
    return out


@pytest.mark.parametrize("name", ["parallelogram_2d", "parallelogram_3d", "screw_nut_3d",
                                  "device_pendulum_3d_explicit"])
def test_gamma_is_minus_the_rate_of_cv_v(name):
    """γ = −d(C_v v)/dt at v̇ = 0 (C̈ = C_v v̇ − γ): the oracle's γ against a central difference of its
    C_v v over ±h = 1e-5 s along the motion (the exact pose at constant v, _along), at a state off
    the manifold; truncation h²|d³(C_v v)/dt³|/6 and round-off 1e-16/h keep it within 1e-8 of
    1 + max|γ| (measured 7e-11 or less)."""
    mech = inerter.load(DATA / f"{name}.toml").oracle().mechanism
    rng = np.random.default_rng(5)
    q, v = _states(mech, rng, count=1)[-1]
    h = 1e-5
    rate = (mech.constraints(_along(mech, q, v, h), v)[1] @ v
            - mech.constraints(_along(mech, q, v, -h), v)[1] @ v) / (2.0 * h)
    gamma = mech.constraints(q, v)[2]
    assert np.max(np.abs(gamma + rate)) <= 1e-8 * (1.0 + np.max(np.abs(gamma))), name


@pytest.mark.parametrize("name", ["screw_nut_3d", "device_pendulum_3d_explicit"])
def test_screw_turn_rate_is_the_angles_derivative_on_the_manifold(name):
    """On the joints' manifold (random poses projected onto it, any velocity), a 3D screw's row
    with its turn's rate as the relative angular velocity about the axis has the C_v and γ of the
    turn φ differentiated itself on Jets (``exact_turn``), within TOL_ROWS (measured 6e-15); off the manifold the
    two differ (measured 0.017 in C_v on screw_nut_3d, 0.039 on device_pendulum_3d_explicit, at the
    pose checked here: more than 1e-3), which is why the rate is the definition."""
    mech = inerter.load(DATA / f"{name}.toml").mechanism
    spec = next(j for j in mech.scene.joints.values() if j.type == "screw")
    by_rate = OracleJoint(spec, mech, mech.initial_q)
    exact = OracleJoint(spec, mech, mech.initial_q)
    exact.exact_turn = True
    rng = np.random.default_rng(13)
    for q, v in _states(mech, rng, on_manifold=True):
        for a, b in zip(by_rate.evaluate(q, v), exact.evaluate(q, v)):
            assert np.max(np.abs(a - b)) <= TOL_ROWS * (1.0 + np.max(np.abs(a))), name
    q, v = _states(mech, rng, count=1)[-1]
    assert np.max(np.abs(by_rate.evaluate(q, v)[1] - exact.evaluate(q, v)[1])) > 1e-3
