"""Safe arithmetic expressions for numeric scene fields.

Any numeric field of a scene file may be written either as a number or as a string
expression over named parameters, in the spirit of Modelica parameter bindings::

    [parameters]
    La = 0.3
    Lb = { value = "La / 2", unit = "m", description = "lower link" }
    L  = "sqrt(La^2 + Lb^2)"

Expressions are parsed with :func:`ast.parse` and evaluated by walking the syntax tree
ourselves; user text is never handed to ``eval``, ``exec`` or ``compile``.  Only the
following constructs are accepted:

* numeric literals (integers and floats, not booleans or complex numbers),
* names of parameters and the constants ``pi`` and ``e``,
* unary ``+`` and ``-``,
* binary ``+``, ``-``, ``*``, ``/`` and the power operator, written ``^`` (Modelica)
  or ``**`` (Python), with the usual precedence,
* parentheses,
* calls, by plain name and with positional arguments only, of the functions in
  :data:`FUNCTIONS`.

Every problem (bad syntax, forbidden construct, unknown name, division by zero,
overflow, an argument outside a function's domain, ...) is reported as a
:class:`~inerter.common.errors.SceneError` naming the source, the field path, the offending
text and what was expected.  Results are always finite Python floats of magnitude at
most :data:`MAX_MAGNITUDE`.

Dimensions travel with the values (:class:`Dim`): a parameter with a unit
(:mod:`.units`) has one, and sums, products, powers and functions combine them, so a
field can refuse an expression whose parameters' units do not fit it
(:class:`UnitError`); numbers and parameters without a unit are plain numbers.
"""
from __future__ import annotations

import ast
import difflib
import functools
import keyword
import math
import numbers
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import NamedTuple
from fractions import Fraction

import numpy as np

from inerter.common.errors import SceneError
from inerter.scene import units

__all__ = [
    "CONSTANTS",
    "FUNCTIONS",
    "RESERVED_NAMES",
    "evaluate",
    "evaluate_parameters",
    "free_names",
    "parameter_meta",
    "quantity",
    "read_parameters",
]


def _min(*args: float) -> float:
    return min(args)


def _max(*args: float) -> float:
    return max(args)


#: Functions callable from expressions: name -> (implementation, least and greatest
#: number of arguments; ``None`` means any number).  All work on floats.
FUNCTIONS: dict[str, tuple[Callable[..., float], int, int | None]] = {
    "sqrt": (math.sqrt, 1, 1),
    "sin": (math.sin, 1, 1),
    "cos": (math.cos, 1, 1),
    "tan": (math.tan, 1, 1),
    "asin": (math.asin, 1, 1),
    "acos": (math.acos, 1, 1),
    "atan": (math.atan, 1, 1),
    "atan2": (math.atan2, 2, 2),
    "exp": (math.exp, 1, 1),
    "log": (math.log, 1, 1),  # natural logarithm, as in Modelica
    "log10": (math.log10, 1, 1),
    "abs": (abs, 1, 1),
    "min": (_min, 1, None),
    "max": (_max, 1, None),
    "hypot": (math.hypot, 1, None),
    "deg2rad": (math.radians, 1, 1),  # degrees -> radians
    "rad": (math.radians, 1, 1),  # alias of deg2rad: rad(90) == pi/2
}

#: Named constants available in every expression.
CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

#: Names a parameter may not take.
RESERVED_NAMES: frozenset[str] = frozenset(FUNCTIONS) | frozenset(CONSTANTS)

# What an expression string must look like (the "expected" part of most messages).
_EXPECTED_EXPRESSION = (
    "an arithmetic expression of numbers, parameters and "
    + ", ".join(FUNCTIONS)
    + ", "
    + ", ".join(CONSTANTS)
    + " (operators + - * / and ^ or ** for powers)"
)
_EXPECTED_VALUE = 'a number or an expression string such as "2*L"'
_EXPECTED_FINITE = "an expression with a finite value"
_EXPECTED_NAME = (
    "a name of ASCII letters, digits and underscores, not starting with a digit, "
    "not a Python keyword and not one of " + ", ".join(sorted(RESERVED_NAMES))
)
_TABLE_KEYS = ("value", "unit", "description")

#: The largest magnitude a value may have (in SI units). Finite values far beyond any mechanism
#: (a position of 1e300 m) overflow the arithmetic of the first step (squares, products with a
#: stiffness); 1e15 leaves every product a step forms finite.
MAX_MAGNITUDE = 1e15
_EXPECTED_MAGNITUDE = f"a number of magnitude at most {MAX_MAGNITUDE:g} (in SI units)"

# Expressions in scene files are short; refusing very long texts bounds the work
# done by the parser and the tree walk.
_MAX_LENGTH = 10_000
# How many known parameter names an "unknown name" message lists at most.
_MAX_LISTED_NAMES = 20

