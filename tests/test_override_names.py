"""A misspelt override (``--set effects.centripetl=false``, ``inerter.load(scene, bb=3)``): one line
naming where it came from, the scene file, the name given and what names there are, with the
closest name where one is close."""
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
