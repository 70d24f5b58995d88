"""Build FMI 2.0 co-simulation FMUs from scene files (``build_fmu.py``, ``inerter build-fmu``).

One FMU per scene, named after the scene (``build/fmu/two_bar_2d.fmu``). Its model identifier
and its model class are unique to the scene, and its Python module
(``inerter_fmu_two_bar_2d_<build>``) to the build, so FMUs of several scenes, and several builds
of one scene (a scene edited and built again, a copy under another file name), run in one process.
The FMU's ``resources/`` hold

- the generated model module (from ``fmu_src/model_module.py.template``),
- the generic slave ``fmu_src/inerter_slave.py``, which does the work,
- ``inerter_payload.zip``: the modules of the ``inerter`` package the slave can import
  (:mod:`.payload`; not the command line, sweeps, studies or this builder), in one archive that
  the slave unpacks once per machine (:func:`write_payload`),
- the scene file, and ``requirements.txt`` (numpy, scipy, with a note on Python and numba),
- pythonfmu's own runtime, added by pythonfmu.

On Linux, ``binaries/linux64/<model>.so`` is the status shim compiled from
``fmu_src/status_shim.c`` (with gcc, at build time), and behind it, as ``<model>.bridge.so``, the
Python bridge compiled from ``fmu_src/python_bridge.c``: the FMI functions over the slave, as
pythonfmu's own binary makes them, without what that binary costs at every instantiation (it
executed the model module again, and started a thread and loaded a 284 KB C++ library for each run
of an importer). The shim returns the slave's status (its variable ``fmi_status``, whose value
reference is compiled in) from exitInitializationMode, setXxx, doStep and setFMUstate. It also
takes the doSteps of a running compiled integration itself, in compiled code, when the slave arms
it (``inerter/fmu/native.py``; the private value references are compiled in too). Without
Python's headers pythonfmu's binary goes behind the shim (``<model>.pythonfmu.so``); without gcc
(or on a host other than Linux x86-64) the FMU is built with pythonfmu's binary alone; the build
warns (FmuBuildWarning) in both cases, and in the second errors come as fmi2Discard from the next
doStep. The win64 binary is always pythonfmu's own, which runs the same slave.

The FMU runs inside the importing process with its Python interpreter (neither binary links
libpython), importing numpy, scipy and numba from that environment (``pythonfmu deploy -f
X.fmu`` installs ``requirements.txt``); its ``description`` says which versions
(:data:`HOST_REQUIREMENTS`). pythonfmu 0.7.0 writes a model description without units, types or
dependencies, so it is completed here (:func:`declarations`):

- ``<UnitDefinitions>`` with each unit's SI exponents and display units (mm, deg), ``unit=`` and
  ``displayUnit=`` on every Real variable, ``min``/``max`` where the scene format has a range;
- the integration method as an Enumeration (``<TypeDefinitions>``) instead of pythonfmu's Integer;
- ``<ModelStructure>``: each output's ``dependencies`` on the inputs, from the model's signals
  (an output computed from the accelerations depends on every input at once, the others on none),
  and ``<InitialUnknowns>`` for the outputs, which are calculated.

A build is skipped when the FMU is current: ``<name>.fmu.source-hash`` next to it holds a hash of
the scene file and of every shipped source, and a build with the same hash does nothing.
"""
from __future__ import annotations

import argparse
import hashlib
import keyword
import math
import platform
import re
import shutil
import string
import subprocess
import sys
import sysconfig
import tempfile
import uuid
import warnings
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

from dataclasses import dataclass, field

from inerter.fmu import native as fmu_native
from inerter.fmu import payload as fmu_payload
from inerter.common import locations
from inerter.common.atomic import replace_file
from inerter.common.errors import InerterError

PACKAGE_DIR = Path(__file__).resolve().parents[1]
#: fmu_src/ in a checkout, its copy in an installed package (inerter.common.locations).
FMU_SRC = locations.fmu_sources()
SLAVE_FILE = "inerter_slave.py"
#: The archive of the package's modules in the FMU's resources (fmu_src/inerter_slave.py reads the
#: same name) and the time stamp of its entries.
PAYLOAD_FILE = "inerter_payload.zip"
PAYLOAD_DATE = (2020, 1, 1, 0, 0, 0)
#: Where pythonfmu's builder embeds pythonfmu in an FMU; the build moves it into the payload.
EMBEDDED_PYTHONFMU = "resources/pythonfmu/"
TEMPLATE_FILE = "model_module.py.template"
SHIM_FILE = "status_shim.c"
SHIM_HEADER = "fmi2_types.h"
BRIDGE_FILE = "python_bridge.c"
LOG_HEADER = "log_format.h"
#: The slave's Integer variable that holds its status (fmu_src/inerter_slave.py).
STATUS_VARIABLE = "fmi_status"
#: Where the binary behind the shim goes: the Python bridge, or pythonfmu's own Linux binary where
#: the bridge cannot be compiled (no Python.h).
BRIDGE_SUFFIX = ".bridge.so"
ORIGINAL_SUFFIX = ".pythonfmu.so"
DEFAULT_OUT_DIR = Path("build") / "fmu"
DEFAULT_SCENES_DIR = locations.scenarios()
#: What the FMU needs of the Python that loads it: the package's own requirements (pyproject.toml).
HOST_REQUIREMENTS = {"python": ">=3.11", "numpy": ">=1.26", "scipy": ">=1.11", "numba": ">=0.60"}
#: The packages the FMU imports from the importer's environment: its resources/requirements.txt
#: (``pythonfmu deploy`` installs it), under a note on the interpreter.
RUNTIME_REQUIREMENTS = tuple(f"{name}{spec}" for name, spec in HOST_REQUIREMENTS.items() if name != "python")
REQUIREMENTS_NOTE = ("# The FMU runs in the importing process's Python (3.11 or later) and imports these from\n"
                     "# its environment.\n")
