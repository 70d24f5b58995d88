"""Fast path (closed forms, Eqs. 15–20 and 33) against the oracle (forces from d²L/dt² by
forward-mode differentiation of L(q)), both at tight tolerance: any error in either shows up."""
from __future__ import annotations

import numpy as np
import pytest

import inerter
from conftest import LUMPED, TWO_BAR

TIGHT = dict(rtol=1e-11, atol=1e-13)


@pytest.mark.parametrize("scene", [LUMPED, TWO_BAR], ids=["lumped_mass", "two_bar"])
@pytest.mark.parametrize("centripetal", [True, False], ids=["corrected", "uncorrected"])
def test_fast_path_agrees_with_oracle(runs, scene, centripetal):
    fast = runs(scene, centripetal, stop_time=10.0, **TIGHT, metrics=False)
    ref = runs(scene, centripetal, oracle=True, stop_time=10.0, **TIGHT, metrics=False)
    assert fast.status == ref.status == "ok"
    positions = [n for n in fast.names if ".r[" in n]
    worst = max(np.max(np.abs(fast[n] - ref[n])) for n in positions)
    assert worst <= 1e-8
    # the element forces agree too (relative to their range)
    for name in (n for n in fast.names if n.endswith(".f")):
        scale = max(1.0, np.max(np.abs(ref[name])))
        assert np.max(np.abs(fast[name] - ref[name])) <= 1e-7 * scale


def test_oracle_and_fast_path_differ_if_the_correction_differs(runs):
    # Guard against a comparison that cannot fail: the two models are far apart.
    a = runs(LUMPED, True, stop_time=10.0, **TIGHT, metrics=False)
    b = runs(LUMPED, False, oracle=True, stop_time=10.0, **TIGHT, metrics=False)
    assert np.max(np.abs(a["P.r[2]"] - b["P.r[2]"])) > 0.1


def test_element_forces_agree_at_random_states():
    """Spot check away from any trajectory: M + M_I and Q at random (q, q̇)."""
    rng = np.random.default_rng(7)
    for cen in (True, False):
        fast = inerter.load(TWO_BAR, **{"effects.centripetal": cen}).mechanism
        ref = inerter.load(TWO_BAR, **{"effects.centripetal": cen}).oracle().mechanism
        for _ in range(20):
            q = fast.q0 + rng.normal(scale=0.3, size=fast.n)
            v = rng.normal(scale=2.0, size=fast.n)
            np.testing.assert_allclose(fast.mass_matrix(q, v), ref.mass_matrix(q, v), rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(fast.generalized_forces(0.3, q, v), ref.generalized_forces(0.3, q, v),
                                       rtol=1e-11, atol=1e-10)
