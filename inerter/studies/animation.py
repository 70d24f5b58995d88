"""Animations of a run: ``animate(result, "two_bar_2d.gif")`` (or ``.html``), ``inerter run --animate``.

Everything drawn comes from the run's outputs, never from its states, so that a solver's result and
an FMU's animate alike: the positions of the named points (``P.r[i]``) and the elements' forces
(``E.f``), at output samples (a frame shows a sample as it is, not an interpolation between two).

What a frame shows: each body as the outline of its named points (their convex hull in the body's
own plane, a segment where they lie on a line, a marker where it has one point; a body without
named points has nothing in the outputs to draw), ground points, joints, the terminals of the
translational elements, each such element along the line between its terminals (springs and
dampers in neutral styles, each inerter coloured by its axial force on one colour map symmetric
about zero, with a colour bar), and the time. 3D scenes are drawn in an orthographic projection
with equal axis scales.

Frame count: `fps` × `duration` (default duration: the run's own length, i.e. real time), capped at
:data:`MAX_FRAMES`: a longer animation keeps its frame rate and plays faster than asked, so that a
long run never makes a huge file (a GIF of MAX_FRAMES frames is 2 to 3 MB).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from inerter.common.errors import InerterError

#: At most this many frames (12 s at 25 fps: a GIF of about 2 to 3 MB, drawn in about half a minute
#: on one core); a longer animation keeps its frame rate and plays faster than asked.
MAX_FRAMES = 300
DEFAULT_FPS = 25.0
MAX_FPS = 60.0
#: The colour map of the inerters' forces (blue: compression, red: tension), symmetric about zero.
FORCE_COLORMAP = "coolwarm"
FORMATS = (".gif", ".html")


class AnimationError(InerterError):
    """A value the animation cannot use; the message reads ``<field>: <problem> (got <value>; expected
    <expected>)``, like a scene error's."""

    def __init__(self, fld: str, value, expected: str, problem: str = "out of range"):
        super().__init__(f"{fld}: {problem} (got {value!r}; expected {expected})")


@dataclass
class Frames:
    """What an animation draws, frame by frame, in the run's own numbers (SI units)."""
    name: str
    dimension: int
    time: np.ndarray                        # each frame's time (s): a sample of the run
    samples: np.ndarray                     # each frame's index in the run's samples
    positions: dict[str, np.ndarray]        # point -> (frames, dimension) positions (m)
    bodies: list[tuple[str, list[str]]]     # body -> its outline: point names in drawing order
    ground: list[str]                       # ground points
    joints: list[tuple[str, str, str]]      # (joint, point a, point b)
    elements: list[tuple[str, str, str, str]]   # (element, kind: spring | damper | inerter | other, a, b)
    forces: dict[str, np.ndarray]           # inerter -> (frames,) axial force (N), tension positive
    force_limit: float                      # the colour scale runs over ±force_limit (N)
    fps: float
    speed: float                            # seconds of run per second of animation
    magnify: float = 1.0                    # displacements from the first sample drawn this many times
    colormap: str = FORCE_COLORMAP
    path: Path | None = None
    notes: list[str] = field(default_factory=list)

    def colour(self, element: str, k: int) -> tuple[float, float, float, float]:
        """The RGBA colour of inerter `element` at frame `k`: the colour map at its force."""
        from matplotlib import colormaps
        from matplotlib.colors import Normalize
        norm = Normalize(-self.force_limit, self.force_limit)
        return tuple(colormaps[self.colormap](norm(self.forces[element][k])))

    def describe(self) -> str:
        return (f"{len(self.time)} frames at {self.fps:g} fps: {len(self.time) / self.fps:.3g} s for "
                f"{self.time[-1] - self.time[0]:.6g} s of run ({self.speed:.3g}× real time)"
                + (f", displacements × {self.magnify:g}" if self.magnify != 1.0 else ""))


# ----------------------------------------------------------------------------------------------
# Frames from a result
# ----------------------------------------------------------------------------------------------
def _check(fld, value, low, high, expected):
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise AnimationError(fld, value, expected, "not a number") from None
    if not (math.isfinite(number) and low < number <= high):
        raise AnimationError(fld, value, expected)
    return number