#: Display units offered where users think in them; values stay in the unit.
DISPLAY_UNITS = {"m": "mm", "m/s": "mm/s", "rad": "deg", "rad/s": "deg/s"}
#: The type of the ``solver`` Enumeration.
METHOD_TYPE = "IntegrationMethod"
HASH_SUFFIX = ".fmu.source-hash"
#: Bump when the layout of a built FMU changes without any shipped source changing.
BUILD_FORMAT = "inerter-fmu-build/6"
MODULE_PREFIX = "inerter_fmu_"
#: The hex digits of the build digest in the module's name (:func:`module_name`).
BUILD_IN_MODULE = 16


class FmuBuildError(InerterError):
    """An FMU cannot be built from a scene (the message names the scene and the problem)."""


class FmuBuildWarning(UserWarning):
    """An FMU was built, but without the status shim (the message says why)."""


# ----------------------------------------------------------------------------------------------
# Units: Modelica unit strings ("N.s/m", "kg.m2", "m/s2") -> SI base-unit exponents
# ----------------------------------------------------------------------------------------------
BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")

#: symbol -> (base-unit exponents, factor to SI)
UNIT_SYMBOLS: dict[str, tuple[dict[str, int], float]] = {
    "kg": ({"kg": 1}, 1.0),
    "g": ({"kg": 1}, 1e-3),
    "m": ({"m": 1}, 1.0),
    "mm": ({"m": 1}, 1e-3),
    "s": ({"s": 1}, 1.0),
    "A": ({"A": 1}, 1.0),
    "K": ({"K": 1}, 1.0),
    "mol": ({"mol": 1}, 1.0),
    "cd": ({"cd": 1}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "deg": ({"rad": 1}, math.pi / 180.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0),
    "J": ({"kg": 1, "m": 2, "s": -2}, 1.0),
    "W": ({"kg": 1, "m": 2, "s": -3}, 1.0),
    "Pa": ({"kg": 1, "m": -1, "s": -2}, 1.0),
    "Hz": ({"s": -1}, 1.0),
}

_FACTOR = re.compile(r"([A-Za-z]+)(-?\d+)?")


def si_unit(unit: str) -> tuple[dict[str, int], float]:
    """Base-unit exponents and factor of a Modelica unit string.

    The syntax is Modelica's: factors joined by ``.``, each a symbol with an optional integer
    exponent (``m2``, ``s-2``), and at most one ``/`` followed by one factor or a parenthesised
    product: ``N.s/m``, ``kg.m2``, ``m/s2``, ``1/s``, ``J/(kg.K)``. ``"1"`` is dimensionless.
    Raises ValueError for anything else.
    """
    text = unit.strip()
    if not text:
        raise ValueError("empty unit")
    numerator, slash, denominator = text.partition("/")
    if slash and denominator.startswith("(") and denominator.endswith(")"):
        denominator = denominator[1:-1]
    elif slash and "." in denominator:
        raise ValueError(f"ambiguous denominator {denominator!r}: write '/({denominator})'")
    exponents: dict[str, int] = {}
    factor = 1.0
    for part, sign in ((numerator, 1), (denominator, -1)):
        if sign < 0 and not slash:
            break
        if part == "1":
            continue
        for item in part.split("."):
            match = _FACTOR.fullmatch(item)
            if match is None or match.group(1) not in UNIT_SYMBOLS:
                raise ValueError(f"unknown unit factor {item!r} (known symbols: "
                                 f"{', '.join(UNIT_SYMBOLS)}, with an integer exponent)")
            base, scale = UNIT_SYMBOLS[match.group(1)]
            power = sign * int(match.group(2) or 1)
            for b, e in base.items():
                exponents[b] = exponents.get(b, 0) + e * power
            factor *= scale ** power
    return {b: exponents[b] for b in BASE_UNITS if exponents.get(b, 0) != 0}, factor


def unit_definitions(units, display=None) -> ET.Element:
    """A ``<UnitDefinitions>`` element for the given unit strings, with a ``<DisplayUnit>`` for
    those `display` maps to one (``{"m": "mm"}``: value in mm = factor · value in m)."""
    root = ET.Element("UnitDefinitions")
    for unit in sorted(set(units)):
        exponents, factor = si_unit(unit)
        node = ET.SubElement(root, "Unit", name=unit)
        attrib = {b: str(e) for b, e in exponents.items()}
        if factor != 1.0:
            attrib["factor"] = repr(factor)
        ET.SubElement(node, "BaseUnit", attrib)
        shown = (display or {}).get(unit)
        if shown is not None:
            shown_exponents, shown_factor = si_unit(shown)
            if shown_exponents != exponents:
                raise ValueError(f"display unit {shown!r} is not a unit of {unit!r}")
            ET.SubElement(node, "DisplayUnit", name=shown, factor=repr(factor / shown_factor))
    return root


# ----------------------------------------------------------------------------------------------
# Building
# ----------------------------------------------------------------------------------------------
def module_name(model_name: str, build: str) -> str:
    """The FMU's Python module for a scene's build (`build`: its :func:`source_hash`). pythonfmu's
    binary imports the module that ``slavemodule.txt`` names, and a process imports a module
    name once: an FMU of another build under the same name would be given the first one's class,
    with that one's scene file (an FMU of a copy of the scene failed to instantiate with a
    FileNotFoundError) and build digest."""
    return f"{MODULE_PREFIX}{model_name}_{build[:BUILD_IN_MODULE]}"


def _requirements_text() -> str:
    return REQUIREMENTS_NOTE + "\n".join(RUNTIME_REQUIREMENTS) + "\n"


def _shipped_package_files() -> list[Path]:
    """The package's files the FMU carries: those the slave can import (:mod:`.payload`)."""
    return fmu_payload.package_files(FMU_SRC / SLAVE_FILE, PACKAGE_DIR)


def write_payload(target: Path) -> None:
    """Write the package's files the FMU carries into one archive, `target` (``inerter/...``).

    One file instead of some sixty: an importer extracts the whole FMU at every instantiation
    (fmpy: about 6 ms for those files on a 2-core machine), while the slave unpacks the archive
    once per machine (``unpack_payload`` in fmu_src/inerter_slave.py). Entries carry a fixed
    time stamp, so the archive, and the folder it unpacks to, depend on the files' contents only.

    The archive carries pythonfmu's modules too (``pythonfmu/...``, the files pythonfmu's builder
    would put in ``resources/pythonfmu/``, which the build leaves out of the FMU): twelve files
    fewer for the importer to extract and delete at every run (about 1.5 ms of fmpy's
    simulate_fmu, docs/benchmarks/fmu_overhead_paper_scenes.md)."""
    entries = [("inerter/" + path.relative_to(PACKAGE_DIR).as_posix(), path)
               for path in _shipped_package_files()]
    entries += [("pythonfmu/" + path.name, path) for path in _pythonfmu_files()]
    with zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as z:
        for name, path in entries:
            z.writestr(zipfile.ZipInfo(name, date_time=PAYLOAD_DATE), path.read_bytes(),
                       compress_type=zipfile.ZIP_DEFLATED)


def _pythonfmu_files() -> list[Path]:
    """pythonfmu's modules, as its builder embeds them in an FMU (every .py file of the package's
    top folder), sorted."""
    import pythonfmu

    return sorted(Path(pythonfmu.__file__).resolve().parent.glob("*.py"))


def source_hash(scene_path: Path, data_files=()) -> str:
    """A hash of everything an FMU of `scene_path` is built from."""
    import pythonfmu

    h = hashlib.sha256()

    def add(label: str, data: bytes):
        h.update(label.encode() + b"\0" + len(data).to_bytes(8, "little") + data)

    add("format", BUILD_FORMAT.encode())
    add("pythonfmu", pythonfmu.__version__.encode())
    add("requirements", _requirements_text().encode())
    add("host", _host_versions().encode())
    add("scene:" + scene_path.name, scene_path.read_bytes())
    for rel in data_files:                                 # records the scene reads (ground motion)
        add("data:" + rel, (scene_path.parent / rel).read_bytes())
    for name in (SLAVE_FILE, TEMPLATE_FILE, SHIM_FILE, SHIM_HEADER, BRIDGE_FILE, LOG_HEADER):
        add("fmu_src/" + name, (FMU_SRC / name).read_bytes())
    # An FMU built without the shim or the bridge is rebuilt once a compiler and Python.h are there.
    add("shim", b"compiled" if _shim_compiler()[0] else b"none")
    add("bridge", b"compiled" if _python_include() else b"none")
    for path in _shipped_package_files():
        add("inerter/" + path.relative_to(PACKAGE_DIR).as_posix(), path.read_bytes())
    for path in _pythonfmu_files():
        add("pythonfmu/" + path.name, path.read_bytes())
    return h.hexdigest()


def _scene_description(scene_path: Path, model) -> str:
    try:
        import tomllib
        data = tomllib.loads(scene_path.read_text(encoding="utf-8"))
        text = data.get("scene", {}).get("description")
        if isinstance(text, str) and text.strip():
            return " ".join(text.split())
    except Exception:
        pass
    return f"inerter scene {model.name}"


def _host_versions() -> str:
    """The versions of Python and of the required packages here, where the FMU is built."""
    from importlib.metadata import PackageNotFoundError, version
    found = [f"Python {platform.python_version()}"]
    for name in HOST_REQUIREMENTS:
        if name != "python":
            try:
                found.append(f"{name} {version(name)}")
            except PackageNotFoundError:
                found.append(f"{name} (not installed)")
    return ", ".join(found)


def host_requirements_text() -> str:
    """What the FMU needs of its host, for its description and the docs."""
    from inerter.engine import compiled
    need = ", ".join(f"{'Python' if name == 'python' else name} {spec}" for name, spec in HOST_REQUIREMENTS.items())
    seconds = getattr(compiled, "COMPILE_SECONDS", {2: 40, 3: 70})
    return (f"Host requirements: it runs in the importer's own Python process and needs {need} installed "
            f"there (built with {_host_versions()}). Its first use on a machine compiles the engine's "
            f"kernels (about {seconds[2]} s for a 2D scene, {seconds[3]} s for a 3D one, on 2 cores; logged "
            f"as it happens), cached for later runs.")


def fmu_description(scene_path: Path, model, tunable) -> str:
    """The FMU's ``description``: the scene's, which parameters are tunable, the host requirements."""
    fixed = [p["name"] for p in model.parameter_info() if p["name"] not in tunable]
    text = _scene_description(scene_path, model).rstrip(".") + "."
    if tunable:
        text += (f" Tunable between steps: {', '.join(tunable)}"
                 + (f"; fixed (set before initialisation): {', '.join(fixed)}." if fixed else "."))
    elif fixed:
        text += " Every parameter is fixed (set before initialisation)."
    return f"{text} {host_requirements_text()}"


@dataclass
class Declarations:
    """What the build adds to pythonfmu's model description, by variable name."""
    units: dict[str, str] = field(default_factory=dict)
    minimums: dict[str, float] = field(default_factory=dict)
    maximums: dict[str, float] = field(default_factory=dict)
    #: variable -> (type name, items in the order of their values 1, 2, ...)
    enumerations: dict[str, tuple[str, list[str]]] = field(default_factory=dict)
    #: output -> the inputs it depends on at the same instant (ModelStructure/Outputs)
    output_dependencies: dict[str, list[str]] | None = None
    #: output -> the knowns it depends on in initialization mode (InitialUnknowns)
    initial_dependencies: dict[str, list[str]] | None = None


def declarations(model, units: dict[str, str]) -> Declarations:
    """The declarations of the FMU of `model`, derived from the model: an output depends on the
    inputs where its signal reads the accelerations (``reads_accelerations``: an inerter's
    force), which every input enters; in initialization mode every output is calculated from the
    scene's parameters and effects, and those that read the accelerations from the inputs too."""
    from inerter.scene.ranges import parameter_minimums
    from inerter.scene.reader import RTOL_RANGE

    inputs = [i["name"] for i in model.input_info()]
    knowns = [p["name"] for p in model.parameter_info()] + [e["name"] for e in model.effect_info()]
    outputs = model.output_info()
    minimums = {name: value for name, value in parameter_minimums(model.scene.raw).items()
                if name in {p["name"] for p in model.parameter_info()}}
    minimums["rtol"] = RTOL_RANGE[0]
    return Declarations(
        units=units, minimums=minimums, maximums={"rtol": RTOL_RANGE[1]},
        enumerations={"solver": (METHOD_TYPE, list(model.methods))},
        output_dependencies={o["name"]: (inputs if o["reads_accelerations"] else []) for o in outputs},
        initial_dependencies={o["name"]: knowns + (inputs if o["reads_accelerations"] else [])
                              for o in outputs})


def _check_model(scene_path: Path, model) -> dict[str, str]:
    """Check the model's names for an FMU and return the unit of each Real variable."""
    name = model.name
    if not (isinstance(name, str) and name.isidentifier() and not keyword.iskeyword(name)
            and name not in ("InerterSlave", "Fmi2Slave", "inerter_slave")):
        raise FmuBuildError(f"{scene_path}: scene name {name!r} cannot name an FMU (expected a "
                            f"Python identifier, not a keyword)")
    units: dict[str, str] = {}
    seen: set[str] = set()

    def add(var: str, unit: str | None, what: str):
        if var in seen:
            raise FmuBuildError(f"{scene_path}: {what} {var!r}: the name is used twice in the "
                                f"FMU (parameters, effects, solver, rtol, atol, inputs, outputs)")
        seen.add(var)
        if unit:
            try:
                si_unit(unit)
            except ValueError as exc:
                raise FmuBuildError(f"{scene_path}: {what} {var!r}: unit {unit!r}: {exc}") from None
            units[var] = unit

    for p in model.parameter_info():
        add(p["name"], p.get("unit"), "parameter")
    for e in model.effect_info():
        add(e["name"], None, "effect")
    add("solver", None, "setting")
    add("rtol", "1", "setting")
    add("atol", None, "setting")
    add(STATUS_VARIABLE, None, "status variable")
    for i in model.input_info():
        add(i["name"], i.get("unit"), "input")
    for o in model.output_info():
        add(o["name"], o.get("unit"), "output")
    return units


def build(scene_path, out_dir=DEFAULT_OUT_DIR, force: bool = False) -> Path:
    """Build the FMU of one scene into `out_dir` and return its path.

    Nothing is done when the FMU there is current (same scene and shipped sources), unless
    `force`. Raises SceneError for an invalid scene, FmuBuildError when the scene cannot be
    made into an FMU.
    """
    return _build(Path(scene_path), Path(out_dir), force)[0]


def _build(scene_path: Path, out_dir: Path, force: bool) -> tuple[Path, bool]:
    import inerter

    if not scene_path.is_file():
        raise FmuBuildError(f"{scene_path}: no such scene file")
    if not (FMU_SRC / SLAVE_FILE).is_file():
        raise FmuBuildError(f"{scene_path}: the FMU sources are missing ({FMU_SRC / SLAVE_FILE} "
                            f"does not exist; expected fmu_src/ beside the package or its copy "
                            f"in an installed one: reinstall inerter)")
    model = inerter.load(scene_path)
    units = _check_model(scene_path, model)
    name = model.name
    fmu_path = out_dir / f"{name}.fmu"
    hash_path = out_dir / f"{name}{HASH_SUFFIX}"
    digest = source_hash(scene_path, model.scene.data_files)
    if (not force and fmu_path.is_file() and hash_path.is_file()
            and hash_path.read_text().strip() == digest):
        return fmu_path, False
    tunable = model.tunable_parameters()        # loads the scene once per parameter: only to build

    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="inerter_fmu_") as tmp:
        stage = Path(tmp) / "stage"
        stage.mkdir()
        module = module_name(name, digest)
        template = string.Template((FMU_SRC / TEMPLATE_FILE).read_text(encoding="utf-8"))
        version = getattr(inerter, "__version__", None)
        (stage / f"{module}.py").write_text(template.substitute(
            name=name, scene_file=scene_path.name, scene_file_repr=repr(scene_path.name),
            description_repr=repr(fmu_description(scene_path, model, tunable)),
            version_repr=repr(None if version is None else str(version)),
            tunable_repr=repr(tuple(tunable)), build_repr=repr(digest)), encoding="utf-8")
        shutil.copy2(FMU_SRC / SLAVE_FILE, stage / SLAVE_FILE)
        write_payload(stage / PAYLOAD_FILE)
        shutil.copy2(scene_path, stage / scene_path.name)
        (stage / "requirements.txt").write_text(_requirements_text())
        extra = []
        for rel in model.scene.data_files:                 # beside the scene, as the scene names them
            target = stage / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(scene_path.parent / rel, target)
            top = stage / Path(rel).parts[0]
            if top not in extra:
                extra.append(top)

        built = _run_pythonfmu(stage / f"{module}.py", Path(tmp) / "out",
                               [stage / SLAVE_FILE, stage / PAYLOAD_FILE, stage / scene_path.name,
                                stage / "requirements.txt", *extra])
        final = Path(tmp) / f"{name}.fmu"
        _complete_model_description(built, final, units, digest, Path(tmp) / "shim",
                                    declarations(model, units), scene_file=scene_path.name)
        hash_path.unlink(missing_ok=True)
        replace_file(fmu_path, lambda part: shutil.copyfile(final, part))
    replace_file(hash_path, lambda part: part.write_text(digest + "\n"))
    return fmu_path, True


