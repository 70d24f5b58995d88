"""The compiled mechanism: a validated scene turned into bodies, coordinates, points, joints,
elements and forces with index maps built once (:mod:`.mechanism`), the point kinematics of
Eqs. (15-25) in 2D (:mod:`.planar`) and 3D (:mod:`.spatial`), the joints' constraint rows
(:mod:`.joints`) and the readable per-element evaluators (:mod:`.evaluators`, which call the laws of
:mod:`inerter.elements`). Only what the scene declares is compiled in.

Layer: above :mod:`inerter.scene`, below :mod:`inerter.engine` and :mod:`inerter.oracle`."""