def check_options(fps: float, duration: float | None, magnify: float = 1.0, labels: dict | None = None):
    """(fps, duration, magnify) as numbers in their ranges, or an AnimationError naming the one that
    is not (``animation fps``..., or the names in `labels`: the command line passes its options')."""
    label = {"fps": "animation fps", "duration": "animation duration", "magnify": "animation magnify",
             **(labels or {})}
    fps = _check(label["fps"], fps, 0.0, MAX_FPS, f"frames per second in (0, {MAX_FPS:g}]")
    if duration is not None:
        duration = _check(label["duration"], duration, 0.0, math.inf, "a length of animation in seconds, > 0")
    magnify = _check(label["magnify"], magnify, 0.0, math.inf, "a factor > 0 on the displacements (1: as they are)")
    return fps, duration, magnify


def frame_samples(time: np.ndarray, fps: float, duration: float | None, max_frames: int = MAX_FRAMES):
    """(sample indices, fps, speed): `fps` × `duration` frames (at most `max_frames` and the samples
    there are), evenly spaced over the run, each at the sample nearest its time."""
    fps, duration, _ = check_options(fps, duration)
    if not (isinstance(max_frames, (int, np.integer)) and max_frames >= 2):
        raise AnimationError("animation max_frames", max_frames, "a whole number ≥ 2")
    if len(time) < 2:
        raise AnimationError("animation of a result", f"{len(time)} samples", "a run with at least 2 output samples",
                             "nothing to animate")
    span = float(time[-1] - time[0])
    if duration is None:
        duration = span
    count = int(min(max(2, round(fps * duration)), max_frames, len(time)))
    targets = np.linspace(time[0], time[-1], count)
    right = np.clip(np.searchsorted(time, targets), 1, len(time) - 1)
    nearer_left = (targets - time[right - 1]) <= (time[right] - targets)
    samples = np.unique(np.where(nearer_left, right - 1, right))
    return samples, fps, span / (len(samples) / fps)


def outline(local: list[tuple[float, ...]]) -> list[int]:
    """Indices of body-frame points in the order that draws their outline: the convex hull of their
    projection on the body's principal plane (rigid motion keeps it), or the two ends where they
    lie on a line, or the one point."""
    pts = np.asarray(local, dtype=float)
    if len(pts) < 2:
        return list(range(len(pts)))
    centred = pts - pts.mean(axis=0)
    _, sv, axes = np.linalg.svd(centred, full_matrices=False)
    plane = centred @ axes[:2].T
    scale = max(sv[0], 1e-300)
    if len(sv) < 2 or sv[1] <= 1e-9 * scale:                  # on a line: its two ends
        return [int(np.argmin(plane[:, 0])), int(np.argmax(plane[:, 0]))]
    order = sorted(range(len(pts)), key=lambda i: (plane[i, 0], plane[i, 1]))

    def half(indices):                                        # Andrew's monotone chain
        chain = []
        for i in indices:
            while len(chain) >= 2:
                (ax, ay), (bx, by), (cx, cy) = plane[chain[-2]], plane[chain[-1]], plane[i]
                if (bx - ax) * (cy - ay) - (by - ay) * (cx - ax) > 1e-12 * scale ** 2:
                    break
                chain.pop()
            chain.append(i)
        return chain
    lower, upper = half(order), half(order[::-1])
    return lower[:-1] + upper[:-1]


def element_kind(kind: str) -> str:
    """How an element kind is drawn: any kind whose name holds "inerter" (an inerter device too) is
    coloured by its force; springs and dampers have their own styles; other kinds a thin line."""
    if "inerter" in kind:
        return "inerter"
    return kind if kind in ("spring", "damper") else "other"


