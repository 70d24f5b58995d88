"""Packaging hook: the wheel carries the FMU sources, the shipped scenes and the device data.

``fmu_src/``, ``scenarios/`` and ``devices/`` stay at the top of the repository, their one source.
Building the package copies them into ``inerter/_data/``, where an installed inerter, which has no repository
beside it, finds them (``inerter/common/locations.py``). An editable install reads the originals.
"""
import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
#: Folders of the repository the installed package reads.
DATA = ("fmu_src", "scenarios", "devices")


class build_py_with_data(build_py):
    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for name in DATA:
            target = Path(self.build_lib) / "inerter" / "_data" / name
            shutil.rmtree(target, ignore_errors=True)
            shutil.copytree(HERE / name, target,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.pyo"))


setup(cmdclass={"build_py": build_py_with_data})
