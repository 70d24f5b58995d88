"""What a run exports besides its arrays: the CSV of ``inerter run`` with each column's unit in its
header, ``summary.json``'s output units, and ``Result.to_dataframe()`` (pandas, optional). The
references are the model's own list of outputs and units (``model.output_info()``, what ``inerter
describe`` prints and the FMU declares) and the result's arrays."""
from __future__ import annotations

import json
import sys

import numpy as np
import pytest

import inerter
from conftest import LUMPED
from inerter.cli import main


@pytest.fixture(scope="module")
def result():
    return inerter.load(LUMPED).simulate(stop_time=0.5, metrics=False)


def declared_units(result) -> dict:
    return {"time": "s", **{o["name"]: o["unit"] for o in result.model.output_info()}}


def test_the_csv_header_gives_each_column_its_unit_and_pandas_reads_it(result, tmp_path):
    pd = pytest.importorskip("pandas")
    result.write_csv(tmp_path / "run.csv")
    table = pd.read_csv(tmp_path / "run.csv")
    names, units = zip(*(column[:-1].rsplit(" (", 1) for column in table.columns))
    assert list(names) == ["time"] + result.names
    assert dict(zip(names, units)) == declared_units(result)
    assert units[:3] == ("s", "m", "m") and dict(zip(names, units))["inerter.f"] == "N"
    assert np.allclose(table["time (s)"], result.time, rtol=1e-11, atol=0)
    assert np.allclose(table["P.r[2] (m)"], result["P.r[2]"], rtol=1e-11, atol=0)    # written at 12 digits


def test_run_writes_units_into_the_csv_and_the_summary(tmp_path):
    assert main(["run", str(LUMPED), "--stop-time", "0.2", "--out", str(tmp_path)]) == 0
    header = (tmp_path / "lumped_mass_2d.csv").read_text().splitlines()[0].split(",")
    model = inerter.load(LUMPED)
    expected = declared_units(model.simulate(stop_time=0.2, metrics=False))
    assert header == [f"{name} ({unit})" for name, unit in expected.items()]
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["output_units"] == expected


def test_a_result_converts_to_a_dataframe_with_its_units(result):
    pytest.importorskip("pandas")
    frame = result.to_dataframe()
    assert frame.index.name == "time" and np.array_equal(frame.index.to_numpy(), result.time)
    assert list(frame.columns) == result.names
    for name in ("P.r[2]", "inerter.f", "energy"):
        assert np.array_equal(frame[name].to_numpy(), result[name])
    assert frame.attrs["units"] == declared_units(result)


def test_to_dataframe_without_pandas_says_what_is_missing(result, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)          # as where pandas is not installed
    with pytest.raises(ModuleNotFoundError) as caught:
        result.to_dataframe()
    text = str(caught.value)
    assert "to_dataframe() needs pandas" in text and "pip install pandas" in text and "\n" not in text
