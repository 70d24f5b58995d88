"""Property-based scene tests (hypothesis): random valid planar chains simulate 1 s without error;
random corruptions of them raise the project's SceneError with a message, never anything else."""
from __future__ import annotations

import math

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings, strategies as st  # noqa: E402

import inerter  # noqa: E402
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
    """A scene dict as TOML: [section] of values, or [section.name] of tables."""
    lines = []
    for section, content in data.items():
        if all(isinstance(x, dict) for x in content.values()) and section != "ground" and content:
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
    data["experiment"] = {"stop_time": 1.0, "output_interval": 0.05, "rtol": 1e-6}
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
