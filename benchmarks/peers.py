"""Peers for the two-bar mechanism (paper Sec. 3.4), measured in the same run as the solver:

* ``TwoAngleODE``: the mechanism written by hand in its two absolute bar angles (Lagrange), with
  the corrected inerter, integrated by scipy's ``solve_ivp``;
* ``mujoco_two_bar``: MuJoCo with hinge joints and a spatial tendon D–E carrying the spring
  (stiffness, springlength), the damper (damping) and the inerter (tendon armature = b); the sine
  force at C applied at every stage through ``mjcb_control``; RK4 with a fixed step.

Derivation of the 2-angle ODE (θ1, θ2 absolute angles of bar 1 and bar 2, both 1 m long, centres
of mass at their middles, A at the origin):

    D = ¾ e(θ1),  E = e(θ1) + ¾ e(θ2),  C = e(θ1) + e(θ2),  e(θ) = (cos θ, sin θ)
    r = E − D = ¼ e(θ1) + ¾ e(θ2),  ∂r/∂θ = [¼ e'(θ1), ¾ e'(θ2)],  L = |r|,  g = ∇L = (∂r/∂θ)ᵀ r̂
    L̈ = g·θ̈ + r̂·a_n + (|ṙ|² − L̇²)/L,  a_n = −¼ θ̇1² e(θ1) − ¾ θ̇2² e(θ2)      (Eq. 9; Eq. 8 drops the last term)
    M = [[J1 + M1/4 + M2, ½M2 cos(θ1 − θ2)], [½M2 cos(θ1 − θ2), J2 + M2/4]]
    h = ½M2 sin(θ1 − θ2) [θ̇2², −θ̇1²]                                          (Coriolis/centrifugal)
    (M + b g gᵀ) θ̈ = −h − kr(θ1 − θ1₀) ê1 + F(t)[cos θ1, cos θ2] − [k(L − L0) + c L̇ + b(r̂·a_n + |ṙ⊥|²/L)] g
"""
from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp


class TwoAngleODE:
    def __init__(self, kr=1000.0, k=100.0, c=100.0, b=10.0, M1=1.0, M2=1.0, J1=0.083, J2=0.083, Fa=8.0, f=1.0,
                 th1=math.pi / 4, th2=3 * math.pi / 4, centripetal=True):
        self.p = (kr, k, c, b, M1, M2, J1, J2, Fa, f, th1, centripetal)
        r0 = 0.25 * np.array((math.cos(th1), math.sin(th1))) + 0.75 * np.array((math.cos(th2), math.sin(th2)))
        self.L0 = float(np.hypot(*r0))
        self.y0 = np.array((th1, th2, 0.0, 0.0))

    def rhs(self, t, y):
        kr, k, c, b, M1, M2, J1, J2, Fa, f, th10, cen = self.p
        t1, t2, w1, w2 = y
        c1, s1, c2, s2 = math.cos(t1), math.sin(t1), math.cos(t2), math.sin(t2)
        rx, ry = 0.25 * c1 + 0.75 * c2, 0.25 * s1 + 0.75 * s2
        L = math.hypot(rx, ry)
        ex, ey = rx / L, ry / L
        g1 = 0.25 * (-s1 * ex + c1 * ey)
        g2 = 0.75 * (-s2 * ex + c2 * ey)
        vx = -0.25 * s1 * w1 - 0.75 * s2 * w2
        vy = 0.25 * c1 * w1 + 0.75 * c2 * w2
        Ld = g1 * w1 + g2 * w2
        an = -0.25 * w1 * w1 * (c1 * ex + s1 * ey) - 0.75 * w2 * w2 * (c2 * ex + s2 * ey)
        if cen:
            an += (vx * vx + vy * vy - Ld * Ld) / L
        Fel = k * (L - self.L0) + c * Ld + b * an
        cd, sd = math.cos(t1 - t2), math.sin(t1 - t2)
        m11 = J1 + 0.25 * M1 + M2 + b * g1 * g1
        m12 = 0.5 * M2 * cd + b * g1 * g2
        m22 = J2 + 0.25 * M2 + b * g2 * g2
        F = Fa * math.sin(2 * math.pi * f * t)
        q1 = -0.5 * M2 * sd * w2 * w2 - kr * (t1 - th10) + F * c1 - Fel * g1
        q2 = 0.5 * M2 * sd * w1 * w1 + F * c2 - Fel * g2
        det = m11 * m22 - m12 * m12
        return [w1, w2, (m22 * q1 - m12 * q2) / det, (m11 * q2 - m12 * q1) / det]

    def solve(self, stop_time, grid, rtol, atol, method="DOP853"):
        """(C_y at the grid, CPU s, nfev)."""
        t0 = time.process_time()
        sol = solve_ivp(self.rhs, (0.0, stop_time), self.y0, method=method, t_eval=grid, rtol=rtol, atol=atol)
        cpu = time.process_time() - t0
        if sol.status != 0:
            raise RuntimeError(sol.message)
        return np.sin(sol.y[0]) + np.sin(sol.y[1]), cpu, sol.nfev


