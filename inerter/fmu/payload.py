"""What an FMU carries of the ``inerter`` package: the modules its slave can import, no others.

The slave (``fmu_src/inerter_slave.py``) imports a few modules of the package, and they import
others, some inside functions that run on one path only. :func:`package_files` follows every
import statement of every module it reaches, wherever the statement stands, so it ships every
module the FMU could import; the command line, sweeps, studies and this builder stay out.

Two imports are not statements, and :func:`inerter.engine.compiled.kernel_sources` lists both:
``inerter.elements`` finds its element kinds by listing its folder, and the compiled engine loads
its kernels from a copy of ``kernels.py``. The kernels' on-disk cache is keyed by the hash of
those files, so the FMU carries them unchanged and finds the kernels its host already compiled.
"""
from __future__ import annotations

import ast
import hashlib
import json
from pathlib import Path

from inerter.common.atomic import replace_file

PACKAGE = "inerter"
PACKAGE_DIR = Path(__file__).resolve().parents[1]


def module_file(name: str, package_dir: Path = PACKAGE_DIR) -> Path | None:
    """The source file of module `name` (``inerter.a.b``) under `package_dir`, None if none."""
    parts = name.split(".")
    if parts[0] != PACKAGE:
        return None
    base = package_dir.joinpath(*parts[1:])
    for candidate in (base / "__init__.py", base.with_suffix(".py")):
        if candidate.is_file():
            return candidate
    return None


def imported_names(source: str, module: str, is_package: bool) -> set[str]:
    """Every module name an import statement of `source` may name (``from a import b`` gives
    ``a`` and ``a.b``; the caller keeps those that are modules), relative imports resolved."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                anchor = module.split(".")
                anchor = anchor[:len(anchor) - node.level + (1 if is_package else 0)]
                base = ".".join(anchor + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names if alias.name != "*")
    return names


def closure(seeds, package_dir: Path = PACKAGE_DIR) -> set[str]:
    """The package's modules that importing `seeds` can import, `seeds` and every parent package
    (importing ``a.b.c`` runs ``a`` and ``a.b`` first) included."""
    found: set[str] = set()
    todo = list(seeds)
    while todo:
        name = todo.pop()
        if name in found:
            continue
        path = module_file(name, package_dir)
        if path is None:
            continue
        found.add(name)
        parts = name.split(".")
        todo.extend(".".join(parts[:i]) for i in range(1, len(parts)))
        todo.extend(imported_names(path.read_text(encoding="utf-8"), name,
                                   path.name == "__init__.py"))
    return found


#: package_files' answers in this process, by :func:`_sources_digest`.
_FOUND: dict[str, list[Path]] = {}


def package_files(slave_file: Path, package_dir: Path = PACKAGE_DIR) -> list[Path]:
    """The files of the package an FMU of the slave `slave_file` needs, sorted. Following the
    imports parses every module (about half a second), and every build and every check that an
    FMU is current asks: the answer is kept under a hash of the slave's and every module's bytes,
    in this process and as a record in the kernels' cache folder (so a new process, as every
    ``inerter run --model fmu`` is, reads it)."""
    slave_file, package_dir = Path(slave_file), Path(package_dir)
    digest = _sources_digest(slave_file, package_dir)
    if digest not in _FOUND:
        _FOUND.clear()
        _FOUND[digest] = _recorded_package_files(slave_file, package_dir, digest)
    return list(_FOUND[digest])


def _recorded_package_files(slave_file: Path, package_dir: Path, digest: str) -> list[Path]:
    """:func:`package_files` from its record, or the imports followed and recorded where there is none."""
    from inerter.engine.compiled import cache_root, kernel_sources

    record = cache_root() / "fmu-files" / f"{digest}.json"
    try:
        return [package_dir / name for name in json.loads(record.read_text(encoding="utf-8"))]
    except (OSError, ValueError):
        pass
    seeds = imported_names(slave_file.read_text(encoding="utf-8"), "__main__", False)
    files = {module_file(m, package_dir) for m in closure(seeds, package_dir)}
    files.update(package_dir / p.relative_to(PACKAGE_DIR) for p in kernel_sources())
    files = sorted(files)
    names = json.dumps([f.relative_to(package_dir).as_posix() for f in files])
    try:                                  # a folder that cannot be written only costs the parsing again
        record.parent.mkdir(parents=True, exist_ok=True)
        replace_file(record, lambda part: part.write_text(names, encoding="utf-8"))
    except OSError:
        pass
    return files


def _sources_digest(slave_file: Path, package_dir: Path) -> str:
    """sha256 of the slave's bytes and of every module of the package, by its name in the package."""
    h = hashlib.sha256(slave_file.read_bytes())
    for path in sorted(package_dir.rglob("*.py")):
        data = path.read_bytes()
        h.update(path.relative_to(package_dir).as_posix().encode() + b"\0" + len(data).to_bytes(8, "little") + data)
    return h.hexdigest()