def frames(result, fps: float = DEFAULT_FPS, duration: float | None = None,
           max_frames: int = MAX_FRAMES, magnify: float = 1.0) -> Frames:
    """The frames of `result` (a solver's or an FMU's): see the module's docstring. `magnify`: each
    point drawn at r(0) + magnify·(r − r(0)), for motions too small to see (a storey's drift)."""
    scene = result.model.scene
    dim = scene.dimension
    time = np.asarray(result.time, dtype=float)
    samples, fps, speed = frame_samples(time, fps, duration, max_frames)
    magnify = check_options(fps, duration, magnify)[2]
    by_body: dict[str, list] = {}
    for p in scene.points.values():
        by_body.setdefault(p.body, []).append(p)
    positions = {}
    for name in scene.points:
        r = np.column_stack([np.asarray(result[f"{name}.r[{i + 1}]"], dtype=float) for i in range(dim)])
        positions[name] = r[samples] if magnify == 1.0 else r[0] + magnify * (r[samples] - r[0])
    bodies, notes = [], []
    for body in scene.bodies:
        pts = by_body.get(body, [])
        if not pts:
            notes.append(f"body {body} has no named points: not drawn")
            continue
        bodies.append((body, [pts[i].name for i in outline([p.local for p in pts])]))
    ground = [p.name for p in by_body.get("ground", [])]
    joints = [(j.name, j.point_a, j.point_b) for j in scene.joints.values()]
    elements = [(e.name, element_kind(e.type), e.point_a, e.point_b) for e in scene.elements.values()
                if e.point_a and e.point_b]
    forces, limit = {}, 0.0
    for name, kind, _, _ in elements:
        if kind == "inerter":
            f = np.asarray(result[f"{name}.f"], dtype=float)
            forces[name] = f[samples]
            finite = f[np.isfinite(f)]
            limit = max(limit, float(np.max(np.abs(finite))) if len(finite) else 0.0)
    return Frames(name=result.model.name, dimension=dim, time=time[samples], samples=samples,
                  positions=positions, bodies=bodies, ground=ground, joints=joints, elements=elements,
                  forces=forces, force_limit=limit if limit > 0 else 1.0, fps=fps, speed=speed, notes=notes,
                  magnify=magnify)


# ----------------------------------------------------------------------------------------------
# Drawing with matplotlib (the GIF)
# ----------------------------------------------------------------------------------------------
ELEMENT_STYLE = {                     # drawn over one another where elements share their terminals
    "inerter": dict(lw=9.0, solid_capstyle="butt", zorder=2),     # outlined: white at zero force
    "damper": dict(lw=4.0, color="0.45", zorder=3),
    "spring": dict(lw=1.3, color="0.05", ls=(0, (4, 2)), zorder=4),
    "other": dict(lw=1.0, color="0.5", ls=":", zorder=4),
}


def bounds(fr: Frames) -> tuple[np.ndarray, float]:
    """(centre, half width) of a square (2D) or cube (3D) holding every point of every frame."""
    every = np.concatenate([p for p in fr.positions.values()]) if fr.positions else np.zeros((1, fr.dimension))
    every = every[np.all(np.isfinite(every), axis=1)]
    low, high = every.min(axis=0), every.max(axis=0)
    half = 0.5 * float(np.max(high - low))
    return 0.5 * (low + high), 1.1 * half if half > 0 else 1.0


