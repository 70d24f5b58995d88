"""Units of the scene's parameters: a unit string to its dimension, its factor to SI and its SI name.

A parameter's unit converts its value to SI when the scene is read, and the dimension is checked
against every field the parameter reaches (:mod:`.expressions` carries dimensions through the
arithmetic). Everything downstream (the mechanism, CSV, summaries, FMU start values and units)
sees SI values with SI units.

Syntax: factors joined by ``*``, ``.``, ``·`` or a space, each a symbol with an optional integer
exponent (``m^2``, ``m**2`` or Modelica's ``m2``, ``s-2``), and ``/`` before one factor or a
parenthesised product: ``N*s/m``, ``N.s/m``, ``kg*m^2``, ``kg.m2``, ``m/s^2``, ``N.m/rad``,
``N/(m.s)``, ``1/s``; ``"1"`` is dimensionless. Only the mechanical units of :data:`SYMBOLS`.

Angles are dimensionless, as in SI: ``rad`` is 1 and ``deg`` is π/180, so an angle field takes
either and a plain number; ``Hz`` is 1/s (cycles per second: an angular velocity in ``Hz`` would
be read as rad/s without the 2π; write ``rad/s`` or ``deg/s``).

``g`` alone is ambiguous: the gram (1e-3 kg) or standard gravity (9.80665 m/s²). It is read as
the one whose dimension fits the fields the parameter is used in (a mass or an acceleration);
inside a compound unit (``g.cm2``) it is the gram.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from fractions import Fraction
from functools import lru_cache

#: A dimension: the exponents of (length, mass, time). Angles are dimensionless.
Dimension = tuple[Fraction, Fraction, Fraction]
DIMENSIONLESS: Dimension = (Fraction(0), Fraction(0), Fraction(0))

STANDARD_GRAVITY = 9.80665          # m/s², exact by definition (CGPM 1901)


def _dim(length=0, mass=0, time=0) -> Dimension:
    return (Fraction(length), Fraction(mass), Fraction(time))


#: symbol -> (dimension, factor to SI, SI symbol with its exponent per power of the symbol)
SYMBOLS: dict[str, tuple[Dimension, float, tuple[tuple[str, int], ...]]] = {
    "m": (_dim(1), 1.0, (("m", 1),)),
    "mm": (_dim(1), 1e-3, (("m", 1),)),
    "cm": (_dim(1), 1e-2, (("m", 1),)),
    "km": (_dim(1), 1e3, (("m", 1),)),
    "um": (_dim(1), 1e-6, (("m", 1),)),
    "kg": (_dim(0, 1), 1.0, (("kg", 1),)),
    "g": (_dim(0, 1), 1e-3, (("kg", 1),)),              # the gram (see the module's note)
    "t": (_dim(0, 1), 1e3, (("kg", 1),)),
    "s": (_dim(0, 0, 1), 1.0, (("s", 1),)),
    "ms": (_dim(0, 0, 1), 1e-3, (("s", 1),)),
    "min": (_dim(0, 0, 1), 60.0, (("s", 1),)),
    "h": (_dim(0, 0, 1), 3600.0, (("s", 1),)),
    "N": (_dim(1, 1, -2), 1.0, (("N", 1),)),
    "kN": (_dim(1, 1, -2), 1e3, (("N", 1),)),
    "MN": (_dim(1, 1, -2), 1e6, (("N", 1),)),
    "J": (_dim(2, 1, -2), 1.0, (("J", 1),)),
    "kJ": (_dim(2, 1, -2), 1e3, (("J", 1),)),
    "W": (_dim(2, 1, -3), 1.0, (("W", 1),)),
    "kW": (_dim(2, 1, -3), 1e3, (("W", 1),)),
    "Pa": (_dim(-1, 1, -2), 1.0, (("Pa", 1),)),
    "kPa": (_dim(-1, 1, -2), 1e3, (("Pa", 1),)),
    "MPa": (_dim(-1, 1, -2), 1e6, (("Pa", 1),)),
    "GPa": (_dim(-1, 1, -2), 1e9, (("Pa", 1),)),
    "Hz": (_dim(0, 0, -1), 1.0, (("Hz", 1),)),
    "rad": (DIMENSIONLESS, 1.0, (("rad", 1),)),
    "deg": (DIMENSIONLESS, math.pi / 180.0, (("rad", 1),)),
}
#: The second reading of ``g`` alone: standard gravity, an acceleration.
GRAVITY_READING = (_dim(1, 0, -2), STANDARD_GRAVITY, (("m", 1), ("s", -2)))
#: Unit strings with two readings.
AMBIGUOUS = ("g",)

#: Names of the dimensions a scene's fields have, for messages.
DIMENSION_NAMES: dict[Dimension, str] = {
    DIMENSIONLESS: "dimensionless (or an angle)",
    _dim(1): "a length",
    _dim(0, 1): "a mass",
    _dim(0, 0, 1): "a time",
    _dim(0, 0, -1): "a frequency (1/s)",
    _dim(1, 0, -1): "a velocity",
    _dim(1, 0, -2): "an acceleration",
    _dim(1, 1, -2): "a force",
    _dim(0, 1, -2): "a stiffness (force/length)",
    _dim(0, 1, -1): "a damping coefficient (force·time/length)",
    _dim(2, 1, 0): "a moment of inertia",
    _dim(2, 1, -2): "a torque or energy",
    _dim(2, 1, -1): "a rotational damping coefficient (torque·time)",
    _dim(2, 1, -3): "a power",
    _dim(-1, 1, -2): "a pressure",
}


class UnitSyntaxError(ValueError):
    """A unit string that does not parse, or names an unknown symbol."""


@dataclass(frozen=True)
class Unit:
    """A parsed unit: ``value_in_unit * factor`` is the value in SI, whose unit is `si`."""
    text: str
    dimension: Dimension
    factor: float
    si: str
    reading: str = ""              # "gram" or "standard gravity" for the two readings of "g"

    def describe(self) -> str:
        """``'kN', a force`` or ``'g' (standard gravity), an acceleration``, for messages."""
        what = f" ({self.reading})" if self.reading else ""
        return f"'{self.text}'{what}, {describe_dimension(self.dimension)}"


def describe_dimension(dimension: Dimension | None) -> str:
    if dimension is None:
        return "a plain number"
    return DIMENSION_NAMES.get(dimension) or f"the dimension {base_name(dimension)}"


def base_name(dimension: Dimension) -> str:
    """A dimension in base SI units, Modelica syntax: ``kg.m2/s2``."""
    return _render([(sym, e) for sym, e in zip(("m", "kg", "s"), dimension) if e != 0])


# ----------------------------------------------------------------------------------------------
# Parsing
# ----------------------------------------------------------------------------------------------
_TOKEN = re.compile(r"\s*(?:(?P<symbol>[A-Za-z]+)|(?P<one>1(?![0-9]))|(?P<power>\^|\*\*)|(?P<int>[+-]?\d+)"
                    r"|(?P<sep>[*.·])|(?P<slash>/)|(?P<open>\()|(?P<close>\)))")


def _tokens(text: str) -> list[tuple[str, str, bool]]:
    """(kind, text, preceded by a space) of each token."""
    out, i = [], 0
    while i < len(text):
        match = _TOKEN.match(text, i)
        if match is None or match.end() == i:
            raise UnitSyntaxError(f"unexpected {text[i:]!r}")
        spaced = match.group(0)[:1].isspace()
        kind = match.lastgroup
        out.append((kind, match.group(kind), spaced))
        i = match.end()
    return out


class _Parser:
    """unit := product ('/' factor)* ;  product := factor (sep? factor)* ;
    factor := (SYMBOL | '1' | '(' product ')') exponent? ;  exponent := ('^' | '**')? INT"""

    def __init__(self, text):
        self.tokens = _tokens(text)
        self.i = 0

    def peek(self):
        return self.tokens[self.i] if self.i < len(self.tokens) else (None, None, False)

    def unit(self):
        factors = self.product()
        while self.peek()[0] == "slash":
            self.i += 1
            factors += [(sym, -e) for sym, e in self.factor()]
            if self.peek()[0] in ("sep", "symbol", "one", "open"):
                raise UnitSyntaxError("a product after '/' is ambiguous: put it in parentheses, e.g. N/(m.s)")
        if self.peek()[0] is not None:
            raise UnitSyntaxError(f"unexpected {self.peek()[1]!r}")
        return factors

    def product(self):
        factors = self.factor()
        while True:
            kind, _, spaced = self.peek()
            if kind == "sep":
                self.i += 1
            elif not (spaced and kind in ("symbol", "one", "open")):
                return factors
            factors += self.factor()

    def factor(self):
        kind, text, _ = self.peek()
        if kind == "symbol":
            self.i += 1
            if text not in SYMBOLS:
                raise UnitSyntaxError(f"unknown unit {text!r} (known: {', '.join(SYMBOLS)})")
            factors = [(text, 1)]
        elif kind == "one":
            self.i += 1
            factors = []
        elif kind == "open":
            self.i += 1
            factors = self.product()
            if self.peek()[0] != "close":
                raise UnitSyntaxError("a ')' is missing")
            self.i += 1
        else:
            raise UnitSyntaxError(f"expected a unit at {text!r}" if text else "a unit is missing")
        kind, _, spaced = self.peek()
        if kind == "power" or (kind in ("int", "one") and not spaced):
            if kind == "power":
                self.i += 1
            kind, text, _ = self.peek()
            if kind not in ("int", "one"):
                raise UnitSyntaxError("an exponent must be an integer" + (f" (at {text!r})" if text else ""))
            self.i += 1
            factors = [(sym, e * int(text)) for sym, e in factors]
        return factors


def _render(parts) -> str:
    """(symbol, exponent) pairs as a Modelica unit string: ``N.s/m``, ``kg.m2``, ``1/s``."""
    def one(sym, e):
        e = abs(e)
        return sym if e == 1 else f"{sym}{e.numerator}" if e.denominator == 1 else f"{sym}{float(e):g}"
    up = [one(s, e) for s, e in parts if e > 0]
    down = [one(s, e) for s, e in parts if e < 0]
    text = ".".join(up) or "1"
    if down:
        text += "/" + (down[0] if len(down) == 1 else "(" + ".".join(down) + ")")
    return text


def _build(text: str, factors, reading: str = "", substitute=None) -> Unit:
    dimension = [Fraction(0)] * 3
    factor = 1.0
    si: dict[str, int] = {}
    for sym, power in factors:
        dim, scale, parts = substitute if (substitute and sym == "g") else SYMBOLS[sym]
        for k in range(3):
            dimension[k] += dim[k] * power
        factor *= scale ** power
        for si_sym, e in parts:
            si[si_sym] = si.get(si_sym, 0) + e * power
    return Unit(text, tuple(dimension), factor, _render([(s, e) for s, e in si.items() if e != 0]), reading)


@lru_cache(maxsize=512)
def readings(text: str) -> tuple[Unit, ...]:
    """The readings of a unit string: one, or two for ``g`` alone (the gram, standard gravity).
    Raises UnitSyntaxError."""
    if not isinstance(text, str) or not text.strip():
        raise UnitSyntaxError("an empty unit (write \"1\" for a dimensionless value)")
    text = text.strip()
    factors = _Parser(text).unit()
    if text == "g":
        return (_build(text, factors, "the gram"), _build(text, factors, "standard gravity", GRAVITY_READING))
    return (_build(text, factors),)


def parse(text: str) -> Unit:
    """The unit of an unambiguous unit string (an element kind's declared unit, say)."""
    found = readings(text)
    if len(found) != 1:
        raise UnitSyntaxError(f"{text!r} is ambiguous")
    return found[0]


@lru_cache(maxsize=256)
def dimension_of(text: str) -> Dimension:
    """The dimension of a field's declared unit (``"N.s/m"``)."""
    return parse(text).dimension


#: The SI name given to a dimension an expression computes (a parameter without a unit whose
#: expression has one): the names the scenes use, else base units.
_PREFERRED = ("m", "kg", "s", "N", "N/m", "N.s/m", "m/s", "m/s2", "kg.m2", "N.m", "N.m.s", "1/s", "W", "Pa")


def si_name(dimension: Dimension) -> str:
    """The SI unit named for `dimension` ("" where no unit string can name it: a fractional power)."""
    if dimension == DIMENSIONLESS:
        return "1"
    if any(e.denominator != 1 for e in dimension):
        return ""
    for name in _PREFERRED:
        if parse(name).dimension == dimension:
            return name
    return base_name(dimension)


def for_reading(unit) -> str:
    """A unit as text for a reader: ``"1"`` (dimensionless; the FMU declares it so, as FMI's
    ``unit="1"``) and no unit as nothing, so that ``e = 0.5`` is not printed ``e = 0.5 1``."""
    return "" if unit is None or str(unit).strip() in ("", "1") else str(unit)
