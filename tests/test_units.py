"""Units that mean something (issue 23, item 7): a parameter's unit converts its value to SI, a
unit whose dimension does not fit the field the parameter reaches is an error, and everything
downstream (CSV, summary, FMU) sees SI. References are hand-converted SI values, never the
package's own conversion."""
from __future__ import annotations

import json
import math
import zipfile
from xml.etree import ElementTree as ET

import numpy as np
import pytest

import inerter
from inerter.cli import main
from inerter.common.errors import SceneError
from inerter.scene.units import UnitSyntaxError, readings
from conftest import LUMPED

# -- the table of units -----------------------------------------------------------------------------
L, M, T = (1, 0, 0), (0, 1, 0), (0, 0, 1)


@pytest.mark.parametrize("text, factor, dimension, si", [
    ("m", 1.0, (1, 0, 0), "m"), ("mm", 0.001, (1, 0, 0), "m"), ("cm", 0.01, (1, 0, 0), "m"),
    ("km", 1000.0, (1, 0, 0), "m"), ("s", 1.0, (0, 0, 1), "s"), ("ms", 0.001, (0, 0, 1), "s"),
    ("kg", 1.0, (0, 1, 0), "kg"), ("t", 1000.0, (0, 1, 0), "kg"), ("N", 1.0, (1, 1, -2), "N"),
    ("kN", 1000.0, (1, 1, -2), "N"), ("N/m", 1.0, (0, 1, -2), "N/m"), ("kN/m", 1000.0, (0, 1, -2), "N/m"),
    ("N/mm", 1000.0, (0, 1, -2), "N/m"), ("N*s/m", 1.0, (0, 1, -1), "N.s/m"), ("N.s/m", 1.0, (0, 1, -1), "N.s/m"),
    ("kN*s/m", 1000.0, (0, 1, -1), "N.s/m"), ("rad", 1.0, (0, 0, 0), "rad"),
    ("deg", math.pi / 180, (0, 0, 0), "rad"), ("Hz", 1.0, (0, 0, -1), "Hz"), ("m/s^2", 1.0, (1, 0, -2), "m/s2"),
    ("m/s2", 1.0, (1, 0, -2), "m/s2"), ("kg*m^2", 1.0, (2, 1, 0), "kg.m2"), ("kg.m2", 1.0, (2, 1, 0), "kg.m2"),
    ("kg m**2", 1.0, (2, 1, 0), "kg.m2"), ("N.m/rad", 1.0, (2, 1, -2), "N.m/rad"),
    ("kN*m/deg", 1000.0 * 180 / math.pi, (2, 1, -2), "N.m/rad"), ("deg/s", math.pi / 180, (0, 0, -1), "rad/s"),
    ("1", 1.0, (0, 0, 0), "1"), ("1/s", 1.0, (0, 0, -1), "1/s"), ("g*cm^2", 1e-7, (2, 1, 0), "kg.m2"),
    ("N/(m.s)", 1.0, (0, 1, -3), "N/(m.s)"),
])
def test_a_unit_gives_its_factor_dimension_and_si_name(text, factor, dimension, si):
    (unit,) = readings(text)
    assert unit.factor == pytest.approx(factor, rel=1e-15)
    assert tuple(unit.dimension) == dimension and unit.si == si


def test_g_alone_is_the_gram_or_standard_gravity():
    gram, gravity = readings("g")
    assert (gram.factor, tuple(gram.dimension), gram.si) == (1e-3, (0, 1, 0), "kg")
    assert (gravity.factor, tuple(gravity.dimension), gravity.si) == (9.80665, (1, 0, -2), "m/s2")


@pytest.mark.parametrize("text", ["furlong", "", "m^", "m^x", "(m", "m)", "N/m.s", "kg**2.5", "m//s", "3m"])
def test_a_malformed_unit_is_refused(text):
    with pytest.raises(UnitSyntaxError):
        readings(text)


