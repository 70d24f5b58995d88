"""The compiled fast path (inerter.engine.compiled): its solver, integrator loops, stepper and cache,
and the terms the shipped scenes lack against the oracle. The shipped scenes' accelerations,
outputs and runs against the oracle are in test_engine_vs_oracle.py. No timing assertions
(timings: benchmarks/)."""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest

import inerter
from inerter.engine import compiled
from inerter.engine.simulation import integrate

ROOT = Path(__file__).resolve().parents[1]
PAPER = [ROOT / "scenarios" / "lumped_mass_2d.toml", ROOT / "scenarios" / "two_bar_2d.toml"]

needs_numba = pytest.mark.skipif(not compiled.AVAILABLE, reason=compiled.WHY_NOT or "numba missing")


def test_numba_missing_falls_back_to_numpy():
    """Without numba the kernel is the numpy path (and says so); with it, the compiled one."""
    model = inerter.load(PAPER[1])
    kernel = compiled.compile_mechanism(model.mechanism)
    assert kernel.compiled == compiled.AVAILABLE
    if not compiled.AVAILABLE:
        pytest.skip(f"numba missing, numpy path used: {compiled.WHY_NOT}")


def _random_states(mech, rng, count=12):
    """Random (t, q, v, inputs, α); in 3D the quaternions are perturbed off unit length too (the
    kernels, as the numpy path, normalise them inside the rotation matrix only)."""
    for _ in range(count):
        q = mech.q0 + 0.2 * rng.standard_normal(mech.nq)
        v = 2.0 * rng.standard_normal(mech.n)
        inputs = 5.0 * rng.standard_normal(len(mech.input_names)) if mech.input_names else None
        yield float(rng.uniform(0.0, 10.0)), q, v, inputs, float(rng.choice([0.0, rng.uniform(0.0, 50.0)]))


def _dense_partial_pivoting(A, b):
    """Gaussian elimination with partial pivoting (first largest |pivot|, rows swapped whole),
    multipliers by division, back substitution left to right: the reference for band_solve."""
    A, b = A.copy(), b.copy()
    N = len(b)
    for k in range(N):
        p = k + int(np.argmax(np.abs(A[k:, k])))
        A[[k, p]], b[[k, p]] = A[[p, k]], b[[p, k]]
        for i in range(k + 1, N):
            l = A[i, k] / A[k, k]
            A[i, k + 1:] -= l * A[k, k + 1:]
            b[i] -= l * b[k]
    x = np.empty(N)
    for i in range(N - 1, -1, -1):
        s = b[i]
        for j in range(i + 1, N):
            s -= A[i, j] * x[j]
        x[i] = s / A[i, i]
    return x


