"""What each effect costs: the same scene with a term switched off, removed or undeclared.

    python benchmarks/effect_cost.py [--out docs/benchmarks]

Variants of the two-bar scene (0-20 s) and of the 32-link chain (0-1 s): centripetal term on /
off, inerters removed from the scene, gravity undeclared / declared as [0, 0] / declared
[0, -9.81]. Cost per evaluation of Eq. (33) on the compiled path (RK4 with a fixed 1 ms step, so
every variant takes the same steps) and on the numpy path (Mechanism.accelerations, a loop of
calls), in ROUNDS rounds over the variants; the ratio to a variant's reference is the median of
the ratios within each round. Target: switching a term off costs no more than the scene without
that term.
"""
from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT))

from inerter import api
import inerter  # noqa: E402
from inerter.engine import compiled  # noqa: E402
from chain_scene import chain_toml  # noqa: E402


def without_inerters(text: str) -> str:
    """Drop every [elements.X] table of type inerter."""
    blocks = re.split(r"(?m)^(?=\[)", text)
    return "".join(b for b in blocks if not (b.startswith("[elements.") and re.search(r'type\s*=\s*"inerter"', b)))


def with_gravity(text: str, g: str) -> str:
    return re.sub(r"(?m)^\[effects\]\n", f"[effects]\ngravity = {g}\n", text, count=1)


#: Interleaved rounds; each variant's smallest time is kept.
ROUNDS = 9


def compiled_cost(model, span, repeats=5):
    s = model.settings(method="RK4", step=1e-3, stop_time=span, max_steps=10 ** 7)
    best, run = float("inf"), None
    for _ in range(repeats):
        run = compiled.integrate_compiled(model.mechanism, s)
        best = min(best, run.cpu_time)
    return best / run.evaluations


def numpy_cost(model, calls=300, repeats=5):
    mech = model.mechanism
    q, v = mech.q0, mech.v0 + 0.1
    best = float("inf")
    for _ in range(repeats):
        t0 = time.process_time()
        for _ in range(calls):
            mech.accelerations(0.1, q, v)
        best = min(best, (time.process_time() - t0) / calls)
    return best


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=str(ROOT / "docs" / "benchmarks"))
    a = p.parse_args(argv)
    if not compiled.AVAILABLE:
        raise SystemExit(f"the compiled path is not available: {compiled.WHY_NOT}")
    api.warm_up()
    tmp = Path(tempfile.mkdtemp())
    bases = [("two_bar_2d", (ROOT / "scenarios" / "two_bar_2d.toml").read_text(), 20.0, 300),
             ("chain_32", chain_toml(32), 1.0, 20)]
    lines = ["# What each effect costs", "",
             f"`python benchmarks/effect_cost.py`, {time.strftime('%Y-%m-%d')}, one run. Cost of one evaluation of "
             f"Eq. (33): compiled (RK4 1 ms over the whole span, CPU time / evaluations) and numpy "
             f"(`Mechanism.accelerations`, a loop of calls), best of {ROUNDS} rounds taken in turn over the "
             "variants.", "",
             "| scene | variant | compiled (µs/eval) | numpy (µs/eval) | compiled ≤ reference? |",
             "|---|---|---|---|---|"]
    verdicts = []
    for name, text, span, calls in bases:
        variants = [
            ("as declared (centripetal on, no gravity)", text, {}, None),
            ("centripetal off", text, {"effects.centripetal": False}, "as declared (centripetal on, no gravity)"),
            ("inerters removed", without_inerters(text), {}, "as declared (centripetal on, no gravity)"),
            ("gravity declared [0, 0] (not compiled)", with_gravity(text, "[0, 0]"), {},
             "gravity declared [0, -9.81]"),
            ("gravity declared [0, -9.81]", with_gravity(text, "[0, -9.81]"), {}, None),
        ]
        models = {}
        for label, body, overrides, _ in variants:
            path = tmp / f"{name}_{len(models)}.toml"
            path.write_text(body)
            models[label] = inerter.load(path, **overrides)
        # Interleaved rounds: load from other processes hits all variants of a round alike. The cost
        # shown is each variant's smallest; the verdict takes, in each round, the variant's time over
        # its reference's in the same round, and the median of those ratios over the rounds.
        rounds = {label: [] for label in models}
        for r in range(ROUNDS):
            order = list(models.items()) if r % 2 == 0 else list(models.items())[::-1]
            for label, model in order:
                rounds[label].append((compiled_cost(model, span, repeats=1), numpy_cost(model, calls, repeats=1)))
        costs = {label: [min(x[0] for x in rs), min(x[1] for x in rs)] for label, rs in rounds.items()}
        for label in models:
            print(name, label, costs[label], flush=True)

        def ratio(label, ref):
            return float(np.median([a[0] / b[0] for a, b in zip(rounds[label], rounds[ref])]))

        # The undeclared-gravity reference is the scene as declared.
        for label, _, _, ref in variants:
            c, n = costs[label]
            verdict = ""
            if ref is not None:
                x = ratio(label, ref)
                ok = x <= 1.03
                verdict = f"{'yes' if ok else 'NO'} (vs {ref}: {x:.2f}×)"
                verdicts.append(ok)
            elif label.startswith("as declared"):
                x = ratio(label, "gravity declared [0, -9.81]")
                ok = x <= 1.03
                verdict = f"{'yes' if ok else 'NO'} (gravity undeclared vs declared: {x:.2f}×)"
                verdicts.append(ok)
            lines.append(f"| {name} | {label} | {c * 1e6:.3f} | {n * 1e6:.1f} | {verdict} |")
    lines += ["", "A term switched off or undeclared is not evaluated (its loop runs zero times or its flag "
              "skips it). Ratios: the median over the rounds of a variant's time over its reference's in the same "
              "round (the order of the variants reversed every other round); within ±3 % they are timing noise.", "",
              f"Target (each switch costs no more than the scene without the term): "
              f"{'met' if all(verdicts) else 'NOT met'}."]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "effect_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
