"""An N-link planar chain scene (TOML) for scaling benchmarks.

    python benchmarks/chain_scene.py 32 out/chain32.toml [--gravity]

N uniform bars (length l, mass m) pinned end to end, the first pinned to the ground; a
rotational spring and damper at every pin; between the midpoints of neighbouring bars a spring,
a damper and an inerter in parallel (so M + M_I couples neighbours and the augmented matrix is
block-banded); a sine force along Y at the free end. The chain starts as a gentle arc (a quarter
turn over its length), at rest.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path


#: The chain's parameters (SI units), shared with the MuJoCo model of benchmarks/chain_mujoco.py.
PARAMETERS = dict(l=0.5, m=1.0, kr=200.0, dr=0.2, k=500.0, c=2.0, b=2.0, Fa=5.0, f=1.0)


def initial_angles(links: int) -> list[float]:
    """Absolute angle of every bar at t = 0: a quarter turn spread evenly over the chain."""
    turn = 0.5 * math.pi / links
    return [(i - 0.5) * turn for i in range(1, links + 1)]


def chain_toml(links: int, gravity: bool = False, extra_forces: bool = False, centripetal: bool = True,
               inerters: bool = True) -> str:
    if links < 1:
        raise ValueError("links must be at least 1")
    P = PARAMETERS
    l, m = P["l"], P["m"]
    lines = [
        "[scene]",
        f'name = "chain_{links}"',
        f'description = "{links}-link planar chain with inerters between neighbours (scaling benchmark)"',
        "",
        "[parameters]",
        f'l = {{ value = {l}, unit = "m", description = "bar length" }}',
        f'm = {{ value = {m}, unit = "kg", description = "bar mass" }}',
        f'kr = {{ value = {P["kr"]}, unit = "N.m/rad", description = "rotational spring at every pin" }}',
        f'dr = {{ value = {P["dr"]}, unit = "N.m.s/rad", description = "rotational damper at every pin" }}',
        f'k = {{ value = {P["k"]}, unit = "N/m", description = "spring between neighbouring midpoints" }}',
        f'c = {{ value = {P["c"]}, unit = "N.s/m", description = "damper between neighbouring midpoints" }}',
        f'b = {{ value = {P["b"]}, unit = "kg", description = "inertance between neighbouring midpoints" }}',
        f'Fa = {{ value = {P["Fa"]}, unit = "N", description = "tip force amplitude" }}',
        f'f = {{ value = {P["f"]}, unit = "Hz", description = "tip force frequency" }}',
        "",
        "[effects]",
        f"centripetal = {'true' if centripetal else 'false'}",
    ]
    if gravity:
        lines.append("gravity = [0, -9.81]")
    lines += ["", "[ground.points]", "O = [0, 0]", ""]
    x = y = 0.0
    for i, th in enumerate(initial_angles(links), start=1):
        cx, cy = x + 0.5 * l * math.cos(th), y + 0.5 * l * math.sin(th)
        lines += [
            f"[bodies.bar{i}]",
            'mass = "m"',
            'inertia = "m*l^2/12"',
            f"position = [{cx!r}, {cy!r}]",
            f"angle = {th!r}",
            f'points = {{ P{i}a = ["-l/2", 0], P{i}b = ["l/2", 0], M{i} = [0, 0] }}',
            "",
        ]
        x, y = x + l * math.cos(th), y + l * math.sin(th)
    for i in range(1, links + 1):
        a = "O" if i == 1 else f"P{i - 1}b"
        prev = "ground" if i == 1 else f"bar{i - 1}"
        lines += [f"[joints.pin{i}]", 'type = "revolute"', f'between = ["{a}", "P{i}a"]', "",
                  f"[elements.kr{i}]", 'type = "rotational_spring"', f'bodies = ["{prev}", "bar{i}"]', 'k = "kr"', "",
                  f"[elements.dr{i}]", 'type = "rotational_damper"', f'bodies = ["{prev}", "bar{i}"]', 'd = "dr"', ""]
    for i in range(1, links):
        pair = f'between = ["M{i}", "M{i + 1}"]'
        lines += [f"[elements.k{i}]", 'type = "spring"', pair, 'k = "k"', "",
                  f"[elements.c{i}]", 'type = "damper"', pair, 'c = "c"', ""]
        if inerters:
            lines += [f"[elements.b{i}]", 'type = "inerter"', pair, 'b = "b"', ""]
    lines += ["[forces.tip]", f'point = "P{links}b"', "direction = [0, 1]", 'function = "sine"',
              'amplitude = "Fa"', 'frequency = "f"', ""]
    if extra_forces:
        lines += ["[forces.push]", f'point = "M{links}"', "direction = [0.6, 0.8]", 'function = "constant"',
                  "value = 1.5", "",
                  "[forces.kick]", 'point = "M1"', "direction = [1, 0]", 'function = "step"', "value = 2.0",
                  "time = 0.3", "initial = -1.0", "",
                  "[forces.hold]", f'point = "P{links}b"', "direction = [0, 1]", 'function = "pd"', "kp = 50",
                  "kd = 2", "reference = 0.1", "",
                  "[forces.tip_in]", f'point = "P{links}b"', 'function = "input"', ""]
    lines += ["[experiment]", "stop_time = 2.0", "output_interval = 0.01", 'method = "DOP853"', "rtol = 1e-8",
              "atol = 1e-10", ""]
    return "\n".join(lines)


def write_chain(path, links: int, **kw) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(chain_toml(links, **kw))
    return path


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("links", type=int)
    p.add_argument("out")
    p.add_argument("--gravity", action="store_true")
    p.add_argument("--no-inerters", action="store_true")
    a = p.parse_args(argv)
    print(write_chain(a.out, a.links, gravity=a.gravity, inerters=not a.no_inerters))


if __name__ == "__main__":
    main()
