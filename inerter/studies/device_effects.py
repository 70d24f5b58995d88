"""The device study: ``inerter device-study --out DIR``.

How each effect of a real ball-screw inerter moves a paper scene's results away from those of the
ideal inerter (Zhu et al. 2022, Eq. 9), on the two-bar mechanism (Sec. 3.4: peak-to-peak and mean
offset of C along Y over the last 10 periods of 60 s) and on the braced frame (peak drifts of the
slab along X and Y). Each row is the scene with its inerters built as a device
(:mod:`inerter.elements.device`, docs/scene_format.md "Inerter devices") with one group of effects:

- ``ideal``: the flywheel alone, b = J (2π/p)² (Smith 2002, IEEE TAC 47(10) Sec. III) with J from
  the scene's b, so the paper's ideal inerter;
- ``masses``: the flywheel's transverse inertia and mass, the housing and the rod
  (:mod:`inerter.elements.device_inertia`), and in 3D the housing's mount (gyroscopic moments);
- ``friction``: Coulomb (tanh-regularised) and viscous friction on the stroke rate;
- ``compliance``: a spring in series with the inerter;
- ``backlash``: a dead zone in that series connection (with the same spring: backlash needs one);
- ``end_stops``: Hunt-Crossley contact past the stroke limits (c_s from e, Lankarani & Nikravesh
  1990);
- ``efficiency``: the screw's efficiency, forward η_f while the terminals drive the flywheel and
  backward η_b while it drives them (:mod:`inerter.elements.device`);
- ``all``: every effect above, the efficiency acting in the series connection on the inerter's
  own stroke (inerter.elements.device, "Efficiency", the series case); in 3D without the mount,
  which the engine refuses beside a series connection (the mount's gyroscopic terms spin the
  flywheel with the terminal distance, not with the inerter's own stroke).

The device's parameters come from ``devices/ballscrew_device.toml``, a source for every
value (most are representative, assumed: its header says which). Each row is written as a scene
file (``DIR/scenes/``), run by the solver (``inerter.load(...).simulate()``) and through its FMU
(fmpy, communication step = output interval 0.01 s, :func:`inerter.fmu.run.simulate_fmu`).
"""
from __future__ import annotations

import argparse
import csv
import json
import math
import shutil
import sys
import time
import tomllib
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from inerter.studies.arguments import Parser
from inerter.common.errors import InerterError, SceneError, shown
from inerter.common.locations import devices as shipped_devices
from inerter.common.options import output_path
from inerter.common.locations import scenarios as _shipped_scenarios

#: The rows: name → (label, effects). Each row is the ideal device plus its effects.
ROWS = {
    "ideal": ("ideal inerter (flywheel only)", ()),
    "masses": ("+ transverse inertia, masses (3D: mount)", ("masses",)),
    "friction": ("+ friction (Coulomb + viscous)", ("friction",)),
    "compliance": ("+ series compliance", ("compliance",)),
    "backlash": ("+ backlash (with the series spring)", ("compliance", "backlash")),
    "end_stops": ("+ end stops", ("end_stops",)),
    "efficiency": ("+ screw efficiency (η_f, η_b)", ("efficiency",)),
    "all": ("all effects together (3D: no mount)", ("masses", "friction", "compliance", "backlash", "end_stops",
                                                     "efficiency")),
}
SCENES = ("two_bar_2d", "braced_frame_3d")
#: The FMU's communication step (s), the scenes' output interval.
FMU_STEP = 0.01


class DeviceStudyError(InerterError):
    """The device data file or a study option is unusable; one line naming the file or option,
    the field, the value and what was expected."""

    def __init__(self, where: str, fld: str, value, expected: str, problem: str = "invalid value"):
        super().__init__(f"{where}: {fld + ': ' if fld else ''}{problem} (got {shown(value)}; expected {expected})")


def device_data_path() -> Path:
    return shipped_devices() / "ballscrew_device.toml"


@dataclass(frozen=True)
class Value:
    value: object
    unit: str
    source: str


@dataclass(frozen=True)
class SceneCase:
    """One scene of the study: its file, its inerters, its metrics and its device values."""
    key: str
    scene: Path
    inerters: tuple[str, ...]
    inertance: str
    metrics: tuple[str, ...]
    values: dict = field(default_factory=dict)          # name → Value


