"""inerter: planar and spatial (2D and 3D) multibody mechanisms with springs, dampers and
inerters, modelled as in Zhu, Macdonald, Jiang & Neild, J. Sound Vib. 540 (2022) 117290, and
shipped as FMI 2.0 FMUs.

``model = inerter.load("scenarios/two_bar_2d.toml", b=20)`` reads a scene (:class:`Model`);
``result = model.simulate()`` runs it (:class:`Result`). The command line is ``inerter``
(:mod:`inerter.cli`); the FMUs are :mod:`inerter.fmu`. Guide: README.md and docs/usage.md."""
from inerter.common.errors import InerterError, SceneError, SimulationError
from inerter.api import Model, Result, load

__version__ = "0.1.0"
__all__ = ["load", "Model", "Result", "InerterError", "SceneError", "SimulationError", "__version__"]
