"""The reference oracle: element forces derived from their definitions, never from the code it
checks. Each translational element's terminal distance L(q) is differentiated by forward-mode
automatic differentiation (:mod:`.derivation`): F = b·d²L/dt² for an inerter (the paper's Eq. 9,
or b·r̈·r̂ without the centripetal term, Eq. 8), k(L − L0) for a spring, c·dL/dt for a damper.

Layer: beside :mod:`inerter.engine` (neither imports the other), above :mod:`inerter.model`."""
from inerter.oracle.derivation import OracleElement  # noqa: F401
