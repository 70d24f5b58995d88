"""Rows of the tables the kernels run on, shared by the 2D and 3D flattening
(:func:`inerter.engine.compiled.flatten`, :func:`inerter.engine.compiled_spatial.flatten3`); the
columns are named in :mod:`inerter.elements.layout`."""
from __future__ import annotations

import numpy as np

from inerter import elements
from inerter.elements import layout
from inerter.scene.changes import differences


def _by_name(objects):
    return {getattr(o, "name", None): o for o in objects}


#: An element kind's code in the tables (``el_int[:, KIND]``, ``rot_int[:, ROT_KIND]``).
ELEMENT_KIND = elements.CODE
#: Column 1 of ``fa_int``, as in :mod:`inerter.engine.kernels`.
FORCE_CODE = {"constant": 0, "sine": 1, "step": 2}


def element_row(e, me, pidx, centripetal, meet_limit) -> tuple[tuple, tuple]:
    """The ``el_int`` and ``el_real`` rows of translational element `e` of the scene (`me`: the
    mechanism's element of that name, whose free length every kind with one takes (a spring, any
    kind whose :attr:`~inerter.elements.base.ElementKind.free` is declared), else the scene's, and
    whose fixed direction an inerter under the small-displacement law takes; `meet_limit`: its
    column of :func:`meet_limits`)."""
    free = 0.0
    if elements.KINDS[e.type].free is not None:
        free = getattr(me, "free_length", None)
        if free is None:
            free = e.free_length
        if free is None:
            raise ValueError(f"{e.type} {e.name}: no free length on the compiled mechanism")
    row_int = [0] * layout.ELEMENT_INT_COLUMNS
    row_int[layout.KIND] = ELEMENT_KIND[e.type]
    row_int[layout.POINT_A] = pidx[e.point_a]
    row_int[layout.POINT_B] = pidx[e.point_b]
    row_real = [0.0] * layout.ELEMENT_REAL_COLUMNS
    row_real[layout.COEFFICIENT] = float(e.coefficient)
    row_real[layout.FREE_LENGTH] = float(free)
    row_real[layout.CENTRIPETAL] = 1.0 if centripetal else 0.0
    row_real[layout.MEET_LIMIT] = float(meet_limit)
    direction = getattr(me, "fixed_direction", None)
    if direction is not None:
        row_real[layout.CENTRIPETAL] = 0.0
        row_real[layout.FIXED_DIRECTION] = 1.0
        row_real[layout.DIRECTION:layout.DIRECTION + len(direction)] = [float(x) for x in direction]
    if getattr(e, "device", None) is not None:
        for column, value in e.device.columns().items():          # DEVICE ... FLUID_QUADRATIC, SERIES ... LOSS
            row_real[column] = float(value)
        row = getattr(me, "row", None)
        if row is not None:                                         # the scene's gravity, for its masses
            row_real[layout.DEVICE_GRAVITY:layout.DEVICE_GRAVITY + 3] = [float(x) for x in
                                                                          row[layout.DEVICE_GRAVITY:layout.DEVICE_GRAVITY + 3]]
    if e.slider_axis is not None:                                 # a prismatic joint's spring or damper
        row_real[layout.SLIDER] = 1.0
        row_real[layout.DIRECTION:layout.DIRECTION + len(e.slider_axis)] = [float(x) for x in e.slider_axis]
    return tuple(row_int), tuple(row_real)


def rotational_row(e, body_a, body_b, free_angle, extra=()) -> tuple[tuple, tuple]:
    """The ``rot_int`` and ``rot_real`` rows of rotational element `e` (bodies as the kernels
    index them; `extra`: the 3D columns from AXIS on)."""
    row_int = [0] * layout.ROT_INT_COLUMNS
    row_int[layout.ROT_KIND] = ELEMENT_KIND[e.type]
    row_int[layout.BODY_A] = body_a
    row_int[layout.BODY_B] = body_b
    row_real = [float(e.coefficient), float(free_angle), *extra]
    assert layout.COEFFICIENT == 0 and layout.FREE_ANGLE == 1 and len(row_real) in (
        layout.ROT_REAL_COLUMNS_2D, layout.ROT_REAL_COLUMNS_3D)
    return tuple(row_int), tuple(row_real)


def adds_mass(row_int, row_real) -> bool:
    """Whether a translational element adds to the mass matrix (its law's inertance is not 0, read
    at L̇ = 0: a screw efficiency's b_eff is > 0 at every L̇; or its device has a kinetic block,
    inerter.elements.device_inertia): its bodies' coordinates are coupled in the sparsity pattern."""
    return (elements.MODULES[row_int[layout.KIND]].inertance.py_func(row_real, 0.0) != 0.0
            or row_real[layout.INERTIA] != 0.0)


