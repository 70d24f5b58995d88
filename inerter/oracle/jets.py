"""Jets: numbers carried with their gradient over chosen velocity coordinates and their first and
second derivatives along the motion (forward-mode automatic differentiation, Taylor mode to second
order), and a body's pose written on them: a point's position from the rotation's definition and
the Jets of a body's coordinates along the motion. The oracle's elements differentiate their
definitions on these; nothing here reads the engine or the element laws.
"""
from __future__ import annotations

import math

import numpy as np


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

    def reciprocal(self):
        return self._chain(1.0 / self.v, -1.0 / self.v ** 2, 2.0 / self.v ** 3)

    def __truediv__(self, o):
        return self * (o.reciprocal() if isinstance(o, Jet) else 1.0 / o)

    def __rtruediv__(self, o):
        return self.reciprocal() * o

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


def jatan2(y: Jet, x: Jet) -> Jet:
    """atan2(y, x) on Jets: its value as math.atan2 gives it, its derivatives those of atan of the
    smaller ratio (y/x, or −x/y where |y| > |x|: atan2 = ±π/2 − atan(x/y)), which never divides by
    a number near 0 away from x = y = 0."""
    t = y / x if abs(x.v) >= abs(y.v) else -(x / y)
    slope = 1.0 / (1.0 + t.v * t.v)
    return t._chain(math.atan2(y.v, x.v), slope, -2.0 * t.v * slope * slope)


def jpow(x: Jet, p: float) -> Jet:
    """x**p for x > 0."""
    return x._chain(x.v ** p, p * x.v ** (p - 1.0), p * (p - 1.0) * x.v ** (p - 2.0))


def jabs(x: Jet) -> Jet:
    return x._chain(abs(x.v), math.copysign(1.0, x.v), 0.0)


def jlogcosh(x: Jet) -> Jet:
    """ln cosh x, written |x| + ln(1 + e^{−2|x|}) − ln 2 so that it does not overflow."""
    a = abs(x.v)
    t = math.tanh(x.v)
    return x._chain(a + math.log1p(math.exp(-2.0 * a)) - math.log(2.0), t, 1.0 - t * t)


def rotation(coords):
    """A body's rotation matrix from its coordinates, on Jets (or floats): in 2D from the angle θ,
    [[cos θ, −sin θ], [sin θ, cos θ]]; in 3D from the quaternion p = (w, v), not necessarily of
    unit length, A = I + 2/|p|² (w[v]× + [v]×²), [v]×² = v vᵀ − |v|² I (Shabana 2009)."""
    if len(coords) == 3:
        c, s = jcos(coords[2]), jsin(coords[2])
        return [[c, -s], [s, c]]
    w, a, b, c = coords[3:]
    k = 2.0 / (w * w + a * a + b * b + c * c)
    aa, bb, cc, ab, ac, bc, wa, wb, wc = a * a, b * b, c * c, a * b, a * c, b * c, w * a, w * b, w * c
    return [[1.0 - k * (bb + cc), k * (ab - wc), k * (ac + wb)],
            [k * (ab + wc), 1.0 - k * (aa + cc), k * (bc - wa)],
            [k * (ac - wb), k * (bc + wa), 1.0 - k * (aa + bb)]]


def times(A, x):
    """A x for A of Jets (or floats) and floats x, skipping the zero entries of x."""
    terms = [(j, float(xj)) for j, xj in enumerate(x) if xj != 0.0]
    if not terms:
        return [row[0] * 0.0 for row in A]
    out = []
    for row in A:
        j, xj = terms[0]
        acc = row[j] * xj
        for j, xj in terms[1:]:
            acc = acc + row[j] * xj
        out.append(acc)
    return out


def placed(R, A, local):
    """r = R + A ū: the point at ū in a body whose centre is R and rotation A (Jets or floats)."""
    return [P + x for P, x in zip(R, times(A, local))]


def point_position(point, coords):
    """r = R + A ū (:func:`rotation`, :func:`placed`), on Jets (or floats); ū for the ground."""
    if point.body < 0:
        return list(point.local)
    return placed(coords[:len(point.local)], rotation(coords), point.local)


def plain_coords(q, point):
    """A point's body coordinates as constant Jets (None for the ground): (x, y, θ) or (R, p)."""
    if point.body < 0:
        return None
    return [Jet.constant(x, 1) for x in q[point.qi:point.qi + (3 if len(point.local) == 2 else 7)]]


def position(q, point):
    """r of a point at pose q, as floats."""
    return [c.v if isinstance(c, Jet) else float(c) for c in point_position(point, plain_coords(q, point))]


def seed(q, v, qi, vi, dim, n, k):
    """Jets for one body's coordinates along the motion, with gradients w.r.t. its velocity
    coordinates (placed at columns k...). 2D: q = (x, y, θ), q̇ = v, q̈|v̇=0 = 0. 3D: R with
    Ṙ = v; quaternion p with ṗ = ½ p⊗(0, ω) = E(p) ω and p̈|ω̇=0 = ½ ṗ⊗(0, ω) = −¼|ω|² p."""
    size = 3 if dim == 2 else 7
    G = np.zeros((size, n))
    for j in range(3):
        G[j, k + j] = 1.0
    jets = [Jet(float(q[qi + j]), float(v[vi + j]), 0.0, G[j]) for j in range(3)]
    if dim == 2:
        return jets
    w0, x, y, z = (float(c) for c in q[qi + 3:qi + 7])
    E = 0.5 * np.array(((-x, -y, -z), (w0, -z, y), (z, w0, -x), (-y, x, w0)))     # ½ p⊗(0, e_j), j = 1..3
    G[3:, k + 3:k + 6] = E
    w = np.asarray(v[vi + 3:vi + 6], dtype=float)
    pdot = E @ w
    half_w2 = -0.25 * float(w @ w)
    for i, pi in enumerate((w0, x, y, z)):
        jets.append(Jet(pi, float(pdot[i]), half_w2 * pi, G[3 + i]))
    return jets


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def parts(jets):
    """(values, first derivatives, second derivatives along the motion, gradients) of Jets, as arrays."""
    return (np.array([j.v for j in jets]), np.array([j.d1 for j in jets]), np.array([j.d2 for j in jets]),
            np.array([j.g for j in jets]))


def vee(W):
    return np.array((W[2, 1], W[0, 2], W[1, 0]))


def angular_velocity(R):
    """(R, ω, ∂ω/∂v, α₀) of a rotation R(q) given as 3 × 3 Jets, in the fixed frame: ω from its
    definition ω̃ = Ṙ Rᵀ, ∂ω/∂v (3 × n) from the gradients, α₀ = vee(R̈Rᵀ + ṘṘᵀ) the angular
    acceleration at v̇ = 0 (the derivative of ṘRᵀ along the motion); R as floats."""
    Rv, Rd, Rdd, Rg = parts([x for row in R for x in row])
    Rv, Rd, Rdd, Rg = Rv.reshape(3, 3), Rd.reshape(3, 3), Rdd.reshape(3, 3), Rg.reshape(3, 3, -1)
    d_omega = np.array([vee(Rg[:, :, i] @ Rv.T) for i in range(Rg.shape[2])]).T.reshape(3, -1)
    return Rv, vee(Rd @ Rv.T), d_omega, vee(Rdd @ Rv.T + Rd @ Rd.T)
