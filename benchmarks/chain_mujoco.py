"""MuJoCo model of the N-link chain of benchmarks/chain_scene.py, for side-by-side timings.

    python benchmarks/chain_mujoco.py [--links 2,8] [--stop-time 2] [--step 1e-4]

prints the agreement of the tip position with the compiled path's DOP853 at rtol 1e-12 (the
check that both model the same physics).

The same physics as the scene, term by term:

* bars: body i hangs from the end of bar i−1 (bar 1 from the origin) by a hinge about z, at
  the relative angle of t = 0 (qpos0 = 0 is the scene's initial state, at rest); mass m at the
  midpoint, inertia m l²/12 about z (the other axes carry the same value; the hinges never
  excite them);
* rotational spring and damper at every pin: the hinge's stiffness kr (springref 0, i.e. the
  initial relative angle, the scene's free angle) and damping dr (τ = dr ω_rel);
* between neighbouring midpoints a spatial tendon with stiffness k, rest length its length at
  t = 0 (the scene's spring free length), damping c (F = c L̇) and armature b: MuJoCo adds
  b JᵀJ to the mass matrix and b Jᵀ(J̇ q̇) to the bias force, the exact inerter F = b L̈
  (centripetal term included, the scene's ``centripetal = true``);
* the tip force F(t) = Fa sin(2π f t) along global y at the free end: applied at every RK4
  stage from ``mjcb_control`` as a force (0, F, 0) at the last bar's centre of mass plus the
  torque (x_tip − x_com) F about z, with d.time the stage's time;
* no gravity (the scaling scene has none), no geoms, contacts and all constraints disabled (and
  the reset after a blow-up, so an unstable step shows as such),
  integrator RK4 (explicit: joint damping is not treated implicitly as with Euler).

The tip position is computed from qpos (after ``mj_step`` the site positions still hold the
pose of the step's first stage).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from chain_scene import PARAMETERS, initial_angles  # noqa: E402


def chain_mjcf(links: int, dt: float, jacobian: str = "auto") -> str:
    """MJCF of the chain; `jacobian`: MuJoCo's dense/sparse choice ("auto": dense below 60 dofs)."""
    P = PARAMETERS
    l, m = P["l"], P["m"]
    J = m * l * l / 12.0
    angles = initial_angles(links)
    rel = [angles[0]] + [angles[i] - angles[i - 1] for i in range(1, links)]
    body, close = [], []
    for i in range(1, links + 1):
        pad = "  " * (i + 1)
        pos = "0 0 0" if i == 1 else f"{l!r} 0 0"
        body += [f'{pad}<body name="bar{i}" pos="{pos}" euler="0 0 {rel[i - 1]!r}">',
                 f'{pad}  <joint name="pin{i}" type="hinge" axis="0 0 1" stiffness="{P["kr"]!r}" springref="0" '
                 f'damping="{P["dr"]!r}"/>',
                 f'{pad}  <inertial pos="{0.5 * l!r} 0 0" mass="{m!r}" diaginertia="{J!r} {J!r} {J!r}"/>',
                 f'{pad}  <site name="M{i}" pos="{0.5 * l!r} 0 0"/>']
        close.insert(0, f"{pad}</body>")
    body.append(f'{"  " * (links + 2)}<site name="tip" pos="{l!r} 0 0"/>')
    tendons = []
    for i in range(1, links):
        tendons += [f'    <spatial name="t{i}" stiffness="{P["k"]!r}" damping="{P["c"]!r}" armature="{P["b"]!r}">',
                    f'      <site site="M{i}"/>', f'      <site site="M{i + 1}"/>', "    </spatial>"]
    return "\n".join([
        f'<mujoco model="chain_{links}">',
        '  <compiler angle="radian" autolimits="false"/>',
        f'  <option gravity="0 0 0" integrator="RK4" timestep="{dt!r}" jacobian="{jacobian}">',
        '    <flag contact="disable" constraint="disable" autoreset="disable"/>',
        "  </option>",
        "  <worldbody>", *body, *close, "  </worldbody>",
        "  <tendon>", *tendons, "  </tendon>",
        "</mujoco>", ""])


