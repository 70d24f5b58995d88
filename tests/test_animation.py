"""Animations of a run (inerter.studies.animation, ``inerter run --animate``): the files open, hold the
frames asked for, and draw what the outputs say.

References: the run's own outputs (``D.r[1]``, ``inerter.f``...) at the time each frame shows, and
the documented colour scale (matplotlib's "coolwarm" over ±max|f| of the whole run). Short runs
(1 s of the two-bar mechanism in 2D and of the double pendulum in 3D) and few frames.
"""
from __future__ import annotations

import json
import re
import shutil
import subprocess

import matplotlib
import numpy as np
import pytest
from matplotlib import colormaps
from matplotlib.colors import to_hex, to_rgba

import inerter
from conftest import LUMPED, SCENARIOS, TWO_BAR
from inerter.cli import main
from inerter.studies.animation import MAX_FRAMES, AnimationError, animate, figure, frames, outline

matplotlib.use("Agg")
PENDULUM = SCENARIOS / "double_pendulum_3d.toml"
SCENES = {"2d": TWO_BAR, "3d": PENDULUM}


@pytest.fixture(scope="module")
def results():
    return {key: inerter.load(scene).simulate(stop_time=1.0, output_interval=0.01, metrics=False)
            for key, scene in SCENES.items()}


def sample_at(result, shown: float) -> int:
    """The run's sample at the time a frame shows (3 decimals: output samples are 0.01 s apart)."""
    i = int(np.argmin(np.abs(result.time - shown)))
    assert abs(result.time[i] - shown) <= 5e-4
    return i


def position(result, point, i, dim) -> np.ndarray:
    return np.array([result[f"{point}.r[{j + 1}]"][i] for j in range(dim)])


def expected_colour(result, f):
    """The colour map's value of force f on the scale ±max|f| of the whole run."""
    limit = np.max(np.abs(result["inerter.f"]))
    return colormaps["coolwarm"]((f + limit) / (2 * limit)), limit


# ----------------------------------------------------------------------------------------------
# Which samples become frames
# ----------------------------------------------------------------------------------------------
def test_frames_are_samples_spread_over_the_run_at_the_rate_asked(results):
    result = results["2d"]
    fr = frames(result, fps=10, duration=2.0)
    assert len(fr.time) == 20 and fr.fps == 10 and fr.speed == pytest.approx(0.5)    # 1 s of run in 2 s
    assert fr.time[0] == result.time[0] and fr.time[-1] == result.time[-1]
    assert set(fr.time) <= set(result.time)                                       # samples, not interpolated
    assert np.all(np.abs(fr.time - np.linspace(0, 1, 20)) <= 0.005 + 1e-12)        # evenly, to half a sample
    assert len(frames(result, fps=25, duration=None).time) == 25                    # default: real time


def test_a_long_animation_is_capped_and_plays_faster(results):
    fine = inerter.load(TWO_BAR).simulate(stop_time=1.0, output_interval=0.001, metrics=False)
    fr = frames(fine, fps=50, duration=100.0)                   # 5000 frames asked for
    assert len(fr.time) == MAX_FRAMES == 300
    assert fr.fps == 50 and fr.speed == pytest.approx(1.0 / (300 / 50))
    assert len(frames(results["2d"], fps=50, duration=100.0).time) == 101          # no more than the samples


def test_outline_of_a_body_from_its_points():
    square = [(1, 1), (0, 0), (1, 0), (0.5, 0.5), (0, 1)]      # corners and the centre, in any order
    ring = outline(square)
    assert sorted(ring) == [0, 1, 2, 4]                          # the centre is inside
    pts = np.array(square, dtype=float)[ring]
    x, y = pts[:, 0], pts[:, 1]
    area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)          # the shoelace formula
    assert abs(area) == pytest.approx(1.0)                       # a polygon, not a bow tie
    assert sorted(outline([(0, 0, 0.5), (0, 0, 0), (0, 0, -0.5)])) == [0, 2]      # a rod: its two ends
    assert outline([(0.2, 0.1)]) == [0]
    tilted = [(np.cos(a), np.sin(a) * 0.6, np.sin(a) * 0.8) for a in np.linspace(0, 2 * np.pi, 7)[:-1]]
    assert sorted(outline(tilted)) == list(range(6))             # a hexagon in a tilted plane


