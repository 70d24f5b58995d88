"""The compiled fast path: Eq. (33) and the explicit integrators in numba-compiled kernels.

    from inerter.engine.compiled import compile_mechanism, integrate_compiled
    kernel = compile_mechanism(model.mechanism)
    qdd, lam = kernel.accelerations(t, q, v, inputs, alpha)      # = Mechanism.accelerations
    run = integrate_compiled(model.mechanism, model.settings())   # an inerter.engine.simulation.Run

A :class:`~inerter.model.mechanism.Mechanism` is flattened once into arrays (bodies' masses and, in 3D,
inertia tensors; points as body index and body-frame coordinates; joints; translational elements
with coefficient, free length and centripetal flag; rotational elements; point forces with their
time functions; gravity and the ground motion when declared): :func:`flatten` for 2D scenes,
:func:`inerter.engine.compiled_spatial.flatten3` for 3D scenes (quaternions or Z-X-Z Euler angles, whose
singularity the loops watch as the numpy path does). The kernels in
:mod:`inerter.engine.kernels` evaluate the mass matrix with M_I, the constraint Jacobian, γ, the
forces and Q_Iv from these arrays (the same formulas as ``elements.py``, ``joints.py``,
``planar.py``, ``spatial.py``) and solve the augmented system with a band LU with partial
pivoting after a reverse Cuthill-McKee ordering, so a chain's cost grows linearly with its length.
The state is y = [q, v, z] with q̇ = B(q) v (the identity in 2D, the orientations' rates in 3D)
and z the elements' internal states (an inerter device's series deflection, its dissipated energy:
:mod:`inerter.elements.device`), each element's slice at ``el_int[e, STATE]``; z is empty, and
never evaluated, where the scene declares none.

Integrators: DOP853 and RK45 with scipy's error control, step-size rule and dense output (the
same steps as the numpy path at the same tolerances), and RK4 with a fixed step, each in one
compiled loop that writes the samples at the output grid, restarted at each jump of the
right-hand side (a step force's switch; ``Mechanism.discontinuities``) and running on through its
kinks (a ground record's samples, ``Mechanism.kinks``), each step that would cross one clipped to
end on it (``kernels.rk_advance``); on request the loop keeps
every step's dense output (:class:`DenseOutput`, the metrics' interpolant). Radau, BDF and LSODA,
and the ``projection`` constraint treatment, run scipy's integrators
(``inerter.engine.simulation.integrate``) on the compiled right-hand side.

This is the default path (``Model.simulate``, ``Model.stepper``); numba is a dependency of the
package. Where it cannot be imported, :data:`AVAILABLE` is False, :func:`compile_mechanism`
returns a kernel that calls the numpy path and :func:`integrate_compiled` runs
:func:`inerter.engine.simulation.integrate`, saying so in ``run.extra["path"]``.
"""
from __future__ import annotations

import copy
from collections import namedtuple
import functools
import hashlib
import math
import importlib.util
import os
import pickle
import sys
import threading
import time as _time
from pathlib import Path

import numpy as np

from inerter.common.atomic import replace_file
from inerter.common.errors import SimulationError
from inerter.engine import ahead
from inerter.engine.simulation import (Run, Stepper, energy_watched, jumps, load_state, monitor_slots, output_grid,
                                       restart_lowest_energy)
from inerter.scene.ground_motion import TERM_AMPLITUDE, TERM_COLUMNS
from inerter.common.rotations import EULER_SEQUENCES
from inerter.elements import FORCE_OUTPUTS, ROTATIONAL, TRANSLATIONAL, device, layout, output_suffixes
from inerter.engine.tables import _by_name, adds_mass, element_tables, force_rows, kernel_tables
from inerter.engine.compiled_spatial import flatten3, joint_row_counts, signal_layout3
from inerter.model.mechanism import wound_from



