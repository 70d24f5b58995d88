"""Tests of inerter.scene.expressions: values, parameter ordering and error messages."""
import math

import pytest

from inerter.common.errors import SceneError
from inerter.scene.expressions import evaluate, evaluate_parameters, free_names, parameter_meta

SOURCE = "scenes/test.toml"
FIELD = "bodies.arm.length"
EXPECTED_EXPRESSION = "an arithmetic expression of numbers, parameters and sqrt, sin, cos"


# ------------------------------------------------------------------------ values


@pytest.mark.parametrize(
    "text, value",
    [
        ("sqrt(La^2+Lb^2)", math.sqrt(2.0)),
        ("sqrt(La**2 + Lb**2)", math.sqrt(2.0)),
        ("2^3^2", 2.0**9),  # right-associative, like Python's **
        ("-La^2", -1.0),  # power binds tighter than unary minus
        ("2^-1", 0.5),
        ("1 + 2*3 - 4/8", 6.5),
        ("(1 + 2) * 3", 9.0),
        ("+La - -Lb", 2.0),
        ("pi", math.pi),
        ("e", math.e),
        ("sin(pi/6)", math.sin(math.pi / 6)),
        ("cos(0) + tan(0)", 1.0),
        ("asin(1) + acos(1) + atan(1)", math.pi / 2 + math.pi / 4),
        ("atan2(1, -1)", 3 * math.pi / 4),
        ("exp(1) + log(e) + log10(1000)", math.e + 1.0 + 3.0),
        ("abs(-3) + min(4, 2, 7) + max(1, 5)", 10.0),
        ("hypot(3, 4)", 5.0),
        ("deg2rad(180) + rad(90)", 1.5 * math.pi),
        ("1e-3 * 2", 0.002),
        ("(-2)^3", -8.0),
    ],
)
def test_values(text, value):
    result = evaluate(text, {"La": 1.0, "Lb": 1.0}, SOURCE, FIELD)
    assert type(result) is float
    assert result == pytest.approx(value, rel=1e-15, abs=1e-15)


def test_numbers_pass_through_as_float():
    assert evaluate(3, {}, SOURCE, FIELD) == 3.0
    assert type(evaluate(3, {}, SOURCE, FIELD)) is float
    assert evaluate(2.5, {}, SOURCE, FIELD) == 2.5


def test_free_names():
    assert free_names("sqrt(La^2 + Lb^2) * pi + e", SOURCE, FIELD) == {"La", "Lb"}
    assert free_names(1.5, SOURCE, FIELD) == set()


def test_parameters_in_any_order():
    raw = {
        "L": "sqrt(La^2 + Lb^2)",
        "Lb": {"value": "La / 2", "unit": "m", "description": "lower link"},
        "La": 2,
        "m": {"value": 1.5, "unit": "kg"},
    }
    values = evaluate_parameters(raw, SOURCE)
    assert list(values) == ["L", "Lb", "La", "m"]  # order of the file
    assert values == {"L": math.sqrt(5.0), "Lb": 1.0, "La": 2.0, "m": 1.5}
    assert all(type(v) is float for v in values.values())


def test_fixed_overrides():
    raw = {"L": "2*La", "La": 1.0, "Lb": "L + 1"}
    values = evaluate_parameters(raw, SOURCE, fixed={"La": 3.0})
    assert values == {"L": 6.0, "La": 3.0, "Lb": 7.0}
    # A fixed parameter no longer depends on anything: this would be a cycle otherwise.
    values = evaluate_parameters({"a": "b + 1", "b": "a + 1"}, SOURCE, fixed={"a": 0.0})
    assert values == {"a": 0.0, "b": 1.0}


def test_parameter_meta():
    raw = {"La": {"value": 1, "unit": "m", "description": "upper link"}, "k": 5, "c": {"value": 2}}
    assert parameter_meta(raw) == {
        "La": {"unit": "m", "description": "upper link"},
        "k": {"unit": "1", "description": ""},
        "c": {"unit": "1", "description": ""},
    }


# ------------------------------------------------------------------------ errors


def check_error(excinfo, field, text, expected, problem=None):
    """The message names source, field, the offending text and the expectation."""
    message = str(excinfo.value)
    assert message.startswith(f"{SOURCE}: {field}: "), message
    assert text in message, message
    assert expected in message, message
    if problem is not None:
        assert problem in message, message
    assert isinstance(excinfo.value, SceneError)