def _run_pythonfmu(script: Path, dest: Path, project_files: list[Path]) -> Path:
    """pythonfmu's builder, with the imports and sys.path entries it leaves behind undone."""
    from pythonfmu import FmuBuilder

    own = {script.stem, Path(SLAVE_FILE).stem}
    saved_path = list(sys.path)
    saved_modules = {k: sys.modules.pop(k) for k in own if k in sys.modules}
    before = set(sys.modules)
    try:
        dest.mkdir(parents=True, exist_ok=True)
        return Path(FmuBuilder.build_FMU(script, dest=dest, project_files=project_files,
                                         canGetAndSetFMUstate=True, canSerializeFMUstate=True))
    finally:
        sys.path[:] = saved_path
        for key in set(sys.modules) - before:
            origin = getattr(sys.modules[key], "__file__", None) or ""
            if key in own or origin.startswith(str(script.parent.parent)):
                del sys.modules[key]
        sys.modules.update(saved_modules)


#: The integration methods, as the solver Enumeration's items describe them.
METHOD_DESCRIPTIONS = {
    "DOP853": "explicit Runge-Kutta 8(5,3), adaptive step",
    "RK45": "explicit Runge-Kutta 5(4) (Dormand-Prince), adaptive step",
    "Radau": "implicit Radau IIA of order 5, adaptive step (stiff scenes)",
    "BDF": "implicit backward differentiation formulas, variable order (stiff scenes)",
    "LSODA": "Adams / BDF switching on stiffness",
    "RK4": "classical Runge-Kutta 4 with the fixed step experiment.step",
}