def figure(fr: Frames, view: tuple[float, float] = (25.0, -60.0)):
    """(figure, update): update(k) draws frame k. Artists are found by their gid: ``body:NAME``,
    ``element:NAME``, ``joints``, ``ground``, ``terminals``, ``time``."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib import colormaps, patheffects
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    fig = plt.figure(figsize=(6.4, 4.8))
    ax = _axes(fig, fr, view)
    plot = (lambda **kw: ax.plot([], [], [], **kw)[0]) if fr.dimension == 3 else (lambda **kw: ax.plot([], [], **kw)[0])
    lines = {}
    outlined = [patheffects.Stroke(linewidth=ELEMENT_STYLE["inerter"]["lw"] + 2, foreground="0.3"), patheffects.Normal()]
    for name, kind, _, _ in fr.elements:
        lines[name] = plot(gid=f"element:{name}", **ELEMENT_STYLE[kind])
        if kind == "inerter":
            lines[name].set_path_effects(outlined)
    for body, _ in fr.bodies:
        lines[body] = plot(gid=f"body:{body}", color="0.25", lw=2.2, marker="o", ms=3, zorder=5)
    dots = {"ground": plot(gid="ground", ls="", marker="s", ms=8, color="0.3", zorder=6),
            "terminals": plot(gid="terminals", ls="", marker="o", ms=4, color="k", zorder=7),
            "joints": plot(gid="joints", ls="", marker="o", ms=7, mfc="white", mec="k", mew=1.3, zorder=8)}
    ends = [p for _, _, a, b in fr.elements for p in (a, b)]
    hinges = [p for _, a, b in fr.joints for p in (a, b)]
    norm = Normalize(-fr.force_limit, fr.force_limit)
    if fr.forces:
        bar = fig.colorbar(ScalarMappable(norm, colormaps[fr.colormap]), ax=ax, shrink=0.8, pad=0.08)
        bar.set_label("inerter force (N): tension > 0")
    kinds = [k for k in ("spring", "damper", "inerter") if any(e[1] == k for e in fr.elements)]
    if kinds:
        from matplotlib.lines import Line2D
        ax.legend([Line2D([], [], **{**ELEMENT_STYLE[k], "color": ELEMENT_STYLE[k].get("color", "0.6")})
                   for k in kinds], kinds, loc="upper left", fontsize=8, framealpha=0.7)
    label = (ax.text2D if fr.dimension == 3 else ax.text)(0.98, 0.97, "", transform=ax.transAxes, ha="right",
                                                          va="top", gid="time", fontsize=10)
    ax.set_title(fr.name + (f" (displacements × {fr.magnify:g})" if fr.magnify != 1.0 else ""), fontsize=10)

    def put(line, names, k, close=False):
        xyz = np.array([fr.positions[n][k] for n in names]).reshape(-1, fr.dimension)
        if close and len(names) > 2:
            xyz = np.vstack((xyz, xyz[:1]))
        if fr.dimension == 3:
            line.set_data_3d(xyz[:, 0], xyz[:, 1], xyz[:, 2])
        else:
            line.set_data(xyz[:, 0], xyz[:, 1])

    def update(k):
        for name, kind, a, b in fr.elements:
            put(lines[name], [a, b], k)
            if kind == "inerter":
                lines[name].set_color(fr.colour(name, k))
        for body, names in fr.bodies:
            put(lines[body], names, k, close=True)
        put(dots["ground"], fr.ground, k)
        put(dots["terminals"], ends, k)
        put(dots["joints"], hinges, k)
        label.set_text(f"t = {fr.time[k]:.3f} s")
        return list(lines.values()) + list(dots.values()) + [label]
    return fig, update


def _axes(fig, fr: Frames, view):
    centre, half = bounds(fr)
    if fr.dimension == 3:
        ax = fig.add_subplot(projection="3d", proj_type="ortho")
        for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
            setter(c - half, c + half)
        ax.set_box_aspect((1, 1, 1), zoom=1.1)        # a metre is as long on every axis
        ax.view_init(elev=view[0], azim=view[1])
        ax.set_zlabel("Z (m)")
    else:
        ax = fig.add_subplot()
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_aspect("equal")
        ax.grid(alpha=0.25)
    ax.set_xlabel("X (m)")
    ax.set_ylabel("Y (m)")
    return ax


def write_gif(fr: Frames, path: Path, view=(25.0, -60.0), dpi: int = 80):
    """The frames as an animated GIF, through matplotlib's PillowWriter (Pillow comes with matplotlib)."""
    try:
        import PIL  # noqa: F401
    except ImportError:
        raise AnimationError("animation path", str(path), "a .html page, or Pillow installed (pip install pillow)",
                             "a GIF needs Pillow, which is not installed") from None
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    fig, update = figure(fr, view)
    try:
        movie = FuncAnimation(fig, update, frames=len(fr.time), interval=1000.0 / fr.fps, blit=False)
        movie.save(str(path), writer=PillowWriter(fps=fr.fps), dpi=dpi)
    finally:
        plt.close(fig)


# ----------------------------------------------------------------------------------------------
# The entry point
# ----------------------------------------------------------------------------------------------
def animate(result, path, fps: float = DEFAULT_FPS, duration: float | None = None,
            view: tuple[float, float] = (25.0, -60.0), max_frames: int = MAX_FRAMES, magnify: float = 1.0) -> Frames:
    """Write an animation of `result` to `path`: ``.gif`` (matplotlib, Pillow) or ``.html`` (a page
    that plays the frames' data itself, with no external file; 3D views turn with the mouse).
    `fps`: frames per second; `duration`: seconds of animation (default: the run's length);
    `view`: (elevation, azimuth) in degrees of a 3D scene's projection; `magnify`: displacements
    from the first sample drawn this many times (see :func:`frames`). Returns the frames written,
    with ``describe()`` saying how many and how fast."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise AnimationError("animation path", str(path), "a file name ending in " + " or ".join(FORMATS), "unknown format")
    given = view
    try:
        view = (float(view[0]), float(view[1]))
        if len(given) != 2 or not all(map(math.isfinite, view)):
            raise ValueError
    except (TypeError, ValueError, IndexError):
        raise AnimationError("animation view", given, "(elevation, azimuth) in degrees, two finite numbers",
                             "not a view") from None
    fr = frames(result, fps, duration, max_frames, magnify)
    if path.suffix.lower() == ".gif":
        write_gif(fr, path, view)
    else:
        from inerter.studies.animation_page import page
        path.write_text(page(fr, view), encoding="utf-8")
    fr.path = path
    return fr
