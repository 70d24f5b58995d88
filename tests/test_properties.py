"""Property-based scene tests (hypothesis): random valid planar chains simulate 1 s without error;
written in random units they load to the same SI values; corrupted field by field, each ends in
one line naming the file and the field (exit 2), never a traceback."""
from __future__ import annotations

import contextlib
import io
import math
import re

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

import inerter  # noqa: E402
from inerter.cli import main  # noqa: E402
from inerter.common.errors import SceneError  # noqa: E402

SETTINGS = dict(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(v)


def dumps(data: dict) -> str:
    """A scene dict as TOML: [section] of values, [section.name] of tables, [[section]] of a list."""
    lines = [f"{k} = {_toml_value(v)}" for k, v in data.items()        # top-level values first (a corruption)
             if not isinstance(v, dict) and not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v))]
    for section, content in data.items():
        if not isinstance(content, (dict, list)) or (isinstance(content, list) and not
                                                     (content and all(isinstance(x, dict) for x in content))):
            continue
        if isinstance(content, list):
            for table in content:
                lines.append(f"[[{section}]]")
                lines += [f"{k} = {_toml_value(x)}" for k, x in table.items()]
        elif all(isinstance(x, dict) for x in content.values()) and section != "ground" and content:
            for name, table in content.items():
                lines.append(f"[{section}.{name}]")
                lines += [f"{k} = {_toml_value(x)}" for k, x in table.items()]
        else:
            lines.append(f"[{section}]")
            lines += [f"{k} = {_toml_value(x)}" for k, x in content.items()]
    return "\n".join(lines) + "\n"


@st.composite
def chains(draw):
    """A pendulum chain of 1-3 links from the ground, with rotational springs/dampers between
    links, and springs, dampers and inerters from ground anchors out of the chain's reach to the
    link tips (so that no element's terminals can meet)."""
    n = draw(st.integers(1, 3))
    pos = st.floats(0.2, 5.0)
    bodies, joints, elements = {}, {}, {}
    x = y = 0.0
    gravity = draw(st.sampled_from([None, [0.0, -9.81]]))
    for i in range(n):
        L = draw(st.floats(0.3, 1.2))
        th = draw(st.floats(-math.pi, math.pi))
        c, s = math.cos(th), math.sin(th)
        name = f"link{i + 1}"
        bodies[name] = {
            "mass": draw(pos), "inertia": draw(st.floats(0.01, 1.0)),
            "position": [x + 0.5 * L * c, y + 0.5 * L * s], "angle": th,
            "angular_velocity": draw(st.floats(-2.0, 2.0)),
            "points": {f"A{i + 1}": [-0.5 * L, 0.0], f"T{i + 1}": [0.5 * L, 0.0]},
        }
        joints[f"j{i + 1}"] = {"type": "revolute", "between": ["O" if i == 0 else f"T{i}", f"A{i + 1}"]}
        if i > 0 and draw(st.booleans()):
            kind = draw(st.sampled_from(["rotational_spring", "rotational_damper"]))
            key = "k" if kind == "rotational_spring" else "d"
            elements[f"r{i + 1}"] = {"type": kind, "bodies": [f"link{i}", name], key: draw(st.floats(0.0, 50.0))}
        x, y = x + L * c, y + L * s
    anchors = {"O": [0.0, 0.0]}
    for i in range(n):
        for kind, key in (("spring", "k"), ("damper", "c"), ("inerter", "b")):
            if draw(st.booleans()):
                ang = draw(st.floats(0.0, 2 * math.pi))
                anchor = f"G{i + 1}{kind[0]}"
                anchors[anchor] = [6.0 * math.cos(ang), 6.0 * math.sin(ang)]    # beyond reach (≤ 3.6 m)
                elements[f"{kind}{i + 1}"] = {"type": kind, "between": [anchor, f"T{i + 1}"],
                                              key: draw(st.floats(0.0, 200.0 if kind != "inerter" else 5.0))}
    data = {"scene": {"name": "random_chain"}}
    if gravity:
        data["effects"] = {"gravity": gravity}
    data.update({"ground": {"points": anchors}, "bodies": bodies, "joints": joints})
    if elements:
        data["elements"] = elements
    if draw(st.booleans()):
        data["forces"] = {"push": {"point": f"T{n}", "direction": [1.0, 0.0], "function": "sine",
                                   "amplitude": draw(st.floats(0.0, 20.0)), "frequency": draw(st.floats(0.1, 5.0))}}
    data["experiment"] = {"stop_time": 1.0, "output_interval": 0.05, "rtol": 1e-6}
    derived = draw(st.booleans())
    if derived:                               # the tip's distance from O, and the chain's energy share
        data["outputs"] = {"derived": {"reach": f"hypot(T{n}.r[1] - O.r[1], T{n}.r[2] - O.r[2])",
                                       "share": {"expression": "energy / (1 + abs(energy))", "unit": "1"}}}
    if draw(st.booleans()):
        data["metrics"] = [{"kind": "peak", "signal": "reach" if derived else f"T{n}.r[2]"}]
    return data


