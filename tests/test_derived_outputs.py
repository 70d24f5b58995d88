"""Derived outputs (``[outputs.derived]``): expressions over other outputs, evaluated from them.

References: the same expression computed by hand (numpy) from the outputs it reads, sample by
sample (exact: the same operations on the same numbers); a peak metric on a derived output against
the expression evaluated on a fine grid of the integrator's dense output of the outputs it reads;
the FMU's outputs against the solver's; ModelStructure against the union of the dependencies of the
outputs read; bad declarations against the one-line error format (file, field, value, expected).
"""
from __future__ import annotations

import json
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest

import inerter
from inerter.cli import main as cli_main
from inerter.common.errors import SceneError

SCENE = """
[scene]
name = "derived_demo"

[parameters]
h = { value = 3.0, unit = "m" }

[ground.points]
A0 = [0, 0]

[bodies.mass]
mass = 1.0
inertia = 0.1
position = [1.0, 0.5]
velocity = [0.3, 0.2]
points = { P = [0, 0] }

[elements.spring]
type = "spring"
between = ["A0", "P"]
k = 50.0

[elements.inerter]
type = "inerter"
between = ["A0", "P"]
b = 0.5

[forces.push]
point = "P"
function = "input"

[experiment]
stop_time = 2.0
output_interval = 0.05
rtol = 1e-10

[outputs.derived]
radius = "hypot(P.r[1] - A0.r[1], P.r[2] - A0.r[2])"
ratio = { expression = "radius / h", description = "radius over h" }
power = "inerter.f * inerter.v_rel"

[[metrics]]
kind = "peak"
signal = "radius"
reference = 0
prefix = "radius"
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("derived") / "derived_demo.toml"
    path.write_text(SCENE)
    return path


@pytest.fixture(scope="module")
def result(scene):
    return inerter.load(scene).simulate()


def by_hand(columns):
    """The scene's three derived outputs from the columns they read (numpy, as a user would)."""
    radius = np.hypot(columns["P.r[1]"] - columns["A0.r[1]"], columns["P.r[2]"] - columns["A0.r[2]"])
    return {"radius": radius, "ratio": radius / 3.0, "power": columns["inerter.f"] * columns["inerter.v_rel"]}


def test_derived_outputs_equal_the_expression_by_hand(result):
    assert result.status == "ok"
    expected = by_hand({n: result[n] for n in ("P.r[1]", "A0.r[1]", "P.r[2]", "A0.r[2]", "inerter.f",
                                                "inerter.v_rel")})
    assert np.max(expected["radius"]) > 1.0 and np.max(np.abs(expected["power"])) > 1e-3   # they move
    everything = result.values()
    for name, values in expected.items():
        assert np.array_equal(result[name], values), name
        assert np.array_equal(everything[:, result.names.index(name)], values), name
    assert "derived output power (W) = inerter.f * inerter.v_rel" in result.model.terms()     # inerter describe
    frame = result.to_dataframe()
    assert np.array_equal(frame["power"].to_numpy(), expected["power"])
    assert frame.attrs["units"]["radius"] == "m" and frame.attrs["units"]["power"] == "W"


def test_derived_outputs_in_csv_and_summary(scene, tmp_path):
    """Through ``inerter run``: the CSV's derived columns are the expression of its other columns
    (to the CSV's 12 significant digits, with which each column is written), units in the header."""
    out = tmp_path / "out"
    assert cli_main(["run", str(scene), "--out", str(out)]) == 0
    data = np.genfromtxt(out / "derived_demo.csv", delimiter=",", names=True)
    header = (out / "derived_demo.csv").read_text().splitlines()[0].split(",")
    assert header[-3:] == ["radius (m)", "ratio (1)", "power (W)"]
    names = [h.rsplit(" (", 1)[0] for h in header]
    columns = {n: data[data.dtype.names[i]] for i, n in enumerate(names)}
    for name, values in by_hand(columns).items():
        assert np.allclose(columns[name], values, rtol=1e-11, atol=1e-12 * np.max(np.abs(values))), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["output_units"]["ratio"] == "1"
    assert summary["metric_units"]["radius_peak"] == "m"
    assert summary["metrics"]["radius_peak"] > 1.0


