"""What the FMU refuses, and how: bytes that are no FMU state of it, the functions it does not
support, and status inquiries FMI 2.0 does not allow or that do not apply. Each returns the status
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

import base64
import json
import os
import pickle

import pytest

from test_fmu import (FMI_DISCARD, FMI_ERROR, INPUT, ROOT, fmus, input_fmu, instance,  # noqa: F401
                      needs_shim, raises_status, stepped_pair, unzipped)
from test_fmu_call_sequences import steps  # noqa: F401

from inerter.fmu import native as fmu_native

pytestmark = pytest.mark.usefixtures("needs_shim")
OTHER_SCENE = ROOT / "scenarios" / "lumped_mass_2d.toml"
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


def edited(blob: bytes, **fields) -> bytes:
    state = json.loads(blob)
    state.update(fields)
    return json.dumps(state).encode()


def test_deserializing_bytes_that_are_no_state_of_this_fmu_is_fmi2error(input_fmu, fmus, instance,
                                                                       steps):
    """Random bytes, none, a cut state, another scene's, another build's, another format's: each
    was fmi2OK (pythonfmu's binary took any bytes; only fmi2SetFMUstate refused the state)."""
    scene, fmu = input_fmu
    inst, clean, h = stepped_pair(fmu, instance)
    for one in (inst, clean):
        one.messages.clear()
    state = inst.fmu.getFMUstate()
    blob = bytes(inst.fmu.serializeFMUstate(state))
    inst.fmu.freeFMUstate(state)
    other = instance(fmus[OTHER_SCENE], "other", logging=False)
    other.initialise()
    other_state = other.fmu.getFMUstate()
    other_blob = bytes(other.fmu.serializeFMUstate(other_state))
    other.fmu.freeFMUstate(other_state)
    outputs = inst.get(inst.outputs)
    cases = [(bytes(range(256)) * 3, "768 bytes", "not text (UTF-8)"),
             (b"", "0 bytes", "no bytes"),
             (blob[:len(blob) // 2], f"{len(blob) // 2} bytes", "not JSON, or cut short"),
             (b'{"format": "something else"}', "format 'something else'", "expected format"),
             (edited(blob, format="inerter-fmu-state/1"), "format 'inerter-fmu-state/1'",
              "(expected format 'inerter-fmu-state/2'"),
             (other_blob, f"it is a state of {OTHER_SCENE.name}, not of {scene.name}", ""),
             (edited(blob, scene="0" * 64), f"a state of another version of {scene.name}", ""),
             (edited(blob, build="0" * 64), "saved by another build of the FMU", "build 000000000000"),
             (edited(blob, settings={"b": 1.0}), "the state's variables differ from this FMU's", ""),
             (edited(blob, stepper="a!b"), "its solver state is not base64", ""),
             (edited(blob, stepper="anVuaw=="), "its solver state cannot be read", "")]
    for data, reason, detail in cases:
        inst.messages.clear()
        raises_status(FMI_ERROR, inst.fmu.deSerializeFMUstate, data)
        [message] = [m for _, m in inst.messages]
        assert message.startswith(f"{scene.name}: fmi2DeSerializeFMUstate: ") and reason in message \
            and detail in message and message.endswith("the instance is unchanged"), message
        assert inst.get(inst.outputs) == outputs
    # Nothing changed: the next steps (an input changed between them) equal those of the twin that
    # never saw the bytes, bit for bit; and its own state still deserializes and restores.
    inst.messages.clear()
    mine, theirs = continue_both(inst, clean, h, h)
    assert mine == theirs
    restored = inst.fmu.deSerializeFMUstate(blob)
    inst.fmu.setFMUstate(restored)
    inst.fmu.freeFMUstate(restored)
    assert inst.get(inst.outputs) == outputs and inst.errors() == []


class _Runs:
    """A pickle whose loading would call `fn(*args)` (pickle's __reduce__)."""

    def __init__(self, fn, *args):
        self.fn, self.args = fn, args

    def __reduce__(self):
        return self.fn, self.args


def test_a_state_whose_solver_pickle_would_run_code_is_fmi2error_and_runs_nothing(input_fmu, instance, tmp_path,
                                                                                  steps):
    """A state of this FMU (format, scene and build as they are: anyone can copy them) whose solver
    state is a pickle that would call os.system, or eval, when unpickled: fmi2DeSerializeFMUstate
    refuses it (fmi2Error, one message naming the scene file and the global), the command never
    runs (the file it would make is not there), and the instance steps on as its untouched twin.
    The solver state is unpickled naming only the globals a state holds
    (inerter.engine.simulation.load_state); before, plain pickle ran it."""
    scene, fmu = input_fmu
    inst, clean, h = stepped_pair(fmu, instance)
    state = inst.fmu.getFMUstate()
    blob = bytes(inst.fmu.serializeFMUstate(state))
    inst.fmu.freeFMUstate(state)
    outputs = inst.get(inst.outputs)
    marker = tmp_path / "ran"
    for payload in (_Runs(os.system, f"touch {marker}"), _Runs(eval, f"open({str(marker)!r}, 'w')")):
        crafted = edited(blob, stepper=base64.b64encode(pickle.dumps((0.0, payload))).decode("ascii"))
        inst.messages.clear()
        raises_status(FMI_ERROR, inst.fmu.deSerializeFMUstate, crafted)
        [message] = [m for _, m in inst.messages]
        named = f"{payload.fn.__module__}.{payload.fn.__name__}"
        assert message.startswith(f"{scene.name}: fmi2DeSerializeFMUstate: {len(crafted)} bytes that are not a "
                                  f"serialized state of this FMU: its solver state cannot be read") \
            and f"it names {named}, which no stepper state holds" in message \
            and message.endswith("the instance is unchanged"), message
        assert not marker.exists()
        assert inst.get(inst.outputs) == outputs
    inst.messages.clear()
    mine, theirs = continue_both(inst, clean, h, h)
    assert mine == theirs and inst.errors() == []


def test_a_serialized_state_continues_bit_for_bit_in_a_fresh_instance(input_fmu, instance, steps):
    """A state serialized mid-run, deserialized into an instance that was only instantiated (no
    setupExperiment, no initialisation) and restored: the same continuation as the run it was
    taken from, bit for bit, with an input changed on the way (the integration restarts there)."""
    fmu = input_fmu[1]
    source = instance(fmu, "source", logging=False)
    source.fmu.setupExperiment(startTime=0.0, stopTime=0.2)
    source.fmu.enterInitializationMode()
    source.fmu.exitInitializationMode()
    h = 0.01
    source.set(INPUT, 2.0)
    for i in range(3):
        source.fmu.doStep(i * h, h)
    state = source.fmu.getFMUstate()
    blob = bytes(source.fmu.serializeFMUstate(state))
    source.fmu.freeFMUstate(state)
    fresh = instance(fmu, "fresh", logging=False)
    restored = fresh.fmu.deSerializeFMUstate(blob)
    fresh.fmu.setFMUstate(restored)
    fresh.fmu.freeFMUstate(restored)
    assert fresh.get(fresh.outputs) == source.get(source.outputs)
    mine, theirs = continue_both(fresh, source, 3 * h, h, n=5)
    assert mine == theirs
    assert fresh.fmu.getRealStatus(LAST_SUCCESSFUL_TIME) == source.fmu.getRealStatus(LAST_SUCCESSFUL_TIME)
    raises_status(FMI_ERROR, fresh.fmu.doStep, 8 * h, 0.2)   # the stop time came with the state
    [message] = fresh.errors()
    assert "past stopTime = 0.2 s" in message, message


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
    names = ("TIME_VR", "PHASE_VR", "STATE_CHECK_VR", "STOP_VR")
    assert [getattr(fmu_native, name) for name in names] == [fmu_native.SYNC_VR + k for k in (1, 2, 3, 4)]
    source = (ROOT / "fmu_src" / "status_shim.c").read_text()
    for k, name in enumerate(names, start=1):
        assert f"#define {name} (NATIVE_SYNC_VR + {k}u)" in source