class MujocoChain:
    """The chain in MuJoCo, integrated with a fixed step over a grid of output samples."""

    def __init__(self, links: int, dt: float, jacobian: str = "auto"):
        import mujoco

        self.mujoco = mujoco
        self.links, self.dt = links, dt
        self.model = mujoco.MjModel.from_xml_string(chain_mjcf(links, dt, jacobian))
        self.data = mujoco.MjData(self.model)
        P = PARAMETERS
        self.l = P["l"]
        self.angles0 = np.array(initial_angles(links))
        self.rel0 = np.diff(self.angles0, prepend=0.0)
        self._check()
        last = links                                          # body id of the last bar (0 is the world)
        Fa, w, half = P["Fa"], 2.0 * math.pi * P["f"], 0.5 * self.l

        def control(m, d):
            F = Fa * math.sin(w * d.time)
            frc = d.xfrc_applied[last]
            frc[1] = F
            frc[5] = half * d.xmat[last, 0] * F              # (x_tip − x_com) F, x_tip − x_com = l/2 cos θ_N
        self.control = control

    def _check(self):
        m, mujoco = self.model, self.mujoco
        if m.nv != self.links or m.ntendon != self.links - 1:
            raise AssertionError("unexpected MuJoCo model size")
        if self.links > 1 and not np.allclose(m.tendon_armature, PARAMETERS["b"]):
            raise AssertionError("this MuJoCo ignores the tendon armature (the inerter)")
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        if self.links > 1 and not np.allclose(m.tendon_lengthspring[:, 0], d.ten_length, rtol=0, atol=1e-14):
            raise AssertionError("tendon rest lengths differ from the initial lengths")
        if not np.allclose(d.site_xpos[-1, :2], self.tip(d.qpos[None, :])[0], rtol=0, atol=1e-13):
            raise AssertionError("tip from qpos differs from MuJoCo's tip site")

    def tip(self, qpos: np.ndarray) -> np.ndarray:
        """Global (x, y) of the free end along a history of qpos (T × N)."""
        th = np.cumsum(np.atleast_2d(qpos) + self.rel0, axis=1)
        return self.l * np.column_stack((np.cos(th).sum(axis=1), np.sin(th).sum(axis=1)))

    def simulate(self, stop_time: float, output_interval: float, dt: float | None = None, integrator: str = "RK4"):
        """`integrator` (RK4, or MuJoCo's default Euler: semi-implicit, joint damping implicit) with
        the step dt (default: the model's) over 0..stop_time. Returns (sample indices
        on the output grid k·output_interval, tip positions there (T × 2; inf after a blow-up),
        CPU s of the stepping, steps). The samples are the grid points the steps land on: every
        one when dt divides the output interval, else every grid point that is a multiple of dt."""
        mujoco, m = self.mujoco, self.model
        dt = float(dt or self.dt)
        m.opt.timestep = dt
        m.opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
        steps = int(math.floor(stop_time / dt + 1e-9))
        ratio = np.arange(steps + 1) * dt / output_interval
        on_grid = np.abs(ratio - np.round(ratio)) < 1e-9
        index = np.round(ratio[on_grid]).astype(int)
        record = on_grid.tolist()
        qpos = np.empty((len(index), m.nq))
        d = mujoco.MjData(m)
        qpos[0] = d.qpos
        k = 1
        step = mujoco.mj_step
        bad = d.warning[mujoco.mjtWarning.mjWARN_BADQACC]
        warn = mujoco.get_mju_user_warning()
        mujoco.set_mju_user_warning(lambda msg: None)        # a blow-up is reported by the result
        mujoco.set_mjcb_control(self.control)
        try:
            start = time.process_time()
            for j in range(1, steps + 1):
                step(m, d)
                if record[j]:
                    qpos[k] = d.qpos
                    k += 1
                    if bad.number:
                        break
            cpu = time.process_time() - start
        finally:
            mujoco.set_mjcb_control(None)
            mujoco.set_mju_user_warning(warn)
        tip = self.tip(qpos)
        if bad.number or not np.all(np.isfinite(tip)):
            tip[:] = np.inf
        return index, tip, cpu, steps

    def step_cost(self, steps: int, forcing: bool = True, repeats: int = 3) -> float:
        """CPU s per RK4 step (best of `repeats`) from the initial state. `forcing=False`: without
        the tip force and its callback, from an initial velocity (a chain at rest costs less to
        step), to show what the callback adds; not the benchmark's physics."""
        mujoco, m = self.mujoco, self.model
        m.opt.timestep = self.dt
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        best = math.inf
        mujoco.set_mjcb_control(self.control if forcing else None)
        try:
            for _ in range(repeats):
                d = mujoco.MjData(m)
                if not forcing:
                    d.qvel[:] = 0.3 * np.sin(np.arange(m.nv) + 1.0)
                start = time.process_time()
                for _ in range(steps):
                    mujoco.mj_step(m, d)
                best = min(best, time.process_time() - start)
        finally:
            mujoco.set_mjcb_control(None)
        return best / steps


def compiled_tip(links: int, stop_time: float, output_interval: float = 0.01, **settings):
    """Tip positions (T × 2) of the compiled path and its Run (settings: method, rtol, atol, step)."""
    import tempfile

    import inerter
    from inerter.engine import compiled
    from chain_scene import write_chain

    tmp = Path(tempfile.mkdtemp())
    model = inerter.load(write_chain(tmp / f"chain_{links}.toml", links))
    s = model.settings(stop_time=stop_time, output_interval=output_interval, **settings)
    s.max_steps = max(s.max_steps, 10 ** 7)
    run = compiled.integrate_compiled(model.mechanism, s)
    if run.status != "ok":
        raise RuntimeError(run.message)
    kernel = compiled._kernel_for(model.mechanism)
    return kernel.point_positions(run.states)[f"P{links}b"], run


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--links", default="2,8")
    p.add_argument("--stop-time", type=float, default=2.0)
    p.add_argument("--step", type=float, default=1e-4, help="MuJoCo RK4 step (s)")
    a = p.parse_args(argv)
    import mujoco

    print(f"MuJoCo {mujoco.__version__}")
    for n in (int(x) for x in a.links.split(",")):
        ref, _ = compiled_tip(n, a.stop_time, method="DOP853", rtol=1e-12, atol=1e-14)
        idx, tip, _, _ = MujocoChain(n, a.step).simulate(a.stop_time, 0.01)
        err = float(np.max(np.linalg.norm(tip - ref[idx], axis=1)))
        print(f"N = {n}: max |tip MuJoCo RK4 {a.step:g} s − compiled DOP853 rtol 1e-12| over 0-{a.stop_time:g} s "
              f"= {err:.2e} m (tip travel {float(np.max(np.linalg.norm(ref - ref[0], axis=1))):.3f} m)")


if __name__ == "__main__":
    main()
