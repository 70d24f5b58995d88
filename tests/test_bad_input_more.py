"""Bad input and runs that stop, found by mutating the shipped scenes and options: each gives one
line on stderr (naming the file, the field, the value and what was expected, or where and why the
run stopped), exit status 2 (3 for a run that stopped early), no traceback, and a stopped run keeps
the samples it finished, without NaN."""
from __future__ import annotations

import csv
import math

import pytest

from inerter.cli import main
from conftest import LUMPED, SCENARIOS, one_line_error as one_line

TERMINALS_MEET = SCENARIOS / "hard" / "terminals_meet_2d.toml"



def rows(path):
    with open(path, newline="") as f:
        return list(csv.reader(f))[1:]


@pytest.mark.parametrize("value", ["2.0", "3.0", "2.5"])
def test_a_dimension_that_is_not_an_integer(tmp_path, capsys, value):
    """`dimension = 2.0` was a TypeError traceback (it counts vector components)."""
    scene = tmp_path / "scene.toml"
    text = LUMPED.read_text()
    scene.write_text(text.replace("[scene]\n", f"[scene]\ndimension = {value}\n", 1))
    assert "dimension" not in text and scene.read_text() != text
    assert main(["describe", str(scene)]) == 2
    one_line(capsys, str(scene), "scene.dimension", value, "2 or 3 (an integer)")


def test_a_scene_with_a_byte_order_mark_reads_as_without(tmp_path, capsys):
    """A UTF-8 byte-order mark (some editors write one) was the parse error 'Invalid statement (at
    line 1, column 1)'; the scene is the same with or without it (same parameters and bodies)."""
    import inerter
    scene = tmp_path / "bom.toml"
    scene.write_bytes(b"\xef\xbb\xbf" + LUMPED.read_bytes())
    a, b = inerter.load(scene).scene, inerter.load(LUMPED).scene
    assert {n: p.value for n, p in a.parameters.items()} == {n: p.value for n, p in b.parameters.items()}
    assert a.bodies == b.bodies


def test_a_run_that_stops_says_so_on_stderr_and_keeps_its_samples(tmp_path, capsys):
    """terminals_meet_2d's terminals meet at t = 1.1107 s (its closed form: the mass falls from
    rest onto the anchor, docs/hard_cases.md): status 3, one line on stderr naming the file, the
    time and the reason (the full report stays on stdout), and the CSV holds the samples to 1.11 s
    (every 0.01 s: 112 rows), all finite."""
    out = tmp_path / "out"
    assert main(["run", str(TERMINALS_MEET), "--out", str(out)]) == 3
    err = one_line(capsys, str(TERMINALS_MEET), "the run stopped before its stop time", "t = 1.1107",
                   "terminals O and P meet", str(out))
    assert "results up to t = 1.11 s" in err
    data = rows(out / "terminals_meet_2d.csv")
    assert len(data) == 112 and float(data[-1][0]) == pytest.approx(1.11)
    assert all(math.isfinite(float(x)) for row in data for x in row)


def test_compare_that_stops_says_so_in_one_line(tmp_path, capsys):
    assert main(["compare", str(TERMINALS_MEET), "--out", str(tmp_path)]) == 3
    one_line(capsys, str(TERMINALS_MEET), "corrected (and uncorrected, oracle): the run stopped", "meet")


def test_max_steps_exhausted(tmp_path, capsys):
    """max_steps = 50 of DOP853 on lumped_mass_2d (rtol 1e-10 takes about 50 steps per second):
    status 3, the reason names max_steps, the samples before the stop are kept and finite."""
    out = tmp_path / "out"
    assert main(["run", str(LUMPED), "--set", "experiment.max_steps=50", "--stop-time", "5", "--out", str(out)]) == 3
    one_line(capsys, str(LUMPED), "max_steps = 50")
    data = rows(out / "lumped_mass_2d.csv")
    assert 1 < len(data) < 1001
    assert all(math.isfinite(float(x)) for row in data for x in row)


