"""A unit written in a field that takes none (``length = "1200 mm"``, ``mass = { value = 5, unit =
"kg" }`` outside [parameters]): fields are SI, units belong to parameters. The error says so and
shows the parameter to write, through the scene reader and the command line alike."""
from __future__ import annotations

import pytest

import inerter
from inerter.cli import main
from inerter.common.errors import SceneError
from inerter.scene.expressions import evaluate
from conftest import LUMPED, one_line_error

SOURCE, FIELD = "scenes/test.toml", "elements.spring.length"


@pytest.mark.parametrize("value, problem, shown, number, unit", [
    ("1200 mm", "a unit in a value ('mm')", "'1200 mm'", "1200", "mm"),
    ("1.5e3mm", "a unit in a value ('mm')", "'1.5e3mm'", "1.5e3", "mm"),
    ("-2 kN/m", "a unit in a value ('kN/m')", "'-2 kN/m'", "-2", "kN/m"),
    ({"value": 1200, "unit": "mm"}, "a value with a unit outside [parameters]", "{'value': 1200, 'unit': 'mm'}",
     "1200", "mm"),
])
def test_a_unit_in_a_field_names_the_parameter_to_write(value, problem, shown, number, unit):
    with pytest.raises(SceneError) as caught:
        evaluate(value, {}, SOURCE, FIELD, unit="m")
    message = str(caught.value)
    assert message.startswith(f"{SOURCE}: {FIELD}: {problem} (got {shown}; expected a number in SI units"), message
    assert f'name = {{ value = {number}, unit = "{unit}" }} in [parameters], then "name" here)' in message


@pytest.mark.parametrize("text", ["2 pi", "La +* 2", "3 furlongs"])
def test_text_that_is_no_number_and_unit_still_does_not_parse(text):
    """A word after a number that is no unit (a constant, a typo) keeps the parser's message."""
    with pytest.raises(SceneError, match=r"does not parse"):
        evaluate(text, {"La": 1.0}, SOURCE, FIELD)


def test_the_command_line_and_load_say_it_in_one_line(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(LUMPED.read_text().replace('length = "sqrt(La^2 + Lb^2)"', 'length = "1414 mm"', 1))
    assert main(["describe", str(path)]) == 2
    one_line_error(capsys, f"{path}: elements.spring.length: a unit in a value ('mm') (got '1414 mm'; ",
                   'name = { value = 1414, unit = "mm" } in [parameters]')
    with pytest.raises(SceneError, match=r"elements\.spring\.length: a unit in a value"):
        inerter.load(path)
