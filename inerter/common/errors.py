"""The project's own exceptions.

Every error a user can cause names *where* (scene file or FMU variable), the field path,
the offending value and what was expected, so that a message alone is enough to fix it.
"""
from __future__ import annotations


class InerterError(Exception):
    """Base class of all errors raised by the `inerter` package."""


class SceneError(InerterError, ValueError):
    """A scene file (or an override of one of its fields) is invalid.

    The message reads ``<source>: <field>: <problem> (got <value>; expected <expected>)``.
    """

    def __init__(self, source: str, field: str, value, expected: str, problem: str | None = None):
        self.source = str(source)
        self.field = field
        self.value = value
        self.expected = expected
        self.problem = problem or "invalid value"
        super().__init__(
            f"{self.source}: {field}: {self.problem} (got {shown(value)}; expected {expected})"
        )


#: The longest a value is quoted in a message (a whole table given where a number was expected).
MAX_SHOWN = 200


def shown(value) -> str:
    """`value` as a message quotes it: its repr on one line, cut to :data:`MAX_SHOWN` characters."""
    text = repr(value)
    return text if len(text) <= MAX_SHOWN else text[:MAX_SHOWN - 3] + "..."


class SimulationError(InerterError, RuntimeError):
    """A simulation cannot go on: the state stays at the last good time `time`.

    `recoverable`: raised where a state cannot be evaluated (a singular or non-finite linear solve)
    and so, inside an explicit integrator's trial step, a shorter step may avoid it."""

    def __init__(self, message: str, time: float | None = None, recoverable: bool = False):
        self.time = time
        self.message = message
        self.recoverable = recoverable
        text = message if time is None else f"t = {time:.9g} s: {message}"
        super().__init__(text)

    def append(self, text: str):
        """Add `text` to the message: what the caller knows of the cause."""
        self.message += text
        self.args = (self.args[0] + text,)


#: Terminal distance below which a translational element's direction is undefined (m).
MIN_LENGTH = 1e-9


class TerminalsMeet(SimulationError):
    """The two terminals of a translational element coincide: r̂ is undefined."""
