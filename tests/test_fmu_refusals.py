"""What the FMU refuses, and how: the functions it does not support, and status inquiries FMI 2.0
does not allow or that do not apply. Each returns the status
FMI 2.0 asks for, with one message naming the scene file as every other error does, and changes
nothing: the instance steps on as its untouched twin does.

The references are FMI 2.0 (2.0.4 text): section 2.1.3 ("fmi2Discard is returned also if the slave
is not able to return the required status information"; a function that cannot do its job returns
fmi2Error), section 4.2.3 (which function answers which fmi2StatusKind: fmi2GetStatus
fmi2DoStepStatus and fmi2GetStringStatus fmi2PendingStatus only after a doStep returned fmi2Pending,
fmi2GetRealStatus fmi2LastSuccessfulTime, fmi2GetBooleanStatus fmi2Terminated; none is an Integer)
and section 4.2.4's state table (the status functions in the stepComplete, stepInProgress,
stepFailed and terminated states only). The capability flags come from the FMU's
modelDescription.xml. All of it is the status shim's (fmu_src/status_shim.c): each test needs it.
"""
from __future__ import annotations

import pytest

from test_fmu import (FMI_DISCARD, FMI_ERROR, INPUT, ROOT, fmus, input_fmu, instance,  # noqa: F401
                      needs_shim, raises_status, stepped_pair, unzipped)
from test_fmu_call_sequences import steps  # noqa: F401

from inerter.fmu import native as fmu_native

pytestmark = pytest.mark.usefixtures("needs_shim")
# fmi2StatusKind (FMI 2.0 section 4.2.3)
DO_STEP_STATUS, PENDING_STATUS, LAST_SUCCESSFUL_TIME, TERMINATED = range(4)


def continue_both(inst, clean, t, h, n=3):
    """n more steps of both instances with a new input from the second on: the rows of each."""
    rows = {id(inst): [], id(clean): []}
    for i in range(n):
        for one in (inst, clean):
            if i == 1:
                one.set(INPUT, -3.0)
            one.fmu.doStep(t + i * h, h)
            rows[id(one)].append(one.get(one.outputs))
    return rows[id(inst)], rows[id(clean)]


UNSUPPORTED = [
    ("fmi2GetDirectionalDerivative", "providesDirectionalDerivative is false",
     lambda inst: inst.fmu.getDirectionalDerivative([inst.vr[inst.outputs[0]]], [inst.vr[INPUT]], [1.0])),
    ("fmi2SetRealInputDerivatives", "canInterpolateInputs is false",
     lambda inst: inst.fmu.setRealInputDerivatives([inst.vr[INPUT]], [1], [1.0])),
    ("fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0",
     lambda inst: inst.fmu.getRealOutputDerivatives([inst.vr[inst.outputs[0]]], [1])),
    ("fmi2CancelStep", "canRunAsynchronuously is false", lambda inst: inst.fmu.cancelStep())]


def test_the_capability_flags_say_what_is_unsupported(input_fmu, instance):
    flags = instance(input_fmu[1], logging=False).md.coSimulation
    assert (flags.providesDirectionalDerivative, flags.canInterpolateInputs,
            flags.maxOutputDerivativeOrder, flags.canRunAsynchronuously) == (False, False, 0, False)


@pytest.mark.parametrize("function, flag, call", UNSUPPORTED, ids=[u[0] for u in UNSUPPORTED])
def test_an_unsupported_function_is_fmi2error_naming_the_scene_file(input_fmu, instance, steps,
                                                                     function, flag, call):
    """It was fmi2Error with pythonfmu's "FMI function not supported: ..." (no file named;
    fmi2GetRealOutputDerivatives named as fmiGetRealOutputDerivatives); with logging off too."""
    scene, fmu = input_fmu
    inst, clean, h = stepped_pair(fmu, instance)
    inst.fmu.setDebugLogging(False, [])
    inst.messages.clear()
    raises_status(FMI_ERROR, call, inst)
    [message] = inst.errors()
    assert message.startswith(f"{scene.name}: {function}: not supported by this FMU "
                              f"(modelDescription.xml: {flag}") and message.endswith("; nothing changes"), message
    mine, theirs = continue_both(inst, clean, h, h)
    assert mine == theirs