def _value(path: Path, fld: str, raw) -> Value:
    if not isinstance(raw, dict) or "value" not in raw:
        raise DeviceStudyError(str(path), fld, raw, "a table { value, unit, source }")
    source = raw.get("source")
    if not isinstance(source, str) or len(source.strip()) < 10:
        raise DeviceStudyError(str(path), fld + ".source", source,
                               "a string saying where the value comes from (or that it is assumed)", "missing source")
    return Value(raw["value"], str(raw.get("unit", "1")), source.strip())


SCENE_KEYS = ("scene", "inerters", "inertance", "metrics")
DEVICE_VALUES = ("lead", "specific_inertance", "flywheel_mass_share", "housing_mass_share", "rod_mass_share",
                 "transverse_ratio", "part_length_share", "velocity_scale", "restitution", "backlash_gap",
                 "efficiency_forward", "efficiency_backward")
SCENE_VALUES = ("coulomb", "viscous", "series_stiffness", "stroke", "stop_stiffness", "impact_speed")


def read_device_data(path=None) -> tuple[dict, dict]:
    """The data file's device values ({name: Value}) and scenes ({key: SceneCase}); every value
    must carry a source string."""
    path = Path(path or device_data_path())
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise DeviceStudyError(str(path), "(file)", str(exc), "a readable TOML file", "cannot be read") from None
    raw_device = data.get("device", {})
    device = {}
    for name in DEVICE_VALUES:
        if name not in raw_device:
            raise DeviceStudyError(str(path), f"device.{name}", None, "a table { value, unit, source }", "missing")
        device[name] = _value(path, f"device.{name}", raw_device[name])
    cases = {}
    for key, raw in data.get("scenes", {}).items():
        missing = [k for k in (*SCENE_KEYS, *SCENE_VALUES) if k not in raw]
        if missing:
            raise DeviceStudyError(str(path), f"scenes.{key}", sorted(raw), "also " + ", ".join(missing), "missing fields")
        values = {k: _value(path, f"scenes.{key}.{k}", v) for k, v in raw.items() if k not in SCENE_KEYS}
        scene = path.parent / raw["scene"]                  # a scene beside the data file, else a shipped one
        if not scene.is_file():
            scene = _shipped_scenarios() / raw["scene"]
        if not scene.is_file():
            raise DeviceStudyError(str(path), f"scenes.{key}.scene", raw["scene"],
                                   "a scene file beside the data file or a shipped scene", "not found")
        cases[key] = SceneCase(key, scene, tuple(raw["inerters"]), raw["inertance"],
                               tuple(raw["metrics"]), values)
    return device, cases


# ------------------------------------------------------------------------------------------------
# The row scenes
# ------------------------------------------------------------------------------------------------
def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)                        # a TOML basic string
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(f"no TOML for {v!r}")


def to_toml(data: dict, prefix: str = "") -> str:
    """A scene's dict as TOML text: scalars first, then sub-tables, then arrays of tables."""
    lines, tables, arrays = [], [], []
    for k, v in data.items():
        if isinstance(v, dict) and prefix != "parameters":      # a parameter's entry on one line
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            arrays.append((k, v))
        else:
            lines.append(f"{k} = {_toml_value(v)}")
    text = "\n".join(lines) + ("\n" if lines else "")
    for k, v in tables:
        name = f"{prefix}.{k}" if prefix else k
        text += f"\n[{name}]\n" + to_toml(v, name)
    for k, items in arrays:
        name = f"{prefix}.{k}" if prefix else k
        for item in items:
            text += f"\n[[{name}]]\n" + to_toml(item, name)
    return text