def _declare(root: ET.Element, units: dict[str, str], extra: Declarations | None) -> set[str]:
    """Write units (and, with `extra`, display units, ranges, enumerations and the model
    structure) into the model description `root`; returns the units used."""
    variables = list(root.find("ModelVariables"))
    index = {var.get("name"): i + 1 for i, var in enumerate(variables)}
    used = set()
    for var in variables:
        name = var.get("name")
        real = var.find("Real")
        unit = units.get(name)
        if real is not None and unit:
            real.set("unit", unit)
            used.add(unit)
            if extra is not None and unit in DISPLAY_UNITS:
                real.set("displayUnit", DISPLAY_UNITS[unit])
        if extra is None:
            continue
        if real is not None:
            for key, bounds in (("min", extra.minimums), ("max", extra.maximums)):
                if name in bounds:
                    real.set(key, repr(float(bounds[name])))
        if name in extra.enumerations and var.find("Integer") is not None:
            integer = var.find("Integer")
            enumeration = ET.Element("Enumeration", {"declaredType": extra.enumerations[name][0],
                                                     **dict(integer.attrib)})
            var.remove(integer)
            var.append(enumeration)
    if extra is None:
        return used
    # Schema order: CoSimulation, UnitDefinitions, TypeDefinitions, LogCategories, ...
    if extra.enumerations:
        types = ET.Element("TypeDefinitions")
        for type_name, items in sorted(set((t, tuple(i)) for t, i in extra.enumerations.values())):
            simple = ET.SubElement(types, "SimpleType", name=type_name)
            node = ET.SubElement(simple, "Enumeration")
            for value, item in enumerate(items, start=1):
                ET.SubElement(node, "Item", name=item, value=str(value),
                              **({"description": METHOD_DESCRIPTIONS[item]} if item in METHOD_DESCRIPTIONS else {}))
        root.insert([child.tag for child in root].index("CoSimulation") + 1, types)
    if extra.output_dependencies is not None:
        structure = root.find("ModelStructure")
        for child in list(structure):
            structure.remove(child)
        outputs = [var.get("name") for var in variables if var.get("causality") == "output"]
        for tag, dependencies in (("Outputs", extra.output_dependencies),
                                  ("InitialUnknowns", extra.initial_dependencies)):
            if not outputs or dependencies is None:
                continue
            node = ET.SubElement(structure, tag)
            for name in outputs:
                knowns = sorted(index[k] for k in dependencies[name])
                # No dependenciesKind: every kind is "dependent", which FMI 2.0 (2.2.8) assumes
                # where the attribute is absent; it was a fifth of the two-bar description, which
                # an importer reads and validates at every run (docs/benchmarks).
                ET.SubElement(node, "Unknown", {"index": str(index[name]),
                                                "dependencies": " ".join(map(str, knowns))})
    return used