# Descriptions of forbidden syntax, for messages.
_BINARY_OPERATOR_SYMBOLS = {
    ast.Mod: "%",
    ast.FloorDiv: "//",
    ast.MatMult: "@",
    ast.LShift: "<<",
    ast.RShift: ">>",
    ast.BitOr: "|",
    ast.BitAnd: "&",
}
_NODE_DESCRIPTIONS = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscripting",
    ast.Slice: "slicing",
    ast.Compare: "a comparison",
    ast.BoolOp: "a boolean operator (and/or)",
    ast.IfExp: "a conditional expression",
    ast.Lambda: "a lambda",
    ast.NamedExpr: "an assignment expression (:=)",
    ast.Starred: "a starred argument",
    ast.List: "a list",
    ast.Tuple: "a tuple",
    ast.Set: "a set",
    ast.Dict: "a dict",
    ast.ListComp: "a comprehension",
    ast.SetComp: "a comprehension",
    ast.DictComp: "a comprehension",
    ast.GeneratorExp: "a generator expression",
    ast.JoinedStr: "an f-string",
    ast.FormattedValue: "an f-string",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
}


class _Problem(Exception):
    """Internal: what is wrong with an expression, before source and field are known."""

    def __init__(self, problem: str, expected: str = _EXPECTED_EXPRESSION):
        super().__init__(problem)
        self.problem = problem
        self.expected = expected


class _UnitProblem(_Problem):
    """Internal: terms whose dimensions do not combine."""


#: A number followed by a unit, as "900 mm" or "1.5e3mm": a unit written where a field takes none.
_NUMBER_AND_UNIT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z][\w.*/^()]*)\s*")


def _unit_problem(text: str) -> _Problem | None:
    """The problem of `text` where it is a number and a unit (``"900 mm"``), else None."""
    found = _NUMBER_AND_UNIT.fullmatch(text)
    if found is None:
        return None
    try:
        units.readings(found[2])
    except ValueError:                       # not a unit: the parser's own message says more
        return None
    return _Problem(f"a unit in a value ({found[2]!r})", _expected_without_unit(found[1], found[2]))


def _expected_without_unit(number, unit) -> str:
    """What a field given a unit expects: SI, or a parameter carrying the unit."""
    return ("a number in SI units (m, kg, s, N, rad); a unit is given to a parameter, "
            f'name = {{ value = {number}, unit = "{unit}" }} in [parameters], then "name" here')


# --------------------------------------------------------------------------- parsing


@functools.lru_cache(maxsize=4096)
def _compile(text: str) -> tuple[ast.expr, frozenset[str]]:
    """Parse and check `text`; return the expression tree and the names it uses.

    The tree is only ever read, so cached trees may be shared between calls.
    Raises `_Problem` (exceptions are not cached).
    """
    if not text.strip():
        raise _Problem("is empty")
    if len(text) > _MAX_LENGTH:
        raise _Problem(f"is too long ({len(text)} characters, at most {_MAX_LENGTH})")
    # Modelica writes powers as "^".  Python parses "^" as exclusive-or, whose
    # precedence is *below* "+" ("a^2+b^2" would mean "a^(2+b)^2"), so the operator is
    # rewritten to "**" before parsing to get the usual precedence.  Outside string
    # literals (which are rejected anyway) "^" can only be that operator.
    source = text.replace("^", "**")
    try:
        tree = ast.parse(source.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        # Besides syntax errors: null bytes, integer literals beyond the digit limit,
        # absurd nesting.  Only the first clause of the parser's message is kept.
        text_of = exc.msg if isinstance(exc, SyntaxError) else str(exc)
        brief = (text_of or "").split(":")[0].strip()[:80] or type(exc).__name__
        raise _unit_problem(text) or _Problem(f"does not parse ({brief})") from None
    names: set[str] = set()
    try:
        _check(tree.body, names)
    except RecursionError:
        raise _Problem("is too deeply nested") from None
    return tree.body, frozenset(names)


def _check(node: ast.AST, names: set[str]) -> None:
    """Reject anything but the allowed constructs; collect parameter names into `names`."""
    if isinstance(node, ast.Constant):
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            kind = {
                bool: "a boolean",
                str: "a string literal",
                bytes: "a bytes literal",
                complex: "a complex number",
            }.get(type(value), f"the literal {value!r}")
            raise _Problem(f"{kind} is not allowed")
        return
    if isinstance(node, ast.Name):
        if node.id in FUNCTIONS:
            raise _Problem(f"'{node.id}' is a function; call it as {node.id}(...)")
        if node.id not in CONSTANTS:
            names.add(node.id)
        return
    if isinstance(node, ast.UnaryOp):
        if not isinstance(node.op, (ast.UAdd, ast.USub)):
            symbol = {ast.Not: "not", ast.Invert: "~"}.get(type(node.op), "?")
            raise _Problem(f"the operator '{symbol}' is not allowed")
        _check(node.operand, names)
        return
    if isinstance(node, ast.BinOp):
        if not isinstance(node.op, tuple(_BINARY_OPERATORS)):
            symbol = _BINARY_OPERATOR_SYMBOLS.get(type(node.op), "?")
            raise _Problem(f"the operator '{symbol}' is not allowed")
        _check(node.left, names)
        _check(node.right, names)
        return
    if isinstance(node, ast.Call):
        if not isinstance(node.func, ast.Name):
            raise _Problem("only functions called by plain name are allowed")
        name = node.func.id
        if name not in FUNCTIONS:
            raise _Problem(f"'{name}' is not an allowed function")
        if node.keywords:
            raise _Problem(f"keyword arguments are not allowed (in the call of {name})")
        least, most = FUNCTIONS[name][1:]
        count = len(node.args)
        if count < least or (most is not None and count > most):
            if most is None:
                wanted = f"at least {least} argument{'s' if least != 1 else ''}"
            elif least == most:
                wanted = f"{least} argument{'s' if least != 1 else ''}"
            else:
                wanted = f"{least} to {most} arguments"
            raise _Problem(f"{name}() takes {wanted}, got {count}")
        for argument in node.args:
            _check(argument, names)
        return
    description = _NODE_DESCRIPTIONS.get(type(node), f"the construct '{type(node).__name__}'")
    raise _Problem(f"{description} is not allowed")


# ------------------------------------------------------------------------ evaluation


def _power(base: float, exponent: float) -> float:
    """``base ** exponent`` on reals, with clear messages instead of complex results."""
    if base == 0.0 and exponent < 0.0:
        raise _Problem("division by zero (zero raised to a negative power)", _EXPECTED_FINITE)
    if base < 0.0 and not exponent.is_integer():
        raise _Problem(
            "a negative number raised to a non-integer power has no real value",
            _EXPECTED_FINITE,
        )
    return math.pow(base, exponent)


def _divide(numerator: float, denominator: float) -> float:
    if denominator == 0.0:
        raise ZeroDivisionError
    return numerator / denominator


_BINARY_OPERATORS: dict[type, Callable[[float, float], float]] = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: _divide,
    ast.Pow: _power,
    # "^" is rewritten to "**" before parsing (see `_compile`), so exclusive-or never
    # reaches the evaluator; should it ever, it still means power.
    ast.BitXor: _power,
}