def cache_root() -> Path:
    """Where the kernels' source is copied for numba's on-disk cache: ``$INERTER_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/inerter``, else ``~/.cache/inerter``."""
    if os.environ.get("INERTER_CACHE_DIR"):
        return Path(os.environ["INERTER_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "inerter"


def kernel_sources() -> list[Path]:
    """The files whose code the kernels compile: :mod:`inerter.engine.kernels`, the element kinds'
    laws and their dispatch (:mod:`inerter.elements`), the shared constants and orientation kinematics."""
    package = Path(__file__).resolve().parents[1]
    return ([Path(__file__).with_name("kernels.py"), package / "common" / "errors.py", package / "common" / "inlined.py",
             package / "common" / "rotations.py", package / "scene" / "ground_motion.py"]
            + sorted((package / "elements").glob("*.py")))


def _import_kernels():
    """Import :mod:`inerter.engine.kernels` from a per-user copy named by the hash of its source.

    numba keys its on-disk cache by the source file's path and time stamp. An FMU importer extracts
    the FMU, and with it this package, into a new temporary folder each time, so a cache next to
    the shipped source would never be found again and every run would pay the compilation (about
    6 s). The copy lives at a path that depends only on the source's content, and is written once,
    so every process (solver runs, sweep workers, each instance of every FMU built from this
    source) loads the kernels compiled by the first. When the cache folder cannot be written,
    the package's own module is imported (numba then caches next to it, where it can).

    The hash covers every source the kernels compile in (:func:`kernel_sources`): the element
    laws they inline too, since numba's cache does not notice a change in a called function."""
    text = Path(__file__).with_name("kernels.py").read_bytes()
    h = hashlib.sha256()
    for path in kernel_sources():
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    digest = h.hexdigest()[:16]
    name = f"inerter_kernels_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    try:
        folder = cache_root() / "kernels" / digest
        target = folder / f"{name}.py"
        wrote = not (target.is_file() and target.read_bytes() == text)
        if wrote:
            folder.mkdir(parents=True, exist_ok=True)
            replace_file(target, lambda part: part.write_bytes(text))   # concurrent processes see a whole file
    except OSError:
        from inerter.engine import kernels as compiled_kernels
        return compiled_kernels
    _write_bytecode(target, wrote)
    spec = importlib.util.spec_from_file_location(name, target)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _write_bytecode(source: Path, fresh: bool):
    """The bytecode of the kernels' copy `source` next to it, once (again where the copy was just
    written: `fresh`), even where the import system writes none (``PYTHONDONTWRITEBYTECODE``, set
    in many containers): compiling its source costs every process about 0.03 s. Where it cannot be
    written, the source is compiled at each import, as before."""
    if not fresh and Path(importlib.util.cache_from_source(str(source))).is_file():
        return
    import py_compile
    try:
        py_compile.compile(str(source), doraise=True)        # written atomically, as the import system does
    except (OSError, py_compile.PyCompileError):
        pass


# ------------------------------------------------------------------------------------------------
# First use: saying so while the kernels compile
# ------------------------------------------------------------------------------------------------
#: Seconds a run's first compilation of the kernels takes on a 2-core machine, by dimension (its
#: integrator loop; then its outputs, about 50 s 2D and 80 s 3D), for the notice: measured
#: 2026-11-27 (docs/benchmarks/first_use.md), 225 s and 257 s.
COMPILE_SECONDS = {2: 230, 3: 260}
#: Seconds ``inerter compile`` takes on a 2-core machine with an empty cache, by dimension (every kernel:
#: the three integrator loops, outputs, co-simulation steps and the FMU's native step), the two
#: dimensions in parallel (api.warm_up), for the notice: measured 2026-11-27 as a pair of
#: processes (benchmarks/compile_profile.py), 432 s (2D) and 590 s (3D) after the outputs' code was
#: compiled once for samples and dense output (docs/benchmarks/first_use.md).
AOT_SECONDS = {2: 430, 3: 590}
#: The kernels entered from Python, in the notice's words (others by their own name).
_WHAT = {"integrate_rk": "the DOP853/RK45 loop", "integrate_rk4": "the RK4 loop",
         "signal_history": "the outputs", "signal_column": "the outputs", "dense_signal": "the outputs",
         "dense_rows": "the dense output",
         "signal_values": "the outputs", "max_residual": "the constraint residual",
         "cosim_step": "the co-simulation step", "rk4_cosim_step": "the RK4 co-simulation step",
         "native_step": "the FMU's native step", "native_step3": "the FMU's native step"}


class CompileNotice:
    """Says on stderr while the kernels compile, so that a first run does not look hung.

    numba's ``numba:compile`` event fires only where a kernel is not found in the on-disk cache
    (:func:`_import_kernels`), so a warm process says nothing and pays nothing. Per outermost
    compilation of a kernel (the kernels it calls compile inside it): the first one of a dimension
    in the process is announced at once, with what the dimension's first compilation takes
    (:data:`COMPILE_SECONDS`); any other is announced once it has taken 2 s. An announced one says
    "done" with its time. ``enabled = False`` silences it (``inerter compile`` says it once).
    ``eager = True`` announces every one at once, on the compiling thread: an FMU sets it while its
    stream is the importer's logger, which it may call from that thread only."""

    LATE = 2.0

    def __init__(self, stream=None):
        self.enabled = True
        self.eager = False                  # announce every compilation at its start (no timer)
        self.stream = stream                # None: sys.stderr at the time of writing
        self.seconds = 0.0                  # time spent in outermost compilations of the kernels
        self._depth = 0
        self._announced = set()             # dimensions announced in this process
        self._lock = threading.Lock()
        self._timer = None
        self._start = 0.0
        self._loud = False

    def _say(self, text):
        stream = self.stream or sys.stderr
        print(f"inerter: {text}", file=stream, flush=True)

    @staticmethod
    def _ours(dispatcher) -> bool:
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        return module.startswith("inerter")       # the kernels, their copy (inerter_kernels_<hash>)

    @staticmethod
    def dimension(args) -> int | None:
        """2 or 3 from the type of a kernel's P among `args` (numba types), None without one."""
        from numba.core import types
        for a in args:
            if (isinstance(a, types.BaseTuple) and len(a) >= len(_k.PARAMS)
                    and all(isinstance(x, types.Array) for x in a)):
                return 3 if _k.is_spatial(a) else 2
        return None

    def on_start(self, event):
        self._depth += 1
        if self._depth > 1 or not self._ours(event.data["dispatcher"]):
            return
        self._start = _time.perf_counter()
        self._loud = False
        if not self.enabled:
            return
        dim = self.dimension(event.data["args"])
        name = event.data["dispatcher"].py_func.__name__
        if dim is not None and dim not in self._announced:
            self._announced.add(dim)
            self._loud = True
            self._say(f"compiling the engine's {dim}D kernels for this machine (once; about "
                      f"{COMPILE_SECONDS[dim]} s on 2 cores, later runs load them from the cache)...")
        elif self.eager:
            label = f"{dim}D kernels" if dim else "kernels"
            self._loud = True
            self._say(f"compiling the engine's {label}: {_WHAT.get(name, name)} (once for this machine)...")
        else:
            label = f"{dim}D kernels" if dim else "kernels"
            self._timer = threading.Timer(self.LATE, self._late, (f"{label}: {_WHAT.get(name, name)}",))
            self._timer.daemon = True
            self._timer.start()

    def _late(self, what):
        with self._lock:
            if threading.current_thread() is not self._timer:      # that compilation has ended
                return
            self._loud = True
            self._say(f"compiling the engine's {what} (once for this machine)...")

    def on_end(self, event):
        self._depth -= 1
        if self._depth or not self._ours(event.data["dispatcher"]):
            return
        seconds = _time.perf_counter() - self._start
        self.seconds += seconds
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
            if self._loud:
                self._say(f"... done in {seconds:.0f} s")
            self._loud = False


#: The process's notice (None without numba).
NOTICE = None


def _install_notice():
    global NOTICE
    from numba.core import event

    class _Listener(CompileNotice, event.Listener):
        pass

    NOTICE = _Listener()
    event.register("numba:compile", NOTICE)


def _blas_check_without_scipy_linalg():
    """Let numba learn that scipy provides BLAS without importing scipy.linalg whole.

    The first kernel a process loads from the cache makes numba load its implementation registries,
    among them ``numba.np.arraymath``, whose import calls ``numba.np.linalg.ensure_blas()``:
    ``import scipy.linalg.cython_blas``, which runs ``scipy/linalg/__init__.py`` and with it
    ``scipy._lib._array_api`` (scipy 1.17 clones the numpy namespace there, importing
    ``numpy.f2py``, ``numpy.ma`` and ``numpy.testing``): 0.2 s of a warm process's first second
    (docs/benchmarks/first_use.md), for a flag that only selects how ``np.dot`` is compiled (the
    kernels call no BLAS routine). Here arraymath is
    imported with the same question answered from the files: scipy's ``linalg/cython_blas``
    extension module is there and built for numba's LAPACK integer width (numba's own check,
    ``_check_lapack_int_width``). Any later BLAS use (typing ``np.dot``, calling it) imports
    scipy.linalg as numba always does. Where numba lacks what this relies on, or has already
    loaded arraymath, nothing is changed."""
    if "numba.np.arraymath" in sys.modules or "scipy.linalg" in sys.modules:
        return
    from importlib.machinery import EXTENSION_SUFFIXES
    try:
        from numba.np import linalg
        original, width = linalg.ensure_blas, linalg._check_lapack_int_width
    except (ImportError, AttributeError):                   # pragma: no cover  (another numba)
        return

    def ensure_blas():
        spec = importlib.util.find_spec("scipy")            # the package's location, not imported
        folder = Path(spec.origin).parent / "linalg" if spec is not None and spec.origin else None
        if folder is None or not any((folder / f"cython_blas{s}").is_file() for s in EXTENSION_SUFFIXES):
            raise ImportError("scipy 0.16+ is required for linear algebra")    # numba's words
        width()

    linalg.ensure_blas = ensure_blas
    try:
        from numba.np import arraymath
        arraymath.ensure_blas = original
    finally:
        linalg.ensure_blas = original


try:
    import numba  # noqa: F401
    _blas_check_without_scipy_linalg()
    _k = _import_kernels()
    #: The kernels a run enters from Python, through their builds ahead of time where this machine
    #: has them (:mod:`inerter.engine.ahead`), else numba's dispatchers.
    ENTRIES = ahead.Entries(_k)
    AVAILABLE = True
    WHY_NOT = ""
    _install_notice()
except ImportError as exc:          # numba missing (or unusable): the numpy path is used
    _k = ENTRIES = None
    AVAILABLE = False
    WHY_NOT = f"numba is not available ({exc}); the numpy path is used"

#: Methods integrated in one compiled loop; the others run scipy's integrators on the kernel.
COMPILED_METHODS = ("DOP853", "RK45", "RK4")
_RK_CODE = {"DOP853": 0, "RK45": 1}
_NO_ORDER = np.zeros(0, dtype=np.int64)

#: The statuses of an evaluation at a state where the accelerations cannot be evaluated (a singular
#: or non-finite solve, terminals that meet): raised inside a trial step, a shorter step may avoid
#: them (``simulation._step``), as the numpy path's.
_STATE_FAILURES = (_k.SINGULAR, _k.NOT_FINITE, _k.TERMINALS_MEET)

_STATUS_TEXT = {
    _k.MAX_STEPS: "more than max_steps integrator steps: the scene may be stiff; try method = \"Radau\" or \"BDF\"",
    _k.STEP_TOO_SMALL: "the step size became too small (below 10 ulp of t)",
    _k.SINGULAR: "the mass matrix M + M_I with the joint constraints is singular: some coordinate has no mass "
       "(check zero masses/inertias and the inerters)",
    _k.NOT_FINITE: "accelerations are not finite (the system matrix is near-singular or a force is unbounded)",
    _k.TERMINALS_MEET: "the terminals of a translational element meet: its direction is undefined",
    _k.STIFF: "the scene is stiff for {method}: its step size ({h:.3g} s) is held at the method's stability limit "
       "(Hairer's test fired in {hits} steps in a row); use method = \"Radau\" or \"BDF\" (implicit)",
    _k.COLLAPSED: "the {method} step size collapsed ({steps} steps in a row below {relative:g}·max(1 s, t), the last "
       "{h:.3g} s): the solution is approaching a singularity",
    _k.GIMBAL_LOCK: "a body's Z-X-Z Euler angles reach their singularity (gimbal lock): the angle rates are undefined; "
       "use orientation = \"quaternion\" (the default)",
    _k.CHANGE_POINT: "a step reaches a pose where the joints' constraint rows lose rank",
    _k.MEETING: "the terminals of a translational element meet: its direction is undefined",
}



# ------------------------------------------------------------------------------------------------
# Flattening a compiled mechanism into arrays
# ------------------------------------------------------------------------------------------------
def _joint_rows2(mech, pidx, angle_index, q0):
    """The ``jt_int`` and ``jt_real`` rows of a 2D scene's joints (columns named in
    :mod:`inerter.elements.layout`; `angle_index(body)`: the index of its angle in q, −1 for the
    ground): a prismatic joint's φ0, ratio and initial advance from the mechanism's joint."""
    scene = mech.scene
    mech_joints = _by_name(getattr(mech, "joints", []))
    jt_int, jt_real = [], []
    for j in scene.joints.values():
        row_int = [0] * layout.JOINT_INT_COLUMNS_2D
        row_real = [0.0] * layout.JOINT_REAL_COLUMNS_2D            # a revolute joint's: all 0.0
        row_int[layout.POINT_A] = pidx[j.point_a]
        row_int[layout.POINT_B] = pidx[j.point_b]
        if j.type == "revolute":
            row_int[layout.JOINT_KIND] = _k_code("REVOLUTE")
        else:
            row_int[layout.JOINT_KIND] = _k_code("PRISMATIC")      # a 2D screw: a prismatic joint that turns
            axis = j.axis
            ia, ib = angle_index(scene.points[j.point_a].body), angle_index(scene.points[j.point_b].body)
            mj = mech_joints.get(j.name)
            phi0 = getattr(mj, "phi0", None)
            if phi0 is None:
                phi0 = (q0[ib] if ib >= 0 else 0.0) - (q0[ia] if ia >= 0 else 0.0)
            row_real[layout.PRISMATIC_NORMAL] = -float(axis[1])    # the axis turned by +90°
            row_real[layout.PRISMATIC_NORMAL + 1] = float(axis[0])
            row_real[layout.PRISMATIC_PHI0] = float(phi0)
            row_real[layout.PRISMATIC_RATIO] = float(getattr(mj, "ratio", 0.0))
            row_real[layout.PRISMATIC_ADVANCE0] = float(getattr(mj, "advance0", 0.0))
        jt_int.append(tuple(row_int))
        jt_real.append(tuple(row_real))
    return jt_int, jt_real


def flatten(mech) -> dict:
    """The arrays the kernels run on, from a 2D mechanism and its scene (index maps in
    ``mech.scene`` order: bodies, points, joints, elements, forces)."""
    scene = mech.scene
    if scene.dimension != 2:
        raise ValueError(f"the compiled path is planar; scene {scene.name!r} has dimension {scene.dimension}")
    body_names = list(scene.bodies)
    bidx = {name: i for i, name in enumerate(body_names)}
    n = 3 * len(body_names)
    point_names = list(scene.points)
    pidx = {name: i for i, name in enumerate(point_names)}
    pbody = np.array([bidx.get(p.body, -1) for p in scene.points.values()], dtype=np.int64)
    ploc = np.array([list(p.local)[:2] for p in scene.points.values()], dtype=float).reshape(-1, 2)
    mass = np.array([x for b in scene.bodies.values() for x in (b.mass, b.mass, b.inertia)], dtype=float)

    def angle_index(body):
        i = bidx.get(body, -1)
        return 3 * i + 2 if i >= 0 else -1

    q0 = np.asarray(mech.q0, dtype=float)
    jt_int, jt_real = _joint_rows2(mech, pidx, angle_index, q0)

    def rotational(e, me):          # bodies' angle indices; φ0 from the mechanism's element
        ia, ib = angle_index(e.body_a), angle_index(e.body_b)
        free = getattr(me, "free_angle", None)
        if free is None:
            free = e.free_length if e.free_length is not None else \
                (q0[ib] if ib >= 0 else 0.0) - (q0[ia] if ia >= 0 else 0.0)
        return ia, ib, free, ()

    tables = element_tables(mech, pidx, rotational)

    has_gravity = mech.gravity is not None          # m g on each body's R (Mechanism._effects)
    gravity = np.array(mech.gravity, dtype=float) if has_gravity else np.zeros(n)

    arrays = kernel_tables(2, tables, (jt_int, jt_real), force_rows(scene, pidx, 2))
    return dict(n=n, nq=n, dim=2, m=2 * len(jt_int), mass=mass, pbody=pbody, ploc=ploc, **arrays,
                gravity=gravity, has_gravity=bool(has_gravity),
                point_names=point_names, body_names=body_names, el_names=tables["el_names"],
                rot_names=tables["rot_names"], el_extra=tables["el_extra"], n_internal=tables["n_internal"])


def signal_layout(flat) -> list[str]:
    """The names of the values :func:`compiled_kernels.signal_values` writes, in its order."""
    if flat["dim"] == 3:
        return signal_layout3(flat)
    names = [f"{p}.{x}" for p in flat["point_names"] for x in ("r[1]", "r[2]", "v[1]", "v[2]")]
    names += [f"{e}.{x}" for e, extra in zip(flat["el_names"], flat["el_extra"])
              for x in (*output_suffixes(TRANSLATIONAL), *extra)]
    names += [f"{e}.{x}" for e in flat["rot_names"] for x in output_suffixes(ROTATIONAL)]
    return names + ["energy", "constraint_residual"]


def _k_code(name):
    return {"REVOLUTE": 0, "PRISMATIC": 1}[name]


def sparsity(flat) -> np.ndarray:
    """Structural pattern of the augmented matrix of Eq. (33) (boolean, (n + m)²): each body's
    block (m I and J: 3 velocity coordinates in 2D, 6 in 3D), the couplings of the two bodies of
    each element with an inertance (M_I), and each joint's rows against both bodies' coordinates."""
    n, m = flat["n"], flat["m"]
    width = 3 if flat["dim"] == 2 else 6
    S = np.zeros((n + m, n + m), dtype=bool)
    for i in range(0, n, width):
        S[i:i + width, i:i + width] = True
    pbody = flat["pbody"]

    def dofs(*points):
        return [d for p in points if pbody[p] >= 0 for d in range(width * pbody[p], width * (pbody[p] + 1))]

    for row_int, row_real in zip(flat["el_int"], flat["el_real"]):
        if adds_mass(row_int, row_real):
            d = dofs(row_int[layout.POINT_A], row_int[layout.POINT_B])
            S[np.ix_(d, d)] = True
    row = n
    for row_int, k in zip(flat["jt_int"], joint_row_counts(flat)):
        d = dofs(row_int[layout.POINT_A], row_int[layout.POINT_B])
        S[np.ix_(range(row, row + k), d)] = True
        S[np.ix_(d, range(row, row + k))] = True
        row += k
    return S


def reverse_cuthill_mckee(A):
    """Reverse Cuthill–McKee order of the symmetric sparsity pattern `A` (boolean, N×N): a
    breadth-first walk from a lowest-degree unknown of each connected part, neighbours by
    ascending degree, reversed (Cuthill & McKee 1969; George 1971). The mechanisms' patterns are
    small, and this avoids importing scipy.sparse (0.2 s) for them."""
    N = A.shape[0]
    neighbours = [np.flatnonzero(A[i]) for i in range(N)]
    degree = np.array([len(nb) for nb in neighbours])
    seen = np.zeros(N, dtype=bool)
    order = []
    for start in np.argsort(degree, kind="stable"):
        if seen[start]:
            continue
        seen[start] = True
        queue = [int(start)]
        while queue:
            i = queue.pop(0)
            order.append(i)
            fresh = [j for j in neighbours[i] if not seen[j]]
            for j in sorted(fresh, key=lambda j: degree[j]):
                seen[j] = True
                queue.append(int(j))
    return np.array(order[::-1], dtype=np.int64)


def ordering(S):
    """(perm, kl, ku): perm[i] = position of unknown i after a reverse Cuthill-McKee ordering
    (identity when that does not narrow the band), and the band widths."""
    N = S.shape[0]
    identity = np.arange(N)

    def widths(perm):
        i, j = np.nonzero(S)
        d = perm[i] - perm[j]
        return (int(max(d.max(), 0)), int(max(-d.min(), 0))) if len(d) else (0, 0)

    best = (identity, *widths(identity))
    order = reverse_cuthill_mckee(S | S.T)
    perm = np.empty(N, dtype=np.int64)
    perm[order] = np.arange(N)
    kl, ku = widths(perm)
    if kl + ku < best[1] + best[2]:
        best = (perm, kl, ku)
    perm, kl, ku = best
    return np.asarray(perm, dtype=np.int64), kl, ku


# ------------------------------------------------------------------------------------------------
# The kernel
# ------------------------------------------------------------------------------------------------
def ground_arrays(mech):
    """(mode, input offset, ground_t, ground_a, ground_terms) of the mechanism's ground motion for
    :func:`kernels.ground_acceleration`: a record's times and scaled values (one sample of zeros
    where there is none) and the analytic terms with scaled amplitudes."""
    g = getattr(mech, "ground_motion", None)
    no_terms = np.zeros((0, TERM_COLUMNS))
    if g is None:
        return _k.GROUND_NONE, 0, np.zeros(1), np.zeros((mech.dim, 1)), no_terms
    if g.input:
        return _k.GROUND_INPUT, mech.dim * len(mech.input_forces), np.zeros(1), np.full((1, 1), g.scale), no_terms
    times, values = g.record if g.record is not None else (np.zeros(1), np.zeros((mech.dim, 1)))
    terms = np.array(g.terms, dtype=float).reshape(-1, TERM_COLUMNS)
    terms[:, TERM_AMPLITUDE] *= g.scale
    return (_k.GROUND_PRESCRIBED, 0, np.ascontiguousarray(times, dtype=float),
            np.ascontiguousarray(g.scale * np.asarray(values, dtype=float).reshape(mech.dim, -1)),
            np.ascontiguousarray(terms))


#: The tables of a kernel that a run or a stepper writes (Kernel.for_run): the elements' rows (their
#: screw efficiencies' modes; a retune's coefficients, inerter.engine.tables.retune_rows), the
#: rotational elements' (the 3D ones' φ_ref; a retune's coefficients), the point forces' and the
#: actuators' (a retune's values).
_RUN_TABLES = ("el_real", "rot_real", "fa_real", "pd_real")


class Kernel:
    """Eq. (33) for one mechanism in compiled code: :meth:`accelerations` matches
    ``Mechanism.accelerations`` to round-off."""

    compiled = True

    def __init__(self, mech):
        self.mech = mech
        spatial = mech.scene.dimension == 3
        flat = flatten3(mech) if spatial else flatten(mech)
        self.flat = flat
        self.n, self.m, self.nq = flat["n"], flat["m"], flat["nq"]
        self.perm, self.kl, self.ku = ordering(sparsity(flat))
        mode, offset, ground_t, ground_a, ground_terms = ground_arrays(mech)
        euler_axes = EULER_SEQUENCES[mech.scene.euler_sequence]
        # the screw efficiencies whose modes each solve settles: the rigid ones (in series the mode is
        # a law of the state, device.series_drive, and needs no solve again)
        efficient = sum(1 for row in flat["el_real"] if device.mode_solved.py_func(row))
        dims = np.array([self.n, self.m, self.kl, self.ku, int(flat["has_gravity"]), flat["dim"], self.nq, mode,
                         offset, *euler_axes, efficient, 0, mech.closed_loops()], dtype=np.int64)
        self.params = (flat["mass"], flat["pbody"], flat["ploc"], flat["el_int"], flat["el_real"],
                       flat["rot_int"], flat["rot_real"], flat["jt_int"], flat["jt_real"], flat["fa_int"],
                       flat["fa_real"], flat["pd_int"], flat["pd_real"], flat["in_int"], flat["gravity"],
                       self.perm, dims, ground_t, ground_a, ground_terms) + ((np.ones(1, dtype=np.int64),) if spatial else ())
        self.spatial = spatial                # P has the slot `spatial`: the kernels compile its 3D code
        N = self.n + self.m
        # The kernel's own Python (py_func), one np.empty: calling the compiled one from here would
        # load its machine code from the cache, a few ms of a warm process's first result.
        self._AB = _k.band_storage.py_func(self.kl, self.ku, N)
        self._rhs = np.empty(N)
        self._gen = np.empty(self.n)
        self._no_inputs = np.zeros(0)
        self.q0 = np.asarray(mech.q0, dtype=float)
        self.v0 = np.asarray(mech.v0, dtype=float)
        self.nz = int(flat["n_internal"])
        self.z0 = np.zeros(self.nz)                # internal states start at zero (tables.internal_states)
        self.ny = self.nq + self.n + self.nz
        self.input_names = list(getattr(mech, "input_names", []))
        self._layout = self._signal_index = None     # signal_layout and its index, once asked for
        self._read_cache = {}

    def for_run(self) -> "Kernel":
        """A copy that owns the tables a run or a co-simulation stepper writes, at their values at
        t = 0: the elements' rows (their screw efficiencies' modes, +1; a retune's coefficients),
        the 3D rotational elements' (their φ_ref, 0), the point forces' and actuators' (a retune's
        values), the count of unsettled solves (0), and its work arrays. The layout and the rest
        of the tables are shared with this kernel, which no run changes, so that two runs or
        steppers of one model do not change each other's (Mechanism.for_run)."""
        run = copy.copy(self)
        run.flat = dict(self.flat)
        copies = {}
        for key in _RUN_TABLES:
            copies[id(self.flat[key])] = run.flat[key] = self.flat[key].copy()
        dims = self.params[_k.DIMS]
        copies[id(dims)] = dims.copy()
        run.params = tuple(copies.get(id(a), a) for a in self.params)
        run.params[_k.DIMS][_k.UNSETTLED] = 0
        el_real = run.params[_k.EL_REAL]
        for row in el_real:
            if device.mode_solved.py_func(row):
                row[layout.EFFICIENCY_MODE] = 1.0
        run.windings[:] = 0.0
        run._AB, run._rhs, run._gen = self._AB.copy(), np.empty_like(self._rhs), np.empty_like(self._gen)
        run._read_cache = dict(self._read_cache)
        return run

    @property
    def windings(self) -> np.ndarray:
        """The 3D rotational elements' φ_ref (layout.PHI_REF: each one's wound angle at the last
        accepted step, inerter.elements.winding), a view the kernels write; empty in 2D."""
        rot_real = self.params[_k.ROT_REAL]
        return rot_real[:, layout.PHI_REF] if self.spatial else rot_real.reshape(-1)[:0]     # 2D: none

    @windings.setter
    def windings(self, values):
        self.windings[:] = values             # into the table the kernels read

    def wound_from_start(self, start=None):
        """φ_ref at 0, its value at t = 0 (or at `start`), while a history is evaluated from there
        (kernels._signals_at winds on from each sample to the next; mechanism.wound_from)."""
        return wound_from(self, start)

    def windings_along(self, times, states, start=None) -> np.ndarray:
        """(rows × elements) each 3D rotational element's φ_ref once wound on to each row of
        `states` (at `times`) in turn, each as the end of a step from the row before, from `start`
        (default 0, the initial pose; kernels.windings_along)."""
        states = np.ascontiguousarray(states, dtype=float)
        out = np.empty((len(states), len(self.windings)))
        if len(states) and self.spatial:
            with self.wound_from_start(start):
                _k.windings_along(np.ascontiguousarray(times, dtype=float), states, self.params, out)
        return out

    def windings_between(self, times0, states0, windings0, times, states) -> np.ndarray:
        """(rows × elements) each 3D rotational element's angle at each row of `states` (at `times`)
        on the branch its integration followed, from the row of `states0` (at `times0`, an end of the
        step that gives the time) where the integrator held `windings0` (kernels.windings_between)."""
        out = np.empty((len(states), len(self.windings)))
        if len(states) and self.spatial:
            f = functools.partial(np.ascontiguousarray, dtype=float)
            with self.wound_from_start():
                _k.windings_between(f(times0), f(states0), f(windings0), f(times), f(states), self.params, out)
        return out

    @property
    def unsettled(self) -> int:
        """How many evaluations of Eq. (33) kept a solve whose screw efficiencies' modes did not
        settle in device.MODE_SOLVES solves (kernels.accelerations; 0 without efficiencies)."""
        return int(self.params[_k.DIMS][_k.UNSETTLED])

    @property
    def band(self):
        """(kl, ku, N): the band of the augmented matrix after ordering."""
        return self.kl, self.ku, self.n + self.m

    def _inputs(self, inputs):
        if inputs is None or not len(self.input_names):
            return self._no_inputs
        return np.ascontiguousarray(inputs, dtype=float)

    def split(self, y):
        """(q, v, z) of a state y = [q, v, z], contiguous float arrays."""
        y = np.ascontiguousarray(y, dtype=float)
        nv = self.nq + self.n
        return y[:self.nq], y[self.nq:nv], y[nv:]

    def accelerations(self, t, q, v, inputs=None, alpha=0.0, z=None):
        """(q̈, λ) of Eq. (33) with Baumgarte stabilisation α, as ``Mechanism.accelerations``; `z`:
        the internal states (default: their initial values, zero)."""
        out = np.empty(self.n + self.m)
        z = self.z0 if z is None else np.ascontiguousarray(z, dtype=float)
        st = _k.accelerations(float(t), np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float),
                              z, self._inputs(inputs), float(alpha), self.params, self._AB, self._rhs, self._gen, out)
        if st:
            raise SimulationError(_STATUS_TEXT[st], t)
        return out[:self.n], out[self.n:]

    def derivative(self, inputs=None, alpha=0.0, jump=None):
        """f(t, y) = [q̇, q̈, ż] for scipy's integrators; `jump`: as ``simulation.derivative``."""
        n, ny = self.n, self.ny
        inp = self._inputs(inputs)
        P, AB, rhs, gen = self.params, self._AB, self._rhs, self._gen
        rhs_fn = _k._rhs
        acc = np.empty(n + self.m)
        before = None if jump is None else float(np.nextafter(jump, -np.inf))

        def fun(t, y):
            if before is not None and t > before:
                t = before
            dy = np.empty(ny)
            st = rhs_fn(float(t), np.ascontiguousarray(y, dtype=float), inp, alpha, P, AB, rhs, gen, acc, dy)
            if st:
                raise SimulationError(_STATUS_TEXT[st], t, recoverable=st in _STATE_FAILURES)
            return dy
        return fun

    def constraint_residual(self, q) -> float:
        return float(_k.constraint_residual(np.ascontiguousarray(q, dtype=float), self.params)) if self.m else 0.0

    def signal_index(self, name) -> int | None:
        """The position of signal `name` in the kernel's signal layout (None: not one of them)."""
        if self._signal_index is None:
            self._layout = signal_layout(self.flat)
            self._signal_index = {n: i for i, n in enumerate(self._layout)}
        return self._signal_index.get(name)

    def _reads(self, index):
        """:meth:`signal_reads`, once per signal."""
        if index not in self._read_cache:
            self._read_cache[index] = self.signal_reads(index)
        return self._read_cache[index]

    def signal_reads(self, index):
        """(needs the accelerations, the state components it reads) of the signal at `index`: a
        point's coordinate reads its body's coordinates (and velocities, for a velocity); an
        element's force and power need q̈ where its law has an inertance, and a screw efficiency's mode and
        loss need it; any other signal reads the whole state."""
        flat = self.flat
        width = 2 * flat["dim"]
        ny = self.ny
        self.signal_index("")
        if self._is_point(index):
            b, c, d = int(flat["pbody"][index // width]), index % width, flat["dim"]
            if b < 0:
                return False, np.zeros(0, dtype=np.int64)
            # r[c] = R[c] + (A ū)[c] reads R[c] and the orientation (θ; the quaternion); ṙ[c] =
            # Ṙ[c] + (A (ω × ū))[c] reads Ṙ[c], the orientation and the angular velocity
            nvb = 3 if d == 2 else 6
            nqb = self.nq * nvb // self.n
            orientation = [nqb * b + j for j in range(d if d == 3 else 2, nqb)]
            if c < d:
                comps = [nqb * b + c] + orientation
            else:
                omega = [self.nq + nvb * b + j for j in range(d if d == 3 else 2, nvb)]
                comps = orientation + [self.nq + nvb * b + c - d] + omega
            return False, np.array(comps, dtype=np.int64)
        name = self._layout[index]
        need = False
        for e, (row_int, row_real) in enumerate(zip(flat["el_int"], flat["el_real"])):
            if name in [f"{flat['el_names'][e]}.{suffix}" for suffix in FORCE_OUTPUTS]:
                need = adds_mass(row_int, row_real)
            elif device.mode_solved.py_func(row_real) and name in (f"{flat['el_names'][e]}.p_loss",
                                                                   f"{flat['el_names'][e]}.mode"):
                need = True             # a rigid screw efficiency's mode and loss: those of the solved L̈
        return need, np.arange(ny, dtype=np.int64)

    def reads_windings(self, index) -> bool:
        """Whether the signal at `index` depends on the branch of the 3D rotational elements' angles
        (``windings``, kernels._hold_windings_of): not a point's coordinate, nor a translational
        element's output evaluated alone without the accelerations (which the elements' torques
        enter); any other signal where the scene has such elements."""
        if not len(self.windings):
            return False
        need, _ = self._reads(index)
        element, _ = self.element_slot(index)
        return not self._is_point(index) and (element < 0 or bool(need))

    def _is_point(self, index) -> bool:
        """Whether the signal at `index` of the layout is a point's coordinate (the layout's first
        2 × dim signals of each point, kernels._point_signal)."""
        return index < 2 * self.flat["dim"] * len(self.flat["point_names"])

    def element_slot(self, index) -> tuple[int, int]:
        """(translational element e, the position of the signal among e's outputs) of the signal at
        `index` of the layout, (-1, 0) for another signal: a column of it evaluates e's outputs alone
        (kernels.element_signals2/3)."""
        if "_slots" not in self.__dict__:
            self.signal_index("")
            family = output_suffixes(TRANSLATIONAL)
            self._slots = {}
            for e, (name, extra) in enumerate(zip(self.flat["el_names"], self.flat["el_extra"])):
                start = self._signal_index[f"{name}.{family[0]}"]
                self._slots.update({start + slot: (e, slot) for slot in range(len(family) + len(extra))})
        return self._slots.get(index, (-1, 0))

    def signal_column(self, index, times, states, inputs=None, alpha=0.0, windings=None):
        """(values, k): the signal at `index` at each sample of a history (rows [q, v, z]), up to the
        first sample k where it cannot be evaluated (k = len(times) when it can at all), with the
        values signal_history gives. `windings`: as signal_history's."""
        need, _ = self._reads(index)
        element, slot = self.element_slot(index)
        states = np.ascontiguousarray(states, dtype=float)
        out = np.empty(len(times))
        with self.wound_from_start():
            st, k = ENTRIES.signal_column(np.ascontiguousarray(times, dtype=float), states,
                                          np.arange(states.shape[1]), _windings_arg(windings),
                                          self._inputs(inputs), float(alpha), int(index), int(element), int(slot), need,
                                          self.params, np.empty(len(self._layout)), out)
        return out[:k], int(k)

    def dense_signal(self, sol, index, times, inputs=None, alpha=0.0, windings=None):
        """(values, k): the signal at `index` at `times` (in any order) on a dense output, up to the
        first time k where it cannot be evaluated: on a :class:`DenseOutput`, in one compiled call
        (:func:`~inerter.engine.kernels.dense_signal`: the state components the signal reads, block
        by block, then the signal as :meth:`signal_column` reads it at samples); another (scipy's
        OdeSolution) through its states. `windings`: the 3D rotational elements' angles at each
        time, as signal_history's; a :class:`DenseOutput` or :class:`LocalDense` gives its own
        where none are given and the signal reads them (each time's from the step that covers it:
        :meth:`DenseOutput.windings_at`; :meth:`reads_windings`)."""
        times = np.ascontiguousarray(times, dtype=float).reshape(-1)
        if isinstance(sol, LocalDense):
            return self._local_dense_signal(sol, index, times, inputs, alpha)
        if not isinstance(sol, DenseOutput):
            return self.signal_column(index, times, np.asarray(sol(times)).T, inputs, alpha, windings)
        if windings is None and self.reads_windings(index):
            windings = sol.windings_at(times)
        with self.wound_from_start():
            return self._dense_read(sol, index, inputs, alpha)(times, _windings_arg(windings))

    def dense_reader(self, sol, index, alpha=0.0):
        """:meth:`dense_signal` of the signal at `index` on `sol` without inputs, as a function of
        the times alone, or None where :meth:`dense_signal` must go through its own steps (a scene
        with 3D rotational elements, whose windings it holds; a dense output that is not a
        :class:`DenseOutput`): what the signal reads found once. A run's metrics read one signal's
        dense output some ten times, and the compiled call itself takes a few microseconds."""
        if not isinstance(sol, DenseOutput) or len(self.windings):
            return None
        read = self._dense_read(sol, index, None, alpha)
        return lambda times: read(np.ascontiguousarray(times, dtype=float).reshape(-1))

    def _dense_read(self, sol, index, inputs, alpha):
        """read(times, windings) → (values, k): :func:`~inerter.engine.kernels.dense_signal` of the
        signal at `index` on the :class:`DenseOutput` `sol`, with what the signal reads found once
        (:meth:`dense_signal`, :meth:`dense_reader`); `times` contiguous floats, `windings` the
        kernels' (_windings_arg)."""
        need, comps = self._reads(index)
        element, slot = self.element_slot(index)
        fixed = (self._inputs(inputs), float(alpha), int(index), int(element), int(slot), need, self.params)
        code, nodes, coeffs, count = sol.method_code, sol.nodes, sol.coeffs, sol.count
        layout = len(self._layout)

        def read(times, windings=_NO_WINDINGS):
            out = np.empty(len(times))
            st, k = ENTRIES.dense_signal(code, nodes, coeffs, count, times, comps, windings, *fixed,
                                         np.empty(layout), out)
            return out[:k], int(k)
        return read

    def _local_dense_signal(self, sol, index, times, inputs, alpha):
        """:meth:`dense_signal` on a :class:`LocalDense`, one sample interval after the other (each
        interval's steps wound on from the angles recorded with its first sample)."""
        out = np.empty(len(times))
        first_bad = len(times)
        for k, where, piece in sol.pieces(times):
            values, good = self.dense_signal(piece, index, times[where], inputs, alpha)
            out[where[:good]] = values
            if good < len(where):
                first_bad = min(first_bad, int(where[good]))
        return out[:first_bad], first_bad

    def signal_order(self, signals):
        """Indices taking the kernel's signal layout to the order of `signals.names` before the
        derived outputs (None when the two do not hold the same signals)."""
        layout = {name: i for i, name in enumerate(signal_layout(self.flat))}
        base = signals.names[:signals.base_count]          # the derived outputs come from these
        if sorted(layout) != sorted(base):
            return None
        return np.array([layout[name] for name in base], dtype=np.int64)

    def signal_values(self, signals, order, t, q, v, inputs=None, alpha=0.0, z=None) -> np.ndarray:
        """Every signal of `signals` at one state (as ``Signals.evaluate``), in compiled code; `z`:
        the internal states (default zero)."""
        q = np.ascontiguousarray(q, dtype=float)
        v = np.ascontiguousarray(v, dtype=float)
        z = self.z0 if z is None else np.ascontiguousarray(z, dtype=float)
        raw = np.empty(len(order))
        acc = np.zeros(self.n + self.m)
        if signals.needs_accelerations:
            st = _k.accelerations(float(t), q, v, z, self._inputs(inputs), float(alpha), self.params, self._AB,
                                  self._rhs, self._gen, acc)
            if st:
                return signals.evaluate(t, q, v, inputs, alpha, z=z)    # raises the numpy path's message
        if _k.signal_values(q, v, z, acc, self.params, raw):
            return signals.evaluate(t, q, v, inputs, alpha, z=z)
        return signals.complete(raw[order])

    def signal_history(self, signals, order, times, states, inputs=None, alpha=0.0, windings=None):
        """(values, k): every signal at each sample of a history, up to the first sample k where one
        cannot be evaluated (k = len(times) when all can). `windings` (samples × the 3D rotational
        elements): each sample's angles read wound from its row, the angles the integrator recorded
        there from the step that covers it (``run.extra["windings"]``), right however many turns
        lie between two samples; None: wound on from sample to sample from t = 0, right only while no element
        turns by half a turn between two of them."""
        states = np.ascontiguousarray(states, dtype=float)
        raw = np.empty((len(states), len(order)))
        with self.wound_from_start():
            st, k = ENTRIES.signal_history(np.ascontiguousarray(times, dtype=float), states, _windings_arg(windings),
                                           self._inputs(inputs), float(alpha), bool(signals.needs_accelerations),
                                           self.params, raw)
        return signals.complete(raw[:k][:, order]), int(k)

    def point_positions(self, states) -> dict:
        """Global positions (time × dimension) of every named point along a state history (rows
        [q, v, z]), from the kernels' point kinematics (r = R + A ū, Eq. 15)."""
        states = np.ascontiguousarray(np.atleast_2d(states), dtype=float)
        times = np.zeros(len(states))
        d = self.flat["dim"]
        self.signal_index("")
        out = {}
        for p, name in enumerate(self.flat["point_names"]):
            columns = [self.signal_column(2 * d * p + c, times, states)[0] for c in range(d)]
            out[name] = np.column_stack(columns)
        return out


#: `windings` for the kernels where none are recorded: each row winds on from the row before.
_NO_WINDINGS = np.zeros((0, 0))


def _windings_arg(windings) -> np.ndarray:
    """The kernels' `windings` (rows × elements, C-contiguous floats) of the Kernel's argument."""
    if windings is None or not np.size(windings):
        return _NO_WINDINGS
    return np.ascontiguousarray(windings, dtype=float)


class NumpyKernel:
    """The same interface on the numpy path (numba missing)."""

    compiled = False

    def __init__(self, mech):
        self.mech = mech
        self.n, self.m = mech.n, mech.m
        self.q0, self.v0 = mech.q0, mech.v0

    def accelerations(self, t, q, v, inputs=None, alpha=0.0):
        return self.mech.accelerations(t, q, v, inputs, alpha)

    def constraint_residual(self, q):
        return self.mech.constraint_residual(q)


def compile_mechanism(mech):
    """A :class:`Kernel` for a 2D mechanism (numba), or the numpy path where the kernels cannot take
    it (:func:`unsupported`)."""
    if unsupported(mech):
        return NumpyKernel(mech)
    return Kernel(mech)


class _KernelMechanism:
    """What :func:`inerter.engine.simulation.integrate` needs of a mechanism, backed by a kernel
    (scipy's implicit integrators and the projection treatment on the compiled right-hand side)."""

    def __init__(self, mech, kernel):
        self._mech, self._kernel = mech, kernel
        self.n, self.m = kernel.n, kernel.m
        self.q0, self.v0, self.z0 = kernel.q0, kernel.v0, kernel.z0
        self.input_names = kernel.input_names

    def for_run(self) -> "_KernelMechanism":
        """A copy that owns its run state: the mechanism's (Mechanism.for_run) and the kernel's
        (Kernel.for_run)."""
        return _KernelMechanism(self._mech.for_run(), self._kernel.for_run())

    def retuned(self, mech) -> "_KernelMechanism":
        """`mech` (the same scene read with other parameter values) on its own kernel, a copy
        owning its run state: a retuned stepper stays on the compiled right-hand side."""
        return kernel_mechanism(mech).for_run()

    @property
    def mechanism(self):
        """The mechanism the kernel was compiled for (the numpy path's evaluation of the same model)."""
        return self._mech

    @property
    def kernel(self):
        return self._kernel

    def state_derivative(self, inputs, alpha, jump=None):
        """f(t, y) on y = [q, v, z] from the kernels' right-hand side (``simulation.derivative``)."""
        return self._kernel.derivative(inputs, alpha, jump)

    def output_values(self, signals, t, y, inputs, alpha) -> list:
        """Every output of `signals` at the state y = [q, v, z], from the kernels (Stepper.output_values)."""
        kernel = self._kernel
        q, v, z = kernel.split(y)
        order = kernel.signal_order(signals)
        if order is None:
            return signals.evaluate(t, q, v, inputs, alpha, functools.partial(kernel.accelerations, z=z), z=z).tolist()
        return kernel.signal_values(signals, order, t, q, v, inputs, alpha, z).tolist()

    def accelerations(self, t, q, v, inputs=None, alpha=0.0):
        return self._kernel.accelerations(t, q, v, inputs, alpha)

    def constraint_residual(self, q):
        return self._kernel.constraint_residual(q)

    def wind(self, y, y_old=None, h=0.0):
        """``Mechanism.wind`` on the kernel's tables (kernels.wind; nothing to do in 2D)."""
        if self._kernel.spatial:
            y = np.ascontiguousarray(y, dtype=float)
            y_old = y if y_old is None else np.ascontiguousarray(y_old, dtype=float)
            _k.wind(y, y_old, float(h), self._kernel.params)

    def reset_windings(self):
        self._kernel.windings[:] = 0.0

    def angles_between(self, times0, states0, windings0, times, states):
        """``Mechanism.angles_between`` in the kernels (Kernel.windings_between)."""
        return self._kernel.windings_between(times0, states0, windings0, times, states)

    def wound_from_start(self, start=None):
        """``Mechanism.wound_from_start`` on the kernel's tables (Kernel.wound_from_start)."""
        return self._kernel.wound_from_start(start)

    @property
    def windings(self) -> np.ndarray:
        return self._kernel.windings.copy()

    @windings.setter
    def windings(self, values):
        self._kernel.windings[:] = values

    def project(self, q, v, *args, **kwargs):
        return self._mech.project(q, v, *args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._mech, name)


_RK_TABLES = {}


def _dop853_coefficients():
    """scipy's DOP853 tables (scipy/integrate/_ivp/dop853_coefficients.py, which needs only numpy),
    read from their file: importing them as a module imports scipy.integrate whole, 0.15 s of a
    fresh process's first result."""
    import importlib.util

    scipy_dir = Path(importlib.util.find_spec("scipy").origin).parent
    spec = importlib.util.spec_from_file_location(
        "inerter_dop853_coefficients", scipy_dir / "integrate" / "_ivp" / "dop853_coefficients.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


#: A running integration of kernels.rk_advance, its arrays in the order of kernels.RK_STATE: the
#: header (RK_T, RK_H, ...), the state y and its derivative f, the state at the step's start and the
#: step's dense-output coefficients.
Running = namedtuple("Running", [name for name, _ in _k.RK_STATE]) if _k is not None else None

#: Where the Runge-Kutta matrix A sits in a tableau (:func:`_tables`, in the order of kernels.TABLEAU).
_TABLEAU_A = [name for name, _ in _k.TABLEAU].index("A") if _k is not None else None


def _gaps_stale(scratch):
    """Mark the terminals' gaps of kernels.cosim_scratch as not those of the integration's state:
    the next step computes them at its start."""
    scratch[_k.SCRATCH_FRESH][0] = 0.0


def _tables(method):
    """The tableau of `method` as the kernels take it, a plain tuple in the order of
    kernels.TABLEAU: (A, B, C, E, E3, D, Pm), the Runge-Kutta matrix, weights and nodes, the error
    weights (E3: DOP853's third-order ones), DOP853's dense-output matrix D and RK45's interpolation
    matrix Pm (zeros where the method has none)."""
    if method not in _RK_TABLES:
        if method == "DOP853":
            d = _dop853_coefficients()
            _RK_TABLES[method] = (np.ascontiguousarray(d.A), np.ascontiguousarray(d.B), np.ascontiguousarray(d.C),
                                  np.ascontiguousarray(d.E5), np.ascontiguousarray(d.E3),
                                  np.ascontiguousarray(d.D), np.zeros((1, 1)))
        else:
            from scipy.integrate import RK45
            _RK_TABLES[method] = (np.ascontiguousarray(RK45.A, dtype=float), np.ascontiguousarray(RK45.B, dtype=float),
                                  np.ascontiguousarray(RK45.C, dtype=float), np.ascontiguousarray(RK45.E, dtype=float),
                                  np.zeros(1), np.zeros((1, 1)), np.ascontiguousarray(RK45.P, dtype=float))
    return _RK_TABLES[method]


def kernel_mechanism(mech):
    """`mech` for :func:`inerter.engine.simulation.integrate` and its Stepper, on the compiled
    right-hand side (its internal states included)."""
    return _KernelMechanism(mech, _kernel_for(mech))


def _kernel_for(mech):
    """The kernel compiled for the model's mechanism `mech` (once; a run's copy of it,
    ``Mechanism.for_run``, takes its model's). Runs and steppers work on its copies (Kernel.for_run)."""
    mech = getattr(mech, "model_mechanism", mech)
    cached = getattr(mech, "_compiled_kernel", None)
    if cached is not None and cached.mech is mech:
        return cached
    kernel = compile_mechanism(mech)
    try:
        mech._compiled_kernel = kernel
    except AttributeError:                                    # pragma: no cover
        pass
    return kernel


def _dense_keep(method, tables, ny, dense):
    """(nodes, coeffs, kept) of kernels.rk_advance, which appends every step's dense output there
    (grown there) where `dense` and the method has one (DOP853, RK45); else three empty arrays
    (kernels.no_keep, its Python, as band_storage's)."""
    if not dense or tables is None:
        return _k.no_keep.py_func(ny)
    _A, _B, _C, _E, _E3, _D, Pm = tables
    rows = 8 if method == "DOP853" else 1 + Pm.shape[1]
    room = 256
    kept = np.zeros(2, dtype=np.int64)
    kept[_k.KEPT_ON] = 1
    return np.empty(room + 1), np.empty((room, rows, ny)), kept


def _rk_segment(kernel, settings, tables, y, t0, t1, seg, seg_out, max_steps, inputs, switches, kinks, keep):
    """kernels.integrate_rk from (t0, y) to t1 with the run's method, tolerances and α, a fresh first
    step, through the `kinks`, ending before the jump at t1 where t1 is one of the `switches`;
    sampled at `seg`, steps kept in `keep`. Returns what integrate_rk returns."""
    A, B, C, E, E3, D, Pm = tables
    return ENTRIES.integrate_rk(_RK_CODE[settings.method], y, t0, t1, seg, seg_out, float(settings.rtol),
                                float(settings.atol), 0.0, max_steps, inputs, float(settings.alpha), kernel.params,
                                A, B, C, E, E3, D, Pm, monitor_slots(settings.method), t1 if t1 in switches else 0.0,
                                kinks, keep)


def _run_failure(kernel, settings, status, h, y_last, t_reached, t_sample, monitor=None) -> str:
    """The message of a whole run's compiled loop that stopped with `status` at `t_reached` (the last
    sample at `t_sample`; `h` its last step). Terminals meeting: the loop stopped at the meeting
    located within the step that brings them together (MEETING, `y_last` the state there), or at
    the last node before a step whose stage finds them meeting (TERMINALS_MEET)."""
    h = h if settings.method != "RK4" else settings.step
    meet = status in (_k.TERMINALS_MEET, _k.MEETING)
    why = failure_text(kernel, status, settings, h, y_last, t_reached if meet else t_sample,
                       int(settings.max_steps), monitor)
    digits = 9 if status == _k.MEETING else 6
    return f"at t = {t_reached:.{digits}g} s: the {settings.method} integrator failed: {why}"


#: The statuses whose message reads the state the loop stopped at (UNSTABLE, ENERGY_JUMP: at the
#: start of the step that stopped it; the linearisation's advice).
_STOPS_AT_ITS_STATE = (_k.CHANGE_POINT, _k.TERMINALS_MEET, _k.MEETING, _k.UNSTABLE, _k.ENERGY_JUMP)


def integrate_compiled(mech, settings, inputs=None, dense=False):
    """Integrate like :func:`inerter.engine.simulation.integrate`, in one compiled loop for DOP853, RK45
    and RK4 with Baumgarte stabilisation; other methods and ``projection`` use scipy's integrators
    on the compiled right-hand side (and their dense output).

    `dense`: keep the dense output of every accepted step of DOP853 and RK45 (scipy's polynomials,
    the same the samples are taken from), as ``Run.dense``, a :class:`DenseOutput`. Without it,
    ``Run.dense`` is a :class:`LocalDense`, which integrates again the sample intervals it is read
    in: what reads a few of them (a peak's refinement) does not make the whole run pay for a dense
    output at every step. With RK4 (fixed step), ``Run.dense`` is an :class:`RK4Dense`, which
    integrates again the sample intervals it is read in, as LocalDense does. The samples are the
    same either way."""
    from inerter.engine.simulation import integrate

    why = unsupported(mech)
    if why:
        run = integrate(mech, settings, inputs)
        run.extra["path"] = f"numpy ({why})"
        return run
    if settings.method not in COMPILED_METHODS or settings.constraint == "projection":
        run = integrate(_KernelMechanism(mech, _kernel_for(mech)), settings, inputs)   # on copies of both
        return _kernel_run(run, run.extra["mechanism"].kernel, "scipy integrator, compiled right-hand side")
    kernel = _kernel_for(mech).for_run()      # this run's tables: its φ_ref, modes and count are its own

    grid = output_grid(settings.stop_time, settings.output_interval)
    # each sample's row: its state, then the φ_ref of each 3D rotational element the integrator held
    # at the step that covers it (kernels._record_windings_of; 0 at t = 0), none without such elements
    ny = kernel.ny
    out = np.zeros((len(grid), ny + len(kernel.windings)))
    y0 = np.concatenate((kernel.q0, kernel.v0, kernel.z0))
    out[0, :ny] = y0
    inp = kernel._inputs(inputs)
    alpha = float(settings.alpha)
    # One integration per segment between jumps of the right-hand side: it restarts at each (a step
    # force's switch; Mechanism.discontinuities) with a fresh first step, the forces evaluated up to
    # it with their values over the segment, as the numpy path's does. Through the kinks (a ground
    # record's samples; Mechanism.kinks) it runs on, its steps clipped to end on each.
    stop = float(settings.stop_time)
    switches = {float(d) for d in jumps(mech, 0.0, stop, settings.method)}
    kinks = np.array(getattr(mech, "kinks", ()), dtype=float)
    ends = sorted(d for d in switches if d < stop) + [stop]
    steps = evals = 0
    h, t0, k, status, t_reached, stopped = 0.0, 0.0, 1, 0, 0.0, None
    tables = None if settings.method == "RK4" else _tables(settings.method)
    keep = _dense_keep(settings.method, tables, len(y0), dense)
    monitor = (monitor_slots("RK4", energy=energy_watched(mech)) if tables is None
               else None)                   # RK4's watches, across segments
    start = _time.process_time()
    y = y0                                    # the 3D rotational elements' angles: from the initial pose (for_run)
    for t1 in ends:
        last = int(np.searchsorted(grid, t1, side="right"))      # grid[k:last] lie in (t0, t1]
        seg = np.concatenate(([t0], grid[k:last]))
        if seg[-1] != t1:
            seg = np.append(seg, t1)
        seg_out = np.empty((len(seg), out.shape[1]))
        seg_out[0, :ny] = y
        seg_out[0, ny:] = kernel.windings
        if settings.method == "RK4":
            status, done, s_steps, s_evals, t_reached, y_reached = _k.integrate_rk4(
                y, t0, t1, seg, seg_out, float(settings.step), int(settings.max_steps) - steps, inp, alpha,
                kernel.params, t1 if t1 in switches else 0.0, kinks, monitor)
        else:
            status, done, s_steps, s_evals, t_reached, h, keep, y_reached = _rk_segment(
                kernel, settings, tables, y, t0, t1, seg, seg_out, int(settings.max_steps) - steps, inp, switches,
                kinks, keep)
        steps += int(s_steps)
        evals += int(s_evals)
        written = min(done - 1, last - k)                         # grid samples among seg_out[1:done]
        out[k:k + written] = seg_out[1:1 + written]
        k += written
        if status != 0:
            stopped = y_reached if status in _STOPS_AT_ITS_STATE else None
            break
        y, t0 = seg_out[-1, :ny].copy(), t1
    cpu = _time.process_time() - start
    states, windings = out[:k, :ny].copy(), out[:k, ny:].copy()
    if status == 0:
        message = "completed"
    else:
        message = _run_failure(kernel, settings, status, h, states[-1] if stopped is None else stopped,
                               t_reached, grid[k - 1], monitor)
    sol = DenseOutput.of_kept(settings.method, keep, kernel)
    if sol is None and tables is not None and k > 1:
        sol = LocalDense(kernel, settings, inp, grid[:k].copy(), states, switches, kinks, tables, windings)
    elif tables is None and k > 1:
        sol = RK4Dense(kernel, settings, inp, grid[:k].copy(), states, switches, kinks, windings)
    run = CompiledRun(grid[:k].copy(), states, sol, "ok" if status == 0 else "failed", message, int(steps),
                      int(evals), cpu, None)
    if windings.shape[1]:
        run.extra["windings"] = windings
    return _kernel_run(run, kernel, "compiled")


def _kernel_run(run, kernel, path):
    """`run`, its extra saying its path, its kernel and how many of its evaluations kept a solve
    whose screw efficiencies' modes did not settle (the count of the run's own kernel, which
    Kernel.for_run starts at 0)."""
    run.extra.update(path=path, kernel=kernel, unsettled=kernel.unsettled)
    return run


class CompiledRun(Run):
    """A :class:`~inerter.engine.simulation.Run` of the compiled loop, whose ``max_drift`` (the
    largest constraint residual over the samples) is computed when first read: a run whose caller
    never reads it does not pay for it."""

    @property
    def max_drift(self) -> float:
        if self._max_drift is None:
            kernel = self.extra["kernel"]
            self._max_drift = float(ENTRIES.max_residual(self.states, kernel.params)) if kernel.m else 0.0
        return self._max_drift

    @max_drift.setter
    def max_drift(self, value):
        self._max_drift = value


class DenseOutput:
    """The dense output of a compiled DOP853 or RK45 run (``Run.dense``): every accepted step's
    polynomial with scipy's formulas, kept by :func:`~inerter.engine.kernels.rk_advance` (steps of
    every segment between jumps, one after the other). ``sol(t)`` gives the states at t
    as scipy's ``OdeSolution`` does: shape (ny,) for a scalar t, (ny, len(t)) for an array,
    evaluated in compiled code (:func:`~inerter.engine.kernels.dense_rows`). ``sol.ts``: the
    nodes (the steps' ends). `kernel`, `start`: the kernel it was integrated on and its 3D rotational
    elements' φ_ref at the first step's start (None: 0, a whole run's), for :meth:`windings_at`."""

    def __init__(self, method_code, nodes, coeffs, count, kernel=None, start=None):
        self.method_code = int(method_code)          # 0 DOP853, 1 RK45 (kernels' codes)
        self.nodes, self.coeffs, self.count = nodes, coeffs, int(count)
        self.ts = nodes[:count + 1]
        self.t_min, self.t_max = float(self.ts[0]), float(self.ts[-1])
        self.n = coeffs.shape[2]
        self.kernel, self.start = kernel, start
        self._step_windings = None            # each step's φ_ref, once asked for

    @classmethod
    def of_kept(cls, method, keep, kernel, start=None):
        """The dense output of the steps kernels.rk_advance kept in `keep` (nodes, coeffs, kept) in a
        run of `method` on `kernel` (`start`: as the constructor's), or None where it kept none."""
        nodes, coeffs, kept = keep
        count = int(kept[_k.KEPT_COUNT])
        return cls(_RK_CODE[method], nodes, coeffs, count, kernel, start) if count > 0 else None

    def windings_at(self, times):
        """(len(times) × elements) each 3D rotational element's angle at each time on the branch the
        integration followed, however far the times lie from each other, from the φ_ref the
        integrator held in the step that gives the time (the step kernels._step_of takes;
        Kernel.windings_between); None without such elements. The steps' φ_ref are those of their
        starts, wound on from step to step as the integrator wound them (Kernel.windings_along)."""
        if self.kernel is None or not len(self.kernel.windings) or not self.count:
            return None
        if self._step_windings is None:
            self._step_windings = self.kernel.windings_along(self.nodes[:self.count], self.coeffs[:self.count, 0, :],
                                                             self.start)
        times = np.asarray(times, dtype=float).reshape(-1)
        step = np.clip(np.searchsorted(self.ts, times, side="left") - 1, 0, self.count - 1)
        return self.kernel.windings_between(self.nodes[step], self.coeffs[step, 0, :], self._step_windings[step],
                                            times, self.rows(times))

    def __call__(self, t):
        times = np.asarray(t, dtype=float)
        scalar = times.ndim == 0
        times = np.ascontiguousarray(times.reshape(-1))
        out = self.rows(times).T               # a view: (ny, len(t)), as OdeSolution's, without a copy
        return out[:, 0] if scalar else out

    def rows(self, times):
        """The states at `times` (a 1-D array), a row per time (C-contiguous floats), as the kernels
        read a history."""
        times = np.ascontiguousarray(times, dtype=float)
        out = np.empty((len(times), self.n))
        _k.dense_rows(self.method_code, self.nodes, self.coeffs, self.count, times, out)
        return out


def _by_interval(grid, times) -> list[tuple[int, np.ndarray]]:
    """[(sample index k, the indices of `times` in the sample interval [grid[k], grid[k + 1]])], for
    each interval holding one (a time before the first sample in the first, after the last in the
    last): where a dense output built interval by interval reads them."""
    t = np.asarray(times, dtype=float).reshape(-1)
    ks = np.clip(np.searchsorted(grid, t, side="right") - 1, 0, len(grid) - 2)
    return [(int(k), np.flatnonzero(ks == k)) for k in np.unique(ks)]


class LocalDense:
    """The dense output of a compiled DOP853 or RK45 run that kept none, built where it is read:
    each sample interval a time falls in is integrated again from the run's state at the sample
    before it (its 3D rotational elements' angles wound from the angles the run recorded there,
    `windings`: samples × elements, ``run.extra["windings"]``),
    with the run's method, tolerances, inputs and α, running on through the same kinks and
    restarting at the same jumps, and its steps' polynomials kept as a whole run's are (one
    :class:`DenseOutput` per interval). It agrees with the dense output the run would have kept to
    the run's tolerance (the same equations under the same error control, from states that agree
    at the samples), not bit for bit. ``sol(t)`` as :class:`DenseOutput`; ``sol.ts``: the samples."""

    def __init__(self, kernel, settings, inputs, grid, states, switches, kinks, tables, windings=None):
        self.kernel, self.settings, self.inputs, self.tables = kernel, settings, inputs, tables
        self.grid, self.states, self.switches, self.kinks = grid, states, switches, kinks
        self.ts = grid
        self.n = states.shape[1]
        self.intervals = {}                  # sample index k → DenseOutput over [grid[k], grid[k + 1]]
        #: The right-hand side's evaluations spent integrating intervals again.
        self.evaluations = 0
        self.recorded = windings if windings is not None and np.size(windings) else None

    def pieces(self, times):
        """[(sample index k, the indices of `times` in k's interval, its DenseOutput)], integrating
        the intervals not integrated yet."""
        out = []
        for k, where in _by_interval(self.grid, times):
            if k not in self.intervals:
                self.intervals[k] = self._integrate(k)
            out.append((k, where, self.intervals[k]))
        return out

    def windings(self, k):
        """The 3D rotational elements' angles recorded with sample k (None: none, 0 at its start)."""
        return None if self.recorded is None else self.recorded[k]

    def windings_at(self, times):
        """As :meth:`DenseOutput.windings_at`, each time's from the steps of its interval."""
        if self.recorded is None:
            return None
        times = np.asarray(times, dtype=float).reshape(-1)
        out = np.empty((len(times), self.recorded.shape[1]))
        for _, where, piece in self.pieces(times):
            out[where] = piece.windings_at(times[where])
        return out

    def _integrate(self, k):
        """The DenseOutput of the steps from sample k to sample k + 1."""
        s, kernel = self.settings, self.kernel
        t0, t_end = float(self.grid[k]), float(self.grid[k + 1])
        ends = sorted(d for d in self.switches if t0 < d < t_end) + [t_end]
        keep = _dense_keep(s.method, self.tables, self.n, True)
        y = self.states[k].copy()
        with kernel.wound_from_start(self.windings(k)):
            for t1 in ends:
                seg_out = np.empty((2, len(y)))
                seg_out[0] = y
                status, _, _, evals, _, _, keep, _ = _rk_segment(
                    kernel, s, self.tables, y, t0, t1, np.array((t0, t1)), seg_out, int(s.max_steps), self.inputs,
                    self.switches, self.kinks, keep)
                if status != 0:
                    raise SimulationError(f"the dense output between t = {t0:.6g} s and {t_end:.6g} s: the "
                                          f"{s.method} integrator failed on integrating that interval again "
                                          f"({failure_text(kernel, status, s, 0.0, y, t0)})", t0)
                self.evaluations += int(evals)
                y, t0 = seg_out[-1].copy(), t1
        return DenseOutput.of_kept(s.method, keep, kernel, self.windings(k))

    def __call__(self, t):
        times = np.asarray(t, dtype=float)
        flat = times.reshape(-1)
        out = np.empty((self.n, len(flat)))
        for _, where, sol in self.pieces(flat):
            out[:, where] = sol(flat[where])
        return out[:, 0] if times.ndim == 0 else out


#: The most numbers an :class:`RK4Dense` keeps of the sample intervals it integrated again (its
#: steps' states); past it the intervals read longest ago are dropped (integrated again if read).
RK4_DENSE_KEPT = 4_000_000


class RK4Dense:
    """The dense output of a compiled RK4 run: each sample interval a time falls in is integrated
    again from the run's state at the sample before it with the run's fixed step (the last step
    shortened to land on the next sample; the same kinks and jumps), and the times are read on
    its steps' cubic Hermite polynomials, as the numpy path's RK4 gives its dense output
    (:class:`inerter.engine.integrators.RK4`). Where the output interval is a multiple of the
    step the steps are the run's own; else they agree with them to the method's order.

    An interval is integrated once: its steps are kept (:class:`_RK4Steps`, each step's cubic by
    its values at four points) and read again for any time in it, up to :data:`RK4_DENSE_KEPT`
    numbers in all. A run with 3D rotational elements (`windings`: the angles the run recorded at
    its samples, ``run.extra["windings"]``) integrates an interval wound from the angles recorded
    at its first sample, as :class:`LocalDense` does, and reads each time's angles on the branch
    its step followed (:meth:`windings_at`). ``sol(t)``: the states (n × len(t)); ``sol.ts``: the
    samples."""

    def __init__(self, kernel, settings, inputs, grid, states, switches, kinks, windings=None):
        from collections import OrderedDict
        self.kernel, self.settings, self.inputs = kernel, settings, inputs
        self.grid, self.states, self.switches, self.kinks = grid, states, switches, kinks
        self.ts = grid
        self.n = states.shape[1]
        self.recorded = windings if windings is not None and np.size(windings) else None
        self.intervals = OrderedDict()       # sample index k → [_RK4Steps of each segment], last read last
        self.kept = 0                        # the numbers they hold
        #: How many sample intervals were integrated again, and the right-hand side's evaluations spent.
        self.integrations = 0
        self.evaluations = 0

    def pieces(self, times):
        """[(sample index k, the indices of `times` in k's interval, its segments' steps)],
        integrating the intervals not kept."""
        out = []
        for k, where in _by_interval(self.grid, times):
            if k in self.intervals:
                self.intervals.move_to_end(k)
            else:
                self.intervals[k] = self._integrate(k)
                self.kept += sum(steps.size for steps in self.intervals[k])
                while self.kept > RK4_DENSE_KEPT and len(self.intervals) > 1:
                    _, dropped = self.intervals.popitem(last=False)
                    self.kept -= sum(steps.size for steps in dropped)
            out.append((k, where, self.intervals[k]))
        return out

    def __call__(self, t):
        times = np.asarray(t, dtype=float)
        flat = times.reshape(-1)
        out = np.empty((self.n, len(flat)))
        for _, where, segments in self.pieces(flat):
            for steps, inside in _RK4Steps.split(segments, flat[where]):
                out[:, where[inside]] = steps.states(flat[where][inside]).T
        return out[:, 0] if times.ndim == 0 else out

    def windings_at(self, times):
        """(len(times) × elements) each 3D rotational element's angle at each time on the branch the
        step that gives it followed (Kernel.windings_between from the step's start); None without
        such elements."""
        if self.recorded is None:
            return None
        times = np.asarray(times, dtype=float).reshape(-1)
        out = np.empty((len(times), self.recorded.shape[1]))
        for _, where, segments in self.pieces(times):
            for steps, inside in _RK4Steps.split(segments, times[where]):
                out[where[inside]] = steps.windings(self.kernel, times[where][inside])
        return out

    def _integrate(self, k):
        """[_RK4Steps of each segment between jumps] from sample k to sample k + 1."""
        s, kernel = self.settings, self.kernel
        t0, t_end = float(self.grid[k]), float(self.grid[k + 1])
        y = self.states[k].copy()
        angles = None if self.recorded is None else self.recorded[k]
        segments = []
        self.integrations += 1
        with kernel.wound_from_start(angles):
            for t1 in sorted(d for d in self.switches if t0 < d < t_end) + [t_end]:
                nodes = _rk4_nodes(t0, t1, float(s.step), self.kinks)
                seg, rows = _RK4Steps.grid(nodes)
                seg_out = np.empty((len(seg), self.n + (0 if angles is None else len(angles))))
                seg_out[0, :self.n] = y
                if angles is not None:
                    seg_out[0, self.n:] = angles
                status, done, _, evals, t_reached, _ = _k.integrate_rk4(
                    y, t0, t1, seg, seg_out, float(s.step), int(s.max_steps), self.inputs, float(s.alpha),
                    kernel.params, t1 if t1 in self.switches else 0.0, self.kinks,
                    monitor_slots("RK4", rk4_watch=False))    # the run these steps repeat passed the watch
                self.evaluations += int(evals)
                if status != 0 or done != len(seg):
                    raise SimulationError(f"the dense output between t = {t0:.6g} s and {t_end:.6g} s: the RK4 "
                                          f"integrator failed on integrating that interval again "
                                          f"({failure_text(kernel, status, s, s.step, y, t_reached)})", t0)
                segments.append(_RK4Steps(nodes, seg, rows, seg_out, self.n))
                y, t0 = seg_out[-1, :self.n].copy(), t1
                angles = None if angles is None else seg_out[-1, self.n:].copy()
        return segments


def _rk4_nodes(t0, t_end, step, kinks) -> np.ndarray:
    """The ends of the steps kernels.integrate_rk4 takes from t0 to t_end (t0 first): the fixed
    step, the step before each kink and before t_end shortened to end there: the loop's own rule
    (kernels.rk4_step_length) run uncompiled, the same floating-point operations, so the same times."""
    nodes, t = [t0], t0
    ik = int(np.searchsorted(kinks, t, side="right"))
    while t < t_end:
        h, ik = _k.rk4_step_length.py_func(t, t_end, step, kinks, ik)
        t = t + h
        nodes.append(t)
    return np.array(nodes)


class _RK4Steps:
    """The RK4 steps of one segment of a sample interval: each step's cubic Hermite polynomial kept
    by its values at four points (its ends and two inner points, near a third and two thirds, as
    integrate_rk4 read them), and with 3D rotational elements the angles it recorded at its start."""

    def __init__(self, nodes, times, rows, values, ny):
        self.nodes = nodes
        self.h = np.diff(nodes)
        first = rows[:-1]                                  # the row of each step's start
        short = rows[1:] - first == 1                      # a step without inner points: linear
        self.s = np.empty((len(self.h), 2))
        start, end = values[first], values[rows[1:]]
        self.values = np.empty((len(self.h), 4, values.shape[1]))
        self.values[:, 0], self.values[:, 3] = start, end
        for j in (1, 2):
            row = np.minimum(first + j, len(times) - 1)
            self.s[:, j - 1] = np.where(short, j / 3.0, (times[row] - nodes[:-1]) / np.where(self.h > 0, self.h, 1.0))
            self.values[:, j] = np.where(short[:, None], start + j / 3.0 * (end - start), values[row])
        self.ny = ny
        self.size = self.values.size

    @staticmethod
    def grid(nodes):
        """(the times integrate_rk4 is to write, the index of each node among them): every node, and
        inside each step two points near a third and two thirds of it, where they lie clear of its
        ends by more than the kernel's tolerance (1e-12·max(1, |t|)); none in a shorter step."""
        times, rows = [nodes[0]], [0]
        for a, b in zip(nodes[:-1], nodes[1:]):
            h = b - a
            if h > 12e-12 * max(1.0, abs(b)):
                times += [a + h / 3.0, a + 2.0 * h / 3.0]
            times.append(b)
            rows.append(len(times) - 1)
        return np.array(times), np.array(rows)

    @staticmethod
    def split(segments, times):
        """[(segment, a boolean mask of `times` in it)]: a time in (start, end] of a segment, the
        first's start too (a time at a jump is read at the end of the segment before it)."""
        ends = np.array([steps.nodes[-1] for steps in segments[:-1]])
        which = np.searchsorted(ends, times, side="left")
        return [(steps, which == j) for j, steps in enumerate(segments) if np.any(which == j)]

    def _step(self, times):
        i = np.clip(np.searchsorted(self.nodes, times, side="right") - 1, 0, len(self.h) - 1)
        s = np.clip((times - self.nodes[i]) / np.where(self.h[i] > 0, self.h[i], 1.0), 0.0, 1.0)
        return i, s

    def states(self, times):
        """(len(times) × ny) the states at `times`, on their steps' cubics (Lagrange's form through
        the four values kept, the cubic integrate_rk4 reads, to rounding)."""
        i, s = self._step(times)
        a, b = self.s[i, 0], self.s[i, 1]
        weights = np.column_stack((-(s - a) * (s - b) * (s - 1.0) / (a * b),
                                   s * (s - b) * (s - 1.0) / (a * (a - b) * (a - 1.0)),
                                   s * (s - a) * (s - 1.0) / (b * (b - a) * (b - 1.0)),
                                   s * (s - a) * (s - b) / ((1.0 - a) * (1.0 - b))))
        return np.einsum("ij,ijk->ik", weights, self.values[i, :, :self.ny])

    def windings(self, kernel, times):
        """(len(times) × elements) the angles at `times` on the branch of the step that gives each,
        wound from the angles recorded at its start (Kernel.windings_between)."""
        i, _ = self._step(times)
        start = self.values[i, 0]
        return kernel.windings_between(self.nodes[i], start[:, :self.ny], start[:, self.ny:], times,
                                       self.states(times))


class CompiledStepper(Stepper):
    """Co-simulation stepping on the compiled path, one compiled call per communication step.

    DOP853 and RK45 keep one integration running across communication points
    (:func:`~inerter.engine.kernels.rk_advance`): a step advances the integrator until its last
    step covers the communication point and takes the state there from the step's dense output,
    as the whole run samples its output grid. The integrator's steps are clipped only to the
    experiment's stop time (`stop_time`, where the importer gave one), so while the inputs stay as
    they were, the outputs equal the whole run's (:func:`integrate_compiled`) bit for bit, and a
    communication step shorter than the integrator's costs no extra evaluations. An input that
    changes is a discontinuity of the right-hand side: the integrator restarts at that
    communication point, with the step size the error control proposed last, and its last step in
    that communication step lands on the next point (as the numpy stepper's always do). A jump of
    the right-hand side (a step force's switch) ends a segment of the integration, which starts
    afresh there (:func:`compiled_kernels.cosim_step`), and its kinks (a ground record's samples)
    end steps, through which it runs on, as the whole run's does.

    RK4 (fixed step) restarts at every communication point, its last step shortened to land on it,
    and the step before a kink shortened to end there.
    The outputs are evaluated in the same compiled call. (time, state, inputs, the integrator's
    own state) is the complete state: a rolled-back step repeats bit for bit."""

    #: Its run state is its kernel's (Kernel.for_run below); the mechanism and signals are read only.
    owns_mechanism = False

    def __init__(self, mech, settings, signals, kernel, stop_time=None):
        super().__init__(mech, settings, signals)
        self.kernel = kernel.for_run()        # its tables (φ_ref from the initial pose, modes) are this run's
        self._coupled = None                  # the elements coupled in the kernel's band, once a retune asks
        self.path = "compiled"
        self.t_bound = float(stop_time) if stop_time is not None and stop_time > 0 else np.inf
        self._order = kernel.signal_order(signals)
        self._need_acc = bool(signals.needs_accelerations)
        self._tables = _tables(settings.method) if settings.method in _RK_CODE else None
        self._work = (None if self._tables is None else
                      _k.work_arrays(kernel.params, kernel.ny, _k.rk_stages(self._tables[_TABLEAU_A])))
        self._monitor = monitor_slots(settings.method, energy=energy_watched(mech))
        self._jumps = np.array(getattr(mech, "discontinuities", ()), dtype=float)
        self._kinks = np.array(getattr(mech, "kinks", ()), dtype=float)
        self._tol = (float(settings.rtol), float(settings.atol), int(settings.max_steps))
        self._raw = np.empty(len(signal_layout(kernel.flat)))
        self._scratch = _k.cosim_scratch(kernel.params, kernel.ny)   # shared with the native steps' table
        self._values = None                   # the outputs at self.time, when the last step made them
        self._rk = None                       # the running integration (Running)
        self._rk_inputs = None                # the inputs it runs with
        self._input_moved = False             # an input changed since the last step
        self._native = None                   # the arrays of native steps (native_table), for self._rk

    def _start_rk(self):
        """A fresh integration at (self.time, self.y) with the held inputs and the last step size
        (0: chosen as scipy does), its segment ending at the next discontinuity (RK_JUMP, 0: none)."""
        ny = self.kernel.ny
        hdr = np.zeros(_k.RK_HEADER)
        hdr[_k.RK_T] = self.time
        hdr[_k.RK_H] = self.h or 0.0
        hdr[_k.RK_JUMP] = _k.next_jump(self._jumps, float(self.time))
        self._rk_inputs = self.kernel._inputs(self.inputs.copy())
        return Running(hdr, np.array(self.y, dtype=float), np.empty(ny), np.array(self.y, dtype=float),
                       np.zeros((7, ny)))

    def set_input(self, name, value):
        old = self.inputs[self.input_index[name]]
        super().set_input(name, value)
        if self.inputs[self.input_index[name]] != old:
            self._rk = None                   # a discontinuity: the integration restarts here
            self._input_moved = True
            self._values = None               # outputs depend on the inputs (inerter forces)

    def retune(self, mech, signals):
        """Go on from the current state with the element coefficients and point-force numbers of
        `mech` (the same scene read with other parameter values), written in place into this
        stepper's tables: a discontinuity, the integration restarts here. The tables are this
        stepper's own (Kernel.for_run), so the model and its other steppers keep theirs. Raises ValueError, the stepper unchanged, where `mech` differs in anything else, or
        gives an inertance to an element whose inertance was 0 when the kernel's band was laid out."""
        from inerter.engine.tables import check_retune, coupled_elements, retune_rows
        check_retune(self.mech.scene, mech.scene)
        if self._coupled is None:             # as the band was laid out (before any retune's values)
            self._coupled = coupled_elements(self.kernel.flat)
        lacking = retune_rows(self.kernel.flat, mech.scene, self._coupled)
        if lacking:
            raise ValueError(f"element {', '.join(lacking)}: an inertance that was 0 when the model was "
                             f"compiled cannot become non-zero between steps (its coupling is not in the "
                             f"compiled band); give it a non-zero value before initialisation")
        self.mech, self.signals = mech, signals
        self._rk = None
        self._input_moved = True
        self._values = None
        self._native = None                   # its table points to the arrays it was made with
        restart_lowest_energy(self._monitor)

    def step(self, t_end):
        t_end = float(t_end)
        if not t_end > self.time:
            raise SimulationError(f"step to t = {t_end!r} is not after the current time", self.time)
        s, kernel = self.settings, self.kernel
        if s.method == "RK4":
            self._step_rk4(t_end)
            return
        rk = self._rk
        if rk is None:
            rk = self._start_rk()
        # The integration runs on in place; a failed step drops it, and the next one restarts at
        # (self.time, self.y), which a failure leaves as they were.
        self._rk = None
        if t_end > self.t_bound:               # the importer went past its stop time
            self.t_bound = np.inf
        # Right after an input changed, the step lands on t_end (an importer that moves its inputs at
        # every point gets the numpy stepper's steps); otherwise it runs on towards the stop time.
        bound = t_end if self._input_moved else self.t_bound
        out = np.empty((1, kernel.ny))
        order = self._order if self._order is not None else _NO_ORDER
        values = np.empty(len(order))
        rtol, atol, max_steps = self._tol
        hdr = rk.hdr
        total_before = hdr[_k.RK_TOTAL]
        _gaps_stale(self._scratch)            # the terminals' gaps at rk's y: computed afresh here
        status, signal_status = _k.cosim_step(
            _RK_CODE[s.method], hdr, rk.y, rk.f, rk.y_prev, rk.dense, t_end, np.zeros(1), out, bound, rtol, atol,
            max_steps, self._rk_inputs, float(s.alpha), kernel.params, self._tables, self._monitor,
            self._work, self._need_acc, self._raw, order, values, self._jumps, self._kinks, self._scratch)
        if status:
            why = failure_text(kernel, status, s, hdr[_k.RK_H], rk.y, hdr[_k.RK_T], int(s.max_steps))
            raise SimulationError(f"the {s.method} integrator failed: {why}", float(hdr[_k.RK_T]))
        self._rk = rk
        self._input_moved = False
        self.y = out[0]
        self.time = t_end
        self.h = float(hdr[_k.RK_H])
        self.steps += int(hdr[_k.RK_TOTAL] - total_before)
        self._values = None if signal_status or self._order is None else self.signals.complete(values).tolist()

    def _step_rk4(self, t_end):
        """RK4 from the communication point, its last step shortened to land on t_end; a jump
        inside (or at t_end) ends a segment there, as the numpy stepper's, and a kink inside ends a
        step (:func:`compiled_kernels.rk4_cosim_step`, which the FMU's native step calls too)."""
        s, kernel = self.settings, self.kernel
        y = np.array(self.y, dtype=float)                 # advanced in place, segment by segment
        status, steps, t_reached, t_fail = _k.rk4_cosim_step(
            y, float(self.time), t_end, self._jumps, self._kinks, np.zeros(2), np.empty((2, len(y))),
            float(s.step), int(s.max_steps), kernel._inputs(self.inputs.copy()), float(s.alpha), kernel.params,
            self._monitor)
        if status:
            at = t_reached if status == _k.MEETING else t_fail      # y is the state at the meeting
            why = failure_text(kernel, status, s, s.step, y, at, int(s.max_steps), self._monitor)
            raise SimulationError(f"the {s.method} integrator failed: {why}", float(t_reached))
        self.steps += int(steps)
        if not np.isfinite(y).all():
            raise SimulationError("the state became non-finite", t_end)
        self.y = y
        self.time = t_end
        self._values = None
        self._input_moved = False

    def output_values(self) -> list:
        """The outputs at the current time, in the order of ``signals.names``."""
        if self._values is not None:
            return self._values
        kernel = self.kernel
        q, v, z = kernel.split(self.y)
        if self._order is None:
            values = self.signals.evaluate(self.time, q, v, self.inputs, self.settings.alpha,
                                           functools.partial(kernel.accelerations, z=z), z=z)
        else:
            values = kernel.signal_values(self.signals, self._order, self.time, q, v, self.inputs,
                                          self.settings.alpha, z)
        self._values = values.tolist()
        return self._values

    # The native doStep (inerter.fmu.native): compiled_kernels.native_step takes steps on the running
    # integration's arrays without entering Python; native_sync takes over what it did.
    def native_table(self, tolerance: float, start: bool = False):
        """The int64 table of :func:`compiled_kernels.native_step` for the next step, its clock at the
        current time (`tolerance`: communication points closer than tolerance·max(1 s, |t|) are
        equal); None where the next step must be taken here: no running integration (DOP853, RK45:
        before the first step, after a failed one) unless `start`, an input changed, outputs the
        kernels do not evaluate. Valid until the next call of :meth:`step` or :meth:`set_state`.

        `start`: where no integration runs, start one at (time, y) with the held inputs, as the
        next :meth:`step` would (:meth:`_start_rk`; it finds it running and goes on with it), so
        that the first step after initialisation can be native too."""
        if self._order is None or self._input_moved:
            return None
        if self.settings.method == "RK4":
            native = self._native
            if native is None:
                ny = self.kernel.ny
                rk = Running(np.zeros(_k.RK_HEADER), np.empty(ny), np.empty(ny), np.empty(ny), np.zeros((7, ny)))
                native = self._native = self._native_arrays(
                    rk, np.empty(len(self.kernel._inputs(self.inputs))), 2,
                    (np.zeros((1, 1)), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1), np.zeros((1, 1)),
                     np.zeros((1, 1))), _k.work_arrays(self.kernel.params, ny, 1))
            native["rk"].y[:] = self.y                  # RK4 restarts at every communication point
            native["inputs"][:] = self.kernel._inputs(self.inputs)
        else:
            if self._rk is None:
                if not start:
                    return None
                self._rk = self._start_rk()
            native = self._native
            if native is None or native["rk"] is not self._rk:
                native = self._native = self._native_arrays(self._rk, self._rk_inputs, 1, self._tables, self._work)
        _gaps_stale(self._scratch)            # the first native step computes the gaps at rk's y
        clock = native["clock"]
        clock[_k.CLOCK_TIME] = self.time
        clock[_k.CLOCK_BOUND] = self.t_bound
        clock[_k.CLOCK_BUSY] = 0.0
        clock[_k.CLOCK_TOLERANCE] = tolerance
        clock[_k.CLOCK_TAKEN] = 0.0
        native["steps"] = native["rk"].hdr[_k.RK_TOTAL]
        return native["table"]

    def _native_arrays(self, rk, inputs, samples, tables, work) -> dict:
        """The table of native_step over the integration's arrays `rk` ([hdr, y, f, y_prev, dense]),
        with `samples` rows of output states (2 for RK4: the step's start and end)."""
        s, kernel = self.settings, self.kernel
        ny = len(rk.y)
        clock = np.zeros(_k.CLOCK_SIZE)
        clock[_k.CLOCK_RTOL], clock[_k.CLOCK_ATOL] = float(s.rtol), float(s.atol)
        clock[_k.CLOCK_ALPHA], clock[_k.CLOCK_STEP] = float(s.alpha), float(s.step or 0.0)
        native = dict(rk=rk, inputs=inputs, clock=clock, ts=np.zeros(samples), out=np.empty((samples, ny)),
                      values=np.empty(len(self._order)), backup=[np.empty_like(a) for a in rk],
                      backup_monitor=np.empty_like(self._monitor))
        arrays = {}
        params = kernel.params[:len(_k.PARAMS)]
        for group, values in ((_k.RK_STATE, rk), (_k.PARAMS, params), (_k.TABLEAU, tables), (_k.WORK, work)):
            arrays.update(zip((name for name, _ in group), values, strict=True))
        arrays["spatial"] = kernel.params[-1] if kernel.spatial else np.zeros(0, dtype=np.int64)
        arrays.update(zip(("b_" + name for name, _ in _k.RK_STATE), native["backup"], strict=True))
        arrays["b_monitor"] = native["backup_monitor"]
        gaps, z, fresh, (nodes, _, kept) = self._scratch
        arrays.update(zip((name for name, _ in _k.COSIM), (gaps, z, fresh, nodes, kept), strict=True))
        arrays.update(ts=native["ts"], out=native["out"], inputs=inputs, monitor=self._monitor,
                      raw=self._raw, order=self._order, values=native["values"], clock=clock, jumps=self._jumps,
                      kinks=self._kinks)
        code = _k.NATIVE_RK4 if s.method == "RK4" else _RK_CODE[s.method]
        size = _k.TABLE_HEAD + 3 * len(_k.NATIVE_SLOTS)
        words = [size, code, int(s.max_steps), int(self._need_acc)]
        for name, kind in _k.NATIVE_SLOTS:       # the words gathered first, written at once: the
            a = arrays[name]                      # table is built at every arming of the FMU's link
            dtype = np.float64 if kind[0] == "f" else np.int64
            flags = a.flags
            if a.dtype != dtype or a.ndim != int(kind[1]) or not flags.c_contiguous or not flags.writeable:
                raise TypeError(f"native step: array {name} is {a.dtype} {a.shape}, expected {kind}")
            words += (a.ctypes.data, a.shape[0], a.shape[1] if a.ndim == 2 else 0)
        native["table"] = np.array(words, dtype=np.int64)
        native["arrays"] = arrays                 # keeps every array the table points to alive
        return native

    def native_function(self):
        """The C function of the native steps for this scene's dimension (numba cfunc)."""
        return _k.native_step_cfunc(self.kernel.spatial)

    def native_values(self) -> np.ndarray:
        """The array native steps write the outputs to (in the order of ``signals.names``, the
        derived outputs left out: :meth:`native_sync` evaluates them), for the table
        :meth:`native_table` returned last."""
        return self._native["values"]

    def native_sync(self) -> int:
        """Take over the steps :func:`compiled_kernels.native_step` took since :meth:`native_table`
        (time, state, step size, counters, outputs), and restore the integration's state from its
        backup where a native step declined half-way. Returns the number of steps taken over."""
        native = self._native
        rk4 = self.settings.method == "RK4"
        if native is None or not (rk4 or native["rk"] is self._rk):
            return 0
        clock = native["clock"]
        if clock[_k.CLOCK_BUSY]:
            for a, backup in zip(native["rk"], native["backup"]):
                a[...] = backup
            self._monitor[:] = native["backup_monitor"]     # the step is taken again from here
            clock[_k.CLOCK_BUSY] = 0.0
        taken = int(clock[_k.CLOCK_TAKEN])
        if not taken:
            return 0
        hdr = native["rk"].hdr
        self.time = float(clock[_k.CLOCK_TIME])
        self.t_bound = float(clock[_k.CLOCK_BOUND])
        if rk4:
            self.y = native["rk"].y.copy()
        else:
            self.y = native["out"][0].copy()
            self.h = float(hdr[_k.RK_H])
        self.steps += int(hdr[_k.RK_TOTAL] - native["steps"])
        native["steps"] = hdr[_k.RK_TOTAL]
        self._values = self.signals.complete(native["values"]).tolist()
        clock[_k.CLOCK_TAKEN] = 0.0
        return taken

    def get_state(self) -> bytes:
        rk = None if self._rk is None else Running(*(a.copy() for a in self._rk))
        return pickle.dumps((self.time, self.y.copy(), self.h, self.inputs.copy(), self.steps, self.t_bound, rk,
                             self._rk_inputs, self._input_moved, self.kernel.windings.copy(), self._monitor.copy()))

    def set_state(self, blob: bytes):
        (self.time, y, self.h, inputs, self.steps, self.t_bound, self._rk, self._rk_inputs,
         self._input_moved, windings, monitor) = load_state(blob)
        self.kernel.windings[:] = windings
        self._monitor[:] = monitor            # in place: a native step's table holds it (RK4's watch)
        self.y = np.array(y)
        self.inputs = np.array(inputs)
        self._values = None
        _gaps_stale(self._scratch)            # the terminals' gaps are those of the state left behind


def failure_text(kernel, status, settings, h, y_last, t_last, max_steps=None, monitor=None) -> str:
    """What a compiled loop's failure `status` in a run with `settings` means, in the words of the
    numpy path: the step size
    `h` it ended with (and the step budget `max_steps` it ran out of); for terminals meeting, the
    element whose terminals were closest in the last good state `y_last` (at `t_last`), the loop
    having stopped within a step of it (TERMINALS_MEET), or at the meeting it located there
    (MEETING, ``Mechanism.meeting_message``); where the solve or the step size failed, what in that state
    may have stalled it (``Mechanism.diagnose``: terminals nearly meeting, a device mount near its
    singularity); where the step size collapsed or the steps read as stiff, the scene's fastest time
    scale (``Mechanism.stiffest``: a device's series mode, the narrowest tanh switch); where RK4's
    step was beyond its stability limit, its watch's values in `monitor` (kernels.rk4_watch) and
    what to set, from the scene's linearisation at `y_last` (``simulation.rk4_advice``: the step,
    the joints' Baumgarte α where their correction sets the limit)."""
    from inerter.engine import simulation as sim
    method = settings.method
    if status == _k.UNSTABLE:
        return (sim.rk4_unstable_text(h, monitor)
                + sim.rk4_advice(h, settings.alpha, kernel.m, monitor, lambda alpha: kernel.derivative(None, alpha),
                                 t_last, y_last) + kernel.mech.stiffest())
    if status == _k.ENERGY_JUMP:
        return (sim.energy_jump_text(h, monitor)
                + sim.energy_jump_advice(h, settings.alpha, kernel.m, monitor,
                                         lambda alpha: kernel.derivative(None, alpha), t_last, y_last))
    text = _status_text(kernel, status, method, h, y_last, t_last, max_steps)
    if status in (_k.STEP_TOO_SMALL, _k.SINGULAR, _k.NOT_FINITE, _k.COLLAPSED, _k.CHANGE_POINT) \
            and y_last is not None:         # as the numpy path: what may have stalled it
        text += kernel.mech.diagnose(y_last)        # it reads the state's q
    if status in (_k.STIFF, _k.COLLAPSED):          # as the numpy path: StiffForMethod, StepCollapse
        text += kernel.mech.stiffest()
    if status == _k.MAX_STEPS:
        return text
    return text + (sim.watch_so_far(h, monitor) or sim.rk4_hint(method, False))


def _status_text(kernel, status, method, h, y_last, t_last, max_steps):
    from inerter.engine import simulation as sim
    text = _STATUS_TEXT[status]
    if status == _k.MAX_STEPS and max_steps is not None:
        return (f"more than max_steps = {max_steps} integrator steps (step size {h:.3g} s): "
                + sim.max_steps_advice(method))
    if status == _k.STIFF:
        return text.format(method=method, h=h, hits=sim.STIFFNESS_HITS)
    if status == _k.COLLAPSED:
        return text.format(method=method, h=h, steps=sim.COLLAPSE_STEPS, relative=sim.COLLAPSE_RELATIVE)
    if status == _k.GIMBAL_LOCK:
        return _gimbal_lock_text(kernel, y_last, t_last)
    if status == _k.MEETING:
        return kernel.mech.meeting_message(y_last, t_last)
    names = kernel.flat["el_names"]
    if status == _k.TERMINALS_MEET and names:
        q, v, z = (part.copy() for part in kernel.split(y_last))
        layout_names = signal_layout(kernel.flat)
        raw = np.empty(len(layout_names))
        _k.signal_values(q, v, z, np.zeros(kernel.n + kernel.m), kernel.params, raw)
        where = {name: i for i, name in enumerate(layout_names)}
        lengths = raw[[where[f"{name}.s_rel"] for name in names]]
        closest = float(np.min(lengths))
        which = [name for name, L in zip(names, lengths) if L <= closest * (1.0 + 1e-9)]
        spec = kernel.mech.scene.elements[which[0]]
        label = ", ".join(f"'{name}'" for name in which)
        label = f"element {label}: its" if len(which) == 1 else f"elements {label}: their"
        return (f"{label} terminals {spec.point_a} and {spec.point_b} meet within a step of t = {t_last:.6g} s "
                f"(where they were {closest:.3g} m apart), so the direction is undefined")
    return text


def _gimbal_lock_text(kernel, y_last, t_last) -> str:
    """The numpy path's words for a body whose Z-X-Z Euler angles reach their singularity: the body
    nearest to it (smallest |sin θ|) in the last good state `y_last`, at `t_last`."""
    names = list(kernel.mech.body_names)
    thetas = np.asarray(y_last, dtype=float)[4:6 * len(names):6]          # (φ, θ, ψ) after R
    i = int(np.argmin(np.abs(np.sin(thetas))))
    return (f"body '{names[i]}': its Z-X-Z Euler angles reach their singularity (gimbal lock) within a step of "
            f"t = {t_last:.6g} s (sin θ = {math.sin(thetas[i]):.2e} there): the angle rates are undefined; use "
            f"orientation = \"quaternion\" (the default)")


def compiled_stepper(mech, settings, signals, stop_time=None):
    """A :class:`CompiledStepper`, or None where the compiled loop cannot take the scene: see
    :func:`unsupported`; an implicit method or the projection treatment."""
    if unsupported(mech) or settings.method not in COMPILED_METHODS or settings.constraint == "projection":
        return None
    return CompiledStepper(mech, settings, signals, _kernel_for(mech), stop_time)


def unsupported(mech) -> str:
    """Why the compiled kernels cannot take `mech` ("" when they can): numba missing."""
    if not AVAILABLE:
        return WHY_NOT
    return ""
