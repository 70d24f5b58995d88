"""Plots of time histories, relative to static equilibrium as in the paper's Figs. 8 and 12."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from inerter.scene.units import for_reading  # noqa: E402


def plotted_signals(model) -> list[str]:
    """The signals a scene's metrics look at (a point coordinate first), or the coordinates of its
    first point on a body (a ground point's never move)."""
    names = []
    for m in model.scene.metrics:
        for s in (m.signal, m.period_of):
            if s and s not in names:
                names.append(s)
    if not names:
        moving = [p.name for p in model.scene.points.values() if p.body != "ground"][:1]
        names = ([f"{p}.r[{i + 1}]" for p in moving for i in range(model.scene.dimension)]
                 or [n for n in model.signals.names if ".r[" in n][:2])
    names.sort(key=lambda n: 0 if ".r[" in n else 1)
    return names


def _relative(model, name, values):
    """Positions relative to their static equilibrium value; other signals as they are."""
    if ".r[" in name:
        try:
            return values - model.static_value(name), f"{name} − static (m)"
        except Exception:  # no equilibrium: plot the raw signal
            pass
    unit = for_reading(model.signals.units[model.signals.index[name]])
    return values, f"{name} ({unit})" if unit else name


def plot_runs(runs, path, title):
    """Overlay several results: `runs` is a list of (label, Result, style dict)."""
    model = runs[0][1].model
    names = plotted_signals(model)
    fig, axes = plt.subplots(len(names), 1, figsize=(9, 3.2 * len(names)), squeeze=False, sharex=True)
    for ax, name in zip(axes[:, 0], names):
        for label, result, style in runs:
            y, ylabel = _relative(result.model, name, result[name])
            line, = ax.plot(result.time, y, label=label, **style)
            ax.axhline(float(np.mean(y[len(y) // 2:])), color=line.get_color(), ls=":", lw=0.8)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    axes[0, 0].set_title(title + "\n(dotted: mean over the second half)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
