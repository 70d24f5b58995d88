"""Scene files: TOML → validated, fully numeric scene description.

A scene is read once, every field is checked against the schema below, every expression is
evaluated against the scene's parameters (after command-line / FMU overrides), and the result is
a plain, immutable :class:`Scene`. Nothing later re-reads the file.

Errors name the file, the field path (``elements.inerter.b``), the value and what was expected
(:class:`~inerter.common.errors.SceneError`). Unknown fields are errors, never silently ignored.
"""
from __future__ import annotations

import difflib
import math

import numpy as np
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

from inerter import elements
from inerter.common.errors import SceneError
from inerter.common.rotations import EULER_SEQUENCES
from inerter.elements.device import EFFECT as DEVICE_EFFECT
from inerter.elements.device import Device, check_device
from inerter.scene import units
from inerter.scene.expressions import (RESERVED_NAMES, UnitError, ambiguous_units, evaluate, output_expression,
                                       parameter_meta, read_parameters)
from inerter.scene.overrides import attributed, origin_of
from inerter.scene.files import MAX_RECORD_BYTES, MAX_RECORD_SAMPLES, MAX_SCENE_BYTES, read_capped

GROUND = "ground"

#: Effects a scene may declare, with their meaning (the compiled model lists which are on).
KNOWN_EFFECTS = {
    "centripetal": "inerter force with the centripetal term, F = b d²L/dt² (Eq. 9); "
                   "false gives the uncorrected F = b r̈·r̂ (Eq. 8)",
    "small_displacement": "inerters act along their initial direction with F = b ê0·(r̈_b − r̈_a), the "
                          "linear element of structural codes (OpenSees-style); true overrides centripetal",
    "gravity": "uniform gravity, a vector in m/s²",
    "ground_acceleration": "the ground moved with a prescribed acceleration (a CSV record, a sine or FMU "
                           "inputs ground.a[i]); coordinates are relative to the ground",
}

#: The element kinds (inerter.elements: one module each, with its parameters).
ELEMENT_TYPES = tuple(elements.KINDS)
JOINT_TYPES = ("revolute", "prismatic", "screw")
JOINT_TYPES_3D = ("spherical", "revolute", "prismatic", "fixed", "cylindrical", "universal", "planar", "screw")
#: The joint kinds that take an axis (in P1's frame): the sliding or turning axis, a universal
#: joint's first axis (fixed in P1's body), a planar joint's normal.
_AXIS_JOINTS = {2: ("prismatic", "screw"), 3: ("revolute", "prismatic", "cylindrical", "universal", "planar", "screw")}
ORIENTATIONS = ("quaternion", "euler_zxz")
FORCE_FUNCTIONS = ("constant", "sine", "step", "input", "pd")
#: The SI unit of each field of a point force.
FORCE_UNITS = {"value": "N", "amplitude": "N", "frequency": "Hz", "phase": "rad", "offset": "N", "time": "s",
               "initial": "N", "kp": "N/m", "kd": "N.s/m", "reference": "m"}
METRIC_KINDS = ("natural_frequency", "free_oscillation", "harmonics", "steady_state", "peak")
#: The names of the values each kind of metric gives (before its prefix): two metrics whose names
#: meet would overwrite one another in ``result.metrics`` and summary.json.
METRIC_VALUES = {"natural_frequency": ("natural_frequency", "natural_frequencies"), "peak": ("peak",),
                 "free_oscillation": ("fundamental_frequency", "fundamental_amplitude", "mean_offset"),
                 "harmonics": ("mean", "amplitude"), "steady_state": ("peak_to_peak", "mean_offset")}
METHODS = ("DOP853", "RK45", "Radau", "BDF", "LSODA", "RK4")
CONSTRAINT_TREATMENTS = ("baumgarte", "projection")
#: The relative tolerances the integrators take (inclusive).
RTOL_RANGE = (1e-14, 0.1)
#: The smallest absolute tolerance (state units): the integrators' error norms square the errors
#: scaled by atol, which overflow below about 1e-150 (two_bar_2d at atol 1e-200: DOP853's step size
#: collapsed at t = 5e-125 s, scipy's Radau factorised an infinite matrix)
ATOL_MIN = 1e-100
#: The longest scene name: it names output files (``<name>_uncorrected.summary.json``), the FMU and
#: its binary (``<name>.pythonfmu.so``), which must stay within the 255 bytes a file name may have.
MAX_SCENE_NAME = 100
#: The most output samples (stop_time / output_interval, or / communication_step) a run may have.
MAX_OUTPUT_SAMPLES = 1_000_000


# ----------------------------------------------------------------------------------------------
# The validated scene
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Parameter:
    name: str
    value: float                    # SI
    unit: str                       # the SI unit of `value` ("m" for a parameter given in mm)
    description: str
    given: str = ""                 # the value as the scene gave it, where its unit is not SI: "1500 mm"
    read: Any = field(default=None, repr=False, compare=False)   # its ParameterValue (unit, dimension)


@dataclass(frozen=True)
class Body:
    name: str
    mass: float
    inertia: Any                    # 2D: J about the centre of mass; 3D: 3×3 tensor in the body frame
    position: tuple[float, ...]
    angle: float                    # 2D
    velocity: tuple[float, ...]
    angular_velocity: Any           # 2D: θ̇; 3D: ω in the global frame
    rotation: Any = None            # 3D: initial rotation matrix (3×3 tuple)
    massless: bool = False          # mass (and inertia) may be 0: the body is carried by inerters


@dataclass(frozen=True)
class Point:
    name: str
    body: str                 # a body name, or GROUND
    local: tuple[float, ...]  # coordinates in the body frame (global for the ground)


@dataclass(frozen=True)
class Joint:
    name: str
    type: str                 # one of JOINT_TYPES (2D) or JOINT_TYPES_3D
    point_a: str
    point_b: str
    axis: tuple[float, ...] | None = None   # the joint's axis in the frame of point_a's body (_AXIS_JOINTS)
    axis2: tuple[float, ...] | None = None  # universal: the second axis, fixed in point_b's body, given in
                                            # point_a's frame at the initial pose (perpendicular to axis)
    stiffness: float = 0.0    # revolute (N.m/rad), prismatic (N/m): a spring about / along the joint, and
    damping: float = 0.0      # a damper (N.m.s/rad, N.s/m): the elements JOINT_spring and JOINT_damper
    lead: float = 0.0         # screw: b's advance along the axis per turn relative to a (m; negative: left-handed)
    coupling_only: bool = False   # screw: only the row tying the turn to the advance, not the cylindrical rows


@dataclass(frozen=True)
class Element:
    name: str
    type: str                 # one of ELEMENT_TYPES
    point_a: str | None = None
    point_b: str | None = None
    body_a: str | None = None  # rotational elements
    body_b: str | None = None
    coefficient: float = 0.0   # k, c or b
    free_length: float | None = None  # spring: L0 (None: the initial distance); rotational: free angle
    axis: tuple[float, ...] | None = None   # 3D rotational elements: axis in body a's frame
    device: Any = None         # an inerter's declared device (inerter.elements.device.Device), or None
    slider_axis: tuple[float, ...] | None = None   # a prismatic joint's spring or damper: it acts along the
                                                   # joint's axis (point_a's body frame), L the signed slide


@dataclass(frozen=True)
class Force:
    name: str
    point: str
    function: str                    # one of FORCE_FUNCTIONS
    direction: tuple[float, ...] | None
    amplitude: float = 0.0
    frequency: float = 0.0
    phase: float = 0.0
    offset: float = 0.0
    value: float = 0.0
    time: float = 0.0
    initial: float = 0.0
    kp: float = 0.0            # pd: F = −kp (d·r − reference) − kd d·v, along d
    kd: float = 0.0
    reference: float = 0.0


@dataclass(frozen=True)
class Metric:
    kind: str
    prefix: str
    signal: str | None = None
    reference: float | None = None   # None: the signal's value at static equilibrium
    period: float | None = None
    periods: int = 10
    period_of: str | None = None


@dataclass(frozen=True)
class Derived:
    """A derived output (``[outputs.derived]``): an expression over other outputs, evaluated at
    every sample, in CSV, summary, Result and FMU like any output."""
    name: str
    expression: Any                  # its OutputExpression (inerter.scene.expressions)
    unit: str                        # SI: inferred from the outputs it reads, or declared
    description: str