# -- a scene in mm, kN, deg and g runs exactly as its SI twin ---------------------------------------------
TWIN = """
[scene]
name = "{name}"

[parameters]
m   = {m}
gee = {gee}
L   = {L}
k   = {k}
c   = {{ value = 20, unit = "N*s/m" }}
b   = {b}
th0 = {th0}
F   = {F}
f   = {{ value = 1.5, unit = "Hz" }}

[effects]
gravity = [0, "-gee"]

[ground.points]
O = [0, 0]
G = ["L", 0]
H = ["-L", 0]

[bodies.bar]
mass = "m"
inertia = 0.01
position = ["0.5*L*sin(th0)", "-0.5*L*cos(th0)"]
angle = "th0 - pi/2"
points = {{ A = ["-0.5*L", 0], T = ["0.5*L", 0] }}

[joints.pivot]
type = "revolute"
between = ["O", "A"]

[elements.spring]
type = "spring"
between = ["G", "T"]
k = "k"

[elements.damper]
type = "damper"
between = ["G", "T"]
c = "c"

[elements.inerter]
type = "inerter"
between = ["H", "T"]
b = "b"

[forces.push]
point = "T"
direction = [1, 0]
function = "sine"
amplitude = "F"
frequency = "f"

[experiment]
stop_time = 2.0
output_interval = 0.01
rtol = 1e-10

[[metrics]]
kind = "natural_frequency"

[[metrics]]
kind = "peak"
signal = "T.r[1]"
"""

WITH_UNITS = dict(
    name="pendulum_units",
    m='{ value = 1500, unit = "g" }',            # the gram: bodies.bar.mass is a mass
    gee='{ value = 1, unit = "g" }',             # standard gravity: effects.gravity is an acceleration
    L='{ value = 500, unit = "mm" }',
    k='{ value = 2.5, unit = "kN/m" }',
    b='{ value = 800, unit = "g" }',             # the gram again, through elements.inerter.b
    th0='{ value = 30, unit = "deg" }',
    F='{ value = 0.002, unit = "kN" }',
)
# The same values converted by hand: 1500 g = 1.5 kg, 1 g = 9.80665 m/s², 500 mm = 0.5 m,
# 2.5 kN/m = 2500 N/m, 800 g = 0.8 kg, 30° = π/6 rad = 0.5235987755982988, 0.002 kN = 2 N.
SI = dict(
    name="pendulum_si",
    m='{ value = 1.5, unit = "kg" }', gee="9.80665", L='{ value = 0.5, unit = "m" }', k="2500",
    b='{ value = 0.8, unit = "kg" }', th0="0.5235987755982988", F='{ value = 2.0, unit = "N" }',
)
SI_VALUES = {"m": 1.5, "gee": 9.80665, "L": 0.5, "k": 2500.0, "c": 20.0, "b": 0.8, "th0": 0.5235987755982988,
             "F": 2.0, "f": 1.5}


@pytest.fixture
def twins(tmp_path):
    paths = {}
    for values in (WITH_UNITS, SI):
        paths[values["name"]] = tmp_path / f"{values['name']}.toml"
        paths[values["name"]].write_text(TWIN.format(**values))
    return paths["pendulum_units"], paths["pendulum_si"]


def _comparable(summary):
    out = dict(summary)
    for key in ("scene", "source"):
        out.pop(key)
    out["statistics"] = {k: v for k, v in summary["statistics"].items() if k != "cpu_time_s"}
    return out


def test_a_scene_in_mm_kn_deg_and_g_runs_exactly_as_its_si_twin(twins, tmp_path):
    units, si = twins
    summaries, csvs = [], []
    for path in (units, si):
        out = tmp_path / path.stem
        assert main(["run", str(path), "--out", str(out)]) == 0
        summaries.append(json.loads((out / "summary.json").read_text()))
        csvs.append((out / f"{path.stem}.csv").read_text())
    assert summaries[0]["settings"]["parameters"] == SI_VALUES
    assert _comparable(summaries[0]) == _comparable(summaries[1])
    assert csvs[0] == csvs[1]
    assert summaries[0]["metrics"]["peak"] > 1e-3           # it moved (2.5 mm): the comparison means something


