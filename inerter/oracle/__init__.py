"""The reference oracle: element forces derived from their definitions, never from the code it
checks. Each translational element's terminal distance L(q) is differentiated by forward-mode
automatic differentiation (:mod:`.derivation`): F = b·d²L/dt² for an inerter (the paper's Eq. 9,
or b·r̈·r̂ without the centripetal term, Eq. 8), k(L − L0) for a spring, c·dL/dt for a damper.
A rotational spring's torque is the derivative of its potential ½k(φ − φ0)², a rotational damper's
that of its dissipation function ½d φ̇², by the same differentiation, on the relative angle in 2D
and the twist about the element's axis in 3D (:mod:`.rotational`). The joints' C(q) are written
from each joint's definition in the scene and differentiated on the same Jets, C_v = ∂Ċ/∂v and
γ = −C̈|v̇=0 (:mod:`.joints`); point forces enter by virtual work, the weight as −∂V/∂v of
V = −Σ m g·R and the ground motion as the bodies' d'Alembert forces −m a_g (:class:`OracleMechanism`,
:mod:`.mechanism`). An inerter device's internal states (series compliance,
backlash, dissipated energy) come from an extended Lagrangian in which the series node's
deflection s is one more coordinate (:mod:`.series`), solved with the rest in one system for
(v̇, s̈, λ) on the engine's layout of z. A screw efficiency scales the inerter's Lagrange term (from
T = ½ b ẋ², ẋ = L̇, or u̇ in series) by 1 + λ(τ), written from the definition (:mod:`.efficiency`),
its loss b λ ẍ ẋ joining the dissipated power; its mode σ = sign(ẍ) is the one assignment of the
scene's efficient elements' signs, of all 2ⁿ tried, that its own solution agrees with (a mount
beside it is refused). The coordinates, the bodies' mass matrix and gyroscopic term and the solution
of Eq. (33) are the model's Mechanism's. A scene with an element of a kind the oracle has no
definition of is refused (:func:`require_definitions`), and so is a 3D scene with joints or point
forces in Z-X-Z Euler angles (the Jets are written on quaternions).

Layer: beside :mod:`inerter.engine` (neither imports the other), above :mod:`inerter.model`."""
from inerter.oracle.derivation import OracleElement, require_definitions  # noqa: F401
from inerter.oracle.mechanism import OracleMechanism  # noqa: F401
