"""Call sequences of other importers through fmpy's low-level API: what FMI 2.0 does not allow
returns fmi2Error with its reason logged (naming the scene file and the value), and changes nothing.

The FMI 2.0 standard (co-simulation state machine; section 4.2.2 on fmi2DoStep and 2.1.6 on
fmi2SetupExperiment) allows no getter in the instantiated state, fmi2Terminate only after
initialisation, a communication step size only > 0, and "if the environment tries to compute past
stopTime the FMU has to return fmi2Status = fmi2Error". pythonfmu's binary returns fmi2OK from every
call but doStep, so these statuses come from the status shim (fmu_src/status_shim.c): each test
needs it, and runs with native steps on (the default) and off (INERTER_FMU_NATIVE=0).
"""
from __future__ import annotations

import math

import pytest

from test_fmu import (FMI_ERROR, INPUT, FMICallException, input_fmu, fmus, instance,  # noqa: F401
                      needs_shim, raises_status, unzipped)

from inerter.fmu import native as fmu_native

pytestmark = pytest.mark.usefixtures("needs_shim")
H = 0.01


@pytest.fixture(params=["native", "slave"])
def steps(request, monkeypatch):
    """Native steps on (the default) or off: the slave takes every step."""
    if request.param == "slave":
        monkeypatch.setenv(fmu_native.SWITCH, "0")
    return request.param


def test_a_getter_of_an_unknown_or_mistyped_value_reference_is_fmi2error(input_fmu, instance, steps):
    """It was fmi2OK with NaN (the error logged only): an importer took NaN for a value."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    inst.initialise()
    for t in (0.0, H):                  # before a step, and after one (native, where on)
        if t:
            inst.fmu.doStep(0.0, H)
        inst.messages.clear()
        raises_status(FMI_ERROR, inst.fmu.getReal, [999999])
        raises_status(FMI_ERROR, inst.fmu.getReal, [inst.vr["effects.centripetal"]])   # a Boolean
        raises_status(FMI_ERROR, inst.fmu.getBoolean, [inst.vr["b"]])                   # a Real
        errors = inst.errors()
        assert len(errors) == 3 and all(m.startswith(f"{scene.name}: ") for m in errors), errors
        assert "valueReference 999999 is not a Real variable" in errors[0]
        # a good getter after them is fmi2OK again
        assert inst.get(["b"]) == [10.0] and len(inst.errors()) == 3


def test_a_getter_before_initialization_mode_is_fmi2error(input_fmu, instance, steps):
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    inst.set("b", 20.0)                 # a setter is allowed there: fmi2OK, nothing logged
    assert inst.messages == []
    raises_status(FMI_ERROR, inst.fmu.getReal, [inst.vr["b"]])
    raises_status(FMI_ERROR, inst.fmu.getInteger, [inst.vr["solver"]])
    raises_status(FMI_ERROR, inst.fmu.getBoolean, [inst.vr["effects.centripetal"]])
    errors = inst.errors()
    assert len(errors) == 3 and all(m.startswith(f"{scene.name}: fmi2Get") for m in errors), errors
    assert "called before fmi2EnterInitializationMode" in errors[0]
    inst.messages.clear()
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()  # from initialization mode on, getters are allowed
    assert inst.get(["b"]) == [20.0]
    inst.fmu.exitInitializationMode()
    inst.fmu.doStep(0.0, H)
    assert inst.errors() == []


def test_a_refused_step_is_fmi2error_and_changes_nothing(input_fmu, instance, steps):
    """A step size not > 0, a step not at the current point, one ending past stopTime (it was
    taken) and one after terminate are fmi2Error (they were fmi2Discard, the status of a step the
    solver could not complete), logged with the scene file and the value, the state unchanged."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    stop = 5 * H
    inst.fmu.setupExperiment(startTime=0.0, stopTime=stop)
    inst.fmu.enterInitializationMode()
    inst.fmu.exitInitializationMode()
    inst.fmu.doStep(0.0, H)
    before = inst.get(inst.outputs)
    for t, h, reason in [(H, 0.0, "step 0.0 s) refused: the step size must be a finite number > 0"),
                         (H, -H, "the step size must be a finite number > 0"),
                         (H, math.nan, "the step size must be a finite number > 0"),
                         (2 * H, H, "a step must start where the last one ended"),
                         (H, stop, f"past stopTime = {stop!r} s of fmi2SetupExperiment")]:
        inst.messages.clear()
        raises_status(FMI_ERROR, inst.fmu.doStep, t, h)
        [message] = inst.errors()
        assert message.startswith(f"{scene.name}: doStep at t = {t!r} s") and reason in message, message
        assert inst.get(inst.outputs) == before
    inst.fmu.doStep(H, stop - H)        # to the stop time exactly: allowed
    assert inst.fmu.getRealStatus(2) == pytest.approx(stop)     # fmi2LastSuccessfulTime
    raises_status(FMI_ERROR, inst.fmu.doStep, stop, H)
    inst.fmu.terminate()
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.doStep, stop, H)
    assert "the FMU is terminated" in inst.errors()[0]


