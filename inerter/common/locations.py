"""Where the package finds the files it reads but does not import: the FMU sources and the scenes.

Their one source is the repository's ``fmu_src/`` and ``scenarios/``, which a source checkout (an
editable install included) reads in place. Building a wheel copies both into ``inerter/_data/``
(``setup.py``), where an installed package, which has no repository beside it, finds them.
"""
from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parents[1]
#: Where a built package carries its copies (setup.py writes them there).
INSTALLED_DATA = PACKAGE_DIR / "_data"


def _folder(name: str) -> Path:
    checkout = PACKAGE_DIR.parent
    if (checkout / "pyproject.toml").is_file() and (checkout / name).is_dir():
        return checkout / name
    return INSTALLED_DATA / name


def fmu_sources() -> Path:
    """The folder of the FMU slave, its module template, the status shim and the controller."""
    return _folder("fmu_src")


def scenarios() -> Path:
    """The folder of the shipped scenes (``two_bar_2d.toml``, ``hard/``, ``records/``, ...)."""
    return _folder("scenarios")
