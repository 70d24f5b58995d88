"""Ground motion as studies give it: analytic terms (sine bursts and their sums), PEER NGA .AT2
records besides CSV, several single-axis records, and the end-of-record policy.

References: the same burst sampled as a record converges on the analytic one as the record's
linear interpolation does (error ∝ Δt², the test halves Δt); an .AT2 record and its CSV twin in
m/s² (values × 9.80665) give the same run to round-off; two single-axis records equal the
two-column CSV of the same samples; on analytic terms both paths follow an explicit model of the
oscillator written in the test (the term's value is one function, scene.ground_motion.burst, run
compiled and uncompiled, so the two paths are no check of each other).
"""
import math
import warnings

import numpy as np
import pytest

import inerter
from inerter.common.errors import SceneError
from inerter.scene.ground_motion import STANDARD_GRAVITY, read_at2

OSCILLATOR = """
[scene]
name = "{name}"
dimension = 2

[effects]
ground_acceleration = {motion}

[ground.points]
S0 = [0, 1]
G0 = [-1, 0]

[bodies.mass]
mass = 2.0
inertia = 1.0
position = [0, 1]
points = {{ J = [0, 0], E = [0, -1] }}

[joints.slide]
type = "prismatic"
between = ["S0", "J"]
axis = [1, 0]

[elements.spring]
type = "spring"
between = ["G0", "E"]
k = 80.0

[elements.damper]
type = "damper"
between = ["G0", "E"]
c = 0.4

[experiment]
stop_time = 6.0
output_interval = 0.01
method = "DOP853"
rtol = 1e-11
atol = 1e-13
"""
BURST = dict(amplitude=1.5, frequency=1.25, phase=0.0, start=0.5, stop=2.9)      # three whole cycles


def _model(tmp_path, name, motion):
    path = tmp_path / f"{name}.toml"
    path.write_text(OSCILLATOR.format(name=name, motion=motion))
    return inerter.load(path)


def _x(model, **kw):
    r = model.simulate(metrics=False, **kw)
    assert r.status == "ok", r.message
    return r, r["E.r[1]"] - r["E.r[1]"][0]


def _burst(t):
    b = BURST
    inside = (t >= b["start"]) & (t < b["stop"])
    return np.where(inside, b["amplitude"] * np.sin(2 * np.pi * b["frequency"] * (t - b["start"]) + b["phase"]), 0.0)


def _analytic(tmp_path):
    terms = ", ".join(f"{k} = {v}" for k, v in BURST.items())
    return _model(tmp_path, "burst", f"{{ terms = [{{ axis = 1, {terms} }}] }}")


def _sampled(tmp_path, dt):
    t = np.round(np.arange(0.0, 6.0 + dt / 2, dt), 12)
    np.savetxt(tmp_path / f"burst_{dt}.csv", np.column_stack((t, _burst(t), np.zeros_like(t))), delimiter=",")
    return _model(tmp_path, f"sampled_{int(round(1 / dt))}", f'{{ file = "burst_{dt}.csv" }}')


def test_a_burst_written_analytically_is_its_sampled_records_limit(tmp_path):
    _, exact = _x(_analytic(tmp_path))
    assert np.max(np.abs(exact)) > 1e-3
    errors = [np.max(np.abs(_x(_sampled(tmp_path, dt))[1] - exact)) for dt in (0.01, 0.005)]
    # the record's interpolation error is at most Δt²/8·(2πf)²·A = 1.2e-3 m/s² of the burst's 1.5
    assert errors[0] < 2e-3 * np.max(np.abs(exact))
    assert 3.0 < errors[0] / errors[1] < 5.0           # linear interpolation: error ∝ Δt²


def _oscillator_reference(t_eval, m=2.0, k=80.0, c=0.4):
    """Explicit model of OSCILLATOR under the burst, independent of the package: the slider's
    displacement x relative to the ground (the spring and damper lie along the slide, L = 1 + x),
    m ẍ + c ẋ + k x = −m a_g(t), a_g = _burst (the term written here from its definition), from
    rest; scipy's DOP853 at rtol 1e-13, atol 1e-16, restarted at the burst's start and stop (kinks
    of the right-hand side)."""
    from scipy.integrate import solve_ivp
    y, out = [0.0, 0.0], []
    edges = [0.0, BURST["start"], BURST["stop"], float(t_eval[-1])]
    for a, b in zip(edges[:-1], edges[1:]):
        inside = t_eval[(t_eval >= a) & ((t_eval < b) | (b == edges[-1]))]
        sol = solve_ivp(lambda t, s: [s[1], (-c * s[1] - k * s[0]) / m - _burst(np.array([t]))[0]], (a, b), y,
                        method="DOP853", rtol=1e-13, atol=1e-16, dense_output=True)
        assert sol.status == 0, sol.message
        out.append(sol.sol(inside)[0])
        y = sol.y[:, -1]
    return np.concatenate(out)


