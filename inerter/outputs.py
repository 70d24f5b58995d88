"""Output signals, named and united as a Modelica user expects (the FMU uses the same names).

Points: ``P.r[i]`` (m), ``P.v[i]`` (m/s). Translational elements: ``E.s_rel`` (m, terminal
distance), ``E.v_rel`` (m/s, its rate), ``E.f`` (N, axial force, tension positive). Rotational
elements: ``E.phi_rel`` (rad), ``E.w_rel`` (rad/s), ``E.tau`` (N.m). Mechanism: ``energy`` (J),
``constraint_residual`` (largest |C_i| of the joint constraints, m or rad).
"""
from __future__ import annotations

import numpy as np


class Signals:
    def __init__(self, mech):
        self.mech = mech
        self.names, self.units, self.descriptions = [], [], []
        self._eval = []       # (name, needs_accelerations, f(t, q, v, a) -> float)
        for pname in mech.point_names:
            point = mech.points[pname]
            for i in range(mech.dim):
                self._add(f"{pname}.r[{i + 1}]", "m", f"position of point {pname}, global axis {i + 1}",
                          False, lambda t, q, v, a, p=point, i=i: float(p.evaluate(q, v)[0][i]))
            for i in range(mech.dim):
                self._add(f"{pname}.v[{i + 1}]", "m/s", f"velocity of point {pname}, global axis {i + 1}",
                          False, lambda t, q, v, a, p=point, i=i: float(p.evaluate(q, v)[1][i]))
        for e in mech.elements:
            if e.kind.startswith("rotational"):
                spec = (("phi_rel", "rad", "relative angle"), ("w_rel", "rad/s", "relative angular velocity"),
                        ("tau", "N.m", "torque (restoring positive)"))
            else:
                spec = (("s_rel", "m", "distance between the terminals"),
                        ("v_rel", "m/s", "rate of change of the terminal distance"),
                        ("f", "N", "axial force, tension positive"))
            needs_a = e.kind == "inerter"
            for k, (suffix, unit, text) in enumerate(spec):
                self._add(f"{e.name}.{suffix}", unit, f"{e.kind} {e.name}: {text}", needs_a and k == 2,
                          lambda t, q, v, a, e=e, k=k: float(e.outputs(q, v, a)[k]))
        self._add("energy", "J", "kinetic + potential energy, with ½·b·(dL/dt)² per inerter", False,
                  lambda t, q, v, a: mech.energy(q, v))
        self._add("constraint_residual", "m", "largest |C_i(q)| of the joint constraints (m or rad)", False,
                  lambda t, q, v, a: mech.constraint_residual(q))
        self.index = {n: i for i, n in enumerate(self.names)}
        self.needs_accelerations = any(f[1] for f in self._eval)

    def _add(self, name, unit, description, needs_a, fn):
        self.names.append(name)
        self.units.append(unit)
        self.descriptions.append(description)
        self._eval.append((name, needs_a, fn))

    def info(self):
        return [dict(name=n, unit=u, description=d) for n, u, d in zip(self.names, self.units, self.descriptions)]

    def evaluate(self, t, q, v, inputs=None, alpha=0.0) -> np.ndarray:
        a = self.mech.accelerations(t, q, v, inputs, alpha)[0] if self.needs_accelerations else None
        return np.array([fn(t, q, v, a) for _, _, fn in self._eval])

    def function(self, name):
        """f(t, q, v, inputs) → value of one signal."""
        _, needs_a, fn = self._eval[self.index[name]]
        mech = self.mech

        def signal(t, q, v, inputs=None, alpha=0.0):
            a = mech.accelerations(t, q, v, inputs, alpha)[0] if needs_a else None
            return fn(t, q, v, a)
        return signal
