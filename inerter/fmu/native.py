"""The FMU's native doStep: co-simulation steps taken by the FMU's binary in compiled code.

Through pythonfmu, every fmi2DoStep and fmi2GetReal enters Python: pythonfmu's own glue, the
slave's, the stepper's and numba's dispatch of some thirty arguments cost about as much per
communication step as the model itself on the paper's scenes (docs/fmu_overhead.md). On Linux the FMU's binary is the
status shim (``fmu_src/status_shim.c``); with this link it takes a doStep itself, without
entering Python, whenever the slave has *armed* it:

- the slave owns a context, an int64 array at a fixed address for the instance's life
  (CTX_* slots): a magic number, whether the link is armed, the address of the C function
  :func:`inerter.engine.kernels.native_step_cfunc` for the scene's dimension, the address of
  the running integration's table (:meth:`inerter.engine.compiled.CompiledStepper.native_table`), and a map from every value
  reference to where its value is: the outputs in the array the C function writes, every other
  variable (parameters, inputs, the solver settings, ``fmi_status``) in arrays the slave fills
  when it arms the link (none of them can change between native steps: fixed parameters are
  refused after initialisation, and a set disarms the link);
- the shim asks for the context's address after fmi2Instantiate, and again after fmi2Reset
  (pythonfmu replaces the slave object, and its context with it), by reading the Integer
  value references LINK_VR and LINK_VR + 1 (not in modelDescription.xml; the slave answers 0
  when the link is off: numba missing, or ``INERTER_FMU_NATIVE=0`` in the environment);
- after a doStep that the slave took and returned fmi2OK, and after an exitInitializationMode
  that returned fmi2OK, the shim arms itself when the context says so: the slave arms it after
  every step on the compiled path (DOP853, RK45, RK4) whose outputs the kernels evaluate, and at
  the end of initialisation (the integration started as the first step would start it, so that
  the first step is native too), and disarms it otherwise;
- an armed shim calls the C function for the next doStep. It returns 1 when it took the step
  (fmi2OK; the outputs are in the values array, and every fmi2GetReal/Integer/Boolean/String is
  served from the map until a call enters Python), and 0 when it declines: not the current
  communication point, a step size not > 0, a failed step, outputs the kernels cannot evaluate.
  A declined step goes to the slave, which restores the integration from the backup the C
  function made and takes the step itself, so every message, status and result is the one the
  slave always gives;
- before any other call enters Python after native steps, the shim sets the Integer SYNC_VR:
  the slave takes over the time, state, counters and outputs the native steps left
  (:meth:`~inerter.engine.compiled.CompiledStepper.native_sync`). Every call but a doStep and the
  getters disarms the shim until the next doStep the slave takes (or exitInitializationMode,
  after a reset).

The same context carries the shim's live logger: after fmi2Instantiate (and fmi2Reset) the shim
writes the address
of its ``live_log`` function and of its instance into CTX_LOG_FUNCTION and CTX_LOG_TARGET, so that
the slave can hand a message to the importer's logger during a long call (the kernels' first
compilation, inside exitInitializationMode) instead of when it returns (:meth:`NativeLink.live_log`).

So the native steps are the steps the slave would take, on the same arrays with the same compiled
code: the results are identical bit for bit (tests/test_fmu_native.py).
"""
from __future__ import annotations

import ctypes
import os

import numpy as np

#: The context's slots: CTX_MAP points to one int64 per value reference, -1 or
#: (kind << 32) + index into the array of that kind (CTX_VALUES for OUTPUT, CTX_REALS, ...).
CTX_MAGIC, CTX_ARMED, CTX_FUNCTION, CTX_TABLE, CTX_MAP_SIZE, CTX_MAP, CTX_VALUES, CTX_REALS, CTX_INTEGERS, \
    CTX_BOOLEANS, CTX_STRINGS, CTX_LOG_FUNCTION, CTX_LOG_TARGET = range(13)
CTX_SIZE = 13
#: Kinds of variables in the map: an output (float64 values the C function writes), another Real
#: (float64), an Integer or a Boolean (int64), a String (int64: the address of a NUL-terminated
#: UTF-8 string).
OUTPUT, REAL, INTEGER, BOOLEAN, STRING = range(5)
#: CTX_MAGIC's value: the shim takes a context only with it ("inerte" in ASCII).
MAGIC = 0x696E65727465
#: Private Integer value references (not in modelDescription.xml): reading LINK_VR and
#: LINK_VR + 1 gives the context's address (its low 31 bits, then the rest); setting SYNC_VR
#: makes the slave take over the native steps.
LINK_VR = 0x7FFFFF00
SYNC_VR = 0x7FFFFF02
#: Private Real value reference: the slave's time (the shim answers fmi2LastSuccessfulTime with it).
TIME_VR = SYNC_VR + 1
#: Private Integer value reference: the slave's phase, an index into the slave's PHASES (the shim
#: answers the status functions only in the phases FMI 2.0 allows them in).
PHASE_VR = SYNC_VR + 2
#: Private String value reference: set to the bytes given to fmi2DeSerializeFMUstate, in hex, the
#: slave checks that they are a state of this FMU and logs an error where they are not (the shim
#: then returns fmi2Error without deserializing them). Nothing else changes.
STATE_CHECK_VR = SYNC_VR + 3
#: Private Real value reference: the slave's stop time (fmi2SetupExperiment's, or a restored FMU
#: state's), NaN where there is none; the shim reads it after fmi2SetFMUstate, so that a native
#: step never ends past the stop time the slave holds.
STOP_VR = SYNC_VR + 4
#: The environment variable that turns the link off ("0").
SWITCH = "INERTER_FMU_NATIVE"


