"""Write :mod:`inerter.elements.dispatch`, the kernels' call of each kind's law by its code, from
the kinds found in this package: ``python -m inerter.elements.generate`` after adding a kind
(``tests/test_elements.py`` fails while the file is stale)."""
from __future__ import annotations

from pathlib import Path

from inerter.elements import MODULES, ROTATIONAL, TRANSLATIONAL

TARGET = Path(__file__).with_name("dispatch.py")

_FUNCTIONS = {
    TRANSLATIONAL: (("inertance", "row, Ldot"), ("force", "row, L, Ldot, an, perp2"), ("energy", "row, L, Ldot"),
                    ("extra_outputs", "row, L, Ldot, an, perp2, gq, x, out, k"), ("state_force", "row, L, Ldot, x"),
                    ("state_energy", "row, L, Ldot, x"), ("state_rates", "row, L, Ldot, an, perp2, gq, x, dx")),
    ROTATIONAL: (("torque", "row, phi, w"), ("rotational_energy", "row, phi, w")),
}
_LAW = {"rotational_energy": "energy"}
#: Laws a kind may leave out, with what the dispatch returns for it: ``extra_outputs`` writes a
#: kind's outputs beyond the family's three (an inerter's device) and returns the next index; the
#: laws of internal states (an inerter's device: ``state_force``, ``state_energy``, ``state_rates``,
#: which writes ẋ into dx) are those of a kind whose elements may have some.
_OPTIONAL = {"extra_outputs": "k", "state_force": "0.0", "state_energy": "0.0", "state_rates": "None"}


def source() -> str:
    alias = {m: "kind_" + m.__name__.rsplit(".", 1)[1] for m in MODULES}
    lines = ['"""The kernels\' call of each element kind\'s law by its code (its place in',
             "inerter.elements.MODULES). Written by ``python -m inerter.elements.generate``: do not edit.\"\"\"",
             "from inerter.elements.base import law"]
    lines += [f"from inerter.elements import {m.__name__.rsplit('.', 1)[1]} as {alias[m]}" for m in MODULES]
    for family, functions in _FUNCTIONS.items():
        of_family = [(code, m) for code, m in enumerate(MODULES) if m.KIND.family == family]
        for name, args in functions:
            law = _LAW.get(name, name)
            members = [(code, m) for code, m in of_family if hasattr(m, law)]
            lines += ["", "", "@law", f"def {name}(kind, {args}):"]
            if name in _OPTIONAL:
                for code, m in members:
                    lines.append(f"    if kind == {code}:")
                    lines.append(f"        return {alias[m]}.{law}({args})")
                lines.append(f"    return {_OPTIONAL[name]}")
                continue
            if not members:
                lines.append("    return 0.0")
                continue
            for code, m in members[:-1]:
                lines.append(f"    if kind == {code}:")
                lines.append(f"        return {alias[m]}.{law}({args})")
            lines.append(f"    return {alias[members[-1][1]]}.{law}({args})"
                         f"  # kind == {members[-1][0]}")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    TARGET.write_text(source(), encoding="utf-8")
    print(f"wrote {TARGET}")