def _complete_model_description(src: Path, dest: Path, units: dict[str, str], digest: str,
                                shim_dir: Path | None = None, extra: Declarations | None = None,
                                scene_file: str | None = None):
    """Copy the FMU `src` to `dest` with units and a content-derived GUID in its description,
    and with `extra` (:func:`declarations`) the rest the build declares.

    With `shim_dir` (a scratch folder), the status shim is compiled there for the slave's
    STATUS_VARIABLE and put in front of pythonfmu's Linux binary (see :func:`_compile_shim`); its
    messages name `scene_file`.
    """
    with zipfile.ZipFile(src) as zin:
        root = ET.fromstring(zin.read("modelDescription.xml"))
        root.set("guid", "{%s}" % uuid.uuid5(uuid.NAMESPACE_URL, f"inerter-fmu:{digest}"))
        status_vr = -1
        for var in root.iter("ScalarVariable"):
            if var.get("name") == STATUS_VARIABLE and var.find("Integer") is not None:
                status_vr = int(var.get("valueReference"))
        if shim_dir is not None and status_vr < 0:
            raise FmuBuildError(f"{src.name}: the model description has no Integer "
                                f"{STATUS_VARIABLE!r} (fmu_src/{SLAVE_FILE} registers it)")
        used = _declare(root, units, extra)
        if used:
            # Schema order: CoSimulation, UnitDefinitions, TypeDefinitions, LogCategories, ...
            position = [child.tag for child in root].index("CoSimulation") + 1
            root.insert(position, unit_definitions(used, DISPLAY_UNITS if extra is not None else {}))
        ET.indent(root, space="  ")
        xml = ET.tostring(root, encoding="UTF-8", xml_declaration=True)

        identifier = root.find("CoSimulation").get("modelIdentifier")
        linux_binary = f"binaries/linux64/{identifier}.so"
        shim = behind = None
        if shim_dir is not None and linux_binary in zin.namelist():
            module = zin.read("resources/slavemodule.txt").decode("utf-8").strip()
            bridge = _compile_bridge(identifier, module, shim_dir, dest.name, scene_file)
            suffix = BRIDGE_SUFFIX if bridge is not None else ORIGINAL_SUFFIX
            shim = _compile_shim(identifier, status_vr, shim_dir, dest.name, scene_file, suffix)
            if shim is not None:
                behind = (f"binaries/linux64/{identifier}{suffix}",
                          bridge if bridge is not None
                          else _stripped(zin.read(linux_binary), shim_dir))
        # Stored, not deflated: importers extract the FMU at every run (fmpy's simulate_fmu
        # does), and inflating it cost 4 ms a run, 8 % of the lumped scene's 20 s at 10 ms steps
        # (docs/fmu_overhead.md); the FMU is 0.88 MB instead of 0.45 MB.
        with zipfile.ZipFile(dest, "w", compression=zipfile.ZIP_STORED) as zout:
            for info in zin.infolist():
                if info.filename.startswith(EMBEDDED_PYTHONFMU):
                    continue                      # in the payload (write_payload)
                if info.filename == "modelDescription.xml":
                    zout.writestr(info.filename, xml)
                elif info.filename == linux_binary and shim is not None:
                    zout.writestr(*behind)
                    zout.writestr(linux_binary, shim)
                else:
                    zout.writestr(info.filename, zin.read(info))