def test_without_a_stop_time_the_fmu_steps_past_the_scenes(input_fmu, instance, steps):
    """stopTimeDefined false: no final time, steps go on past the scene's experiment.stop_time."""
    inst = instance(input_fmu[1], logging=False)
    inst.initialise()                   # setupExperiment without stopTime
    inst.fmu.doStep(0.0, 70.0)          # two_bar_2d's stop_time is 60 s
    assert inst.fmu.getRealStatus(2) == pytest.approx(70.0) and inst.errors() == []


def test_terminate_outside_a_run_is_fmi2error_and_changes_nothing(input_fmu, instance, steps):
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    raises_status(FMI_ERROR, inst.fmu.terminate)              # instantiated
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()
    raises_status(FMI_ERROR, inst.fmu.terminate)              # initialization mode
    errors = inst.errors()
    assert len(errors) == 2 and all(m.startswith(f"{scene.name}: fmi2Terminate: refused in the ")
                                    for m in errors), errors
    inst.fmu.exitInitializationMode()   # the instance runs as if nothing happened
    inst.fmu.doStep(0.0, H)
    inst.fmu.terminate()                # after initialisation: allowed, once
    raises_status(FMI_ERROR, inst.fmu.terminate)
    inst.fmu.reset()
    inst.initialise()
    inst.fmu.doStep(0.0, H)


def test_a_run_after_reset_equals_a_fresh_instances(input_fmu, instance, steps):
    """fmi2Reset from any state, then a run with other parameters and inputs: the outputs of a
    fresh instance of the same FMU, exactly."""
    fmu = input_fmu[1]
    used, fresh = instance(fmu, "used", logging=False), instance(fmu, "fresh", logging=False)

    def run(inst, b, force):
        inst.initialise(reals={"b": b})
        inst.set(INPUT, force)
        rows = []
        for i in range(20):
            inst.fmu.doStep(i * H, H)
            rows.append(inst.get(inst.outputs))
        return rows
    run(used, 10.0, 0.0)
    used.fmu.reset()                    # from stepping
    used.fmu.setupExperiment(startTime=0.0)
    used.fmu.enterInitializationMode()
    used.fmu.reset()                    # from initialization mode
    assert run(used, 25.0, 1.5) == run(fresh, 25.0, 1.5)


def test_last_successful_time_is_the_fmus_time(input_fmu, instance, steps):
    """fmi2GetRealStatus(fmi2LastSuccessfulTime), which a master reads after a step (fmpy after a
    discarded one), is the time the FMU is at. pythonfmu's binary answered the end of the last
    doStep the slave was called for: NaN after native steps or before any, the end of a refused
    step, the time before a rollback."""
    inst = instance(input_fmu[1], logging=False)
    inst.initialise()
    last = 2                                                  # fmi2LastSuccessfulTime
    assert inst.fmu.getRealStatus(last) == 0.0
    inst.fmu.doStep(0.0, H)
    inst.fmu.doStep(H, H)
    assert inst.fmu.getRealStatus(last) == pytest.approx(2 * H, abs=1e-15)
    state = inst.fmu.getFMUstate()
    raises_status(FMI_ERROR, inst.fmu.doStep, 0.5, H)          # refused: the FMU stays at 2H
    assert inst.fmu.getRealStatus(last) == pytest.approx(2 * H, abs=1e-15)
    inst.fmu.doStep(2 * H, H)
    assert inst.fmu.getRealStatus(last) == pytest.approx(3 * H, abs=1e-15)
    inst.fmu.setFMUstate(state)                                # rolled back
    assert inst.fmu.getRealStatus(last) == pytest.approx(2 * H, abs=1e-15)
    inst.fmu.freeFMUstate(state)


