"""Static equilibrium and linearisation about it (paper Appendix A, generalised).

Static equilibrium: Q_e(q, q̇ = 0) with the loads' static parts (constant forces, sine offsets,
step initial values, zero inputs) balanced by the constraint forces, C(q) = 0.

Linearisation: the constraint manifold is parametrised near q* by z (n − m independent
coordinates): q(z) = q* + N z + Y w(z) with C(q(z)) = 0, N spanning the null space of C_q(q*).
With T = ∂q/∂z, the reduced mass is Tᵀ(M + M_I)T, and the reduced stiffness is
K = −∂(TᵀQ)/∂z (central differences of the virtual work of the applied forces, which excludes the
constraint forces exactly). For the lumped-mass scene this is Eq. (A.6):
m_e = m + (L_b/L_0)² b, k_e = k (L_b/L_0)².
"""
from __future__ import annotations

import numpy as np

from inerter.common.errors import SimulationError


def static_forces(mech, q):
    """Generalised forces with every time function at its static value and zero velocities."""
    z = np.zeros(mech.n)
    Q = np.zeros(mech.n)
    if mech.gravity is not None:
        Q += mech.gravity
    for e in mech.elements:
        e.add_force(q, z, Q)
    for f, point, fn in mech.applied:
        level = fn.static_value()
        if level:
            mech._add_point_force(Q, point, q, level * np.asarray(f.direction))
    for f, point in mech.feedback:
        mech._add_point_force(Q, point, q, mech._pd_force(f, point, q, z, static=True))
    return Q


def static_equilibrium(mech, q_start=None, tol=1e-12):
    """q* with static_forces(q*) + C_qᵀλ = 0 and C(q*) = 0, found by Newton's method
    (MINPACK's hybrid Powell where Newton does not settle) from `q_start` (default: the initial pose)."""
    if mech.dim != 2:
        raise SimulationError("the static equilibrium and linearisation are implemented for planar scenes only; "
                              "give metrics of 3D scenes an explicit reference")
    n, m = mech.n, mech.m
    q_start = mech.q0 if q_start is None else q_start
    z = np.zeros(n)

    def residual(x):
        q, lam = x[:n], x[n:]
        Q = static_forces(mech, q)
        if not m:
            return Q
        C, Cq, _ = mech.constraints(q, z)
        return np.concatenate((Q - Cq.T @ lam, C))

    x0 = np.concatenate((q_start, np.zeros(m)))
    scale = max(1.0, float(np.max(np.abs(static_forces(mech, q_start)))))
    x = _newton(residual, x0, tol * scale)
    if x is not None:
        return x[:n]
    # Newton did not settle (a singular Jacobian, a far start): MINPACK's hybrid Powell method,
    # imported only here (scipy.optimize costs 0.2 s of a fresh process's first result)
    from scipy.optimize import root

    sol = root(residual, x0, method="hybr", options={"xtol": 1e-14})
    worst = float(np.max(np.abs(residual(sol.x)))) if sol.x.size else 0.0
    if not sol.success and worst > tol * scale * 1e3:
        raise SimulationError(f"no static equilibrium found near the initial pose ({sol.message}; "
                              f"residual {worst:.3g})", 0.0)
    return sol.x[:n]


def _newton(residual, x0, tol, iterations=30, h=1e-7):
    """x with max|residual(x)| ≤ tol by Newton's method on a central-difference Jacobian, or None
    when it does not get there (the caller falls back to a more robust method)."""
    x = np.array(x0, dtype=float)
    r = residual(x)
    for _ in range(iterations):
        if not np.all(np.isfinite(r)):
            return None
        if float(np.max(np.abs(r), initial=0.0)) <= tol:
            return x
        J = np.empty((r.size, x.size))
        for j in range(x.size):
            dx = np.zeros_like(x)
            dx[j] = h * max(1.0, abs(x[j]))
            J[:, j] = (residual(x + dx) - residual(x - dx)) / (2 * dx[j])
        try:
            x = x - np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            return None
        r = residual(x)
    return None


