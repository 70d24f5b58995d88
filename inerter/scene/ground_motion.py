"""Ground motion: the whole ground translated with a prescribed acceleration history a_g(t).

Coordinates are taken relative to the moving ground frame, which adds the inertial force −m a_g to
every body; terminal distances (springs, dampers, inerters) are unchanged by a common translation.
The history is a CSV record (time and one column per axis, linearly interpolated, zero outside
the record), a sine, or FMU inputs ``ground.a[i]``.
"""
from __future__ import annotations

import math

import numpy as np


class GroundMotion:
    def __init__(self, dim, record=None, amplitude=None, frequency=None, scale=1.0, input=False, source=""):
        self.dim = dim
        self.record = record            # (times, values[dim, n]) or None
        self.amplitude = None if amplitude is None else np.asarray(amplitude, dtype=float)
        self.frequency = frequency
        self.scale = float(scale)
        self.input = bool(input)
        self.source = source

    def acceleration(self, t, inputs=None, offset=0):
        if self.input:
            if inputs is None or len(inputs) < offset + self.dim:
                return np.zeros(self.dim)
            return self.scale * np.asarray(inputs[offset:offset + self.dim], dtype=float)
        if self.record is not None:
            times, values = self.record
            return self.scale * np.array([np.interp(t, times, values[i], left=0.0, right=0.0)
                                          for i in range(self.dim)])
        return self.scale * self.amplitude * math.sin(2.0 * math.pi * self.frequency * t)

    def describe(self):
        if self.input:
            return "acceleration from the inputs ground.a[i]"
        if self.record is not None:
            return f"acceleration record {self.source} ({len(self.record[0])} samples, scale {self.scale:g})"
        return f"sine acceleration, amplitude {list(self.amplitude)} m/s², {self.frequency:g} Hz"