@needs_numba
@pytest.mark.parametrize("kl,ku,N", [(1, 1, 6), (3, 2, 9), (2, 5, 12), (8, 8, 10), (8, 8, 40), (0, 3, 7)])
def test_band_solve_is_partial_pivoting_bit_for_bit(kl, ku, N):
    """band_solve (row-wise band storage, each row's profile tracked) gives the same solution, bit
    for bit, as plain dense elimination with partial pivoting: skipping the zeros outside the
    profiles changes no operation on a nonzero. Random banded matrices with a third of the band
    zero and zero diagonals in places (as the augmented matrix's λ rows), so rows are swapped; the
    residual is checked against the matrix too (1e-12 relative). A singular matrix returns False."""
    from inerter.engine import kernels as ck

    rng = np.random.default_rng(kl * 100 + ku * 10 + N)
    solved = 0
    for trial in range(20):
        A = np.zeros((N, N))
        for i in range(N):
            for j in range(max(0, i - kl), min(N, i + ku + 1)):
                if i == j and i % 3 == 2:
                    continue                                 # a zero diagonal: the pivot comes from below
                if rng.random() < 0.67 or i == j:
                    A[i, j] = rng.standard_normal()
        if kl == 0:
            A[np.diag_indices(N)] = 1.0 + rng.random(N)     # no row below to pivot with
        b = rng.standard_normal(N)
        if abs(np.linalg.det(A)) < 1e-8:
            continue
        AB = ck.band_storage(kl, ku, N)
        AB[:] = 0.0
        for i in range(N):
            for j in range(max(0, i - kl), min(N, i + ku + 1)):
                AB[i, kl + j - i] = A[i, j]
        x = b.copy()
        assert ck.band_solve(AB, x, kl)
        assert np.array_equal(x, _dense_partial_pivoting(A, b)), trial
        assert np.max(np.abs(A @ x - b)) <= 1e-12 * np.max(np.abs(A)) * np.max(np.abs(x)) * N
        solved += 1
    assert solved >= 10, f"only {solved} of 20 random matrices were well enough conditioned"
    singular = ck.band_storage(kl, ku, N)
    singular[:] = 0.0
    singular[:, kl] = 1.0
    singular[N // 2, kl] = 0.0                          # diagonal with one zero: column N // 2 is empty
    assert not ck.band_solve(singular, np.ones(N), kl)


@needs_numba
def test_band_solve_above_its_stack_rows_is_the_same_elimination():
    """Above STACK_ROWS rows band_solve keeps its rows' profile on the heap, not on the stack: the
    same elimination. A block-diagonal system (a random 9 × 9 band block with zero diagonals in
    places, then the identity) solved whole, N = STACK_ROWS + 9, gives bit for bit the block's
    solution solved alone (N = 9, the profile on the stack), itself the dense elimination's (the
    reference of the test above), and b on the identity: the identity's rows hold nothing in the
    block's columns, so no operation of the block's elimination changes."""
    from inerter.engine import kernels as ck

    kl, ku, n = 2, 2, 9
    rng = np.random.default_rng(29)
    A = np.zeros((n, n))
    for i in range(n):
        for j in range(max(0, i - kl), min(n, i + ku + 1)):
            A[i, j] = 0.0 if (i == j and i % 3 == 1) else rng.standard_normal()
    assert abs(np.linalg.det(A)) > 1e-6
    N = ck.STACK_ROWS + n
    b = rng.standard_normal(N)
    AB = ck.band_storage(kl, ku, N)
    AB[:] = 0.0
    AB[n:, kl] = 1.0
    for i in range(n):
        for j in range(max(0, i - kl), min(n, i + ku + 1)):
            AB[i, kl + j - i] = A[i, j]
    block = AB[:n].copy()
    x_block = b[:n].copy()
    assert ck.band_solve(block, x_block, kl)
    x = b.copy()
    assert ck.band_solve(AB, x, kl)
    assert np.array_equal(x_block, _dense_partial_pivoting(A, b[:n]))
    assert np.array_equal(x[:n], x_block) and np.array_equal(x[n:], b[n:])


@needs_numba
def test_unowned_views_share_the_arrays_memory():
    """compiled_kernels._unowned gives views of the very arrays passed in (a write through a view is
    a write to the array), of the same shapes and dtypes."""
    from numba import njit
    ck = compiled._k

    @njit
    def write_through(arrays, value):
        views = ck._unowned(arrays)
        views[0][1] = value
        views[1][1, 0] = 7
        return views[0].shape[0], views[1].shape[1]

    a, b = np.zeros(3), np.zeros((2, 2), dtype=np.int64)
    assert write_through((a, b), 2.5) == (3, 2)
    assert a[1] == 2.5 and b[1, 0] == 7


@needs_numba
@pytest.mark.parametrize("method", ["DOP853", "RK4"])
def test_kernels_leave_the_reference_counts_of_the_scenes_arrays_as_they_were(method):
    """The kernels take the scene's arrays P and their scratch as views numba does not
    reference-count (compiled_kernels._unowned). A view that took a reference and never gave it
    back would keep P's arrays alive for ever; one that gave back a reference it never took would
    free them under the caller. Numba's hold on an array passed from Python is a reference to the
    Python object, so either would show in sys.getrefcount: whole runs, stepper steps (which take
    the scratch the stepper keeps) and outputs must leave every count as it was, and repeat their
    results bit for bit."""
    import sys

    model = inerter.load(PAPER[1], **{"experiment.method": method})
    kernel = compiled._kernel_for(model.mechanism)

    def run():
        result = model.simulate(stop_time=0.5, output_interval=0.01, metrics=False, path="compiled")
        stepper = model.stepper(path="compiled")
        assert stepper.path == "compiled"
        for k in range(1, 11):
            stepper.step(0.05 * k)
        return result["C.r[2]"], np.array(list(stepper.outputs().values()))

    first = run()
    counts = [sys.getrefcount(a) for a in kernel.params]
    for _ in range(3):
        again = run()
        np.testing.assert_array_equal(again[0], first[0])
        np.testing.assert_array_equal(again[1], first[1])
    assert [sys.getrefcount(a) for a in kernel.params] == counts


#: Kernel accelerations against the oracle's, relative to the largest |q̈|, |λ| at the state (as in
#: test_engine_vs_oracle.py: round-off of different formulas for the same Eq. 33).
TOL_ACC = 1e-12


def _against_oracle(model, kernel, states):
    """Kernel.accelerations (q̈ and λ) at `states` against the oracle mechanism's (TOL_ACC)."""
    oracle = model.oracle().mechanism
    for t, q, v, inputs, alpha in states:
        ref = np.concatenate(oracle.accelerations(t, q, v, inputs, alpha))
        got = np.concatenate(kernel.accelerations(t, q, v, inputs, alpha))
        assert np.max(np.abs(got - ref)) <= TOL_ACC * np.max(np.abs(ref)), (t, alpha)


@needs_numba
def test_gravity_and_step_force_and_chain(tmp_path):
    """Terms the shipped scenes lack, against the oracle (which derives the translational elements
    and the rotational springs and dampers): gravity in 2D, constant/step forces, dampers,
    rotational dampers between bodies, a long chain (band solve after reordering)."""
    import sys
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from chain_scene import write_chain
    finally:
        sys.path.pop(0)
    for links, gravity in ((3, True), (12, False)):
        path = write_chain(tmp_path / f"chain{links}.toml", links, gravity=gravity, extra_forces=True)
        model = inerter.load(path)
        mech = model.mechanism
        kernel = compiled.compile_mechanism(mech)
        if links == 12:
            kl, ku, N = kernel.band
            assert kl + ku < N // 2
        assert {e.kind for e in mech.elements} >= {"rotational_spring", "rotational_damper", "damper"}
        rng = np.random.default_rng(links)
        _against_oracle(model, kernel, _random_states(mech, rng, 6))


GROUND_MOTIONS = {
    "sine": "{ amplitude = [1.5, -0.8], frequency = 1.7, scale = 0.9 }",
    "record": '{ file = "ground.csv", scale = 2.0 }',
    "input": "{ input = true, scale = 1.5 }",
}


def _two_bar_on_moving_ground(tmp_path, kind):
    """The paper's two-bar scene with its ground moved: a sine, a short CSV record (zero after it
    ends) or FMU inputs ground.a[i]."""
    text = PAPER[1].read_text().replace("[effects]\n", f"[effects]\nground_acceleration = {GROUND_MOTIONS[kind]}\n", 1)
    (tmp_path / "ground.csv").write_text("# t, a_x, a_y\n0,0,0\n0.05,1.0,-0.5\n0.12,-0.7,0.4\n0.2,0.3,0.9\n0.31,0,0\n")
    path = tmp_path / f"two_bar_ground_{kind}.toml"
    path.write_text(text)
    return inerter.load(path)


def test_a_records_samples_are_kinks_and_its_ends_jumps_where_it_is_not_zero(tmp_path):
    """A linearly interpolated record is continuous at its samples (Mechanism.kinks); outside it the
    motion is zero, so an end where its value is not zero is a jump (Mechanism.discontinuities),
    and an end where it is zero a kink. A sine has neither."""
    ends_at_zero = _two_bar_on_moving_ground(tmp_path, "record").mechanism
    assert ends_at_zero.kinks == [0.05, 0.12, 0.2, 0.31] and ends_at_zero.discontinuities == []
    (tmp_path / "ground.csv").write_text("0.1,1.0,0\n0.2,0.5,0.5\n0.3,0,-0.2\n")
    late = inerter.load(tmp_path / "two_bar_ground_record.toml").mechanism
    assert late.kinks == [0.2] and late.discontinuities == [0.1, 0.3]
    braced = inerter.load(ROOT / "scenarios" / "braced_frame_3d.toml").mechanism
    assert braced.discontinuities == [15.0] and len(braced.kinks) == 1499
    sine = _two_bar_on_moving_ground(tmp_path, "sine").mechanism
    assert sine.kinks == [] and sine.discontinuities == []


@needs_numba
@pytest.mark.parametrize("kind", sorted(GROUND_MOTIONS))
def test_ground_motion_on_the_compiled_path(tmp_path, kind):
    """Ground motion (−m a_g on every body, coordinates relative to the ground) in the kernels,
    against the oracle: Eq. (33) to 1e-12 relative at random states and at the record's samples
    and between them; a whole compiled DOP853 run at rtol 1e-12, atol 1e-14 (ending a step on each
    of the record's samples) within 2e-10 of the oracle's run at the same tolerances, in every state
    component (m, rad, m/s, rad/s; the bound derived in test_engine_vs_oracle.py, TOL_RUN)."""
    model = _two_bar_on_moving_ground(tmp_path, kind)
    mech = model.mechanism
    assert mech.ground_motion is not None and not compiled.unsupported(mech)
    kernel = compiled.compile_mechanism(mech)
    rng = np.random.default_rng(11)
    states = list(_random_states(mech, rng, 6))
    states += [(t, mech.q0, mech.v0, states[0][3], 0.0) for t in (0.0, 0.05, 0.08, 0.2, 0.31, 0.4)]
    _against_oracle(model, kernel, states)
    inputs = np.array([0.4, -0.3, 2.0, -1.0]) if kind == "input" else None
    if inputs is not None:
        assert mech.input_names[-2:] == ["ground.a[1]", "ground.a[2]"]
    s = model.settings(method="DOP853", stop_time=0.5, rtol=1e-12, atol=1e-14)
    a = compiled.integrate_compiled(mech, s, inputs)
    b = integrate(model.oracle().mechanism, s, inputs)
    assert a.extra["path"] == "compiled" and a.status == b.status == "ok"
    assert np.max(np.abs(a.states - b.states)) <= 2e-10


@needs_numba
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
def test_compiled_integrator_takes_scipys_steps(method):
    """Same error control, step-size rule and dense output as scipy: the same step count as scipy's
    integrator on the oracle's right-hand side (equal to round-off), and the samples agree far
    below the tolerance (1e-8 at rtol 1e-8)."""
    model = inerter.load(PAPER[1])
    s = model.settings(method=method, stop_time=2.0, rtol=1e-8, atol=1e-10)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(model.oracle().mechanism, s)
    assert a.status == "ok" and a.steps == b.steps
    assert a.states.shape == b.states.shape
    assert np.max(np.abs(a.states - b.states)) < 1e-8


@needs_numba
def test_compiled_rk4_matches_the_oracles_rk4():
    """Reference: the numpy RK4 loop on the oracle's right-hand side (element forces derived from
    L(q) on Jets): the same steps and evaluations, and states within 1e-11 (m, rad, m/s, rad/s),
    the bound held against the numpy path before: the same fixed steps on right-hand sides equal to
    round-off."""
    model = inerter.load(PAPER[1])
    s = model.settings(method="RK4", stop_time=1.0, step=2e-3)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(model.oracle().mechanism, s)
    assert a.steps == b.steps and a.evaluations == b.evaluations
    assert np.max(np.abs(a.states - b.states)) < 1e-11


@needs_numba
def test_scipy_methods_and_projection_on_compiled_rhs():
    """Radau, and DOP853 with the projection treatment, run scipy's integrators on the compiled
    right-hand side (and Mechanism.project): the path says so, and the states agree with the
    oracle's run with the same method and settings within 1e-9 (m, m/s: the same algorithm on
    right-hand sides equal to round-off takes the same steps, far below the tolerance)."""
    model = inerter.load(PAPER[0])
    oracle = model.oracle().mechanism
    s = model.settings(method="Radau", stop_time=0.5, rtol=1e-8, atol=1e-10)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(oracle, s)
    assert a.extra["path"] == "scipy integrator, compiled right-hand side"
    assert a.status == "ok" and np.max(np.abs(a.states - b.states)) < 1e-9
    s = model.settings(method="DOP853", constraint="projection", stop_time=0.2, rtol=1e-9, atol=1e-11)
    a = compiled.integrate_compiled(model.mechanism, s)
    b = integrate(oracle, s)
    assert a.extra["path"] == "scipy integrator, compiled right-hand side"
    assert a.status == "ok" and np.max(np.abs(a.states - b.states)) < 1e-9


@needs_numba
def test_failure_is_reported_not_raised():
    model = inerter.load(PAPER[1])
    settings = dataclasses.replace(model.settings(stop_time=5.0, rtol=1e-10, atol=1e-12), max_steps=10)
    run = compiled.integrate_compiled(model.mechanism, settings)
    assert run.status == "failed" and "max_steps" in run.message
    assert 1 <= len(run.time) < 501


@needs_numba
def test_bench_writes_table_csv_and_png(tmp_path):
    from inerter.studies.bench import main_bench
    code = main_bench([str(PAPER[0]), "--out", str(tmp_path), "--stop-time", "0.5", "--paths", "compiled",
                       "--methods", "DOP853,RK4", "--quick"])
    assert code == 0
    for ext in ("md", "csv", "png"):
        assert (tmp_path / f"work_precision.{ext}").stat().st_size > 0
    assert "compiled DOP853" in (tmp_path / "work_precision.md").read_text()


def test_bench_measures_the_fmu_path_against_the_oracle(tmp_path):
    """`inerter bench --paths fmu`: whole fmpy runs at 10 ms and 2 ms communication steps, their error
    against the oracle (rtol 1e-12) on every point. At rtol 1e-11 DOP853 restarted at every
    communication point is within 1e-9 m of the oracle over 0.5 s."""
    pytest.importorskip("fmpy")
    import csv

    from inerter.studies.bench import main_bench
    code = main_bench([str(PAPER[0]), "--out", str(tmp_path), "--stop-time", "0.5", "--paths", "fmu",
                       "--methods", "DOP853", "--quick"])
    assert code == 0
    with open(tmp_path / "work_precision.csv") as fh:
        rows = [r for r in csv.DictReader(fh)]
    for label in ("FMU DOP853, 10 ms step", "FMU DOP853, 2 ms step"):
        mine = [r for r in rows if r["series"] == label]
        assert mine and all(r["status"] == "ok" for r in mine), label
        tight = [float(r["error_m"]) for r in mine if float(r["setting"]) == 1e-11]
        assert tight and tight[0] <= 1e-9, (label, tight)


# ----------------------------------------------------------------------------------------------
# Outputs, co-simulation stepping and the kernels' on-disk cache
# ----------------------------------------------------------------------------------------------
def _step_both(model, stop, step, inputs=None):
    """The compiled stepper and the oracle's (scipy's integrator on the oracle's right-hand side),
    stepped over the same communication points with the same inputs."""
    runs = {}
    for path in ("compiled", "oracle"):
        st = model.stepper(path="compiled") if path == "compiled" else model.oracle().stepper()
        assert st.path == ("compiled" if path == "compiled" else "numpy")
        ys, outs = [], []
        for k in range(1, int(round(stop / step)) + 1):
            for name, value in (inputs or {}).items():
                st.set_input(name, value(k * step))
            st.step(k * step)
            ys.append(st.y.copy())
            outs.append(list(st.outputs().values()))
        runs[path] = (np.array(ys), np.array(outs), st.steps)
    return runs


@needs_numba
@pytest.mark.parametrize("path", [PAPER[1], ROOT / "scenarios" / "two_bar_2d_pd.toml"], ids=lambda p: p.stem)
def test_where_inputs_change_the_compiled_stepper_restarts_as_the_oracles_stepper(path):
    """An input that changes at every communication point: the compiled stepper restarts its DOP853
    loop there with the step size the error control proposed, as the numpy stepper restarts scipy's
    DOP853. Reference: the numpy stepper on the oracle (element forces derived from L(q)). Same
    steps, so the states agree to round-off carried over 100 restarts: bound 1e-10 (m, rad, m/s)
    at the scene's tolerance rtol 1e-10; outputs to 1e-9 relative (as against the numpy path)."""
    model = inerter.load(path)
    inputs = {name: (lambda t: 5.0 * np.sin(7.0 * t)) for name in model.mechanism.input_names}
    assert inputs
    runs = _step_both(model, 1.0, 0.01, inputs)
    (ya, oa, sa), (yb, ob, sb) = runs["compiled"], runs["oracle"]
    assert sa == sb
    assert np.max(np.abs(ya - yb)) <= 1e-10
    assert np.all(np.abs(oa - ob) <= 1e-9 * (1.0 + np.abs(ob)))


@needs_numba
@pytest.mark.parametrize("method", ["DOP853", "RK45"])
@pytest.mark.parametrize("path", PAPER + [ROOT / "scenarios" / "two_bar_2d_pd.toml",
                                  ROOT / "scenarios" / "double_pendulum_3d.toml"], ids=lambda p: p.stem)
def test_with_inputs_held_the_compiled_stepper_is_the_whole_run(path, method):
    """Inputs that do not change: the compiled stepper keeps one integration running across the
    communication points, its steps clipped to the stop time only, and takes the state at each
    point from the dense output, as the whole run samples its grid: the same steps and, at every
    communication point, the whole run's state and outputs bit for bit. Without a stop time its
    steps are not clipped at all, and it takes no more steps than with one (the test of the numpy
    stepper, which runs on in the same way, is in test_stepper.py)."""
    model = inerter.load(path)
    stop, step = 2.0, 0.01
    whole = model.simulate(stop_time=stop, output_interval=step, method=method, metrics=False, path="compiled")
    assert whole.run.extra["path"] == "compiled"
    st = model.stepper(method=method, path="compiled", stop_time=stop)
    unbounded = model.stepper(method=method, path="compiled")
    assert st.outputs() == {name: float(whole[name][0]) for name in model.signals.names}
    for k in range(1, len(whole.time)):
        st.step(whole.time[k])
        unbounded.step(whole.time[k])
        assert np.array_equal(st.y, whole.run.states[k])
        assert st.outputs() == {name: float(whole[name][k]) for name in model.signals.names}
    assert st.steps == whole.run.steps
    assert unbounded.steps <= whole.run.steps            # the same steps, its last one not clipped


@needs_numba
@pytest.mark.parametrize("method", ["DOP853", "RK45", "RK4"])
@pytest.mark.parametrize("path, stop", [(ROOT / "scenarios" / "hard" / "step_force_1dof_2d.toml", 2.0),
                                        (ROOT / "scenarios" / "braced_frame_3d.toml", 0.3)],
                         ids=["step force", "ground record"])
def test_at_jumps_and_kinks_the_compiled_path_steps_as_the_oracle(path, stop, method):
    """A step force's switch (a jump) ends a segment: the compiled whole run and the compiled
    stepper restart there with a fresh first step, the forces evaluated up to the switch with their
    values over the segment. A ground record's samples (kinks) end steps, through which the
    integration runs on with the step size proposed before the clip (RK4: its fixed step). Both as
    the numpy path. Reference: the numpy path's integrators on the oracle's right-hand side
    (element forces derived from L(q)), whole run and stepper: the same number of steps, states
    within 1e-12 (round-off of right-hand sides computed by different formulas; the bound held
    against the numpy path before). The compiled stepper with
    inputs held gives the compiled whole run's states to round-off (1e-15 relative; RK4 restarts at
    every communication point, as the numpy stepper's, so it is compared with that one only)."""
    model = inerter.load(path)
    assert model.mechanism.discontinuities or model.mechanism.kinks
    s = model.settings(method=method, stop_time=stop)
    whole = compiled.integrate_compiled(model.mechanism, s)
    oracle = model.oracle()
    ref = integrate(oracle.mechanism, s)
    assert whole.extra["path"] == "compiled" and whole.status == ref.status == "ok"
    assert whole.steps == ref.steps
    assert np.max(np.abs(whole.states - ref.states)) <= 1e-12
    st = model.stepper(method=method, path="compiled", stop_time=stop)
    oracle_st = oracle.stepper(method=method, stop_time=stop)
    assert st.path == "compiled"
    for k in range(1, len(whole.time)):
        st.step(whole.time[k])
        oracle_st.step(whole.time[k])
        assert np.max(np.abs(st.y - oracle_st.y)) <= 1e-12
        if method != "RK4":
            assert np.all(np.abs(st.y - whole.states[k]) <= 1e-15 * (1.0 + np.abs(whole.states[k])))
    assert st.steps == oracle_st.steps
    if method != "RK4":
        assert st.steps == whole.steps


def _restarting(model):
    """`model` with its ground record's samples among the jumps: the integrators restart at every
    sample (as they did before the samples were kinks)."""
    mech = model.mechanism
    mech.discontinuities = sorted(set(mech.discontinuities) | set(mech.kinks))
    mech.kinks = []
    return model


@needs_numba
def test_a_ground_record_is_run_through_its_samples_to_the_oracles_results():
    """A ground record's samples are kinks of the right-hand side (its slope jumps, its value does
    not): the compiled DOP853 loop ends a step on each and runs on through it, starting once. At
    rtol 1e-10, atol 1e-12 its states (m, rad, m/s, rad/s) at every sample are within 1e-10 ·
    max(1, max |y|) of the oracle's run restarting at every sample at rtol 1e-12, atol 1e-14
    (measured: 1.4e-12, as the restarting engine's run). Evaluations, with every step's dense
    output kept: 15 per accepted DOP853 step (11 stages, the end point's derivative, 3 for the
    dense output), 12 per rejected trial and 2 per start (the first derivative and the first step's
    choice): the run through the samples starts once, the restarting one at t = 0 and at each of
    the 99 samples (measured: 127 steps, 3 rejected, 1943 evaluations against 117 steps, 13
    rejected, 2111 evaluations)."""
    path = ROOT / "scenarios" / "braced_frame_3d.toml"
    stop = 1.0
    model = inerter.load(path)
    samples = sum(1 for t in model.mechanism.kinks if t < stop)
    assert samples == 99 and not [t for t in model.mechanism.discontinuities if t < stop]
    s = model.settings(method="DOP853", stop_time=stop, rtol=1e-10, atol=1e-12)
    through = compiled.integrate_compiled(model.mechanism, s, dense=True)
    restarts = compiled.integrate_compiled(_restarting(inerter.load(path)).mechanism, s, dense=True)
    tight = model.settings(method="DOP853", stop_time=stop, rtol=1e-12, atol=1e-14)
    oracle = integrate(_restarting(inerter.load(path).oracle()).mechanism, tight)
    assert through.status == restarts.status == oracle.status == "ok"
    bound = 1e-10 * max(1.0, float(np.max(np.abs(oracle.states))))
    assert np.max(np.abs(through.states - oracle.states)) <= bound
    assert np.max(np.abs(restarts.states - oracle.states)) <= bound
    assert (through.evaluations - 15 * through.steps - 2) % 12 == 0
    assert (restarts.evaluations - 15 * restarts.steps - 2 * (samples + 1)) % 12 == 0
    assert through.evaluations - 15 * through.steps < 2 * samples
    assert through.evaluations < restarts.evaluations


@needs_numba
@pytest.mark.parametrize("change_input", [False, True], ids=["running on", "restarted by an input"])
def test_compiled_stepper_rolls_back_bit_for_bit(change_input):
    """get_state holds the running integration too: the steps repeated after set_state give the same
    states and outputs, bit for bit, whether the integration ran on or restarted."""
    model = inerter.load(PAPER[1])
    st = model.stepper(path="compiled", stop_time=1.0)
    for k in range(1, 6):
        st.step(0.01 * k)
    state = st.get_state()

    def two_steps():
        if change_input:
            st.set_input("C.f[2]", 3.0)
        st.step(0.06)
        st.step(0.07)
        return st.y.copy(), st.outputs(), st.steps

    first = two_steps()
    st.set_state(state)
    again = two_steps()
    assert np.array_equal(again[0], first[0]) and again[1:] == first[1:]


def test_the_compiled_stepper_falls_back_where_the_loop_cannot_go():
    """Implicit methods and projection: scipy's stepper on the kernels' right-hand side; a missing
    numba: the numpy stepper. 3D scenes with quaternions or Z-X-Z Euler angles, step forces and
    ground records run the compiled loop."""
    two_bar = inerter.load(PAPER[1])
    for kw in ({"method": "Radau"}, {"method": "BDF"}):
        implicit = two_bar.stepper(path="compiled", **kw)
        assert implicit.path == ("compiled" if compiled.AVAILABLE else "numpy")
        assert not hasattr(implicit, "native_table")                     # scipy's stepper, not the loop
        if compiled.AVAILABLE:
            assert type(implicit.mech).__name__ == "_KernelMechanism"      # on the kernels' right-hand side
    as_3d = ROOT / "scenarios" / "two_bar_2d_as_3d.toml"
    assert inerter.load(as_3d).stepper(path="compiled").path == ("compiled" if compiled.AVAILABLE else "numpy")
    euler = inerter.load(ROOT / "scenarios" / "gimbal_lock_3d.toml", **{"scene.orientation": "euler_zxz"})
    assert euler.stepper(path="compiled").path == ("compiled" if compiled.AVAILABLE else "numpy")
    for scene in ("braced_frame_3d.toml", "hard/step_force_1dof_2d.toml"):
        assert inerter.load(ROOT / "scenarios" / scene).stepper(path="compiled").path == \
            ("compiled" if compiled.AVAILABLE else "numpy")
    assert two_bar.stepper(path="compiled").path == ("compiled" if compiled.AVAILABLE else "numpy")
    with pytest.raises(ValueError, match="expected 'numpy' or 'compiled'"):
        two_bar.stepper(path="fast")


# One small kernel of the module (band_storage) stands for all: numba caches each function of the
# kernels' copy the same way, by the copy's file. Compiling `accelerations` in a fresh cache, as this
# probe did before, took 70 s of the suite to show the same (AMD EPYC host, 2026-11-28).
KERNEL_CACHE_PROBE = """
import json
from inerter.engine import compiled
import inerter
compiled._k.band_storage(1, 1, 4)
stats = compiled._k.band_storage.stats
print(json.dumps({"file": compiled._k.__file__, "package": inerter.__file__,
                  "hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values())}))
"""


@needs_numba
def test_kernels_compiled_once_are_found_from_another_copy_of_the_package(tmp_path):
    """An FMU importer extracts the FMU, and the package inside it, to a new folder each run; the
    kernels are loaded from a copy named by their source's hash, so numba's on-disk cache made by
    one copy of the package is found by the next (no compilation: cache hits, no misses)."""
    import json
    import shutil
    import subprocess
    import sys
    cache = tmp_path / "cache"
    results = []
    for copy in ("first", "second"):
        shutil.copytree(ROOT / "inerter", tmp_path / copy / "inerter",
                        ignore=shutil.ignore_patterns("__pycache__"))
        env = dict(os.environ, INERTER_CACHE_DIR=str(cache), PYTHONPATH=str(tmp_path / copy))
        proc = subprocess.run([sys.executable, "-c", KERNEL_CACHE_PROBE], env=env,
                              capture_output=True, text=True, timeout=600, cwd=tmp_path)
        assert proc.returncode == 0, proc.stderr[-3000:]
        results.append(json.loads(proc.stdout.strip().splitlines()[-1]))
    first, second = results
    assert first["package"].startswith(str(tmp_path / "first")) and second["package"].startswith(str(tmp_path / "second"))
    assert first["file"] == second["file"] and first["file"].startswith(str(cache))
    assert first["misses"] >= 1                      # compiled by the first copy ...
    assert second["hits"] >= 1 and second["misses"] == 0   # ... and only loaded by the second


@needs_numba
def test_the_compiled_stepper_runs_on_past_the_stop_time_it_was_given():
    """An importer that steps past the stop time it announced: the bound is dropped and the
    integration runs on. Up to the stop time the steps are the whole run's; after it, the state
    agrees with a run to the later time within its tolerance (scene rtol 1e-10: bound 1e-9)."""
    model = inerter.load(PAPER[1])
    st = model.stepper(path="compiled", stop_time=0.05)
    for k in range(1, 11):
        st.step(0.01 * k)
    assert st.t_bound == np.inf and st.time == 0.1
    ref = model.simulate(stop_time=0.1, output_interval=0.01, metrics=False, path="compiled")
    assert np.max(np.abs(st.y - ref.run.states[-1])) <= 1e-9


@needs_numba
def test_the_step_budget_bounds_each_call_of_the_running_integration():
    """experiment.max_steps bounds one call of the compiled loop: the whole run, or one
    communication step. An FMU that runs on across communication points gets the budget afresh at
    every doStep (a co-simulation hours long must not run out of it), as when it restarted."""
    model = inerter.load(PAPER[1], **{"experiment.max_steps": 50})
    whole = model.simulate(stop_time=2.0, output_interval=0.01, metrics=False, path="compiled")
    assert whole.status == "failed" and "max_steps" in whole.message
    st = model.stepper(path="compiled", stop_time=2.0)
    for k in range(1, 201):
        st.step(0.01 * k)
    assert st.steps > 50 and st.time == 2.0