def device_parameters(device: dict, case: SceneCase, b: float, length: float) -> dict:
    """The device's numbers for one scene, {name: (value, unit, description)}: J from b and the
    lead (b = J (2π/p)², Smith 2002), the masses from b and the specific inertance, the parts'
    geometry from the terminal distance `length`, c_s from e (Lankarani & Nikravesh 1990)."""
    d = {k: v.value for k, v in device.items()}
    s = {k: v.value for k, v in case.values.items()}
    mass = b / d["specific_inertance"]
    part = d["part_length_share"] * length
    J = b * (d["lead"] / (2.0 * math.pi)) ** 2
    m_h, m_r = d["housing_mass_share"] * mass, d["rod_mass_share"] * mass
    k_s, v_i, e = s["stop_stiffness"], s["impact_speed"], d["restitution"]
    return {
        "dev_lead": (d["lead"], "m", "ball-screw lead p"),
        "dev_J": (J, "kg.m2", "flywheel axial inertia J = b (p/(2 pi))^2"),
        "dev_Jt": (d["transverse_ratio"] * J, "kg.m2", "flywheel transverse inertia (thin disc J/2)"),
        "dev_m_fw": (d["flywheel_mass_share"] * mass, "kg", "flywheel mass"),
        "dev_m_h": (m_h, "kg", "housing mass"),
        "dev_m_r": (m_r, "kg", "rod mass"),
        "dev_h": (part / 2.0, "m", "housing, rod and flywheel centres from their terminals"),
        "dev_It_h": (m_h * part ** 2 / 12.0, "kg.m2", "housing transverse inertia (slender, m l^2/12)"),
        "dev_It_r": (m_r * part ** 2 / 12.0, "kg.m2", "rod transverse inertia (slender, m l^2/12)"),
        "dev_Fc": (s["coulomb"], "N", "Coulomb friction"),
        "dev_cf": (s["viscous"], "N.s/m", "viscous friction"),
        "dev_vs": (d["velocity_scale"], "m/s", "friction regularisation velocity scale"),
        "dev_kc": (s["series_stiffness"], "N/m", "series stiffness"),
        "dev_gap": (d["backlash_gap"], "m", "backlash total free play"),
        "dev_Lmin": (length - s["stroke"], "m", "lower stroke limit"),
        "dev_Lmax": (length + s["stroke"], "m", "upper stroke limit"),
        "dev_ks": (k_s, "N/m", "end-stop contact stiffness"),
        "dev_cs": (3.0 * k_s * (1.0 - e * e) / (4.0 * v_i), "N.s/m2", "end-stop damping 3 k_s (1 - e^2)/(4 v)"),
        "dev_etaf": (d["efficiency_forward"], "1", "screw efficiency, terminals driving the flywheel"),
        "dev_etab": (d["efficiency_backward"], "1", "screw efficiency, flywheel driving the terminals"),
    }


def device_tables(effects, dimension: int, mount_axis=None) -> dict:
    """The ``[elements.NAME.device]`` sub-tables of a row, over the parameters of
    :func:`device_parameters`."""
    dev = {"flywheel": {"inertia": "dev_J", "lead": "dev_lead"}}
    if "masses" in effects:
        dev["flywheel"].update(transverse_inertia="dev_Jt", mass="dev_m_fw", centre="dev_h")
        dev["housing"] = {"mass": "dev_m_h", "centre": "dev_h", "transverse_inertia": "dev_It_h"}
        dev["rod"] = {"mass": "dev_m_r", "centre": "dev_h", "transverse_inertia": "dev_It_r"}
        if dimension == 3 and mount_axis is not None and "compliance" not in effects:
            dev["mount"] = {"axis": list(mount_axis)}
    if "friction" in effects:
        dev["friction"] = {"coulomb": "dev_Fc", "viscous": "dev_cf", "velocity_scale": "dev_vs"}
    if "compliance" in effects:
        dev["compliance"] = {"stiffness": "dev_kc"}
    if "backlash" in effects:
        dev["backlash"] = {"gap": "dev_gap"}
    if "efficiency" in effects:
        dev["efficiency"] = {"forward": "dev_etaf", "backward": "dev_etab"}
    if "end_stops" in effects:
        dev["end_stops"] = {"min": "dev_Lmin", "max": "dev_Lmax", "stiffness": "dev_ks", "damping": "dev_cs"}
    return dev


def _terminal_lengths(model, inerters) -> dict:
    """Each inerter's terminal distance L0 in the scene's initial pose."""
    mech = model.mechanism
    q0, v0 = np.asarray(mech.q0, dtype=float), np.asarray(mech.v0, dtype=float)
    return {name: float(model.signals.function(f"{name}.s_rel")(0.0, q0, v0)) for name in inerters}