@pytest.mark.parametrize("path", ["compiled", "numpy"])
def test_analytic_terms_give_the_explicit_models_run(tmp_path, path):
    """Reference: the explicit model of the oscillator under the burst (_oscillator_reference).
    Each path (the engine, and the numpy path, which evaluates the same term function,
    scene.ground_motion.burst, uncompiled) within 1e-9 of the largest |x| at every sample (the
    bound the two paths were held to against each other; at the scene's rtol 1e-11 each run's
    global error is at most ~N·rtol·|x| over its N = 156 steps; measured 3.2e-11 on either path)."""
    model = _analytic(tmp_path)
    r, x = _x(model, path=path)
    assert r.run.extra.get("path", "numpy") == path
    reference = _oscillator_reference(r.time)
    assert np.max(np.abs(x - reference)) <= 1e-9 * np.max(np.abs(reference)), np.max(np.abs(x - reference))


def test_a_term_starting_off_zero_is_a_jump_and_on_zero_a_kink(tmp_path):
    on_zero = _analytic(tmp_path).mechanism
    assert 0.5 in on_zero.kinks and 0.5 not in on_zero.discontinuities
    phased = _model(tmp_path, "phased", "{ terms = [{ axis = 1, amplitude = 1.0, frequency = 1.0, phase = 0.5, "
                                        "start = 0.25, stop = 1.0 }] }").mechanism
    assert 0.25 in phased.discontinuities and 1.0 in phased.discontinuities


def _write_at2(path, dt, values_g):
    lines = ["PEER NGA STRONG MOTION DATABASE RECORD", "synthetic test record, not an earthquake",
             "ACCELERATION TIME SERIES IN UNITS OF G", f"NPTS= {len(values_g):6d}, DT= {dt:.4f} SEC"]
    rows = [" ".join(f"{v: .10E}" for v in values_g[i:i + 5]) for i in range(0, len(values_g), 5)]
    path.write_text("\n".join(lines + rows) + "\n")


def test_an_at2_record_and_its_csv_twin_give_the_same_run(tmp_path):
    dt = 0.01
    t = np.arange(0, 401) * dt
    g_values = np.array([float(f"{v:.10E}") for v in 0.2 * np.sin(2 * np.pi * 1.7 * t) * np.exp(-t)])
    _write_at2(tmp_path / "rec.AT2", dt, g_values)
    times, read = read_at2(tmp_path / "rec.AT2")
    assert np.array_equal(read, g_values) and np.allclose(times, t, rtol=0, atol=1e-12)
    np.savetxt(tmp_path / "rec.csv", np.column_stack((times, STANDARD_GRAVITY * read, np.zeros_like(t))),
               delimiter=",", fmt="%.17g")
    _, from_at2 = _x(_model(tmp_path, "at2", '{ file = "rec.AT2", axis = 1 }'))
    _, from_csv = _x(_model(tmp_path, "csv", '{ file = "rec.csv" }'))
    assert np.max(np.abs(from_at2)) > 1e-4
    assert np.max(np.abs(from_at2 - from_csv)) <= 1e-15
    np.savetxt(tmp_path / "rec_g.csv", np.column_stack((times, read)), delimiter=",", fmt="%.17g")
    _, in_g = _x(_model(tmp_path, "csv_g", '{ records = [{ file = "rec_g.csv", axis = 1, unit = "g" }] }'))
    assert np.max(np.abs(in_g - from_csv)) <= 1e-15


def test_two_single_axis_records_equal_the_two_column_csv(tmp_path):
    t = np.arange(0, 301) * 0.01
    ax, ay = 0.5 * np.sin(3 * t) * (t < 2.5), 0.3 * np.cos(2 * t) * t * (t < 2.5)
    np.savetxt(tmp_path / "both.csv", np.column_stack((t, ax, ay)), delimiter=",", fmt="%.17g")
    np.savetxt(tmp_path / "x.csv", np.column_stack((t, ax)), delimiter=",", fmt="%.17g")
    np.savetxt(tmp_path / "y.csv", np.column_stack((t, ay)), delimiter=",", fmt="%.17g")
    a = _model(tmp_path, "both", '{ file = "both.csv" }')
    b = _model(tmp_path, "split", '{ records = [{ file = "x.csv", axis = 1 }, { file = "y.csv", axis = 2 }] }')
    for s in (0.3, 1.7, 2.49, 2.6):
        assert np.array_equal(a.mechanism.ground_motion.acceleration(s), b.mechanism.ground_motion.acceleration(s))
    assert np.array_equal(_x(a)[1], _x(b)[1])


