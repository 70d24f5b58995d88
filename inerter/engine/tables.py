"""Rows of the tables the kernels run on, shared by the 2D and 3D flattening
(:func:`inerter.engine.compiled.flatten`, :func:`inerter.engine.compiled_spatial.flatten3`)."""
from __future__ import annotations


def _by_name(objects):
    return {getattr(o, "name", None): o for o in objects}


#: Column 0 of ``el_int`` and column 1 of ``fa_int``, as in :mod:`inerter.engine.kernels`.
ELEMENT_KIND = {"spring": 0, "damper": 1, "inerter": 2}
FORCE_CODE = {"constant": 0, "sine": 1, "step": 2}


def element_row(e, me, pidx, centripetal, meet_limit) -> tuple[tuple, tuple]:
    """The ``el_int`` and ``el_real`` rows of translational element `e` of the scene (`me`: the
    mechanism's element of that name, whose free length a spring takes, else the scene's;
    `meet_limit`: its column of :func:`meet_limits`)."""
    free = 0.0
    if e.type == "spring":
        free = getattr(me, "free_length", None)
        if free is None:
            free = e.free_length
        if free is None:
            raise ValueError(f"spring {e.name}: no free length on the compiled mechanism")
    return ((ELEMENT_KIND[e.type], pidx[e.point_a], pidx[e.point_b], int(bool(centripetal))),
            (float(e.coefficient), float(free), float(meet_limit)))


def meet_limits(mech, elements) -> dict[str, float]:
    """Column 2 of ``el_real`` by translational element name: the distance below which its terminals
    meet (``Mechanism.meet_limit``), 0.0 for an element whose pair of terminals an earlier element
    shares (compiled_kernels.terminals_meet checks each pair once, as Mechanism.check_terminals)."""
    seen, limits = set(), {}
    for e in elements:
        if e.type in ("rotational_spring", "rotational_damper"):
            continue
        pair = frozenset((e.point_a, e.point_b))
        limits[e.name] = 0.0 if pair in seen else float(mech.meet_limit[e.name])
        seen.add(pair)
    return limits


def force_rows(scene, pidx, dim) -> tuple[list, list, list, list, list]:
    """(fa_int, fa_real, pd_int, pd_real, in_int): the scene's applied point forces with time
    functions (point, code; direction's `dim` components, value, amplitude, frequency, phase,
    offset, time, initial), grounded PD actuators (point; direction, kp, kd, reference) and input
    forces (point)."""
    fa_int, fa_real, pd_int, pd_real, in_int = [], [], [], [], []
    for f in scene.forces.values():
        p = pidx[f.point]
        d = [float(x) for x in f.direction[:dim]] if f.direction is not None else None
        if f.function in FORCE_CODE:
            fa_int.append((p, FORCE_CODE[f.function]))
            fa_real.append((*d, f.value, f.amplitude, f.frequency, f.phase, f.offset, f.time, f.initial))
        elif f.function == "pd":
            pd_int.append((p,))
            pd_real.append((*d, f.kp, f.kd, f.reference))
        elif f.function == "input":
            in_int.append((p,))
    return fa_int, fa_real, pd_int, pd_real, in_int
