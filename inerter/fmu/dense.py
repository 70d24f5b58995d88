"""An FMU's dense output, read from the FMU itself: what an FMU run's metrics and events read
between its communication points (:meth:`inerter.fmu.run.FmuResult.dense`).

An importer sees an FMU only at its communication points. Between them, the values come from a
second instance of the same FMU, started with the run's start values and stop time and stepped to
each time asked for. With DOP853 or RK45 (and Radau or BDF on the numpy path) the FMU keeps one
integration running across communication points, its steps clipped only to the stop time, and
takes the state at a communication point from the running step's dense output
(``fmu_src/README.md``, "The compiled path inside the FMU"). A communication point placed at t
therefore reads the FMU's own integrator's dense output at t, at the accuracy of the run, with the
same steps as the run: the instance gives the run's samples again, which is checked where it
passes them. Other integrations (RK4, LSODA, the ``projection`` treatment) restart at every
communication point, so a point placed between two would change the trajectory: for them the
dense output stays a cubic spline through the samples, as the solver's RK4 runs have.

Stepping is forward only, so the times asked for are taken in increasing order. The instance
keeps an FMU state (``fmi2GetFMUstate``) at samples as it passes them, every :data:`SAVE_EVERY`
samples or fewer, as many as stepping them costs what going back to a state does (an implicit
method's steps through a stiff contact cost far more than an explicit one's), and goes back to the
latest one before a time behind it (or far ahead of it) with ``fmi2SetFMUstate``;
the FMU's state holds its running integration, so a step repeated from it gives the same values
bit for bit.
"""
from __future__ import annotations

import bisect
import shutil
import time

import numpy as np

from inerter.engine.simulation import RUNS_ON, SimulationError

#: Samples between the FMU states kept, at most: a restore costs about as much as stepping this many
#: communication intervals (0.45 ms against 0.04 ms each, two_bar_2d through fmpy). Where stepping
#: costs more, fewer (:meth:`FmuDense._adapt`).
SAVE_EVERY = 10
#: What a restore is taken to cost (s) until one is measured (two_bar_2d through fmpy).
RESTORE_SECONDS = 4.5e-4
#: The relative difference allowed between the run's samples and the same samples stepped again
#: (the same integration, so in practice 0; a difference means the instance is not the run's).
SAMPLE_TOLERANCE = 1e-12


def reads_the_fmu(settings) -> bool:
    """Whether an FMU run with these settings keeps one integration across communication points,
    so that stepping it to any time reads its dense output there."""
    return settings.method in RUNS_ON and settings.constraint != "projection"


