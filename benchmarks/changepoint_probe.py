"""What the compiled DOP853 loop sees near a change point (docs/changepoint.md).

    python benchmarks/changepoint_probe.py [SCENE]      # default tests/data/parallelogram_2d.toml

Runs the scene's compiled whole run keeping every step's dense output and prints, at the accepted
steps around the time where C_v's smallest/largest singular value is least: the step size, that
ratio, the largest |q̈| and |λ| of Eq. (33). Then scipy's DOP853 on the same compiled right-hand
side, and at every stage of its step across that time the same measures. The run stops there
now (kernels.loop_watch); to see what the loop did before that watch, run it on the commit before
it (docs/changepoint.md).
"""
from __future__ import annotations

import sys

import numpy as np
from scipy.integrate import DOP853

import inerter
from inerter.engine import compiled


def main(path="tests/data/parallelogram_2d.toml"):
    model = inerter.load(path)
    mech = model.mechanism
    settings = model.settings()
    kernel = compiled._kernel_for(mech)
    zero = np.zeros(mech.n)

    def ratio(q):
        sv = np.linalg.svd(mech.constraints(q[:mech.nq], zero)[1], compute_uv=False)
        return sv[-1] / sv[0]

    def measures(t, y):
        qdd, lam = kernel.accelerations(t, y[:mech.nq], y[mech.nq:mech.nq + mech.n], alpha=settings.alpha)
        return ratio(y), np.abs(qdd).max(), np.abs(lam).max()

    run = compiled.integrate_compiled(mech, settings, dense=True)
    nodes = run.dense.ts
    print(f"{model.name}: {run.status} ({run.message[:100]}), {len(nodes) - 1} steps")
    least = int(np.argmin([ratio(run.dense(t)) for t in nodes]))
    print("t (s)         step (s)   sv ratio   max|qdd|   max|lambda|")
    for j in range(max(1, least - 12), min(len(nodes), least + 12)):
        r, a, lam = measures(nodes[j], run.dense(nodes[j]))
        print(f"{nodes[j]:.10f}  {nodes[j] - nodes[j - 1]:9.2e}  {r:9.2e}  {a:9.2e}  {lam:9.2e}")
    fun = kernel.derivative(alpha=settings.alpha)
    stages = []

    def recorded(t, y):
        stages.append((t, y.copy()))
        return fun(t, y)
    solver = DOP853(recorded, 0.0, np.concatenate((mech.q0, mech.v0, kernel.z0)), settings.stop_time,
                    rtol=settings.rtol, atol=settings.atol)
    t_least = nodes[least]
    while solver.status == "running" and solver.t < t_least:
        start, first = solver.t, len(stages)
        solver.step()
    print(f"scipy's DOP853: the step from {start:.9f} s to {solver.t:.9f} s, its stages:")
    for t, y in stages[first:]:
        r, a, lam = measures(t, y)
        print(f"  t = {t:.9f}  sv ratio {r:9.2e}  max|qdd| {a:9.2e}  max|lambda| {lam:9.2e}")


if __name__ == "__main__":
    main(*sys.argv[1:])
