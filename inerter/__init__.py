"""inerter: planar multibody mechanisms with springs, dampers and inerters, modelled as in
Zhu, Macdonald, Jiang & Neild, J. Sound Vib. 540 (2022) 117290, and shipped as FMI 2.0 FMUs."""
from inerter.common.errors import InerterError, SceneError, SimulationError
from inerter.api import Model, Result, load

__version__ = "0.1.0"
__all__ = ["load", "Model", "Result", "InerterError", "SceneError", "SimulationError", "__version__"]
