"""The reference oracle's translational elements: forces from the definitions, by differentiation.

Every translational element is a function of its terminal distance L(q) only. The oracle computes
L(q) from the bodies' poses and differentiates it with forward-mode automatic differentiation
(:class:`Jet`), never using the closed forms of Eqs. (15–20):

* the gradient ∇L (exact), so that L̇ = ∇L·q̇ and the generalised force is −F ∇L,
* the second derivative along the motion, q̇ᵀ∇²L q̇ (exact, Taylor mode), so that
  L̈ = ∇L·q̈ + q̇ᵀ∇²L q̇.

Inerter with the centripetal term: F = b L̈ (Eq. 9). Without it (Eq. 8): F = b r̈·r̂, which the
oracle obtains as b(L̈ − |ṙ⊥|²/L) with ṙ from the Jacobian of r(q), again by differentiation.
An error in either the fast path or this module shows up as a disagreement between the two.
"""
from __future__ import annotations

import math

import numpy as np

from .elements import MIN_LENGTH, TerminalsMeet
from .planar import DOF_PER_BODY


class Jet:
    """A number with its gradient g (w.r.t. n chosen coordinates) and its first and second
    derivatives d1, d2 along a curve q(t) = q + q̇ t (so d2 = q̇ᵀ∇²f q̇)."""

    __slots__ = ("v", "d1", "d2", "g")

    def __init__(self, v, d1, d2, g):
        self.v, self.d1, self.d2, self.g = v, d1, d2, g

    @staticmethod
    def constant(value, n):
        return Jet(float(value), 0.0, 0.0, np.zeros(n))

    def __add__(self, o):
        if not isinstance(o, Jet):
            return Jet(self.v + o, self.d1, self.d2, self.g)
        return Jet(self.v + o.v, self.d1 + o.d1, self.d2 + o.d2, self.g + o.g)

    __radd__ = __add__

    def __neg__(self):
        return Jet(-self.v, -self.d1, -self.d2, -self.g)

    def __sub__(self, o):
        return self + (-o)

    def __rsub__(self, o):
        return (-self) + o

    def __mul__(self, o):
        if not isinstance(o, Jet):
            return Jet(self.v * o, self.d1 * o, self.d2 * o, self.g * o)
        return Jet(self.v * o.v,
                   self.d1 * o.v + self.v * o.d1,
                   self.d2 * o.v + 2.0 * self.d1 * o.d1 + self.v * o.d2,
                   self.g * o.v + self.v * o.g)

    __rmul__ = __mul__

    def _chain(self, f0, f1, f2):
        """Apply a scalar function with value f0 and derivatives f1, f2 at self.v."""
        return Jet(f0, f1 * self.d1, f1 * self.d2 + f2 * self.d1 * self.d1, f1 * self.g)


def jsqrt(x: Jet) -> Jet:
    s = math.sqrt(x.v)
    return x._chain(s, 0.5 / s, -0.25 / (s * x.v))


def jsin(x: Jet) -> Jet:
    s, c = math.sin(x.v), math.cos(x.v)
    return x._chain(s, c, -s)


def jcos(x: Jet) -> Jet:
    s, c = math.sin(x.v), math.cos(x.v)
    return x._chain(c, -s, -c)


def point_position(point, coords):
    """r = R + A(θ)ū written out from the rotation's definition, on Jets (or floats)."""
    if point.body < 0:
        return list(point.local)
    x, y, th = coords
    ux, uy = point.local
    c, s = jcos(th), jsin(th)
    return [x + c * ux - s * uy, y + s * ux + c * uy]


class DistanceProbe:
    """L(q) between two points, with ∇L, L̇, q̇ᵀ∇²Lq̇ and the terminal velocity ṙ, by Jets."""

    def __init__(self, pair, labels, name):
        self.pair = pair
        self.dofs = pair.dofs
        self.labels = labels
        self.name = name

    def evaluate(self, q, v):
        n = len(self.dofs)
        coords, k = {}, 0
        for p in (self.pair.a, self.pair.b):
            if p.body >= 0 and p.body not in coords:
                base = DOF_PER_BODY * p.body
                jets = []
                for j in range(DOF_PER_BODY):
                    g = np.zeros(n)
                    g[k] = 1.0
                    jets.append(Jet(float(q[base + j]), float(v[base + j]), 0.0, g))
                    k += 1
                coords[p.body] = jets
        ra = point_position(self.pair.a, coords.get(self.pair.a.body))
        rb = point_position(self.pair.b, coords.get(self.pair.b.body))
        r = [b - a for a, b in zip(ra, rb)]
        r = [c if isinstance(c, Jet) else Jet.constant(c, n) for c in r]
        L2 = r[0] * r[0] + r[1] * r[1]
        if not math.sqrt(L2.v) > MIN_LENGTH:
            raise TerminalsMeet(
                f"element '{self.name}': its terminals {self.labels[0]} and {self.labels[1]} meet "
                f"(distance {math.sqrt(L2.v):.3g} m < {MIN_LENGTH:g} m), so its direction is undefined")
        L = jsqrt(L2)
        rdot = np.array([c.d1 for c in r])                      # ṙ = J_r q̇
        return L, rdot


class OracleElement:
    """Spring, damper or inerter through L(q) and its derivatives."""

    def __init__(self, spec, pair, centripetal, free_length, labels):
        self.name = spec.name
        self.kind = spec.type
        self.coefficient = float(spec.coefficient)
        self.coefficient_name = {"spring": "k", "damper": "c", "inerter": "b"}[spec.type]
        self.centripetal = bool(centripetal)
        self.free_length = free_length
        self.probe = DistanceProbe(pair, labels, spec.name)
        self.pair = pair

    def _force_parts(self, L, rdot):
        """F = a·q̈ part (gradient factor) + the rest: returns (mass factor, rest)."""
        b = self.coefficient
        if self.kind == "spring":
            return 0.0, b * (L.v - self.free_length)            # Eq. (5)
        if self.kind == "damper":
            return 0.0, b * L.d1                                # c dL/dt, Eq. (6)
        rest = L.d2                                             # q̇ᵀ∇²Lq̇: L̈ = ∇L·q̈ + this
        if not self.centripetal:
            rest -= (float(rdot @ rdot) - L.d1 * L.d1) / L.v    # remove |ṙ⊥|²/L: F = b r̈·r̂ (Eq. 8)
        return b, b * rest

    def geometry(self, q, v):
        return self.probe.evaluate(q, v)

    def add_mass(self, q, v, M, geo=None):
        if self.kind != "inerter":
            return
        L, _ = geo or self.probe.evaluate(q, v)
        idx = self.probe.dofs
        M[np.ix_(idx, idx)] += self.coefficient * np.outer(L.g, L.g)

    def add_force(self, q, v, Q, geo=None):
        L, rdot = geo or self.probe.evaluate(q, v)
        _, rest = self._force_parts(L, rdot)
        Q[self.probe.dofs] -= rest * L.g                        # Q = −F ∇L

    def outputs(self, q, v, a):
        L, rdot = self.probe.evaluate(q, v)
        mass, rest = self._force_parts(L, rdot)
        F = rest + mass * float(L.g @ a[self.probe.dofs])
        return L.v, L.d1, F

    def length(self, q):
        return self.probe.evaluate(q, np.zeros_like(q))[0].v

    def kinetic(self, q, v):
        if self.kind != "inerter":
            return 0.0
        return 0.5 * self.coefficient * self.probe.evaluate(q, v)[0].d1 ** 2

    def potential(self, q):
        if self.kind != "spring":
            return 0.0
        return 0.5 * self.coefficient * (self.length(q) - self.free_length) ** 2