def _reduce(fn):
    return lambda *args: functools.reduce(fn, args)


class _Ops(NamedTuple):
    """The arithmetic an expression tree is evaluated with (:func:`_value`): a name's value as a
    number, the binary operators, the functions, and which results are accepted."""
    number: Callable
    binary: Mapping
    functions: Mapping
    finite: Callable


#: Floats: every problem (a division by zero, a value out of a function's domain) is an error.
_SCALAR = _Ops(float, _BINARY_OPERATORS, {name: f for name, (f, _, _) in FUNCTIONS.items()}, math.isfinite)
#: Arrays of samples (a derived output over the time history), numpy's element-wise functions
#: standing for the math module's: a sample where the expression has no value is NaN (or ±inf),
#: not an error, so that the other samples keep theirs.
_ARRAYS = _Ops(
    lambda x: np.asarray(x, dtype=float),
    {ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.divide, ast.Pow: np.power,
     ast.BitXor: np.power},
    {"sqrt": np.sqrt, "sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin, "acos": np.arccos,
     "atan": np.arctan, "atan2": np.arctan2, "exp": np.exp, "log": np.log, "log10": np.log10, "abs": np.abs,
     "min": _reduce(np.minimum), "max": _reduce(np.maximum), "hypot": _reduce(np.hypot),
     "deg2rad": np.radians, "rad": np.radians},
    lambda x: True)


def _known_names(names) -> str:
    """The "expected" text of an unknown-name message."""
    known = sorted(names)
    if not known:
        return "a defined parameter (none are defined) or " + ", ".join(CONSTANTS)
    listed = ", ".join(known[:_MAX_LISTED_NAMES])
    if len(known) > _MAX_LISTED_NAMES:
        listed += f", ... ({len(known) - _MAX_LISTED_NAMES} more)"
    return f"one of the parameters {listed} (or {', '.join(CONSTANTS)})"


def _unknown_name(name: str, known) -> _Problem:
    """The problem of a name that is neither a parameter nor a constant."""
    problem = f"unknown name '{name}'"
    close = difflib.get_close_matches(name, [str(n) for n in known], n=1)
    if close:
        problem += f" (did you mean '{close[0]}'?)"
    return _Problem(problem, _known_names(known))


#: Functions whose argument must be dimensionless (or an angle) and whose result is a plain number.
_DIMENSIONLESS_ARGUMENTS = ("sin", "cos", "tan", "asin", "acos", "atan", "exp", "log", "log10", "deg2rad", "rad")


class Dim(NamedTuple):
    """The dimension an expression computes, from its parameters' units. `dimension` None: a
    plain number (literals, constants, parameters without a unit), dimensionless in a product
    and of its partner's dimension in a sum. `loose`: a plain number multiplies a quantity in
    it, and may carry a unit the scene does not state (``0.5*w`` where 0.5 is a length), so a
    dimension that does not fit is let pass; the dimension of a quantity written with
    parameters alone is checked."""
    dimension: object = None
    loose: bool = False


PLAIN = Dim()


def _combine(a: Dim, b: Dim, what: str) -> Dim:
    """Terms that must share one dimension (a sum, min, max, hypot, atan2)."""
    if a.dimension is None or b.dimension is None or a.dimension == b.dimension:
        return Dim(a.dimension if a.dimension is not None else b.dimension, a.loose or b.loose)
    if a.loose or b.loose:
        return Dim(b.dimension if a.loose and not b.loose else a.dimension, True)
    raise _UnitProblem(f"{what} {units.describe_dimension(a.dimension)} and {units.describe_dimension(b.dimension)}",
                       "terms of one dimension")


