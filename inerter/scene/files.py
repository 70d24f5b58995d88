"""The files a scene reads (the scene itself, ground-motion records), read with a cap on their size.

A file is read in one call of at most its limit plus one byte, so a device (``/dev/zero``), a
pipe that never ends or a file far larger than any scene or record is refused, naming its limit,
before it can fill the memory. The limits are generous for what the files hold: a scene is a few
kilobytes of TOML; a record of 1 000 000 samples (the most the reader takes) is about 40 MiB of CSV.
"""
from __future__ import annotations

from pathlib import Path

from inerter.common.errors import SceneError

MiB = 2 ** 20
#: The largest scene file read (bytes).
MAX_SCENE_BYTES = 4 * MiB
#: The largest ground-motion record read (bytes), and the most samples it may hold: each sample
#: ends an integrator step, so a record's size bounds the work of a run from below.
MAX_RECORD_BYTES = 64 * MiB
MAX_RECORD_SAMPLES = 1_000_000


def read_capped(path, limit: int, source: str, field: str, what: str) -> bytes:
    """The bytes of `path`, at most `limit` of them; a missing, unreadable or larger file is a
    SceneError naming `source`, `field` and the file (`what`: "a scene file (TOML)", ...)."""
    name = str(path)
    try:
        with open(Path(path), "rb") as fh:
            data = fh.read(limit + 1)
    except FileNotFoundError:
        raise SceneError(source, field, name, f"an existing {what}", "file not found") from None
    except IsADirectoryError:
        raise SceneError(source, field, name, what, "a folder, not a file") from None
    except OSError as exc:
        raise SceneError(source, field, name, f"a readable {what}",
                         f"cannot read: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise SceneError(source, field, name, f"{what} of at most {limit // MiB} MiB",
                         f"too large (more than {limit // MiB} MiB)")
    return data
