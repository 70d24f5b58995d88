"""A dask worker preload (``dask worker --preload THIS``) that makes the worker's Python unable to
import inerter, as in an environment where the package is not installed. ``python -I`` alone does
not do it where the environment holds an installed (or editable) inerter."""
import sys


class _NotInstalled:
    def find_spec(self, name, path=None, target=None):
        if name == "inerter" or name.startswith("inerter."):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, _NotInstalled())