class NativeLink:
    """The slave's end of the link: the context, armed after a step the slave took and at the end
    of initialisation."""

    def __init__(self, outputs: dict[int, int], others: dict[int, tuple[int, object]]):
        """`outputs`: value reference -> index of the output in the stepper's output values;
        `others`: value reference -> (kind, a function returning its value) for every other
        variable."""
        self.ctx = np.zeros(CTX_SIZE, dtype=np.int64)
        self.ctx[CTX_MAGIC] = MAGIC
        size = max(list(outputs) + list(others), default=-1) + 1
        self.map = np.full(size, -1, dtype=np.int64)
        for vr, index in outputs.items():
            self.map[vr] = (OUTPUT << 32) + index
        self._getters = {kind: [] for kind in (REAL, INTEGER, BOOLEAN, STRING)}
        for vr, (kind, getter) in others.items():
            self.map[vr] = (kind << 32) + len(self._getters[kind])
            self._getters[kind].append(getter)
        self._buffers = {REAL: np.zeros(len(self._getters[REAL])),
                         **{kind: np.zeros(len(self._getters[kind]), dtype=np.int64)
                            for kind in (INTEGER, BOOLEAN, STRING)}}
        for kind, slot in ((REAL, CTX_REALS), (INTEGER, CTX_INTEGERS), (BOOLEAN, CTX_BOOLEANS),
                           (STRING, CTX_STRINGS)):
            self.ctx[slot] = self._buffers[kind].ctypes.data
        self._strings = []                    # the strings CTX_STRINGS points to, kept alive
        self.ctx[CTX_MAP_SIZE] = size
        self.ctx[CTX_MAP] = self.map.ctypes.data
        self.why_off = self._why_off()
        self.stale = True                     # the values of the other variables may have changed
        self._table = None                    # what the context points to, kept alive

    def _refresh(self) -> None:
        """The other variables' values into their arrays."""
        self._buffers[REAL][:] = [float(get()) for get in self._getters[REAL]]
        self._buffers[INTEGER][:] = [int(get()) for get in self._getters[INTEGER]]
        self._buffers[BOOLEAN][:] = [1 if get() else 0 for get in self._getters[BOOLEAN]]
        self._strings = [ctypes.create_string_buffer(str(get()).encode("utf-8"))
                         for get in self._getters[STRING]]
        self._buffers[STRING][:] = [ctypes.addressof(text) for text in self._strings]
        self.stale = False

    @staticmethod
    def _why_off() -> str:
        if os.environ.get(SWITCH, "1").strip() == "0":
            return f"{SWITCH}=0"
        from inerter.engine import compiled
        return "" if compiled.AVAILABLE else compiled.WHY_NOT

    def address_words(self) -> list[int]:
        """[low 31 bits, the rest] of the context's address; [0, 0] when the link is off."""
        if self.why_off:
            return [0, 0]
        address = int(self.ctx.ctypes.data)
        return [address & 0x7FFFFFFF, address >> 31]

    def arm(self, stepper, tolerance: float, start: bool = False) -> None:
        """Arm the link for the stepper's next step, where it can be taken natively (`start`: also
        where no integration runs yet, at the end of initialisation:
        :meth:`~inerter.engine.compiled.CompiledStepper.native_table` starts it)."""
        self.ctx[CTX_ARMED] = 0
        table = None
        if not self.why_off and hasattr(stepper, "native_table"):
            table = stepper.native_table(tolerance, start=start)
        if table is None:
            return
        if self.stale:
            self._refresh()
        if not self.ctx[CTX_FUNCTION]:
            self.ctx[CTX_FUNCTION] = stepper.native_function().address
        values = stepper.native_values()
        self._table = (table, values)
        self.ctx[CTX_TABLE] = table.ctypes.data
        self.ctx[CTX_VALUES] = values.ctypes.data
        self.ctx[CTX_ARMED] = 1

    @staticmethod
    def sync(stepper) -> int:
        """The slave takes over the stepper's native steps (the shim asks before any other call
        enters Python after them); returns how many there were."""
        take_over = getattr(stepper, "native_sync", None)
        return take_over() if take_over is not None else 0

    def live_log(self, status: int, category: str, message: str) -> bool:
        """Hand `message` to the importer's logger now, through the shim (which wrote its logging
        function into CTX_LOG_FUNCTION after fmi2Instantiate; it passes the message on as it does
        the original's: where the importer turned logging on, or for a status from fmi2Discard up). False where there is no shim to do it: pythonfmu
        then delivers the message when the call in progress returns. Only from the thread of that
        call: FMI 2.0 does not let an FMU call the logger from another."""
        address = int(self.ctx[CTX_LOG_FUNCTION])
        if not address:
            return False
        function = ctypes.CFUNCTYPE(None, ctypes.c_int64, ctypes.c_int32, ctypes.c_char_p,
                                    ctypes.c_char_p)(address)
        function(int(self.ctx[CTX_LOG_TARGET]), status, category.encode("utf-8"),
                 message.encode("utf-8", errors="replace"))
        return True

    def disarm(self) -> None:
        self.ctx[CTX_ARMED] = 0

    def turn_off(self, why: str) -> None:
        """No native steps in this instance any more (the shim keeps the context's address)."""
        self.disarm()
        self.why_off = why
