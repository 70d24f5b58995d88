"""An animation as one self-contained HTML page: the frames' data inlined as JSON, drawn on a canvas
by a short script in the page (no external file, no network), with play/pause, a time slider and,
in 3D, an orthographic view that turns when dragged.

The page draws what :class:`inerter.studies.animation.Frames` holds (`fr` below), as the GIF does: positions in
metres straight from the outputs, each inerter's colour precomputed here from the colour map, so
that the script has no colour map of its own to keep in step.
"""
from __future__ import annotations

import html
import json
import math

import numpy as np
from matplotlib.colors import Normalize, to_hex

#: Where the page holds its data: ``<script id="frames" type="application/json">``.
DATA_ID = "frames"


def _numbers(values):
    """Nested lists of floats at full precision; a value that is not finite becomes null."""
    if isinstance(values, np.ndarray):
        values = values.tolist()
    if isinstance(values, list):
        return [_numbers(v) for v in values]
    return float(values) if math.isfinite(values) else None


def page_data(fr, view=(25.0, -60.0)) -> dict:
    """The frames as plain JSON values (what the page's script reads)."""
    from matplotlib import colormaps
    cmap = colormaps[fr.colormap]
    elements = []
    for name, kind, a, b in fr.elements:
        entry = {"name": name, "kind": kind, "a": a, "b": b}
        if kind == "inerter":
            entry["force"] = _numbers(fr.forces[name])
            entry["colour"] = [to_hex(fr.colour(name, k)) for k in range(len(fr.time))]
        elements.append(entry)
    return {
        "name": fr.name, "dimension": fr.dimension, "fps": fr.fps, "speed": fr.speed,
        "time": _numbers(fr.time), "samples": [int(i) for i in fr.samples],
        "points": {name: _numbers(p) for name, p in fr.positions.items()},
        "bodies": [{"name": body, "outline": names} for body, names in fr.bodies],
        "ground": fr.ground, "joints": [{"name": n, "a": a, "b": b} for n, a, b in fr.joints],
        "elements": elements, "force_limit": fr.force_limit, "colormap": fr.colormap,
        "colourbar": [to_hex(cmap(Normalize(0, 10)(i))) for i in range(11)],    # bottom (−limit) to top
        "view": {"elevation": float(view[0]), "azimuth": float(view[1])},
    }


