"""The FMU's native doStep (inerter/fmu/native.py, fmu_src/status_shim.c).

On the compiled path the FMU's binary takes co-simulation steps in compiled code without entering
Python, and hands everything else to the slave after it took those steps over. It must change
nothing but the time a step costs: every output, status and message is compared with an instance
of the same FMU whose native steps are off (INERTER_FMU_NATIVE=0, the slave takes every step),
exactly, through importer call sequences that cross the native path at each of its hand-overs
(outputs read, a parameter read, FMU state got and set, an input set, a step at the wrong time,
past the stop time, a step that fails).
"""
from __future__ import annotations

import math

import pytest

from test_fmu import (FMI_DISCARD, FMI_ERROR, INPUT, INPUT_SCENE, SCENE_PARAMS, FMICallException,  # noqa: F401
                      fmus, instance, needs_shim, unzipped)

import inerter  # noqa: E402
from inerter.fmu import native as fmu_native  # noqa: E402
from inerter.engine import compiled

pytestmark = pytest.mark.skipif(not compiled.AVAILABLE, reason="numba is missing: no native steps")


def native_scene(scene):
    """Skip a scene whose steps the compiled path does not take (3D, ...)."""
    if inerter.load(scene).stepper(path="compiled").path != "compiled":
        pytest.skip("the compiled stepper does not take this scene: no native steps")


@pytest.fixture
def pair(instance, monkeypatch, needs_shim):
    """pair(fmu) -> (native instance, instance whose native steps are off)."""
    def make(fmu):
        made = []
        for switch in ("1", "0"):
            monkeypatch.setenv(fmu_native.SWITCH, switch)
            made.append(instance(fmu, f"native-{switch}"))
        monkeypatch.delenv(fmu_native.SWITCH)
        return made
    return make


class Transcript:
    """What an instance gives back to a sequence of calls: values, statuses (fmpy raises on a
    status worse than warning) and the messages logged, in order."""

    def __init__(self, inst):
        self.inst = inst
        self.entries = []

    def call(self, label, fn, *args):
        try:
            value = fn(*args)
            status = 0
        except FMICallException as exc:
            value, status = None, exc.status
        self.entries.append((label, status, value))
        return value

    def step(self, t, h):
        return self.call(f"doStep({t!r}, {h!r})", self.inst.fmu.doStep, t, h)

    def outputs(self):
        return self.call("outputs", self.inst.get, self.inst.outputs)

    def messages(self):
        return [(s, m) for s, m in self.inst.messages if not m.startswith(("initialised", "terminated"))]


def native_steps(inst) -> int:
    """Communication steps the binary took natively, from the slave's message at terminate."""
    inst.fmu.terminate()
    [line] = [m for _, m in inst.messages if m.startswith("terminated")]
    return int(line.split(", ")[1].split()[0])


def replay(inst, scene_has_input: bool, stop_time: float, solver: str | None = None):
    """The call sequence crossing every hand-over of the native path."""
    tr = Transcript(inst)
    inst.fmu.setupExperiment(startTime=0.0, stopTime=stop_time)
    inst.fmu.enterInitializationMode()
    if solver is not None:
        inst.fmu.setInteger([inst.vr["solver"]], [inst.item("solver", solver)])
    inst.fmu.exitInitializationMode()
    h, t = 0.01, 0.0
    parameter = next(v.name for v in inst.md.modelVariables if v.causality == "parameter"
                     and v.type == "Real")
    for k in range(12):                                  # native from the first step on
        tr.step(t, h)
        t += h
        tr.outputs()
    # Every variable is served between native steps; each kind as the slave gives it.
    tr.call("parameter", inst.get, [parameter])
    tr.call("solver", inst.fmu.getInteger, [inst.vr["solver"]])
    tr.call("compiled", inst.fmu.getBoolean, [inst.vr["compiled"]])
    tr.call("fmi_status", inst.fmu.getInteger, [inst.vr["fmi_status"]])
    tr.call("mixed", inst.get, [inst.outputs[0], parameter, inst.outputs[-1]])
    tr.step(t, h)
    t += h
    tr.call("all reals", inst.fmu.getReal, [v.valueReference for v in inst.md.modelVariables
                                            if v.type == "Real"])
    tr.call("unknown", inst.fmu.getReal, [10_000])       # the slave logs it: fmi2Error
    tr.outputs()
    state = inst.fmu.getFMUstate()
    first = [(tr.step(t + n * h, h), tr.outputs()) for n in range(4)]
    inst.fmu.setFMUstate(state)
    again = [(tr.step(t + n * h, h), tr.outputs()) for n in range(4)]
    assert again == first, "a rolled-back step did not repeat"
    inst.fmu.freeFMUstate(state)
    t += 4 * h
    tr.step(t + 0.5, h)                                  # not the current point: refused
    tr.step(t, -h)                                       # a step size not > 0: refused
    if scene_has_input:
        tr.call("set input", inst.set, INPUT, 3.0)       # the integration restarts
        for _ in range(3):
            tr.step(t, h)
            t += h
            tr.outputs()
    while t < stop_time + 3 * h:                          # on past the stop time
        tr.step(t, h)
        t += h
    tr.outputs()
    return tr


