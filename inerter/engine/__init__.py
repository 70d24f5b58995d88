"""The engine: assembly of the augmented system of Eqs. (27-33), constraint handling, integrators
(:mod:`.simulation`, :mod:`.integrators`), the compiled kernels (:mod:`.kernels`, built from the laws
of :mod:`inerter.elements`) and their tables (:mod:`.compiled`, :mod:`.compiled_spatial`,
:mod:`.tables`), outputs (:mod:`.outputs`), metrics (:mod:`.metrics`) and the static equilibrium
with its linearisation (:mod:`.equilibrium`).

Layer: above :mod:`inerter.model`; the oracle (:mod:`inerter.oracle`) stands beside it and the two
never import each other."""