def test_status_functions_before_initialisation_are_fmi2error(input_fmu, instance):
    """FMI 2.0's state table allows them after initialisation only; fmi2GetRealStatus and
    fmi2GetBooleanStatus were fmi2OK there (0.0, false)."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    calls = [(inst.fmu.getStatus, DO_STEP_STATUS), (inst.fmu.getRealStatus, LAST_SUCCESSFUL_TIME),
             (inst.fmu.getIntegerStatus, LAST_SUCCESSFUL_TIME),
             (inst.fmu.getBooleanStatus, TERMINATED), (inst.fmu.getStringStatus, PENDING_STATUS)]
    for state in ("instantiated", "initialization"):
        if state == "initialization":
            inst.fmu.setupExperiment(startTime=0.0)
            inst.fmu.enterInitializationMode()
        for call, kind in calls:
            inst.messages.clear()
            raises_status(FMI_ERROR, call, kind)
            [message] = inst.errors()
            assert message.startswith(f"{scene.name}: fmi2Get") and \
                f"refused in the {state} state" in message, message
    inst.fmu.exitInitializationMode()
    assert inst.fmu.getRealStatus(LAST_SUCCESSFUL_TIME) == 0.0


def test_status_inquiries_after_initialisation(input_fmu, instance, steps):
    """fmi2LastSuccessfulTime and fmi2Terminated are answered (after native steps too); a kind a
    function does not give, or one that does not apply (no doStep is ever pending), is fmi2Discard
    (fmi2GetStatus was fmi2Error); a number that is no fmi2StatusKind is fmi2Error. Each refusal
    logs one message naming the scene file; none changes the run."""
    scene, fmu = input_fmu
    inst, clean, h = stepped_pair(fmu, instance)
    inst.messages.clear()
    assert inst.fmu.getRealStatus(LAST_SUCCESSFUL_TIME) == h
    assert inst.fmu.getBooleanStatus(TERMINATED) is False
    assert inst.messages == []
    discards = [(inst.fmu.getStatus, DO_STEP_STATUS, "fmi2GetStatus(fmi2DoStepStatus): not applicable"),
                (inst.fmu.getStringStatus, PENDING_STATUS,
                 "fmi2GetStringStatus(fmi2PendingStatus): not applicable"),
                (inst.fmu.getStatus, TERMINATED, "fmi2GetStatus: fmi2Terminated is not a status this "
                                                 "function gives (FMI 2.0 section 4.2.3: it is asked of "
                                                 "fmi2GetBooleanStatus)"),
                (inst.fmu.getRealStatus, DO_STEP_STATUS, "it is asked of fmi2GetStatus"),
                (inst.fmu.getBooleanStatus, LAST_SUCCESSFUL_TIME, "it is asked of fmi2GetRealStatus"),
                (inst.fmu.getStringStatus, TERMINATED, "it is asked of fmi2GetBooleanStatus"),
                (inst.fmu.getIntegerStatus, LAST_SUCCESSFUL_TIME, "FMI 2.0 defines no Integer status")]
    for call, kind, reason in discards:
        inst.messages.clear()
        raises_status(FMI_DISCARD, call, kind)
        [(status, message)] = inst.messages
        assert status == FMI_DISCARD and message.startswith(f"{scene.name}: ") and reason in message, message
    for call in (inst.fmu.getStatus, inst.fmu.getRealStatus, inst.fmu.getBooleanStatus):
        inst.messages.clear()
        raises_status(FMI_ERROR, call, 7)
        [message] = inst.errors()
        assert message.startswith(f"{scene.name}: fmi2Get") and "7 is not an fmi2StatusKind" in message
    mine, theirs = continue_both(inst, clean, h, h)
    assert mine == theirs
    assert inst.fmu.getRealStatus(LAST_SUCCESSFUL_TIME) == pytest.approx(4 * h, abs=1e-15)
    inst.fmu.terminate()                  # terminated: still answered
    assert inst.fmu.getBooleanStatus(TERMINATED) is False
    assert inst.fmu.getRealStatus(LAST_SUCCESSFUL_TIME) == pytest.approx(4 * h, abs=1e-15)


def test_status_inquiries_in_the_error_state_are_fmi2error(input_fmu, instance):
    """After a failed exitInitializationMode (FMI 2.0's error state: reset or free only)."""
    scene, fmu = input_fmu
    inst = instance(fmu, logging=False)
    inst.fmu.setupExperiment(startTime=0.0)
    inst.fmu.enterInitializationMode()
    inst.set("M1", 0.0)
    raises_status(FMI_ERROR, inst.fmu.exitInitializationMode)
    inst.messages.clear()
    raises_status(FMI_ERROR, inst.fmu.getRealStatus, LAST_SUCCESSFUL_TIME)
    assert "refused in the failed state" in inst.errors()[0]
    inst.fmu.reset()
    inst.initialise()
    assert inst.fmu.getRealStatus(LAST_SUCCESSFUL_TIME) == 0.0


def test_the_private_value_references_are_the_shims():
    """The shim derives them from NATIVE_SYNC_VR (fmu_src/status_shim.c); the slave takes them
    from inerter.fmu.native."""
    names = ("TIME_VR", "PHASE_VR")
    assert [getattr(fmu_native, name) for name in names] == [fmu_native.SYNC_VR + k for k in (1, 2)]
    source = (ROOT / "fmu_src" / "status_shim.c").read_text()
    for k, name in enumerate(names, start=1):
        assert f"#define {name} (NATIVE_SYNC_VR + {k}u)" in source
