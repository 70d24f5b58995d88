"""Scene files: reading and validating TOML (:mod:`.reader`), parameter expressions
(:mod:`.expressions`), units (:mod:`.units`), files read with a cap on their size (:mod:`.files`),
ground-motion records (:mod:`.ground_motion`) and command-line overrides (:mod:`.overrides`). A
scene is a validated description, in SI; nothing here simulates.

Layer: above :mod:`inerter.elements` (each kind's parameters), below :mod:`inerter.model`."""
from inerter.scene.reader import GROUND, Scene, load_scene  # noqa: F401