def _product(a: Dim, b: Dim, sign: int) -> Dim:
    """The dimension of a * b (sign 1) or a / b (sign -1)."""
    if a.dimension is None and b.dimension is None:
        return PLAIN
    if b.dimension is None:
        return Dim(a.dimension, True)
    base = a.dimension if a.dimension is not None else units.DIMENSIONLESS
    return Dim(tuple(x + sign * y for x, y in zip(base, b.dimension)), a.loose or b.loose or a.dimension is None)


def _value(node: ast.expr, names: Mapping[str, float], dims: Mapping, ops: "_Ops | None" = None) -> tuple[float, Dim]:
    """Evaluate a checked expression tree: (value, its Dim). Every intermediate result is finite.
    `ops`: the arithmetic (default :data:`_SCALAR`, on floats; :data:`_ARRAYS` evaluates the same
    tree element by element on arrays of samples, a derived output's)."""
    ops = ops or _SCALAR
    if isinstance(node, ast.Constant):
        try:
            result = float(node.value)
        except OverflowError:
            raise _Problem(f"the number {node.value} is too large", _EXPECTED_FINITE) from None
        dim = PLAIN
    elif isinstance(node, ast.Name):
        # The constants take precedence (parameters may not be named like them).
        if node.id in CONSTANTS:
            return CONSTANTS[node.id], PLAIN
        if node.id not in names:
            raise _unknown_name(node.id, names)
        result = ops.number(names[node.id])
        dim = Dim(getattr(dims.get(node.id), "dimension", None))
    elif isinstance(node, ast.UnaryOp):
        operand, dim = _value(node.operand, names, dims, ops)
        result = -operand if isinstance(node.op, ast.USub) else operand
    elif isinstance(node, ast.BinOp):
        left, ldim = _value(node.left, names, dims, ops)
        right, rdim = _value(node.right, names, dims, ops)
        try:
            result = ops.binary[type(node.op)](left, right)
        except ZeroDivisionError:
            raise _Problem(f"division by zero in {ast.unparse(node)}", _EXPECTED_FINITE) from None
        except OverflowError:
            raise _Problem(f"overflow in {ast.unparse(node)}", _EXPECTED_FINITE) from None
        dim = _binary_dimension(node, ldim, rdim, right)
    elif isinstance(node, ast.Call):
        name = node.func.id  # type: ignore[attr-defined]  # checked by `_check`
        function = ops.functions[name]
        evaluated = [_value(argument, names, dims, ops) for argument in node.args]
        arguments = [a for a, _ in evaluated]
        try:
            result = ops.number(function(*arguments))
        except ZeroDivisionError:
            raise _Problem(f"division by zero in {ast.unparse(node)}", _EXPECTED_FINITE) from None
        except OverflowError:
            raise _Problem(f"overflow in {ast.unparse(node)}", _EXPECTED_FINITE) from None
        except ValueError:
            shown = ", ".join(f"{a:.17g}" for a in arguments)
            raise _Problem(
                f"argument out of the domain of {name}: {name}({shown})", _EXPECTED_FINITE
            ) from None
        dim = _call_dimension(name, [d for _, d in evaluated])
    else:  # pragma: no cover - `_check` lets nothing else through
        raise _Problem(f"the construct '{type(node).__name__}' is not allowed")
    if not ops.finite(result):
        raise _Problem(f"evaluates to {result} (in {ast.unparse(node)})", _EXPECTED_FINITE)
    return result, dim


def _binary_dimension(node: ast.BinOp, ldim: Dim, rdim: Dim, right: float) -> Dim:
    if isinstance(node.op, (ast.Add, ast.Sub)):
        return _combine(ldim, rdim, f"{ast.unparse(node)} adds")
    if isinstance(node.op, (ast.Mult, ast.Div)):
        return _product(ldim, rdim, 1 if isinstance(node.op, ast.Mult) else -1)
    # a power: the exponent a plain or dimensionless number, the base's dimension times it
    if rdim.dimension not in (None, units.DIMENSIONLESS) and not rdim.loose:
        raise _UnitProblem(f"the exponent of {ast.unparse(node)} is {units.describe_dimension(rdim.dimension)}",
                           "a dimensionless exponent")
    if ldim.dimension is None or ldim.dimension == units.DIMENSIONLESS:
        return ldim
    power = Fraction(right).limit_denominator(1000)
    if abs(float(power) - right) > 1e-12 * max(1.0, abs(right)):
        return Dim(None, True)                  # no dimension has an irrational power: let it pass
    return Dim(tuple(e * power for e in ldim.dimension), ldim.loose)


def _call_dimension(name: str, dims: list[Dim]) -> Dim:
    if name in _DIMENSIONLESS_ARGUMENTS:
        for d in dims:
            if d.dimension not in (None, units.DIMENSIONLESS) and not d.loose:
                raise _UnitProblem(f"{name}() of {units.describe_dimension(d.dimension)}",
                                   "a dimensionless argument (or an angle)")
        return PLAIN
    if name == "sqrt":
        d = dims[0]
        return d if d.dimension is None else Dim(tuple(e / 2 for e in d.dimension), d.loose)
    common = dims[0]
    for d in dims[1:]:
        common = _combine(common, d, f"{name}() mixes")
    return PLAIN if name == "atan2" else common