@pytest.mark.parametrize("second, clash", [
    ('kind = "natural_frequency"', "natural_frequency"),
    ('kind = "peak"\nsignal = "C.r[1]"', "peak"),
    ('kind = "free_oscillation"\nsignal = "C.r[1]"\nprefix = "C_y"', "C_y_mean_offset"),
])
def test_two_metrics_whose_values_share_a_name(tmp_path, capsys, second, clash):
    """Two metrics giving a value of the same name (the same kind without prefixes, or a steady
    state's and a free oscillation's mean_offset under one prefix) overwrote one another silently
    in result.metrics and summary.json."""
    from conftest import TWO_BAR
    text = TWO_BAR.read_text() + '\n[[metrics]]\nkind = "peak"\nsignal = "C.r[2]"\n'
    scene = tmp_path / "scene.toml"
    scene.write_text(text + f"\n[[metrics]]\n{second}\n")
    assert main(["describe", str(scene)]) == 2
    one_line(capsys, str(scene), ".prefix", "name clash", repr(clash))


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_a_mechanism_at_a_change_point_stops_and_says_why(tmp_path, capsys, path):
    """tests/data/parallelogram_2d.toml turns at a constant crank rate θ̇0 (the loader's projection
    of the given velocities; no force acts and the coupler translates, so the kinetic energy
    ½(2(J + m/4) + m)θ̇² fixes θ̇) from θ = π/2 to the change point θ = π at t* = (π/2)/|θ̇0|
    (closed form), where all four pivots lie on a line. The run stops just before t* (status 3) and
    names the dependent joints; its samples up to there are kept and finite. It said only
    "Required step size is less than spacing between numbers" (numpy path); the compiled loop went
    on along the anti-parallelogram branch without a word."""
    _stops_at_the_change_point(tmp_path, capsys, ["--path", path])


@pytest.mark.parametrize("settings", [
    ("experiment.method=RK45",),
    ("experiment.method=RK4",),
    # steps that jump across t* (0.05 s, 0.04 rad of crank; the joints' rows are 5e-3 from dependent
    # at their ends): the orientation det(C_v(q₁) C_v(q₀)ᵀ) changes sign over the step
    ("experiment.method=RK4", "experiment.step=0.05"),
    ("experiment.rtol=1e-3", "experiment.atol=1e-6"),
])
def test_each_compiled_loop_stops_at_the_change_point(tmp_path, capsys, settings):
    """As above for the compiled RK45 and RK4 loops, and with steps long enough to jump across the
    change point (kernels.loop_watch, locate_crossing): the same stop, samples and line."""
    _stops_at_the_change_point(tmp_path, capsys, ["--path", "compiled"] + [a for s in settings for a in ("--set", s)])


@pytest.mark.parametrize("path", ["numpy", "compiled"])
@pytest.mark.parametrize("settings", [
    ("experiment.method=Radau",), ("experiment.method=BDF",), ("experiment.method=LSODA",),
    ("experiment.constraint=projection",)])
def test_scipys_integrators_stop_at_the_change_point(tmp_path, capsys, settings, path):
    """scipy's integrators (Radau, BDF, LSODA) and the projection treatment, on either path
    (simulation.StepMonitor): the same stop, samples and line as the compiled loops'. They went on
    across the change point along one branch or the other and reported the run completed."""
    _stops_at_the_change_point(tmp_path, capsys, ["--path", path] + [a for s in settings for a in ("--set", s)])


@pytest.mark.parametrize("settings", [("experiment.method=Radau",), ("experiment.constraint=projection",)])
def test_scipys_integrators_stop_at_the_spatial_change_point(tmp_path, capsys, settings):
    _stops_at_the_change_point(tmp_path, capsys, ["--path", "compiled"] + [a for s in settings for a in ("--set", s)],
                               "parallelogram_3d", rate=5)


@pytest.mark.parametrize("h", [0.0007, 0.003, 0.01, 0.037])
def test_a_cosim_step_fails_where_it_reaches_the_change_point(h):
    """Co-simulation steps of h on the compiled stepper (its DOP853 integration runs on across
    communication points, its steps of up to 0.03 s reaching past them): every step before the
    change point succeeds, and the one that fails holds t* (closed form, above) or ends within
    1e-3 s before it (the watch stops where the joints' rows are within 1e-4 of dependent, about
    1e-4 rad of crank before t*), saying so, and fails again from the same state when retried (an
    integrator step reaching it past a communication point is taken back, kernels._step_back)."""
    import inerter
    from conftest import ROOT
    from inerter.common.errors import SimulationError
    model = inerter.load(ROOT / "tests" / "data" / "parallelogram_2d.toml")
    t_star = (math.pi / 2) / abs(model.mechanism.v0[2])
    stepper = model.stepper(path="compiled")
    assert stepper.path == "compiled"
    t = 0.0
    while t < 2.0:
        try:
            stepper.step(t + h)
        except SimulationError as exc:
            failure = str(exc)
            break
        t += h
    else:
        pytest.fail("no step failed")
    assert t <= t_star < t + h + 1e-3, (t, t + h, t_star)
    assert "change point" in failure and "joints a, b, c, d" in failure
    with pytest.raises(SimulationError, match="change point"):
        stepper.step(t + h)


