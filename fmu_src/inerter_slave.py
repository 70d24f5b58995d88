"""The generic FMI 2.0 co-simulation slave: one inerter scene behind the FMI interface.

Every FMU built by :mod:`inerter.fmu.build` ships this file in its ``resources/`` next to a
small generated module that subclasses :class:`InerterSlave` under the scene's name and names
the scene file shipped beside it. The slave loads that scene with the solver package shipped in
the same ``resources/`` and exposes it as

- every scene parameter as a Real parameter (``b``, ``k``, ...), every effect switch as a
  Boolean parameter (``effects.centripetal``), and the integrator settings ``solver`` (an
  Enumeration of the methods), ``rtol`` and ``atol`` (Real). The parameters the running engine
  takes between steps (the class's :attr:`~InerterSlave.tunable`: element coefficients, point-force
  amplitudes, frequencies and gains) are *tunable*: set between steps, they hold from the current
  communication point on (``Stepper.retune``). The others are *fixed*: they can be set until
  exitInitializationMode, not after.
- every model input as a Real input (``C.f[1]``), held constant over a communication step;
- every model output as a Real output (``C.r[2]``, ``spring.f``, ``energy``, ...), *calculated*:
  in initialization mode from the settings and inputs set so far, then at each communication
  point. An output computed from the accelerations (an inerter's force) follows an input set at a
  communication point at once (direct feedthrough, declared in the ModelStructure); positions and
  velocities do not.

Statuses. pythonfmu 0.7.0 turns any Python exception into fmi2Fatal and destroys the instance,
and its binary returns fmi2OK from every call but doStep, which gives fmi2Discard when
:meth:`do_step` returns False; the Python bridge (``python_bridge.c``, its place on Linux) keeps
that contract. So this slave never lets an exception escape: it logs every
problem (status error, or discard for a failed step) and keeps the status of its last
exitInitializationMode, setXxx, doStep and setFMUstate call in the Integer variable
``fmi_status`` (causality local: 0 fmi2OK, 2 fmi2Discard, 3 fmi2Error). On Linux the FMU's
binary is a shim (``status_shim.c``) in front of the bridge: it reads ``fmi_status`` after each
of those calls and returns it when it is worse than fmi2OK. So

- an invalid parameter, effect or solver setting: exitInitializationMode logs the solver's
  message (file, field, value, expected; the settings changed) and returns fmi2Error; the
  outputs read NaN and every doStep returns fmi2Error with the same message until the
  importer resets the FMU (FMI 2.0 allows nothing but reset or free after that error);
- a non-finite input, a fixed parameter set after initialisation, an output or an unknown value
  reference set: the value is ignored (the state stays as it was), the attempt is logged and the
  setXxx returns fmi2Error. The importer may go on from there;
- a step the solver cannot complete: doStep returns fmi2Discard with the solver's message and
  the FMU stays at the last good communication point, so the importer can retry or roll back;
- a call FMI 2.0 does not allow in the instance's state or with its arguments (a doStep before
  initialisation, after terminate, not at the current point, of a size not > 0, or ending past
  fmi2SetupExperiment's stopTime; a getter before initialization mode or of an unknown value
  reference; terminate outside a run): an error is logged and the call changes nothing; the shim
  returns fmi2Error (for a getter, terminate and the like: because the slave logged an error).

Every message of status discard or error names the scene file.

Without the shim (the win64 binary, or a build on a machine without a C compiler) those calls
return fmi2OK. A rejected value is then reported by the next doStep instead, which returns
fmi2Discard without stepping, once: a rejection counts as reported when ``fmi_status`` has been
read after the call that made it (which the shim always does).

FMU state (fmi2GetFMUstate / SetFMUstate / Serialize / DeSerialize) holds the whole state: the
parameter settings, the inputs, the outputs and the solver's own state (time, coordinates,
integrator step size, held inputs), so that a step repeated after a rollback gives bit-identical
outputs. The serialized form is JSON with the solver state in base64, marked with its format, the
scene file's name and digest and the FMU's build digest: the status shim hands the bytes given to
fmi2DeSerializeFMUstate to :meth:`InerterSlave._check_serialized` first, and returns fmi2Error with
the reason logged for bytes that are no state of this FMU.
"""
from __future__ import annotations

import base64
import contextlib
import functools
import hashlib
import io
import json
import math
import operator
import os
import shutil
import sys
import tempfile
import threading
import traceback
import typing
import zipfile
from pathlib import Path

#: The archive of the package's modules beside this file (inerter.fmu.build.write_payload).
PAYLOAD_FILE = "inerter_payload.zip"