@settings(**SETTINGS)
@given(scene=chains())
def test_random_valid_scenes_simulate(tmp_path_factory, scene):
    path = tmp_path_factory.mktemp("valid") / "chain.toml"
    path.write_text(dumps(scene))
    result = inerter.load(path).simulate(metrics=False)
    assert result.status == "ok", result.message
    assert result.time[-1] == 1.0


def _targets(scene):
    """(path to a value, kind of value) of the fields a corruption may hit."""
    out = []
    for b, body in scene["bodies"].items():
        out += [(("bodies", b, "mass"), "positive"), (("bodies", b, "inertia"), "positive"),
                (("bodies", b, "position"), "vector")]
    for j in scene["joints"]:
        out += [(("joints", j, "type"), "name"), (("joints", j, "between"), "points")]
    for e, spec in scene.get("elements", {}).items():
        key = next(k for k in spec if k in ("k", "c", "b", "d"))
        out += [(("elements", e, key), "coefficient"), (("elements", e, "type"), "name"),
                (("elements", e, "points" if "between" in spec else "bodies_ref"), "ref")]
    for name in scene.get("outputs", {}).get("derived", {}):
        out.append((("outputs", "derived", name), "expression"))
    return out


@st.composite
def corruptions(draw):
    scene = draw(chains())
    path, kind = draw(st.sampled_from(_targets(scene)))
    section, name, key = path
    table = scene[section][name]
    how = draw(st.sampled_from(["delete", "unknown_field", "wrong_type", "nan", "negative", "unknown_ref"]))
    if key in ("points", "bodies_ref"):
        key = "between" if key == "points" else "bodies"
        how = draw(st.sampled_from(["delete", "unknown_ref", "wrong_type"]))
    if kind == "expression":                  # a derived output (deleting one leaves a valid scene)
        table[key] = draw(st.sampled_from([True, [1.0], {"x": 1.0}, math.nan, -1.0, "no_such_name + energy",
                                           "T9.r[1] + 1", "hypot(O.r[1],", "energy + O.r[1]", "2 * pi"]))
        return scene
    if how == "delete":
        del table[key]
    elif how == "unknown_field":
        table[draw(st.sampled_from(["colour", "weight", "massive", "kk"]))] = draw(st.sampled_from([1.0, "x", True]))
    elif how == "wrong_type":
        table[key] = draw(st.sampled_from([True, [1.0, [2.0]], {"x": 1.0}, "no_such_name"]))
    elif how == "nan":
        value = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        table[key] = [value, 0.0] if kind == "vector" else value
    elif how == "negative":
        if kind in ("positive", "coefficient"):
            table[key] = -draw(st.floats(0.01, 10.0))
        else:
            table[key] = -1.0 if kind != "vector" else [-1.0]
    elif how == "unknown_ref":
        if key in ("between", "bodies"):
            table[key] = [table[key][0], "nowhere"]
        else:
            table[key] = "nowhere"
    return scene


@settings(**SETTINGS)
@given(scene=corruptions())
def test_corrupted_scenes_raise_scene_error(tmp_path_factory, scene):
    path = tmp_path_factory.mktemp("corrupt") / "chain.toml"
    path.write_text(dumps(scene))
    with pytest.raises(SceneError) as info:
        inerter.load(path)
    assert str(path) in str(info.value) and info.value.field and info.value.expected