def test_peak_of_a_derived_output_comes_from_the_dense_output(result):
    """The metric evaluates the expression on the dense values of P.r[1], P.r[2], A0.r[...]: it
    equals the largest value on a grid of 400 001 points of that dense output (grid step 5 µs: the
    grid's own error at a smooth maximum is ~ (ω h)²/2 of the amplitude, below 1e-9 here)."""
    t = np.linspace(0.0, 2.0, 400_001)
    dense = {n: result.dense(n)(t) for n in ("P.r[1]", "A0.r[1]", "P.r[2]", "A0.r[2]")}
    fine = np.max(np.hypot(dense["P.r[1]"] - dense["A0.r[1]"], dense["P.r[2]"] - dense["A0.r[2]"]))
    assert result.metrics["radius_peak"] == pytest.approx(fine, rel=1e-9)
    assert result.metrics["radius_peak"] >= np.max(result["radius"])


def _structure(fmu: Path, tag: str = "Outputs") -> dict[str, set[str]]:
    with zipfile.ZipFile(fmu) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    names = [v.get("name") for v in root.find("ModelVariables")]
    return {names[int(u.get("index")) - 1]: {names[int(i) - 1] for i in (u.get("dependencies") or "").split()}
            for u in root.find("ModelStructure").find(tag)}


def test_fmu_derived_outputs_equal_the_solvers(scene, result, tmp_path):
    pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    from inerter.fmu.build import build
    from inerter.fmu.run import simulate_fmu
    fmu = build(scene, out_dir=tmp_path)
    deps = _structure(fmu)
    assert deps["radius"] == set() and deps["ratio"] == set()
    # the union of the dependencies of what it reads: the inerter's force follows the inputs at once
    assert deps["power"] == deps["inerter.f"] | deps["inerter.v_rel"] == {"P.f[1]", "P.f[2]"}
    initial = _structure(fmu, "InitialUnknowns")
    for name, reads in (("radius", ("P.r[1]", "A0.r[1]", "P.r[2]", "A0.r[2]")), ("power", ("inerter.f", "inerter.v_rel"))):
        assert initial[name] == set().union(*(initial[x] for x in reads)), name
    fmu_result = simulate_fmu(scene, fmu_path=fmu)
    assert fmu_result.status == "ok"
    assert np.allclose(fmu_result.time, result.time, rtol=0, atol=1e-12)
    for name in ("radius", "ratio", "power"):
        # the same integrator, rtol and atol through other steps (tests/test_shipped_scenes.py's bound)
        scale = 1e-10 * np.max(np.abs(result[name])) + 1e-12
        assert np.max(np.abs(fmu_result[name] - result[name])) <= 1000 * scale, name


BAD = [
    ('radius = "hypot(Q.r[1], P.r[2])"', "outputs.derived.radius", "unknown output 'Q.r[1]'"),
    ('radius = "hypot(P.r[1], "', "outputs.derived.radius", "does not parse"),
    ('radius = "P.r[1] + inerter.f"', "outputs.derived.radius", "adds a length and a force"),
    ('radius = "P.r[1] + nothing"', "outputs.derived.radius", "unknown name 'nothing'"),
    ('radius = "2 * pi"', "outputs.derived.radius", "reads no output"),
    ("radius = 3", "outputs.derived.radius", "not a string"),
    ('energy = "P.r[1]"', "outputs.derived.energy", "name clash"),
    ('h = "P.r[1]"', "outputs.derived.h", "name clash"),
    ('radius = { expression = "P.r[1]", unit = "N" }', "outputs.derived.radius.unit", "does not fit"),
    ('radius = { expression = "P.r[1]", unit = "mm" }', "outputs.derived.radius.unit", "not an SI unit"),
    ('radius = { expression = "P.r[1]", colour = "red" }', "outputs.derived.radius.colour", "unknown field"),
    ('radius = "ratio * h"\nratio = "P.r[1] / h"', "outputs.derived.radius", "unknown name 'ratio'"),
    # the same, saying why: an output reads only those declared above it
    ('radius = "ratio * h"\nratio = "P.r[1] / h"', "outputs.derived.radius",
     "unknown name 'ratio': a derived output declared below radius, which reads only those above it (move ratio up)"),
]