def page(fr, view=(25.0, -60.0)) -> str:
    """The HTML page of `fr`."""
    data = json.dumps(page_data(fr, view), separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    return (TEMPLATE.replace("@TITLE@", html.escape(fr.name))
            .replace("@DESCRIBE@", html.escape(fr.describe()))
            .replace("@DATA_ID@", DATA_ID).replace("@DATA@", data).replace("@SCRIPT@", SCRIPT))


TEMPLATE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>@TITLE@</title>
<style>
 body { font: 14px system-ui, sans-serif; margin: 1em; color: #222; }
 #stage { display: flex; align-items: center; gap: 12px; }
 canvas { border: 1px solid #ccc; background: #fff; touch-action: none; }
 #bar { display: flex; align-items: stretch; gap: 6px; height: 380px; }
 #gradient { width: 18px; border: 1px solid #888; }
 #ticks { display: flex; flex-direction: column; justify-content: space-between; font-size: 12px; }
 #controls { display: flex; align-items: center; gap: 10px; margin-top: 8px; }
 #slider { width: 520px; }
 .legend span { margin-right: 1.2em; } .note { color: #666; font-size: 12px; }
</style></head>
<body>
<h3>@TITLE@</h3>
<div id="stage"><canvas id="view" width="720" height="540"></canvas>
 <div id="bar"><div id="gradient"></div><div id="ticks"><span id="top"></span><span>0 N</span><span id="bottom"></span></div>
 <div style="writing-mode: vertical-rl; font-size: 12px">inerter force (N): tension &gt; 0</div></div></div>
<div id="controls"><button id="play">pause</button><input id="slider" type="range" min="0" value="0">
 <span id="time"></span></div>
<p class="legend"><span>&#9472; &#9472; spring</span><span>&#9644; damper</span><span>&#9608; inerter (its colour: its force)</span>
 <span>&#9711; joint</span><span>&#9632; ground point</span></p>
<p class="note">@DESCRIBE@. <span id="hint"></span></p>
<script id="@DATA_ID@" type="application/json">@DATA@</script>
<script>@SCRIPT@</script>
</body></html>
"""

SCRIPT = r"""
"use strict";
const D = JSON.parse(document.getElementById("frames").textContent);
const canvas = document.getElementById("view"), ctx = canvas.getContext("2d");
const slider = document.getElementById("slider"), button = document.getElementById("play");
const n = D.time.length, dim = D.dimension;
let k = 0, playing = true, elev = D.view.elevation, azim = D.view.azimuth, last = null;
slider.max = n - 1;
document.getElementById("gradient").style.background = "linear-gradient(to top, " + D.colourbar.join(", ") + ")";
document.getElementById("top").textContent = "+" + D.force_limit.toPrecision(3) + " N";
document.getElementById("bottom").textContent = "\u2212" + D.force_limit.toPrecision(3) + " N";
if (!D.elements.some(e => e.kind === "inerter")) document.getElementById("bar").style.display = "none";
if (dim === 3) document.getElementById("hint").textContent = "Drag the view to turn it (orthographic, equal scales).";
// the centre and size of what is drawn, over every frame: a sphere in 3D (the view turns), a box in 2D
const lo = Array(dim).fill(Infinity), hi = Array(dim).fill(-Infinity);
for (const name in D.points) for (const p of D.points[name]) if (p[0] !== null)
  for (let i = 0; i < dim; i++) { lo[i] = Math.min(lo[i], p[i]); hi[i] = Math.max(hi[i], p[i]); }
const centre = lo.map((l, i) => 0.5 * (l + hi[i]));
let radius = 0;
if (dim === 3) { for (const name in D.points) for (const p of D.points[name]) if (p[0] !== null)
  radius = Math.max(radius, Math.hypot(p[0] - centre[0], p[1] - centre[1], p[2] - centre[2])); }
else radius = 0.5 * Math.max(hi[0] - lo[0], hi[1] - lo[1]);
radius = radius > 0 ? 1.1 * radius : 1;
function project(p) {            // metres -> canvas pixels (orthographic in 3D, as matplotlib's view)
  const s = 0.47 * Math.min(canvas.width, canvas.height) / radius;
  let u, v;
  if (dim === 2) { u = p[0] - centre[0]; v = p[1] - centre[1]; }
  else {
    const a = azim * Math.PI / 180, e = elev * Math.PI / 180;
    const x = p[0] - centre[0], y = p[1] - centre[1], z = p[2] - centre[2];
    u = -Math.sin(a) * x + Math.cos(a) * y;
    v = -Math.sin(e) * Math.cos(a) * x - Math.sin(e) * Math.sin(a) * y + Math.cos(e) * z;
  }
  return [canvas.width / 2 + s * u, canvas.height / 2 - s * v];
}
const at = name => D.points[name][k];
function path(names, close) {
  const pts = names.map(at);
  if (pts.some(p => p[0] === null)) return false;
  ctx.beginPath();
  pts.map(project).forEach((q, i) => i ? ctx.lineTo(q[0], q[1]) : ctx.moveTo(q[0], q[1]));
  if (close && pts.length > 2) ctx.closePath();
  return true;
}
function marks(names, size, fill, stroke, square) {
  for (const name of names) {
    if (at(name)[0] === null) continue;
    const q = project(at(name));
    ctx.beginPath();
    if (square) ctx.rect(q[0] - size, q[1] - size, 2 * size, 2 * size); else ctx.arc(q[0], q[1], size, 0, 2 * Math.PI);
    ctx.fillStyle = fill; ctx.fill();
    if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = 1.5; ctx.stroke(); }
  }
}
const STYLE = { inerter: [9, [], 2], damper: [4, [], 3], spring: [1.6, [6, 3], 4], other: [1, [2, 3], 4] };
function triad() {               // the global axes, in the lower left corner
  const o = [60, canvas.height - 50], names = ["X", "Y", "Z"].slice(0, dim), colours = ["#c33", "#393", "#36c"];
  const c0 = project(centre);
  names.forEach((label, i) => {
    const p = centre.slice(); p[i] += 0.15 * radius;
    const q = project(p), dx = q[0] - c0[0], dy = q[1] - c0[1];
    ctx.strokeStyle = ctx.fillStyle = colours[i]; ctx.lineWidth = 2; ctx.setLineDash([]);
    ctx.beginPath(); ctx.moveTo(o[0], o[1]); ctx.lineTo(o[0] + dx, o[1] + dy); ctx.stroke();
    ctx.fillText(label, o[0] + 1.15 * dx - 3, o[1] + 1.15 * dy + 4);
  });
}
function draw() {
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.font = "13px sans-serif"; ctx.lineCap = "butt";
  const order = D.elements.slice().sort((a, b) => STYLE[a.kind][2] - STYLE[b.kind][2]);
  for (const e of order) {
    const [width, dash] = STYLE[e.kind];
    if (!path([e.a, e.b], false)) continue;
    ctx.setLineDash(dash);
    if (e.kind === "inerter") { ctx.lineWidth = width + 2; ctx.strokeStyle = "#4d4d4d"; ctx.stroke(); }  // white at zero force
    ctx.lineWidth = width;
    ctx.strokeStyle = e.kind === "inerter" ? e.colour[k] : (e.kind === "damper" ? "#737373" : "#0d0d0d");
    ctx.stroke();
  }
  ctx.setLineDash([]);
  for (const body of D.bodies) {
    if (!path(body.outline, true)) continue;
    ctx.lineWidth = 2.5; ctx.strokeStyle = "#404040"; ctx.stroke();
    marks(body.outline, 2.5, "#404040");
  }
  marks(D.ground, 6, "#4d4d4d", null, true);
  marks(D.elements.flatMap(e => [e.a, e.b]), 3.5, "#000");
  marks(D.joints.flatMap(j => [j.a, j.b]), 5.5, "#fff", "#000");
  triad();
  ctx.fillStyle = "#222";
  ctx.fillText("t = " + D.time[k].toFixed(3) + " s", canvas.width - 110, canvas.height - 12);
  slider.value = k;
  document.getElementById("time").textContent = "frame " + (k + 1) + " of " + n + ", t = " + D.time[k].toFixed(3) + " s";
}
function tick(now) {
  if (playing) {
    if (last === null) last = now;
    if (now - last >= 1000 / D.fps) { k = (k + 1) % n; last = now; draw(); }
  }
  requestAnimationFrame(tick);
}
button.onclick = () => { playing = !playing; last = null; button.textContent = playing ? "pause" : "play"; };
slider.oninput = () => { k = +slider.value; draw(); };
let drag = null;
canvas.onpointerdown = ev => { if (dim === 3) { drag = [ev.clientX, ev.clientY]; canvas.setPointerCapture(ev.pointerId); } };
canvas.onpointerup = () => { drag = null; };
canvas.onpointermove = ev => {
  if (!drag) return;
  azim -= 0.5 * (ev.clientX - drag[0]); elev = Math.max(-90, Math.min(90, elev + 0.5 * (ev.clientY - drag[1])));
  drag = [ev.clientX, ev.clientY]; draw();
};
draw();
requestAnimationFrame(tick);
"""
