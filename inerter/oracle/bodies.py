"""The bodies' inertia derived from their kinetic energy, for the oracle's mechanism.

Each body's T is written from its definition in the scene (mass m, inertia J about its centre):
T = ½ m |Ṙ|² + ½ J θ̇² in 2D, T = ½ m |Ṙ|² + ½ ω̄ᵀ J ω̄ in 3D, with ω̄ the angular velocity in the
body frame (the velocity coordinates v = (Ṙ, θ̇) or (Ṙ, ω̄) of each body, paper Sec. 3), on Jets
of the body's own velocity coordinates (:class:`~.jets.Jet`: T's gradient ∂T/∂v).

* **Mass matrix.** T is quadratic in v, so ∂T/∂v = M v: M's column j is ∂T/∂v at v = e_j.
* **Velocity forces.** Ṙ and θ̇ are the rates of coordinates, whose Lagrange equations carry no
  velocity term here (T does not depend on R or θ). ω̄ is a quasi-velocity: with it, the
  Boltzmann–Hamel equations on the rotations (the Euler–Poincaré equations) read
  d/dt ∂T/∂ω̄ + ω̄ × ∂T/∂ω̄ = τ̄ (Greenwood, *Advanced Dynamics*, 2003, Sec. 6.5; Marsden & Ratiu,
  *Introduction to Mechanics and Symmetry*, 1999, Sec. 13.5), so the generalised force on ω̄ carries
  −ω̄ × ∂T/∂ω̄. T is quadratic in v, so ∂T/∂ω̄ is the mass block's ω̄ rows times v: taken from
  the block derived above rather than from a Jet of T at every state (the same numbers, cheaper).

Nothing here reads the model's mass matrix or the engine's gyroscopic law.
"""
from __future__ import annotations

import numpy as np

from inerter.oracle.jets import Jet


def kinetic_energy(body, dim: int, v) -> Jet:
    """A body's T at its velocity coordinates `v` (3 in 2D, 6 in 3D), on Jets over them."""
    n = len(v)
    x = [Jet(float(v[i]), 0.0, 0.0, np.eye(n)[i]) for i in range(n)]
    T = 0.5 * float(body.mass) * sum((x[i] * x[i] for i in range(dim)), Jet.constant(0.0, n))
    if dim == 2:
        return T + 0.5 * float(body.inertia) * x[2] * x[2]
    J = np.asarray(body.inertia, dtype=float)
    w = x[3:6]
    for r in range(3):
        for c in range(3):
            T = T + 0.5 * float(J[r, c]) * w[r] * w[c]
    return T


def mass_block(body, dim: int) -> np.ndarray:
    """The body's block of the mass matrix: ∂T/∂v at each unit velocity (T quadratic in v)."""
    n = 3 if dim == 2 else 6
    return np.column_stack([kinetic_energy(body, dim, np.eye(n)[j]).g for j in range(n)])


def velocity_force(block: np.ndarray, v) -> np.ndarray:
    """A 3D body's velocity forces on its coordinates (Ṙ, ω̄): −ω̄ × ∂T/∂ω̄ on ω̄ (Hamel), with
    ∂T/∂v = block · v (`block`: :func:`mass_block`)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(6)
    out[3:6] = -np.cross(v[3:6], (block @ v)[3:6])
    return out
