"""What the commands' options share: the error of an option's value, and the check of an output path."""
from __future__ import annotations

from pathlib import Path

from inerter.common.errors import InerterError, shown


class OptionError(InerterError):
    """A command-line option has a value the command cannot use; the message reads
    ``<option>: <problem> (got <value>; expected <expected>)``, like a scene error's."""

    def __init__(self, option: str, value, expected: str, problem: str = "out of range"):
        super().__init__(f"{option}: {problem} (got {shown(value)}; expected {expected})")


def output_path(text, option: str = "--out", expected: str = "a folder path, such as out/run") -> Path:
    """The path an output option names. An empty one (``--out ""``) is an error: as a path it is
    the current folder, which the command would fill without a word."""
    if not str(text).strip():
        raise OptionError(option, text, expected, "empty path")
    return Path(text)