def test_a_record_that_does_not_end_at_rest_is_warned_about(tmp_path):
    t = np.arange(0, 101) * 0.01
    np.savetxt(tmp_path / "open.csv", np.column_stack((t, np.full_like(t, 0.2), 0 * t)), delimiter=",")
    model = _model(tmp_path, "open", '{ file = "open.csv" }')
    assert len(model.scene.warnings) == 1 and "steps to zero" in model.scene.warnings[0]
    assert 1.0 in model.mechanism.discontinuities
    r = model.simulate(stop_time=1.5, metrics=False)
    assert r.summary()["warnings"] == model.scene.warnings
    quiet = _analytic(tmp_path)
    assert quiet.scene.warnings == []


def test_a_record_that_does_not_end_at_rest_is_not_warned_about_by_a_run_ending_before_it(tmp_path):
    """The step to zero at the record's end (1 s) is never reached by a run that stops at 0.8 s or
    at 1 s itself: its result does not warn of it (summary.json and `inerter run` print
    Result.warnings); one running on past it does (the test above)."""
    t = np.arange(0, 101) * 0.01
    np.savetxt(tmp_path / "open.csv", np.column_stack((t, np.full_like(t, 0.2), 0 * t)), delimiter=",")
    model = _model(tmp_path, "open", '{ file = "open.csv" }')
    for stop in (0.8, 1.0):
        r = model.simulate(stop_time=stop, metrics=False)
        assert r.status == "ok" and r.warnings == [] and r.summary()["warnings"] == []
    assert model.simulate(stop_time=1.2, metrics=False).warnings == model.scene.warnings


@pytest.mark.parametrize("motion, field", [
    ('{ file = "bad.AT2" }', "effects.ground_acceleration.file"),
    ('{ terms = [{ axis = 3, amplitude = 1.0, frequency = 1.0 }] }', "effects.ground_acceleration.terms[0].axis"),
    ('{ terms = [{ axis = 1, amplitude = 1.0, frequency = 1.0, start = 2.0, stop = 1.0 }] }',
     "effects.ground_acceleration.terms[0].stop"),
    ('{ file = "x.AT2", unit = "m/s2" }', "effects.ground_acceleration.unit"),
    ('{ amplitude = [1, 0], frequency = 1.0, terms = [{ axis = 1, amplitude = 1.0, frequency = 1.0 }] }',
     "effects.ground_acceleration"),
])
def test_bad_ground_motion_is_one_error_naming_the_field(tmp_path, motion, field):
    (tmp_path / "bad.AT2").write_text("header\nheader\nheader\nno sizes here\n0.1 0.2\n")
    with pytest.raises(SceneError) as err:
        _model(tmp_path, "bad", motion)
    assert f": {field}:" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("text, problem", [
    ("# t, a\n0,0\n\n# pause\n0.1,abc\n", "(line 5, column 2: 'abc' is not a number)"),
    ("0,0\n0.1,1\n\n0.2\n", "(line 4: 1 columns, the first row has 2)"),
    ("# t, a\n0,0\n0.2,1\n# back\n0.1,1\n", "time not increasing (line 5: t = 0.1 s after 0.2 s)"),
    ("0,0\n0.1,1\n0.1,2\n", "time not increasing (line 3: t = 0.1 s after 0.1 s)"),
    ("0,0\n# x\n0.1,nan\n0.2,0\n", "wrong value (line 3, column 2: nan)"),
    ("0,0\n0.1,1e300\n0.2,0\n", "wrong value (line 2, column 2: 1e+300)"),
    ("# nothing\n", "wrong shape (no rows)"),
    ("0,0\n", "wrong shape (1 row of 2 columns)"),
])
def test_a_malformed_record_is_one_error_naming_the_file_and_its_line(tmp_path, text, problem):
    """A CSV record's error names the scene's field, the record file and the line of the file that
    is wrong (numpy's own message counted data rows, and several problems named no row); a value
    above the magnitude limit of every scene value (1e15, SI) is refused there, not left to stop
    the integrator at t = 0; an empty file is that error alone (numpy's warning is not printed)."""
    (tmp_path / "rec.csv").write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(SceneError) as err:
            _model(tmp_path, "bad", '{ file = "rec.csv", axis = 1 }')
    message = str(err.value)
    assert ": effects.ground_acceleration.file: " in message and "\n" not in message
    assert problem in message and str(tmp_path / "rec.csv") in message, message


