"""Work-precision of the inerter devices' hard cases (stick-slip, backlash impacts, end-stop
contact; scenarios/hard/*_device_2d.toml): steps, evaluations, events, CPU time and error at each
tolerance down to the tightest, DOP853 and Radau on the compiled right-hand side.

    python benchmarks/hard_case_steps.py [--out docs/benchmarks]

Writes hard_case_steps.md (inerter.studies.bench.hard_case_rows, hard_case_table).
"""
from __future__ import annotations

import argparse
import datetime
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from inerter.studies.bench import REPEATS_TEXT, hard_case_rows, hard_case_table  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    args = ap.parse_args(argv)
    rows = hard_case_rows(ROOT / "scenarios" / "hard")
    text = "\n".join([
        "# Work-precision of the device hard cases", "",
        f"`python benchmarks/hard_case_steps.py`, {datetime.date.today().isoformat()}: 5 s of each scene of "
        "scenarios/hard/ (stick-slip of a tanh friction with v_s = 1 mm/s, backlash impacts of a 2 mm gap "
        "with k_c = 1e4 N/m, Hunt-Crossley end stops with a Hertz exponent), atol = rtol/100, compiled "
        "right-hand side (DOP853: the compiled loop; Radau: scipy's). Error: the largest deviation of the "
        "points' positions from the same scene's DOP853 run at rtol 1e-13, over the 10 ms samples. CPU: the "
        f"integration's process time, {REPEATS_TEXT}. Events: end-stop contacts and releases, backlash "
        "engagements and releases found (Result.events).", "",
        hard_case_table(rows), "",
        "Where a run failed, its message (the table's status):", ""]
        + [f"- {r['case']} {r['method']} rtol {r['rtol']:g}: {r['message']}" for r in rows if r["status"] != "ok"])
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "hard_case_steps.md").write_text(text, encoding="utf-8")
    print(text)


if __name__ == "__main__":
    main()
