"""User-facing text: a refused override named by where it came from, dimensionless units printed
as nothing, an empty output path refused, a friction table that gives no friction refused, and a
collapsed implicit step size said in the project's words with its likely cause."""
from __future__ import annotations

import os
import re

import numpy as np
import pytest

import inerter
from inerter.cli import main
from inerter.common.errors import SceneError
from conftest import LUMPED, ROOT, SCENARIOS, one_line_error

DEVICE_SCENE = SCENARIOS / "two_bar_2d_device.toml"
EFFICIENCY_SERIES = ROOT / "tests" / "data" / "device_combo_efficiency_series_3d.toml"


def scene_with(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# -- 1. a refused value names the override that gave it ---------------------------------------------
@pytest.mark.parametrize("command", ["run", "compare"])
def test_a_set_value_the_scene_refuses_names_the_set(tmp_path, capsys, command):
    """lead is read through the expression "lead" of elements.inerter.device.flywheel.lead: the error
    is that field's, with the --set that gave it in front (it read as the scene file's own)."""
    out = tmp_path / "out"
    assert main([command, str(DEVICE_SCENE), "--set", "lead=0", "--out", str(out)]) == 2
    one_line_error(capsys, f"inerter: error: --set lead=0: {DEVICE_SCENE}: elements.inerter.device.flywheel.lead: "
                           "out of range (got 0.0; expected a number > 0 m)")
    assert not out.exists()
    assert main([command, str(LUMPED), "--set", "b=-1", "--out", str(out)]) == 2
    one_line_error(capsys, f"inerter: error: --set b=-1: {LUMPED}: elements.inerter.b: out of range (got -1.0")


def test_describe_names_the_set_too(capsys):
    assert main(["describe", str(LUMPED), "--set", "b={value = -2, unit = \"g\"}"]) == 2
    one_line_error(capsys, 'inerter: error: --set b={value = -2, unit = "g"}: ', "elements.inerter.b", "-0.002")


def test_a_value_read_through_other_parameters_names_the_override(tmp_path):
    """b = 2 base: an override of base reaches elements.inerter.b through b; inerter.load names it."""
    text = LUMPED.read_text().replace("[parameters]\n", "[parameters]\nbase = 50.0\n", 1)
    text = text.replace('b  = { value = 100.0,', 'b  = { value = "2*base",', 1)
    path = scene_with(tmp_path, text)
    assert inerter.load(path).scene.parameters["b"].value == 100.0
    with pytest.raises(SceneError) as info:
        inerter.load(path, base=-1)
    assert str(info.value).startswith(f"override base=-1: {path}: elements.inerter.b: out of range (got -2.0"), info.value


def test_a_scene_file_value_is_not_blamed_on_an_unrelated_override(tmp_path, capsys):
    path = scene_with(tmp_path, LUMPED.read_text().replace('b = "b"', "b = -3.0", 1))
    assert main(["run", str(path), "--set", "y0=1.2", "--out", str(tmp_path / "out")]) == 2
    one_line_error(capsys, f"inerter: error: {path}: elements.inerter.b: out of range (got -3.0")


def test_an_unknown_override_name_is_named_once(capsys):
    assert main(["describe", str(LUMPED), "--set", "bb=3"]) == 2
    err = one_line_error(capsys, "inerter: error: --set bb=3: bb: unknown name (got 3;")
    assert err.count("--set") == 1


def test_a_sweep_names_the_vary_or_set_value(tmp_path, capsys):
    from inerter.studies.sweep import main_sweep
    out = tmp_path / "never"
    assert main_sweep([str(DEVICE_SCENE), "--vary", "lead=0,0.01", "--out", str(out)]) == 2
    one_line_error(capsys, f"inerter: error: --vary lead=0: {DEVICE_SCENE}: elements.inerter.device.flywheel.lead: ")
    assert main_sweep([str(DEVICE_SCENE), "--vary", "Fc=1,2", "--set", "lead=-1", "--out", str(out)]) == 2
    one_line_error(capsys, f"inerter: error: --set lead=-1: {DEVICE_SCENE}: elements.inerter.device.flywheel.lead: ",
                   "got -1.0")
    assert not out.exists()


# -- 2. a dimensionless unit is printed as nothing ---------------------------------------------------
def test_describe_prints_no_unit_for_a_dimensionless_quantity(tmp_path, capsys):
    """e_stop has unit "1": `e_stop = 0.5  ...`, not `e_stop = 0.5 1  ...`; a derived output in "1"
    has no "(1)". The SI unit the FMU declares stays "1" (parameter_info, modelDescription's source)."""
    assert main(["describe", str(DEVICE_SCENE)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "  e_stop = 0.5  end-stop coefficient of restitution" in lines
    assert not [line for line in lines if re.search(r"= \S+ 1(  |$)", line)], lines
    info = {p["name"]: p for p in inerter.load(DEVICE_SCENE).parameter_info()}
    assert info["e_stop"]["unit"] == "1"

    text = LUMPED.read_text() + '\n[outputs.derived]\nlift = { expression = "P.r[2] / Lb", unit = "1" }\n'
    path = scene_with(tmp_path, text)
    assert main(["describe", str(path)]) == 0
    assert "  derived output lift = P.r[2] / Lb" in capsys.readouterr().out.splitlines()
    from inerter.studies.plotting import _relative
    model = inerter.load(path)
    assert _relative(model, "lift", [1.0])[1] == "lift"
    assert _relative(model, "inerter.f", [1.0])[1] == "inerter.f (N)"


# -- 3. an empty output path is an error --------------------------------------------------------------
@pytest.mark.parametrize("argv", [
    ["run", str(LUMPED), "--out"],
    ["compare", str(LUMPED), "--out"],
    ["build-fmu", str(LUMPED), "--out"],
    ["paper", "--out"],
    ["sweep", str(LUMPED), "--vary", "y0=1,2", "--out"],
    ["sweep-plot", "results.csv", "--x", "y0", "--y", "peak", "--out"],
    ["bench", str(LUMPED), "--out"],
    ["study", "fig9", "--out"],
    ["device-study", "--out"],
    ["build-system", "--out-dir"],
])
def test_an_empty_output_path_is_a_one_line_error(tmp_path, capsys, monkeypatch, argv):
    """`--out ""` is the current folder as a path: it was filled without a word."""
    monkeypatch.chdir(tmp_path)
    assert main(argv + [""]) == 2
    one_line_error(capsys, f"inerter: error: {argv[-1]}: empty path (got ''; expected a ")
    assert os.listdir(tmp_path) == []


def test_a_blank_output_path_is_refused_too(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(LUMPED), "--out", "  "]) == 2
    one_line_error(capsys, "--out: empty path (got '  '; expected a folder path")
    assert os.listdir(tmp_path) == []


# -- 4. a device table whose fields give nothing ------------------------------------------------------
FRICTION = "\n[elements.inerter.device.friction]\n"


@pytest.mark.parametrize("fields, field, problem", [
    ("velocity_scale = 1e-3\n", "velocity_scale", "no friction given (velocity_scale alone adds none)"),
    ("viscous = 2.0\nvelocity_scale = 1e-3\n", "velocity_scale", "velocity_scale without coulomb"),
])
def test_a_friction_velocity_scale_without_a_coulomb_force_is_an_error(tmp_path, capsys, fields, field, problem):
    """v_s only shapes F_c tanh(L̇/v_s): without coulomb it adds nothing (it ran as no friction)."""
    path = scene_with(tmp_path, LUMPED.read_text() + FRICTION + fields)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = one_line_error(capsys, f"{path}: elements.inerter.device.friction.{field}: {problem} (got 0.001; expected ")
    assert "coulomb (N)" in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("fields", ["coulomb = 1.0\nvelocity_scale = 1e-3\n", "viscous = 2.0\n",
                                    "coulomb = 1.0\nviscous = 2.0\nvelocity_scale = 1e-3\n"])
def test_a_friction_that_gives_a_force_is_accepted(tmp_path, fields):
    model = inerter.load(scene_with(tmp_path, LUMPED.read_text() + FRICTION + fields))
    assert "inerter.f_friction" in model.signals.names


# -- 5. a collapsed implicit step, in the project's words ----------------------------------------------
def _efficiency_series_with_parameters(tmp_path):
    """tests/data/device_combo_efficiency_series_3d.toml, its flywheel inertia, series stiffness and
    screw efficiency made parameters (same values) so that --set reaches them."""
    text = EFFICIENCY_SERIES.read_text()
    text = text.replace("[effects]", '[parameters]\nJ = { value = 5e-5, unit = "kg.m2", description = "flywheel" }\n'
                        'kc = { value = 5e3, unit = "N/m", description = "series stiffness" }\n'
                        'eta = { value = 0.7, unit = "1", description = "screw efficiencies" }\n'
                        'vs = { value = 5e-3, unit = "m/s", description = "efficiency velocity scale" }\n[effects]', 1)
    for old, new in (("inertia = 5e-5", 'inertia = "J"'), ("stiffness = 5e3", 'stiffness = "kc"'),
                     ("forward = 0.85", 'forward = "eta"'), ("backward = 0.7", 'backward = "eta"'),
                     ("velocity_scale = 5e-3", 'velocity_scale = "vs"')):
        assert text.count(old) == 1
        text = text.replace(old, new)
    return scene_with(tmp_path, text)


def test_scipys_collapsed_step_is_said_in_the_projects_words():
    """y' = y², y(0) = 1 blows up at t = 1: scipy's Radau stops there with "Required step size is less
    than spacing between numbers."; the step says what stopped, and where, in the project's words."""
    from scipy.integrate import Radau

    from inerter.engine import simulation as sim
    solver = Radau(lambda t, y: y * y, 0.0, [1.0], 2.0, rtol=1e-8, atol=1e-10)
    with pytest.raises(sim.StepCollapse) as info:
        while solver.status == "running":
            sim._step(solver, "Radau")
    assert solver.status == "failed" and abs(info.value.time - 1.0) < 1e-6
    text = str(info.value)
    assert text.startswith("t = 1 s: the Radau step size collapsed (the step it asked for, after ") and \
        "below the spacing of floating-point numbers at t" in text and "Required" not in text, text


def test_the_stiffest_effect_is_named_with_its_values(tmp_path):
    """k_c = 1e9 N/m on b = J n² = 1e-5 · 200² = 0.4 kg with η_b = 0.05: the series mode
    √(k_c/(b η_b)) = √(1e9/0.02) = 2.236e5 rad/s (closed form), period 2π/ω = 2.81e-5 s; the
    narrowest switch is the efficiency's v_s = 1e-6 m/s."""
    model = inerter.load(_efficiency_series_with_parameters(tmp_path), J=1e-5, kc=1e9, eta=0.05, vs=1e-6)
    text = model.mechanism.stiffest()
    assert text == ("; likely cause: the stiffest effect, element 'dev': series compliance k_c = 1e+09 N/m on "
                    "b η_b = 0.02 kg (η_b = 0.05): its mode √(k_c/(b η_b)) = 2.24e+05 rad/s, a period of 2.81e-05 s; "
                    "the narrowest switch, element 'dev': efficiency.velocity_scale = 1e-06 m/s"), text
    assert inerter.load(LUMPED).mechanism.stiffest() == ""


def test_a_run_whose_radau_step_collapses_says_so_and_keeps_its_samples(tmp_path, capsys, monkeypatch):
    """The device scene with k_c = 1e9 N/m, η = 0.05, v_s = 1e-6 m/s, b = 0.4 kg: where scipy's Radau
    reports a collapsed step (emulated past t = 0.5 ms as scipy reports it: status "failed" and its
    message), the run stops with exit status 3, one line saying what stopped, when, and the likely
    cause, and the samples before it written."""
    from inerter.engine import simulation as sim
    real = sim.make_solver

    def collapsing(*args, **kwargs):
        solver = real(*args, **kwargs)
        step = solver.step

        def step_or_collapse():
            if solver.t > 5e-4:
                solver.status = "failed"
                return sim.SCIPY_COLLAPSE
            return step()
        solver.step = step_or_collapse
        return solver
    monkeypatch.setattr(sim, "make_solver", collapsing)
    path = _efficiency_series_with_parameters(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(path), "--set", "J=1e-5", "--set", "kc=1e9", "--set", "eta=0.05", "--set", "vs=1e-6",
                 "--method", "Radau", "--stop-time", "0.01", "--set", "experiment.output_interval=1e-4",
                 "--out", str(out)]) == 3
    err = one_line_error(capsys, "the run stopped before its stop time (t = 0.000", "s: the Radau step size collapsed",
                         "; likely cause: the stiffest effect, element 'dev': series compliance k_c = 1e+09 N/m",
                         "efficiency.velocity_scale = 1e-06 m/s", "results up to t = 0.0005 s written in")
    assert "spacing between numbers" not in err
    rows = (out / "device_combo_efficiency_series_3d.csv").read_text().splitlines()
    assert len(rows) == 1 + 6                  # the header, t = 0 ... 0.5 ms every 0.1 ms


@pytest.mark.parametrize("status", [6, 7])
def test_the_compiled_loops_stiff_and_collapse_failures_name_the_stiffest_effect_too(tmp_path, status):
    """The compiled loop's failures 6 (held at DOP853's stability limit) and 7 (step size collapsed)
    end with the same likely cause as the numpy path's: the series mode √(k_c/(b η_b)) =
    √(1e9/0.02) = 2.24e5 rad/s (closed form) of the device scene above."""
    from inerter.engine import compiled
    model = inerter.load(_efficiency_series_with_parameters(tmp_path), J=1e-5, kc=1e9, eta=0.05, vs=1e-6)
    kernel = compiled._kernel_for(model.mechanism)
    mech = model.mechanism
    y = np.concatenate([mech.q0, mech.v0, mech.z0])       # the state the loop stopped at: t = 0 here
    text = compiled.failure_text(kernel, status, model.settings(method="DOP853"), 1e-9, y, 0.0)
    assert text.endswith("; the narrowest switch, element 'dev': efficiency.velocity_scale = 1e-06 m/s"), text
    assert "; likely cause: the stiffest effect, element 'dev': series compliance k_c = 1e+09 N/m on b η_b = 0.02 kg " \
           "(η_b = 0.05): its mode √(k_c/(b η_b)) = 2.24e+05 rad/s" in text, text
    assert ("stiff for DOP853" if status == 6 else "DOP853 step size collapsed") in text, text


@pytest.mark.parametrize("command", [["bench", str(SCENARIOS / "two_bar_2d.toml")], ["study", "two_bar_b"]])
def test_bench_and_study_name_the_set_that_gave_a_refused_value(tmp_path, capsys, command):
    """k = -1 N/m is out of the spring's range: the error is the field's, with the --set in front (it
    read 'override k=-1'); nothing runs."""
    out = tmp_path / "out"
    assert main(command + ["--set", "k=-1", "--out", str(out)]) == 2
    err = one_line_error(capsys, "inerter: error: --set k=-1: ", "elements.", "out of range (got -1.0")
    assert "override k=-1" not in err
    assert not out.exists()


PEND_COMPACT = ROOT / "tests" / "data" / "device_pendulum_3d_compact.toml"


@pytest.mark.parametrize("edit, field, expected", [
    # without a mount the model holds the housing's and the rod's spin about the device's axis at
    # zero: their axial inertias would act on nothing
    (lambda t: t.replace("[elements.device.device.mount]\naxis = [1, 0, 0]", ""),
     "elements.device.device.housing.axial_inertia", "axial inertia without a mount"),
    (lambda t: t.replace("[elements.device.device.mount]\naxis = [1, 0, 0]", "").replace(
        'transverse_inertia = "It_h"\naxial_inertia = "Ja_h"', 'transverse_inertia = "It_h"'),
     "elements.device.device.rod.axial_inertia", "axial inertia without a mount"),
    # a centre places the flywheel's mass: without one it places nothing
    (lambda t: t.replace('mass = "m_fw"\n', ""), "elements.device.device.flywheel.centre", "centre without mass")])
def test_a_device_field_that_would_act_on_nothing_is_refused(tmp_path, edit, field, expected):
    """tests/data/device_pendulum_3d_compact.toml (loads as it is) with its mount, or its flywheel's
    mass, taken out: the field that then does nothing is refused, named with its value."""
    inerter.load(PEND_COMPACT)
    text = PEND_COMPACT.read_text(encoding="utf-8")
    changed = edit(text)
    assert changed != text
    with pytest.raises(SceneError) as info:
        inerter.load(scene_with(tmp_path, changed))
    message = str(info.value)
    assert f": {field}: {expected} (got " in message and "\n" not in message, message


def test_a_collapse_the_step_monitor_finds_says_what_may_have_stalled_it_once(monkeypatch):
    """The monitor's own collapse (COLLAPSE_STEPS steps in a row below COLLAPSE_RELATIVE·max(1 s, t),
    made to fire after 3 steps here) carries what Mechanism.diagnose found; the run's message gives
    it once (it was appended a second time)."""
    from inerter.engine import simulation as sim
    model = inerter.load(LUMPED)
    monkeypatch.setattr(sim, "COLLAPSE_RELATIVE", 1e3)
    monkeypatch.setattr(sim, "COLLAPSE_STEPS", 3)
    monkeypatch.setattr(type(model.mechanism), "diagnose", lambda self, y: "; MARK: what may have stalled it")
    result = model.simulate(stop_time=1.0, path="numpy", metrics=False)
    assert result.status == "failed" and "step size collapsed" in result.message, result.message
    assert result.message.count("; MARK: what may have stalled it") == 1, result.message


@pytest.mark.parametrize("command", ["run", "compare"])
@pytest.mark.parametrize("model", ["solver", "oracle"])
def test_a_communication_step_without_the_fmu_is_refused(tmp_path, capsys, command, model):
    """--step is the FMU's communication step: without --model fmu it was taken and did nothing
    (the solver's samples are its output interval). Refused before anything is run or written."""
    assert main([command, str(LUMPED), "--model", model, "--step", "0.1", "--out", str(tmp_path / "o")]) == 2
    one_line_error(capsys, "inerter: error: --step: the FMU's communication step, without --model fmu (got '0.1'",
                   "experiment.output_interval")
    assert not (tmp_path / "o").exists()


def test_compare_on_the_oracle_runs_it_once_per_variant(tmp_path, capsys):
    """`compare --model oracle`: the corrected run is the oracle's, so it is not run a third time
    nor compared with itself (it printed "largest |oracle − oracle| ... 0 m")."""
    import json

    out = tmp_path / "cmp"
    assert main(["compare", str(LUMPED), "--model", "oracle", "--stop-time", "2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "largest |" not in printed
    assert not (out / "lumped_mass_2d_oracle.csv").exists()
    runs = json.loads((out / "summary.json").read_text())["runs"]
    assert runs["oracle"] == runs["corrected"] and runs["max_difference_to_oracle_m"] is None
    assert runs["corrected"]["metrics"] != runs["uncorrected"]["metrics"]


def test_a_reader_that_leaves_early_is_no_error(tmp_path):
    """``inerter describe SCENE | head``: the reader closes the pipe before the description is
    written; the command stops quietly with 141 (128 + SIGPIPE, as a shell reports a tool the
    signal ended), not with ``inerter: error: Broken pipe``."""
    import subprocess
    import sys
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen([sys.executable, "-c", "import sys; from inerter.cli import main; sys.exit(main())",
                             "describe", str(LUMPED)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()                                     # before the package is even imported
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert err == "", err


def test_a_scene_without_metrics_plots_its_first_moving_point(tmp_path):
    """run's PNG of a scene without [[metrics]]: the coordinates of its first point on a body (all
    of them: the 3D mass below moves along Z only), not the first point of the outputs, a ground
    point whose coordinates never move."""
    from inerter.studies.plotting import plotted_signals
    path = scene_with(tmp_path, """
[scene]
dimension = 3
[ground.points]
O = [0, 0, 0]
G = [0.3, 0, 1]
[bodies.mass]
mass = 1
inertia = [1, 1, 1]
position = [0.3, 0, 1]
points = { P = [0, 0, 0] }
[joints.slider]
type = "prismatic"
between = ["G", "P"]
axis = [0, 0, 1]
[elements.spring]
type = "spring"
between = ["O", "P"]
k = 100
""")
    assert plotted_signals(inerter.load(path)) == ["P.r[1]", "P.r[2]", "P.r[3]"]