def scene_device_values(case: SceneCase, device: dict) -> dict:
    """:func:`device_parameters` for the case's scene: its b and its inerters' distance L0."""
    import inerter
    model = inerter.load(case.scene)
    lengths = _terminal_lengths(model, case.inerters)
    if len(set(round(v, 12) for v in lengths.values())) != 1:
        raise DeviceStudyError(str(case.scene), "inerters", lengths, "inerters of one terminal distance "
                               "(the device's geometry is one per scene)")
    if case.inertance not in model.scene.parameters:
        raise DeviceStudyError(str(device_data_path()), f"scenes.{case.key}.inertance", case.inertance,
                               f"a parameter of {case.scene.name}", "unknown parameter")
    b = float(model.scene.parameters[case.inertance].value)
    return device_parameters(device, case, b, next(iter(lengths.values())))


def write_row_scene(case: SceneCase, device: dict, row: str, folder: Path) -> Path:
    """The scene of one row: the case's scene with its inerters built as the row's device, its
    device numbers as parameters (described by their sources), written into `folder` with the
    records it reads."""
    from inerter.scene.reader import read_toml
    _, data = read_toml(case.scene)
    params = data["parameters"]
    for name, (value, unit, what) in scene_device_values(case, device).items():
        params[name] = {"value": value, "unit": unit, "description": f"device study: {what}"}
    dim = int(data.get("scene", {}).get("dimension", 2))
    axes = case.values["mount_axes"].value if "mount_axes" in case.values else {}
    for name in case.inerters:
        element = data["elements"][name]
        element.pop("b", None)
        element["device"] = device_tables(ROWS[row][1], dim, axes.get(name))
    name = f"{case.key}_dev_{row}"
    data["scene"]["name"] = name
    data["scene"]["description"] = f"{case.key} with its inerters as a ball-screw device: {ROWS[row][0]} (device study)"
    folder.mkdir(parents=True, exist_ok=True)
    import inerter
    for rel in inerter.load(case.scene).scene.data_files:       # records, relative to the scene
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(case.scene.parent / rel, folder / rel)
    path = folder / f"{name}.toml"
    path.write_text(f"# {data['scene']['description']}: written by inerter device-study from "
                    f"{case.scene.name} and devices/ballscrew_device.toml.\n" + to_toml(data), encoding="utf-8")
    return path


# ------------------------------------------------------------------------------------------------
# The runs
# ------------------------------------------------------------------------------------------------
@dataclass
class RowResult:
    scene: str
    row: str
    metric: str
    solver: float
    fmu: float | None = None
    solver_sampled: float | None = None     # the solver's, from its samples as the FMU's (spline)
    solver_seconds: float = 0.0
    fmu_seconds: float = 0.0


def run_row(case: SceneCase, path: Path, stop_time=None, fmu_dir=None) -> list[RowResult]:
    """One row's metrics by the solver and (with `fmu_dir`) through its FMU."""
    import inerter
    from inerter.api import compute_metrics
    overrides = {"experiment.output_interval": FMU_STEP}           # the FMU's samples, for _Sampled
    if stop_time is not None:
        overrides["experiment.stop_time"] = float(stop_time)
    t0 = time.perf_counter()
    result = inerter.load(path, **overrides).simulate()
    t_solver = time.perf_counter() - t0
    if result.status != "ok":
        raise DeviceStudyError(str(path), "(run)", result.message, "a run to the stop time", "the solver stopped")
    missing = [m for m in case.metrics if m not in result.metrics]
    if missing:
        raise DeviceStudyError(str(path), "metrics", missing, "metrics of the run (--stop-time long enough?)",
                               "not computed: " + "; ".join(result.metric_errors.values()))
    sampled = compute_metrics(result.model, _Sampled(result))
    fmu_metrics, t_fmu = {}, 0.0
    if fmu_dir is not None:
        from inerter.fmu.build import build
        from inerter.fmu.run import simulate_fmu
        t0 = time.perf_counter()
        fmu_path = build(path, fmu_dir)
        fmu = simulate_fmu(path, {}, stop_time=stop_time, step=FMU_STEP, fmu_path=fmu_path)
        t_fmu = time.perf_counter() - t0
        if fmu.status != "ok":
            raise DeviceStudyError(str(fmu_path), "(run)", fmu.message, "a run to the stop time", "the FMU stopped")
        fmu_metrics = fmu.metrics
    row = path.stem.split("_dev_", 1)[1]
    return [RowResult(case.key, row, m, float(result.metrics[m]),
                      float(fmu_metrics[m]) if m in fmu_metrics else None, float(sampled[m]), t_solver, t_fmu)
            for m in case.metrics]


