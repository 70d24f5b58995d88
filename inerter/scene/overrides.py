"""``--set NAME=VALUE`` overrides from the command line, read as the scene file reads values."""
from __future__ import annotations

import tomllib

from inerter.common.errors import SceneError


def parse_set(items) -> dict:
    """``NAME=VALUE`` pairs; VALUE is read as a TOML value (20, 1e-3, false, [0, -9.81]) or, failing
    that, as a bare string (a method name)."""
    out = {}
    for item in items or []:
        if "=" not in item:
            raise SceneError("--set", item, item, "NAME=VALUE, e.g. b=20 or effects.centripetal=false",
                             "missing '='")
        name, text = item.split("=", 1)
        name = name.strip()
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        out[name] = value
    return out