@pytest.mark.parametrize("call", ["setupExperiment", "enterInitializationMode", "exitInitializationMode"])
def test_an_initialisation_call_out_of_order_is_fmi2error_and_changes_nothing(input_fmu, instance, steps, call):
    """fmi2SetupExperiment only before initialization mode, fmi2EnterInitializationMode once,
    fmi2ExitInitializationMode only in it (each was fmi2OK; an exit without enter initialised)."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    if call == "exitInitializationMode":       # without enterInitializationMode
        raises_status(FMI_ERROR, inst.fmu.exitInitializationMode)
        inst.fmu.setupExperiment(startTime=0.0, stopTime=2 * H)
    else:
        inst.fmu.setupExperiment(startTime=0.0, stopTime=2 * H)
        inst.fmu.enterInitializationMode()
        if call == "setupExperiment":          # in initialization mode: its stop time is not taken
            raises_status(FMI_ERROR, inst.fmu.setupExperiment, None, 0.0, 1.0)
        else:
            raises_status(FMI_ERROR, inst.fmu.enterInitializationMode)
    [message] = inst.errors()
    assert message.startswith(f"{scene.name}: fmi2{call[0].upper()}{call[1:]}: refused in the "), message
    if call == "exitInitializationMode":
        inst.fmu.enterInitializationMode()
    inst.fmu.exitInitializationMode()
    inst.fmu.doStep(0.0, 2 * H)
    raises_status(FMI_ERROR, inst.fmu.doStep, 2 * H, H)      # the stop time set first holds


def test_log_categories_select_messages_but_never_silence_an_error(input_fmu, instance, steps):
    """fmi2SetDebugLogging with categories: those of modelDescription.xml are taken (the shim knows
    them: LOG_CATEGORIES), another is fmi2Error; a selection lets through the fmi2OK messages of
    the categories named (logAll for the slave's), and every error whatever it names (a category
    the importer named was passed on to pythonfmu's binary, which then dropped every message of the
    others, errors included)."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=True)
    for category in inst.md.logCategories:
        inst.fmu.setDebugLogging(True, [category.name])
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.setDebugLogging, True, ["bogus"])
    [message] = inst.errors()
    assert "fmi2SetDebugLogging: unknown log category 'bogus'" in message and "two_bar_2d" in message
    inst.fmu.setDebugLogging(True, ["logStatusWarning"])
    inst.messages.clear()
    inst.initialise()                                          # its fmi2OK message: not selected
    assert inst.messages == []
    raises_status(FMI_ERROR, inst.fmu.setReal, [inst.vr[INPUT]], [math.nan])
    assert len(inst.errors()) == 1 and f"{INPUT}: input not finite" in inst.errors()[0]
    inst.fmu.setDebugLogging(True, ["logAll"])
    inst.messages.clear()
    inst.fmu.doStep(0.0, H)
    inst.fmu.terminate()                                       # its fmi2OK message: logAll
    assert [m for _, m in inst.messages if m.startswith("terminated:")]


def test_an_input_set_after_terminate_is_fmi2error(input_fmu, instance, steps):
    """FMI 2.0 allows no setter in the terminated state: an input was taken silently (fmi2OK)."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    inst.initialise()
    inst.set(INPUT, 2.0)
    inst.fmu.doStep(0.0, H)
    inst.fmu.terminate()
    raises_status(FMI_ERROR, inst.set, INPUT, 3.0)
    [message] = inst.errors()
    assert message.startswith(f"{scene.name}: {INPUT}: an input cannot be set in the terminated state "
                              f"(got 3.0;") and "it stays 2.0" in message, message
    assert inst.get([INPUT]) == [2.0]

