"""Ground motion: the whole ground translated with a prescribed acceleration history a_g(t).

Coordinates are taken relative to the moving ground frame, which adds the inertial force −m a_g to
every body; terminal distances (springs, dampers, inerters) are unchanged by a common translation.
The history is the sum of
- records: samples of one or more axes, linearly interpolated, zero before the first sample and
  after the last (the ground comes to rest when the record ends: where its last value is not zero,
  the acceleration steps to zero there and :attr:`GroundMotion.warnings` says so);
- analytic terms per axis, :func:`burst`: A sin(2πf(t − t_start) + φ) for t_start ≤ t < t_stop
  (a sine when t_start = 0 and t_stop = ∞);
or it is taken from FMU inputs ``ground.a[i]``.

A term's value is written once, :func:`burst`, compiled into the engine's kernels and run
uncompiled here.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from inerter.common.inlined import inlined

#: The columns of a row of analytic terms (GroundMotion.terms): axis (0-based), amplitude (m/s²),
#: frequency (Hz), phase (rad), start (s), stop (s; inf: none).
TERM_AXIS, TERM_AMPLITUDE, TERM_FREQUENCY, TERM_PHASE, TERM_START, TERM_STOP = range(6)
TERM_COLUMNS = 6
#: Standard gravity (m/s²): records in g (PEER NGA .AT2) are converted with it.
STANDARD_GRAVITY = 9.80665


@inlined
def burst(t, amplitude, frequency, phase, start, stop):
    """One analytic term: A sin(2πf(t − start) + φ) for start ≤ t < stop, 0 elsewhere."""
    if t < start or t >= stop:
        return 0.0
    return amplitude * math.sin(2.0 * math.pi * frequency * (t - start) + phase)


class GroundMotion:
    def __init__(self, dim, record=None, terms=None, scale=1.0, input=False, source="", files=()):
        self.dim = dim
        self.files = list(files)        # the record files read, relative to the scene file
        self.record = record            # (times, values[dim, n]) or None
        self.terms = np.zeros((0, TERM_COLUMNS)) if terms is None else np.asarray(terms, dtype=float)
        self.scale = float(scale)
        self.input = bool(input)
        self.source = source
        self.warnings = []
        if record is not None and self.scale != 0.0 and np.any(record[1][:, -1] != 0.0):
            end = [float(x) for x in record[1][:, -1]]
            self.warnings.append(f"ground motion {source}: the record ends at t = {record[0][-1]:g} s with "
                                 f"a_g = {end} m/s² (unscaled), not zero: after it the ground is at rest, "
                                 f"so its acceleration steps to zero there")

    @classmethod
    def sine(cls, dim, amplitude, frequency, scale=1.0):
        """a_g = amplitude·sin(2πft) on every axis (the scene's `amplitude` + `frequency`)."""
        terms = [(axis, a, frequency, 0.0, 0.0, math.inf) for axis, a in enumerate(amplitude)]
        return cls(dim, terms=terms, scale=scale, source=f"sine {list(amplitude)} m/s², {frequency:g} Hz")

    def acceleration(self, t, inputs=None, offset=0):
        if self.input:
            if inputs is None or len(inputs) < offset + self.dim:
                return np.zeros(self.dim)
            return self.scale * np.asarray(inputs[offset:offset + self.dim], dtype=float)
        a = np.zeros(self.dim)
        if self.record is not None:
            times, values = self.record
            a += [np.interp(t, times, values[i], left=0.0, right=0.0) for i in range(self.dim)]
        for row in self.terms:
            a[int(row[TERM_AXIS])] += burst.py_func(t, *row[TERM_AMPLITUDE:])
        return self.scale * a

    def breaks(self):
        """(kinks, jumps), each an increasing list of times > 0: where the acceleration's slope
        jumps but its value does not (a record's samples inside it, a record's end or a term's
        start or stop where the value is zero) and where its value jumps (a record's end on a
        value other than zero, a term starting or stopping on one). Empty for inputs."""
        if self.input:
            return [], []
        kinks, jumps = set(), set()
        if self.record is not None:
            times, values = self.record
            kinks.update(float(t) for t in times[1:-1] if t > 0)
            for i in (0, len(times) - 1):
                if times[i] > 0:
                    drops = self.scale != 0.0 and bool(np.any(values[:, i] != 0.0))
                    (jumps if drops else kinks).add(float(times[i]))
        for row in self.terms:
            amplitude, frequency, phase, start, stop = row[TERM_AMPLITUDE:]
            for at in (start, stop):
                if 0.0 < at < math.inf:
                    # the term's value at `at` from inside its interval (its stop lifted)
                    value = burst.py_func(at, amplitude, frequency, phase, start, math.inf)
                    (jumps if self.scale != 0.0 and abs(value) > 1e-12 * abs(amplitude) else kinks).add(float(at))
        return sorted(kinks - jumps), sorted(jumps)

    def describe(self):
        if self.input:
            return "acceleration from the inputs ground.a[i]"
        parts = []
        if self.record is not None:
            parts.append(f"record {self.source} ({len(self.record[0])} samples)")
        if len(self.terms):
            parts.append(f"{len(self.terms)} analytic term{'s' if len(self.terms) > 1 else ''}")
        return f"acceleration: {' + '.join(parts)}, scale {self.scale:g}"


class RecordValueError(ValueError):
    """A record's value that is read but not allowed (not finite, or above the magnitude limit)."""


#: The line of an .AT2 file its values begin on (after the four header lines).
AT2_FIRST_VALUE_LINE = 5


def read_at2(path, max_points=10_000_000, max_magnitude=math.inf):
    """(times, accelerations in g) of a PEER NGA record (.AT2): four header lines, the fourth
    giving NPTS and DT (``NPTS=  5590, DT= .0050 SEC``), then NPTS values in g, several per line.
    Raises ValueError naming the line of the file that is wrong, what it holds and what was
    expected; :class:`RecordValueError` for a value that is not finite or of magnitude above
    `max_magnitude` (g)."""
    path = Path(path)
    with path.open("r", encoding="utf-8", errors="replace") as f:
        header = [f.readline() for _ in range(4)]
        npts, dt = _at2_size(header[3])
        if npts > max_points:
            raise ValueError(f"line 4: NPTS = {npts}, more than the {max_points} points a record may have")
        text = f.read(32 * (npts + 1))
    tokens = text.split()[:npts + 1]
    try:
        values = np.array(tokens, dtype=float)
    except ValueError:
        index = next((i for i, token in enumerate(tokens) if not _is_number(token)), None)
        if index is None:
            raise
        raise ValueError(f"line {_at2_line(text, index)}: {tokens[index]!r} (value {index + 1} of NPTS) "
                         f"is not a number") from None
    if len(values) < npts:
        raise ValueError(f"line {_at2_line(text, len(values) - 1) if len(values) else AT2_FIRST_VALUE_LINE - 1}: "
                         f"the file ends after {len(values)} values, expected NPTS = {npts} (line 4)")
    if len(values) > npts:
        raise ValueError(f"line {_at2_line(text, npts)}: {tokens[npts]!r} is value {npts + 1}, expected "
                         f"NPTS = {npts} values (line 4)")
    bad = np.flatnonzero(~np.isfinite(values) | (np.abs(values) > max_magnitude))
    if len(bad):
        index = int(bad[0])
        raise RecordValueError(f"line {_at2_line(text, index)}, value {index + 1} of NPTS: {float(values[index])!r} g")
    return np.arange(npts) * dt, values


def _is_number(token: str) -> bool:
    try:
        np.array([token], dtype=float)
    except ValueError:
        return False
    return True


def _at2_line(text: str, index: int) -> int:
    """The line of the file holding value `index` (0-based) of an .AT2 file's values, `text`
    (the file after its header)."""
    count = 0
    for number, line in enumerate(text.split("\n"), start=AT2_FIRST_VALUE_LINE):
        count += len(line.split())
        if count > index:
            return number
    return AT2_FIRST_VALUE_LINE + text.count("\n")


def _at2_size(line):
    """(NPTS, DT) from an AT2 header line such as ``NPTS=  5590, DT= .0050 SEC``."""
    import re
    npts = re.search(r"NPTS\s*=\s*(\d+)", line, re.IGNORECASE)
    dt = re.search(r"DT\s*=\s*([0-9.eE+-]+)", line, re.IGNORECASE)
    if not npts or not dt:
        raise ValueError(f"line 4: {line.strip()[:80]!r}, expected the fourth header line to give NPTS and DT, "
                         f"e.g. 'NPTS=  5590, DT= .0050 SEC'")
    n = int(npts.group(1))
    try:
        step = float(dt.group(1))
    except ValueError:
        raise ValueError(f"line 4: DT = {dt.group(1)!r} is not a number") from None
    if n < 2 or not step > 0:
        raise ValueError(f"line 4: NPTS = {n} and DT = {step:g}, expected at least 2 points and DT > 0")
    return n, step


def combine_records(dim, components):
    """One record (times, values[dim, n]) from records of single axes, `components` = [(axis,
    times, values)]: the union of their sample times, each interpolated there (exact: a sum of
    piecewise-linear histories is piecewise linear with breaks at the union), zero outside each."""
    times = np.unique(np.concatenate([c[1] for c in components]))
    values = np.zeros((dim, len(times)))
    for axis, t, v in components:
        values[axis] += np.interp(times, t, v, left=0.0, right=0.0)
    return times, values
