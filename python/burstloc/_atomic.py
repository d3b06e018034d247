"""One atomic writer for every file burstloc writes.

A file is written to a temporary file in the target's directory, flushed to disk, then moved
over the target with ``os.replace``: a reader sees the old file or the new one, never a partial
one, and a failed or interrupted write leaves the old file untouched. The new file keeps the
old one's permissions, or gets those of an ordinary new file (``0o666`` less the umask).
JSON is written with ``allow_nan=False``: a NaN or an infinity is refused (a ``ValueError``),
never written.
"""

from __future__ import annotations

import json
import os
import stat
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np

__all__ = ["atomic_write", "write_bytes", "write_json", "write_npz", "write_text"]


def atomic_write(path: str | os.PathLike[str], write: Callable[[IO[bytes]], None]) -> Path:
    """Call ``write`` on a temporary binary file beside ``path``, then move it over ``path``.

    The parent directory is created if missing. On any error (or interruption) the temporary
    file is removed and ``path`` is left as it was.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _mode_for(target))
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return target


def _mode_for(target: Path) -> int:
    """The permissions the written file gets: the old file's, else an ordinary new file's."""
    try:
        return stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        mask = os.umask(0)
        os.umask(mask)
        return 0o666 & ~mask


def write_bytes(path: str | os.PathLike[str], data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""

    def write(f: IO[bytes]) -> None:
        f.write(data)

    return atomic_write(path, write)


def write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return write_bytes(path, text.encode("utf-8"))


def write_json(path: str | os.PathLike[str], document: Any, *, indent: int | None = 2) -> Path:
    """Write ``document`` as JSON to ``path`` atomically.

    Raises:
        ValueError: the document holds a NaN or an infinity (nothing is written).
    """
    text = json.dumps(document, indent=indent, allow_nan=False)
    return write_text(path, text + "\n")


def write_npz(path: str | os.PathLike[str], arrays: Mapping[str, np.ndarray]) -> Path:
    """Write ``arrays`` to an ``.npz`` file atomically."""
    return atomic_write(path, lambda f: np.savez(f, **arrays))