class _Sampled:
    """A solver result seen as an FMU's is: its samples, a cubic spline through them for the
    metrics (:func:`inerter.api.sample_spline`), no dense output."""

    def __init__(self, result):
        self.time, self._result, self.metric_errors = result.time, result, {}

    def __getitem__(self, name):
        return self._result[name]

    def dense(self, name):
        from inerter.api import sample_spline
        return sample_spline(self.time, self._result[name])


def check_study(data=None, scenes=SCENES, rows=tuple(ROWS), stop_time=None) -> tuple[dict, dict]:
    """The study's data file, scenes, rows and stop time, checked before anything is run or written;
    returns the data file's (device, cases) (:func:`read_device_data`)."""
    device, cases = read_device_data(data)
    for key in scenes:
        if key not in cases:
            raise DeviceStudyError("--scenes", "", key, "one of " + ", ".join(cases), "unknown scene")
    for row in rows:
        if row not in ROWS:
            raise DeviceStudyError("--rows", "", row, "one of " + ", ".join(ROWS), "unknown row")
    if stop_time is not None:
        check_stop_time(stop_time, [cases[key] for key in scenes])
    return device, cases


def check_stop_time(stop_time, cases):
    """--stop-time read as each scene's runs read it: the experiment's own checks (with the FMU's
    step, :data:`FMU_STEP`), and long enough for the scene's steady-state metrics of the study,
    which read the last `periods` periods of the excitation (``two_bar_2d``: 10 periods of 1 s), a
    shorter run computing none of them (the first row then failed, after its run)."""
    from inerter.scene.reader import build_scene, read_toml
    if not (stop_time > 0 and math.isfinite(stop_time)):
        raise DeviceStudyError("--stop-time", "", stop_time, "a positive number of seconds", "out of range")
    for case in cases:
        scene = build_scene(*read_toml(case.scene), {})
        try:
            scene.experiment_with({"stop_time": stop_time, "output_interval": FMU_STEP, "communication_step": FMU_STEP})
        except SceneError as exc:          # (the study samples every FMU_STEP: a long run has too many samples)
            raise DeviceStudyError("--stop-time", "", stop_time, f"a stop time {case.scene.name} can run to with "
                                   f"the study's samples every {FMU_STEP:g} s ({exc.field}: {exc.problem}; expected "
                                   f"{exc.expected})", "refused by the scene's experiment") from None
        for m in scene.metrics:
            keys = [f"{m.prefix}_{k}" if m.prefix else k for k in ("peak_to_peak", "mean_offset")]
            need = m.periods * m.period if m.kind == "steady_state" else 0.0
            if stop_time < need and set(keys) & set(case.metrics):
                raise DeviceStudyError("--stop-time", "", stop_time, f"at least {need:g} s: {case.key}'s "
                                       f"{', '.join(k for k in keys if k in case.metrics)} read the last {m.periods} "
                                       f"periods of {m.period:g} s of its run", "too short")


def device_study(out, scenes=SCENES, rows=tuple(ROWS), stop_time=None, fmu=True, data=None,
                 progress=None) -> list[RowResult]:
    """Every (scene, row): write its scene into ``out/scenes``, run it by the solver and (with
    `fmu`) through its FMU (built into ``out/fmu``). Returns the rows' metrics. Its arguments are
    checked before anything runs (:func:`check_study`)."""
    device, cases = check_study(data, scenes, rows, stop_time)
    out = Path(out)
    results = []
    for key in scenes:
        for row in ("ideal", *[r for r in rows if r != "ideal"]):     # the reference first
            path = write_row_scene(cases[key], device, row, out / "scenes")
            got = run_row(cases[key], path, stop_time, out / "fmu" if fmu else None)
            results.extend(got)
            if progress:
                progress(got)
    return results


