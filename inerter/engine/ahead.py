"""The kernels a run enters from Python, built ahead of time for this machine, so that a warm
process's first result does not take them from numba's cache.

numba takes a kernel from its on-disk cache by parsing the kernel's LLVM bitcode again and
registering its symbols, and its first load of the process fills numba's registries: about 0.4 s
of a warm process's first result on a 2-core AMD EPYC host, for the five kernels a run and its
metrics enter (:data:`ENTRY_KERNELS`; docs/performance.md). ``inerter compile`` builds those
kernels with numba's ahead-of-time compiler (``numba.pycc``) into one extension module per
dimension beside the kernels' cache; importing one takes under a millisecond. A build compiles the
kernels' own code (their ``py_func``, the element laws they inline) for the argument types that
numba's dispatchers were compiled for in the warm-up, for this machine's CPU: the same code as the
dispatchers', with the same results (tests/test_ahead.py).

A call goes to a build only where its arguments have exactly the types the build was made for
(numba's fingerprint of the arguments, then their numba types, once per fingerprint): a build
unboxes its arguments as those types without checking them. Every other call, and every call where
no build exists or it cannot be loaded, goes to numba's dispatcher, as before.
(``inerter.api.build_ahead`` builds each dimension in a process of its own.)
"""
from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib.util
import os
import pickle
import shutil
import sys
import sysconfig
import tempfile
import warnings
from pathlib import Path

#: The kernels a run and its metrics enter from Python (``compiled.integrate_compiled``, the
#: outputs' columns and dense output, the whole history's outputs, the constraint drift).
ENTRY_KERNELS = ("integrate_rk", "signal_column", "dense_signal", "signal_history", "max_residual")

#: Seconds the two dimensions' builds take side by side on a 2-core machine, for ``inerter
#: compile``'s notice: 85 s on 2026-11-28, an AMD EPYC host (docs/performance.md).
BUILD_SECONDS = 90

#: Set ``INERTER_AHEAD=0`` to enter every kernel through numba's dispatcher (a benchmark's "before").
_OFF = "INERTER_AHEAD"


@functools.lru_cache(maxsize=None)
def platform_tag() -> str:
    """What a build depends on besides the kernels' source: the interpreter's ABI, numpy's and
    numba's versions, this machine's CPU and its features (a cache folder shared between machines
    keeps each machine's own build)."""
    import llvmlite.binding as ll
    import numba
    import numpy
    parts = (sys.implementation.cache_tag, sysconfig.get_config_var("EXT_SUFFIX") or "", numpy.__version__,
             numba.__version__, ll.get_host_cpu_name(), ll.get_host_cpu_features().flatten())
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:12]


def module_name(kernels, dimension: int) -> str:
    """The build's module name for the kernels module `kernels` (named by its source's hash) and
    `dimension`."""
    return f"{kernels.__name__}_ahead{dimension}d_{platform_tag()}"


def _paths(kernels, dimension: int) -> tuple[Path, Path]:
    """(the extension module, its table of exports) of `dimension`'s build beside `kernels`."""
    name = module_name(kernels, dimension)
    folder = Path(kernels.__file__).parent
    return folder / f"{name}{sysconfig.get_config_var('EXT_SUFFIX')}", folder / f"{name}.exports"


def exports_of(kernels, names=ENTRY_KERNELS) -> dict:
    """{kernel: [(argument types, exported name)]}: every signature numba has compiled (or loaded)
    in this process for the kernels `names`."""
    return {name: [(argtypes, f"{name}_{i}") for i, argtypes in enumerate(getattr(kernels, name).overloads)]
            for name in names if getattr(kernels, name).overloads}


def build(kernels, dimension: int, names=ENTRY_KERNELS) -> Path | None:
    """Build `dimension`'s extension module of the kernels `names` for the signatures compiled in
    this process (:func:`exports_of`; the warm-up of that dimension alone), beside `kernels`.
    Written whole or not at all: the module, then its table of exports, each moved into place.
    Returns the module's path (None: nothing compiled to build)."""
    exports = exports_of(kernels, names)
    if not exports:
        return None
    import llvmlite.binding as ll
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")             # numba.pycc is pending deprecation in numba
        from numba.pycc import CC
    module, table = _paths(kernels, dimension)
    work = Path(tempfile.mkdtemp(prefix="build-", dir=module.parent))
    try:
        cc = CC(module_name(kernels, dimension))
        cc.output_dir = str(work)
        cc.target_cpu = ll.get_host_cpu_name()      # this machine's instructions, as numba's own
        cc.verbose = False
        for name, signatures in exports.items():
            dispatcher = getattr(kernels, name)
            for argtypes, exported in signatures:
                cc.export(exported, dispatcher.overloads[argtypes].signature)(dispatcher.py_func)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            cc.compile()
        os.replace(work / module.name, module)
        (work / table.name).write_bytes(pickle.dumps(exports))
        os.replace(work / table.name, table)        # last: a table names a whole module
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return module