# ----------------------------------------------------------------------------------------------
# The same scene in random units: the SI values the test converts by hand
# ----------------------------------------------------------------------------------------------
#: Units a field's value may be written in, each with its factor to SI (the definitions, kept
#: here apart from the package's table).
UNITS = {
    "mass": [("kg", 1.0), ("g", 1e-3), ("t", 1e3)],
    "length": [("m", 1.0), ("mm", 1e-3), ("cm", 1e-2), ("km", 1e3)],
    "angle": [("rad", 1.0), ("deg", math.pi / 180)],
    "inertia": [("kg*m^2", 1.0), ("kg.m2", 1.0), ("g*cm^2", 1e-7)],
    "angular_velocity": [("rad/s", 1.0), ("deg/s", math.pi / 180)],
    "stiffness": [("N/m", 1.0), ("kN/m", 1e3), ("N/mm", 1e3)],
    "damping": [("N*s/m", 1.0), ("N.s/m", 1.0), ("kN*s/m", 1e3)],
    "rotational_stiffness": [("N*m/rad", 1.0), ("N.m/deg", 180 / math.pi)],
    "rotational_damping": [("N*m*s/rad", 1.0), ("kN.m.s/rad", 1e3)],
    "acceleration": [("m/s^2", 1.0), ("g", 9.80665)],
    "force": [("N", 1.0), ("kN", 1e3)],
    "frequency": [("Hz", 1.0)],
}
BODY_FIELDS = {"mass": "mass", "inertia": "inertia", "angle": "angle", "angular_velocity": "angular_velocity",
               "position": "length"}
ELEMENT_FIELDS = {("spring", "k"): "stiffness", ("damper", "c"): "damping", ("inerter", "b"): "mass",
                  ("rotational_spring", "k"): "rotational_stiffness", ("rotational_damper", "d"): "rotational_damping"}


def _quantities(scene):
    """(path, dimension) of every number of the scene a parameter with a unit may replace."""
    out = []
    for name, point in scene["ground"]["points"].items():
        out += [(("ground", "points", name, i), "length") for i in range(2)]
    for b, body in scene["bodies"].items():
        for key, dim in BODY_FIELDS.items():
            if key in body:
                out += [(("bodies", b, key, i), dim) for i in range(2)] if key == "position" else [(("bodies", b, key), dim)]
        out += [(("bodies", b, "points", p, i), "length") for p in body["points"] for i in range(2)]
    for e, spec in scene.get("elements", {}).items():
        key = next(k for k in spec if k in ("k", "c", "b", "d"))
        out.append((("elements", e, key), ELEMENT_FIELDS[(spec["type"], key)]))
    if "effects" in scene:
        out.append((("effects", "gravity", 1), "acceleration"))
    if "forces" in scene:
        out += [(("forces", "push", "amplitude"), "force"), (("forces", "push", "frequency"), "frequency")]
    return out


def _get(data, path):
    for key in path:
        data = data[key]
    return data


def _set(data, path, value):
    _get(data, path[:-1])[path[-1]] = value


@st.composite
def in_units(draw):
    """(scene in SI, the same scene with parameters in random units replacing its numbers)."""
    scene = draw(chains())
    import copy
    written = copy.deepcopy(scene)
    parameters = {}
    for i, (path, dim) in enumerate(_quantities(scene)):
        if not draw(st.booleans()):
            continue
        unit, factor = draw(st.sampled_from(UNITS[dim]))
        parameters[f"p{i}"] = {"value": _get(scene, path) / factor, "unit": unit}
        _set(written, path, f"p{i}")
    return scene, {"parameters": parameters, **written}


