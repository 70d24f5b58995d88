"""Functions written once for two runs: compiled into the engine's kernels, and run as written by
the Python interpreter.

The element laws (:mod:`inerter.elements`), the rotation math (:mod:`inerter.common.rotations`) and
the ground motion's terms are plain scalar functions. The kernels compile them in (most inlined:
numba's ``inline="always"`` copies their IR into the caller, so that a kernel is one function), and
the readable evaluators run them uncompiled. A law that calls another law must then stay uncompiled
all the way down when it runs in Python: a numba dispatcher called from Python compiles itself for
the types it is given, on first use in a fresh installation, in the middle of a run that asked for
no compilation. The dispatchers made here are typed and compiled by numba like any other where a
kernel calls them, and run as the plain function they wrap where Python calls them.
"""
from __future__ import annotations

import functools

from numba import njit
from numba.core.registry import CPUDispatcher


class KernelFunction(CPUDispatcher):
    """A numba dispatcher for a function the kernels call; called from Python, it runs its
    ``py_func`` (the definition as written), never a compilation of it. :func:`compiled_copy` gives a
    compiled copy where a test wants to call the compiled definition from Python."""

    def __call__(self, *args, **kwargs):
        return self.py_func(*args, **kwargs)


def inlined(fn):
    """`fn` as the kernels inline it (``njit(inline="always")``), run uncompiled from Python."""
    return KernelFunction(py_func=fn, locals={}, targetoptions={"nopython": True, "inline": "always"})


def not_inlined(fn):
    """`fn` as the kernels call it without inlining it (compiled on its own, cached on disk), run
    uncompiled from Python: code that most runs never reach stays out of the kernels that call it."""
    dispatcher = KernelFunction(py_func=fn, locals={}, targetoptions={"nopython": True})
    dispatcher.enable_caching()
    return dispatcher


@functools.cache
def compiled_copy(function):
    """A compiled copy of a :class:`KernelFunction` (or of any plain function), callable from
    Python: the functions it calls are compiled into it as in the kernels (one copy per function,
    compiled on its first call)."""
    return njit(getattr(function, "py_func", function))
