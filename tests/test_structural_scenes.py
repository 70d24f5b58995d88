"""The structural scenes against the exact solutions of their linear ODEs.

tid_storey_2d (a storey with a tuned inerter damper, its node massless and carried by the
inerter) and shear_building_tmdi_2d (three storeys with a tuned mass damper inerter) slide along X
with every terminal on one line, so each is exactly M_t ẍ + C ẋ + K x = −M 1 a_g(t), with M_t the
masses plus the inertances' b (e_i − e_j)(e_i − e_j)ᵀ. The record a_g is piecewise linear (the
engine interpolates it so), so the state at every sample follows exactly from the previous one by
the matrix exponential of the first-order hold (the augmented system [[A, B, 0], [0, 0, 1],
[0, 0, 0]] over one sample). The matrices are built here from the scene's parameters and the
textbook assembly of springs, dampers and inerters between floors, not from the engine.
Tolerance: 1e-8 of each response's peak (the engine at rtol 1e-11; its steps end on every sample).
"""
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm, solve

import inerter

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def _connect(matrix, i, j, value):
    """Add an element of coefficient `value` between coordinates i and j (−1: the ground)."""
    for a, sa in ((i, 1.0), (j, -1.0)):
        for b, sb in ((i, 1.0), (j, -1.0)):
            if a >= 0 and b >= 0:
                matrix[a, b] += sa * sb * value


def _exact(masses, K, C, Minertance, times, ag):
    """(x, ẍ): relative displacements and accelerations at `times` (the record's samples) of
    M_t ẍ + C ẋ + K x = −m a_g from rest, with a_g linear between samples (first-order hold,
    exact)."""
    n = len(masses)
    Mt = np.diag(masses) + Minertance
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-solve(Mt, K), -solve(Mt, C)]])
    B = np.concatenate((np.zeros(n), -solve(Mt, np.asarray(masses, dtype=float))))
    h = times[1] - times[0]
    assert np.allclose(np.diff(times), h, rtol=0, atol=1e-12)
    X = np.zeros((2 * n + 2, 2 * n + 2))
    X[:2 * n, :2 * n] = A
    X[:2 * n, 2 * n] = B
    X[2 * n, 2 * n + 1] = 1.0
    E = expm(X * h)
    Phi, G0, G1 = E[:2 * n, :2 * n], E[:2 * n, 2 * n], E[:2 * n, 2 * n + 1]
    z = np.zeros(2 * n)
    states = [z]
    for k in range(len(times) - 1):
        z = Phi @ z + G0 * ag[k] + G1 * (ag[k + 1] - ag[k]) / h
        states.append(z)
    states = np.array(states)
    acc = (states @ A.T)[:, n:] + np.outer(ag, B[n:])
    return states[:, :n], acc


def _record(model):
    table = np.loadtxt(SCENARIOS / "records" / "synthetic_x.csv", delimiter=",")
    scale = model.scene.parameters["scale"].value
    return table[:, 0], scale * table[:, 1]


def _run(model):
    result = model.simulate(rtol=1e-11, atol=1e-13, metrics=False)
    assert result.status == "ok", result.message
    return result


def test_tid_storey_matches_its_exact_linear_solution():
    model = inerter.load(SCENARIOS / "tid_storey_2d.toml")
    p = {name: par.value for name, par in model.scene.parameters.items()}
    K, C, MI = np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2))
    floor, node = 0, 1
    _connect(K, floor, -1, p["k"])
    _connect(C, floor, -1, p["c"])
    _connect(K, floor, node, p["kt"])
    _connect(C, floor, node, p["ct"])
    _connect(MI, node, -1, p["b"])
    times, ag = _record(model)
    exact, _ = _exact([p["m"], 0.0], K, C, MI, times, ag)        # the node is massless
    r = _run(model)
    assert np.allclose(r.time, times, rtol=0, atol=1e-9)
    for name, column in (("E.r[1]", floor), ("N.r[1]", node)):
        x = r[name] - r[name][0]
        peak = np.max(np.abs(exact[:, column]))
        assert peak > 1e-3
        assert np.max(np.abs(x - exact[:, column])) <= 1e-8 * peak, name


def test_shear_building_tmdi_matches_its_exact_linear_solution():
    model = inerter.load(SCENARIOS / "shear_building_tmdi_2d.toml")
    p = {name: par.value for name, par in model.scene.parameters.items()}
    K, C, MI = np.zeros((4, 4)), np.zeros((4, 4)), np.zeros((4, 4))
    for storey, below in ((0, -1), (1, 0), (2, 1)):
        _connect(K, storey, below, p["k"])
        _connect(C, storey, below, p["c"])
    damper, second, roof = 3, 1, 2
    _connect(K, damper, roof, p["kd"])
    _connect(C, damper, roof, p["cd"])
    _connect(MI, damper, second, p["b"])
    times, ag = _record(model)
    exact, acc = _exact([p["m"], p["m"], p["m"], p["md"]], K, C, MI, times, ag)
    r = _run(model)
    for name, column in (("E1.r[1]", 0), ("E2.r[1]", 1), ("E3.r[1]", 2), ("Ed.r[1]", 3)):
        x = r[name] - r[name][0]
        peak = np.max(np.abs(exact[:, column]))
        assert peak > 1e-3
        assert np.max(np.abs(x - exact[:, column])) <= 1e-8 * peak, name
    # the inerter's force, tension positive: b times the relative acceleration of its terminals
    force = p["b"] * (acc[:, damper] - acc[:, second])
    assert np.max(np.abs(r["tmdi_inerter.f"] - force)) <= 1e-8 * np.max(np.abs(force))