# ------------------------------------------------------------------------------------------------
# The table and the figure
# ------------------------------------------------------------------------------------------------
def table_rows(results: list[RowResult]) -> list[dict]:
    """Each result with its change from the ideal row (absolute and %), by the solver and by the
    FMU, and the FMU's difference from the solver."""
    ideal = {(r.scene, r.metric): r for r in results if r.row == "ideal"}
    out = []
    for r in results:
        ref = ideal[(r.scene, r.metric)]
        row = {"scene": r.scene, "row": r.row, "label": ROWS[r.row][0], "metric": r.metric, "solver": r.solver,
               "solver_sampled": r.solver_sampled, "sampled_minus_solver": r.solver_sampled - r.solver,
               "solver_change": r.solver - ref.solver, "solver_change_pct": 100.0 * (r.solver - ref.solver) / ref.solver}
        if r.fmu is not None and ref.fmu is not None:
            row.update(fmu=r.fmu, fmu_change=r.fmu - ref.fmu, fmu_change_pct=100.0 * (r.fmu - ref.fmu) / ref.fmu,
                       fmu_minus_solver=r.fmu - r.solver)
        out.append(row)
    return out


CSV_FIELDS = ("scene", "row", "metric", "solver", "solver_change", "solver_change_pct", "fmu", "fmu_change",
              "fmu_change_pct", "fmu_minus_solver",
              "solver_sampled", "sampled_minus_solver")


def write_csv(rows: list[dict], path: Path) -> Path:
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for row in rows:
            w.writerow({k: (f"{v:.12g}" if isinstance(v, float) else v) for k, v in row.items()})
    return path


def _mm(v) -> str:
    return "–" if v is None else f"{1e3 * v:.4f}"


TABLE_HEADER = ("Device values: devices/ballscrew_device.toml. Sourced: b = J (2π/p)² (Smith 2002), "
                "e = 0.5 (Appl. Sci. 13 (2023) 2168), c_s from e (Lankarani & Nikravesh 1990), the device's mass "
                "m = b/90 (Madhamshetty & Manimala 2018). The lead, mass split, friction, series stiffness, "
                "backlash, transverse inertia's shape, stroke limits, contact stiffness and screw efficiencies are "
                "REPRESENTATIVE, "
                "ASSUMED, not the identified parameters of a published device.")