@dataclass(frozen=True)
class Experiment:
    stop_time: float
    output_interval: float
    method: str
    rtol: float
    atol: float
    constraint: str
    baumgarte: float
    communication_step: float
    step: float
    max_steps: int


@dataclass(frozen=True)
class Scene:
    source: str
    name: str
    description: str
    dimension: int
    orientation: str
    parameters: dict[str, Parameter]
    effects: dict[str, Any]
    bodies: dict[str, Body]
    points: dict[str, Point]
    joints: dict[str, Joint]
    elements: dict[str, Element]
    forces: dict[str, Force]
    experiment: Experiment
    metrics: tuple[Metric, ...]
    derived: tuple[Derived, ...] = ()   # [outputs.derived], in their order (one may read those before it)
    euler_sequence: str = "zyx"   # 3D: the intrinsic sequence of the bodies' B.euler[i] outputs (yaw, pitch,
                                  # roll: singular at ±90° pitch, not at the reference pose as Z-X-Z is)
    raw: dict = field(repr=False, default_factory=dict)
    experiment_overrides: dict = field(repr=False, default_factory=dict)   # experiment.NAME given at load

    @property
    def centripetal(self) -> bool:
        return bool(self.effects.get("centripetal", True)) and not self.small_displacement

    @property
    def small_displacement(self) -> bool:
        """Inerters under the small-displacement law (a fixed direction, no centripetal term)."""
        return bool(self.effects.get("small_displacement", False))

    @property
    def inerter_law(self) -> str:
        """Which of the three inerter laws the scene's inerters follow."""
        if self.small_displacement:
            return "small-displacement law (F = b ê0·r̈ along the initial direction ê0)"
        return "with centripetal term (Eq. 9)" if self.centripetal else "without centripetal term (Eq. 8)"

    def experiment_with(self, overrides: Mapping[str, Any], source: str | None = None) -> Experiment:
        """The experiment with `overrides` (``{"rtol": 1e-6}``) on top of those the scene was
        loaded with, read and checked as a load with ``experiment.NAME`` overrides would (the same
        function: same defaults, same errors), without rebuilding the scene. `source` names where
        the overrides come from in errors (default: the scene file)."""
        r = _Reader(source or self.source, {n: p.value for n, p in self.parameters.items()},
                    {n: p.read for n, p in self.parameters.items()})
        return _read_experiment(r, self.raw.get("experiment", {}), dict(self.experiment_overrides, **overrides))

    @property
    def data_files(self) -> list[str]:
        """Files the scene reads besides itself (paths relative to the scene file)."""
        g = self.effects.get("ground_acceleration")
        return list(g.files) if g is not None else []

    @property
    def warnings(self) -> list[str]:
        """What the scene does that its author may not expect (a record that does not end at rest)."""
        g = self.effects.get("ground_acceleration")
        return list(g.warnings) if g is not None else []


# ----------------------------------------------------------------------------------------------
# Reading helpers: each checks one field and names it in its error
# ----------------------------------------------------------------------------------------------
class _Reader:
    """Reads fields of one scene: `names` are the parameters' SI values, `dims` their units (the
    dimension an expression over them has is checked against each field's unit)."""

    def __init__(self, source: str, names: Mapping[str, float], dims: Mapping | None = None):
        self.source = source
        self.names = names
        self.dims = dims or {}

    def evaluate(self, expr, path, unit=None):
        return evaluate(expr, self.names, self.source, path, unit, self.dims)

    def error(self, fld, value, expected, problem=None):
        return SceneError(self.source, fld, value, expected, problem)

    def table(self, data, fld, allowed: Mapping[str, bool]) -> dict:
        """Check `data` is a table whose keys are in `allowed` (value: required?)."""
        if not isinstance(data, dict):
            raise self.error(fld, data, "a table", "not a table")
        for key in data:
            if key not in allowed:
                raise self.error(f"{fld}.{key}" if fld else key, data[key],
                                 "one of: " + ", ".join(sorted(allowed)) + _closest(str(key), allowed),
                                 "unknown field")
        for key, required in allowed.items():
            if required and key not in data:
                raise self.error(f"{fld}.{key}" if fld else key, None,
                                 f"a value for required field '{key}'", "missing field")
        return data

    def number(self, data, key, fld, default=None, minimum=None, exclusive=False, required=True, unit=None):
        """A number field in SI; `unit`: its SI unit, which the dimension of an expression over
        parameters with units must fit (None: any)."""
        path = f"{fld}.{key}"
        if key not in data:
            if default is not None or not required:
                return default
            raise self.error(path, None, "a number or expression" + (f" ({unit})" if unit else ""), "missing field")
        value = self.evaluate(data[key], path, unit)
        if minimum is not None:
            if (exclusive and not value > minimum) or (not exclusive and not value >= minimum):
                op = ">" if exclusive else "≥"
                shown = f" {unit}" if unit and unit != "1" else ""
                raise self.error(path, value, f"a number {op} {minimum:g}{shown}", "out of range")
        return value

    def vector(self, data, key, fld, dim, default=None, unit_length=False, unit=None):
        path = f"{fld}.{key}"
        if key not in data:
            if default is not None:
                return tuple(float(v) for v in default)
            raise self.error(path, None, f"a list of {dim} numbers", "missing field")
        raw = data[key]
        if not isinstance(raw, list) or len(raw) != dim:
            raise self.error(path, raw, f"a list of {dim} numbers or expressions", "wrong shape")
        values = tuple(self.evaluate(v, f"{path}[{i + 1}]", unit) for i, v in enumerate(raw))
        if unit_length:
            norm = math.sqrt(sum(v * v for v in values))
            if norm == 0.0:
                raise self.error(path, raw, "a non-zero direction", "zero vector")
            values = tuple(v / norm for v in values)
        return values

    def string(self, data, key, fld, choices=None, default=None):
        path = f"{fld}.{key}"
        if key not in data:
            if default is not None:
                return default
            raise self.error(path, None, "a string" if not choices else "one of: " + ", ".join(choices),
                             "missing field")
        value = data[key]
        if not isinstance(value, str):
            raise self.error(path, value, "a string", "wrong type")
        if choices is not None and value not in choices:
            raise self.error(path, value, "one of: " + ", ".join(choices), "unknown value")
        return value

    def name_pair(self, data, key, fld, known: Mapping, what: str):
        path = f"{fld}.{key}"
        if key not in data:
            raise self.error(path, None, f"a list of two {what} names", "missing field")
        raw = data[key]
        if not (isinstance(raw, list) and len(raw) == 2 and all(isinstance(v, str) for v in raw)):
            raise self.error(path, raw, f"a list of two {what} names", "wrong shape")
        for i, name in enumerate(raw):
            if name not in known:
                raise self.error(f"{path}[{i + 1}]", name,
                                 f"a {what} of the scene: " + _listing(known), f"unknown {what}")
        if raw[0] == raw[1]:
            raise self.error(path, raw, f"two different {what}s", f"the same {what} twice")
        return raw[0], raw[1]


def _listing(names, limit=12):
    names = sorted(names)
    text = ", ".join(names[:limit])
    return text + (", ..." if len(names) > limit else "") if names else "(none)"


def _check_name(reader: _Reader, name: str, fld: str):
    if not (isinstance(name, str) and name.isidentifier()):
        raise reader.error(fld, name, "a name made of letters, digits and '_' (not starting with a digit)",
                           "invalid name")


# ----------------------------------------------------------------------------------------------
# Loading
# ----------------------------------------------------------------------------------------------
EXPERIMENT_FIELDS = ("stop_time", "output_interval", "method", "rtol", "atol", "constraint", "baumgarte",
                     "communication_step", "step", "max_steps")
TOP_LEVEL = {"scene": False, "parameters": False, "effects": False, "ground": False, "bodies": False,
             "joints": False, "elements": False, "forces": False, "experiment": False, "metrics": False,
             "outputs": False}