# ----------------------------------------------------------------------------------------------
# What is drawn: the inerter from its terminals' outputs, coloured by its force output
# ----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("key", ["2d", "3d"])
def test_the_drawn_inerter_joins_its_terminals_and_shows_its_force(results, key):
    result = results[key]
    dim = 2 if key == "2d" else 3
    fr = frames(result, fps=10, duration=1.0)
    fig, update = figure(fr)
    ax = fig.axes[0]
    for k in (3, 7):
        update(k)
        artists = {a.get_gid(): a for a in ax.get_children() if a.get_gid()}
        i = sample_at(result, float(re.fullmatch(r"t = ([0-9.]+) s", artists["time"].get_text()).group(1)))
        line = artists["element:inerter"]
        drawn = np.array(line.get_data_3d() if dim == 3 else line.get_data())
        terminals = [position(result, p, i, dim) for p in ("D", "E")]
        assert np.array_equal(drawn.T, np.array(terminals))
        colour, limit = expected_colour(result, result["inerter.f"][i])
        assert np.allclose(to_rgba(line.get_color()), colour, atol=1e-12)
        assert abs(result["inerter.f"][i]) > 0.02 * limit            # a colour off the map's white centre
        if dim == 2:                                                # the bar drawn from end A to end B
            bar = np.array(artists["body:bar1"].get_data()).T
            assert np.array_equal(bar, np.array([position(result, p, i, 2) for p in ("A", "B")]))
    bar_axes = [a for a in fig.axes if "inerter force" in a.get_ylabel()]
    assert len(bar_axes) == 1 and np.allclose(bar_axes[0].get_ylim(), (-limit, limit), rtol=1e-12)
    matplotlib.pyplot.close(fig)


def test_magnified_displacements_are_drawn_from_the_initial_pose(results):
    """A storey's drift of millimetres is drawn visible: r(0) + magnify·(r − r(0)), from the outputs."""
    result = results["3d"]
    fr = frames(result, fps=10, duration=1.0, magnify=10.0)
    fig, update = figure(fr)
    update(5)
    artists = {a.get_gid(): a for a in fig.axes[0].get_children() if a.get_gid()}
    i = sample_at(result, float(re.fullmatch(r"t = ([0-9.]+) s", artists["time"].get_text()).group(1)))
    drawn = np.array(artists["element:inerter"].get_data_3d()).T
    expected = [position(result, p, 0, 3) + 10.0 * (position(result, p, i, 3) - position(result, p, 0, 3))
                for p in ("D", "E")]
    assert np.allclose(drawn, expected, rtol=0, atol=1e-12)
    assert "(displacements × 10)" in fig.axes[0].get_title() and "displacements × 10" in fr.describe()
    matplotlib.pyplot.close(fig)


@pytest.mark.parametrize("key", ["2d", "3d"])
def test_a_gif_opens_with_the_frames_asked_for(results, key, tmp_path):
    from PIL import Image
    path = tmp_path / f"{key}.gif"
    fr = animate(results[key], path, fps=10, duration=0.8)
    assert fr.path == path and len(fr.time) == 8
    with Image.open(path) as gif:
        assert gif.format == "GIF" and gif.n_frames == 8
        assert gif.info["duration"] == 100                         # ms per frame: 10 fps
        assert gif.size[0] > 300


# ----------------------------------------------------------------------------------------------
# The HTML page: self-contained, its data the outputs
# ----------------------------------------------------------------------------------------------
def page_data(text: str) -> dict:
    found = re.search(r'<script id="frames" type="application/json">(.*?)</script>', text, re.S)
    return json.loads(found.group(1))


@pytest.mark.parametrize("key", ["2d", "3d"])
def test_an_html_page_is_self_contained_and_holds_the_outputs(results, key, tmp_path):
    result = results[key]
    dim = 2 if key == "2d" else 3
    path = tmp_path / f"{key}.html"
    animate(result, path, fps=10, duration=1.0)
    text = path.read_text(encoding="utf-8")
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    assert not re.search(r"https?://|\bsrc=|\bhref=|@import|url\(", text)       # nothing fetched from anywhere
    data = page_data(text)
    assert data["dimension"] == dim and len(data["time"]) == 10
    inerter_entry = next(e for e in data["elements"] if e["name"] == "inerter")
    for k in (2, 9):
        i = sample_at(result, data["time"][k])
        assert data["time"][k] == result.time[i]
        for p in ("D", "E"):
            assert data["points"][p][k] == list(position(result, p, i, dim))
        assert inerter_entry["force"][k] == result["inerter.f"][i]
        colour, limit = expected_colour(result, result["inerter.f"][i])
        assert inerter_entry["colour"][k] == to_hex(colour)
    assert data["force_limit"] == pytest.approx(limit, rel=1e-15)


