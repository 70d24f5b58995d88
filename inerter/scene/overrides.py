"""``--set NAME=VALUE`` overrides from the command line, read as the scene file reads values."""
from __future__ import annotations

import re
import tomllib
from typing import Any, Mapping

from inerter.common.errors import SceneError, shown
from inerter.scene.expressions import free_names


def read_value(text: str):
    """A value typed on the command line, as the scene file would hold it: a TOML value (20,
    1e-3, false, [0, -9.81], {value = 20, unit = "kN"}) or, failing that, the text itself (an
    expression such as 2*pi, or a method name). The scene reader then checks it as it checks the
    field it replaces."""
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_set(items) -> dict:
    """``NAME=VALUE`` pairs into ``{NAME: value}`` (see :func:`read_value`)."""
    out = {}
    for item in items or []:
        if "=" not in item:
            raise SceneError("--set", item, item, "NAME=VALUE, e.g. b=20 or effects.centripetal=false",
                             "missing '='")
        name, text = item.split("=", 1)
        if not name.strip():
            raise SceneError("--set", item, item, "NAME=VALUE, e.g. b=20 or effects.centripetal=false",
                             "missing name")
        out[name.strip()] = read_value(text)
    return out


# -- where a refused value came from ------------------------------------------------------------------
def set_origins(items, option: str = "--set") -> dict:
    """``{NAME: "--set NAME=VALUE"}`` for ``NAME=VALUE`` items as typed (see :func:`parse_set`):
    how an error names the override that gave a refused value."""
    return {item.split("=", 1)[0].strip(): f"{option} {item.strip()}" for item in items or [] if "=" in item}


def origin_of(key: str, value, origins: Mapping[str, str] | None = None) -> str:
    """Where the override `key` came from, as the caller names it (``--set lead=0``), else
    ``override lead=0`` (``inerter.load(scene, lead=0)``, an FMU's start value)."""
    if origins and key in origins:
        return origins[key]
    return f"override {key}={value if isinstance(value, str) else shown(value)}"


def overrides_behind(fld: str, data, overrides: Mapping[str, Any]) -> list[str]:
    """The override keys that the scene's field `fld` (``elements.inerter.device.flywheel.lead``,
    ``bodies.arm.position[2]``, ``parameters.b.value``, ``experiment.stop_time``) takes its value
    from: the override of that field itself, or of a parameter its expression reads, directly or
    through other parameters. Found from the field's text in the scene `data`."""
    raw_params = data.get("parameters", {}) if isinstance(data, dict) else {}
    raw_params = raw_params if isinstance(raw_params, dict) else {}
    direct = [k for k in overrides if _within(fld, k) or (k in raw_params and _within(fld, f"parameters.{k}"))]
    seen: set[str] = set()
    stack = list(_names_in(_at(data, fld)))
    while stack:                       # the parameters it reads, and those they read
        name = stack.pop()
        if name in seen or name not in raw_params:
            continue
        seen.add(name)
        stack.extend(_names_in(overrides[name] if name in overrides else raw_params[name]))
    return [k for k in overrides if k in direct or k in seen]


def _within(fld: str, path: str) -> bool:
    return fld == path or fld.startswith((path + ".", path + "["))


def _at(data, fld: str):
    """The raw value at the field path `fld` (``a.b[2]``: 1-based index), or None."""
    node = data
    for name, index in re.findall(r"([^.\[\]]+)|\[(\d+)\]", fld):
        if name and isinstance(node, dict) and name in node:
            node = node[name]
        elif index and isinstance(node, list) and 1 <= int(index) <= len(node):
            node = node[int(index) - 1]
        else:
            return None
    return node


def _names_in(node) -> set[str]:
    """The names an expression (or a list of them, or a parameter's ``{value = ...}`` table) reads;
    none from other tables, whose strings are names of points, bodies and kinds."""
    if isinstance(node, str):
        try:
            return free_names(node, "", "")
        except SceneError:
            return set()
    if isinstance(node, list):
        return set().union(*(_names_in(v) for v in node)) if node else set()
    if isinstance(node, dict) and "value" in node:
        return _names_in(node["value"])
    return set()


def attributed(exc: SceneError, source: str, data, overrides: Mapping[str, Any],
               origins: Mapping[str, str] | None = None) -> SceneError:
    """`exc`, a scene file's error, with the overrides its value came from in front
    (``--set lead=0: scene.toml: elements.inerter.device.flywheel.lead: out of range ...``); as it
    is where none did, or where it names its origin already (an unknown override's name)."""
    if exc.source != source or not overrides:
        return exc
    keys = overrides_behind(exc.field, data, overrides)
    if not keys:
        return exc
    where = ", ".join(origin_of(k, overrides[k], origins) for k in keys)
    return SceneError(f"{where}: {exc.source}", exc.field, exc.value, exc.expected, exc.problem)
