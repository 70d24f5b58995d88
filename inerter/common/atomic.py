"""Files written in one step, for processes that read them meanwhile (test workers, sweep workers,
a second build of the same FMU, kernels' cache copies)."""
from __future__ import annotations

import os
from pathlib import Path


def replace_file(target: Path, fill) -> None:
    """Put a file at `target` in one step: `fill(part)` writes it beside `target` (same folder, so
    the rename cannot cross file systems), then it is renamed over it, so that a reader sees the
    old file or the new one, never a part."""
    target = Path(target)
    part = target.with_name(f".{target.name}.{os.getpid()}.part")
    fill(part)
    os.replace(part, target)
