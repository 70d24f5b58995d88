"""The function a sweep sends to the dask workers for each run: :func:`run`.

It is sent by value (cloudpickle), not by reference: a worker whose environment cannot import
inerter would die unpickling a reference to :func:`inerter.studies.sweep.run_one` (dask's
connection fails before the task exists, the worker closes, and the sweep waits for a worker that
never comes). Unpickled by value, this function imports the package itself and, where it cannot
(or finds another version), answers with ``environment_error``, which stops the sweep at once with
that message. It imports what it needs inside itself, so that nothing of this package travels
with it.
"""


def run(task: dict) -> dict:
    """``run_one(task)``, or ``{"key", "environment_error"}`` where this worker cannot run inerter."""
    import importlib
    import os
    import sys
    # A parent process that ran an FMU in itself hands its workers a sys.path whose front holds that
    # FMU's resources/ (pythonfmu puts it there), with the FMU's trimmed copy of this package: not
    # the package to run with.
    sys.path[:] = [p for p in sys.path if not os.path.isfile(os.path.join(p or ".", "slavemodule.txt"))]
    try:
        sweep = importlib.import_module("inerter.studies.sweep")
        version = getattr(sys.modules["inerter"], "__version__", None)
    except Exception as exc:            # whatever the import raises is the answer
        problem = f"cannot import inerter ({type(exc).__name__}: {exc}): install inerter {task['version']}"
    else:
        if version == task["version"]:
            return sweep.run_one(task)
        problem = f"has inerter {version}, this sweep {task['version']}: install inerter {task['version']}"
    try:
        from distributed import get_worker
        worker = get_worker().address
    except (ImportError, ValueError):
        worker = "(not a dask worker)"
    return {"key": task["key"], "environment_error": f"dask worker {worker} (Python {sys.executable}) {problem} "
            "in every worker's environment, or start the workers from the environment of this sweep"}


class ByValue:
    """`fn` as a callable that any pickler (dask pickles a graph with the standard one, which takes
    a function by reference) turns into ``cloudpickle.loads(<fn by value>)``."""

    def __init__(self, fn):
        self.fn = fn

    def __call__(self, *args, **kwargs):
        return self.fn(*args, **kwargs)

    def __reduce__(self):
        import cloudpickle
        return cloudpickle.loads, (cloudpickle.dumps(self.fn),)


def sendable() -> ByValue:
    """:func:`run`, to be sent to the workers by value."""
    import sys

    import cloudpickle
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    return ByValue(run)