def _number(value, source: str, field: str) -> float:
    """A literal (non-string) field value as a finite float."""
    if isinstance(value, bool):
        raise SceneError(source, field, value, _EXPECTED_VALUE, "a boolean is not a number")
    if isinstance(value, dict) and "unit" in value:
        raise SceneError(source, field, value, _expected_without_unit(value.get("value", "..."), value["unit"]),
                         "a value with a unit outside [parameters]")
    if not isinstance(value, numbers.Real):
        raise SceneError(
            source, field, value, _EXPECTED_VALUE, f"a {type(value).__name__} is not a number"
        )
    try:
        result = float(value)
    except (OverflowError, ValueError, TypeError):
        raise SceneError(source, field, value, _EXPECTED_VALUE, "is not a usable number") from None
    if not math.isfinite(result):
        raise SceneError(source, field, value, "a finite number", "is not finite")
    return result


def _bounded(result: float, value, source: str, field: str) -> float:
    """`result`, if its magnitude is at most :data:`MAX_MAGNITUDE`."""
    if abs(result) > MAX_MAGNITUDE:
        raise SceneError(source, field, value, _EXPECTED_MAGNITUDE, "too large")
    return result


# ------------------------------------------------------------------------ public API


class UnitError(SceneError):
    """A value whose unit does not fit the field it is used in (a SceneError). `parameters`: the
    parameters with units whose dimensions met there."""

    def __init__(self, source, field, value, expected, problem=None, parameters=()):
        super().__init__(source, field, value, expected, problem)
        self.parameters = tuple(parameters)


def _with_units(expr, dims) -> list[str]:
    """The parameters of `expr` that have a unit."""
    if not isinstance(expr, str):
        return []
    try:
        used = _compile(expr)[1]
    except _Problem:
        return []
    return sorted(n for n in used if getattr(dims.get(n), "dimension", None) is not None)


def quantity(expr, names: Mapping[str, float], source: str, field: str, dims: Mapping | None = None):
    """(value, Dim) of a number or an expression over `names`. `dims` maps a parameter name to
    its unit (an object with ``.dimension`` and ``.describe()``); a number, and a parameter it
    does not list, is a plain number."""
    if not isinstance(expr, str):
        return _number(expr, source, field), PLAIN
    try:
        tree, _ = _compile(expr)
        return _value(tree, names, dims or {})
    except _UnitProblem as problem:
        raise UnitError(source, field, expr, problem.expected, problem.problem,
                        _with_units(expr, dims or {})) from None
    except _Problem as problem:
        raise SceneError(source, field, expr, problem.expected, problem.problem) from None
    except RecursionError:
        raise SceneError(source, field, expr, _EXPECTED_EXPRESSION, "is too deeply nested") from None


def evaluate(expr, names: Mapping[str, float], source: str, field: str, unit: str | None = None,
             dims: Mapping | None = None) -> float:
    """The value of a numeric field: a number, or an expression over `names`.

    `expr` is an int or float (booleans are refused) or an expression string.  `names`
    maps parameter names to their values (SI).  `source` and `field` (e.g. the scene file
    and ``bodies.arm.mass``) are used in error messages.  `unit`: the field's SI unit
    (``"kg"``); an expression whose parameters (`dims`, their units) give it another
    dimension is a :class:`UnitError`, while a plain number is taken as SI.  Returns a
    finite float of magnitude at most MAX_MAGNITUDE; raises :class:`SceneError` for
    anything else.
    """
    value, dim = quantity(expr, names, source, field, dims)
    if unit is not None and not fits(dim, units.dimension_of(unit)):
        raise UnitError(source, field, expr, f"a value in {unit} ({units.describe_dimension(units.dimension_of(unit))})",
                        "the unit does not fit: " + _culprits(expr, dims, dim.dimension), _with_units(expr, dims))
    return _bounded(value, expr, source, field)


def fits(dim: Dim, dimension) -> bool:
    """Whether an expression of Dim `dim` may stand where `dimension` is expected."""
    return dim.dimension is None or dim.loose or dim.dimension == dimension


def _culprits(expr, dims, dim) -> str:
    """What gave `expr` its dimension: its parameters with a unit."""
    used = _with_units(expr, dims)
    said = ", ".join(f"parameter {n} is in {dims[n].describe()}" for n in used)
    if isinstance(expr, str) and expr.strip() in used:
        return said
    return f"{units.describe_dimension(dim)}" + (f" ({said})" if said else "")


def free_names(expr, source: str, field: str) -> set[str]:
    """The parameter names an expression uses (constants and functions excluded).

    Numbers use no names.  The expression is fully checked (syntax and allowed
    constructs), so errors surface here with the right field path.
    """
    if not isinstance(expr, str):
        _number(expr, source, field)
        return set()
    try:
        return set(_compile(expr)[1])
    except _Problem as problem:
        raise SceneError(source, field, expr, problem.expected, problem.problem) from None


def _check_parameter_name(name, source: str, prefix: str) -> None:
    field = f"{prefix}.{name}"
    if not isinstance(name, str) or not name.isascii() or not name.isidentifier():
        raise SceneError(source, field, name, _EXPECTED_NAME, "invalid parameter name")
    if keyword.iskeyword(name):
        raise SceneError(source, field, name, _EXPECTED_NAME, "a Python keyword cannot be a parameter name")
    if name in RESERVED_NAMES:
        kind = "function" if name in FUNCTIONS else "constant"
        raise SceneError(
            source, field, name, _EXPECTED_NAME, f"the name of the {kind} '{name}' cannot be a parameter name"
        )