def test_an_fmu_declares_si_values_with_si_units(twins, tmp_path):
    """The FMU of the scene in mm, kN, deg and g: its parameters' start values and units are SI,
    and its outputs equal those of its SI twin's FMU."""
    units, si = twins
    tables = []
    for path in (units, si):
        out = tmp_path / ("fmu_" + path.stem)
        assert main(["run", str(path), "--model", "fmu", "--out", str(out), "--stop-time", "0.5"]) == 0
        tables.append((out / f"{path.stem}.csv").read_text())
    assert tables[0] == tables[1]
    with zipfile.ZipFile(f"build/fmu/{units.stem}.fmu") as fmu:
        root = ET.fromstring(fmu.read("modelDescription.xml"))
    declared = {v.get("name"): v.find("Real") for v in root.iter("ScalarVariable") if v.find("Real") is not None}
    for name, unit, value in (("L", "m", 0.5), ("k", "N/m", 2500.0), ("th0", "rad", 0.5235987755982988),
                              ("m", "kg", 1.5), ("gee", "m/s2", 9.80665), ("F", "N", 2.0)):
        assert declared[name].get("unit") == unit
        assert float(declared[name].get("start")) == value


def test_a_position_in_mm_is_a_position_in_m(tmp_path):
    """The issue's case: y0 = 1500 mm starts the mass at 1.5 m, not 1500 m."""
    path = tmp_path / "lm.toml"
    path.write_text(LUMPED.read_text().replace('y0 = { value = 1.5,    unit = "m"', 'y0 = { value = 1500, unit = "mm"'))
    model = inerter.load(path)
    assert model.scene.parameters["y0"].value == 1.5
    assert model.scene.parameters["y0"].unit == "m" and model.scene.parameters["y0"].given == "1500 mm"
    assert model.simulate(stop_time=0.1)["P.r[2]"][0] == 1.5


# -- units that do not fit -------------------------------------------------------------------------
@pytest.mark.parametrize("parameter, entry, field, unit, expected", [
    ("b", '{ value = 100.0, unit = "N" }', "elements.inerter.b", "'N', a force", "a value in kg (a mass)"),
    ("k", '{ value = 1.0e4, unit = "kg" }', "elements.spring.k", "'kg', a mass", "a value in N/m (a stiffness"),
    ("y0", '{ value = 1.5, unit = "deg" }', "bodies.mass.position[2]", "'deg', dimensionless",
     "a value in m (a length)"),
    ("m", '{ value = 5.0, unit = "g" }', "bodies.mass.mass", "'g' (the gram), a mass", "a value in kg (a mass)"),
])
def test_a_unit_that_does_not_fit_is_a_one_line_error(tmp_path, capsys, parameter, entry, field, unit, expected):
    text = LUMPED.read_text()
    start = text.index(f"\n{parameter} ") + 1
    end = text.index("\n", start)
    path = tmp_path / "lm.toml"
    path.write_text(text[:start] + f"{parameter} = {entry}" + text[end:])
    if parameter == "m":      # 5 g where a mass belongs is fine; used as a length as well, it is not
        path.write_text(path.read_text().replace('position = ["La", "y0"]', 'position = ["m", "y0"]'))
        field, expected = "bodies.mass.position[1]", "a value in m (a length)"
        unit = "'g' (the gram), a mass"
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith(f"inerter: error: {path}: {field}: the unit does not fit: parameter {parameter} is in {unit}"), err
    assert expected in err, err


def test_g_is_read_by_the_field_it_reaches(tmp_path):
    """One unit string, two parameters: as a mass it is the gram, as an acceleration standard
    gravity; one parameter used as both fits neither reading."""
    text = LUMPED.read_text().replace('m  = { value = 5.0,    unit = "kg"', 'm  = { value = 5000, unit = "g"')
    text = text.replace("[effects]\n", '[effects]\ngravity = [0, "-a"]\n').replace(
        "[parameters]\n", '[parameters]\na = { value = 0.5, unit = "g" }\n')
    path = tmp_path / "both.toml"
    path.write_text(text)
    scene = inerter.load(path).scene
    assert scene.parameters["m"].value == 5.0 and scene.parameters["m"].unit == "kg"
    assert scene.parameters["a"].value == 0.5 * 9.80665 and scene.parameters["a"].unit == "m/s2"
    assert scene.effects["gravity"] == (0.0, -0.5 * 9.80665)
    path.write_text(text.replace('gravity = [0, "-a"]', 'gravity = [0, "-m"]'))
    with pytest.raises(SceneError) as info:
        inerter.load(path)
    assert "parameter m is in 'g'" in str(info.value)


