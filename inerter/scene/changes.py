"""What differs between two readings of one scene file (with different parameter values).

A co-simulation master may change a parameter between steps: what that changes in the model
decides whether the running engine can take it (:mod:`inerter.engine.tables`, ``TUNABLE``) or a
new model is needed. The answer is given as the scene's field paths, the words of its errors.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from inerter import elements

#: The parts of a scene that make its model (the experiment, metrics and the parameters
#: themselves do not: they are read by the solver settings, the metrics and the expressions).
MODEL_SECTIONS = ("bodies", "points", "joints", "elements", "forces")


def _same(a, b) -> bool:
    """Exact equality of two scene values (numbers, tuples, arrays, records of them)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and bool(np.all(a == b))
    if isinstance(a, (tuple, list)) and isinstance(b, (tuple, list)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if type(a) is not type(b):
        return False
    if hasattr(a, "__dict__") and not dataclasses.is_dataclass(a):
        return _same(vars(a), vars(b))
    return a == b


def _field_name(section: str, item, field: str) -> str:
    """A field as the scene file names it: an element's coefficient by its kind's key (``b``)."""
    if section == "elements":
        kind = elements.KINDS[item.type]
        if field == "coefficient":
            return kind.coefficient.key
        if field == "free_length" and kind.free is not None:
            return kind.free.key
    return field


def differences(old, new) -> list[str]:
    """The field paths (``elements.inerter.b``, ``bodies.bar1.position``, ``effects.gravity``) whose
    values differ between two scenes read from one file; a whole section or item when its names
    differ."""
    out = []
    for name in ("dimension", "orientation"):
        if getattr(old, name) != getattr(new, name):
            out.append(f"scene.{name}")
    for key in sorted(set(old.effects) | set(new.effects)):
        if key not in old.effects or key not in new.effects or not _same(old.effects[key], new.effects[key]):
            out.append(f"effects.{key}")
    for section in MODEL_SECTIONS:
        a, b = getattr(old, section), getattr(new, section)
        if list(a) != list(b):
            out.append(section)
            continue
        for name, item in a.items():
            other = b[name]
            if type(item) is not type(other):
                out.append(f"{section}.{name}")
                continue
            for f in dataclasses.fields(item):
                if not _same(getattr(item, f.name), getattr(other, f.name)):
                    out.append(f"{section}.{name}.{_field_name(section, item, f.name)}")
    return out