@pytest.mark.parametrize(
    "text, problem, expected",
    [
        # unknown name; the expectation lists the known parameters
        ("La + xyz", "unknown name 'xyz'", "one of the parameters La, Lb"),
        # syntax error
        ("2 * (La + ", "does not parse", EXPECTED_EXPRESSION),
        # attribute access (a classic sandbox escape)
        ("().__class__", "attribute access", EXPECTED_EXPRESSION),
        # calling something not on the whitelist
        ("__import__('os')", "'__import__' is not an allowed function", EXPECTED_EXPRESSION),
        ("lambda: 1", "a lambda is not allowed", EXPECTED_EXPRESSION),
        ("'abc'", "a string literal is not allowed", EXPECTED_EXPRESSION),
        ("True + 1", "a boolean is not allowed", EXPECTED_EXPRESSION),
        ("La < Lb", "a comparison is not allowed", EXPECTED_EXPRESSION),
        ("max(1, key=2)", "keyword arguments are not allowed", EXPECTED_EXPRESSION),
        ("La[0]", "subscripting is not allowed", EXPECTED_EXPRESSION),
        ("7 % 2", "the operator '%' is not allowed", EXPECTED_EXPRESSION),
        ("sqrt", "'sqrt' is a function", EXPECTED_EXPRESSION),
        ("sqrt(1, 2)", "sqrt() takes 1 argument, got 2", EXPECTED_EXPRESSION),
        ("[La, Lb]", "a list is not allowed", EXPECTED_EXPRESSION),
        ("", "is empty", EXPECTED_EXPRESSION),
        # numerical failures
        ("1 / (La - Lb)", "division by zero", "finite value"),
        ("0^-1", "division by zero", "finite value"),
        ("1e308 * 10", "evaluates to inf", "finite value"),
        ("1e999", "evaluates to inf", "finite value"),
        ("exp(1000)", "overflow", "finite value"),
        ("sqrt(-1)", "out of the domain of sqrt", "finite value"),
        ("(-8)^(1/3)", "non-integer power", "finite value"),
    ],
)
def test_bad_expressions(text, problem, expected):
    with pytest.raises(SceneError) as excinfo:
        evaluate(text, {"La": 1.0, "Lb": 1.0}, SOURCE, FIELD)
    check_error(excinfo, FIELD, text, expected, problem)


def test_syntax_error_is_caught_by_free_names_too():
    with pytest.raises(SceneError) as excinfo:
        free_names("La +* 2", SOURCE, FIELD)
    check_error(excinfo, FIELD, "La +* 2", EXPECTED_EXPRESSION, "does not parse")


@pytest.mark.parametrize(
    "value, problem",
    [(True, "a boolean is not a number"), (None, "is not a number"), ([1], "is not a number")],
)
def test_bad_literal_values(value, problem):
    with pytest.raises(SceneError) as excinfo:
        evaluate(value, {}, SOURCE, FIELD)
    check_error(excinfo, FIELD, repr(value), "a number or an expression string", problem)


def test_non_finite_number():
    with pytest.raises(SceneError) as excinfo:
        evaluate(float("nan"), {}, SOURCE, FIELD)
    check_error(excinfo, FIELD, "nan", "a finite number", "is not finite")


def test_unknown_name_lists_known_names_sorted_and_truncated():
    names = {f"p{i:02d}": 1.0 for i in range(30)}
    with pytest.raises(SceneError) as excinfo:
        evaluate("p00 + q", names, SOURCE, FIELD)
    message = str(excinfo.value)
    assert "unknown name 'q'" in message
    assert "p00, p01, p02" in message and "(10 more)" in message and "p29" not in message


def test_cycle():
    raw = {"a": "b + 1", "b": {"value": "c * 2"}, "c": "a - 1", "d": 4}
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters(raw, SOURCE)
    check_error(
        excinfo, "parameters.a", "b + 1", "parameters that do not depend on themselves",
        "circular definition a -> b -> c -> a",
    )


def test_self_reference():
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters({"k": {"value": "2*k"}}, SOURCE)
    check_error(excinfo, "parameters.k.value", "2*k", "do not depend on themselves", "k -> k")


def test_bad_parameter_table_key():
    raw = {"La": {"value": 1.0, "units": "m"}}
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters(raw, SOURCE)
    check_error(excinfo, "parameters.La.units", "'m'", "value, unit and description", "unknown key 'units'")


def test_parameter_table_without_value():
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters({"La": {"unit": "m"}}, SOURCE)
    check_error(excinfo, "parameters.La", "'unit': 'm'", "a table with 'value'", "missing 'value'")


@pytest.mark.parametrize(
    "name, problem",
    [("sqrt", "function 'sqrt'"), ("pi", "constant 'pi'"), ("2L", "invalid parameter name"),
     ("a.b", "invalid parameter name"), ("lambda", "keyword")],
)
def test_bad_parameter_names(name, problem):
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters({name: 1.0}, SOURCE)
    check_error(excinfo, f"parameters.{name}", repr(name), "a name of ASCII letters", problem)


def test_errors_in_parameters_name_their_field():
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters({"a": 1.0, "b": {"value": "a + nope"}}, SOURCE, prefix="params")
    check_error(excinfo, "params.b.value", "a + nope", "one of the parameters a, b", "unknown name 'nope'")
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters({"a": True}, SOURCE)
    check_error(excinfo, "parameters.a", "True", "a number", "a boolean is not a number")


def test_fixed_unknown_parameter():
    with pytest.raises(SceneError) as excinfo:
        evaluate_parameters({"a": 1.0}, SOURCE, fixed={"b": 2.0})
    check_error(excinfo, "parameters.b", "2.0", "one of the parameters a", "no parameter 'b'")
