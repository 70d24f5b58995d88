"""A coupled co-simulation: the two-bar FMU (plant) driven by the PD-controller FMU.

The controller reads C.r[2] and C.v[2] of the plant and returns F = −kp (y − reference) − kd v
(direct feedthrough), which acts on the plant as the input C.f[2], held over each communication
step h. The same system solved as one scene (``two_bar_2d_pd.toml``, a ``pd`` force at C) is the
reference; it also gives the controller's gains. Two master loops run it on fmpy:

- ``sequential`` (Gauss–Seidel): read the plant's outputs at t_k, set them on the controller, read
  its force F_k and set it on the plant, then step both. The force held over [t_k, t_k + h] is the
  controller's law at t_k, and differs from the one scene's only by that zero-order hold.
- ``parallel`` (Jacobi), the scheme of libcosim's fixed-step algorithm: step both, then read every
  output and set every input. The controller stepped over [t_k, t_k + h] with the plant's outputs
  at t_k, so the force it gives then reaches the plant one step later: over [t_k, t_k + h] the
  plant holds the law at t_{k−1} (at t_0 for the first step, where both loops start from
  outputs made consistent at t_0).

:func:`build_system` writes the same system for other masters: an OSP system structure
(``OspSystemStructure.xml``) and an SSP 1.0 ``SystemStructure.ssd`` beside the two FMUs, both read
by libcosim. Communication points are whole nanoseconds, t_k = (k·h_ns)/10⁹ with steps
t_{k+1} − t_k, as libcosim passes them to the FMUs, so that a run of either file in libcosim and
the parallel loop here step the FMUs through the same calls with the same values.
"""
from __future__ import annotations

import hashlib
import math
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np

from inerter.common import locations
from inerter.fmu.build import (DEFAULT_OUT_DIR, FMU_SRC, FmuBuildError, _complete_model_description,
                               _run_pythonfmu, build, si_unit)

CONTROLLER = "pd_controller.py"
CONTROLLER_UNITS = {"kp": "N/m", "kd": "N.s/m", "reference": "m", "y": "m", "v": "m/s", "F": "N"}
#: The plant's scene and the one-scene counterpart whose actuator gives the controller's gains.
PLANT_SCENE = "two_bar_2d.toml"
SYSTEM_SCENE = "two_bar_2d_pd.toml"
#: Instance names in the system structures, and the connections (from, output, to, input).
PLANT, CTRL = "plant", "controller"
CONNECTIONS = ((PLANT, "C.r[2]", CTRL, "y"), (PLANT, "C.v[2]", CTRL, "v"), (CTRL, "F", PLANT, "C.f[2]"))
OSP_FILE = "OspSystemStructure.xml"
SSD_FILE = "SystemStructure.ssd"
COUPLINGS = ("sequential", "parallel")


def build_controller(out_dir=DEFAULT_OUT_DIR) -> Path:
    """Build the controller FMU (only when its source changed)."""
    out_dir = Path(out_dir)
    source = FMU_SRC / CONTROLLER
    digest = hashlib.sha256(source.read_bytes()).hexdigest()
    fmu = out_dir / "inerter_pd_controller.fmu"
    stamp = out_dir / "inerter_pd_controller.fmu.source-hash"
    if fmu.is_file() and stamp.is_file() and stamp.read_text().strip() == digest:
        return fmu
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="inerter_ctrl_") as tmp:
        script = Path(tmp) / "inerter_pd_controller.py"
        shutil.copy2(source, script)
        built = _run_pythonfmu(script, Path(tmp) / "out", [])
        _complete_model_description(built, fmu, CONTROLLER_UNITS, digest)
    stamp.write_text(digest + "\n")
    return fmu


def controller_gains(scene=None) -> dict[str, float]:
    """kp, kd and reference of the ``pd`` force of `scene` (default: the shipped SYSTEM_SCENE)."""
    import inerter

    path = Path(scene) if scene else locations.scenarios() / SYSTEM_SCENE
    model = inerter.load(path)
    pd = [f for f in model.scene.forces.values() if f.function == "pd"]
    if len(pd) != 1:
        raise FmuBuildError(f"{path}: forces: expected one force with function = \"pd\" (the "
                            f"controller's law), found {len(pd)}")
    return {"kp": pd[0].kp, "kd": pd[0].kd, "reference": pd[0].reference}


# ----------------------------------------------------------------------------------------------
# System structure files
# ----------------------------------------------------------------------------------------------
def _number(x: float) -> str:
    return repr(float(x))