@pytest.mark.parametrize("entry, field, problem", BAD, ids=[b[2] for b in BAD])
def test_bad_derived_outputs_are_one_line_errors(tmp_path, entry, field, problem):
    head, _ = SCENE.split("[outputs.derived]")
    path = tmp_path / "bad.toml"
    path.write_text(head.replace("[[metrics]]", "") + "[outputs.derived]\n" + entry + "\n")
    with pytest.raises(SceneError) as info:
        inerter.load(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: {field}: ") and problem in message and "expected" in message


def test_a_metric_may_name_a_derived_output_and_an_unknown_one_is_refused(tmp_path):
    path = tmp_path / "bad_metric.toml"
    path.write_text(SCENE.replace('signal = "radius"', 'signal = "radious"'))
    with pytest.raises(SceneError, match=r"metrics\[1\]\.signal: unknown signal .*radius"):
        inerter.load(path)


@pytest.mark.parametrize("entry, unit", [
    ('d = "inerter.f * inerter.v_rel"', "W"),                       # N · m/s
    ('d = "atan2(P.r[2], P.r[1])"', "1"),                           # a plain number of lengths
    ('d = "radius_sq / h"\nradius_sq = "P.r[1]^2"', None),         # (declared after: refused below)
    ('d = "P.r[1]^2 / h"', "m"),
    ('d = "2 * P.r[1]"', "m"),
    ('d = { expression = "0.5 * 50 * spring.s_rel^2", unit = "J" }', "J"),   # 50 may be in N/m: declared
    ('d = { expression = "P.r[1] * spring.f", unit = "N.m" }', "N.m"),
])
def test_the_unit_of_a_derived_output(tmp_path, entry, unit):
    """Inferred from the units of what it reads (docs/scene_format.md), or declared where a plain
    number may carry a unit the scene does not state."""
    head, _ = SCENE.split("[outputs.derived]")
    path = tmp_path / "units.toml"
    path.write_text(head + "[outputs.derived]\n" + entry + "\n")
    if unit is None:
        with pytest.raises(SceneError, match="unknown name 'radius_sq'"):
            inerter.load(path)
        return
    info = {o["name"]: o["unit"] for o in inerter.load(path).output_info()}
    assert info["d"] == unit


def test_the_evaluator_on_arrays_computes_what_it_does_on_floats():
    """A derived output runs the scene's one expression evaluator on arrays (numpy's functions for
    the math module's): every function the scene format has, at sample values, against the
    evaluator on floats (to rounding: numpy and math may differ in the last bit)."""
    from inerter.scene import expressions as ex
    assert set(ex._ARRAYS.functions) == set(ex.FUNCTIONS)
    x = np.array([0.1, 0.37, 0.9])
    for name, (_, least, _) in ex.FUNCTIONS.items():
        count = max(least, 2 if name in ("min", "max", "hypot") else 1)
        text = f"{name}(" + ", ".join(["Q"] + ["Q/2"] * (count - 1)) + ")"
        out = ex.output_expression(text.replace("Q", "P.r[1]"), {"P.r[1]": "1"}, {}, "t", "f")
        arrays = out.evaluate([x])
        floats = [ex.evaluate(text, {"Q": v}, "t", "f") for v in x]
        assert np.allclose(arrays, floats, rtol=1e-15, atol=0), name
    ratio = ex.output_expression("P.r[1]^2 / (P.r[1] - 0.37)", {"P.r[1]": "m"}, {}, "t", "f").evaluate([x])
    assert np.isinf(ratio[1]) and np.isfinite(ratio[[0, 2]]).all()        # no value at one sample: not an error


def test_native_steps_with_derived_outputs_give_what_the_slave_gives(scene, tmp_path):
    """The FMU's binary steps natively (tests/test_fmu_native.py) with the kernels' outputs; a
    getter that asks for a derived output goes to the slave, which takes the native steps over and
    evaluates it: the same call sequence as test_fmu_native's, bit for bit against an instance whose
    native steps are off, with most steps native."""
    pytest.importorskip("fmpy")
    pytest.importorskip("pythonfmu")
    import test_fmu_native as tn
    from test_fmu import Instance, shim_expected
    from inerter.engine import compiled
    from inerter.fmu.build import build
    if not compiled.AVAILABLE or not shim_expected():
        pytest.skip("no native steps here")
    folder = _unzip(build(scene, out_dir=tmp_path), tmp_path / "unzipped")
    made = []
    try:
        for switch in ("1", "0"):
            with pytest.MonkeyPatch.context() as mp:
                mp.setenv(tn.fmu_native.SWITCH, switch)
                made.append(Instance(str(folder), f"native-{switch}"))
        native, slave = made
        assert "power" in native.outputs
        a = tn.replay(native, False, stop_time=0.3)
        b = tn.replay(slave, False, stop_time=0.3)
        assert a.entries == b.entries
        assert a.messages() == b.messages()
        assert tn.native_steps(native) >= 30
    finally:
        for inst in reversed(made):
            inst.close()


def _unzip(fmu: Path, folder: Path) -> Path:
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def test_a_derived_output_without_value_at_some_samples_is_a_warning_not_silent(tmp_path):
    """sqrt(P.r[2]/h - 0.2): the mass starts at y = 0.5 m < 0.2 h, so the expression is undefined at
    the first samples (NaN there, as numpy gives it), and the result, summary and CLI say so."""
    path = tmp_path / "derived_demo.toml"
    path.write_text(SCENE.replace('power = "inerter.f * inerter.v_rel"',
                                  'power = "inerter.f * inerter.v_rel"\nlift = "sqrt(P.r[2] / h - 0.2)"'))
    result = inerter.load(path).simulate(stop_time=0.5)
    missing = ~np.isfinite(result["lift"])
    assert missing[0] and missing.sum() < len(missing) or missing.all()
    notes = [w for w in result.warnings if "outputs.derived.lift" in w]
    assert len(notes) == 1 and f"no value at {int(missing.sum())} of {len(missing)} samples" in notes[0]
    assert str(path) in notes[0] and "t = 0 s" in notes[0]
    assert not [w for w in result.warnings if "outputs.derived.radius" in w]
    out = tmp_path / "out"
    assert cli_main(["run", str(path), "--out", str(out), "--stop-time", "0.5"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert any("outputs.derived.lift" in w for w in summary["warnings"])


def test_the_fmu_logs_a_derived_output_without_value_once(tmp_path):
    pytest.importorskip("fmpy")
    import fmpy
    from inerter.fmu.build import build
    path = tmp_path / "derived_demo.toml"
    path.write_text(SCENE.replace('power = "inerter.f * inerter.v_rel"',
                                  'power = "inerter.f * inerter.v_rel"\nlift = "sqrt(P.r[2] / h - 0.2)"'))
    fmu = build(path, out_dir=tmp_path / "fmu")
    said = []
    result = fmpy.simulate_fmu(str(fmu), stop_time=0.5, output=["lift"], debug_logging=True,
                               logger=lambda env, name, status, category, message: said.append(message.decode()))
    assert not np.isfinite(result["lift"][1])
    notes = [m for m in said if "outputs.derived.lift: no value" in m]
    assert len(notes) == 1, said


def test_a_metric_of_a_derived_output_without_value_at_some_samples_says_where(tmp_path):
    """A peak of sqrt(P.r[2]/h - 0.2), undefined at the first samples (above): the metric is left out
    with a reason naming the output, how many samples have no value and the first one's time (it
    read "t and x must be finite (the history contains nan or inf)")."""
    path = tmp_path / "derived_demo.toml"
    path.write_text(SCENE.replace('power = "inerter.f * inerter.v_rel"',
                                  'power = "inerter.f * inerter.v_rel"\nlift = "sqrt(P.r[2] / h - 0.2)"')
                    + '\n[[metrics]]\nkind = "peak"\nsignal = "lift"\nreference = 0\n')
    result = inerter.load(path).simulate(stop_time=0.5)
    missing = ~np.isfinite(result["lift"])
    assert missing.any() and "peak" not in result.metrics
    [(label, why)] = [(k, v) for k, v in result.metric_errors.items() if "lift" in k]
    assert why == (f"lift has no value at {int(missing.sum())} of {len(missing)} samples, the first at t = 0 s: "
                   "the metric needs it at every sample")
