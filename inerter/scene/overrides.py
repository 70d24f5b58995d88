"""``--set NAME=VALUE`` overrides from the command line, read as the scene file reads values."""
from __future__ import annotations

import tomllib

from inerter.common.errors import SceneError


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