def _numbers(scene):
    """Every number the scene compiles from, by where it goes."""
    out = {}
    for b in scene.bodies.values():
        out.update({(b.name, "mass"): b.mass, (b.name, "inertia"): b.inertia, (b.name, "angle"): b.angle,
                    (b.name, "angular_velocity"): b.angular_velocity})
        out.update({(b.name, "position", i): x for i, x in enumerate(b.position)})
    for p in scene.points.values():
        out.update({(p.name, i): x for i, x in enumerate(p.local)})
    for e in scene.elements.values():
        out[(e.name, "coefficient")] = e.coefficient
        out[(e.name, "free")] = e.free_length
    for f in scene.forces.values():
        out.update({(f.name, "amplitude"): f.amplitude, (f.name, "frequency"): f.frequency})
    out.update({("gravity", i): g for i, g in enumerate(scene.effects.get("gravity", ()))})
    return out


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(pair=in_units())
def test_a_scene_in_random_units_loads_to_its_si_values(tmp_path_factory, pair):
    folder = tmp_path_factory.mktemp("units")
    si, written = pair
    (folder / "si.toml").write_text(dumps(si))
    (folder / "units.toml").write_text(dumps(written))
    expected, got = _numbers(inerter.load(folder / "si.toml").scene), _numbers(inerter.load(folder / "units.toml").scene)
    assert expected.keys() == got.keys()
    for key, value in expected.items():
        if value is None:
            assert got[key] is None, key
        else:
            assert got[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key


# ----------------------------------------------------------------------------------------------
# Field by field: every corruption of every field ends in one line naming the file and the field
# ----------------------------------------------------------------------------------------------
def _leaves(data, path=()):
    """The path of every value of a scene dict (a table's keys, a list's items, the lists too)."""
    if isinstance(data, dict):
        for key, value in data.items():
            yield from _leaves(value, path + (key,))
    elif isinstance(data, list):
        yield path
        for i, value in enumerate(data):
            yield from _leaves(value, path + (i,))
    else:
        yield path


#: Values that are wrong wherever they stand: each must be reported at the field it is in.
INVALID = [math.nan, math.inf, -math.inf, 1e300, True, "2 *", "nowhere", {"x": 1.0}, [[1.0]], ""]
#: Values a field may or may not take (a number where a name belongs, a negative number, ...).
DOUBTFUL = [-1.0, 0.0, 1.0, 1e-300, "1/0", [1.0, 2.0, 3.0], [], "sqrt(-1)", "deg2rad(90)", "pi"]


def _field_text(path) -> str:
    """A path as the reader writes a field: ``bodies.link1.position[2]``, ``metrics[1].signal``."""
    text = ""
    for key in path:
        text += f"[{key + 1}]" if isinstance(key, int) else (f".{key}" if text else key)
    return text


@st.composite
def corrupted(draw):
    """(scene, path, how): one field of a valid scene deleted, given a value, or joined by a key."""
    import copy
    scene = copy.deepcopy(draw(chains()))
    if draw(st.booleans()):             # parameters with units too, so that their fields are hit
        scene = draw(in_units())[1]
    path = draw(st.sampled_from(list(_leaves(scene))))
    how = draw(st.sampled_from(["invalid", "doubtful", "delete", "unknown_key", "unit"]))
    parent = _get(scene, path[:-1]) if path else scene
    if how == "delete":
        if isinstance(parent, list):
            parent.pop(path[-1])
        else:
            del parent[path[-1]]
    elif how == "unknown_key" and isinstance(parent, dict):
        parent["no_such_key"] = 1.0
    elif how == "unit" and path[0] == "parameters":
        scene["parameters"][path[1]] = {"value": 1.0, "unit": draw(st.sampled_from(["furlong", "N", "kg*", "s"]))}
    else:
        value = draw(st.sampled_from(INVALID if how == "invalid" else DOUBTFUL))
        parent[path[-1]] = value
        how = how if how in ("invalid", "doubtful") else "doubtful"
    return scene, path, how


LINE = re.compile(r"^inerter: error: (?P<file>\S+): (?P<field>[^:]+): .+ \(got .*; expected .+\)$")


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(case=corrupted())
def test_every_corruption_of_every_field_is_one_line_naming_it(tmp_path_factory, case):
    """The command line on the corrupted scene (load only: describe): exit 0 where the value is
    one the field takes, else exit 2 and one line ``inerter: error: FILE: FIELD: ... (got VALUE;
    expected ...)``; a value wrong wherever it stands is reported at its own field (or, for a
    parameter, where the parameter is used, naming it)."""
    scene, path, how = case
    file = tmp_path_factory.mktemp("field") / "chain.toml"
    file.write_text(dumps(scene))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["describe", str(file)])
    text = err.getvalue().strip()
    assert "Traceback" not in text
    assert code in (0, 2), text
    if code == 0:
        assert how != "invalid" or path[0] == "scene", (path, text)
        return
    assert "\n" not in text, text
    match = LINE.match(text)
    assert match and match["file"] == str(file), text
    if how == "invalid" and path[0] != "parameters":
        field = _field_text(path)
        assert match["field"].startswith(field) or field.startswith(match["field"]), (field, text)
    elif how == "invalid":
        assert f"parameters.{path[1]}" in match["field"] or f"parameter {path[1]}" in text \
            or path[1] in match["field"], (path, text)