AT2_HEADER = "PEER NGA STRONG MOTION DATABASE RECORD\nsynthetic\nACCELERATION TIME SERIES IN UNITS OF G\n"


@pytest.mark.parametrize("body, problem", [
    ("NPTS=  7, DT= .01 SEC\n0.1 0.2 0.3\n0.4 abc 0.6\n0.7\n",
     "unreadable (line 6: 'abc' (value 5 of NPTS) is not a number)"),
    ("NPTS=  7, DT= .01 SEC\n0.1 0.2 0.3\n\n0.4 0.5\n", "unreadable (line 7: the file ends after 5 values, "
                                                         "expected NPTS = 7 (line 4))"),
    ("NPTS=  4, DT= .01 SEC\n0.1 0.2 0.3\n0.4 0.5\n", "unreadable (line 6: '0.5' is value 5, expected NPTS = 4 "
                                                      "values (line 4))"),
    ("NPTS=  4, DT= .01 SEC\n0.1 0.2\n\n0.3 nan\n", "wrong value (line 7, value 4 of NPTS: nan g)"),
    ("NPTS=  4, DT= .01 SEC\n0.1 inf 0 0\n", "wrong value (line 5, value 2 of NPTS: inf g)"),
    ("NPTS=  4, DT= .0.1 SEC\n0.1 0.2 0.3 0.4\n", "unreadable (line 4: DT = '.0.1' is not a number)"),
    ("NPTS=  4 DT .01\n0.1 0.2 0.3 0.4\n", "unreadable (line 4: 'NPTS=  4 DT .01', expected the fourth header"),
    ("NPTS=  1, DT= .01 SEC\n0.1\n", "unreadable (line 4: NPTS = 1 and DT = 0.01, expected at least 2 points"),
])
def test_a_malformed_at2_record_is_one_error_naming_the_file_and_its_line(tmp_path, body, problem):
    """A PEER .AT2 record's error names the scene's field, the record file and the line of the file
    that is wrong, as a CSV record's does (the reference: the line counted by hand in each text,
    the header's four lines first); it named no line before (numpy's 'could not convert string to
    float', 'the header gives NPTS = 7 but the file holds 5 values', 'a value is not finite')."""
    (tmp_path / "rec.AT2").write_text(AT2_HEADER + body)
    with pytest.raises(SceneError) as err:
        _model(tmp_path, "bad", '{ file = "rec.AT2", axis = 1 }')
    message = str(err.value)
    assert ": effects.ground_acceleration.file: " in message and "\n" not in message
    assert problem in message and str(tmp_path / "rec.AT2") in message, message


def test_a_record_value_above_the_magnitude_limit_in_si_is_refused(tmp_path):
    """The limit of every scene value, 1e15 in SI units, holds for a record's accelerations after
    their conversion from g (a CSV with unit = "g", a PEER .AT2): 2e14 g is 2.0e15 m/s², refused
    naming the value; 1e14 g (9.8e14 m/s²) is read."""
    (tmp_path / "big.AT2").write_text("PEER\nx\nACCELERATION IN G\nNPTS=  3, DT= .01 SEC\n0.1 2e14 0.0\n")
    (tmp_path / "big.csv").write_text("0,0\n0.01,2e14\n0.02,0\n")
    (tmp_path / "fine.csv").write_text("0,0\n0.01,1e14\n0.02,0\n")
    for motion, problem in (('{ file = "big.AT2", axis = 1 }', "wrong value (line 5, value 2 of NPTS: 200000000000000.0 g)"),
                            ('{ file = "big.csv", axis = 1, unit = "g" }', "wrong value (line 2, column 2: 200000000000000.0)")):
        with pytest.raises(SceneError) as err:
            _model(tmp_path, "big", motion)
        assert ": effects.ground_acceleration.file: " in str(err.value) and problem in str(err.value), str(err.value)
    _model(tmp_path, "fine", '{ file = "fine.csv", axis = 1, unit = "g" }')