def meet_limits(mech, specs) -> dict[str, float]:
    """Column MEET_LIMIT of ``el_real`` by translational element name: the distance below which
    its terminals meet (``Mechanism.meet_limit``), 0.0 for an element whose pair of terminals an
    earlier element shares (kernels.terminals_meet checks each pair once, as
    Mechanism.chord_margin does)."""
    seen, limits = set(), {}
    for e in specs:
        if not elements.translational(e.type):
            continue
        if e.slider_axis is not None:           # along a joint's axis: its L is the slide, it has no direction to lose
            limits[e.name] = 0.0
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
            fa_int.append((p, FORCE_CODE[f.function]))               # FORCE_POINT, FORCE_FUNCTION
            by_column = {layout.F_VALUE: f.value, layout.F_AMPLITUDE: f.amplitude, layout.F_FREQUENCY: f.frequency,
                         layout.F_PHASE: f.phase, layout.F_OFFSET: f.offset, layout.F_TIME: f.time,
                         layout.F_INITIAL: f.initial}
            fa_real.append((*d, *(by_column[c] for c in range(len(by_column)))))
        elif f.function == "pd":
            pd_int.append((p,))
            by_column = {layout.PD_KP: f.kp, layout.PD_KD: f.kd, layout.PD_REFERENCE: f.reference}
            pd_real.append((*d, *(by_column[c] for c in range(len(by_column)))))
        elif f.function == "input":
            in_int.append((p,))
    return fa_int, fa_real, pd_int, pd_real, in_int


def table_widths(dim: int) -> dict[str, int]:
    """The column count of each table the kernels run on, in a `dim`-D scene (layout's names): a
    point force's integer row holds its point and time function, its real row the direction's
    `dim` components and then the time function's numbers (F_*) or the PD law's (PD_*)."""
    planar = dim == 2
    return dict(el_int=layout.ELEMENT_INT_COLUMNS, el_real=layout.ELEMENT_REAL_COLUMNS,
                rot_int=layout.ROT_INT_COLUMNS,
                rot_real=layout.ROT_REAL_COLUMNS_2D if planar else layout.ROT_REAL_COLUMNS_3D,
                jt_int=layout.JOINT_INT_COLUMNS_2D if planar else layout.JOINT_INT_COLUMNS_3D,
                jt_real=layout.JOINT_REAL_COLUMNS_2D if planar else layout.JOINT_REAL_COLUMNS_3D,
                fa_int=layout.FORCE_FUNCTION + 1, fa_real=dim + layout.F_INITIAL + 1,
                pd_int=layout.FORCE_POINT + 1, pd_real=dim + layout.PD_REFERENCE + 1,
                in_int=layout.FORCE_POINT + 1)


def kernel_tables(dim: int, element_rows: dict, joint_rows: tuple, forces: tuple) -> dict:
    """The tables as the kernels take them, each a contiguous 2-D array of its width
    (:func:`table_widths`; int64 or float), an empty table (0, width): the elements' rows of
    :func:`element_tables`, the joints' (jt_int, jt_real) and the forces' :func:`force_rows`."""
    widths = table_widths(dim)
    rows = {**element_rows, **dict(zip(("jt_int", "jt_real"), joint_rows)),
            **dict(zip(("fa_int", "fa_real", "pd_int", "pd_real", "in_int"), forces))}
    return {name: np.ascontiguousarray(np.array(rows[name], dtype=np.int64 if name.endswith("_int") else float)
                                       .reshape(-1, widths[name]))
            for name in widths}


def element_tables(mech, pidx, rotational) -> dict:
    """The element tables of a mechanism: ``el_int``/``el_real`` rows of its translational elements
    and ``rot_int``/``rot_real`` rows of its rotational ones, with their names, in scene order, and
    ``el_extra``: each translational element's outputs beyond its family's (a device's), and
    ``n_internal``: the number of internal states z (y = [q, v, z]), each element's at its
    ``el_int[e, STATE]`` (:func:`internal_states`). ``rotational(spec, element)`` gives a
    rotational element's (body a, body b, free angle, extra columns) as the kernels of its
    dimension index them."""
    scene = mech.scene
    mech_elements = _by_name(getattr(mech, "elements", []))
    out = {key: [] for key in ("el_int", "el_real", "el_names", "el_extra", "rot_int", "rot_real", "rot_names")}
    limits = meet_limits(mech, scene.elements.values())
    offset = 0
    for e in scene.elements.values():
        me = mech_elements.get(e.name)
        if elements.translational(e.type):
            row_int, row_real = element_row(e, me, pidx, scene.centripetal, limits[e.name])
            count = len(internal_states(e))
            if count:
                row_int = list(row_int)
                row_int[layout.STATE], row_int[layout.STATES] = offset, count
                row_int = tuple(row_int)
                offset += count
            prefix = "el"
        else:
            row_int, row_real = rotational_row(e, *rotational(e, me))
            prefix = "rot"
        out[prefix + "_int"].append(row_int)
        out[prefix + "_real"].append(row_real)
        out[prefix + "_names"].append(e.name)
        if prefix == "el":
            out["el_extra"].append([suffix for suffix, _, _ in elements.outputs(e)[len(elements.FAMILY_OUTPUTS[elements.TRANSLATIONAL]):]])
    out["n_internal"] = offset
    return out


