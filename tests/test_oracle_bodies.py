"""The oracle's bodies' inertia, derived from their kinetic energy (inerter.oracle.bodies).

References: the mass matrix of T = ½ m |Ṙ|² + ½ ω̄ᵀ J ω̄ written out by hand (diag(m I, J)); and a
free rigid body's conservation laws, which the Euler equations imply and the derivation does not
use: the spatial angular momentum h = A J Aᵀ ω (ω in the global frame) and T stay constant.
"""
from __future__ import annotations

import numpy as np
import pytest

import inerter
from inerter.oracle import bodies
from inerter.oracle.mechanism import OracleMechanism

J = np.array([[0.30, 0.02, -0.01], [0.02, 0.20, 0.03], [-0.01, 0.03, 0.10]])

FREE_BODY = """
[scene]
name = "free_asymmetric_body"
dimension = 3
orientation = "quaternion"

[bodies.top]
mass = 2.0
inertia = [[0.30, 0.02, -0.01], [0.02, 0.20, 0.03], [-0.01, 0.03, 0.10]]
position = [0, 0, 0]
axis = [1, 1, 0]
angle = 0.4
angular_velocity = [1.0, 2.0, 3.0]   # largest about the intermediate axis's neighbourhood: tumbling

[experiment]
stop_time = 4.0
output_interval = 0.01
method = "DOP853"
rtol = 1e-12
atol = 1e-14
"""


class _Body:
    def __init__(self, mass, inertia):
        self.mass, self.inertia = mass, inertia


def test_the_mass_blocks_are_t_written_out():
    """2D: diag(m, m, J); 3D: diag(m I, J), J with off-diagonal terms; exactly (T's gradient at
    unit velocities halves and doubles only)."""
    assert np.array_equal(bodies.mass_block(_Body(3.0, 0.7), 2), np.diag([3.0, 3.0, 0.7]))
    want = np.zeros((6, 6))
    want[:3, :3] = 2.0 * np.eye(3)
    want[3:, 3:] = J
    assert np.array_equal(bodies.mass_block(_Body(2.0, J.tolist()), 3), want)


def rotation(quaternion):
    w, x, y, z = quaternion
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def momentum_drift(result) -> float:
    """The largest |h(t) − h(0)| / |h(0)| over the samples, h = A J Aᵀ ω."""
    q = np.column_stack([result[f"top.q[{i}]"] for i in range(1, 5)])
    w = np.column_stack([result[f"top.w[{i}]"] for i in range(1, 4)])
    h = np.array([rotation(qk) @ J @ rotation(qk).T @ wk for qk, wk in zip(q, w)])
    return float(np.max(np.linalg.norm(h - h[0], axis=1)) / np.linalg.norm(h[0]))


@pytest.fixture(scope="module")
def free_body(tmp_path_factory):
    path = tmp_path_factory.mktemp("free_body") / "free_asymmetric_body.toml"
    path.write_text(FREE_BODY)
    return path


def test_a_free_body_keeps_its_angular_momentum_and_energy(free_body):
    """The oracle's free asymmetric body over 4 s (several tumbles) at rtol 1e-12: h constant to
    1e-10 relative and T to 1e-10 relative (measured 9.9e-12 and 6.1e-12: the run's tolerance)."""
    model = inerter.load(free_body).oracle()
    assert isinstance(model.mechanism, OracleMechanism)
    result = model.simulate(metrics=False)
    assert result.status == "ok", result.message
    assert momentum_drift(result) <= 1e-10
    energy = result["energy"]
    assert np.max(np.abs(energy - energy[0])) <= 1e-10 * abs(energy[0])


def test_the_check_fails_with_the_hamel_term_of_the_wrong_sign(free_body, monkeypatch):
    """The same run with +ω̄ × ∂T/∂ω̄: T is still conserved (the term does no work), h is not."""
    original = OracleMechanism.body_forces
    monkeypatch.setattr(OracleMechanism, "body_forces", lambda self, v: -original(self, v))
    result = inerter.load(free_body).oracle().simulate(stop_time=1.0, metrics=False)
    assert result.status == "ok", result.message
    assert momentum_drift(result) > 1e-3