@pytest.mark.parametrize("scene", SCENE_PARAMS)
def test_native_steps_give_what_the_slave_gives_bit_for_bit(fmus, scene, pair):
    native_scene(scene)
    native, slave = pair(fmus[scene])
    has_input = scene == INPUT_SCENE
    a = replay(native, has_input, stop_time=0.3)
    b = replay(slave, has_input, stop_time=0.3)
    assert a.entries == b.entries
    assert a.messages() == b.messages()
    # fmi2Error: the unknown value reference, the two refused steps and those past the stop time
    refused = [label for label, s, _ in a.entries if s == FMI_ERROR]
    assert refused[0] == "unknown" and len(refused) == 6 and FMI_DISCARD not in [s for _, s, _ in a.entries], refused
    # The native instance took most steps natively; the other none (and says why).
    assert native_steps(native) >= 30
    assert native_steps(slave) == 0 and f"{fmu_native.SWITCH}=0" in slave.logged()


@pytest.mark.parametrize("solver", ["RK45", "RK4"])
def test_native_steps_of_each_compiled_method_give_what_the_slave_gives(fmus, pair, solver):
    """The scene's own method (DOP853) is above; RK45 runs on as DOP853 does, RK4 restarts at every
    communication point (the native step too)."""
    native_scene(INPUT_SCENE)
    native, slave = pair(fmus[INPUT_SCENE])
    a = replay(native, True, stop_time=0.3, solver=solver)
    b = replay(slave, True, stop_time=0.3, solver=solver)
    assert a.entries == b.entries
    assert a.messages() == b.messages()
    assert native_steps(native) >= 30 and native_steps(slave) == 0


STEP_FORCE = INPUT_SCENE.parent / "hard" / "step_force_1dof_2d.toml"
BRACED_FRAME = INPUT_SCENE.parent / "braced_frame_3d.toml"


@pytest.fixture(scope="module")
def step_forces_scene(tmp_path_factory):
    """scenarios/hard/step_force_1dof_2d.toml with three step forces, whose switches fall inside the
    communication steps of :func:`replay` (0.105 s; 0.155 s, in the steps that are rolled back) and on
    one of its points (0.2 s)."""
    text = STEP_FORCE.read_text(encoding="utf-8")
    text = text.replace('name = "step_force_1dof_2d"', 'name = "step_forces_rk4_2d"')
    text = text.replace('ts = { value = 0.5,', 'ts = { value = 0.105,')
    assert "step_forces_rk4_2d" in text and "0.105" in text
    for name, time in (("later", 0.155), ("on_point", 0.2)):
        text += (f'\n[forces.{name}]\npoint = "P"\ndirection = [1, 0]\nfunction = "step"\n'
                 f'value = "F"\ntime = {time}\ninitial = 0\n')
    path = tmp_path_factory.mktemp("scene") / "step_forces_rk4_2d.toml"
    path.write_text(text, encoding="utf-8")
    assert inerter.load(path).mechanism.discontinuities == [0.105, 0.155, 0.2]
    return path


@pytest.mark.parametrize("which", ["step_forces", "braced_frame_3d"])
def test_native_rk4_steps_through_discontinuities_give_what_the_slave_gives(fmus, pair, step_forces_scene,
                                                                            which):
    """RK4 restarts at each jump of the right-hand side inside a communication step (step forces'
    switches) and ends a step on each kink (the braced frame's ground record, sampled every 10 ms,
    on every point), in the native step as in the slave's: the same results bit for bit, the steps
    taken natively."""
    scene = step_forces_scene if which == "step_forces" else BRACED_FRAME
    native_scene(scene)
    native, slave = pair(fmus[scene])
    a = replay(native, False, stop_time=0.3, solver="RK4")
    b = replay(slave, False, stop_time=0.3, solver="RK4")
    assert a.entries == b.entries
    assert a.messages() == b.messages()
    assert native_steps(native) >= 30 and native_steps(slave) == 0