def read_toml(path) -> tuple[str, dict]:
    """The scene file's TOML, read with a cap on its size (:mod:`.files`)."""
    source = str(path)
    text = read_capped(path, MAX_SCENE_BYTES, source, "(file)", "scene file (TOML)")
    try:
        data = tomllib.loads(text.decode("utf-8-sig"))      # -sig: a byte-order mark some editors write
    except UnicodeDecodeError:
        raise SceneError(source, "(file)", "binary data", "a UTF-8 TOML text", "not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(source, "(file)", str(exc), "valid TOML", "does not parse") from None
    return source, data


def load_scene(path, overrides: Mapping[str, Any] | None = None, origins: Mapping[str, str] | None = None) -> Scene:
    """Read, validate and evaluate a scene file; `overrides` as from ``--set`` (see split_overrides),
    `origins` where each came from, for errors (``{"b": "--set b=20"}``; see build_scene)."""
    source, data = read_toml(path)
    return build_scene(source, data, overrides or {}, origins)


def split_overrides(source: str, overrides: Mapping[str, Any], parameter_names, origins=None):
    """Sort overrides into parameters, effects and experiment settings; unknown names are errors,
    named by where they came from (:func:`inerter.scene.overrides.origin_of`)."""
    params, effects, experiment = {}, {}, {}
    for key, value in overrides.items():
        if key == "scene.orientation":
            experiment["__orientation__"] = value
        elif key.startswith("effects."):
            name = key[len("effects."):]
            if name not in KNOWN_EFFECTS:
                raise SceneError(f"{origin_of(key, value, origins)}: {source}", key, value,
                                 "an effect: " + ", ".join(f"effects.{e}" for e in KNOWN_EFFECTS)
                                 + _closest(name, KNOWN_EFFECTS, "effects."), "unknown effect")
            effects[name] = value
        elif key.startswith("experiment."):
            experiment[key[len("experiment."):]] = value
        elif key in parameter_names:
            params[key] = value          # read as the scene's entry is (evaluate_parameters)
        else:
            raise SceneError(origin_of(key, value, origins), key, value,
                             "a parameter of " + source + ": " + _listing(parameter_names)
                             + ", or effects.NAME, experiment.NAME, scene.orientation"
                             + _closest(key, parameter_names), "unknown name")
    return params, effects, experiment


def closest_name(name, known) -> str | None:
    """The one of the names `known` closest to the misspelt `name`, where one is close (difflib's
    ratio of at least 0.6), else None: the "did you mean" of the scene's and the results' errors."""
    close = difflib.get_close_matches(str(name), [str(k) for k in known], n=1)
    return close[0] if close else None


def _closest(name: str, known, prefix: str = "") -> str:
    """``; did you mean 'b'?`` where one of the names `known` is close to the misspelt `name`."""
    close = closest_name(name, known)
    return f"; did you mean '{prefix}{close}'?" if close else ""


def build_scene(source: str, data: dict, overrides: Mapping[str, Any], origins: Mapping[str, str] | None = None) -> Scene:
    """The scene of the TOML `data` with `overrides`. An error in a value an override gave names
    the override first (`origins`: where each came from, ``{"lead": "--set lead=0"}``; else
    ``override lead=0``): :func:`inerter.scene.overrides.attributed`. A parameter in a unit with two readings (``"g"``: the gram
    or standard gravity) is read as the one whose dimension fits every field it reaches: first
    as the first reading; a parameter a unit error names is read the other way and the scene
    read again (each at most once, so at most one read more than there are such parameters)."""
    raw_params = data.get("parameters", {}) if isinstance(data, dict) else {}
    p_names = set(raw_params) if isinstance(raw_params, dict) else set()
    fixed = {k: v for k, v in overrides.items() if k in p_names}
    choices = set(ambiguous_units(raw_params, fixed)) if isinstance(raw_params, dict) else set()
    reading: dict[str, int] = {}
    first: dict[str, UnitError] = {}          # the error that made a parameter be read the other way
    while True:
        try:
            return _build_scene(source, data, overrides, reading, origins)
        except UnitError as exc:
            flip = [n for n in exc.parameters if n in choices and n not in reading]
            if not flip:       # fits neither reading: the error its first reading gave
                error = next((first[n] for n in exc.parameters if n in first), exc)
                raise attributed(error, source, data, overrides, origins) from None
            reading.update({n: 1 for n in flip})
            first.update({n: exc for n in flip})
        except SceneError as exc:
            raise attributed(exc, source, data, overrides, origins) from None


def _build_scene(source: str, data: dict, overrides: Mapping[str, Any], reading: Mapping[str, int],
                 origins: Mapping[str, str] | None = None) -> Scene:
    base = _Reader(source, {})
    base.table(data, "", TOP_LEVEL)

    head = base.table(data.get("scene", {}), "scene", {"name": False, "description": False, "dimension": False,
                                                       "orientation": False, "euler_sequence": False})
    name = head.get("name", Path(source).stem)
    _check_name(base, name, "scene.name")
    if len(name) > MAX_SCENE_NAME:
        raise base.error("scene.name" if "name" in head else "scene.name (the file's stem)", name,
                         f"a name of at most {MAX_SCENE_NAME} characters (it names the output files and the FMU)",
                         f"too long ({len(name)} characters)")
    dimension = head.get("dimension", 2)
    if not isinstance(dimension, int) or isinstance(dimension, bool):     # 2.0 too: it counts components
        raise base.error("scene.dimension", dimension, "2 or 3 (an integer)", "wrong type")
    if dimension not in (2, 3):
        raise base.error("scene.dimension", dimension, "2 or 3", "unsupported dimension")
    orientation = head.get("orientation", "quaternion")
    p_names = set(data.get("parameters", {})) if isinstance(data.get("parameters", {}), dict) else set()
    orientation_override = split_overrides(source, overrides, p_names, origins)[2].get("__orientation__")
    if orientation_override is not None:
        if dimension != 3:
            raise SceneError(origin_of("scene.orientation", orientation_override, origins), "scene.orientation",
                             orientation_override, "a 3D scene", "no orientation in 2D")
        orientation = orientation_override
    if orientation not in ORIENTATIONS:
        raise base.error("scene.orientation", orientation, "one of: " + ", ".join(ORIENTATIONS), "unknown value")
    if dimension == 2 and "orientation" in head:
        raise base.error("scene.orientation", orientation, "no orientation choice in 2D (one angle per body)",
                         "unexpected field")
    euler_sequence = head.get("euler_sequence", "zyx")
    if dimension == 2 and "euler_sequence" in head:
        raise base.error("scene.euler_sequence", euler_sequence, "no Euler angles in 2D (one angle per body)",
                         "unexpected field")
    if euler_sequence not in EULER_SEQUENCES:
        raise base.error("scene.euler_sequence", euler_sequence,
                         "an intrinsic sequence of the bodies' Euler-angle outputs: " + ", ".join(EULER_SEQUENCES),
                         "unknown sequence")
    description = head.get("description", "")
    if not isinstance(description, str):
        raise base.error("scene.description", description, "a string", "wrong type")

    raw_params = data.get("parameters", {})
    if not isinstance(raw_params, dict):
        raise base.error("parameters", raw_params, "a table of named values", "not a table")
    p_over, e_over, x_over = split_overrides(source, overrides, set(raw_params), origins)
    x_over.pop("__orientation__", None)
    read = read_parameters(raw_params, source, fixed=p_over, reading=reading)
    meta = parameter_meta(raw_params)
    parameters = {n: Parameter(n, v.value, v.si_unit, meta[n]["description"], v.given, v) for n, v in read.items()}
    r = _Reader(source, {n: v.value for n, v in read.items()}, read)

    effects = _read_effects(r, data.get("effects", {}), e_over, dimension, Path(source).parent)
    bodies, points = _read_bodies(r, data, dimension)
    joints = _read_joints(r, data.get("joints", {}), points, dimension)
    element_specs = _read_elements(r, data.get("elements", {}), points, bodies, dimension)
    element_specs.update(_joint_elements(r, joints, points, element_specs, dimension))
    forces = _read_forces(r, data.get("forces", {}), points, dimension)
    experiment = _read_experiment(r, data.get("experiment", {}), x_over)
    outputs = _signal_names(points, element_specs, dimension, bodies)
    derived = _read_derived(r, data.get("outputs", {}), outputs)
    outputs.update({d.name: d.unit for d in derived})
    metrics = _read_metrics(r, data.get("metrics", []), outputs)
    return Scene(source, name, description, dimension, orientation, parameters, effects, bodies, points, joints,
                 element_specs, forces, experiment, metrics, derived=derived, euler_sequence=euler_sequence,
                 raw=data, experiment_overrides=x_over)


def _read_effects(r: _Reader, raw, overrides, dimension, folder):
    if not isinstance(raw, dict):
        raise r.error("effects", raw, "a table of effects", "not a table")
    merged = dict(raw)
    merged.update(overrides)
    effects = {}
    for name, value in merged.items():
        fld = f"effects.{name}"
        if name not in KNOWN_EFFECTS:
            raise r.error(fld, value, "one of: " + ", ".join(KNOWN_EFFECTS), "unknown effect")
        if name in ("centripetal", "small_displacement"):
            if not isinstance(value, bool):
                raise r.error(fld, value, "true or false", "wrong type")
            effects[name] = value
        elif name == "gravity":
            effects[name] = r.vector(merged, name, "effects", dimension, unit="m/s2")
        elif name == "ground_acceleration":
            effects[name] = _read_ground_motion(r, value, fld, dimension, folder)
    return effects


def _read_ground_motion(r: _Reader, spec, fld, dimension, folder):
    """The ground's acceleration: records (CSV, one column per axis; PEER NGA .AT2, one axis, in g),
    analytic terms per axis, a sine on every axis, or FMU inputs (see docs/scene_format.md)."""
    from inerter.scene.ground_motion import GroundMotion, combine_records
    r.table(spec, fld, {"file": False, "axis": False, "unit": False, "records": False, "terms": False,
                        "amplitude": False, "frequency": False, "scale": False, "input": False})
    scale = r.number(spec, "scale", fld, default=1.0, unit="1")
    sources = [k for k in ("file", "records", "terms", "amplitude", "input") if k in spec]
    allowed = ({"file", "terms"}, {"records", "terms"}, {"file"}, {"records"}, {"terms"}, {"amplitude"}, {"input"})
    if set(sources) not in allowed:
        raise r.error(fld, spec, "one source: file (a record), records = [...], terms = [...] (either of the "
                      "first two with terms), amplitude + frequency (a sine), or input = true (FMU inputs)",
                      "ambiguous or missing source" if sources else "no source")
    if "input" in spec:
        if spec["input"] is not True:
            raise r.error(f"{fld}.input", spec["input"], "true", "wrong value")
        return GroundMotion(dimension, scale=scale, input=True)
    if "amplitude" in spec:
        return GroundMotion.sine(dimension, r.vector(spec, "amplitude", fld, dimension, unit="m/s2"),
                                 r.number(spec, "frequency", fld, minimum=0.0, exclusive=True, unit="Hz"),
                                 scale=scale)
    record, names = None, []
    if "file" in spec:
        record, names = _read_record(r, spec, fld, dimension, folder), [str(spec["file"])]
    elif "records" in spec:
        listed = spec["records"]
        if not isinstance(listed, list) or not listed:
            raise r.error(f"{fld}.records", listed, "a list of records, e.g. [{ file = \"H1.AT2\", axis = 1 }]",
                          "not a list")
        parts = [_read_record(r, item, f"{fld}.records[{i}]", dimension, folder, single_axis=True)
                 for i, item in enumerate(listed)]
        record = combine_records(dimension, [(axis, t, v[0]) for axis, (t, v) in parts])
        names = [str(item.get("file")) for item in listed]
    terms = _read_terms(r, spec["terms"], f"{fld}.terms", dimension) if "terms" in spec else None
    return GroundMotion(dimension, record=record, terms=terms, scale=scale, source=" + ".join(names), files=names)


def _read_record(r: _Reader, spec, fld, dimension, folder, single_axis=False):
    """A record: (times, values[dim, n]) in m/s², or with `single_axis` (axis index, (times,
    values[1, n])). A CSV file has time and one column per axis (an `axis` only with one column);
    a .AT2 file (PEER NGA) one axis in g."""
    from inerter.scene.ground_motion import STANDARD_GRAVITY
    if single_axis:
        r.table(spec, fld, {"file": True, "axis": False, "unit": False})
    name = spec["file"]
    if not isinstance(name, str):
        raise r.error(f"{fld}.file", name, "a record's file name (.csv or .AT2), relative to the scene file",
                      "wrong type")
    path = folder / name
    at2 = path.suffix.lower() == ".at2"
    unit = spec.get("unit", "g" if at2 else "m/s2")
    if unit not in ("m/s2", "g") or (at2 and unit != "g"):
        raise r.error(f"{fld}.unit", unit, "\"g\" (an .AT2 record is in g)" if at2 else "\"m/s2\" or \"g\"",
                      "unknown unit")
    to_si = STANDARD_GRAVITY if unit == "g" else 1.0
    axis = None
    if at2 or single_axis or "axis" in spec:
        value = r.number(spec, "axis", fld, default=1.0, minimum=1.0, unit="1")
        axis = int(value) - 1
        if axis >= dimension or axis + 1 != value:
            raise r.error(f"{fld}.axis", value, f"an axis 1..{dimension}", "out of range")
    if at2:
        times, values = _read_at2_record(r, fld, path)
        values = values[None, :]
    else:
        table = _read_csv_record(r, fld, path, 1 if axis is not None else dimension, unit)
        times, values = table[:, 0], table[:, 1:].T.copy()
    values = values * to_si
    if single_axis:
        return axis, (times, values)
    if axis is not None:                       # one axis of a dim-axis scene
        full = np.zeros((dimension, len(times)))
        full[axis] = values[0]
        values = full
    return times, values


def _read_at2_record(r: _Reader, fld, path):
    """A PEER NGA record's (times, values in g), its errors naming the file's line that is wrong."""
    from inerter.scene.expressions import MAX_MAGNITUDE
    from inerter.scene.ground_motion import STANDARD_GRAVITY, RecordValueError, read_at2
    try:
        return read_at2(path, MAX_RECORD_SAMPLES, MAX_MAGNITUDE / STANDARD_GRAVITY)
    except FileNotFoundError:
        raise r.error(f"{fld}.file", str(path), "an existing PEER NGA record (.AT2)", "file not found") from None
    except RecordValueError as exc:
        raise r.error(f"{fld}.file", str(path), f"finite values in g of magnitude at most {MAX_MAGNITUDE:g} m/s²",
                      f"wrong value ({exc})") from None
    except (OSError, ValueError) as exc:
        raise r.error(f"{fld}.file", str(path), "a PEER NGA record (.AT2: 4 header lines, NPTS and DT "
                      "in the fourth, then NPTS values in g)", f"unreadable ({exc})") from None


def _data_lines(text: str) -> list[int]:
    """The 1-based line numbers of a CSV text's data rows (numpy.loadtxt's rows: the lines with
    anything left before a ``#`` comment)."""
    return [i for i, line in enumerate(text.splitlines(), start=1) if line.split("#", 1)[0].strip()]


def _unreadable_row(text: str) -> str | None:
    """Where numpy.loadtxt could not read a CSV text: the first data line whose count of cells
    differs from the first's, or with a cell that is not a number (None if none is found)."""
    count = None
    lines = text.splitlines()
    for number in _data_lines(text):
        cells = lines[number - 1].split("#", 1)[0].split(",")
        count = len(cells) if count is None else count
        if len(cells) != count:
            return f"line {number}: {len(cells)} columns, the first row has {count}"
        for column, cell in enumerate(cells, start=1):
            try:
                float(cell.strip().replace("_", "?"))     # numpy reads no "1_0"
            except ValueError:
                return f"line {number}, column {column}: {cell.strip()!r} is not a number"
    return None


def _read_csv_record(r: _Reader, fld, path, columns: int, unit: str):
    """A CSV record's table (time, then `columns` accelerations in `unit`), its errors naming the
    file's line where a row is wrong (a cell that is not a number, a count of columns, a value
    that is not finite or of magnitude above MAX_MAGNITUDE, a time not after the one before)."""
    import io
    import warnings
    from inerter.scene.expressions import MAX_MAGNITUDE
    from inerter.scene.ground_motion import STANDARD_GRAVITY
    data = read_capped(path, MAX_RECORD_BYTES, r.source, f"{fld}.file", "CSV record (time, a_1 ... a_dim)")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise r.error(f"{fld}.file", str(path), "a CSV text (time, a_1 ... a_dim)", "not UTF-8 text") from None
    lines = _data_lines(text)
    expected = (f"≥ 2 rows of {columns + 1} finite columns (time increasing, then {columns} "
                f"acceleration{'s' if columns > 1 else ''} in {unit})")

    def line(row: int) -> str:
        return f"line {lines[row]}" if 0 <= row < len(lines) else f"row {row + 1}"
    try:
        with warnings.catch_warnings():            # an empty file: the error below says so
            warnings.simplefilter("ignore", UserWarning)
            table = np.loadtxt(io.StringIO(text), delimiter=",", comments="#", ndmin=2)
    except ValueError as exc:
        brief = str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__
        raise r.error(f"{fld}.file", str(path), "numeric CSV columns: time, a_1 ... a_dim",
                      f"unreadable ({_unreadable_row(text) or brief})") from None
    if table.shape[0] > MAX_RECORD_SAMPLES:
        raise r.error(f"{fld}.file", str(path), f"at most {MAX_RECORD_SAMPLES:,} samples (every sample ends an "
                      "integrator step; resample the record)", f"too many samples ({table.shape[0]:,})")
    if table.shape[0] < 2 or table.shape[1] != columns + 1:
        got = f"{table.shape[0]} row{'s' if table.shape[0] != 1 else ''} of {table.shape[1]} column" \
              f"{'s' if table.shape[1] != 1 else ''}" if table.size else "no rows"
        raise r.error(f"{fld}.file", str(path), expected, f"wrong shape ({got})")
    si = np.abs(table) * np.r_[1.0, np.full(columns, STANDARD_GRAVITY if unit == "g" else 1.0)]
    bad = ~np.isfinite(table) | (si > MAX_MAGNITUDE)
    if bad.any():
        row, col = np.argwhere(bad)[0]
        raise r.error(f"{fld}.file", str(path), expected + f", of magnitude at most {MAX_MAGNITUDE:g} (SI)",
                      f"wrong value ({line(row)}, column {col + 1}: {float(table[row, col])!r})")
    back = np.flatnonzero(np.diff(table[:, 0]) <= 0)
    if len(back):
        row = back[0] + 1
        raise r.error(f"{fld}.file", str(path), expected,
                      f"time not increasing ({line(row)}: t = {float(table[row, 0])!r} s after {float(table[row - 1, 0])!r} s)")
    return table


def _read_terms(r: _Reader, raw, fld, dimension):
    """Analytic terms: rows (axis, amplitude, frequency, phase, start, stop) of GroundMotion.terms."""
    import math as _math
    if not isinstance(raw, list) or not raw:
        raise r.error(fld, raw, "a list of terms, e.g. [{ axis = 1, amplitude = 2.0, frequency = 1.5 }]",
                      "not a list")
    rows = []
    for i, term in enumerate(raw):
        f = f"{fld}[{i}]"
        r.table(term, f, {"axis": True, "amplitude": True, "frequency": True, "phase": False, "start": False,
                          "stop": False})
        value = r.number(term, "axis", f, minimum=1.0, unit="1")
        axis = int(value)
        if axis > dimension or axis != value:
            raise r.error(f"{f}.axis", term["axis"], f"an axis 1..{dimension}", "out of range")
        start = r.number(term, "start", f, default=0.0, minimum=0.0, unit="s")
        stop = r.number(term, "stop", f, default=_math.inf, unit="s")
        if not stop > start:
            raise r.error(f"{f}.stop", stop, f"a time after start = {start:g} s", "out of range")
        rows.append((axis - 1, r.number(term, "amplitude", f, unit="m/s2"),
                     r.number(term, "frequency", f, minimum=0.0, unit="Hz"),
                     r.number(term, "phase", f, default=0.0, unit="rad"), start, stop))
    return rows


def _read_bodies(r: _Reader, data, dimension):
    bodies, points = {}, {}
    raw_bodies = data.get("bodies", {})
    if not isinstance(raw_bodies, dict):
        raise r.error("bodies", raw_bodies, "a table of bodies", "not a table")
    zero = [0.0] * dimension

    def add_points(owner, raw, fld):
        if not isinstance(raw, dict):
            raise r.error(fld, raw, "a table of named points", "not a table")
        for pname in raw:
            _check_name(r, pname, f"{fld}.{pname}")
            if pname in points:
                raise r.error(f"{fld}.{pname}", pname, "a point name used once in the scene",
                              f"duplicate point name (also on {points[pname].body})")
            points[pname] = Point(pname, owner, r.vector(raw, pname, fld, dimension, unit="m"))

    ground = r.table(data.get("ground", {}), "ground", {"points": False})
    add_points(GROUND, ground.get("points", {}), "ground.points")

    for bname, raw in raw_bodies.items():
        fld = f"bodies.{bname}"
        _check_name(r, bname, fld)
        if bname == GROUND:
            raise r.error(fld, bname, "a body name other than 'ground'", "reserved name")
        if dimension == 2:
            massless = _read_massless(r, raw, fld)
            r.table(raw, fld, {"mass": not massless, "inertia": not massless, "position": True, "angle": False,
                               "velocity": False, "angular_velocity": False, "points": False, "massless": False})
            bodies[bname] = Body(
                bname,
                mass=_read_mass(r, raw, fld, massless),
                inertia=r.number(raw, "inertia", fld, minimum=0.0, default=0.0 if massless else None, unit="kg.m2"),
                position=r.vector(raw, "position", fld, dimension, unit="m"),
                angle=r.number(raw, "angle", fld, default=0.0, unit="rad"),
                velocity=r.vector(raw, "velocity", fld, dimension, default=zero, unit="m/s"),
                angular_velocity=r.number(raw, "angular_velocity", fld, default=0.0, unit="rad/s"),
                massless=massless,
            )
        else:
            massless = _read_massless(r, raw, fld)
            r.table(raw, fld, {"mass": not massless, "inertia": not massless, "position": True, "axis": False,
                               "angle": False, "euler": False, "quaternion": False, "velocity": False,
                               "angular_velocity": False, "points": False, "massless": False})
            bodies[bname] = Body(
                bname,
                mass=_read_mass(r, raw, fld, massless),
                inertia=_read_inertia(r, raw, fld) if "inertia" in raw else ((0.0,) * 3,) * 3,
                position=r.vector(raw, "position", fld, 3, unit="m"),
                angle=0.0,
                velocity=r.vector(raw, "velocity", fld, 3, default=zero, unit="m/s"),
                angular_velocity=r.vector(raw, "angular_velocity", fld, 3, default=zero, unit="rad/s"),
                rotation=_read_rotation(r, raw, fld),
                massless=massless,
            )
        add_points(bname, raw.get("points", {}), f"{fld}.points")
    if not bodies:
        raise r.error("bodies", {}, "at least one body", "no bodies")
    return bodies, points


def _read_massless(r: _Reader, raw, fld) -> bool:
    if not isinstance(raw, dict):
        raise r.error(fld, raw, "a table", "not a table")
    value = raw.get("massless", False)
    if not isinstance(value, bool):
        raise r.error(f"{fld}.massless", value, "true or false", "wrong type")
    return value


def _read_mass(r: _Reader, raw, fld, massless: bool) -> float:
    """A body's mass: > 0, or ≥ 0 (default 0) on a body declared ``massless = true``, whose
    coordinates then get their mass from inerters (checked when the mechanism is compiled)."""
    if massless:
        return r.number(raw, "mass", fld, default=0.0, minimum=0.0, unit="kg")
    mass = r.number(raw, "mass", fld, unit="kg")
    if not mass > 0.0:
        raise r.error(f"{fld}.mass", mass, "a number > 0 (kg); a body carried only by inerters may have "
                      "mass = 0 if it says so with massless = true", "out of range")
    return mass


def _read_inertia(r: _Reader, raw, fld):
    """A 3D inertia: three principal values (body axes) or a symmetric positive semi-definite 3×3."""
    import numpy as np
    value = raw["inertia"]
    path = f"{fld}.inertia"
    expected = "3 principal moments [Jx, Jy, Jz] ≥ 0 or a symmetric 3×3 matrix, kg.m2"
    if isinstance(value, list) and len(value) == 3 and all(not isinstance(v, list) for v in value):
        J = np.diag(r.vector(raw, "inertia", fld, 3, unit="kg.m2"))
    elif isinstance(value, list) and len(value) == 3 and all(isinstance(v, list) and len(v) == 3 for v in value):
        J = np.array([[r.evaluate(x, f"{path}[{i + 1}][{j + 1}]", "kg.m2") for j, x in enumerate(row)]
                      for i, row in enumerate(value)])
    else:
        raise r.error(path, value, expected, "wrong shape")
    if not np.allclose(J, J.T, rtol=0, atol=1e-12 * max(1.0, np.abs(J).max())) \
            or np.min(np.linalg.eigvalsh(J)) < -1e-12 * max(1.0, np.abs(J).max()):
        raise r.error(path, value, expected, "not symmetric positive semi-definite")
    return tuple(tuple(float(x) for x in row) for row in J)


def _read_rotation(r: _Reader, raw, fld):
    """Initial rotation: axis (default Z) and angle, Z-X-Z Euler angles [φ, θ, ψ], or a unit
    quaternion [w, x, y, z]: one of the three."""
    from inerter.common.rotations import axis_angle_matrix, euler_matrix, quat_matrix
    given = [k for k in ("euler", "quaternion") if k in raw] + (["axis/angle"] if "axis" in raw or "angle" in raw
                                                                 else [])
    if len(given) > 1:
        key = "euler" if "euler" in raw else "quaternion"
        raise r.error(f"{fld}.{key}", raw[key], "one of: euler = [φ, θ, ψ], quaternion = [w, x, y, z], "
                      "or axis and angle", "more than one given: " + ", ".join(given))
    if "quaternion" in raw:
        p = r.vector(raw, "quaternion", fld, 4, unit="1")
        norm = math.sqrt(sum(x * x for x in p))
        if abs(norm - 1.0) > 1e-9:
            raise r.error(f"{fld}.quaternion", list(p), "a unit quaternion [w, x, y, z] (|p| = 1 to 1e-9)",
                          f"|p| = {norm:.12g}")
        A = quat_matrix(p)
    elif "euler" in raw:
        A = euler_matrix(r.vector(raw, "euler", fld, 3, unit="rad"))
    else:
        axis = r.vector(raw, "axis", fld, 3, default=(0.0, 0.0, 1.0), unit_length=True)
        A = axis_angle_matrix(axis, r.number(raw, "angle", fld, default=0.0, unit="rad"))
    return tuple(tuple(float(x) for x in row) for row in A)


def _read_joints(r: _Reader, raw, points, dimension):
    if not isinstance(raw, dict):
        raise r.error("joints", raw, "a table of joints", "not a table")
    joints = {}
    for jname, spec in raw.items():
        fld = f"joints.{jname}"
        _check_name(r, jname, fld)
        if not isinstance(spec, dict):
            raise r.error(fld, spec, "a table", "not a table")
        jtype = r.string(spec, "type", fld, JOINT_TYPES if dimension == 2 else JOINT_TYPES_3D)
        needs_axis = jtype in _AXIS_JOINTS[dimension]
        allowed = {"type": True, "between": True}
        if needs_axis:
            allowed["axis"] = True
        if jtype == "universal":
            allowed["axis2"] = True
        if jtype in _JOINT_SPRINGS:
            allowed.update(stiffness=False, damping=False)
        if jtype == "screw":
            allowed.update(lead=True, **({"coupling_only": False} if dimension == 3 else {}))
        r.table(spec, fld, allowed)
        a, b = r.name_pair(spec, "between", fld, points, "point")
        if points[a].body == points[b].body:
            raise r.error(f"{fld}.between", [a, b], "points on two different bodies (or a body and the ground)",
                          f"both points are on {points[a].body}")
        axis = r.vector(spec, "axis", fld, dimension, unit_length=True) if needs_axis else None
        axis2 = None
        if jtype == "universal":
            axis2 = r.vector(spec, "axis2", fld, 3, unit_length=True)
            if abs(sum(x * y for x, y in zip(axis, axis2))) > 1e-9:
                raise r.error(f"{fld}.axis2", list(axis2), f"a unit vector perpendicular to axis = {list(axis)}",
                              "not perpendicular (a universal joint's two axes cross at a right angle)")
        stiffness, damping = 0.0, 0.0
        if jtype in _JOINT_SPRINGS:
            (_, k_unit), (_, d_unit) = _JOINT_SPRINGS[jtype]
            stiffness = r.number(spec, "stiffness", fld, default=0.0, minimum=0.0, unit=k_unit)
            damping = r.number(spec, "damping", fld, default=0.0, minimum=0.0, unit=d_unit)
        lead, coupling_only = 0.0, False
        if jtype == "screw":
            lead = r.number(spec, "lead", fld, unit="m")
            if lead == 0.0:
                raise r.error(f"{fld}.lead", lead, "a non-zero lead (m; negative for a left-handed screw)", "zero")
            coupling_only = spec.get("coupling_only", False)
            if not isinstance(coupling_only, bool):
                raise r.error(f"{fld}.coupling_only", coupling_only, "true or false", "not a boolean")
        joints[jname] = Joint(jname, jtype, a, b, axis, axis2, stiffness, damping, lead, coupling_only)
    return joints


#: Joints that may carry `stiffness` and `damping`: the elements they become, with the fields' units.
_JOINT_SPRINGS = {"revolute": (("rotational_spring", "N.m/rad"), ("rotational_damper", "N.m.s/rad")),
                  "prismatic": (("spring", "N/m"), ("damper", "N.s/m"))}


def _joint_elements(r: _Reader, joints, points, elements_read, dimension):
    """The spring and damper a revolute or prismatic joint declares with `stiffness` and `damping`
    (a column base's spring without a separate element), named JOINT_spring and JOINT_damper:
    revolute, a rotational spring and damper between the joint's two bodies, about its axis in 3D;
    prismatic, a spring and damper between its two points along its axis (fixed in the first
    point's body), on the signed slide. The spring's free angle or slide is the initial one."""
    out = {}
    for j in joints.values():
        if j.type not in _JOINT_SPRINGS:
            continue
        for key, (etype, _), coefficient in zip(("stiffness", "damping"), _JOINT_SPRINGS[j.type],
                                                (j.stiffness, j.damping)):
            if not coefficient:
                continue
            ename = f"{j.name}_{etype.split('_')[-1]}"
            if ename in elements_read or ename in points:
                raise r.error(f"joints.{j.name}.{key}", coefficient,
                              f"no element or point named {ename!r} (the joint's {etype.replace('_', ' ')})",
                              "name clash")
            if j.type == "prismatic":
                out[ename] = Element(ename, etype, point_a=j.point_a, point_b=j.point_b, coefficient=coefficient,
                                     slider_axis=tuple(j.axis))
            else:
                out[ename] = Element(ename, etype, body_a=points[j.point_a].body, body_b=points[j.point_b].body,
                                     coefficient=coefficient, axis=j.axis if dimension == 3 else None)
    return out


def _read_elements(r: _Reader, raw, points, bodies, dimension):
    if not isinstance(raw, dict):
        raise r.error("elements", raw, "a table of elements", "not a table")
    out = {}
    body_names = dict(bodies, **{GROUND: None})
    for ename, spec in raw.items():
        fld = f"elements.{ename}"
        _check_name(r, ename, fld)
        if ename in points:
            raise r.error(fld, ename, "an element name that is not also a point name",
                          "name clash with a point (outputs would collide)")
        if not isinstance(spec, dict):
            raise r.error(fld, spec, "a table", "not a table")
        etype = r.string(spec, "type", fld, ELEMENT_TYPES)
        kind = elements.KINDS[etype]
        rotational = kind.family == elements.ROTATIONAL
        device = _read_device(r, spec["device"], f"{fld}.device", kind, dimension) if kind.device and "device" in spec else None
        inertance = device.inertance() if device is not None else None
        if inertance is not None and kind.coefficient.key in spec:
            source = next(n for n, _ in device.effects if DEVICE_EFFECT[n].inertance is not None)
            raise r.error(f"{fld}.{kind.coefficient.key}", spec[kind.coefficient.key],
                          f"no {kind.coefficient.key} where device.{source} gives the inertance "
                          f"({inertance:g} {kind.coefficient.unit})", "given twice")
        allowed = {"type": True, "bodies" if rotational else "between": True,
                   kind.coefficient.key: inertance is None}
        if kind.free is not None:
            allowed[kind.free.key] = kind.free.required
        if rotational and dimension == 3:
            allowed["axis"] = True
        if kind.device:
            allowed["device"] = False
        r.table(spec, fld, allowed)
        if rotational:
            a, b = r.name_pair(spec, "bodies", fld, body_names, "body")
        else:
            a, b = r.name_pair(spec, "between", fld, points, "point")
            if points[a].body == points[b].body:
                raise r.error(f"{fld}.between", [a, b], "points on two different bodies",
                              f"both points are on {points[a].body}: the element could never act")
        coef = _read_parameter(r, spec, fld, kind.coefficient) if inertance is None else inertance
        if device is not None and device.has("compliance") and not coef > 0.0:
            raise r.error(f"{fld}.{kind.coefficient.key}", coef, f"an inertance > 0 ({kind.coefficient.unit}) with "
                          "device.compliance (the series node's law divides by it)", "out of range")
        free = _read_parameter(r, spec, fld, kind.free) if kind.free is not None else None
        if rotational:
            axis = r.vector(spec, "axis", fld, 3, unit_length=True) if dimension == 3 else None
            out[ename] = Element(ename, etype, body_a=a, body_b=b, coefficient=coef, free_length=free, axis=axis)
        else:
            out[ename] = Element(ename, etype, point_a=a, point_b=b, coefficient=coef, free_length=free,
                                 device=device)
    return out


def _read_parameter(r: _Reader, spec, fld, p: "elements.Parameter"):
    """One parameter of an element kind or of a device effect, within the range it declares
    (inerter.elements); an optional one left out takes its default (None: absent)."""
    if p.key not in spec and not p.required:
        return p.default
    if p.size > 1:
        return tuple(float(x) for x in r.vector(spec, p.key, fld, p.size, unit_length=True))
    value = r.number(spec, p.key, fld, required=p.required, unit=_fixed_unit(p.unit))
    if not p.admits(value):
        raise r.error(f"{fld}.{p.key}", value, p.expected(), "out of range")
    return value


def _fixed_unit(unit: str) -> str | None:
    """`unit` where it has one dimension; None where it depends on another parameter (an end
    stop's N/m^n): such a field's dimension is not checked."""
    from inerter.scene import units
    try:
        units.dimension_of(unit)
    except units.UnitSyntaxError:
        return None
    return unit


def _read_device(r: _Reader, raw, fld, kind: "elements.ElementKind", dimension: int):
    """An element's ``device`` table: one sub-table per effect its kind allows
    (inerter.elements.device.EFFECTS), each parameter within its range, the effect's own check
    (one of lead or ratio, min < max, ...) and at most one source of the inertance."""
    if not isinstance(raw, dict):
        raise r.error(fld, raw, "a table of device effects: " + ", ".join(e.name for e in kind.device), "not a table")
    names = [e.name for e in kind.device]
    for key in raw:
        if key not in names:
            raise r.error(f"{fld}.{key}", raw[key], "one of: " + ", ".join(names), "unknown device effect")
    if not raw:
        raise r.error(fld, raw, "at least one effect: " + ", ".join(names), "empty device")
    effects = []
    for effect in kind.device:
        if effect.name not in raw:
            continue
        efld = f"{fld}.{effect.name}"
        if dimension not in effect.dimensions:
            raise r.error(efld, raw[effect.name], f"no {effect.name} in a {dimension}D scene", effect.why_not_2d)
        table = r.table(raw[effect.name], efld, {p.key: p.required for p in effect.parameters})
        if effect.parameters and not table:      # its defaults alone (friction's viscous = 0) do nothing
            raise r.error(efld, table, "at least one of its fields: " + ", ".join(p.key for p in effect.parameters),
                          "empty effect")
        values = {p.key: _read_parameter(r, table, efld, p) for p in effect.parameters}
        problem = effect.check(values) if effect.check is not None else None
        if problem is not None:
            key, value, expected, what = problem
            raise r.error(f"{efld}.{key}", value, expected, what)
        effects.append((effect.name, tuple(values.items())))
    problem = check_device({name: dict(values) for name, values in effects})
    if problem is not None:
        name, key, value, expected, what = problem
        raise r.error(f"{fld}.{name}" + (f".{key}" if key else ""), value, expected, what)
    sources = [name for name, _ in effects if DEVICE_EFFECT[name].inertance is not None]
    if len(sources) > 1:
        raise r.error(f"{fld}.{sources[1]}", raw[sources[1]], f"one source of the inertance (device.{sources[0]} "
                      "gives it already)", "two sources of inertance")
    return Device(tuple(effects))


def _read_forces(r: _Reader, raw, points, dimension):
    if not isinstance(raw, dict):
        raise r.error("forces", raw, "a table of point forces", "not a table")
    forces = {}
    input_points = set()
    fields = {"constant": ("value",), "sine": ("amplitude", "frequency", "phase", "offset"),
              "step": ("value", "time", "initial"), "input": (), "pd": ("kp", "kd", "reference")}
    for fname, spec in raw.items():
        fld = f"forces.{fname}"
        _check_name(r, fname, fld)
        if not isinstance(spec, dict):
            raise r.error(fld, spec, "a table", "not a table")
        function = r.string(spec, "function", fld, FORCE_FUNCTIONS)
        allowed = {"point": True, "function": True}
        if function != "input":
            allowed["direction"] = True
        allowed.update({k: k in ("value", "amplitude", "frequency", "kp") for k in fields[function]})
        r.table(spec, fld, allowed)
        point = r.string(spec, "point", fld)
        if point not in points:
            raise r.error(f"{fld}.point", point, "a point of the scene: " + _listing(points), "unknown point")
        if points[point].body == GROUND:
            raise r.error(f"{fld}.point", point, "a point on a body", "a force on the ground does nothing")
        if function == "input":
            if point in input_points:
                raise r.error(f"{fld}.point", point, "one input force per point", "duplicate input force")
            input_points.add(point)
            forces[fname] = Force(fname, point, function, None)
            continue
        kwargs = {k: r.number(spec, k, fld, default=0.0, unit=FORCE_UNITS[k]) for k in fields[function]}
        for gain in ("kp", "kd"):
            if gain in kwargs and kwargs[gain] < 0:
                raise r.error(f"{fld}.{gain}", kwargs[gain], "a gain ≥ 0", "out of range")
        if function == "sine" and kwargs["frequency"] <= 0:
            raise r.error(f"{fld}.frequency", kwargs["frequency"], "a frequency > 0 (Hz)", "out of range")
        forces[fname] = Force(fname, point, function, r.vector(spec, "direction", fld, dimension, unit_length=True),
                              **kwargs)
    return forces


def _read_experiment(r: _Reader, raw, overrides):
    r.table(raw, "experiment", {"stop_time": False, "output_interval": False, "method": False, "rtol": False,
                                "atol": False, "constraint": False, "baumgarte": False,
                                "communication_step": False, "step": False, "max_steps": False})
    merged = dict(raw)
    for key, value in overrides.items():
        if key not in EXPERIMENT_FIELDS:
            raise r.error(f"experiment.{key}", value, "one of: " + ", ".join(EXPERIMENT_FIELDS)
                          + _closest(key, EXPERIMENT_FIELDS), "unknown field")
        merged[key] = value
    fld = "experiment"
    stop = r.number(merged, "stop_time", fld, default=10.0, minimum=0.0, exclusive=True, unit="s")

    def sampling(key, value):
        """An interval between samples: at most the stop time, and not so short that the run's
        samples (and the arrays holding them) pass MAX_OUTPUT_SAMPLES."""
        if value > stop:
            raise r.error(f"experiment.{key}", value, f"at most stop_time = {stop:g} s", "longer than the run")
        if stop / value > MAX_OUTPUT_SAMPLES:
            raise r.error(f"experiment.{key}", value, f"at least stop_time / {MAX_OUTPUT_SAMPLES:,} = "
                          f"{stop / MAX_OUTPUT_SAMPLES:g} s (at most {MAX_OUTPUT_SAMPLES:,} samples a run)",
                          "too many samples")
        return value

    interval = sampling("output_interval", r.number(merged, "output_interval", fld, default=0.01, minimum=0.0,
                                                    exclusive=True, unit="s"))
    rtol = r.number(merged, "rtol", fld, default=1e-8, minimum=RTOL_RANGE[0], unit="1")
    if rtol > RTOL_RANGE[1]:
        raise r.error("experiment.rtol", rtol, f"a relative tolerance in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}]",
                      "out of range")
    method = r.string(merged, "method", fld, METHODS, default="DOP853")
    step = r.number(merged, "step", fld, default=1e-3, minimum=0.0, exclusive=True, unit="s")
    if method == "RK4" and step > stop:
        raise r.error("experiment.step", step, f"RK4's step at most stop_time = {stop:g} s", "longer than the run")
    return Experiment(
        stop_time=stop, output_interval=interval,
        method=method,
        rtol=rtol,
        atol=r.number(merged, "atol", fld, default=rtol * 1e-2, minimum=ATOL_MIN),
        constraint=r.string(merged, "constraint", fld, CONSTRAINT_TREATMENTS, default="baumgarte"),
        baumgarte=r.number(merged, "baumgarte", fld, default=10.0, minimum=0.0, unit="1/s"),
        communication_step=sampling("communication_step", r.number(
            merged, "communication_step", fld, default=interval, minimum=0.0, exclusive=True, unit="s")),
        step=step,
        max_steps=_whole(r, merged, "max_steps", default=2_000_000),
    )


def _whole(r: _Reader, data, key, default):
    """A whole number ≥ 1 (a count)."""
    value = r.number(data, key, "experiment", default=default, minimum=1.0, unit="1")
    if value != int(value):
        raise r.error(f"experiment.{key}", value, "a whole number ≥ 1", "not a whole number")
    return int(value)


def _signal_names(points, element_specs, dimension, bodies=()) -> dict[str, str | None]:
    """Every output's name and SI unit (None: mixed units)."""
    names = {}
    for p in points:
        for i in range(1, dimension + 1):
            names.update({f"{p}.r[{i}]": "m", f"{p}.v[{i}]": "m/s"})
    for e, el in element_specs.items():
        names.update({f"{e}.{suffix}": unit for suffix, unit, _ in elements.outputs(el)})
    if dimension == 3:
        for bname in bodies:
            names.update({f"{bname}.q[{i}]": "1" for i in range(1, 5)})
            names.update({f"{bname}.euler[{i}]": "rad" for i in range(1, 4)})
            names.update({f"{bname}.w[{i}]": "rad/s" for i in range(1, 4)})
    names.update({"energy": "J", "constraint_residual": None})
    return names


def _read_derived(r: _Reader, raw, outputs) -> tuple[Derived, ...]:
    """``[outputs.derived]``: ``NAME = "expression"`` or ``NAME = { expression, unit, description }``,
    an expression over the outputs (those before it included) and parameters; its unit is the one
    its outputs' units give it, or the declared one (SI), which must fit."""
    r.table(raw, "outputs", {"derived": False})
    table = raw.get("derived", {})
    if not isinstance(table, dict):
        raise r.error("outputs.derived", table, 'a table of NAME = "expression" entries', "not a table")
    known, derived = dict(outputs), []
    for name, spec in table.items():
        fld = f"outputs.derived.{name}"
        _check_name(r, name, fld)
        if name in known or name in r.names or name in RESERVED_NAMES:
            raise r.error(fld, name, "a name that is not already an output, a parameter, a function or a constant",
                          "name clash")
        text, declared, description = spec, None, None
        if isinstance(spec, dict):
            r.table(spec, fld, {"expression": True, "unit": False, "description": False})
            text, declared = spec["expression"], spec.get("unit")
            description = r.string(spec, "description", fld, default="") or None
            fld_expr = f"{fld}.expression"
        else:
            fld_expr = fld
        try:
            expression = output_expression(text, known, r.names, r.source, fld_expr, r.dims)
        except SceneError as exc:                   # one declared below it: say so
            later = next((n for n in table if n not in known and n != name
                          and exc.problem.startswith(f"unknown name '{n}'")), None)
            if later is None:
                raise
            raise r.error(fld_expr, text, exc.expected, f"unknown name '{later}': a derived output declared "
                          f"below {name}, which reads only those above it (move {later} up)") from None
        unit = _derived_unit(r, fld, declared, expression, known)
        derived.append(Derived(name, expression, unit, description or f"derived output: {text}"))
        known[name] = unit
    return tuple(derived)


def _derived_unit(r: _Reader, fld, declared, expression, outputs) -> str:
    """A derived output's SI unit: the declared one (checked against the expression's dimension,
    where that is known and no plain number multiplies a quantity in it: ``0.5*50*x^2`` may be an
    energy), or the unit of an output it reads of that dimension (rad for a difference of angles),
    or the one the dimension names."""
    inferred = ""
    if expression.dimension is not None:
        inferred = next((outputs[x] for x in expression.reads
                         if outputs[x] and units.dimension_of(outputs[x]) == expression.dimension),
                        units.si_name(expression.dimension))
    if declared is None:
        if not inferred:
            raise r.error(fld, expression.text, "a table { expression = ..., unit = \"...\" } declaring its SI unit",
                          "its unit cannot be inferred from the outputs it reads")
        return inferred
    try:
        unit = units.parse(declared) if isinstance(declared, str) else None
    except units.UnitSyntaxError:
        unit = None
    if unit is None or unit.factor != 1.0:
        raise r.error(f"{fld}.unit", declared, "an SI unit (the outputs are in SI): m, N, N.m, m/s2, 1, ...",
                      "not an SI unit")
    if expression.dimension is not None and not expression.loose and unit.dimension != expression.dimension:
        raise r.error(f"{fld}.unit", declared, f"a unit of {units.describe_dimension(expression.dimension)}"
                      f" ({inferred or 'the expression'}), as the outputs it reads give it", "the unit does not fit")
    return declared


def _read_metrics(r: _Reader, raw, signals):
    if not isinstance(raw, list):
        raise r.error("metrics", raw, "an array of tables ([[metrics]])", "not an array")
    metrics = []
    named: dict[str, int] = {}                # each value's name (prefixed), by the metric giving it
    for i, spec in enumerate(raw):
        fld = f"metrics[{i + 1}]"
        if not isinstance(spec, dict):
            raise r.error(fld, spec, "a table", "not a table")
        kind = r.string(spec, "kind", fld, METRIC_KINDS)
        allowed = {"kind": True, "prefix": False}
        if kind != "natural_frequency":
            allowed.update({"signal": True} if kind == "harmonics" else {"signal": True, "reference": False})
        if kind == "steady_state":
            allowed.update({"period": True, "periods": False})
        if kind == "harmonics":
            allowed.update({"period_of": True})
        r.table(spec, fld, allowed)
        prefix = r.string(spec, "prefix", fld, default="")
        for value in METRIC_VALUES[kind]:
            key = f"{prefix}_{value}" if prefix else value
            if key in named:
                raise r.error(f"{fld}.prefix", prefix, f"a prefix that keeps this metric's values apart from "
                              f"metrics[{named[key] + 1}]'s (both would give {key!r})", "name clash")
            named[key] = i
        signal = None
        if "signal" in spec:
            signal = r.string(spec, "signal", fld)
            if signal not in signals:
                raise r.error(f"{fld}.signal", signal, "an output of the scene: " + _listing(signals, 20),
                              "unknown signal")
        period_of = None
        if "period_of" in spec:
            period_of = r.string(spec, "period_of", fld)
            if period_of not in signals:
                raise r.error(f"{fld}.period_of", period_of, "an output of the scene", "unknown signal")
        periods = spec.get("periods", 10)
        if isinstance(periods, bool) or not isinstance(periods, int) or periods < 1:
            raise r.error(f"{fld}.periods", periods, "a whole number ≥ 1", "out of range")
        metrics.append(Metric(
            kind=kind, prefix=prefix, signal=signal,
            reference=r.number(spec, "reference", fld, required=False, unit=signals.get(signal)),
            period=r.number(spec, "period", fld, minimum=0.0, exclusive=True, required=False, unit="s"),
            periods=periods, period_of=period_of))
    return tuple(metrics)