class FmuDense:
    """Values of an FMU's outputs at any times of its run, from a second instance stepped there.

    `fmu_path`, `start_values` and `stop_time` are the run's (as given to ``fmpy.simulate_fmu``);
    `result` is the run's :class:`~inerter.fmu.run.FmuResult` (its ``time`` and samples). The
    instance is made at the first call and freed by :meth:`close` (a later call makes it again).
    `instance`: an instantiated ``fmpy.fmi2.FMU2Slave`` of the same FMU whose run is over (a
    sweep's, kept across runs) to reset and step again instead of making one; :meth:`close` then
    leaves it instantiated, for its owner to reset."""

    def __init__(self, fmu_path, start_values, stop_time, result, instance=None):
        self.path, self.start_values, self.stop_time = str(fmu_path), dict(start_values), float(stop_time)
        self.result = result
        self._given = instance
        self._checked = None       # (names, their samples: sample × name), what _keep compares, once read
        self._times = np.asarray(result.time, dtype=float).tolist()   # a list: bisect, not np.searchsorted per scalar
        self._fmu = None
        self._saved = {}           # sample index → FMU state
        self._kept = []            # the indices of _saved, in increasing order (bisect)
        self._time = 0.0           # where the instance is
        #: doStep calls and FMU-state restores made, for the benchmarks' accounts.
        self.steps = self.restores = 0
        self._stride = SAVE_EVERY          # samples between the states kept from here on
        self._restore_seconds = RESTORE_SECONDS

    def names(self):
        return self._variables().keys()

    def values(self, name: str, times) -> np.ndarray:
        """The output `name` at `times` (any order, none NaN, clipped to the run's interval: the
        rounding ``api.at_times`` lets through, which reads a NaN time as NaN and refuses a time
        outside the run for :meth:`inerter.fmu.run.FmuResult.dense`)."""
        t = np.clip(np.asarray(times, dtype=float).reshape(-1), self._times[0], self._times[-1])
        out = np.empty(len(t))
        reference = [self._variables()[name]]
        for i in np.argsort(t, kind="stable"):
            self._go_to(float(t[i]))
            out[i] = self._fmu.getReal(reference)[0]
        return out

    def close(self):
        if self._fmu is None:
            return
        fmu, self._fmu = self._fmu, None
        try:
            for state in self._saved.values():
                fmu.freeFMUstate(state)
            if self._given is None:
                fmu.terminate()
                fmu.freeInstance()
        finally:
            self._saved.clear()
            self._kept.clear()
            if self._given is None:
                shutil.rmtree(self._dir, ignore_errors=True)

    # -- the instance ----------------------------------------------------------------------
    def _variables(self) -> dict:
        if self._fmu is None:
            self._open()
        return self._outputs

    def _open(self):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        from fmpy.simulation import apply_start_values

        md = read_model_description(self.path)
        self._outputs = {v.name: v.valueReference for v in md.modelVariables if v.causality == "output"}
        if self._given is not None:
            fmu = self._given
            fmu.reset()
        else:
            self._dir = extract(self.path)
            fmu = FMU2Slave(guid=md.guid, unzipDirectory=self._dir,
                            modelIdentifier=md.coSimulation.modelIdentifier, instanceName="dense output")
            fmu.instantiate()
        try:
            fmu.setupExperiment(startTime=self._times[0], stopTime=self.stop_time)
            fmu.enterInitializationMode()
            apply_start_values(fmu, md, self.start_values)
            fmu.exitInitializationMode()
        except Exception as exc:
            if self._given is None:
                fmu.freeInstance()
                shutil.rmtree(self._dir, ignore_errors=True)
            raise SimulationError(f"the FMU's dense output: a second instance of {self.path} could not be "
                                  f"initialised ({exc})", self._times[0]) from None
        self._fmu, self._time = fmu, self._times[0]
        self._keep(0)

    def _keep(self, k: int):
        """Keep the FMU state at sample k, where the instance is, after checking it gives the run's sample."""
        names, samples = self._samples()
        got = np.array(self._fmu.getReal([self._outputs[n] for n in names]))
        want = samples[k]
        scale = 1.0 + np.abs(want)
        off = ~((np.abs(got - want) <= SAMPLE_TOLERANCE * scale) | (np.isnan(got) & np.isnan(want)))
        if np.any(off):             # (a derived output without value there is NaN in both)
            worst = names[int(np.argmax(off))]
            raise SimulationError(f"the FMU's dense output: a second instance stepped to t = {self._times[k]:.9g} s "
                                  f"gives {worst} = {got[names.index(worst)]!r}, the run gave "
                                  f"{want[names.index(worst)]!r}: it does not repeat the run", self._times[k])
        self._saved[k] = self._fmu.getFMUstate()
        bisect.insort(self._kept, k)

    def _samples(self):
        """The outputs the run and the instance both have, and the run's samples of them (read once:
        a column of an FMU result is a copy)."""
        if self._checked is None:
            names = [n for n in self.result.names if n in self._outputs]
            self._checked = names, np.column_stack([np.asarray(self.result[n], dtype=float) for n in names])
        return self._checked

    # -- stepping --------------------------------------------------------------------------
    def _go_to(self, t: float):
        """Bring the instance to time t: back to a kept state where t is behind it (or a kept
        state lies well ahead of it), then forward, keeping states at samples every stride on the
        way (none where one is kept within the stride already)."""
        here = bisect.bisect_right(self._times, self._time) - 1
        target = bisect.bisect_right(self._times, t) - 1
        kept = self._kept[bisect.bisect_right(self._kept, target) - 1]     # the latest kept at or before target
        if t < self._time or kept >= here + 2 * self._stride:
            self._restore(kept)
            here = kept
        last = self._kept[bisect.bisect_right(self._kept, here) - 1]      # the latest kept at or before here
        while True:
            ahead = bisect.bisect_right(self._kept, last)
            k = max(last + self._stride, here + 1)
            if ahead < len(self._kept) and self._kept[ahead] <= min(k, target):
                last = self._kept[ahead]                                   # one kept within the stride already
                continue
            if k > target:
                break
            started, samples = time.perf_counter(), k - here
            self._step(self._times[k])
            self._adapt((time.perf_counter() - started) / samples)
            self._keep(k)
            last = here = k
        self._step(t)

    def _restore(self, k: int):
        started = time.perf_counter()
        self._fmu.setFMUstate(self._saved[k])
        self._restore_seconds = time.perf_counter() - started
        self._time = self._times[k]
        self.restores += 1

    def _adapt(self, per_sample: float):
        """The stride for a stepping cost of `per_sample` seconds a sample: as many samples as cost
        what the last restore did, between 1 and :data:`SAVE_EVERY`."""
        self._stride = int(min(SAVE_EVERY, max(1.0, self._restore_seconds / max(per_sample, 1e-9))))

    def _step(self, t: float):
        if t <= self._time:
            return
        try:
            self._fmu.doStep(currentCommunicationPoint=self._time, communicationStepSize=t - self._time)
        except Exception as exc:
            raise SimulationError(f"the FMU's dense output: a second instance of the FMU did not step from "
                                  f"t = {self._time:.9g} s to {t:.9g} s ({exc})", self._time) from None
        self.steps += 1
        self._time = t
