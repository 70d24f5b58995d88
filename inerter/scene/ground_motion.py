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

    def breaks(self):
        """(kinks, jumps) of a record, each an increasing list of times > 0: where the
        acceleration's slope jumps but its value does not (the samples inside the record, and an
        end where the record's value is zero) and where its value jumps (an end where the record's
        value is not zero: outside the record the motion is zero). Empty for a sine and for inputs."""
        if self.record is None or self.input:
            return [], []
        times, values = self.record
        kinks = [float(t) for t in times[1:-1] if t > 0]
        jumps = []
        for i in (0, len(times) - 1):
            if times[i] > 0:
                drops = self.scale != 0.0 and bool(np.any(values[:, i] != 0.0))
                (jumps if drops else kinks).append(float(times[i]))
        return sorted(kinks), jumps

    def describe(self):
        if self.input:
            return "acceleration from the inputs ground.a[i]"
        if self.record is not None:
            return f"acceleration record {self.source} ({len(self.record[0])} samples, scale {self.scale:g})"
        return f"sine acceleration, amplitude {list(self.amplitude)} m/s², {self.frequency:g} Hz"
