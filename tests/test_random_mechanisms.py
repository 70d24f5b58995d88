"""The compiled engine against the oracle on random mechanisms that no shipped scene resembles.

A seeded generator writes small valid scenes, 2D and 3D: 1-4 bodies in chains (and closed loops
where the loop keeps a degree of freedom), every joint type of the format (2D: revolute,
prismatic, screw; 3D: spherical, revolute, prismatic, fixed, cylindrical, universal, planar,
screw), springs (with and without a free length), dampers and inerters between random points,
joint springs and dampers, rotational springs and dampers, point forces (constant, sine, step, pd,
input), gravity on or off, the inerter with (Eq. 9) or without (Eq. 8) its centripetal term or the
small-displacement law, and in 3D every way of giving an initial rotation (axis and angle, Z-X-Z
Euler angles, a quaternion, none) with inertias as principal moments or full matrices, on
quaternion or Z-X-Z Euler coordinates. Masses, inertias and distances are drawn from ranges that
keep the mass matrix well conditioned; joints are satisfied at t = 0 by construction (each joint's
two points are placed at one global point, or on the joint's line or plane), velocities are random
(the loader projects them onto the joints).

These cases found that a prismatic joint's spring and damper on a moving body acted along the
turning axis ê without the term ∂ê/∂q·r (zero on the joint's line, not off it, where the states of
the acceleration check lie): the oracle differentiates L = ê(q)·r; seeds 2D 17 and 3D 26 hold it.

The reference is the oracle (`model.oracle()`: translational elements' forces differentiated from
L(q) on Jets, planar rotational elements from their potential and dissipation function), as in
tests/test_engine_vs_oracle.py, with that module's tolerances and for the same reasons:
accelerations and multipliers to 1e-12 relative (floor 1e-2 of the case's largest), outputs to
1e-12 (forces over their coefficients), and a DOP853 run at rtol 1e-12 on both sides to 2e-10 of
each output's range. A planar scene written as a 3D one (revolute axes along Z, everything in the
plane) gives the same motion: its run agrees with the 2D run to 2e-10 of the range (the two
integrate the same planar equations; only round-off and step choices differ).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

import inerter
from inerter.engine import compiled
from inerter.engine.simulation import integrate

#: Tolerances: see the module docstring (the same as tests/test_engine_vs_oracle.py's).
TOL_ACC, ACC_FLOOR, TOL_OUT, TOL_RUN = 1e-12, 1e-2, 1e-12, 2e-10
RTOL, ATOL = 1e-12, 1e-14
RUN_TIME = 0.3


# ------------------------------------------------------------------------------------------------
# TOML writing (the scenes are dicts; no TOML writer ships with Python)
# ------------------------------------------------------------------------------------------------
def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(v)


def to_toml(scene: dict) -> str:
    """TOML text of a scene dict: top-level tables, named sub-tables, `points` inline."""
    lines = []

    def table(path, d):
        lines.append(f"[{path}]")
        subs = []
        for k, v in d.items():
            if isinstance(v, dict) and k != "points":
                subs.append((k, v))
            else:
                lines.append(f"{k} = {_value(v)}")
        lines.append("")
        for k, v in subs:
            table(f"{path}.{k}", v)

    for key, d in scene.items():
        if key in ("bodies", "joints", "elements", "forces"):
            for name, sub in d.items():
                table(f"{key}.{name}", sub)
        else:
            table(key, d)
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------------
# Rotations (written here, independently of inerter.common.rotations)
# ------------------------------------------------------------------------------------------------
def rot2(th):
    c, s = math.cos(th), math.sin(th)
    return np.array([[c, -s], [s, c]])


def axis_angle(axis, angle):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def euler_zxz(phi, theta, psi):
    return axis_angle((0, 0, 1), phi) @ axis_angle((1, 0, 0), theta) @ axis_angle((0, 0, 1), psi)


def quat_matrix(p):
    w, x, y, z = np.asarray(p, float) / np.linalg.norm(p)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def unit(rng, dim):
    u = rng.standard_normal(dim)
    return u / np.linalg.norm(u)


def perpendicular(u, rng):
    w = rng.standard_normal(3)
    w -= (w @ u) * u
    return w / np.linalg.norm(w)


# ------------------------------------------------------------------------------------------------
# The generator
# ------------------------------------------------------------------------------------------------
class Builder:
    """A random scene under construction: bodies with their global poses, and points placed at
    global positions (stored in their body's frame)."""

    def __init__(self, rng, dim):
        self.rng, self.dim = rng, dim
        self.bodies, self.pose = {}, {"ground": (np.zeros(dim), np.eye(dim))}
        self.ground_points, self.points, self.owner = {}, {}, {}
        self.joints, self.elements, self.forces = {}, {}, {}

    def add_point(self, body, x):
        """A point of `body` at global position x (its body-frame coordinates are stored)."""
        name = f"P{len(self.owner)}"
        c, A = self.pose[body]
        local = A.T @ (np.asarray(x, float) - c)
        (self.ground_points if body == "ground" else self.points[body])[name] = [float(v) for v in local]
        self.owner[name] = (body, np.asarray(x, float))
        return name

    def random_point(self, body, spread=0.4):
        c, _ = self.pose[body]
        return self.add_point(body, c + spread * self.rng.standard_normal(self.dim))


def _body_2d(rng, b, name):
    c = rng.uniform(-1.0, 1.0, 2)
    th = float(rng.uniform(-math.pi, math.pi))
    b.pose[name] = (c, rot2(th))
    b.points[name] = {}
    b.bodies[name] = {"mass": float(rng.uniform(0.5, 3.0)), "inertia": float(rng.uniform(0.05, 0.5)),
                      "position": list(c), "angle": th, "velocity": list(0.5 * rng.standard_normal(2)),
                      "angular_velocity": float(rng.standard_normal())}


def _rotation_3d(rng, spec, euler_coordinates):
    """A random initial rotation written one of the format's ways, with its matrix."""
    way = rng.choice(["axis", "euler", "quaternion"] + ([] if euler_coordinates else ["none"]))
    if way == "axis":
        axis, angle = unit(rng, 3), float(rng.uniform(-math.pi, math.pi))
        spec.update(axis=list(axis), angle=angle)
        return axis_angle(axis, angle)
    if way == "euler":
        e = [float(rng.uniform(-3, 3)), float(rng.uniform(0.4, 2.7)), float(rng.uniform(-3, 3))]
        spec["euler"] = e
        return euler_zxz(*e)
    if way == "quaternion":
        p = unit(rng, 4)
        spec["quaternion"] = list(p)
        return quat_matrix(p)
    return np.eye(3)


def _body_3d(rng, b, name, euler_coordinates):
    c = rng.uniform(-1.0, 1.0, 3)
    spec = {"mass": float(rng.uniform(0.5, 3.0))}
    J = rng.uniform(0.05, 0.5, 3)
    if rng.random() < 0.5:
        spec["inertia"] = list(J)
    else:
        R = axis_angle(unit(rng, 3), float(rng.uniform(0, math.pi)))
        spec["inertia"] = [list(row) for row in R @ np.diag(J) @ R.T]
    spec["position"] = list(c)
    A = _rotation_3d(rng, spec, euler_coordinates)
    if euler_coordinates and abs(abs(A[2, 2]) - 1.0) < 0.05:     # Z-X-Z's singularity θ = 0 or π
        A = euler_zxz(0.3, 1.2, -0.4)
        for k in ("axis", "angle", "quaternion"):
            spec.pop(k, None)
        spec["euler"] = [0.3, 1.2, -0.4]
    spec.update(velocity=list(0.5 * rng.standard_normal(3)), angular_velocity=list(rng.standard_normal(3)))
    b.pose[name] = (c, A)
    b.points[name] = {}
    b.bodies[name] = spec


def _joint_2d(b, name, jtype, a, c):
    """A 2D joint between bodies a and c, satisfied at the initial pose."""
    rng = b.rng
    x = 0.5 * (b.pose[a][0] + b.pose[c][0]) + 0.3 * rng.standard_normal(2)
    spec = {"type": jtype}
    if jtype == "revolute":
        spec["between"] = [b.add_point(a, x), b.add_point(c, x)]
    else:
        u = unit(rng, 2)
        pa = b.add_point(a, x)
        spec["between"] = [pa, b.add_point(c, x + float(rng.uniform(-0.5, 0.5)) * u)]
        spec["axis"] = list(b.pose[a][1].T @ u)
        if jtype == "screw":
            spec["lead"] = float(rng.choice([-1, 1]) * rng.uniform(0.5, 3.0))
    if jtype in ("revolute", "prismatic") and b.rng.random() < 0.4:
        spec["stiffness"] = float(rng.uniform(1.0, 20.0))
        spec["damping"] = float(rng.uniform(0.0, 2.0))
    b.joints[name] = spec


#: 3D joint types and how their two points are placed: at one point, on a line along the axis, or
#: in the plane normal to it.
PLACEMENT_3D = {"spherical": "point", "revolute": "point", "fixed": "point", "universal": "point",
                "prismatic": "line", "cylindrical": "line", "screw": "line", "planar": "plane"}


def _joint_3d(b, name, jtype, a, c):
    rng = b.rng
    x = 0.5 * (b.pose[a][0] + b.pose[c][0]) + 0.3 * rng.standard_normal(3)
    u = unit(rng, 3)
    Aa = b.pose[a][1]
    spec = {"type": jtype}
    placement = PLACEMENT_3D[jtype]
    if placement == "point":
        y = x
    elif placement == "line":
        y = x + float(rng.uniform(-0.5, 0.5)) * u
    else:
        y = x + 0.5 * perpendicular(u, rng) * float(rng.uniform(-1, 1))
    spec["between"] = [b.add_point(a, x), b.add_point(c, y)]
    if jtype != "spherical" and jtype != "fixed":
        spec["axis"] = list(Aa.T @ u)
    if jtype == "universal":
        spec["axis2"] = list(Aa.T @ perpendicular(u, rng))
    if jtype == "screw":
        spec["lead"] = float(rng.choice([-1, 1]) * rng.uniform(0.5, 3.0))
    if jtype in ("revolute", "prismatic") and rng.random() < 0.4:
        spec["stiffness"] = float(rng.uniform(1.0, 20.0))
        spec["damping"] = float(rng.uniform(0.0, 2.0))
    b.joints[name] = spec


def _topology(b, names, types, loop_type, loop_ok):
    """A chain or tree of joints from the ground, and sometimes a closing joint to the ground."""
    rng = b.rng
    chain = rng.random() < 0.5
    add = _joint_2d if b.dim == 2 else _joint_3d
    for i, name in enumerate(names):
        if rng.random() < 0.15:                    # a free body, held by elements only
            continue
        parent = "ground" if i == 0 else (names[i - 1] if chain else rng.choice(["ground", *names[:i]]))
        add(b, f"j{len(b.joints)}", str(rng.choice(types)), parent, name)
    if chain and loop_ok(len(b.joints), len(names)) and rng.random() < 0.6:
        add(b, f"j{len(b.joints)}", loop_type, names[-1], "ground")


def _elements(b, names, small_displacement):
    rng = b.rng
    owners = ["ground", *names]
    for k in range(int(rng.integers(1, 5))):
        for _ in range(20):
            a, c = rng.choice(owners, 2, replace=False)
            pa, pc = b.random_point(a), b.random_point(c)
            if np.linalg.norm(b.owner[pa][1] - b.owner[pc][1]) > 0.3:
                break
        kind = str(rng.choice(["spring", "damper", "inerter"]))
        spec = {"type": kind, "between": [pa, pc]}
        if kind == "spring":
            spec["k"] = float(rng.uniform(5.0, 50.0))
            if rng.random() < 0.5:
                spec["length"] = float(rng.uniform(0.2, 1.5))
        elif kind == "damper":
            spec["c"] = float(rng.uniform(0.5, 5.0))
        else:
            spec["b"] = float(rng.uniform(0.2, 3.0))
        b.elements[f"e{k}"] = spec
    for k in range(int(rng.integers(0, 3))):
        a, c = rng.choice(owners, 2, replace=False)
        kind = str(rng.choice(["rotational_spring", "rotational_damper"]))
        spec = {"type": kind, "bodies": [str(a), str(c)]}
        if kind == "rotational_spring":
            spec["k"] = float(rng.uniform(1.0, 20.0))
            if rng.random() < 0.5:
                spec["angle"] = float(rng.uniform(-1.0, 1.0))
        else:
            spec["d"] = float(rng.uniform(0.1, 2.0))
        if b.dim == 3:
            spec["axis"] = list(unit(rng, 3))
        b.elements[f"r{k}"] = spec


def _forces(b, names):
    rng = b.rng
    for k in range(int(rng.integers(0, 3))):
        point = b.random_point(str(rng.choice(names)))
        function = str(rng.choice(["constant", "sine", "step", "pd", "input"]))
        spec = {"point": point, "function": function}
        if function != "input":
            spec["direction"] = list(unit(rng, b.dim))
        if function == "constant":
            spec["value"] = float(rng.uniform(-5, 5))
        elif function == "sine":
            spec.update(amplitude=float(rng.uniform(-5, 5)), frequency=float(rng.uniform(0.5, 3)),
                        phase=float(rng.uniform(0, 3)))
        elif function == "step":
            spec.update(value=float(rng.uniform(-5, 5)), time=float(rng.uniform(0.05, 0.25)),
                        initial=float(rng.uniform(-1, 1)))
        elif function == "pd":
            spec.update(kp=float(rng.uniform(1, 20)), kd=float(rng.uniform(0, 2)),
                        reference=float(rng.uniform(-0.5, 0.5)))
        b.forces[f"F{k}"] = spec


def random_scene(seed: int, dim: int) -> dict:
    """A random valid scene (a dict for to_toml), the same for the same seed and dimension."""
    rng = np.random.default_rng(seed)
    b = Builder(rng, dim)
    euler_coordinates = dim == 3 and rng.random() < 0.25
    names = [f"b{i}" for i in range(int(rng.integers(1, 5)))]
    for name in names:
        (_body_2d(rng, b, name) if dim == 2 else _body_3d(rng, b, name, euler_coordinates))
    if dim == 2:
        # a closing revolute joint keeps a degree of freedom when 3 or more bodies make the loop
        _topology(b, names, ["revolute", "revolute", "prismatic", "screw"], "revolute",
                  lambda joints, bodies: joints == bodies and bodies >= 3)
    else:
        # 3D loops closed by a spherical joint over spherical and universal joints (no redundancy)
        spherical_chain = rng.random() < 0.4
        types = ["spherical", "universal"] if spherical_chain else list(PLACEMENT_3D)
        _topology(b, names, types, "spherical",
                  lambda joints, bodies: spherical_chain and joints == bodies and bodies >= 2)
    for name in names:
        b.random_point(name)                       # a point on every body (its outputs)
    small = rng.random() < 0.15
    _elements(b, names, small)
    _forces(b, names)
    effects = {"centripetal": bool(rng.random() < 0.6)}
    if small:
        effects["small_displacement"] = True
    if rng.random() < 0.6:
        effects["gravity"] = list(9.81 * unit(rng, dim))
    scene = {"scene": {"name": f"random_{dim}d_{seed}", "dimension": dim}}
    if euler_coordinates:
        scene["scene"]["orientation"] = "euler_zxz"
    scene["effects"] = effects
    if b.ground_points:
        scene["ground"] = {"points": b.ground_points}
    for name in names:
        b.bodies[name]["points"] = b.points[name]
    scene["bodies"] = b.bodies
    for key in ("joints", "elements", "forces"):
        if getattr(b, key):
            scene[key] = getattr(b, key)
    scene["experiment"] = {"stop_time": RUN_TIME, "output_interval": 0.01}
    return scene


# ------------------------------------------------------------------------------------------------
# The checks
# ------------------------------------------------------------------------------------------------
def load(tmp_path, scene, **overrides):
    path = tmp_path / f"{scene['scene']['name']}.toml"
    path.write_text(to_toml(scene))
    return inerter.load(path, **overrides)


def _states(mech, run, rng):
    """(t, q, v, inputs, α): the initial state, states of the oracle's run, and those positions
    moved off the joints (3D orientation coordinates off unit length) with random velocities,
    times, inputs and Baumgarte α."""
    nq = mech.nq
    out = [(0.0, mech.q0.copy(), mech.v0.copy(), None, 0.0)]
    last = len(run.time) - (2 if run.status != "ok" else 1)
    for i in np.unique(np.linspace(0, max(last, 0), 4).astype(int)):
        q = run.states[i, :nq].copy()
        out.append((float(run.time[i]), q, run.states[i, nq:nq + mech.n].copy(), None, 0.0))
        q = q + 0.05 * rng.standard_normal(nq)
        inputs = 3.0 * rng.standard_normal(len(mech.input_names)) if mech.input_names else None
        out.append((float(rng.uniform(0, 1)), q, rng.standard_normal(mech.n), inputs, float(rng.uniform(0, 30))))
    return out


def _coefficients(mech) -> dict:
    """An element's force (torque), power and stored energy, each by its coefficient: the unit of
    comparison that keeps a stiff spring's round-off in a length from being multiplied by k."""
    coef = {}
    for e in mech.elements:
        if e.coefficient > 0:
            force = "tau" if e.kind.startswith("rotational") else "f"
            coef.update({f"{e.name}.{suffix}": e.coefficient for suffix in (force, "power", "energy")})
    return coef


def _scale(model):
    """Each output's unit of comparison: an element's force (torque), power and energy over its
    coefficient."""
    coef = _coefficients(model.mechanism)
    return np.array([coef.get(name, 1.0) for name in model.signals.names])


def _history(signals, nq, run, inputs, alpha):
    return np.array([signals.evaluate(t, y[:nq], y[nq:], inputs, alpha) for t, y in zip(run.time, run.states)])


def check_against_oracle(model, seed=0):
    """Accelerations, outputs and a run of the compiled engine against the oracle (module
    docstring); returns the worst deviations, each over its bound."""
    mech, signals = model.mechanism, model.signals
    oracle = model.oracle()
    kernel = compiled.compile_mechanism(mech)
    assert kernel.compiled
    order = kernel.signal_order(signals)
    settings = model.settings(method="DOP853", rtol=RTOL, atol=ATOL)
    inputs = (np.array([(-1.0) ** k * (1.0 + 0.5 * k) for k in range(len(mech.input_names))])
              if mech.input_names else None)
    ref_run = integrate(oracle.mechanism, settings, inputs)
    states = _states(mech, ref_run, np.random.default_rng(seed))
    pairs = [(np.concatenate(kernel.accelerations(*s)), np.concatenate(oracle.mechanism.accelerations(*s)))
             for s in states]
    top = max(float(np.max(np.abs(o))) for _, o in pairs) if pairs[0][1].size else 1.0
    acc = max(float(np.max(np.abs(a - o), initial=0.0)) / (TOL_ACC * max(float(np.max(np.abs(o), initial=0.0)),
                                                                            ACC_FLOOR * top, 1e-300))
              for a, o in pairs)
    scale = _scale(model)
    inerters = np.array([n in {f"{e.name}.f" for e in mech.inerters} for n in signals.names])
    # an inerter's power f·v_rel carries the error of q̈ times |v_rel| (its v_rel's column beside it)
    index = {n: k for k, n in enumerate(signals.names)}
    powers = [(index[f"{e.name}.power"], index[f"{e.name}.v_rel"]) for e in mech.inerters]
    out = 0.0
    for s in states:
        a = kernel.signal_values(signals, order, *s) / scale
        o = oracle.signals.evaluate(*s) / scale
        qdd = oracle.mechanism.accelerations(*s)[0]
        carried = inerters.astype(float)
        for k, kv in powers:
            carried[k] = 1.0 + abs(o[kv])
        out = max(out, float(np.max(np.abs(a - o) / (1.0 + np.abs(o) + carried * float(np.max(np.abs(qdd), initial=0.0))))) / TOL_OUT)
    run = compiled.integrate_compiled(mech, settings, inputs)
    assert run.extra["path"] == "compiled"
    assert run.status == ref_run.status, (run.message, ref_run.message)
    assert np.array_equal(run.time, ref_run.time)
    values, _ = kernel.signal_history(signals, order, run.time, run.states, inputs, settings.alpha)
    ref = _history(oracle.signals, mech.nq, ref_run, inputs, settings.alpha)
    dev = np.abs(values - ref) / scale / np.maximum(1.0, np.max(np.abs(ref / scale), axis=0))
    return dict(acc=acc, out=out, run=float(np.max(dev)) / TOL_RUN, status=run.status)


def _run_outputs(model, inputs=None, oracle=False, path="compiled"):
    """A DOP853 run at RTOL, ATOL (compiled, or the oracle's numpy run) and its outputs by name."""
    mech, signals = model.mechanism, model.signals
    settings = model.settings(method="DOP853", rtol=RTOL, atol=ATOL)
    if oracle:
        o = model.oracle()
        run = integrate(o.mechanism, settings, inputs)
        values = _history(o.signals, mech.nq, run, inputs, settings.alpha)
    else:
        kernel = compiled.compile_mechanism(mech)
        run = compiled.integrate_compiled(mech, settings, inputs)
        values, _ = kernel.signal_history(signals, kernel.signal_order(signals), run.time, run.states, inputs,
                                          settings.alpha)
    return run, dict(zip(signals.names, values.T))


def _range_deviation(a, b, names, coefficients):
    """max over the names of |a − b| over max(1, the range of b), forces over their coefficients."""
    worst, where = 0.0, None
    for n in names:
        k = coefficients.get(n, 1.0)
        d = float(np.max(np.abs(a[n] - b[n]))) / k / max(1.0, float(np.max(np.abs(b[n]))) / k)
        if d > worst:
            worst, where = d, n
    return worst, where


def as_3d(scene: dict) -> dict:
    """A planar scene (revolute and prismatic joints, no closed loop) written as a 3D one: every
    vector with z = 0, rotations about Z, revolute axes along Z, rotational elements about Z with
    their free angle measured from the initial pose as 3D measures it."""
    import copy
    s = copy.deepcopy(scene)
    s["scene"]["dimension"] = 3
    s["scene"]["name"] += "_as_3d"
    z = lambda v: [*v, 0.0]                                            # noqa: E731
    if "gravity" in s["effects"]:
        s["effects"]["gravity"] = z(s["effects"]["gravity"])
    if "ground" in s:
        s["ground"]["points"] = {k: z(v) for k, v in s["ground"]["points"].items()}
    angle = {"ground": 0.0}
    for name, b in s["bodies"].items():
        angle[name] = b["angle"]
        b.update(inertia=[b["inertia"], b["inertia"], b["inertia"]], position=z(b["position"]), axis=[0, 0, 1],
                 velocity=z(b["velocity"]), angular_velocity=[0.0, 0.0, b["angular_velocity"]],
                 points={k: z(v) for k, v in b["points"].items()})
    for j in s.get("joints", {}).values():
        j["axis"] = z(j["axis"]) if "axis" in j else [0, 0, 1]
    for e in s.get("elements", {}).values():
        if e["type"].startswith("rotational"):
            e["axis"] = [0, 0, 1]
            if "angle" in e:
                a, b = e["bodies"]
                e["angle"] -= angle[b] - angle[a]
    for f in s.get("forces", {}).values():
        if "direction" in f:
            f["direction"] = z(f["direction"])
    return s


# ------------------------------------------------------------------------------------------------
# The tests
# ------------------------------------------------------------------------------------------------
def _has(scene, what):
    gp = scene.get("ground", {}).get("points", {})
    joints = scene.get("joints", {}).values()
    if what == "moving slider":          # a prismatic joint's spring or damper whose axis turns
        return any(j["type"] == "prismatic" and "stiffness" in j and j["between"][0] not in gp for j in joints)
    if what == "euler":
        return scene["scene"].get("orientation") == "euler_zxz"
    raise ValueError(what)


#: Seeds of 2D and 3D scenes (each a different mix of bodies, joints, loops, elements, forces and
#: effects; see `random_scene`), chosen to cover every joint type and both loop kinds.
SEEDS_2D = [1, 3, 9, 13, 15, 17, 18]             # 15: a closed loop; 17: a prismatic joint's spring on a moving body
SEEDS_3D = [0, 9, 10, 13, 14, 21, 22, 24, 26, 37]  # 37: a closed loop; 26: as 2D 17
SEEDS_EULER = [29, 34, 36]                       # 3D scenes on Z-X-Z Euler coordinates; 36: a loop
SEEDS_AS_3D = [1, 6, 11, 23, 36, 57]


@pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")
@pytest.mark.parametrize("dim, seed", [(2, s) for s in SEEDS_2D] + [(3, s) for s in SEEDS_3D])
def test_random_mechanism_equals_the_oracle(tmp_path, dim, seed):
    """Accelerations, outputs and a run of the compiled engine against the oracle (module docstring:
    the reference and the tolerances)."""
    scene = random_scene(seed, dim)
    assert not _has(scene, "euler")
    result = check_against_oracle(load(tmp_path, scene), seed)
    assert result["acc"] <= 1.0 and result["out"] <= 1.0 and result["run"] <= 1.0, result


@pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")
@pytest.mark.parametrize("seed", SEEDS_EULER)
def test_random_mechanism_on_euler_angles_equals_the_oracle_on_quaternions(tmp_path, seed):
    """A scene on Z-X-Z Euler coordinates (the compiled engine) against the oracle on the same scene
    with quaternion coordinates (the oracle differentiates quaternion kinematics only): every output
    but the orientation's own (B.q, B.euler: a quaternion's sign and an angle's branch are
    conventions) within TOL_RUN of its range, forces over their coefficients."""
    scene = random_scene(seed, 3)
    assert _has(scene, "euler")
    model = load(tmp_path, scene)
    mech = model.mechanism
    inputs = np.arange(1.0, 1.0 + len(mech.input_names)) if mech.input_names else None
    run, values = _run_outputs(model, inputs)
    ref_run, ref = _run_outputs(model.with_overrides(**{"scene.orientation": "quaternion"}), inputs, oracle=True)
    assert run.status == ref_run.status == "ok" and np.array_equal(run.time, ref_run.time)
    names = [n for n in ref if ".q[" not in n and ".euler[" not in n]
    coefficients = _coefficients(mech)
    dev, where = _range_deviation(values, ref, names, coefficients)
    assert dev <= TOL_RUN, (where, dev)


@pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")
@pytest.mark.parametrize("seed", SEEDS_AS_3D)
def test_a_random_planar_scene_written_as_3d_moves_as_in_2d(tmp_path, seed):
    """The 2D scene and its 3D writing (as_3d) run with DOP853 at RTOL: every output of the 2D run
    (phi_rel from its initial value: 3D measures it from the initial pose) within TOL_RUN of its
    range in the 3D run, and the 3D points stay in the plane (|z| ≤ 1e-12 m)."""
    scene = random_scene(seed, 2)
    assert not any(j["type"] == "screw" for j in scene.get("joints", {}).values())
    m2, m3 = load(tmp_path, scene), load(tmp_path, as_3d(scene))
    n2, n3 = m2.mechanism.input_names, m3.mechanism.input_names
    i2 = np.array([(-1.0) ** k * (1.0 + 0.5 * k) for k in range(len(n2))]) if n2 else None
    i3 = np.array([dict(zip(n2, i2)).get(n, 0.0) for n in n3]) if n3 else None
    (r2, o2), (r3, o3) = _run_outputs(m2, i2), _run_outputs(m3, i3)
    assert r2.status == r3.status == "ok" and np.array_equal(r2.time, r3.time)
    for o in (o2, o3):
        for n in o:
            if n.endswith("phi_rel"):
                o[n] = o[n] - o[n][0]
    dev, where = _range_deviation(o3, o2, list(o2), _coefficients(m2.mechanism))
    assert dev <= TOL_RUN, (where, dev)
    assert max(float(np.max(np.abs(o3[n]))) for n in o3 if n.endswith(".r[3]")) <= 1e-12