def internal_states(spec) -> tuple[tuple[str, str, str], ...]:
    """(name, unit, description) of the internal states of scene element `spec` (an inerter
    device's, :meth:`inerter.elements.device.Device.states`), in their order in z."""
    device = getattr(spec, "device", None)
    return device.states() if device is not None else ()



# ------------------------------------------------------------------------------------------------
# Between steps: what the tables take without a new model
# ------------------------------------------------------------------------------------------------
#: Fields of a point force that its table row holds as plain numbers the kernels read at every
#: evaluation (a step force's time and a sine's phase are not: they place discontinuities).
TUNABLE_FORCE_FIELDS = ("value", "amplitude", "frequency", "kp", "kd")
_FORCE_COLUMN = {"value": layout.F_VALUE, "amplitude": layout.F_AMPLITUDE, "frequency": layout.F_FREQUENCY}
_PD_COLUMN = {"kp": layout.PD_KP, "kd": layout.PD_KD}


#: Effect switches the running engine takes between steps: a column of every element's row.
TUNABLE_EFFECTS = ("effects.centripetal",)


def tunable_field(scene, path: str) -> bool:
    """Whether the scene field `path` (``elements.inerter.b``, ``forces.Fa.amplitude``) is a number
    the running engine can change between steps: an element's coefficient, a point force's value,
    amplitude, frequency or gains, the centripetal switch."""
    if path in TUNABLE_EFFECTS:
        return True
    parts = path.split(".")
    if len(parts) == 3 and parts[0] == "elements" and parts[2] == "device" and parts[1] in scene.elements:
        return True                          # an inerter device's numbers: its columns (layout)
    if len(parts) != 3:
        return False
    section, name, key = parts
    if section == "elements" and name in scene.elements:
        return key == elements.KINDS[scene.elements[name].type].coefficient.key
    if section == "forces" and name in scene.forces:
        return key in TUNABLE_FORCE_FIELDS
    return False


def untunable_changes(old, new) -> list[str]:
    """The fields in which scene `new` (the file of `old` read with other parameter values)
    differs from `old` that the running engine cannot take between steps: they need a new model."""
    return [path for path in differences(old, new) if not tunable_field(old, path)]


def check_retune(old, new) -> None:
    """Raise ValueError unless scene `new` differs from `old` only in tunable fields."""
    fixed = untunable_changes(old, new)
    if fixed:
        raise ValueError(f"it would change {', '.join(fixed)}, which the running model cannot take "
                         f"between steps (only element coefficients, point-force values, amplitudes, "
                         f"frequencies and gains, and the centripetal switch can change)")


def coupled_elements(flat) -> list[bool]:
    """Whether each translational element of `flat` couples its bodies in the mass matrix (its
    inertance is not 0): the band the kernels solve in is laid out for these."""
    return [adds_mass(row_int, row_real) for row_int, row_real in zip(flat["el_int"], flat["el_real"])]


def retune_rows(flat, scene, coupled) -> list[str]:
    """Write the tunable numbers of `scene` (the running scene read with other parameter values)
    into the tables `flat` in place: element coefficients, point-force values, amplitudes,
    frequencies and PD gains. `coupled`: :func:`coupled_elements` of the tables the band was laid
    out for. Returns the elements that would need a coupling the band lacks (an inertance that was
    0 there): nothing is written then."""
    lacking = [name for i, name in enumerate(flat["el_names"])
               if not coupled[i] and adds_mass(flat["el_int"][i], _with_coefficient(
                   flat["el_real"][i], scene.elements[name].coefficient))]
    if lacking:
        return lacking
    for i, name in enumerate(flat["el_names"]):
        flat["el_real"][i, layout.COEFFICIENT] = scene.elements[name].coefficient
        if flat["el_real"][i, layout.FIXED_DIRECTION] == 0.0:       # the small-displacement law has none
            flat["el_real"][i, layout.CENTRIPETAL] = 1.0 if scene.centripetal else 0.0
        device = getattr(scene.elements[name], "device", None)
        if device is not None:
            for column, value in device.columns().items():          # DEVICE ... FLUID_QUADRATIC, SERIES ... LOSS
                flat["el_real"][i, column] = float(value)
    for i, name in enumerate(flat["rot_names"]):
        flat["rot_real"][i, layout.COEFFICIENT] = scene.elements[name].coefficient
    dim = flat["dim"]
    pidx = {name: i for i, name in enumerate(flat["point_names"])}
    _, fa_real, _, pd_real, _ = force_rows(scene, pidx, dim)
    for table, rows, columns in (("fa_real", fa_real, _FORCE_COLUMN), ("pd_real", pd_real, _PD_COLUMN)):
        for i, row in enumerate(rows):
            for column in columns.values():
                flat[table][i, dim + column] = row[dim + column]
    return []


def _with_coefficient(row_real, value):
    row = list(row_real)
    row[layout.COEFFICIENT] = float(value)
    return row