# -- overrides and expressions -------------------------------------------------------------------------
def test_an_override_is_si_or_carries_its_unit(tmp_path):
    path = tmp_path / "lm.toml"
    path.write_text(LUMPED.read_text().replace('y0 = { value = 1.5,    unit = "m"', 'y0 = { value = 1500, unit = "mm"'))
    assert inerter.load(path, y0=1.2).scene.parameters["y0"].value == 1.2              # SI, as an FMU sets it
    assert inerter.load(path, y0={"value": 1200, "unit": "mm"}).scene.parameters["y0"].value == 1.2
    assert inerter.load(path, y0={"value": 0.12, "unit": "cm"}).scene.parameters["y0"].value == 0.0012
    with pytest.raises(SceneError, match=r"parameters\.y0\.unit: the unit does not fit: 'kN', a force"):
        inerter.load(path, y0={"value": 1, "unit": "kN"})


@pytest.mark.parametrize("expression, fits", [
    ("sqrt(La^2 + Lb^2)", True),      # a length from lengths
    ("La + Lb", True),
    ("2*La", True),
    ("La*Lb/La", True),
    ("La*k/k", True),
    ("La + m", False),                # a length plus a mass
    ("La*La", False),                 # an area where a length belongs
    ("k/m", False),                   # 1/s² where a length belongs
])
def test_an_expression_carries_its_parameters_dimensions(tmp_path, expression, fits):
    """A spring's free length (m) written over parameters in mm, kg and N/m."""
    text = LUMPED.read_text().replace('length = "sqrt(La^2 + Lb^2)"', f'length = "{expression}"')
    text = text.replace('La = { value = 1.0,    unit = "m"', 'La = { value = 1000, unit = "mm"')
    path = tmp_path / "lm.toml"
    path.write_text(text)
    if fits:
        model = inerter.load(path)
        assert model.scene.elements["spring"].free_length > 0
    else:
        with pytest.raises(SceneError) as info:
            inerter.load(path)
        assert "elements.spring.length" in str(info.value) and "a length" in str(info.value)


def test_a_plain_number_in_a_product_may_carry_a_unit(tmp_path):
    """0.5*w*sin(th): the 0.5 is a length the scene does not state; the product is let pass, as
    the shipped two_bar_aligned scene writes its initial velocities."""
    text = LUMPED.read_text().replace("[parameters]\n", '[parameters]\nw = { value = 2, unit = "rad/s" }\n')
    text = text.replace('position = ["La", "y0"]', 'position = ["La", "y0"]\nvelocity = [0, "0.5*w"]')
    path = tmp_path / "lm.toml"
    path.write_text(text)
    assert inerter.load(path).scene.bodies["mass"].velocity == (0.0, 1.0)
    path.write_text(text.replace('"0.5*w"', '"w"'))
    with pytest.raises(SceneError, match=r"bodies\.mass\.velocity\[2\]: the unit does not fit: parameter w is in "
                                         r"'rad/s'"):
        inerter.load(path)


def test_functions_of_angles_take_angles(tmp_path):
    text = LUMPED.read_text().replace('position = ["La", "y0"]', 'position = ["La", "y0*cos(La)"]')
    path = tmp_path / "lm.toml"
    path.write_text(text)
    with pytest.raises(SceneError, match=r"cos\(\) of a length"):
        inerter.load(path)


def test_describe_shows_si_and_what_was_given(tmp_path, capsys):
    path = tmp_path / "lm.toml"
    path.write_text(LUMPED.read_text().replace('y0 = { value = 1.5,    unit = "m"', 'y0 = { value = 1500, unit = "mm"'))
    assert main(["describe", str(path)]) == 0
    assert "y0 = 1.5 m (given as 1500 mm)" in capsys.readouterr().out


def test_values_in_si_everywhere_downstream(tmp_path):
    """summary.json and the CSV: SI values (the mass's start at 1.5 m, not 1500)."""
    path = tmp_path / "lm.toml"
    path.write_text(LUMPED.read_text().replace('y0 = { value = 1.5,    unit = "m"', 'y0 = { value = 1500, unit = "mm"'))
    out = tmp_path / "out"
    assert main(["run", str(path), "--stop-time", "0.1", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["parameters"]["y0"] == 1.5
    data = np.genfromtxt(out / "lumped_mass_2d.csv", delimiter=",", names=True)
    assert data["Pr2_m"][0] == 1.5