@pytest.mark.parametrize("method", ["DOP853", "RK4"])
def test_a_spatial_mechanism_at_a_change_point_stops_and_says_why(tmp_path, capsys, method):
    """tests/data/parallelogram_3d.toml, the parallelogram with spatial bodies (revolute joints about
    Z at the ground, spherical joints at the coupler): the same crank rate θ̇0 (ω_z, body frame =
    global about Z) and t* = (π/2)/|θ̇0|, the same stop on the 3D kernels."""
    _stops_at_the_change_point(tmp_path, capsys, ["--path", "compiled", "--set", f"experiment.method={method}"],
                               "parallelogram_3d", rate=5)


def _stops_at_the_change_point(tmp_path, capsys, args, name="parallelogram_2d", rate=2):
    """`rate`: the crank's angle rate's index in v0."""
    import inerter
    from conftest import ROOT
    scene = ROOT / "tests" / "data" / f"{name}.toml"
    mech = inerter.load(scene).mechanism
    t_star = (math.pi / 2) / abs(mech.v0[rate])
    out = tmp_path / "out"
    assert main(["run", str(scene), *args, "--out", str(out)]) == 3
    one_line(capsys, str(scene), "joints a, b, c, d", "change point")
    data = rows(out / f"{name}.csv")
    assert all(math.isfinite(float(x)) for row in data for x in row)
    assert t_star - 0.02 <= float(data[-1][0]) <= t_star


@pytest.mark.parametrize("method", ["DOP853", "RK4"])
def test_a_four_bar_passing_near_a_change_point_goes_on(method):
    """tests/data/fourbar_near_change_point_2d.toml, a crank-rocker (ground 1, crank 0.5, coupler 1,
    rocker 0.51: Grashof, the crank turns fully) whose four pivots come within a centimetre of a
    line at crank angle π: its joints' rows come near dependent (smallest/largest singular value of
    C_v below 0.05 at a sample) but never are, and the compiled run goes on through it to its stop
    time (crank angle π/2 to past 3π/2), as the oracle's run does (the numpy Mechanism's joints,
    code separate from the kernels' rows, element forces derived from L(q)), with the same
    samples (1e-6: both runs at rtol 1e-8, as the two paths were held before; RK4: the same fixed
    steps)."""
    import inerter
    import numpy as np
    from conftest import ROOT
    model = inerter.load(ROOT / "tests" / "data" / "fourbar_near_change_point_2d.toml")
    mech = model.mechanism
    fast = model.simulate(path="compiled", method=method, metrics=False)
    slow = model.oracle().simulate(method=method, metrics=False)
    assert fast.status == slow.status == "ok", (fast.message, slow.message)
    states = fast.run.states
    assert states[0][2] < math.pi < 1.5 * math.pi < states[-1][2]    # the crank turns on past angle π
    ratios = [np.linalg.svd(mech.constraints(y[:mech.nq], np.zeros(mech.n))[1], compute_uv=False) for y in states]
    assert min(sv[-1] / sv[0] for sv in ratios) < 0.05
    assert np.max(np.abs(states - slow.run.states)) < 1e-6


@pytest.mark.parametrize("path", ["numpy", "compiled"])
def test_a_stiff_spring_does_not_read_as_terminals_meeting(tmp_path, capsys, path):
    """double_pendulum_3d with k = 1e15 N/m between D and E (1.24 m apart at t = 0, their meeting
    limit 1e-6 of that): DOP853 needs steps of ~1e-11 s and runs out of max_steps = 2000. A trial
    step far too long for it has wild stages in which D and E meet; both paths try it again shorter
    (the compiled path used to stop at t = 0 saying the terminals meet "where they were 1.24 m
    apart")."""
    scene = SCENARIOS / "double_pendulum_3d.toml"
    assert main(["run", str(scene), "--set", "k=1e15", "--set", "experiment.max_steps=2000", "--stop-time", "0.2",
                 "--path", path, "--out", str(tmp_path)]) == 3
    err = one_line(capsys, str(scene), "the run stopped before its stop time")
    assert "meet" not in err and "max_steps = 2000" in err, err


@pytest.mark.parametrize("call", ["simulate", "stepper"])
def test_a_bad_setting_of_a_call_names_that_call(call):
    """A solver setting passed to `simulate()` or `stepper()` is refused naming the scene file, the
    call it was given to, the field, the value and what was expected (stepper() said simulate())."""
    import inerter
    from inerter.common.errors import SceneError
    model = inerter.load(LUMPED)
    with pytest.raises(SceneError) as refused:
        getattr(model, call)(method="x")
    text = str(refused.value)
    assert f"{call}()" in text and str(LUMPED.name) in text
    assert "experiment.method" in text and "'x'" in text and "DOP853" in text
