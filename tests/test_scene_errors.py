"""Bad scene input: each kind gives the project's own SceneError naming the file, the field path,
the offending value and what was expected; never a traceback of another type."""
from __future__ import annotations

import re
import tomllib

import pytest

import inerter
from inerter.cli import main as cli_main
from inerter.common.errors import SceneError
from conftest import LUMPED, TWO_BAR

BASE = TWO_BAR.read_text()


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def expect_error(path, field, value_fragment, expected_fragment, **overrides):
    with pytest.raises(SceneError) as info:
        inerter.load(path, **overrides)
    msg = str(info.value)
    assert str(path) in msg or info.value.source in ("--set",), msg
    assert field in msg, msg
    assert value_fragment in msg, msg
    assert expected_fragment in msg, msg
    return msg


CASES = [
    # (id, text transformation, field, value fragment, expectation fragment)
    ("missing_field", lambda s: s.replace('mass = "M2"\n', "", 1), "bodies.bar2.mass", "None", "required"),
    ("unknown_field", lambda s: s.replace('mass = "M1"', 'mass = "M1"\ncolour = "red"', 1),
     "bodies.bar1.colour", "red", "one of"),
    ("wrong_type", lambda s: s.replace('k = "k"', 'k = true', 1), "elements.spring.k", "True", "number"),
    ("negative_mass", lambda s: s.replace('mass = "M1"', 'mass = -1', 1), "bodies.bar1.mass", "-1", "> 0"),
    ("negative_inertia", lambda s: s.replace('inertia = "J2"', 'inertia = "-J2"', 1), "bodies.bar2.inertia",
     "-0.083", "≥ 0"),
    ("negative_b", lambda s: s.replace('b = "b"', 'b = "-b"', 1), "elements.inerter.b", "-10", "≥ 0"),
    ("unknown_point", lambda s: s.replace('between = ["D", "E"]\nc', 'between = ["D", "Q"]\nc', 1),
     "elements.damper.between[2]", "Q", "a point of the scene"),
    ("unknown_body", lambda s: s.replace('bodies = ["ground", "bar1"]', 'bodies = ["ground", "bar9"]', 1),
     "elements.kr.bodies[2]", "bar9", "a body of the scene"),
    ("duplicate_point", lambda s: s.replace("C = [0.5, 0]", "D = [0.5, 0]", 1), "bodies.bar2.points.D", "D",
     "used once"),
    ("unknown_effect", lambda s: s.replace("centripetal = true", "centripetal = true\ncoriolis = true", 1),
     "effects.coriolis", "True", "centripetal"),
    ("bad_expression", lambda s: s.replace('amplitude = "Fa"', 'amplitude = "Fa *"', 1),
     "forces.Fa.amplitude", "Fa *", "expression"),
    ("unknown_name", lambda s: s.replace('amplitude = "Fa"', 'amplitude = "Fb"', 1),
     "forces.Fa.amplitude", "Fb", "Fa"),
    ("nan", lambda s: s.replace('amplitude = "Fa"', 'amplitude = nan', 1), "forces.Fa.amplitude", "nan", "finite"),
    ("inf_parameter", lambda s: s.replace('value = 8.0,', 'value = inf,', 1), "parameters.Fa", "inf", "finite"),
    # D moved onto B (end of body 1) and E onto B2 (start of body 2): the D-E elements have no length
    ("coincident_terminals", lambda s: s.replace("E = [0.25, 0]", "E = [-0.5, 0]", 1).replace(
        "D = [0.25, 0]", "D = [0.5, 0]", 1),
     "elements.spring.between", "D", "apart"),
    ("violated_joint", lambda s: s.replace('angle = "th2"', 'angle = "th2 + 0.1"', 1), "joints.B", "violated",
     "satisfies the joint"),
    ("unknown_method", lambda s: s.replace('method = "DOP853"', 'method = "Euler"', 1), "experiment.method",
     "Euler", "DOP853"),
    ("bad_toml", lambda s: s + "\n[[[broken\n", "(file)", "", "valid TOML"),
    ("unknown_section", lambda s: s + "\n[sensors]\nx = 1\n", "sensors", "", "one of"),
    ("unknown_element_type", lambda s: s.replace('type = "damper"', 'type = "dashpot"', 1), "elements.damper.type",
     "dashpot", "inerter"),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_scene(tmp_path, case):
    _, transform, field, value, expected = case
    text = transform(BASE)
    assert text != BASE, "the transformation must change the scene"
    path = write(tmp_path, text)
    expect_error(path, field, value, expected)


def test_missing_file(tmp_path):
    with pytest.raises(SceneError, match="file not found"):
        inerter.load(tmp_path / "nope.toml")


@pytest.mark.parametrize("overrides, fragment", [
    ({"bb": 3.0}, "unknown name"),
    ({"b": "ten"}, "unknown name 'ten'"),
    ({"b": True}, "a boolean is not a number"),
    ({"b": -1.0}, "≥ 0"),
    ({"effects.coriolis": True}, "unknown effect"),
    ({"effects.centripetal": "yes"}, "true or false"),
    ({"experiment.solver": "RK4"}, "unknown field"),
])
def test_bad_overrides(overrides, fragment):
    with pytest.raises(SceneError) as info:
        inerter.load(TWO_BAR, **overrides)
    assert fragment in str(info.value)
    name = next(iter(overrides))
    assert name.split(".")[-1] in str(info.value)


def test_cli_reports_scene_errors_without_traceback(tmp_path, capsys):
    code = cli_main(["run", str(TWO_BAR), "--set", "b=-5", "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("inerter: error: ")
    assert "elements.inerter.b" in err and "-5" in err and "Traceback" not in err


def test_every_shipped_scene_is_valid():
    for path in sorted(TWO_BAR.parent.glob("*.toml")):
        with open(path, "rb") as fh:
            tomllib.load(fh)
        model = inerter.load(path)
        assert model.terms()


@pytest.mark.parametrize("kwargs, field", [
    (dict(method="Foo"), "method"), (dict(constraint="x"), "constraint"), (dict(stop_time=-1.0), "stop_time"),
    (dict(stop_time=float("nan")), "stop_time"), (dict(rtol=0.0), "rtol"), (dict(output_interval=0.0), "output_interval"),
    (dict(output_interval=30.0), "output_interval"),
])
def test_a_bad_simulate_argument_names_itself(kwargs, field):
    """From Python as from the command line and the scene file: the same check (the scene reader's)
    names the file, simulate(), the field, its value and what was expected."""
    model = inerter.load(LUMPED)
    with pytest.raises(inerter.SceneError) as info:
        model.simulate(**kwargs)
    assert info.value.field == f"experiment.{field}"
    assert str(info.value).startswith(f"{LUMPED}: simulate(): experiment.{field}: ")


def test_a_model_reads_each_set_of_simulate_settings_as_a_fresh_load_would():
    """The model keeps the experiment read for each set of overrides (Model.settings): asked again,
    it gives what a fresh model reads; a value equal to a kept one but of another type (True == 1
    as a key) is read, and refused, for itself; a refused value is refused again."""
    model = inerter.load(LUMPED)
    for kwargs in (dict(stop_time=1), dict(stop_time=1.0, rtol=1e-8), dict(stop_time=1)):
        assert model.settings(**kwargs) == inerter.load(LUMPED).settings(**kwargs)
    for _ in range(2):
        with pytest.raises(inerter.SceneError, match="experiment.stop_time: a boolean is not a number"):
            model.settings(stop_time=True)
        with pytest.raises(inerter.SceneError, match="experiment.rtol"):
            model.settings(rtol=0.0)


def test_a_harmonics_metric_takes_no_reference(tmp_path):
    """`harmonics` gives the mean and amplitude of its signal over `period_of`'s periods, with no
    reference (docs/scene_format.md, [[metrics]]): a `reference` there would be silently unused, so
    it is an unknown field, as any field a table does not take."""
    text = LUMPED.read_text().replace('period_of = "P.r[2]"', 'period_of = "P.r[2]"\nreference = 0', 1)
    assert text != LUMPED.read_text()
    msg = expect_error(write(tmp_path, text), "metrics[3].reference", "0", "one of: kind, period_of, prefix, signal")
    assert "unknown field" in msg