def _tangent_chart(mech, q_star):
    """Functions z ↦ q(z) and q ↦ T = ∂q/∂z there (q on the manifold) parametrising the constraint
    manifold near q*, and the number of independent coordinates z."""
    n, m = mech.n, mech.m
    zero = np.zeros(n)
    if not m:
        eye = np.eye(n)
        return (lambda z: q_star + z), (lambda q: eye), n
    _, Cq, _ = mech.constraints(q_star, zero)
    N, Y = _null_and_range(Cq)

    def q_of(zv):
        w = np.zeros(Y.shape[1])
        for _ in range(50):
            q = q_star + N @ zv + Y @ w
            C, Cq_, _ = mech.constraints(q, zero)
            if np.max(np.abs(C)) < 1e-15:
                break
            w -= np.linalg.solve(Cq_ @ Y, C)
        return q

    def T_at(q):
        _, Cq_, _ = mech.constraints(q, zero)
        return N - Y @ np.linalg.solve(Cq_ @ Y, Cq_ @ N)

    return q_of, T_at, N.shape[1]


def _null_and_range(Cq):
    """(N, Y): orthonormal bases of the null space of C_q and of the range of C_qᵀ, from one SVD
    with scipy.linalg's rank rule (singular values above max(shape)·eps·σ_max)."""
    _, sigma, Vt = np.linalg.svd(Cq)
    tol = max(Cq.shape) * np.finfo(float).eps * (sigma[0] if sigma.size else 0.0)
    rank = int(np.sum(sigma > tol))
    return Vt[rank:].T.conj(), Vt[:rank].T.conj()


def linearize(mech, q_star=None, h=1e-6):
    """Reduced (M_r, D_r, K_r) about the static equilibrium, in independent coordinates z."""
    q_star = static_equilibrium(mech) if q_star is None else q_star
    M, K, T0 = _mass_and_stiffness(mech, q_star, h)
    D = np.zeros_like(K)
    still = static_forces(mech, q_star)
    for j in range(K.shape[0]):
        dv = T0[:, j] * h
        Qp = mech.generalized_forces(0.0, q_star, dv) - still
        Qm = mech.generalized_forces(0.0, q_star, -dv) - still
        # time-dependent loads cancel in the difference; only velocity-dependent forces remain
        D[:, j] = -(T0.T @ (Qp - Qm)) / (2 * h)
    return M, D, K, q_star


def _mass_and_stiffness(mech, q_star, h):
    """(M_r, K_r, T) about the equilibrium q*: the reduced mass Tᵀ(M + M_I)T and stiffness
    −∂(TᵀQ)/∂z by central differences of step h (symmetrised), and T = ∂q/∂z at q*."""
    if len(getattr(mech, "z0", ())):
        raise SimulationError("the linearisation is of (q, v) only, and this scene's inerter devices have "
                              "internal states (series compliance, backlash): its frequencies would miss their "
                              "modes; give metrics of such a scene an explicit reference")
    if mech.efficient:
        raise SimulationError("the linearisation needs a smooth mass matrix, and this scene's screw efficiency "
                              "(device.efficiency) makes b depend on the direction of the power flow: give metrics of "
                              "such a scene an explicit reference")
    q_of, T_at, k = _tangent_chart(mech, q_star)
    T0 = T_at(q_of(np.zeros(k)))
    M = T0.T @ mech.mass_matrix(q_star, np.zeros(mech.n)) @ T0
    K = np.zeros((k, k))
    for j in range(k):
        dz = np.zeros(k)
        dz[j] = h
        qp, qm = q_of(dz), q_of(-dz)
        fp = T_at(qp).T @ static_forces(mech, qp)
        fm = T_at(qm).T @ static_forces(mech, qm)
        K[:, j] = -(fp - fm) / (2 * h)
    return M, 0.5 * (K + K.T), T0


def natural_frequencies(mech, q_star=None):
    """Undamped natural frequencies (Hz) of the linearisation, ascending (its mass and stiffness:
    the damping is not worked out)."""
    M, K, _ = _mass_and_stiffness(mech, static_equilibrium(mech) if q_star is None else q_star, 1e-6)
    if M.size == 0:
        return np.zeros(0)
    # K v = ω² M v with M = LLᵀ is the symmetric problem (L⁻¹ K L⁻ᵀ) u = ω² u (as LAPACK's sygv)
    L = np.linalg.cholesky(M)
    A = np.linalg.solve(L, np.linalg.solve(L, K).T)
    w2 = np.linalg.eigvalsh(0.5 * (A + A.T))
    return np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