MJCF = """
<mujoco model="two_bar">
  <compiler angle="radian"/>
  <option gravity="0 0 0" integrator="RK4" timestep="{dt}"/>
  <worldbody>
    <body name="bar1" pos="0 0 0" euler="0 0 {th1}">
      <joint name="A" type="hinge" axis="0 0 1" stiffness="{kr}" springref="0"/>
      <inertial pos="0.5 0 0" mass="{M1}" diaginertia="{J1} {J1} {J1}"/>
      <site name="D" pos="0.75 0 0"/>
      <body name="bar2" pos="1 0 0" euler="0 0 {dth}">
        <joint name="B" type="hinge" axis="0 0 1"/>
        <inertial pos="0.5 0 0" mass="{M2}" diaginertia="{J2} {J2} {J2}"/>
        <site name="E" pos="0.75 0 0"/>
        <site name="C" pos="1 0 0"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <spatial name="DE" stiffness="{k}" damping="{c}" armature="{b}" springlength="{L0}">
      <site site="D"/>
      <site site="E"/>
    </spatial>
  </tendon>
</mujoco>
"""


def mujoco_two_bar(stop_time, grid, dt, kr=1000.0, k=100.0, c=100.0, b=10.0, M1=1.0, M2=1.0, J1=0.083, J2=0.083,
                   Fa=8.0, f=1.0, th1=math.pi / 4, th2=3 * math.pi / 4):
    """(C_y at the grid, CPU s, steps); raises ImportError without mujoco."""
    import mujoco

    L0 = TwoAngleODE(th1=th1, th2=th2).L0
    model = mujoco.MjModel.from_xml_string(MJCF.format(dt=dt, th1=th1, dth=th2 - th1, kr=kr, k=k, c=c, b=b, M1=M1,
                                                       M2=M2, J1=J1, J2=J2, L0=L0))
    data = mujoco.MjData(model)
    w = 2 * math.pi * f

    def control(m, d):
        a1 = th1 + d.qpos[0]
        a2 = a1 + (th2 - th1) + d.qpos[1]
        F = Fa * math.sin(w * d.time)
        d.qfrc_applied[0] = F * (math.cos(a1) + math.cos(a2))
        d.qfrc_applied[1] = F * math.cos(a2)

    out = np.empty(len(grid))
    stride = int(round((grid[1] - grid[0]) / dt))
    if abs(stride * dt - (grid[1] - grid[0])) > 1e-12:
        raise ValueError("the MuJoCo step must divide the output interval")
    mujoco.set_mjcb_control(control)
    try:
        mujoco.mj_forward(model, data)
        out[0] = _cy(data.qpos, th1, th2)
        steps = 0
        t0 = time.process_time()
        for i in range(1, len(grid)):
            for _ in range(stride):
                mujoco.mj_step(model, data)
            steps += stride
            out[i] = _cy(data.qpos, th1, th2)
        cpu = time.process_time() - t0
    finally:
        mujoco.set_mjcb_control(None)
    return out, cpu, steps


def _cy(qpos, th1, th2):
    """C_y from the hinge angles (site_xpos after mj_step still holds the previous step's pose)."""
    a1 = th1 + qpos[0]
    return math.sin(a1) + math.sin(a1 + (th2 - th1) + qpos[1])
