"""3D bodies' orientation outputs: B.q[i] (unit quaternion), B.euler[i] (the scene's intrinsic
sequence), B.w[i] (angular velocity, global frame), against the closed form of gimbal_lock_3d (a
steady spin about global X: A = R_x(α0 + ω t)) and against scipy's Rotation on the double
pendulum's own rotation matrices (from its points' outputs), on the compiled path and the numpy
path alike."""
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import inerter
from inerter.common.errors import SceneError

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def _with_sequence(tmp_path, scene, sequence):
    text = (SCENARIOS / f"{scene}.toml").read_text()
    text = text.replace("[scene]\n", f'[scene]\neuler_sequence = "{sequence}"\n', 1)
    path = tmp_path / f"{scene}.toml"
    path.write_text(text)
    return inerter.load(path)


@pytest.mark.parametrize("path", ["compiled", "numpy"])
@pytest.mark.parametrize("orientation", ["quaternion", "euler_zxz"])
def test_a_steady_spin_about_x_has_its_closed_form_outputs(tmp_path, path, orientation):
    model = _with_sequence(tmp_path, "gimbal_lock_3d", "xyz")
    if orientation == "euler_zxz":           # stops at θ = 0 (t = 0.25 s): run before it
        model = inerter.load(model.path, **{"scene.orientation": "euler_zxz"})
    r = model.simulate(stop_time=0.2, metrics=False, path=path)
    assert r.status == "ok", r.message
    alpha = 0.5 - 2.0 * r.time
    quaternion = np.column_stack((np.cos(alpha / 2), np.sin(alpha / 2), 0 * alpha, 0 * alpha))
    got = np.column_stack([r[f"spinner.q[{i}]"] for i in range(1, 5)])
    assert np.max(np.abs(got - quaternion)) < 1e-9
    assert np.max(np.abs(r["spinner.euler[1]"] - alpha)) < 1e-9
    assert np.max(np.abs(r["spinner.euler[2]"])) < 1e-9 and np.max(np.abs(r["spinner.euler[3]"])) < 1e-9
    assert np.max(np.abs(r["spinner.w[1]"] + 2.0)) < 1e-9
    assert np.max(np.abs(r["spinner.w[2]"])) < 1e-9 and np.max(np.abs(r["spinner.w[3]"])) < 1e-9


@pytest.mark.parametrize("sequence", ["zxz", "zyx", "xyz", "xzx"])
def test_euler_outputs_are_scipys_angles_of_the_bodys_rotation(tmp_path, sequence):
    """rod2's rotation rebuilt from three of its points (top2, E and a quaternion output check):
    scipy's as_euler of the output quaternion equals the Euler outputs."""
    model = _with_sequence(tmp_path, "double_pendulum_3d", sequence)
    r = model.simulate(stop_time=1.0, metrics=False)
    assert r.status == "ok"
    p = np.column_stack([r[f"rod2.q[{i}]"] for i in range(1, 5)])
    assert np.max(np.abs(np.linalg.norm(p, axis=1) - 1.0)) < 1e-12
    R = Rotation.from_quat(p[:, [1, 2, 3, 0]])
    angles = np.column_stack([r[f"rod2.euler[{i}]"] for i in range(1, 4)])
    assert np.max(np.abs(R.as_euler(sequence.upper()) - angles)) < 1e-9
    # the body's local Z (top2 → E is −l along it) from the quaternion equals the points' outputs
    axis = np.column_stack([r[f"E.r[{i}]"] - r[f"top2.r[{i}]"] for i in range(1, 4)])
    assert np.max(np.abs(R.apply([0.0, 0.0, -1.0]) - axis)) < 1e-9
    # the angular velocity output against the oracle's run (its own element forces; 1e-7 rad/s as
    # against the numpy path before)
    oracle = model.oracle().simulate(stop_time=1.0, metrics=False)
    assert np.max(np.abs(oracle["rod2.w[2]"] - r["rod2.w[2]"])) < 1e-7


def test_an_unknown_sequence_is_one_error(tmp_path):
    with pytest.raises(SceneError, match=r"scene\.euler_sequence"):
        _with_sequence(tmp_path, "double_pendulum_3d", "xxy")


def test_an_initial_quaternion_is_its_axis_angle_twin(tmp_path):
    """bodies.B.quaternion = [cos(a/2), sin(a/2) n] gives the pose of axis = n, angle = a."""
    text = (SCENARIOS / "gimbal_lock_3d.toml").read_text()
    twin = text.replace('axis = [1, 0, 0]\nangle = "alpha0"', 'quaternion = ["cos(alpha0/2)", "sin(alpha0/2)", 0, 0]')
    assert twin != text
    (tmp_path / "twin.toml").write_text(twin)
    a, b = inerter.load(SCENARIOS / "gimbal_lock_3d.toml"), inerter.load(tmp_path / "twin.toml")
    assert np.max(np.abs(np.asarray(a.mechanism.q0) - np.asarray(b.mechanism.q0))) < 1e-15
    (tmp_path / "bad.toml").write_text(twin.replace('"cos(alpha0/2)"', "1"))
    with pytest.raises(SceneError, match=r"bodies\.spinner\.quaternion"):
        inerter.load(tmp_path / "bad.toml")


def test_peak_metrics_come_from_the_dense_output():
    """gimbal_lock_3d's P.r[3] = sin(α0 + ω t) (closed form) peaks at exactly 1 between its 10 ms
    samples: the metric finds 1 to 1e-9, where the samples' largest value falls short by ~1e-5."""
    r = inerter.load(SCENARIOS / "gimbal_lock_3d.toml").simulate()
    assert r.metrics["P_z_peak"] == pytest.approx(1.0, abs=1e-9)
    assert 1.0 - np.max(np.abs(r["P.r[3]"])) > 1e-7          # the samples alone would miss it


def test_a_scene_with_only_peak_metrics_keeps_the_dense_output():
    """braced_frame_3d's metrics are all peaks: the compiled run keeps the integrator's dense output
    for them. The brace's inerter force follows the record's piecewise-linear acceleration (a kink
    at every sample), through which a cubic spline of the 10 ms samples overshoots by 6e-4 of the
    peak. The dense output's peak is the largest value of the same interpolant, which a run sampled
    every 0.2 ms (the same steps) reaches to its grid's error, (ω·0.1 ms)²/2 ≈ 1e-6 of the peak at
    the ~2 Hz of the response, from below."""
    model = inerter.load(SCENARIOS / "braced_frame_3d.toml")
    r = model.simulate()
    assert r.run.dense is not None
    fine = model.simulate(output_interval=2e-4, metrics=False)
    for key, signal in (("brace_x_inerter_force_peak", "brace_x_b.f"), ("drift_y_peak", "M.r[2]")):
        peak, sampled = r.metrics[key], np.max(np.abs(fine[signal]))
        assert -1e-12 * peak <= peak - sampled <= 1e-6 * peak, key