def test_the_page_script_draws_the_inerter_between_its_terminals(results, tmp_path):
    """The page's script run by Node with a stand-in canvas that records each stroke: at a frame,
    the inerter is stroked in that frame's colour along the line between its terminals (2D: the
    screen vector is the world vector with Y flipped, at the same scale as the bar A-B)."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("Node.js is not installed")
    result = results["2d"]
    path = tmp_path / "page.html"
    animate(result, path, fps=10, duration=1.0)
    data = page_data(path.read_text(encoding="utf-8"))
    runner = tmp_path / "run_page.js"
    runner.write_text(NODE_RUNNER)
    k = 6
    done = subprocess.run([node, str(runner), str(path), str(k)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    strokes = json.loads(done.stdout)["strokes"]
    i = sample_at(result, data["time"][k])
    colour = next(e for e in data["elements"] if e["name"] == "inerter")["colour"][k]
    drawn = [s for s in strokes if s["style"] == colour]
    assert len(drawn) == 1
    (x0, y0), (x1, y1) = drawn[0]["points"]
    d, e, a, b = (position(result, p, i, 2) for p in ("D", "E", "A", "B"))
    bar = next(s for s in strokes if s["style"] == "#404040")["points"]      # the first body drawn: bar1
    scale = np.hypot(bar[1][0] - bar[0][0], bar[1][1] - bar[0][1]) / np.linalg.norm(b - a)
    assert np.allclose([x1 - x0, y0 - y1], scale * (e - d), rtol=1e-9, atol=1e-9)


NODE_RUNNER = r"""
const fs = require("fs");
const html = fs.readFileSync(process.argv[2], "utf8"), frame = +process.argv[3];
const data = html.match(/<script id="frames" type="application\/json">([\s\S]*?)<\/script>/)[1];
const script = html.match(/<script>([\s\S]*?)<\/script>/)[1];
const strokes = [];
let current = [];
const ctx = {
  beginPath() { current = []; }, moveTo(x, y) { current.push([x, y]); }, lineTo(x, y) { current.push([x, y]); },
  closePath() {}, rect() {}, arc() {}, fill() {}, clearRect() {}, setLineDash() {}, fillText() {},
  stroke() { strokes.push({ points: current.slice(), style: this.strokeStyle }); },
};
const nodes = {};
const element = id => nodes[id] || (nodes[id] = { id, style: {}, textContent: id === "frames" ? data : "",
  width: 720, height: 540, getContext: () => ctx, setPointerCapture() {} });
global.document = { getElementById: element };
global.requestAnimationFrame = () => {};
new Function(script)();
strokes.length = 0;
element("slider").value = String(frame);
element("slider").oninput();
console.log(JSON.stringify({ strokes }));
"""


# ----------------------------------------------------------------------------------------------
# The command line and bad input
# ----------------------------------------------------------------------------------------------
def test_run_animate_writes_the_animation_beside_the_csv(tmp_path, capsys):
    from PIL import Image
    assert main(["run", str(LUMPED), "--stop-time", "0.5", "--out", str(tmp_path), "--animate", "--fps", "8"]) == 0
    assert "wrote " + str(tmp_path / "lumped_mass_2d.gif") + ": 4 frames at 8 fps" in capsys.readouterr().out
    with Image.open(tmp_path / "lumped_mass_2d.gif") as gif:
        assert gif.n_frames == 4
    assert (tmp_path / "lumped_mass_2d.csv").is_file()
    assert main(["run", str(LUMPED), "--stop-time", "0.5", "--out", str(tmp_path), "--animate", "html",
                 "--duration", "0.25"]) == 0
    assert len(page_data((tmp_path / "lumped_mass_2d.html").read_text())["time"]) == 6     # 25 fps × 0.25 s


@pytest.mark.parametrize("argv, message", [
    (["--animate", "--fps", "0"], "--fps: out of range (got 0.0; expected frames per second in (0, 60])"),
    (["--animate", "--duration", "inf"], "--duration: out of range (got inf; expected a length of animation"),
    (["--fps", "10"], "--fps: no animation asked for (got 10.0; expected --animate beside it)"),
    (["--animate", "html", "--magnify", "-5"], "--magnify: out of range (got -5.0; expected a factor > 0"),
])
def test_bad_animation_options_are_one_line_errors_before_the_run(argv, message, tmp_path, capsys):
    assert main(["run", str(LUMPED), "--out", str(tmp_path), *argv]) == 2
    err = capsys.readouterr().err
    assert err == f"inerter: error: {err.split('error: ', 1)[1]}" and message in err and err.count("\n") == 1
    assert not (tmp_path / "lumped_mass_2d.csv").exists()           # nothing was run


def test_bad_animation_arguments_name_the_argument(results, tmp_path):
    result = results["2d"]
    with pytest.raises(AnimationError, match=r"animation path: unknown format \(got '.*x\.mp4'; expected a "
                                             r"file name ending in \.gif or \.html\)"):
        animate(result, tmp_path / "x.mp4")
    with pytest.raises(AnimationError, match=r"animation fps: not a number \(got 'fast'"):
        animate(result, tmp_path / "x.gif", fps="fast")
    with pytest.raises(AnimationError, match=r"animation duration: out of range \(got -1"):
        animate(result, tmp_path / "x.gif", duration=-1)
    with pytest.raises(AnimationError, match=r"animation view: not a view \(got \(30, nan\); expected \(elevation"):
        animate(result, tmp_path / "x.html", view=(30, float("nan")))
    assert not list(tmp_path.iterdir())
