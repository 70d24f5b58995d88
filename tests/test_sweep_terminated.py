"""A sweep stopped by SIGTERM (``kill PID``, as a batch system stops a job) stops as Ctrl-C does:
one line on stderr, exit status 143 (128 + 15), no traceback, its local cluster closed, every
finished row kept; the same command then runs the rest, each run once. Before, SIGTERM killed the
sweep where it stood: no message, dask's tracebacks from the workers and a leaked-semaphore warning
on stderr (the rows were kept: each is flushed as it finishes)."""
from __future__ import annotations

import csv
import signal
import subprocess
import sys
import time

import pytest

from conftest import LUMPED, ROOT
from inerter.studies.sweep import main_sweep

pytest.importorskip("distributed")

RUNS = 100          # enough that the compiled path's runs (~10 ms each) cannot all end before the signal


def rows_of(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_sigterm_stops_a_sweep_cleanly_and_the_same_command_finishes_it(tmp_path):
    out = tmp_path / "terminated"
    args = [str(LUMPED), "--vary", f"y0=1.1:1.8:{RUNS}", "--set", "experiment.rtol=1e-8", "--stop-time", "3",
            "--workers", "1", "--out", str(out), "--no-progress"]
    proc = subprocess.Popen([sys.executable, "-c", f"import sys; from inerter.studies.sweep import main_sweep; "
                             f"sys.exit(main_sweep({args!r}))"], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    results = out / "results.csv"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if results.is_file() and len(results.read_text().splitlines()) >= 3:       # header + 2 rows
            break
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)                 # the sweep's own process only, as `kill PID` does
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert err.strip() == ("inerter: terminated; the runs that finished are in results.csv: run the same "
                           "command again to go on"), err
    assert not (out / "results.csv.lock").exists()               # (it stayed, before)
    done_before = rows_of(results)
    assert 0 < len(done_before) < RUNS, "the sweep was not stopped part-way"
    assert main_sweep(args) == 0
    rows = rows_of(results)
    assert len(rows) == RUNS and len({r["key"] for r in rows}) == RUNS          # each run once
    assert rows[:len(done_before)] == done_before                              # nothing finished recomputed
    assert sorted(p.name for p in out.iterdir()) == ["results.csv", "sweep.json"]
