"""Where the package finds the files it reads but does not import: the FMU sources, the scenes and
the inerter devices' data.

Their one source is the repository's ``fmu_src/``, ``scenarios/`` and ``devices/``, which a source
checkout (an editable install included) reads in place. Building a wheel copies them into
``inerter/_data/`` (``setup.py``), where an installed package, which has no repository beside it,
finds them.
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


def devices() -> Path:
    """The folder of the inerter devices' data (``ballscrew_device.toml``: each value with its unit and
    source), which the device study reads; not scenes."""
    return _folder("devices")
