"""Element kinds, one module each, every kind's physics written once for 2D and 3D.

A kind's module holds its :class:`~inerter.elements.base.ElementKind` (the scene's ``type``, its
parameters with units and physical ranges, its outputs) and its law as scalar functions compiled by
:func:`~inerter.elements.base.law`, in the vector form of the paper's Eqs. 5-9: for a
translational element, of the terminal distance L, its rate L̇ = ṙ·r̂, a_n·r̂ and |ṙ⊥|²
(whatever the dimension), for a rotational one of the angle φ and its rate. The engine's kernels
(2D and 3D assembly, outputs) call these functions through :mod:`.dispatch`; the readable
evaluators run the same functions uncompiled. The scene reader takes each kind's parameters from
here, so a kind is declared, validated, simulated and reported from its one module.

Beside the kinds: :mod:`.base` (what a kind is, :func:`~inerter.elements.base.law`), :mod:`.layout`
(the named columns of the engine's element tables), :mod:`.terminals` (a translational element's
terminal geometry, whatever its kind: the line it acts along, r̂, a fixed ê₀ or a prismatic joint's
axis turning with a body, the L its law reads and whether its terminals meet), :mod:`.joint_rows` (a
joint's constraint rows: each row type's C, C_v coefficients and γ), :mod:`.winding` (a 3D
rotational element's angle wound on past half a turn), :mod:`.device` and
:mod:`.device_inertia` (an inerter's device effects), :mod:`.dispatch` and :mod:`.generate` (the
kernels' dispatch over the kinds, generated).

Adding a kind, e.g. a linear spring whose free length L0 sets its preload
(``elements.NAME.type = "preloaded_spring"``; its law is the shipped spring's, F = k (L − L0), so
that only the steps are new):

1. ``inerter/elements/preloaded_spring.py``::

       from inerter.elements.base import TRANSLATIONAL, ElementKind, Parameter, law
       from inerter.elements.layout import COEFFICIENT, FREE_LENGTH

       KIND = ElementKind(name="preloaded_spring", family=TRANSLATIONAL, equation="Eq. 5",
                          description="linear spring with its free length as preload",
                          coefficient=Parameter("k", "N/m", "stiffness", minimum=0.0),
                          free=Parameter("length", "m", "free length", minimum=0.0, required=False))

       @law
       def inertance(row, Ldot):
           return 0.0

       @law
       def force(row, L, Ldot, an, perp2):
           return row[COEFFICIENT] * (L - row[FREE_LENGTH])

       @law
       def energy(row, L, Ldot):
           return 0.5 * row[COEFFICIENT] * (L - row[FREE_LENGTH]) ** 2

2. ``python -m inerter.elements.generate`` writes the kernels' dispatch (:mod:`.dispatch`; a test
   fails while it is stale). The numpy path (``simulate(path="numpy")``) runs the kind at once; the
   compiled kernels' cache key covers this package's files, so the next compiled run compiles them
   again, once (minutes: ``docs/benchmarks/first_use.md``).
3. Its own definition in the oracle, written again from the kind's potential or dissipation function
   (a translational kind in :class:`inerter.oracle.derivation.OracleElement`, a rotational one in
   :mod:`inerter.oracle.rotational`), never read from here: that is what lets the oracle check the
   law. Until it is written, the engine runs the kind but the oracle refuses a scene with it, in one
   line: ``SCENE: elements.NAME.type: the oracle has no independent definition of the translational
   kind 'preloaded_spring' of element 'NAME' yet (...)``.
4. Its tests: the law against a closed form (``tests/test_elements.py`` does so for the shipped
   kinds), and a scene using it among those ``tests/test_engine_vs_oracle.py`` runs through the
   engine and the oracle (every ``scenarios/*.toml``, found by glob, and its ``EXTRA_CASES``).
   ``tests/test_adding_a_kind.py`` takes this example from this docstring and follows steps 1 and 2
   in a copy of the package, then checks the numpy path against a closed form and step 3's refusal.

A kind may also report outputs beyond its family's (:data:`FAMILY_OUTPUTS`): a law ``extra_outputs(row, L, Ldot, an,
perp2, gq, x, out, k)`` (gq = gᵀq̈ at the solved accelerations, x its internal states) that writes
them at ``out[k]``... and returns the index after them, and
``extra_output_names(spec)`` that names them for a scene element (the inerter's device,
:mod:`.device`, does so).

An element may also have internal states x, its slice of z in the engine's state y = [q, v, z]
(an inerter device's series deflection and rate, its dissipated energy: ``el_int[e, STATE]``,
``STATES``). Its kind then gives ``state_force(row, L, Ldot, x)`` (added to its force),
``state_energy(row, L, Ldot, x)`` and ``state_rates(row, L, Ldot, an, perp2, gq, x, dx)`` (ẋ once
q̈ is solved, gq = gᵀq̈), which the kernels call only for an element that has states.

A translational law returns the axial force less its inertance times gᵀq̈: ``inertance(row, Ldot)``
is the factor that goes into the mass matrix (M += b g gᵀ, Eq. 33; zero for all but the inerter, a
law of L̇ only for a screw efficiency's b_eff, :mod:`.device`) and
``force(row, L, Ldot, an, perp2)`` the rest (Q −= F g, Eqs. 29 and 31).
"""
from __future__ import annotations

import importlib
import pkgutil

from inerter.elements.base import (  # noqa: F401
    FAMILY_OUTPUTS, FORCE_OUTPUTS, ROTATIONAL, TRANSLATIONAL, ElementKind, Parameter, output_suffixes)

_NOT_KINDS = {"base", "layout", "dispatch", "generate", "device", "device_inertia", "joint_rows", "kinematics",
              "terminals", "twist", "winding"}


def _kind_modules():
    """Every module of this package that defines a KIND, in name order (their codes)."""
    names = sorted(m.name for m in pkgutil.iter_modules(__path__) if m.name not in _NOT_KINDS)
    mods = [importlib.import_module(f"{__name__}.{n}") for n in names]
    return tuple(m for m in mods if hasattr(m, "KIND"))


#: The kinds' modules; a kind's code in the engine's tables is its place here.
MODULES = _kind_modules()
#: The kinds by the scene's ``type``.
KINDS: dict[str, ElementKind] = {m.KIND.name: m.KIND for m in MODULES}
#: A kind's code in the engine's tables, by the scene's ``type``.
CODE: dict[str, int] = {m.KIND.name: i for i, m in enumerate(MODULES)}
#: A kind's module, by the scene's ``type``.
MODULE = {m.KIND.name: m for m in MODULES}


def translational(name: str) -> bool:
    return KINDS[name].family == TRANSLATIONAL


def outputs(spec) -> tuple[tuple[str, str, str], ...]:
    """(suffix, unit, description) of every output of scene element `spec`: its family's
    (:data:`FAMILY_OUTPUTS`) and, where its kind has them (an inerter's device), those its law writes after them
    (``extra_outputs``, named by the module's ``extra_output_names(spec)``)."""
    module = MODULE[spec.type]
    extra = getattr(module, "extra_output_names", None)
    return KINDS[spec.type].outputs + (tuple(extra(spec)) if extra is not None else ())