def build_system(out_dir=DEFAULT_OUT_DIR, step: float = 0.01, gains=None) -> dict[str, Path]:
    """Build the plant and controller FMUs into `out_dir` and write the system beside them as
    ``OspSystemStructure.xml`` and ``SystemStructure.ssd`` (FMUs named relative to them).

    `step` is the communication step (s); `gains` default to :func:`controller_gains`. Returns
    the paths by role: ``plant``, ``controller``, ``osp``, ``ssd``.
    """
    if not (isinstance(step, (int, float)) and math.isfinite(step) and step >= 1e-9):
        raise FmuBuildError(f"step: {step!r}: expected a communication step of at least 1e-9 s "
                            f"(libcosim counts time in whole nanoseconds)")
    out_dir = Path(out_dir)
    gains = dict(gains or controller_gains())
    paths = {PLANT: build(locations.scenarios() / PLANT_SCENE, out_dir),
             CTRL: build_controller(out_dir)}
    paths["osp"] = out_dir / OSP_FILE
    paths["osp"].write_bytes(_osp_structure(paths, step, gains))
    paths["ssd"] = out_dir / SSD_FILE
    paths["ssd"].write_bytes(_ssd_structure(paths, step, gains))
    return paths


def _osp_structure(paths, step, gains) -> bytes:
    ns = "http://opensimulationplatform.com/MSMI/OSPSystemStructure"
    ET.register_namespace("", ns)

    def q(tag):
        return f"{{{ns}}}{tag}"

    root = ET.Element(q("OspSystemStructure"), version="0.1")
    ET.SubElement(root, q("StartTime")).text = "0.0"
    ET.SubElement(root, q("BaseStepSize")).text = _number(step)
    ET.SubElement(root, q("Algorithm")).text = "fixedStep"
    simulators = ET.SubElement(root, q("Simulators"))
    for role in (PLANT, CTRL):
        sim = ET.SubElement(simulators, q("Simulator"), name=role, source=paths[role].name,
                            stepSize=_number(step))
        if role == CTRL:
            values = ET.SubElement(sim, q("InitialValues"))
            for name, value in gains.items():
                node = ET.SubElement(values, q("InitialValue"), variable=name)
                ET.SubElement(node, q("Real"), value=_number(value))
    connections = ET.SubElement(root, q("Connections"))
    for source, output, target, input_ in CONNECTIONS:
        link = ET.SubElement(connections, q("VariableConnection"))
        ET.SubElement(link, q("Variable"), simulator=source, name=output)
        ET.SubElement(link, q("Variable"), simulator=target, name=input_)
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


def _ssd_structure(paths, step, gains) -> bytes:
    ssd = "http://ssp-standard.org/SSP1/SystemStructureDescription"
    ssc = "http://ssp-standard.org/SSP1/SystemStructureCommon"
    ssv = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    osp = "http://opensimulationplatform.com/SSP/OSPAnnotations"
    for prefix, uri in (("ssd", ssd), ("ssc", ssc), ("ssv", ssv), ("osp", osp)):
        ET.register_namespace(prefix, uri)

    def d(tag):
        return f"{{{ssd}}}{tag}"

    units = {PLANT: {"C.r[2]": "m", "C.v[2]": "m/s", "C.f[2]": "N"}, CTRL: CONTROLLER_UNITS}
    kinds = {PLANT: {"C.r[2]": "output", "C.v[2]": "output", "C.f[2]": "input"},
             CTRL: {"y": "input", "v": "input", "F": "output", **{g: "parameter" for g in gains}}}
    root = ET.Element(d("SystemStructureDescription"), version="1.0", name="two_bar_pd")
    system = ET.SubElement(root, d("System"), name="two_bar_pd",
                           description="The two-bar mechanism with a PD controller on C along Y")
    elements = ET.SubElement(system, d("Elements"))
    for role in (PLANT, CTRL):
        component = ET.SubElement(elements, d("Component"), name=role, source=paths[role].name,
                                  type="application/x-fmu-sharedlibrary")
        connectors = ET.SubElement(component, d("Connectors"))
        for name, kind in kinds[role].items():
            connector = ET.SubElement(connectors, d("Connector"), name=name, kind=kind)
            ET.SubElement(connector, f"{{{ssc}}}Real", unit=units[role][name])
        if role == CTRL:
            values = ET.SubElement(ET.SubElement(ET.SubElement(component, d("ParameterBindings")),
                                                 d("ParameterBinding")), d("ParameterValues"))
            parameters = ET.SubElement(ET.SubElement(values, f"{{{ssv}}}ParameterSet",
                                                     version="1.0", name="gains"),
                                       f"{{{ssv}}}Parameters")
            for name, value in gains.items():
                parameter = ET.SubElement(parameters, f"{{{ssv}}}Parameter", name=name)
                ET.SubElement(parameter, f"{{{ssv}}}Real", value=_number(value))
    connections = ET.SubElement(system, d("Connections"))
    for source, output, target, input_ in CONNECTIONS:
        ET.SubElement(connections, d("Connection"), startElement=source, startConnector=output,
                      endElement=target, endConnector=input_)
    unit_list = ET.SubElement(root, d("Units"))
    for unit in sorted({u for role in units.values() for u in role.values()}):
        exponents, factor = si_unit(unit)
        node = ET.SubElement(unit_list, f"{{{ssc}}}Unit", name=unit)
        attrib = {b: str(e) for b, e in exponents.items()}
        if factor != 1.0:
            attrib["factor"] = _number(factor)
        ET.SubElement(node, f"{{{ssc}}}BaseUnit", attrib)
    experiment = ET.SubElement(root, d("DefaultExperiment"), startTime="0.0")
    annotation = ET.SubElement(ET.SubElement(experiment, d("Annotations")), f"{{{ssc}}}Annotation",
                               type="com.opensimulationplatform")
    ET.SubElement(ET.SubElement(annotation, f"{{{osp}}}Algorithm"), f"{{{osp}}}FixedStepAlgorithm",
                  baseStepSize=_number(step))
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="UTF-8", xml_declaration=True)


