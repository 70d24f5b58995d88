"""A coupled co-simulation on fmpy: the two-bar FMU driven by the PD-controller FMU.

The master loop (Gauss–Seidel order, one communication step h): read C.r[2], C.v[2] from the
mechanism at t_k, set them as the controller's inputs, read its force F_k (direct feedthrough),
set C.f[2] = F_k on the mechanism (held over the step) and step both FMUs to t_k + h.
The same system solved as one scene (`two_bar_2d_pd.toml`, a `pd` force at C) is the reference:
the co-simulation differs from it only by the zero-order hold of F, so the difference shrinks
in proportion to h.
"""
from __future__ import annotations

import hashlib
import shutil
import tempfile
from pathlib import Path

import numpy as np

from inerter.fmu.build import DEFAULT_OUT_DIR, FMU_SRC, _complete_model_description, _run_pythonfmu

CONTROLLER = "pd_controller.py"
CONTROLLER_UNITS = {"kp": "N/m", "kd": "N.s/m", "reference": "m", "y": "m", "v": "m/s", "F": "N"}


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


def run_coupled(mechanism_fmu, controller_fmu, stop_time, step, kp, kd, reference, start=None):
    """Master loop; returns (time, C_y, F) sampled at the communication points."""
    plant = _Slave(mechanism_fmu, start, "mechanism")
    ctrl = _Slave(controller_fmu, {"kp": kp, "kd": kd, "reference": reference}, "controller")
    n = int(round(stop_time / step))
    t = np.arange(n + 1) * step
    y = np.empty(n + 1)
    F = np.empty(n + 1)
    try:
        for k in range(n + 1):
            cy, cv = plant.get("C.r[2]", "C.v[2]")
            ctrl.set("y", cy)
            ctrl.set("v", cv)
            (force,) = ctrl.get("F")
            y[k], F[k] = cy, force
            if k == n:
                break
            plant.set("C.f[2]", force)
            ctrl.fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=step)
            plant.fmu.doStep(currentCommunicationPoint=t[k], communicationStepSize=step)
    finally:
        plant.close()
        ctrl.close()
    return t, y, F
