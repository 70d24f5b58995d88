"""What one evaluation of the right-hand side costs, and its parts: the integrators' `_rhs`
(Eq. 33 assembled and solved, q̇ and the internal states' rates), the assembly alone and the band
solve alone, each called in a compiled loop of `--calls` evaluations at one state of the scene.

    python benchmarks/eval_cost.py [SCENE.toml ...] [--calls 200000] [--rounds 3]
    PYTHONPATH=<tree> python benchmarks/eval_cost.py ...        # another tree's kernels

Printed: a markdown table of µs per call (best of the rounds); the band solve's row is net of
restoring the matrix before each call (timed apart). Run it under two trees alternately to compare
them (docs/performance.md).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

SCENES = ["scenarios/lumped_mass_2d.toml", "scenarios/two_bar_2d.toml", "scenarios/tid_storey_2d.toml",
          "scenarios/two_bar_2d_as_3d.toml", "scenarios/double_pendulum_3d.toml"]


def _loops(k):
    """Compiled loops over the kernels of module `k` (the cached kernels: compiled.\\_k)."""
    from numba import njit

    @njit
    def rhs(n, t, y, inputs, alpha, P, AB, b, gen, acc, dy):
        s = 0
        for _ in range(n):
            s += k._rhs(t, y, inputs, alpha, P, AB, b, gen, acc, dy)
        return s

    @njit
    def accelerations(n, t, q, v, z, inputs, alpha, P, AB, b, gen, acc):
        s = 0
        for _ in range(n):
            s += k.accelerations(t, q, v, z, inputs, alpha, P, AB, b, gen, acc)
        return s

    @njit
    def restore(n, AB0, b0, AB, b):
        for _ in range(n):
            AB[:, :] = AB0
            b[:] = b0

    @njit
    def solve(n, AB0, b0, AB, b, kl):
        s = 0
        for _ in range(n):
            AB[:, :] = AB0
            b[:] = b0
            s += k.band_solve(AB, b, kl)
        return s

    return rhs, accelerations, restore, solve


def _state(kernel):
    """A state off the initial pose (velocities and internal states nonzero), so that every term
    is evaluated."""
    y = np.concatenate([np.asarray(kernel.q0, float), np.asarray(kernel.v0, float), np.zeros(kernel.ny - kernel.nq - kernel.n)])
    y[kernel.nq:kernel.nq + kernel.n] += 0.1 * np.cos(np.arange(kernel.n))
    return y


def measure(path, calls, rounds):
    """µs per call of each part for the scene at `path`: a dict."""
    import inerter
    from inerter.engine import compiled

    k = compiled._k
    rhs_loop, acc_loop, restore, solve = _loops(k)
    model = inerter.load(path)
    kernel = compiled._kernel_for(model.mechanism)
    P, ny, nq, n = kernel.params, kernel.ny, kernel.nq, kernel.n
    AB, b, gen, acc, *_ = k.work_arrays(P, ny, 1)
    y = _state(kernel)
    inputs = np.zeros(2 * len(model.mechanism.input_names))
    q, v, z = y[:nq], y[nq:nq + n], y[nq + n:]
    args = (0.1, y, inputs, 0.0, P, AB, b, gen, acc, np.empty(ny))
    acc_args = (0.1, q, v, z, inputs, 0.0, P, AB, b, gen, acc)
    kl = int(P[k.DIMS][k.KL])
    rhs_loop(1, *args)
    acc_loop(1, *acc_args)
    AB0, b0 = _assembled(k, acc_args)
    restore(1, AB0, b0, AB, b)
    solve(1, AB0, b0, AB, b, kl)
    best = {"rhs": np.inf, "accelerations": np.inf, "restore": np.inf, "solve": np.inf}
    for _ in range(rounds):
        for name, run in (("rhs", lambda: rhs_loop(calls, *args)), ("accelerations", lambda: acc_loop(calls, *acc_args)),
                          ("restore", lambda: restore(calls, AB0, b0, AB, b)),
                          ("solve", lambda: solve(calls, AB0, b0, AB, b, kl))):
            t0 = time.process_time()
            run()
            best[name] = min(best[name], (time.process_time() - t0) / calls * 1e6)
    return {"N": AB.shape[0], "width": AB.shape[1], "rhs": best["rhs"], "accelerations": best["accelerations"],
            "solve": best["solve"] - best["restore"]}


def _assembled(k, acc_args):
    """The augmented matrix and right side of Eq. (33) as the assembly leaves them (before the solve)."""
    from numba import njit

    @njit
    def assembled(t, q, v, z, inputs, alpha, P, AB, b, gen):
        k._assemble_of(t, q, v, z, inputs, alpha, P, AB, b, gen)

    t, q, v, z, inputs, alpha, P, AB, b, gen, _ = acc_args
    assembled(t, q, v, z, inputs, alpha, P, AB, b, gen)
    return AB.copy(), b.copy()


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenes", nargs="*", default=SCENES)
    parser.add_argument("--calls", type=int, default=200_000)
    parser.add_argument("--rounds", type=int, default=3)
    a = parser.parse_args(argv)
    print("| scene | N × band | `_rhs` (µs) | `accelerations` (µs) | band solve (µs) |")
    print("|---|---|---|---|---|")
    for path in a.scenes:
        r = measure(path, a.calls, a.rounds)
        print(f"| {path} | {r['N']} × {r['width']} | {r['rhs']:.3f} | {r['accelerations']:.3f} | {r['solve']:.3f} |",
              flush=True)


if __name__ == "__main__":
    main()