TERMINALS_MEET = INPUT_SCENE.parent / "hard" / "terminals_meet_2d.toml"


def _until_a_step_fails_then_again(inst, most, strings=None):
    """The transcript of `inst` initialised (with `strings`) and stepped by 10 ms, its outputs read
    after each step, until a step fails (at most `most` steps), then that step asked for again."""
    inst.initialise(strings=strings)
    tr = Transcript(inst)
    h, t = 0.01, 0.0
    for _ in range(most):
        tr.step(t, h)
        tr.outputs()
        if tr.entries[-2][1]:
            break
        t += h
    tr.step(t, h)                                    # the same step fails again
    tr.outputs()
    return tr


def _fail_alike(native, slave, most, strings=None):
    """Both instances stepped until a step fails, then that step again: the same transcript and
    messages, the same step failing twice. Returns (the first instance's transcript, the failing
    step's t, its status)."""
    a, b = (_until_a_step_fails_then_again(inst, most, strings) for inst in (native, slave))
    assert a.entries == b.entries
    assert a.messages() == b.messages()
    failed = [(label, status) for label, status, _ in a.entries if status]
    assert len(failed) == 2 and failed[0] == failed[1], failed
    return a, float(failed[0][0][len("doStep("):].split(",")[0]), failed[0][1]


def test_a_step_that_fails_natively_is_taken_and_reported_by_the_slave(fmus, pair):
    """A mass driven into the point its elements are attached to (scenarios/hard): the native step
    that reaches it fails half-way and declines; the slave restores the integration from the
    backup and takes the step, which fails the same way: the same fmi2Discard, message and last
    good state as without native steps, and again when the importer retries it."""
    native_scene(TERMINALS_MEET)
    a, t_fail, _ = _fail_alike(*pair(fmus[TERMINALS_MEET]), 200)
    native = a.inst
    # The step that fails is the one holding the closed-form time of impact (the scene's header).
    assert t_fail <= math.pi * math.sqrt(2) / 4 < t_fail + 0.01
    assert "terminals O and P meet" in a.messages()[-1][1]
    assert native_steps(native) == 111                  # every step before the one that fails


PARALLELOGRAM = INPUT_SCENE.parents[1] / "tests" / "data" / "parallelogram_2d.toml"


@pytest.mark.parametrize("solver", [None, "RK4"])
def test_a_step_that_reaches_a_change_point_fails_as_the_slave_reports_it(fmus, pair, solver):
    """tests/data/parallelogram_2d.toml, whose four pivots lie on a line at t* = (π/2)/|θ̇0| (closed
    form, tests/test_bad_input_more.py): the communication step holding t* fails in the native
    step (kernels.loop_watch) and in the slave's alike: the same fmi2Discard, message (naming the
    joints and the change point) and last good outputs as without native steps, and again when
    the importer retries it; the steps before it are native."""
    native_scene(PARALLELOGRAM)
    t_star = (math.pi / 2) / abs(inerter.load(PARALLELOGRAM).mechanism.v0[2])
    a, t_fail, status = _fail_alike(*pair(fmus[PARALLELOGRAM]), 300, {"solver": solver} if solver else None)
    assert status == FMI_DISCARD
    assert t_fail <= t_star < t_fail + 0.01 + 1e-12
    assert "change point" in a.messages()[-1][1] and "joints a, b, c, d" in a.messages()[-1][1]
    assert native_steps(a.inst) == round(t_fail / 0.01)   # every step before the one that fails


def before_first_step(inst, case: str, solver: str | None) -> Transcript:
    """Initialise, then one of the call sequences that hand over to the slave between
    exitInitializationMode and the first step, then steps."""
    tr = Transcript(inst)
    inst.fmu.setupExperiment(startTime=0.0, stopTime=0.3)
    inst.fmu.enterInitializationMode()
    if solver is not None:
        inst.fmu.setInteger([inst.vr["solver"]], [inst.item("solver", solver)])
    inst.fmu.exitInitializationMode()
    h = 0.01
    if case == "read":                                   # the slave answers; the link stays armed
        tr.outputs()
        tr.call("solver", inst.fmu.getInteger, [inst.vr["solver"]])
    elif case == "input":                                # the slave takes the first step
        tr.call("set input", inst.set, INPUT, 3.0)
    elif case == "reset":                                # native steps, then a fresh start
        for n in range(2):
            tr.step(n * h, h)
            tr.outputs()
        inst.fmu.reset()                                 # a new slave object, a new context
        inst.fmu.setupExperiment(startTime=0.0, stopTime=0.3)
        inst.fmu.enterInitializationMode()
        if solver is not None:
            inst.fmu.setInteger([inst.vr["solver"]], [inst.item("solver", solver)])
        inst.fmu.exitInitializationMode()
    elif case == "state":                                # native steps, rolled back to t = 0
        state = inst.fmu.getFMUstate()
        first = [(tr.step(n * h, h), tr.outputs()) for n in range(2)]
        inst.fmu.setFMUstate(state)
        inst.fmu.freeFMUstate(state)
        assert [(tr.step(n * h, h), tr.outputs()) for n in range(2)] == first
    t = 2 * h if case == "state" else 0.0
    for _ in range(3):
        tr.step(t, h)
        t += h
        tr.outputs()
    return tr


