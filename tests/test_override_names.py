"""A misspelt override (``--set effects.centripetl=false``, ``inerter.load(scene, bb=3)``) or field of
a scene file (``stop_tme``, ``[experimnet]``): one line naming where it came from, the scene file,
the name given and what names there are, with the closest name where one is close."""
from __future__ import annotations

import pytest

import inerter
from inerter.cli import main
from inerter.common.errors import SceneError
from conftest import LUMPED, one_line_error


def test_an_unknown_effect_names_the_scene_file_and_the_closest_effect(capsys):
    assert main(["describe", str(LUMPED), "--set", "effects.centripetl=false"]) == 2
    one_line_error(capsys, f"inerter: error: --set effects.centripetl=false: {LUMPED}: effects.centripetl: "
                           "unknown effect (got False; expected an effect: effects.centripetal, ",
                   "; did you mean 'effects.centripetal'?)")
    with pytest.raises(SceneError) as caught:
        inerter.load(LUMPED, **{"effects.centripetl": False})
    assert str(caught.value).startswith(f"override effects.centripetl=False: {LUMPED}: effects.centripetl: "
                                        "unknown effect"), caught.value


@pytest.mark.parametrize("given, hint", [("bb=3", "; did you mean 'b'?)"), ("zzz=3", "scene.orientation)")])
def test_an_unknown_parameter_suggests_the_closest_one_where_one_is_close(capsys, given, hint):
    assert main(["describe", str(LUMPED), "--set", given]) == 2
    err = one_line_error(capsys, f"--set {given}: ", f"expected a parameter of {LUMPED}: La, Lb, b, k, m, y0")
    assert err.endswith(hint), err


@pytest.mark.parametrize("old, new, field, hint", [
    ("stop_time = 20.0", "stop_tme = 20.0", "experiment.stop_tme", "did you mean 'stop_time'?"),
    ("[experiment]", "[experimnet]", "experimnet", "did you mean 'experiment'?"),
    ("[elements.spring]", "[element.spring]", "element", "did you mean 'elements'?"),
])
def test_a_misspelt_field_of_a_scene_file_suggests_the_closest_one(tmp_path, capsys, old, new, field, hint):
    path = tmp_path / "scene.toml"
    path.write_text(LUMPED.read_text().replace(old, new, 1))
    assert main(["describe", str(path)]) == 2
    err = one_line_error(capsys, f"{path}: {field}: unknown field (got ", "; expected one of: ")
    assert err.endswith(f"; {hint})"), err


def test_a_misspelt_experiment_override_suggests_the_closest_field(capsys):
    assert main(["describe", str(LUMPED), "--set", "experiment.rtoll=1e-8"]) == 2
    err = one_line_error(capsys, f"--set experiment.rtoll=1e-8: {LUMPED}: experiment.rtoll: unknown field")
    assert err.endswith("; did you mean 'rtol'?)"), err
