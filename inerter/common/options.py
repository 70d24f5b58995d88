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


def output_folder(text, option: str = "--out", file: bool = False) -> Path:
    """The folder an output option names (`file`: the file), checked before any work (it is made
    later): not empty, not an existing file (`file`: not an existing folder), and not inside a file
    (``--out results.csv/run``)."""
    path = output_path(text, option, "a PNG file path, such as out/sweep/plot.png" if file else
                       "a folder path, such as out/run")
    if file and path.is_dir():
        raise OptionError(option, str(text), "a file path, such as out/sweep/plot.png", "names a folder")
    for part in (path.parents if file else (path, *path.parents)):
        if part.exists():
            if not part.is_dir():
                where = "names an existing file" if part == path else f"{part} is a file, not a folder"
                raise OptionError(option, str(text), "a folder (or a path where one can be made)", where)
            break
    return path


def count(value, option: str, least: int = 1):
    """A whole-number option (``--max-runs``, ``--workers``) of at least `least`."""
    if value is not None and value < least:
        raise OptionError(option, value, f"a whole number ≥ {least}")
    return value


def unwritable(exc: OSError) -> str:
    """The one-line error of an output file that cannot be written: its path and the system's reason."""
    where = f"{exc.filename}: " if exc.filename else ""
    return f"{where}{exc.strerror or exc}"