def built(kernels, dimension: int) -> bool:
    """Whether `dimension`'s build of `kernels` exists for this machine."""
    return all(path.is_file() for path in _paths(kernels, dimension))


def load_builds(kernels) -> dict:
    """{kernel: {argument types: compiled function}} from every build of `kernels` for this
    machine; empty where none exists or none loads (a missing or unreadable file, an extension
    this interpreter cannot import), or where ``INERTER_AHEAD=0``."""
    builds = {}
    if os.environ.get(_OFF) == "0" or not hasattr(kernels, "__file__"):
        return builds
    for dimension in (2, 3):
        module_path, table = _paths(kernels, dimension)
        try:
            exports = pickle.loads(table.read_bytes())
            spec = importlib.util.spec_from_file_location(module_name(kernels, dimension), module_path)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            found = {(name, argtypes): getattr(module, exported)
                     for name, signatures in exports.items() for argtypes, exported in signatures}
        except Exception:               # noqa: BLE001 (any failure: numba's dispatchers serve)
            continue                    # (a table naming what its module lacks too)
        for (name, argtypes), function in found.items():
            builds.setdefault(name, {})[argtypes] = function
    return builds


class Entry:
    """One kernel as Python enters it: the build made for the call's argument types where there is
    one, else numba's dispatcher. The choice is kept per fingerprint of the arguments (numba's own,
    a fraction of a microsecond); a new fingerprint is typed once, as the dispatcher types it."""

    __slots__ = ("dispatcher", "_builds", "_chosen", "_fingerprint")

    def __init__(self, dispatcher, builds: dict):
        from numba._dispatcher import compute_fingerprint
        self.dispatcher = dispatcher
        self._builds = builds
        self._chosen = {}
        self._fingerprint = compute_fingerprint

    def __call__(self, *args):
        try:
            key = self._fingerprint(args)
        except NotImplementedError:             # an argument numba does not fingerprint
            return self.dispatcher(*args)
        target = self._chosen.get(key)
        if target is None:
            target = self._chosen[key] = self._choose(args)
        return target(*args)

    def _choose(self, args):
        if not self._builds:
            return self.dispatcher
        from numba.core.typing.typeof import Purpose, typeof
        return self._builds.get(tuple(typeof(a, Purpose.argument) for a in args), self.dispatcher)


class Entries:
    """The kernels of :data:`ENTRY_KERNELS` as attributes (:class:`Entry`, or the dispatcher where
    there is no build), the builds loaded at
    the first call of any. :meth:`dispatchers_only` enters them through numba's dispatchers (the
    warm-up, whose compiled signatures the builds are made for)."""

    def __init__(self, kernels):
        self._kernels = kernels
        self._builds = None
        self._with_builds = True
        self._made = {}                 # (name, with builds): its Entry, once called
        self._point()

    def _point(self):
        for name in ENTRY_KERNELS:
            made = self._made.get((name, self._with_builds))
            setattr(self, name, made if made is not None else self._first_call(name))

    def _first_call(self, name):
        def first_call(*args):
            return self._entry(name)(*args)
        return first_call

    def _entry(self, name):
        """`name`'s :class:`Entry`, or its dispatcher itself where it has no build (no choice to
        make at each call)."""
        builds = {}
        if self._with_builds:
            if self._builds is None:
                self._builds = load_builds(self._kernels)
            builds = self._builds.get(name, {})
        dispatcher = getattr(self._kernels, name)
        entry = self._made[name, self._with_builds] = Entry(dispatcher, builds) if builds else dispatcher
        setattr(self, name, entry)
        return entry

    @contextlib.contextmanager
    def dispatchers_only(self):
        """Every call through numba's dispatchers while inside."""
        self._with_builds = False
        self._point()
        try:
            yield
        finally:
            self._with_builds = True
            self._point()