def _cache_root() -> Path:
    """The package's cache folder, as inerter.engine.compiled finds it for the kernels (written
    again here: the package is not importable before its payload is unpacked)."""
    if os.environ.get("INERTER_CACHE_DIR"):
        return Path(os.environ["INERTER_CACHE_DIR"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "inerter"


def _unpacked(archive: Path, roots) -> Path | None:
    """The folder holding `archive` unpacked, under the first of `roots` that can take it: named
    by the archive's hash, unpacked into a temporary folder renamed into place, so that
    concurrent instances see a whole folder or none, and later ones find it."""
    data = archive.read_bytes()
    digest = hashlib.sha256(data).hexdigest()[:16]
    for root in roots:
        folder = root / digest
        if (folder / "inerter" / "__init__.py").is_file():
            return folder
        try:
            root.mkdir(parents=True, exist_ok=True)
            work = Path(tempfile.mkdtemp(dir=root, prefix=f".{digest}-"))
            with zipfile.ZipFile(io.BytesIO(data)) as z:
                z.extractall(work)
            try:
                os.rename(work, folder)
            except OSError:                      # another instance was first
                shutil.rmtree(work, ignore_errors=True)
        except OSError:
            continue
        if (folder / "inerter" / "__init__.py").is_file():
            return folder
    return None


def unpack_payload(resources: Path) -> Path | None:
    """Make the package this FMU carries importable, before anything imports it.

    The package's modules come in one archive (an importer extracts the whole FMU at every
    instantiation, and sixty files cost it more than one). It is unpacked once per machine, into
    the package's cache folder (or, where that cannot be written, into resources/), and that
    folder goes on sys.path where resources/ stands, so the shipped package takes the place it
    took as a folder of resources/. Where ``inerter`` is imported already, nothing changes: the
    slave runs with it and says so (:meth:`InerterSlave._warn_if_foreign_package`). Returns the
    folder the shipped package is in, None where there is none."""
    archive = resources / PAYLOAD_FILE
    if not archive.is_file():
        return None
    folder = _unpacked(archive, (_cache_root() / "fmu-payload", resources / "_payload"))
    if folder is None:
        return None
    if "inerter" in sys.modules:
        # The package stays the one imported; the folder, last on sys.path, still gives the
        # pythonfmu the FMU carries where the process has none.
        if str(folder) not in sys.path:
            sys.path.append(str(folder))
        return folder
    entries = [str(Path(p).resolve()) if p else p for p in sys.path]
    where = entries.index(str(resources.resolve())) if str(resources.resolve()) in entries else 0
    if str(folder) not in sys.path:
        sys.path.insert(where, str(folder))
    return folder


SHIPPED_PACKAGE = unpack_payload(Path(__file__).resolve().parent)

# After the payload is unpacked: it carries pythonfmu as well as the package.
from pythonfmu import Boolean, DefaultExperiment, Fmi2Slave, Integer, Real, String  # noqa: E402
from pythonfmu.enums import Fmi2Causality, Fmi2Status, Fmi2Variability, Fmi2Initial  # noqa: E402
import inerter  # noqa: E402
from inerter.fmu import native as fmu_native
from inerter.common.errors import InerterError, SimulationError
from inerter.engine.simulation import load_state

#: The serialized state's format: /2 carries the scene file's name and the FMU's build digest.
STATE_FORMAT = "inerter-fmu-state/2"

#: The Integer variable that holds the status of the slave's last checked call; the Linux
#: binary (fmu_src/status_shim.c) reads it and returns it.
STATUS_VARIABLE = "fmi_status"
OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3

#: The FMU's solver settings -> the scene's ``[experiment]`` fields they set.
SOLVER_SETTINGS = {"solver": "method", "rtol": "rtol", "atol": "atol"}
#: The Boolean parameter choosing the compiled path (not a scene setting).
PATH_SETTING = "compiled"

# Phases of an instance, after FMI 2.0 co-simulation's states.
INSTANTIATED = "instantiated"      # fixed parameters may be set
INITIALIZATION = "initialization"  # between enter and exitInitializationMode: the same
STEPPING = "stepping"              # after a successful exitInitializationMode
FAILED = "failed"                  # initialisation failed, or an unexpected error: steps refused
TERMINATED = "terminated"
#: The phases in the order of their index, which the status shim reads (fmu_native.PHASE_VR).
PHASES = (INSTANTIATED, INITIALIZATION, STEPPING, FAILED, TERMINATED)

#: Communication points closer than this (relative to max(1 s, |t|)) are taken as equal.
TIME_TOLERANCE = 1e-9


def _compile_notice():
    """The engine's CompileNotice (None without numba)."""
    try:
        from inerter.engine import compiled
    except Exception:
        return None
    return getattr(compiled, "NOTICE", None)


#: The models loaded in this process, by the digest of their scene file: (the digest of the scene
#: and every file it reads, {overrides: model}). A Model is the compiled description; steppers hold
#: the state and change nothing in it (MuJoCo's mjModel / mjData). So the later instances of an FMU
#: in one process (an importer's next run, a parameter sweep) take the models of the first instead
#: of reading, validating and building the scene again (about half of an instantiation).
_LOADED: dict[str, tuple[str, dict]] = {}
#: The most scenes kept in _LOADED (the oldest goes first).
LOADED_SCENES = 8


def _files_digest(scene_path: Path, scene_bytes: bytes, data_files) -> str:
    """The digest of a scene file and of the files it reads (ground records, beside it)."""
    h = hashlib.sha256(scene_bytes)
    for rel in data_files:
        h.update(b"\0" + str(rel).encode("utf-8") + b"\0" + (scene_path.parent / rel).read_bytes())
    return h.hexdigest()


def _loaded_models(scene_path: Path, scene_bytes: bytes, scene_digest: str) -> dict:
    """{overrides: model} for the scene at `scene_path`, with at least the scene's own model (key
    ()): those loaded in this process when the scene and every file it reads are the same bytes,
    else a fresh load (which raises as ``inerter.load`` does)."""
    known = _LOADED.get(scene_digest)
    if known is not None:
        digest, models = known
        try:
            if _files_digest(scene_path, scene_bytes, models[()].scene.data_files) == digest:
                return models
        except OSError:
            pass                                  # a file missing here: the load below says so
    model = inerter.load(scene_path)
    models = {(): model}
    _LOADED.pop(scene_digest, None)
    while len(_LOADED) >= LOADED_SCENES:
        del _LOADED[next(iter(_LOADED))]
    _LOADED[scene_digest] = (_files_digest(scene_path, scene_bytes, model.scene.data_files), models)
    return models


class _Variables(typing.NamedTuple):
    """An FMU's variables as its slave class declares them for one model of its scene."""
    model: object        # the model they were made for
    specs: list          # (variable, its getter from an instance, its setter from an instance)
    status_vr: int       # fmi_status's value reference
    native_outputs: dict  # value reference -> index in the stepper's outputs (the derived ones left out)
    native_kinds: dict   # value reference -> the native link's kind, for every variable but the outputs


#: The variables of each slave class and scene (by its digest), made once per process: an
#: instance copies them and binds its getters and setters (InerterSlave._register) instead of
#: building some forty pythonfmu variables at every instantiation.
_VARIABLES: dict = {}


def _variables(cls, scene_digest: str, model) -> _Variables:
    """`cls`'s variables for `model` (the scene's own model, shared by the instances of a process:
    _loaded_models), made at the first call with that model."""
    known = _VARIABLES.get((cls, scene_digest))
    if known is not None and known.model is model:
        return known
    specs = cls._variable_specs(model)
    _VARIABLES.pop((cls, scene_digest), None)
    while len(_VARIABLES) >= LOADED_SCENES:       # as _LOADED: the oldest goes, and its model with it
        del _VARIABLES[next(iter(_VARIABLES))]
    output_index = {o["name"]: i for i, o in enumerate(model.output_info())}
    kinds = ((Real, fmu_native.REAL), (Integer, fmu_native.INTEGER),
             (Boolean, fmu_native.BOOLEAN), (String, fmu_native.STRING))
    known = _VARIABLES[(cls, scene_digest)] = _Variables(
        model, specs,
        status_vr=next(var.value_reference for var, _, _ in specs if var.name == STATUS_VARIABLE),
        native_outputs={var.value_reference: output_index[var.name] for var, _, _ in specs
                        if var.causality == Fmi2Causality.output and not model.signals.is_derived(var.name)},
        native_kinds={var.value_reference: next(kind for c, kind in kinds if isinstance(var, c))
                      for var, _, _ in specs if var.causality != Fmi2Causality.output})
    return known


@functools.cache
def _foreign_package() -> str:
    """The warning for a process that had imported another ``inerter`` than the one this FMU ships
    ("" where it runs the shipped one): the same for every instance in the process (both folders
    are fixed once this module is imported), so it is found once, not at every instantiation."""
    if SHIPPED_PACKAGE is None:
        return ""
    shipped = (SHIPPED_PACKAGE / "inerter").resolve()
    used = Path(inerter.__file__).resolve().parent
    if used == shipped:
        return ""
    return (f"this process had already imported the inerter package from {used}; the FMU runs "
            f"with it, not with the copy shipped in {shipped}")


class _LogLines:
    """A text stream that hands each line written to it to `log` (CompileNotice prints to it)."""

    def __init__(self, log):
        self._log = log
        self._text = ""

    def write(self, text: str) -> int:
        self._text += text
        while "\n" in self._text:
            line, self._text = self._text.split("\n", 1)
            if line.strip():
                self._log(line.strip())
        return len(text)

    def flush(self):
        pass


class ExactReal(Real):
    """pythonfmu's Real, with its start value written so that it reads back as the same float.

    pythonfmu 0.7.0 writes it with 16 significant digits, which can be one ulp off (a scene
    parameter 11.327612281500457 would become 11.32761228150046); ``repr`` gives the shortest
    string that reads back exactly.
    """

    def to_xml(self):
        parent = super().to_xml()
        if self.start is not None and math.isfinite(float(self.start)):
            parent.find("Real").set("start", repr(float(self.start)))
        return parent


def _same(a, b) -> bool:
    """Exact equality of two setting values (NaN equals nothing, so it always counts as set)."""
    return type(a) is type(b) and a == b


class InerterSlave(Fmi2Slave):
    """An inerter scene as an FMI 2.0 co-simulation slave.

    A subclass sets :attr:`scene_file`, the scene's file name inside the FMU's ``resources/``.
    """

    #: The scene file, relative to the FMU's resources folder (set by the generated subclass).
    scene_file: str = ""
    #: The parameters the running engine takes between steps (``Model.tunable_parameters()``,
    #: found at build time and set by the generated subclass); the others are fixed.
    tunable: tuple = ()
    #: The digest of everything the FMU was built from (``inerter.fmu.build.source_hash``, set by
    #: the generated subclass): a serialized state is taken only by an FMU of the same build.
    build: str = ""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        if not self.scene_file:
            raise TypeError(f"{type(self).__name__} does not name its scene file (scene_file)")
        folder = Path(self.resources or ".")
        self.scene_path = folder / self.scene_file
        # resources/ as messages may write it (as given, and resolved), which _named_files leaves out
        self._resource_prefixes = tuple({str(folder) + os.sep, str(folder.resolve()) + os.sep})
        scene_bytes = self.scene_path.read_bytes()
        self.scene_digest = hashlib.sha256(scene_bytes).hexdigest()
        # loaded models by their overrides (at most a few), shared with the earlier instances of
        # the same scene in this process (_loaded_models)
        self._models = _loaded_models(self.scene_path, scene_bytes, self.scene_digest)
        model = self._models[()]
        experiment = model.experiment
        if getattr(self.__class__, "description", None) is None:
            self.description = f"inerter scene {model.name}"
        # The communication step an importer should take by default: the scene's
        # experiment.communication_step where it has one, else its output interval.
        step = experiment.get("communication_step") or experiment["output_interval"]
        self.default_experiment = DefaultExperiment(
            start_time=0.0, stop_time=float(experiment["stop_time"]), step_size=float(step),
            tolerance=float(experiment["rtol"]))

        # What the importer can set, with the scene's values as defaults.
        self._defaults: dict[str, object] = {}
        for p in model.parameter_info():
            self._defaults[p["name"]] = float(p["value"])
        for e in model.effect_info():
            self._defaults[e["name"]] = bool(e["value"])
        self._methods = list(model.methods)       # the solver Enumeration's items, 1, 2, ...
        self._defaults["solver"] = str(experiment["method"])
        self._defaults["rtol"] = float(experiment["rtol"])
        self._defaults["atol"] = float(experiment["atol"])
        self._defaults[PATH_SETTING] = True
        self._settings = dict(self._defaults)
        self._explicit: set[str] = set()          # settings the importer set
        self._inputs = {i["name"]: 0.0 for i in model.input_info()}
        self._inputs_pending = True               # inputs set since the stepper last took them
        self._output_names = [o["name"] for o in model.output_info()]
        self._output_index = {name: i for i, name in enumerate(self._output_names)}
        self._derived = [self._output_index[d.name] for d in model.signals.derived]
        self._undefined_noted: set[int] = set()    # derived outputs logged as NaN already

        self._phase = INSTANTIATED
        self._start_time = 0.0
        self._stop_time: float | None = None      # from fmi2SetupExperiment, where defined
        self._tolerance: float | None = None      # from fmi2SetupExperiment
        self._failure: str | None = None          # why the instance cannot step
        self._status = OK                         # of the last checked call (fmi_status)
        self._call_rejections: list[str] = []     # values rejected by the last checked call
        self._rejected: list[str] = []            # unreported rejections: the next doStep's
        self._stepper = None
        self._slave_steps = 0                     # communication steps taken here
        self._native_steps = 0                    # ... and by the FMU's binary (fmu_native)
        self._getters: dict = {}                  # (class, value references) -> their getter
        # The outputs, in the order of _output_names: calculated when first read (in
        # initialization mode from the settings and inputs set so far), so that instantiating
        # compiles nothing.
        self._outputs = [math.nan] * len(self._output_names)
        self._stale = True                        # the outputs must be evaluated again
        self._preview = None                      # (key, stepper) of initialization mode's outputs
        self._call_thread = None                  # the thread inside an FMI call that may compile

        variables = self._register(model)
        self._status_vr = variables.status_vr
        # The native doStep (inerter/fmu/native.py): the FMU's binary steps in compiled code
        # whenever this slave arms it. The derived outputs are not in its values (the kernels do not
        # evaluate them): a getter that asks for one comes here, after the slave took the steps over.
        self._native = fmu_native.NativeLink(
            variables.native_outputs,
            {vr: (kind, self.vars[vr].getter) for vr, kind in variables.native_kinds.items()})
        self._warn_if_foreign_package()

    # ------------------------------------------------------------------------------------------
    # Variables
    # ------------------------------------------------------------------------------------------
    def _register(self, model):
        """The FMU's variables, bound to this instance: copies of the class's (:func:`_variables`,
        made once per process for the scene's model), each with this instance's getter and setter."""
        variables = _variables(type(self), self.scene_digest, model)
        for proto, make_getter, make_setter in variables.specs:
            var = object.__new__(type(proto))
            # name, value reference, causality...: the class's, in attribute dicts all instances
            # share (only pythonfmu's build writes to them: the start values, read from the getters)
            var.__dict__.update(proto.__dict__)
            var.getter, var.setter = make_getter(self), make_setter(self)
            self.vars[proto.value_reference] = var
        return variables

    @classmethod
    def _variable_specs(cls, model) -> list:
        """(variable, its getter from an instance, its setter from an instance) for every variable
        of the FMU, in the order of their value references (0, 1, ...)."""
        fixed = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        tunable = dict(causality=Fmi2Causality.parameter, variability=Fmi2Variability.tunable)
        methods = ", ".join(f"{i} {m}" for i, m in enumerate(model.methods, start=1))
        specs = []

        def setting(var, name, kind):
            specs.append((var, lambda s: s._setting_getter(name), lambda s: s._setting_setter(name, kind)))

        for p in model.parameter_info():
            kind = tunable if p["name"] in cls.tunable else fixed
            note = " (tunable: may change between steps)" if p["name"] in cls.tunable else ""
            setting(ExactReal(p["name"], description=p["description"] + note, **kind), p["name"], float)
        for e in model.effect_info():
            kind = tunable if e["name"] in cls.tunable else fixed
            note = " (tunable: may change between steps)" if e["name"] in cls.tunable else ""
            setting(Boolean(e["name"], description=e["description"] + note, **kind), e["name"], bool)
        # An Integer here; the build declares it an Enumeration of the methods (pythonfmu 0.7.0
        # has no Enumeration variable), whose items are the integers 1, 2, ... in this order.
        specs.append((Integer("solver", description=f"integration method: {methods}", **fixed),
                      lambda s: s._solver_getter, lambda s: s._setting_setter("solver", s._solver_item)))
        setting(ExactReal(
            "rtol", description="relative tolerance of the integrator (fmi2SetupExperiment's "
                                "tolerance is used when rtol is not set)", **fixed), "rtol", float)
        setting(ExactReal(
            "atol", description="absolute tolerance of the integrator, in the units of each "
                                "coordinate", **fixed), "atol", float)
        setting(Boolean(
            PATH_SETTING, description="integrate with the numba-compiled kernels and integrator loops "
            "where numba is installed in the importing Python and the scene allows it (planar, no "
            "ground motion, an explicit method, Baumgarte stabilisation, no step force); false: the "
            "numpy path. Both give the same results to round-off", **fixed), PATH_SETTING, bool)
        for i in model.input_info():
            name = i["name"]
            specs.append((ExactReal(name, description=i["description"], causality=Fmi2Causality.input,
                                    variability=Fmi2Variability.continuous, start=0.0),
                          lambda s, n=name: s._input_getter(n), lambda s, n=name: s._input_setter(n)))
        for o in model.output_info():
            name = o["name"]
            specs.append((ExactReal(name, description=o["description"], causality=Fmi2Causality.output,
                                    variability=Fmi2Variability.continuous, initial=Fmi2Initial.calculated),
                          lambda s, n=name: s._output_getter(n), lambda s, n=name: s._output_setter(n)))
        # Last, so that the value references of the other variables do not depend on it.
        specs.append((Integer(
            STATUS_VARIABLE, description="status of the FMU's last exitInitializationMode, "
            "setXxx, doStep or setFMUstate call (0 fmi2OK, 2 fmi2Discard, 3 fmi2Error), which "
            "the FMU's binary returns on Linux", causality=Fmi2Causality.local,
            variability=Fmi2Variability.discrete, initial=Fmi2Initial.calculated),
            lambda s: s._read_status, lambda s: s._status_setter))
        for vr, (var, _, _) in enumerate(specs):
            var.value_reference = vr
        return specs

    def _setting_getter(self, name):
        return lambda: self._settings[name]

    def _solver_getter(self) -> int:
        method = self._settings["solver"]
        return self._methods.index(method) + 1 if method in self._methods else int(method)

    def _solver_item(self, value):
        """The method of Enumeration item `value`; an integer that is no item is kept as it is and
        refused by exitInitializationMode."""
        item = int(value)
        return self._methods[item - 1] if 1 <= item <= len(self._methods) else item

    def _setting_setter(self, name, kind):
        def setter(value):
            value = kind(value)
            if self._phase in (INSTANTIATED, INITIALIZATION):
                self._settings[name] = value
                self._explicit.add(name)
                self._stale = True
            elif name in self.tunable and self._phase == STEPPING:
                self._retune(name, value)
            else:
                kind_of = "a tunable" if name in self.tunable else "a fixed"
                self._reject(f"{name}: {kind_of} parameter cannot be changed "
                             f"{'after initialisation' if kind_of == 'a fixed' else 'now'} (got "
                             f"{value!r}; it stays {self._settings[name]!r}; phase {self._phase}); "
                             f"set it before exitInitializationMode, or reset the FMU")
        return setter

    def _retune(self, name: str, value: float):
        """A tunable parameter set between steps: the running stepper goes on from the current
        communication point with the scene's numbers read with the new value (the integration
        restarts there). A value the scene refuses, or one that would change more than the
        engine can take, is rejected and nothing changes."""
        t = self._stepper.time
        if not math.isfinite(value):
            self._reject(f"{name}: not finite (got {value!r}; expected a finite number): ignored, "
                         f"it stays {self._settings[name]!r}")
            return
        settings = dict(self._settings)
        settings[name] = value
        try:
            model = self._model_for(self._overrides(settings))
            self._stepper.retune(model.mechanism, model.signals)
        except (InerterError, ValueError) as exc:
            self._reject(f"{name}: cannot change to {value!r} at t = {t!r} s: {exc}; it stays "
                         f"{self._settings[name]!r}")
            return
        self._settings[name] = value
        self._explicit.add(name)
        self._stale = True
        self.log(f"{name} = {value!r} from t = {t!r} s on", Fmi2Status.ok)

    def _input_getter(self, name):
        return lambda: self._inputs[name]

    def _input_setter(self, name):
        def setter(value):
            value = float(value)
            if self._phase in (TERMINATED, FAILED):
                self._reject(f"{name}: an input cannot be set in the {self._phase} state (got "
                             f"{value!r}; expected a reset first: FMI 2.0 allows no setter there); "
                             f"it stays {self._inputs[name]!r}")
            elif math.isfinite(value):
                if value != self._inputs[name]:
                    self._stale = True            # the outputs that read q̈ follow at once
                self._inputs[name] = value
                self._inputs_pending = True
            else:
                self._reject(f"{name}: input not finite (got {value!r}; expected a finite "
                             f"number): ignored, it stays {self._inputs[name]!r}")
        return setter

    def _output_getter(self, name):
        index = self._output_index[name]
        return lambda: self._outputs[index]

    def _output_setter(self, name):
        def setter(value):
            self._reject(f"{name}: an output cannot be set (got {value!r})")
        return setter

    # ------------------------------------------------------------------------------------------
    # Statuses
    # ------------------------------------------------------------------------------------------
    def _begin_call(self):
        """Start a call whose status goes to fmi_status (exitInitializationMode, setXxx, doStep,
        setFMUstate). Rejections of the previous call that nobody read are left to the next
        doStep."""
        self._native.disarm()                     # the next step is taken here, at least
        if self._call_rejections:
            self._rejected.extend(self._call_rejections)
            self._call_rejections = []
        self._status = OK

    def _read_status(self) -> int:
        """fmi_status; reading an error reports the last call's rejections (the shim reads it
        after every checked call), so the next doStep does not report them again."""
        if self._status != OK:
            self._call_rejections.clear()
        return self._status

    def _status_setter(self, value):
        self._reject(f"{STATUS_VARIABLE}: a local variable cannot be set (got {value!r})")

    def _reject(self, message: str):
        """A value the importer set is refused: log it; the call returns fmi2Error."""
        self._status = ERROR
        self._call_rejections.append(message)
        self.log(message, Fmi2Status.error)

    # pythonfmu's get_*/set_* raise on a wrong value reference or type, which would end the
    # instance with fmi2Fatal: these log the problem instead.
    def _get(self, vrs, cls, kind, fallback):
        # The fast path: a plan per (class, value references), made once (see _plan).
        key = (cls, tuple(vrs))
        plan = self._getters.get(key)
        if plan is None:
            if len(self._getters) > 64:           # an importer asking for ever new sets
                self._getters.clear()
            plan = self._getters[key] = self._plan(vrs, cls, kind)
        if plan is not None:
            try:
                return plan()
            except Exception:
                pass                              # the slow path below logs each problem
        values = []
        for vr in vrs:
            var = self.vars.get(vr)
            try:
                if not isinstance(var, cls):
                    raise TypeError(f"valueReference {vr} is not a {cls.__name__} variable")
                values.append(kind(var.getter()))
            except Exception as exc:
                self.log(f"get{cls.__name__}: {exc}", Fmi2Status.error)
                values.append(fallback)
        return values

    def _plan(self, vrs, cls, kind):
        """A function returning the values of `vrs` (all of class `cls`), or None when one is not:
        the outputs straight from the list of the last step's values, the others through their
        getters. Taken at every step for the recorded variables; isinstance on pythonfmu's
        variable classes alone costs about a microsecond per variable and call."""
        variables = [self.vars.get(vr) for vr in vrs]
        if not vrs or not all(isinstance(var, cls) for var in variables):
            return None
        if kind is float and all(var.causality == Fmi2Causality.output for var in variables):
            pick = operator.itemgetter(*[self._output_index[var.name] for var in variables])
            if len(variables) == 1:
                return lambda: [pick(self._outputs)]
            return lambda: list(pick(self._outputs))
        getters = [var.getter for var in variables]
        return lambda: [kind(g()) for g in getters]

    def _set(self, vrs, values, cls):
        self._native.stale = True
        for vr, value in zip(vrs, values):
            var = self.vars.get(vr)
            try:
                if not isinstance(var, cls):
                    raise TypeError(f"valueReference {vr} is not a {cls.__name__} variable")
                var.setter(value)
            except Exception as exc:
                self._reject(f"set{cls.__name__}: {exc}")

    def _early(self, call: str, vrs):
        """Log an error for a getter called before initialization mode (FMI 2.0 allows none in
        the instantiated state): the status shim returns fmi2Error; the values are given anyway."""
        self.log(f"{call}: called before fmi2EnterInitializationMode (value references "
                 f"{list(vrs)}; expected fmi2EnterInitializationMode first: FMI 2.0 allows no getter "
                 f"in the instantiated state)", Fmi2Status.error)

    def get_real(self, vrs):
        if len(vrs) == 1 and vrs[0] == fmu_native.TIME_VR:
            return [self._time()]
        if len(vrs) == 1 and vrs[0] == fmu_native.STOP_VR:
            return [math.nan if self._stop_time is None else float(self._stop_time)]
        if self._phase == INSTANTIATED:
            self._early("fmi2GetReal", vrs)
        if self._stale:
            self._refresh_outputs()
        return self._get(vrs, Real, float, math.nan)

    def _time(self) -> float:
        """The end of the last step completed: the stepper's time, else the start time."""
        return float(self._stepper.time) if self._stepper is not None else self._start_time

    def get_integer(self, vrs):
        if len(vrs) == 2 and vrs[0] == fmu_native.LINK_VR and vrs[1] == fmu_native.LINK_VR + 1:
            return self._native.address_words()
        if len(vrs) == 1 and vrs[0] == fmu_native.PHASE_VR:
            return [PHASES.index(self._phase)]
        if self._phase == INSTANTIATED and list(vrs) != [self._status_vr]:   # the shim reads that
            self._early("fmi2GetInteger", vrs)
        return self._get(vrs, Integer, int, 0)

    def get_boolean(self, vrs):
        if self._phase == INSTANTIATED:
            self._early("fmi2GetBoolean", vrs)
        return self._get(vrs, Boolean, bool, False)

    def get_string(self, vrs):
        if self._phase == INSTANTIATED:
            self._early("fmi2GetString", vrs)
        return self._get(vrs, String, str, "")

    def set_real(self, vrs, values):
        self._begin_call()
        self._set(vrs, values, Real)

    def set_integer(self, vrs, values):
        if len(vrs) == 1 and vrs[0] == fmu_native.SYNC_VR:
            self._native_sync()
            return
        self._begin_call()
        self._set(vrs, values, Integer)

    def set_boolean(self, vrs, values):
        self._begin_call()
        self._set(vrs, values, Boolean)

    def set_string(self, vrs, values):
        if len(vrs) == 1 and vrs[0] == fmu_native.STATE_CHECK_VR:
            self._check_serialized(values[0])
            return
        self._begin_call()
        self._set(vrs, values, String)

    # ------------------------------------------------------------------------------------------
    # Initialisation
    # ------------------------------------------------------------------------------------------
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        if self._phase != INSTANTIATED:
            self._out_of_order("fmi2SetupExperiment", "before fmi2EnterInitializationMode")
            return
        self._start_time = float(start_time)
        self._stop_time = None if stop_time is None else float(stop_time)
        self._tolerance = None if tolerance is None else float(tolerance)

    def enter_initialization_mode(self):
        if self._phase != INSTANTIATED:
            self._out_of_order("fmi2EnterInitializationMode", "once, after fmi2Instantiate or fmi2Reset")
            return
        self._phase = INITIALIZATION

    def _out_of_order(self, call: str, expected: str):
        """Log an error for a call FMI 2.0 does not allow in the instance's state: the status shim
        returns fmi2Error; the call changes nothing."""
        self.log(f"{call}: refused in the {self._phase} state (expected it {expected}); nothing "
                 f"changes", Fmi2Status.error)

    def exit_initialization_mode(self):
        self._begin_call()
        try:
            with self._compile_notices():
                self._initialise()
        except Exception as exc:  # a bug: report it rather than end the importer with fmi2Fatal
            self._fail(f"exitInitializationMode: unexpected error: {exc!r}\n{traceback.format_exc()}")

    def _effective_settings(self) -> dict:
        settings = dict(self._settings)
        if "rtol" not in self._explicit and self._tolerance is not None:
            settings["rtol"] = self._tolerance
        return settings

    def _overrides(self, settings: dict) -> dict:
        """The `inerter.load` overrides for the parameters and effects that differ from the scene's
        (the solver settings need no new load: see _new_stepper)."""
        return {name: value for name, value in settings.items()
                if name != PATH_SETTING and name not in SOLVER_SETTINGS
                and not _same(value, self._defaults[name])}

    def _model_for(self, overrides: dict):
        key = tuple(sorted(overrides.items(), key=lambda kv: kv[0]))
        model = self._models.get(key)
        if model is None:                             # a value the scene refuses is named as the FMU's
            model = inerter.Model(self.scene_path, overrides,
                                  origins={k: f"FMU parameter {k} = {v!r}" for k, v in overrides.items()})
            if len(self._models) > 8:                 # the scene's own model stays
                for other in [k for k in self._models if k]:
                    del self._models[other]
            self._models[key] = model
        return model

    def _new_stepper(self, settings: dict):
        """Load the scene with `settings` and return a stepper at t = 0 (raises InerterError)."""
        for name, value in settings.items():
            if isinstance(value, float) and not math.isfinite(value):
                raise ValueError(f"{self.scene_file}: {name}: not finite (got {value!r}; "
                                 f"expected a finite number)")
        if settings["solver"] not in self._methods:
            items = ", ".join(f"{i} ({m})" for i, m in enumerate(self._methods, start=1))
            raise ValueError(f"{self.scene_file}: solver: no such item (got {settings['solver']!r}; "
                             f"expected one of {items})")
        model = self._model_for(self._overrides(settings))
        path = "compiled" if settings[PATH_SETTING] else "numpy"
        changed = {field: settings[name] for name, field in SOLVER_SETTINGS.items()
                   if not _same(settings[name], self._defaults[name])}
        if not changed:                               # the scene's own solver settings
            return model.stepper(path=path, stop_time=self._stop_time)
        # The solver settings that differ from the scene's, read and checked as a load with
        # experiment.method/rtol/atol overrides would read them (same defaults, same errors).
        experiment = model.scene.experiment_with(changed)
        return model.stepper(method=experiment.method, rtol=experiment.rtol, atol=experiment.atol, path=path,
                             stop_time=self._stop_time)

    def _initialise(self):
        if self._phase != INITIALIZATION:
            self._status = ERROR
            self._out_of_order("fmi2ExitInitializationMode", "after fmi2EnterInitializationMode")
            return
        if self._start_time != 0.0:
            self._fail(f"exitInitializationMode: the scene starts at t = 0 s (got startTime = "
                       f"{self._start_time!r} s from fmi2SetupExperiment; expected 0)")
            return
        if self._stop_time is not None and not self._stop_time >= 0.0:     # NaN too
            self._fail(f"exitInitializationMode: {self.scene_file}: stopTime: before the start (got stopTime = "
                       f"{self._stop_time!r} s from fmi2SetupExperiment; expected a stop time ≥ startTime = 0 s)")
            return
        settings = self._effective_settings()
        try:
            stepper = self._preview_stepper(settings)
            outputs = [float(v) for v in stepper.output_values()]
        except (InerterError, ValueError) as exc:
            changed = ", ".join(f"{k} = {v!r}" for k, v in settings.items()
                                if not _same(v, self._defaults[k]))
            origin = ("" if "rtol" in self._explicit or self._tolerance is None
                      or _same(settings["rtol"], self._defaults["rtol"])
                      else " (rtol from fmi2SetupExperiment's tolerance)")
            self._fail(f"exitInitializationMode: {exc} [settings changed from the scene: "
                       f"{changed or 'none'}{origin}]")
            return
        self._stepper, self._outputs, self._phase = stepper, outputs, STEPPING
        self._preview = None
        self._stale = False
        self._native.stale = True
        self._inputs_pending = False              # the stepper holds them (_preview_stepper)
        changed = ", ".join(f"{k} = {v!r}" for k, v in settings.items()
                            if not _same(v, self._defaults[k]))
        used = stepper.settings          # atol follows rtol where the scene states no atol
        self.log(f"initialised at t = 0 s with solver {used.method}, "
                 f"rtol {used.rtol:g}, atol {used.atol:g}, {stepper.path} path; "
                 f"changed from the scene: {changed or 'nothing'}", Fmi2Status.ok)
        if not self._rejected:                    # else the first doStep reports them (_refusal)
            self._arm_native(stepper, start=True)   # the first step may be native too

    def _preview_stepper(self, settings: dict):
        """A stepper at t = 0 for `settings` with the inputs set so far: the one initialization
        mode's outputs came from, when nothing changed since (raises as _new_stepper)."""
        key = json.dumps([sorted((k, repr(v)) for k, v in settings.items()),
                          sorted(self._inputs.items()), self._stop_time])
        if self._preview is None or self._preview[0] != key:
            self._preview = None
            stepper = self._new_stepper(settings)
            self._push_inputs(stepper)
            self._preview = (key, stepper)
        return self._preview[1]

    def _push_inputs(self, stepper):
        for name, value in self._inputs.items():
            stepper.set_input(name, value)
        self._inputs_pending = False

    def _refresh_outputs(self):
        """The outputs at the current time, for the settings and inputs as they are now: in
        initialization mode those of t = 0 with the settings set so far, while stepping after an
        input or a tunable parameter changed at the communication point."""
        self._stale = False
        try:
            with self._compile_notices():
                if self._phase in (INSTANTIATED, INITIALIZATION):
                    stepper = self._preview_stepper(self._effective_settings())
                elif self._phase == STEPPING:
                    stepper = self._stepper
                    self._push_inputs(stepper)
                else:
                    return
                self._outputs = [float(v) for v in stepper.output_values()]
        except (InerterError, ValueError) as exc:
            self._outputs = [math.nan] * len(self._output_names)
            self.log(f"the outputs cannot be calculated (they read NaN): {exc}",
                     Fmi2Status.warning if self._phase != STEPPING else Fmi2Status.error)
        except Exception as exc:  # a bug: report it rather than end the importer with fmi2Fatal
            self._outputs = [math.nan] * len(self._output_names)
            self.log(f"the outputs cannot be calculated (they read NaN): unexpected error: "
                     f"{exc!r}\n{traceback.format_exc()}", Fmi2Status.error)

    @contextlib.contextmanager
    def _compile_notices(self):
        """While the engine may compile its kernels (its first use on a machine: about a minute),
        its CompileNotice writes to the FMU's logger: at once through the status shim (Linux),
        else when the call returns (pythonfmu delivers its messages then)."""
        notice = _compile_notice()
        if notice is None or self._call_thread is not None:
            yield
            return
        previous = notice.stream, notice.eager
        notice.stream = _LogLines(self._log_now)
        notice.eager = True                       # said on this thread, which may log at once
        self._call_thread = threading.get_ident()
        try:
            yield
        finally:
            notice.stream, notice.eager = previous
            self._call_thread = None

    def log(self, msg: str, status: Fmi2Status = Fmi2Status.ok, category=None, debug=None):
        """pythonfmu's log, with the files of resources/ named as the user knows them (below); a
        message of a status the importer must act on names the scene file where it does not."""
        msg = self._named_files(msg)
        if status in (Fmi2Status.discard, Fmi2Status.error, Fmi2Status.fatal) and self.scene_file \
                and self.scene_file not in msg:
            msg = f"{self.scene_file}: {msg}"
        super().log(msg, status, category, debug)

    def _named_files(self, message: str) -> str:
        """`message` with the FMU's resources/ folder left out of the file names it holds: the
        scene file and its ground records are named as in the scene (``two_bar_2d.toml``,
        ``records/x.csv``), not by the importer's temporary folder it unzipped the FMU into."""
        for prefix in self._resource_prefixes:
            message = message.replace(prefix, "")
        return message

    def _log_now(self, message: str, status: Fmi2Status = Fmi2Status.ok):
        """Log `message` to the importer at once where the status shim gives its logger (on the
        thread of the call in progress), else through pythonfmu's queue."""
        message = self._named_files(message)
        category = f"logStatus{status.name.capitalize()}"
        if category not in self.log_categories:
            category = "logAll"
        if threading.get_ident() != self._call_thread or \
                not self._native.live_log(int(status), category, message):
            self.log(message, status)

    def _fail(self, message: str):
        self._native.disarm()
        self._status = ERROR
        self._phase = FAILED
        self._failure = message
        self._stepper = None
        self._outputs = [math.nan] * len(self._output_names)
        self.log(f"{message}; the FMU cannot step: every doStep is refused until it "
                 f"is reset", Fmi2Status.error)

    # ------------------------------------------------------------------------------------------
    # Stepping
    # ------------------------------------------------------------------------------------------
    def do_step(self, current_time, step_size):
        self._begin_call()
        try:
            with self._compile_notices():
                return self._do_step(float(current_time), float(step_size))
        except Exception as exc:  # a bug: stop stepping rather than end the importer
            self._fail(f"doStep at t = {current_time!r} s: unexpected error: {exc!r}\n"
                       f"{traceback.format_exc()}")
            return False

    def _refuse(self, message: str, status: Fmi2Status = Fmi2Status.error) -> bool:
        """doStep returns False and logs why: fmi2Error for a step refused (a call FMI 2.0 does
        not allow: no running integration, a step size not > 0, a step not starting at the
        current communication point or ending past stopTime), fmi2Discard for a step the solver
        could not complete (`status` discard). pythonfmu's binary returns fmi2Discard for both;
        the status shim returns fmi_status."""
        self._status = DISCARD if status == Fmi2Status.discard else ERROR
        self.log(message, status)
        return False

    def _do_step(self, t: float, h: float) -> bool:
        why = self._refusal(t, h)
        if why is not None:
            return self._refuse(f"doStep at t = {t!r} s (step {h!r} s) refused{why}")
        stepper = self._stepper
        if self._inputs_pending:
            for name, value in self._inputs.items():
                stepper.set_input(name, value)
            self._inputs_pending = False
        return self._advance(stepper, t, h)

    def _refusal(self, t: float, h: float) -> str | None:
        """Why a doStep(t, h) cannot be taken (the end of the message), or None when it can."""
        if self._rejected:
            messages = "; ".join(self._rejected)
            self._rejected.clear()
            return f", once, to report values rejected since the last step: {messages}"
        if self._phase == FAILED:
            return f": {self._failure}"
        if self._phase == TERMINATED:
            return ": the FMU is terminated (reset it to run again)"
        if self._phase != STEPPING:
            return ": the FMU is not initialised yet (call exitInitializationMode first)"
        if self._inputs_pending:
            bad = [f"{name} = {value!r}" for name, value in self._inputs.items()
                   if not math.isfinite(value)]
            if bad:
                return (f": input not finite ({', '.join(bad)}; expected finite numbers); the "
                        f"state is unchanged")
        if not (math.isfinite(h) and h > 0.0):
            return ": the step size must be a finite number > 0"
        now = self._stepper.time
        if abs(t - now) > TIME_TOLERANCE * max(1.0, abs(t), abs(now)):
            return (f": the FMU is at t = {now!r} s; a step must start where the last one ended "
                    f"(or roll back with fmi2SetFMUstate)")
        stop = self._stop_time
        if stop is not None and t + h > stop + TIME_TOLERANCE * max(1.0, abs(stop)):
            return (f": it would end at t = {t + h!r} s, past stopTime = {stop!r} s of "
                    f"fmi2SetupExperiment (expected an end ≤ stopTime: FMI 2.0 makes a step past it "
                    f"an error); the state is unchanged")
        return None

    def _advance(self, stepper, t: float, h: float) -> bool:
        try:
            stepper.step(t + h)
        except SimulationError as exc:
            return self._refuse(f"doStep at t = {t!r} s (step {h!r} s) discarded: {exc}; the FMU "
                                f"stays at t = {stepper.time!r} s", Fmi2Status.discard)
        self._outputs = stepper.output_values()    # floats, in the order of _output_names
        self._stale = False
        self._slave_steps += 1
        self._note_undefined_outputs(stepper.time)
        self._arm_native(stepper)
        return True

    def _note_undefined_outputs(self, t):
        """Log, once per derived output, the first communication point where it has no value."""
        for i in self._derived:
            if i not in self._undefined_noted and not math.isfinite(self._outputs[i]):
                self._undefined_noted.add(i)
                self.log(f"outputs.derived.{self._output_names[i]}: no value at t = {t!r} s (NaN): its "
                         f"expression is undefined there", Fmi2Status.warning)

    def _arm_native(self, stepper, start: bool = False):
        """Let the FMU's binary take the next step natively where it can (inerter/fmu/native.py);
        `start`: at the end of initialisation, where the integration is not running yet."""
        try:
            self._native.arm(stepper, TIME_TOLERANCE, start=start)
        except Exception as exc:  # the steps go on here, as without the link
            self._native.turn_off(repr(exc))
            self.log(f"native doStep turned off, the steps go on in Python: {exc!r}",
                     Fmi2Status.warning)

    def _native_sync(self):
        """Take over the steps the FMU's binary took natively since the last step here (the shim
        asks before any other call enters Python after them)."""
        try:
            taken = self._native.sync(self._stepper)
            if taken:
                self._native_steps += taken
                self._outputs = self._stepper.output_values()
                self._stale = False
                self._note_undefined_outputs(self._stepper.time)
        except Exception as exc:  # a bug: stop stepping rather than end the importer
            self._fail(f"taking over the native steps: unexpected error: {exc!r}\n"
                       f"{traceback.format_exc()}")

    def terminate(self):
        self._native.disarm()
        if self._phase not in (STEPPING, FAILED):
            self._out_of_order("fmi2Terminate", "after fmi2ExitInitializationMode, once")
            return
        self._phase = TERMINATED
        total = self._slave_steps + self._native_steps
        self.log(f"terminated: {total} communication steps, {self._native_steps} of them taken in "
                 f"native code by the FMU's binary"
                 + (f" (native steps off: {self._native.why_off})" if self._native.why_off else ""),
                 Fmi2Status.ok)

    # ------------------------------------------------------------------------------------------
    # FMU state
    # ------------------------------------------------------------------------------------------
    def _get_fmu_state(self):
        if self._stale and self._phase == STEPPING:
            self._refresh_outputs()               # the state holds the outputs of its inputs
        try:
            return {
                "format": STATE_FORMAT,
                "scene_file": self.scene_file,
                "scene": self.scene_digest,
                "build": self.build,
                "phase": self._phase,
                "failure": self._failure,
                "settings": dict(self._settings),
                "explicit": sorted(self._explicit),
                "start_time": self._start_time,
                "tolerance": self._tolerance,
                "inputs": dict(self._inputs),
                "stop_time": self._stop_time,
                "outputs": list(self._outputs),
                "stepper": None if self._stepper is None else bytes(self._stepper.get_state()),
            }
        except Exception as exc:
            self.log(f"getFMUstate: {exc!r}; the state returned cannot be restored",
                     Fmi2Status.error)
            return {"format": None, "error": repr(exc)}

    def _set_fmu_state(self, state):
        self._begin_call()
        try:
            self._restore(state)
        except Exception as exc:
            self._status = ERROR
            self.log(f"{self.scene_file}: setFMUstate: the state could not be restored ({exc!r}); the FMU "
                     f"is unchanged", Fmi2Status.error)

    def _check_serialized(self, text: str):
        """The bytes given to fmi2DeSerializeFMUstate, in hex (the status shim sends them to the
        private String fmu_native.STATE_CHECK_VR first): log an error where they are not a state this
        FMU can restore, so that the shim returns fmi2Error; nothing changes."""
        try:
            data = bytes.fromhex(text)
        except (TypeError, ValueError) as exc:       # the shim's encoding: a bug
            self.log(f"{self.scene_file}: fmi2DeSerializeFMUstate: the bytes did not reach the "
                     f"FMU's Python ({exc!r}); no FMU state is made", Fmi2Status.error)
            return
        try:
            self._checked(self._fmu_state_from_bytes(data), dry=True)
        except Exception as exc:
            why = (f"no {exc.args[0]!r} in it" if isinstance(exc, KeyError) else
                   str(exc) if isinstance(exc, ValueError) else repr(exc))
            self.log(f"{self.scene_file}: fmi2DeSerializeFMUstate: {len(data)} bytes that are not a "
                     f"serialized state of this FMU: {why}; no FMU state is made, the instance is "
                     f"unchanged", Fmi2Status.error)

    def _checked(self, state, dry: bool = False) -> tuple[dict, object]:
        """(settings, stepper) of `state` when it is a state of this FMU, the stepper (None where
        the state has none) restored from it; raises ValueError saying why where it is not.
        `dry`: the solver state is only read (as the stepper reads it: only the globals a state
        holds are looked up, so crafted bytes run nothing; inerter.engine.simulation.load_state),
        no stepper is made (stepper None). Nothing of the instance changes."""
        if not isinstance(state, dict) or state.get("format") != STATE_FORMAT:
            got = state.get("format") if isinstance(state, dict) else None
            raise ValueError(
                (state["error"] if isinstance(state, dict) and "error" in state else
                 f"format {got!r}" if isinstance(got, str) else "no format")
                + f" (expected format {STATE_FORMAT!r}, of a state serialized by this FMU)")
        if state.get("scene") != self.scene_digest:
            other = state.get("scene_file")
            raise ValueError(f"it is a state of {other}, not of {self.scene_file}"
                             if other != self.scene_file else
                             f"it is a state of another version of {self.scene_file} (the scene "
                             f"file's digest differs)")
        if state.get("build") != self.build:
            raise ValueError(f"it was saved by another build of the FMU of {self.scene_file} "
                             f"(build {str(state.get('build'))[:12]}, this FMU's {self.build[:12]}): "
                             f"its solver state may not be this one's")
        settings = dict(state["settings"])
        if set(settings) != set(self._defaults) or set(state["inputs"]) != set(self._inputs) \
                or len(state["outputs"]) != len(self._output_names):
            raise ValueError("the state's variables differ from this FMU's")
        if state["phase"] not in PHASES:
            raise ValueError(f"unknown phase {state['phase']!r} (expected one of {PHASES})")
        stepper = None
        if dry and state["stepper"] is not None:
            try:
                solver = load_state(state["stepper"])
            except Exception as exc:
                raise ValueError(f"its solver state cannot be read ({exc!r})") from None
            if not isinstance(solver, tuple):
                raise ValueError(f"its solver state is a {type(solver).__name__}, not a tuple")
        elif state["stepper"] is not None:
            effective = dict(settings)
            if "rtol" not in state["explicit"] and state["tolerance"] is not None:
                effective["rtol"] = state["tolerance"]
            stepper = self._new_stepper(effective)
            stepper.set_state(state["stepper"])
        return settings, stepper

    def _restore(self, state):
        settings, stepper = self._checked(state)
        # Everything checked: commit.
        self._native.stale = True
        self._settings = settings
        self._explicit = set(state["explicit"])
        self._phase = state["phase"]
        self._failure = state["failure"]
        self._start_time = state["start_time"]
        self._stop_time = state["stop_time"]
        self._tolerance = state["tolerance"]
        self._inputs = dict(state["inputs"])
        self._inputs_pending = True
        self._outputs = list(state["outputs"])
        self._stale = self._phase in (INSTANTIATED, INITIALIZATION)
        self._preview = None
        self._stepper = stepper

    @staticmethod
    def _fmu_state_to_bytes(state) -> bytes:
        if not isinstance(state, dict):
            return json.dumps({"format": None, "error": "not a state"}).encode()
        data = dict(state)
        if data.get("stepper") is not None:
            data["stepper"] = base64.b64encode(data["stepper"]).decode("ascii")
        return json.dumps(data).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(data: bytes):
        # pythonfmu calls it on the class: bytes that are no state give a state that
        # setFMUstate refuses with fmi2Error and the reason (with the status shim,
        # fmi2DeSerializeFMUstate refuses them first: _check_serialized)
        data = bytes(data)
        if not data:
            return {"format": None, "error": "no bytes"}
        try:
            state = json.loads(data.decode("utf-8"))
        except UnicodeDecodeError as exc:
            return {"format": None, "error": f"not text (UTF-8): {exc.reason} at byte {exc.start}"}
        except ValueError as exc:                 # json.JSONDecodeError: truncated, not JSON
            return {"format": None, "error": f"not JSON, or cut short: {exc}"}
        if not isinstance(state, dict):
            return {"format": None, "error": f"JSON {type(state).__name__}, not an object"}
        try:
            if state.get("stepper") is not None:
                state["stepper"] = base64.b64decode(state["stepper"], validate=True)
        except Exception as exc:
            return {"format": None, "error": f"its solver state is not base64: {exc}"}
        return state

    # ------------------------------------------------------------------------------------------
    def _warn_if_foreign_package(self):
        message = _foreign_package()
        if message:
            self.log(message, Fmi2Status.warning)