@dataclass(frozen=True)
class _Binding:
    """One parameter's entry: its value (a number or an expression), the field that names it,
    its unit (None: none given) and whether it is an override (a plain override is SI)."""
    name: str
    expr: object
    field: str
    unit: object = None
    unit_field: str = ""
    override: bool = False


def _parameter_binding(name: str, spec, source: str, prefix: str, override: bool = False) -> _Binding:
    """The value (number or expression), field path and unit string of a parameter entry."""
    field = f"{prefix}.{name}"
    if not isinstance(spec, Mapping):
        return _Binding(name, spec, field, override=override)
    for key in spec:
        if key not in _TABLE_KEYS:
            raise SceneError(
                source, f"{field}.{key}", spec[key], "only the keys value, unit and description",
                f"unknown key '{key}' in a parameter table",
            )
    if "value" not in spec:
        raise SceneError(
            source, field, dict(spec), "a table with 'value' (and optionally 'unit', 'description')",
            "missing 'value'",
        )
    for key in ("unit", "description"):
        if key in spec and not isinstance(spec[key], str):
            raise SceneError(source, f"{field}.{key}", spec[key], "a string", f"'{key}' must be a string")
    return _Binding(name, spec["value"], f"{field}.value", spec.get("unit"), f"{field}.unit", override)


@dataclass(frozen=True)
class ParameterValue:
    """A parameter as read: its value in SI, its unit (the declared one, or one its expression
    computes: None for a plain number), the SI unit of its value and the value as given."""
    value: float
    unit: "units.Unit | None"
    si_unit: str
    given: str = ""                  # "1500 mm" where the unit is not SI

    @property
    def dimension(self):
        return None if self.unit is None else self.unit.dimension

    def describe(self) -> str:
        return self.unit.describe() if self.unit is not None else "a plain number"


def _unit_of(binding: _Binding, source: str, reading: int):
    """The Unit of a binding's unit string (`reading`: which, for a string with two)."""
    if binding.unit is None:
        return None
    try:
        found = units.readings(binding.unit)
    except units.UnitSyntaxError as exc:
        raise SceneError(source, binding.unit_field, binding.unit,
                         'a unit such as "m", "mm", "kN/m", "N*s/m", "kg*m^2", "deg", "g" or "1"',
                         f"not a unit: {exc}") from None
    return found[min(reading, len(found) - 1)]


def ambiguous_units(raw: Mapping[str, object], fixed: Mapping[str, object] | None = None) -> list[str]:
    """The parameters (of `raw` and `fixed`) whose unit string has two readings (``"g"``)."""
    out = []
    for table in (raw, fixed or {}):
        for name, spec in table.items():
            unit = spec.get("unit") if isinstance(spec, Mapping) else None
            if isinstance(unit, str) and unit.strip() in units.AMBIGUOUS and name not in out:
                out.append(name)
    return out


def read_parameters(
    raw: Mapping[str, object],
    source: str,
    prefix: str = "parameters",
    fixed: Mapping[str, object] | None = None,
    reading: Mapping[str, int] | None = None,
) -> dict[str, ParameterValue]:
    """Read a scene's parameter table: values in SI, with their units.

    `raw` maps each parameter name to a number, an expression string or a table
    ``{value = ..., unit = "...", description = "..."}``.  Parameters may refer to each
    other in any order; they are evaluated in dependency order and a circular
    definition is an error.  A table's number (or an expression of plain numbers) is in
    its unit and converted to SI; an expression over parameters with units is a quantity
    whose dimension must be the unit's.  `fixed` gives entries that replace those of
    existing parameters (overrides from the command line or an FMU), read as entries of
    `raw` are, except that a plain number or expression is in SI (the FMU's units); the
    expressions they replace are still checked but not evaluated.  `reading` chooses
    the reading of an ambiguous unit (``"g"``: 0 the gram, 1 standard gravity) by name.

    Errors name the field ``<prefix>.<name>`` (``<prefix>.<name>.value`` or ``.unit``
    for tables).
    """
    if not isinstance(raw, Mapping):
        raise SceneError(source, prefix, raw, "a table of name = value entries", "is not a table")
    fixed = dict(fixed or {})
    reading = dict(reading or {})

    bindings: dict[str, _Binding] = {}
    for name, spec in raw.items():
        _check_parameter_name(name, source, prefix)
        bindings[name] = _parameter_binding(name, spec, source, prefix)

    # Every expression of the scene is checked, those an override replaces included: they are
    # still part of the scene. An override is then read as the entry it replaces would be.
    for name, b in bindings.items():
        _check_names(b.expr, b.field, bindings, source)
    declared = {name: _unit_of(b, source, reading.get(name, 0)) for name, b in bindings.items()}
    for name, value in fixed.items():
        if name not in bindings:
            known = ", ".join(sorted(bindings)) or "(none)"
            raise SceneError(
                source, f"{prefix}.{name}", value, f"one of the parameters {known}", f"no parameter '{name}' to override"
            )
        bindings[name] = _parameter_binding(name, value, source, prefix, override=True)
        _check_names(bindings[name].expr, bindings[name].field, bindings, source)

    order_of = {name: index for index, name in enumerate(bindings)}
    depends = {name: sorted(free_names(b.expr, source, b.field), key=order_of.__getitem__)
               for name, b in bindings.items()}
    values: dict[str, float] = {}
    read: dict[str, ParameterValue] = {}
    for name in _dependency_order(depends, bindings, source):
        b = bindings[name]
        read[name] = _read_one(b, declared[name], _unit_of(b, source, reading.get(name, 0)), values, read, source)
        values[name] = read[name].value
    return {name: read[name] for name in bindings}