def markdown_table(rows: list[dict]) -> str:
    """The rows as a markdown table (metrics in mm)."""
    lines = ["> " + TABLE_HEADER, "",
             "| scene | row | metric | solver (mm) | change (mm) | change (%) | FMU (mm) | change (mm) | "
             "change (%) | FMU − solver (mm) | spline through the solver's samples − solver (mm) |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        fmu = r.get("fmu")
        fmu_pct = "–" if fmu is None else f"{r['fmu_change_pct']:+.3f}"
        diff = "–" if fmu is None else f"{1e3 * r['fmu_minus_solver']:.2e}"
        lines.append(f"| {r['scene']} | {r['label']} | {r['metric']} | {_mm(r['solver'])} | {_mm(r['solver_change'])} | "
                     f"{r['solver_change_pct']:+.3f} | {_mm(fmu)} | {_mm(r.get('fmu_change'))} | {fmu_pct} | {diff} | "
                     f"{1e3 * r['sampled_minus_solver']:.1e} |")
    return "\n".join(lines) + "\n"


def parameter_table(data=None, scenes=SCENES) -> str:
    """The device's numbers in each scene (the row scenes' ``dev_*`` parameters), as markdown."""
    device, cases = read_device_data(data)
    values = {key: scene_device_values(cases[key], device) for key in scenes}
    first = values[scenes[0]]
    lines = ["| parameter | " + " | ".join(scenes) + " | unit | what |",
             "|---|" + "---:|" * len(scenes) + "---|---|"]
    for name, (_, unit, what) in first.items():
        lines.append(f"| {name} | " + " | ".join(f"{values[k][name][0]:.4g}" for k in scenes) + f" | {unit} | {what} |")
    return "\n".join(lines) + "\n"


def plot_changes(rows: list[dict], path: Path) -> Path:
    """A bar chart of each effect's change from the ideal (%), one panel per scene (a row of the
    figure) and metric (a column): bars the solver's, dots the FMU's."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    metrics = {s: list(dict.fromkeys(r["metric"] for r in rows if r["scene"] == s)) for s in scenes}
    ncol = max(len(m) for m in metrics.values())
    fig, axes = plt.subplots(len(scenes), ncol, figsize=(5.2 * ncol + 1.6, 2.9 * len(scenes)), squeeze=False)
    for i, scene in enumerate(scenes):
        for j in range(ncol):
            ax = axes[i][j]
            if j >= len(metrics[scene]):
                ax.set_visible(False)
                continue
            metric = metrics[scene][j]
            sel = {r["row"]: r for r in rows if (r["scene"], r["metric"]) == (scene, metric) and r["row"] != "ideal"}
            keys = [k for k in ROWS if k in sel]
            y = np.arange(len(keys))
            ax.barh(y, [sel[k]["solver_change_pct"] for k in keys], color="C0", label="solver")
            fm = [(n, sel[k]["fmu_change_pct"]) for n, k in enumerate(keys) if "fmu_change_pct" in sel[k]]
            if fm:
                ax.plot([v for _, v in fm], [n for n, _ in fm], "o", color="C3", ms=4, label="FMU (fmpy)")
            ax.axvline(0.0, color="0.3", lw=0.8)
            ax.set_yticks(y, [ROWS[k][0] for k in keys] if j == 0 else [""] * len(keys), fontsize=8)
            ax.invert_yaxis()
            ax.set_title(f"{scene}: {metric}", fontsize=9)
            ax.grid(axis="x", alpha=0.3)
            if i == len(scenes) - 1:
                ax.set_xlabel("change from the ideal inerter (%)", fontsize=9)
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper right", fontsize=8, frameon=False)
    fig.suptitle("Ball-screw device effects against the ideal inerter (device values mostly representative, "
                 "assumed)", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# ------------------------------------------------------------------------------------------------
# The command
# ------------------------------------------------------------------------------------------------
def device_study_parser() -> argparse.ArgumentParser:
    p = Parser(prog="inerter device-study",
               description="Each effect of a ball-screw inerter against the ideal inerter on "
                           "the paper's two-bar and the braced frame, by the solver and the FMU: "
                           "a table (.md, .csv) and a bar chart (.png).")
    p.add_argument("--out", default="out/device_study", metavar="DIR",
                   help="folder of the table, the figure, the row scenes and their FMUs (default: %(default)s)")
    p.add_argument("--scenes", nargs="+", default=list(SCENES), metavar="SCENE",
                   help="the scenes: " + ", ".join(SCENES) + " (default: both)")
    p.add_argument("--rows", nargs="+", default=list(ROWS), metavar="ROW",
                   help="the rows: " + ", ".join(ROWS) + " (default: all; ideal is always run)")
    p.add_argument("--stop-time", type=float, default=None, metavar="SECONDS",
                   help="a shorter run than the scenes' own (60 s two-bar, 15 s braced frame); at least "
                        "the two-bar's steady-state window, 10 s")
    p.add_argument("--no-fmu", action="store_true", help="the solver only")
    p.add_argument("--data", default=None, metavar="TOML",
                   help="the device's values (default: devices/ballscrew_device.toml)")
    return p


def main(argv=None) -> int:
    args = device_study_parser().parse_args(argv)
    check_study(args.data, args.scenes, args.rows, args.stop_time)          # before the folder is made
    out = output_path(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise DeviceStudyError("--out", "", str(out), "a folder that can be created and written",
                               f"cannot create the output folder: {exc.strerror or exc}") from None
    t0 = time.perf_counter()

    def progress(got):
        for r in got:
            fmu = "" if r.fmu is None else f", FMU {r.fmu:.9g} ({r.fmu_seconds:.1f} s with its build)"
            print(f"  {r.scene} {r.row}: {r.metric} = {r.solver:.9g} ({r.solver_seconds:.1f} s){fmu}", flush=True)

    results = device_study(out, args.scenes, args.rows, args.stop_time, not args.no_fmu, args.data, progress)
    rows = table_rows(results)
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    command = "inerter device-study " + " ".join(sys.argv[2:] if argv is None else argv)
    md = out / "device_study.md"
    md.write_text(f"Written {stamp} by `{command.strip()}` in {time.perf_counter() - t0:.0f} s.\n\n"
                  + markdown_table(rows) + "\nThe device's numbers in each scene:\n\n"
                  + parameter_table(args.data, tuple(args.scenes)))
    written = [md, write_csv(rows, out / "device_study.csv"), plot_changes(rows, out / "device_study.png")]
    print(markdown_table(rows))
    print("wrote " + ", ".join(str(p) for p in written))
    return 0


def main_device_study(argv=None) -> int:
    """``inerter device-study``: the device study (this module)."""
    from inerter.studies.sweep import _guarded
    return _guarded(main, argv)