def _shim_compiler() -> tuple[str | None, str]:
    """gcc, when it can build the shim for binaries/linux64 here; else (None, why not)."""
    if platform.system() != "Linux" or platform.machine().lower() not in ("x86_64", "amd64"):
        return None, (f"the status shim is built on Linux x86-64 only (this is "
                      f"{platform.system()} {platform.machine()})")
    gcc = shutil.which("gcc")
    if gcc is None:
        return None, "gcc was not found on PATH"
    return gcc, ""


def _stripped(binary: bytes, work: Path) -> bytes:
    """pythonfmu's Linux binary without its symbol table (``strip --strip-all``: 346 KB -> 284
    KB; the dynamic symbols the shim looks up stay), as it is where ``strip`` is missing or
    fails. An importer extracts every byte of the FMU at every run (docs/benchmarks)."""
    tool = shutil.which("strip")
    if tool is None:
        return binary
    work.mkdir(parents=True, exist_ok=True)
    path = work / "pythonfmu-binary.so"
    path.write_bytes(binary)
    try:
        proc = subprocess.run([tool, "--strip-all", str(path)], capture_output=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return binary
    return path.read_bytes() if proc.returncode == 0 else binary


def _c_string(text: str) -> str:
    """`text` as a C string literal: its UTF-8 bytes, each but letters, digits and ``._-+/ `` as a
    three-digit octal escape (a file name may hold quotes, backslashes or '%')."""
    safe = set(b"abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-+/ ")
    return '"' + "".join(chr(b) if b in safe else f"\\{b:03o}" for b in text.encode("utf-8")) + '"'


def _gcc_library(gcc: str, work: Path, name: str, source: str, flags: list[str],
                 libraries: tuple = ()) -> tuple[bytes | None, str]:
    """The shared library `name` compiled from fmu_src/`source` with `flags`: (its bytes, "") or
    (None, why not)."""
    work.mkdir(parents=True, exist_ok=True)
    out = work / name
    # -s: no symbol table (the exported functions are in the dynamic one): fewer bytes for an
    # importer to extract at every run.
    command = [gcc, "-shared", "-fPIC", "-O2", "-s", "-fvisibility=hidden", "-pthread", *flags,
               "-o", str(out), source, *libraries]
    try:
        proc = subprocess.run(command, cwd=FMU_SRC, capture_output=True, text=True, timeout=300)
    except (OSError, subprocess.SubprocessError) as exc:
        return None, f"{' '.join(command)} failed: {exc}"
    if proc.returncode == 0 and out.is_file():
        return out.read_bytes(), ""
    return None, (f"{' '.join(command)} failed (exit status {proc.returncode}): "
                  f"{(proc.stderr or proc.stdout).strip()[-2000:]}")


def _compile_shim(identifier: str, status_vr: int, work: Path, fmu_name: str,
                  scene_file: str | None = None, behind: str = BRIDGE_SUFFIX) -> bytes | None:
    """The status shim for `identifier`, compiled from fmu_src/status_shim.c, in front of the
    binary `identifier + behind` and with its own messages naming `scene_file` (the FMU's file
    name without it); None (with a FmuBuildWarning) when it cannot be compiled here."""
    gcc, why = _shim_compiler()
    if gcc is not None:
        shim, why = _gcc_library(gcc, work, f"{identifier}.so", SHIM_FILE, [
            f"-DSTATUS_VR={status_vr}u", f"-DNATIVE_LINK_VR={fmu_native.LINK_VR}u",
            f"-DNATIVE_SYNC_VR={fmu_native.SYNC_VR}u", f"-DNATIVE_MAGIC={fmu_native.MAGIC}LL",
            f'-DORIGINAL_LIBRARY="{identifier}{behind}"',
            f"-DSCENE_FILE={_c_string(scene_file or fmu_name)}"], ("-ldl",))
        if shim is not None:
            return shim
    warnings.warn(f"{fmu_name}: built without the status shim: {why}. Its Linux binary is "
                  f"pythonfmu's alone, which returns fmi2OK from exitInitializationMode and "
                  f"setXxx whatever happens: an error is reported by the message logged and the "
                  f"fmi2Discard of the next doStep", FmuBuildWarning, stacklevel=2)
    return None


def _python_include() -> str | None:
    """The folder of this Python's C headers, where it holds Python.h; else None."""
    folder = sysconfig.get_path("include")
    return folder if folder and (Path(folder) / "Python.h").is_file() else None


def _compile_bridge(identifier: str, module: str, work: Path, fmu_name: str,
                    scene_file: str | None = None) -> bytes | None:
    """The Python bridge for `identifier` (fmu_src/python_bridge.c: the FMI functions over the
    slave, the model module `module` and its class `identifier` compiled in, its messages naming
    `scene_file`), to go behind the shim; None where it cannot be compiled here (no gcc, no
    Python.h: pythonfmu's binary then goes behind the shim, and the build warns)."""
    gcc, _ = _shim_compiler()
    if gcc is None:
        return None                               # no shim either: _compile_shim warns
    include = _python_include()
    if include is None:
        why = (f"Python.h was not found in {sysconfig.get_path('include')} (install Python's "
               f"headers)")
    else:
        bridge, why = _gcc_library(gcc, work, f"{identifier}{BRIDGE_SUFFIX}", BRIDGE_FILE, [
            f"-I{include}", f"-DSLAVE_MODULE={_c_string(module)}",
            f"-DSLAVE_CLASS={_c_string(identifier)}",
            f"-DSCENE_FILE={_c_string(scene_file or fmu_name)}"])
        if bridge is not None:
            return bridge
    warnings.warn(f"{fmu_name}: built without the Python bridge: {why}. pythonfmu's binary "
                  f"is behind the status shim instead (a run of an importer that extracts the FMU "
                  f"afresh then costs about 0.8 ms more)", FmuBuildWarning, stacklevel=2)
    return None


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------
def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of ``build_fmu.py`` and ``inerter build-fmu``."""
    parser.add_argument("scenes", nargs="*", metavar="SCENE",
                        help=f"scene files (default: every {DEFAULT_SCENES_DIR.name}/*.toml)")
    parser.add_argument("-o", "--out-dir", default=str(DEFAULT_OUT_DIR),
                        help="where the FMUs go (default: %(default)s)")
    parser.add_argument("-f", "--force", action="store_true",
                        help="rebuild even when an FMU is current")


def run(args: argparse.Namespace) -> int:
    """Build the FMUs that `args` name; print one line per scene; return the exit status."""
    scenes = [Path(s) for s in args.scenes] or sorted(DEFAULT_SCENES_DIR.glob("*.toml"))
    if not scenes:
        print(f"inerter: error: no scene given and none in {DEFAULT_SCENES_DIR}", file=sys.stderr)
        return 2
    status = 0
    made: dict[Path, Path] = {}
    for scene in scenes:
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", FmuBuildWarning)
                path, built = _build(scene, Path(args.out_dir), args.force)
        except InerterError as exc:
            print(f"inerter: error: {exc}", file=sys.stderr)
            status = 1
            continue
        finally:
            for warning in caught:
                if issubclass(warning.category, FmuBuildWarning):
                    print(f"warning: {warning.message}", file=sys.stderr)
                else:
                    warnings.showwarning(warning.message, warning.category, warning.filename,
                                         warning.lineno)
        if path in made:
            print(f"inerter: error: {scene}: builds {path}, as {made[path]} does (two scenes with one "
                  f"name)", file=sys.stderr)
            status = 1
        made[path] = scene
        print(f"{'built' if built else 'up to date'}: {path}")
    return status


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="build_fmu.py",
        description="Build one FMI 2.0 co-simulation FMU per scene (rebuilt only when the "
                    "scene or the code changed).")
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
