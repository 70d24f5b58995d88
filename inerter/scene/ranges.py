"""The range a scene parameter must lie in, from the fields it fills.

A parameter written as a field's whole value (``b = "b"`` in ``[elements.inerter]``) must satisfy
that field's range: an element kind's parameters declare theirs (:mod:`inerter.elements`), a PD
actuator's gains are ≥ 0, a planar body's inertia is ≥ 0. An importer can check a value against
these bounds before running (the FMU's ``min``). A parameter used inside a longer expression gets
no bound from it; exclusive bounds (a mass > 0, a frequency > 0) are not stated (FMI's ``min`` is
inclusive): the scene reader still refuses those values, with its message.
"""
from __future__ import annotations

import math

from inerter import elements


def _bare_name(value, names) -> str | None:
    """The parameter a field's value is, when it is nothing but a parameter's name."""
    if isinstance(value, str) and value.strip() in names:
        return value.strip()
    return None


def parameter_minimums(raw: dict) -> dict[str, float]:
    """Lower bounds (inclusive) of the scene's parameters, by name, from the scene file's data
    `raw` (``Scene.raw``); parameters with none are left out."""
    names = set(raw.get("parameters", {}) or {})
    bounds: dict[str, float] = {}

    def bound(value, minimum):
        name = _bare_name(value, names)
        if name is not None and minimum is not None and minimum != -math.inf:
            bounds[name] = max(bounds.get(name, -math.inf), float(minimum))

    for spec in (raw.get("elements", {}) or {}).values():
        if not isinstance(spec, dict) or spec.get("type") not in elements.KINDS:
            continue
        kind = elements.KINDS[spec["type"]]
        for p in (kind.coefficient, kind.free):
            if p is not None and p.key in spec:
                bound(spec[p.key], p.minimum)
    for spec in (raw.get("forces", {}) or {}).values():
        if isinstance(spec, dict) and spec.get("function") == "pd":
            for gain in ("kp", "kd"):
                bound(spec.get(gain), 0.0)
    dimension = (raw.get("scene", {}) or {}).get("dimension", 2)
    for spec in (raw.get("bodies", {}) or {}).values():
        if not isinstance(spec, dict):
            continue
        if dimension == 2:
            bound(spec.get("inertia"), 0.0)
        if spec.get("massless") is True:
            bound(spec.get("mass"), 0.0)
    return bounds
