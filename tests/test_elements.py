"""Element kinds (inerter.elements): each kind's law, written once, against closed forms; the
registry and the kernels' dispatch generated from it."""
import math

import numpy as np
import pytest

from inerter.common.inlined import compiled_copy
from inerter import elements
from inerter.elements import dispatch, generate, layout
from inerter.scene.reader import ELEMENT_TYPES


def test_the_dispatch_is_generated_from_the_kinds_found():
    """``python -m inerter.elements.generate`` writes it; a kind added without running it fails here."""
    assert generate.TARGET.read_text(encoding="utf-8") == generate.source()


def test_every_kind_declares_its_law_parameters_and_outputs():
    assert list(elements.CODE.values()) == list(range(len(elements.MODULES)))
    assert set(ELEMENT_TYPES) == set(elements.KINDS)
    for name, module in elements.MODULE.items():
        kind = module.KIND
        assert kind.coefficient.unit and kind.coefficient.key, name
        laws = ("inertance", "force", "energy") if kind.family == elements.TRANSLATIONAL else ("torque", "energy")
        for law in laws:
            assert callable(getattr(module, law).py_func), (name, law)
        family = (("s_rel", "v_rel", "f") if kind.family == elements.TRANSLATIONAL else ("phi_rel", "w_rel", "tau"))
        assert tuple(suffix for suffix, _, _ in kind.outputs) == family + ("power", "energy"), name
        assert dict((s, u) for s, u, _ in kind.outputs)["power"] == "W", name
        assert dict((s, u) for s, u, _ in kind.outputs)["energy"] == "J", name


def _row(k, free=0.0, centripetal=True):
    row = np.zeros(layout.ELEMENT_REAL_COLUMNS)
    row[layout.COEFFICIENT] = k
    row[layout.FREE_LENGTH] = free
    row[layout.CENTRIPETAL] = 1.0 if centripetal else 0.0
    return row


def _rotating_terminal(t, L0=1.3, A=0.2, Om=2.7, w=1.9):
    """r(t) = L(t) (cos ωt, sin ωt, 0), L(t) = L0 + A sin Ωt: a terminal distance that changes while
    the element turns. Returns L, L̇, L̈ (closed forms) and r, ṙ, r̈."""
    L, Ld, Ldd = L0 + A * math.sin(Om * t), A * Om * math.cos(Om * t), -A * Om * Om * math.sin(Om * t)
    c, s = math.cos(w * t), math.sin(w * t)
    e, e_t = np.array([c, s, 0.0]), np.array([-s, c, 0.0])
    r = L * e
    rd = Ld * e + L * w * e_t
    rdd = (Ldd - L * w * w) * e + 2.0 * Ld * w * e_t
    return L, Ld, Ldd, r, rd, rdd


@pytest.mark.parametrize("t", [0.0, 0.4, 1.7, 3.1])
def test_the_inerter_law_is_b_times_the_second_derivative_of_the_length(t):
    """Closed form: with all of r̈ in a_n (q̈ = 0), F = b L̈ with the centripetal term (Eq. 9) and
    b r̈·r̂ without it (Eq. 8), whatever the element's rotation."""
    b = 3.5
    L, Ld, Ldd, r, rd, rdd = _rotating_terminal(t)
    rhat = r / L
    Ldot = float(rd @ rhat)
    an = float(rdd @ rhat)
    perp2 = float(rd @ rd) - Ldot * Ldot
    law = elements.MODULE["inerter"]
    for run in (compiled_copy(law.force), law.force.py_func):
        assert run(_row(b), L, Ldot, an, perp2) == pytest.approx(b * Ldd, rel=1e-13, abs=1e-13)
        assert run(_row(b, centripetal=False), L, Ldot, an, perp2) == pytest.approx(
            b * float(rdd @ rhat), rel=1e-13)
    assert law.inertance.py_func(_row(b), Ldot) == b
    assert law.energy.py_func(_row(b), L, Ldot) == pytest.approx(0.5 * b * Ld * Ld, rel=1e-13)


def test_spring_and_damper_laws():
    """Eqs. 5 and 7, and the spring's potential ½k(L − L0)²."""
    k, c, L0, L, Ld = 200.0, 7.0, 0.8, 1.1, -0.3
    spring, damper = elements.MODULE["spring"], elements.MODULE["damper"]
    assert spring.force(_row(k, L0), L, Ld, 5.0, 2.0) == pytest.approx(k * (L - L0), rel=1e-15)
    assert spring.energy(_row(k, L0), L, Ld) == pytest.approx(0.5 * k * (L - L0) ** 2, rel=1e-15)
    assert damper.force(_row(c), L, Ld, 5.0, 2.0) == pytest.approx(c * Ld, rel=1e-15)
    assert spring.inertance(_row(k), Ld) == 0.0 == damper.inertance(_row(c), Ld) == damper.energy(_row(c), L, Ld)


def test_rotational_laws():
    row = np.array([40.0, 0.25])
    spring, damper = elements.MODULE["rotational_spring"], elements.MODULE["rotational_damper"]
    assert spring.torque(row, 1.0, 3.0) == pytest.approx(40.0 * 0.75, rel=1e-15)
    assert spring.energy(row, 1.0, 3.0) == pytest.approx(0.5 * 40.0 * 0.75 ** 2, rel=1e-15)
    assert damper.torque(row, 1.0, 3.0) == pytest.approx(120.0, rel=1e-15)


def test_the_dispatch_calls_each_kind_by_its_code():
    """The dispatch, compiled as the kernels compile it, gives each kind's law run as written."""
    L, Ld, an, perp2 = 1.2, 0.4, -0.7, 0.09
    for name, code in elements.CODE.items():
        module = elements.MODULE[name]
        if module.KIND.family == elements.TRANSLATIONAL:
            row = _row(2.0, 0.5)
            assert compiled_copy(dispatch.force)(code, row, L, Ld, an, perp2) == module.force.py_func(row, L, Ld, an, perp2)
            assert compiled_copy(dispatch.inertance)(code, row, Ld) == module.inertance.py_func(row, Ld)
            assert compiled_copy(dispatch.energy)(code, row, L, Ld) == module.energy.py_func(row, L, Ld)
        else:
            row = np.array([2.0, 0.5])
            assert compiled_copy(dispatch.torque)(code, row, L, Ld) == module.torque.py_func(row, L, Ld)
            assert compiled_copy(dispatch.rotational_energy)(code, row, L, Ld) == module.energy.py_func(row, L, Ld)
