"""Events of a run: when an inerter device's end stops make and break contact, and when its
backlash gap closes and opens (:mod:`inerter.elements.device`).

An event is a crossing of a level by an output: the terminal distance ``E.s_rel`` through a stop's
L_min (contact on the way down, release on the way up) or L_max (contact on the way up), the series
deflection ``E.s_series`` through ±Δ/2 (engaged outside, free inside). The crossings are bracketed
on the samples and the integrator's own nodes (so that a contact shorter than an output interval
is not missed: its stiff force shortens the steps through it) and refined on the dense output to
1e-14 of the run's span (:func:`inerter.engine.metrics.crossing_times`, the metrics' root
finder), so that an event time is as accurate as the integrator's dense output.
"""
from __future__ import annotations

import numpy as np

from inerter.engine.metrics import crossing_times


def _levels(spec):
    """(output suffix, level, direction into the event, event name on the way in, on the way out,
    where) of each declared event of scene element `spec`."""
    device = getattr(spec, "device", None)
    if device is None:
        return []
    out = []
    if device.has("end_stops"):
        stops = device.values("end_stops")
        if stops["min"] is not None:
            out.append(("s_rel", float(stops["min"]), -1, "contact", "release", "lower stop"))
        if stops["max"] is not None:
            out.append(("s_rel", float(stops["max"]), 1, "contact", "release", "upper stop"))
    if device.has("backlash"):
        half = 0.5 * float(device.values("backlash")["gap"])
        out.append(("s_series", half, 1, "engaged", "free", "gap, positive side"))
        out.append(("s_series", -half, -1, "engaged", "free", "gap, negative side"))
    return out


def declares_events(scene) -> bool:
    """Whether a scene has events to report (an end stop or a backlash gap)."""
    return any(_levels(spec) for spec in scene.elements.values())


def device_events(scene, times, signal) -> list[dict]:
    """Every event of the run, in time order: dicts with ``time`` (s), ``element``, ``event``
    (contact, release, engaged, free) and ``where`` (lower stop, upper stop, gap side). `times`:
    the samples and the integrator's nodes (increasing); `signal(name)`: a callable t ↦ the output
    `name` at the times t (``Result.dense``)."""
    t = np.unique(np.asarray(times, dtype=float))
    found = []
    cache = {}
    for name, spec in scene.elements.items():
        for suffix, level, into, entered, left, where in _levels(spec):
            key = f"{name}.{suffix}"
            if key not in cache:
                dense = signal(key)
                cache[key] = (dense, np.asarray(dense(t), dtype=float))
            dense, x = cache[key]
            for direction, what in ((into, entered), (-into, left)):
                when = crossing_times(t, x, level, direction, dense)
                found += [dict(time=float(w), element=name, event=what, where=where) for w in when]
    return sorted(found, key=lambda e: e["time"])
