"""An output name a result does not have (``result["inerter.F"]``, ``result.dense("P.r[3]")``), of
the solver's Result and of an FMU run's alike: one line naming the scene file, the call, the name
given and the outputs there are, with the closest one where a name is close (a misspelling), and
still a KeyError, as a missing key of a mapping is."""
from __future__ import annotations

import pytest

import inerter
from inerter.common.errors import InerterError
from inerter.fmu.run import simulate_fmu
from conftest import LUMPED


@pytest.fixture(scope="module")
def result():
    return inerter.load(LUMPED).simulate(stop_time=0.1, metrics=False)


def message(call):
    with pytest.raises(KeyError) as caught:
        call()
    assert isinstance(caught.value, InerterError)
    text = str(caught.value)
    assert "\n" not in text and not text.startswith("'"), text
    return text


@pytest.mark.parametrize("call, where, name, close", [
    (lambda r: r["inerter.F"], "result['inerter.F']", "'inerter.F'", "inerter.f"),
    (lambda r: r.dense("P.r[3]"), "dense('P.r[3]')", "'P.r[3]'", "P.r[2]"),
    (lambda r: r.dense("tip"), "dense('tip')", "'tip'", None),
])
def test_an_unknown_output_names_the_file_the_call_the_name_and_the_outputs(result, call, where, name, close):
    text = message(lambda: call(result))
    assert text.startswith(f"{LUMPED}: {where}: not an output"), text
    assert f"(got {name}; expected an output of the scene: " in text, text
    assert "P.r[2], P.v[1]" in text and text.endswith("energy, constraint_residual)"), text
    assert (f"(did you mean '{close}'?)" in text) if close else ("did you mean" not in text), text


def test_an_fmu_runs_unknown_output_reads_the_same(tmp_path):
    fmu = simulate_fmu(LUMPED, stop_time=0.1, metrics=False)
    for call, where in ((lambda: fmu["inerter.F"], "result['inerter.F']"),
                        (lambda: fmu.dense("inerter.F"), "dense('inerter.F')")):
        text = message(call)
        assert text.startswith(f"{LUMPED} (FMU): {where}: not an output (did you mean 'inerter.f'?) "
                               "(got 'inerter.F'; expected an output of the scene: "), text