def _read_one(b: _Binding, declared, unit, values, read, source) -> ParameterValue:
    """One parameter's value in SI, from its binding `b` with its own `unit` (None: none given)
    and the `declared` unit of the scene's entry (the same, unless `b` is an override)."""
    value, computed = quantity(b.expr, values, source, b.field, read)
    dim = computed.dimension
    if declared is not None and unit is not None and unit.dimension != declared.dimension:
        raise UnitError(source, b.unit_field, b.unit, f"a unit of the dimension the scene declares: "
                        f"{declared.describe()}", f"the unit does not fit: {unit.describe()}", (b.name,))
    target = unit or (declared if b.override else None)
    if target is None:                       # no unit: a plain number, or what its expression computes
        if dim is None or computed.loose:
            return ParameterValue(_bounded(value, b.expr, source, b.field), None, "1")
        si = units.si_name(dim)
        return ParameterValue(_bounded(value, b.expr, source, b.field),
                              units.Unit(si, dim, 1.0, si, "from its expression"), si)
    if not fits(computed, target.dimension):
        raise UnitError(source, b.field, b.expr, f"a value in {target.describe()}",
                        "the unit does not fit: " + _culprits(b.expr, read, dim), (b.name, *_with_units(b.expr, read)))
    # a number in its table's unit (a quantity of the unit's dimension is SI already)
    plain_in_unit = unit is not None and dim != target.dimension
    si = value * target.factor if plain_in_unit else value
    given = f"{value:g} {target.text}" if plain_in_unit and target.factor != 1.0 else ""
    return ParameterValue(_bounded(si, b.expr, source, b.field), target, target.si, given)


def evaluate_parameters(
    raw: Mapping[str, object],
    source: str,
    prefix: str = "parameters",
    fixed: Mapping[str, object] | None = None,
) -> dict[str, float]:
    """The parameters' values in SI, ``{name: value}`` in the order of `raw` (see read_parameters)."""
    return {name: p.value for name, p in read_parameters(raw, source, prefix, fixed).items()}


def _check_names(expr, field: str, bindings, source: str) -> None:
    """`expr` parses and uses only parameters of `bindings`."""
    unknown = sorted(free_names(expr, source, field).difference(bindings))
    if unknown:
        problem = _unknown_name(unknown[0], bindings)
        raise SceneError(source, field, expr, problem.expected, problem.problem)


def _dependency_order(depends: Mapping[str, list[str]], bindings: Mapping[str, "_Binding"], source: str) -> list[str]:
    """Names ordered so that each comes after those it depends on (depth-first)."""
    done: set[str] = set()
    order: list[str] = []
    for root in depends:
        if root in done:
            continue
        path = [root]  # the chain of names being visited
        on_path = {root}
        stack = [iter(depends[root])]
        while stack:
            for dependency in stack[-1]:
                if dependency in on_path:
                    cycle = path[path.index(dependency):] + [dependency]
                    b = bindings[cycle[0]]
                    raise SceneError(
                        source, b.field, b.expr, "parameters that do not depend on themselves",
                        "circular definition " + " -> ".join(cycle),
                    )
                if dependency not in done:
                    path.append(dependency)
                    on_path.add(dependency)
                    stack.append(iter(depends[dependency]))
                    break
            else:  # all dependencies of path[-1] are done
                stack.pop()
                name = path.pop()
                on_path.discard(name)
                done.add(name)
                order.append(name)
    return order


def parameter_meta(raw) -> dict[str, dict]:
    """Unit and description of each parameter: ``{name: {"unit": ..., "description": ...}}``.

    The unit defaults to ``"1"`` (dimensionless) and the description to ``""``.  This
    does not validate `raw`; :func:`evaluate_parameters` does.
    """
    meta: dict[str, dict] = {}
    if not isinstance(raw, Mapping):
        return meta
    for name, spec in raw.items():
        unit, description = "1", ""
        if isinstance(spec, Mapping):
            unit = str(spec.get("unit", "1"))
            description = str(spec.get("description", ""))
        meta[name] = {"unit": unit, "description": description}
    return meta


# ------------------------------------------------------------------- derived outputs


#: A reference to an output in a derived output's expression: a name, a name with a field
#: (``brace.f``), either with an index (``S1.r[1]``); not after a digit, a dot or a bracket (the
#: exponent of ``1e-3``).
_OUTPUT_REFERENCE = re.compile(r"(?<![\w.\]])[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)?(?:\[\d+\])?")
#: The name the k-th output an expression reads takes in its parsed form (``S1.r[1]`` is not a name
#: the expression syntax has: attribute access and subscripts are refused).
_PLACEHOLDER = "__output{}"
#: Trial values of the outputs when the dimension of an expression is worked out: the first set at
#: which the expression has a value gives it (a dimension does not depend on values).
_TRIALS = (lambda k: 1.0 + 0.37 * k, lambda k: 0.25 + 0.0173 * k, lambda k: -0.5 - 0.113 * k)
_EXPECTED_OUTPUT_EXPRESSION = ('an expression over the scene\'s outputs and parameters, e.g. '
                               '"hypot(S1.r[1] - S0.r[1], S1.r[2] - S0.r[2])"')