@pytest.mark.parametrize("solver", [None, "RK4"])
@pytest.mark.parametrize("case, natively", [("read", 3), ("input", 2), ("state", 6), ("reset", 3)])
def test_the_first_step_is_native_and_what_comes_before_it_is_the_slaves(fmus, pair, case, natively,
                                                                          solver, monkeypatch):
    """The slave arms the link at the end of initialisation, the integration started as its first
    step would start it: the first step is native, and every call between initialisation and it
    gives what the slave gives (outputs and a parameter read at t = 0, an input set before the
    first step, the FMU state got at t = 0 and set back after native steps, a reset after native
    steps and a new initialisation: the shim links to the new slave object's context), bit for
    bit, with the scene's method (DOP853) and with RK4. The count of native steps is the slave
    object's (a reset starts it again)."""
    native_scene(INPUT_SCENE)
    native, slave = pair(fmus[INPUT_SCENE])
    monkeypatch.setenv(fmu_native.SWITCH, "1")          # as each was made: a reset reads it again
    a = before_first_step(native, case, solver)
    monkeypatch.setenv(fmu_native.SWITCH, "0")
    b = before_first_step(slave, case, solver)
    assert a.entries == b.entries
    assert a.messages() == b.messages()
    assert not any(status for _, status, _ in a.entries)
    # Native: every step but the first after an input set or the state set back (the slave's).
    assert native_steps(native) == natively and native_steps(slave) == 0


def test_outputs_and_inputs_read_between_native_steps_are_the_slaves(fmus, pair):
    """After native steps the binary serves getReal from the values the step wrote (outputs) and
    those the slave left when it armed the link (inputs)."""
    scene = INPUT_SCENE
    native_scene(scene)
    native, slave = pair(fmus[scene])
    results = []
    for inst in (native, slave):
        inst.initialise()
        t, h = 0.0, 0.01
        for _ in range(5):
            inst.fmu.doStep(t, h)
            t += h
        mixed = inst.get([inst.outputs[0], INPUT, inst.outputs[-1]])
        inst.fmu.doStep(t, h)
        results.append((mixed, inst.get(inst.outputs)))
    assert results[0] == results[1]
    assert not any(math.isnan(v) for v in results[0][1])


def test_an_rk4_step_beyond_its_limit_declined_natively_is_reported_as_the_slave_reports_it(fmus, pair,
                                                                                              tmp_path_factory):
    """scenarios/hard/stiff_1dof_2d.toml with RK4 at hω = 2.9 (9.2 ms, beyond the region: RK4's
    factor |R(2.9i)| = 1.19 per step) and 10 ms communication steps: the stability watch counts its
    steps across the native steps, and the one where the mode has grown 100 times fails in the
    native step, which declines; the slave restores the integration and the watch's counters from
    the backup (kernels.native_step, b_monitor) and takes the step again, which fails as without
    native steps: the same fmi2 status, message (the same count of steps in a row) and outputs,
    and again when the importer retries it."""
    stiff = INPUT_SCENE.parent / "hard" / "stiff_1dof_2d.toml"
    native_scene(stiff)
    h = 2.9 / math.sqrt(1.0e8 / (1.0e3 + 1.0e-3))        # the scene's ω = √(k/(m + b))
    text = stiff.read_text().replace('name = "stiff_1dof_2d"', 'name = "stiff_rk4_native_2d"')
    experiment = text.index("[experiment]")
    scene = tmp_path_factory.mktemp("rk4_native") / "stiff_rk4_native_2d.toml"
    scene.write_text(text[:experiment] + f"[experiment]\nstop_time = 3.0\nmethod = \"RK4\"\nstep = {h!r}\n")
    a, t_fail, _ = _fail_alike(*pair(fmus[scene]), 300)
    assert "beyond its stability limit" in a.messages()[-1][1], a.messages()[-1]
    assert native_steps(a.inst) == round(t_fail / 0.01)