# ----------------------------------------------------------------------------------------------
# The master loops
# ----------------------------------------------------------------------------------------------
class _Slave:
    """One FMU instance through fmpy's low-level API, addressed by variable names."""

    def __init__(self, path, start=None, instance="instance"):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.dir = extract(str(path))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.dir,
                             modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance)
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in (start or {}).items():
            self.set(name, value)
        self.fmu.exitInitializationMode()

    def set(self, name, value):
        if self.types[name] == "Boolean":
            self.fmu.setBoolean([self.vr[name]], [bool(value)])
        else:
            self.fmu.setReal([self.vr[name]], [float(value)])

    def get(self, *names):
        return self.fmu.getReal([self.vr[n] for n in names])

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.dir, ignore_errors=True)


def communication_points(stop_time: float, step: float) -> np.ndarray:
    """t_k = (k·h_ns)/10⁹ up to `stop_time`, h_ns the step in whole nanoseconds (as libcosim)."""
    h_ns = int(step * 1e9)                    # libcosim's to_duration truncates likewise
    n = int(round(stop_time / step))
    return np.array([k * h_ns for k in range(n + 1)], dtype=np.int64) / 1e9


@dataclass
class CoupledRun:
    """A coupled run at the communication points t: the plant's C.r[2] (y) and C.v[2] (v), and the
    force F[k] its input C.f[2] held over [t_k, t_{k+1}] (F[-1]: the one the next step would hold)."""
    coupling: str
    t: np.ndarray
    y: np.ndarray
    v: np.ndarray
    F: np.ndarray


def run_system(mechanism_fmu, controller_fmu, stop_time, step, gains, coupling="sequential",
               start=None) -> CoupledRun:
    """The plant and the controller on an fmpy master loop (`coupling`: see the module's text)."""
    if coupling not in COUPLINGS:
        raise ValueError(f"coupling: {coupling!r}: expected one of {', '.join(COUPLINGS)}")
    t = communication_points(stop_time, step)
    n = len(t) - 1
    y, v, F = np.empty(n + 1), np.empty(n + 1), np.empty(n + 1)
    plant = _Slave(mechanism_fmu, start, PLANT)
    ctrl = _Slave(controller_fmu, gains, CTRL)
    try:
        # Both loops start from consistent values at t_0: the controller's force of the plant's
        # initial outputs (the controller has direct feedthrough).
        y[0], v[0] = plant.get("C.r[2]", "C.v[2]")
        ctrl.set("y", y[0])
        ctrl.set("v", v[0])
        (force,) = ctrl.get("F")
        for k in range(n + 1):
            F[k] = force
            if k == n:
                break
            plant.set("C.f[2]", force)
            ctrl.fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=t[k + 1] - t[k])
            plant.fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=t[k + 1] - t[k])
            y[k + 1], v[k + 1] = plant.get("C.r[2]", "C.v[2]")
            if coupling == "parallel":
                (force,) = ctrl.get("F")          # of the inputs it held over the step
            ctrl.set("y", y[k + 1])
            ctrl.set("v", v[k + 1])
            if coupling == "sequential":
                (force,) = ctrl.get("F")          # of the plant's outputs at t_{k+1}
    finally:
        plant.close()
        ctrl.close()
    return CoupledRun(coupling, t, y, v, F)


def run_coupled(mechanism_fmu, controller_fmu, stop_time, step, kp, kd, reference, start=None):
    """The sequential master loop; returns (time, C_y, F) sampled at the communication points."""
    run = run_system(mechanism_fmu, controller_fmu, stop_time, step,
                     {"kp": kp, "kd": kd, "reference": reference}, "sequential", start)
    return run.t, run.y, run.F