@dataclass(frozen=True)
class OutputExpression:
    """A derived output's expression, checked: `code` is `text` with the k-th output it reads,
    ``reads[k]``, written ``__output{k}``; `constants` the parameters it uses (name, SI value);
    `dimension` the dimension of its value (None where it cannot be worked out); `loose` where a
    plain number multiplies a quantity in it (the number may carry a unit: :class:`Dim`)."""
    text: str
    code: str
    reads: tuple[str, ...]
    constants: tuple[tuple[str, float], ...]
    dimension: tuple | None
    loose: bool = False

    def evaluate(self, values) -> np.ndarray:
        """The expression at each sample: `values[k]` the samples of ``reads[k]`` (arrays of one
        shape, or floats), element by element; NaN where it has no value (a square root of a
        negative number, 0/0)."""
        names = dict(self.constants)
        names.update({_PLACEHOLDER.format(k): v for k, v in enumerate(values)})
        with np.errstate(all="ignore"):
            return _value(_compile(self.code)[0], names, {}, _ARRAYS)[0]


def output_expression(text, outputs: Mapping[str, str | None], names: Mapping[str, float], source: str,
                      field: str, dims: Mapping | None = None) -> OutputExpression:
    """Check a derived output's expression: `outputs` maps the outputs it may read to their SI
    units (None: of no one dimension), `names` the parameters to their SI values (`dims`: their
    units). Raises a one-line :class:`SceneError` naming `field` for bad syntax, an unknown output
    or name, an expression that reads no output, and a :class:`UnitError` for terms whose
    dimensions do not combine."""
    if not isinstance(text, str):
        raise SceneError(source, field, text, _EXPECTED_OUTPUT_EXPRESSION, "not a string")
    reads: list[str] = []

    def placeholder(match):
        token = match.group(0)
        if token in outputs:
            if token not in reads:
                reads.append(token)
            return _PLACEHOLDER.format(reads.index(token))
        if "." in token or "[" in token:
            problem = f"unknown output '{token}'"
            close = difflib.get_close_matches(token, list(outputs), n=1)
            raise SceneError(source, field, text, "an output of the scene: " + _known_outputs(outputs),
                             problem + (f" (did you mean '{close[0]}'?)" if close else ""))
        return token
    code = _OUTPUT_REFERENCE.sub(placeholder, text) if len(text) <= _MAX_LENGTH else text
    try:
        used = _compile(code)[1]
    except _Problem as problem:
        raise SceneError(source, field, text, problem.expected, _named(problem.problem, reads)) from None
    for name in sorted(used):
        if not name.startswith("__output") and name not in names:
            raise SceneError(source, field, text, "an output of the scene (" + _known_outputs(outputs)
                             + ") or a parameter", _unknown_name(name, names).problem)
    if not reads:
        raise SceneError(source, field, text, _EXPECTED_OUTPUT_EXPRESSION, "reads no output")
    constants = tuple((n, float(names[n])) for n in sorted(used) if n in names)
    dim = _output_dimension(text, code, reads, outputs, names, dims or {}, source, field)
    return OutputExpression(text, code, tuple(reads), constants, dim.dimension, dim.loose)


def _known_outputs(outputs) -> str:
    known = list(outputs)
    listed = ", ".join(known[:_MAX_LISTED_NAMES])
    return listed + (f", ... ({len(known) - _MAX_LISTED_NAMES} more)" if len(known) > _MAX_LISTED_NAMES else "")


def _output_dimension(text, code, reads, outputs, names, dims, source, field):
    """The Dim of a derived output's value, from the units of the outputs and parameters it reads:
    dimensionless where the expression makes a plain number of them (atan2, sin, a ratio); None
    where it reads an output of no one unit and has no dimension from the others, or no trial
    values give the expression a value."""
    with_units = dict(dims)
    for k, name in enumerate(reads):
        unit = outputs[name]
        with_units[_PLACEHOLDER.format(k)] = Dim(units.dimension_of(unit) if unit else None)
    tree = _compile(code)[0]
    for trial in _TRIALS:
        values = dict(names)
        values.update({_PLACEHOLDER.format(k): trial(k) for k in range(len(reads))})
        try:
            dim = _value(tree, values, with_units)[1]
        except _UnitProblem as problem:
            raise UnitError(source, field, text, problem.expected, _named(problem.problem, reads)) from None
        except _Problem:          # no value at these trial values: try others
            continue
        if dim.dimension is None and all(outputs[name] for name in reads):
            return Dim(units.DIMENSIONLESS, dim.loose)   # a plain number of quantities of known units (atan2)
        return dim
    return PLAIN


def _named(problem: str, reads) -> str:
    """A problem's text with the outputs' names for their placeholders."""
    for k in reversed(range(len(reads))):
        problem = problem.replace(_PLACEHOLDER.format(k), reads[k])
    return problem
