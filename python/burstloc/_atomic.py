"""One atomic writer for every file burstloc writes.

A file is written to a temporary file in the target's directory, flushed to disk, then moved
over the target with ``os.replace``: a reader sees the old file or the new one, never a partial
one, and a failed or interrupted write leaves the old file untouched. The new file keeps the
old one's permissions, or gets those of an ordinary new file (``0o666`` less the umask).
JSON is written with ``allow_nan=False``: a NaN or an infinity is refused, naming the field,
never written. Every failure is an :class:`~burstloc.exceptions.OutputError`
(``cannot write PATH: reason``).

:func:`check_output` checks an output path before any work is done (the directory exists and
is writable, no directory where a file is expected), so a long run never ends in an unwritable
path.
"""

from __future__ import annotations

import json
import os
import stat
import tempfile
import zipfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO, Any

import numpy as np

from burstloc._validate import NPZ_DOCUMENT, NPZ_MIN_SIZE, NPZ_REFERENCE, find_non_finite
from burstloc.exceptions import OutputError

__all__ = [
    "atomic_write",
    "check_output",
    "write_bytes",
    "write_json",
    "write_json_npz",
    "write_npz",
    "write_text",
]


def _probe(directory: Path) -> None:
    """Create and remove a file in ``directory`` (OSError if that is not possible)."""
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".burstloc-probe.", suffix=".tmp")
    os.close(fd)
    os.unlink(tmp)


def check_output(path: str | os.PathLike[str], *, directory: bool = False) -> Path:
    """Check, before any work, that ``path`` can be written; return it.

    A file (``directory=False``): its directory exists and is writable, and ``path`` is not a
    directory. A directory: it is a writable directory, or it can be created (its nearest
    existing ancestor is a writable directory). Nothing is left behind.

    Raises:
        OutputError: ``cannot write PATH: reason``.
    """
    target = Path(path)

    def refuse(reason: str) -> OutputError:
        return OutputError(f"cannot write {os.fspath(path)}: {reason}")

    if directory:
        existing = target
        while not existing.exists() and existing != existing.parent:
            if existing.is_symlink():
                raise refuse(f"{existing} is a broken link")
            existing = existing.parent
        if not existing.is_dir():
            raise refuse(f"{existing} is not a directory")
    else:
        if target.is_dir():
            raise refuse("is a directory")
        existing = target.parent
        if not existing.exists():
            raise refuse(f"directory {existing} does not exist")
        if not existing.is_dir():
            raise refuse(f"{existing} is not a directory")
    try:
        _probe(existing)
    except OSError as exc:
        raise refuse(f"directory {existing} is not writable ({exc.strerror or exc})") from None
    return target


def atomic_write(path: str | os.PathLike[str], write: Callable[[IO[bytes]], None]) -> Path:
    """Call ``write`` on a temporary binary file beside ``path``, then move it over ``path``.

    The parent directory is created if missing. On any error (or interruption) the temporary
    file is removed and ``path`` is left as it was.

    Raises:
        OutputError: the file cannot be written (``cannot write PATH: reason``).
    """
    target = Path(path)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    except OSError as exc:
        raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, _mode_for(target))
        os.replace(tmp, target)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise OutputError(f"cannot write {target}: {exc.strerror or exc}") from None
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
        OutputError: the document holds a NaN or an infinity (the message names the field;
            nothing is written), or the file cannot be written.
    """
    try:
        text = json.dumps(document, indent=indent, allow_nan=False)
    except ValueError:
        field, value = find_non_finite(document)
        raise OutputError(
            f"cannot write {os.fspath(path)}: field {field} is {value} (JSON holds finite "
            "numbers only)"
        ) from None
    return write_text(path, text + "\n")


def write_npz(path: str | os.PathLike[str], arrays: Mapping[str, np.ndarray]) -> Path:
    """Write ``arrays`` to an ``.npz`` file atomically (the layout of ``np.savez``).

    The archive is closed whatever happens (``np.savez`` leaves it open when a write fails, and
    the garbage collector's late ``ZipFile.close`` then writes into the closed file: "Exception
    ignored ... seek of closed file" after the error).
    """

    def write(f: IO[bytes]) -> None:
        with zipfile.ZipFile(f, mode="w", compression=zipfile.ZIP_STORED) as archive:
            for name, array in arrays.items():
                with archive.open(f"{name}.npy", mode="w", force_zip64=True) as member:
                    np.lib.format.write_array(member, np.asanyarray(array), allow_pickle=False)

    return atomic_write(path, write)


def write_json_npz(
    path: str | os.PathLike[str], document: Any, *, min_size: int = NPZ_MIN_SIZE
) -> Path:
    """Write a JSON document as an ``.npz`` file: every list of finite floats (or rectangular
    list of such lists) with at least ``min_size`` numbers becomes a binary array, replaced in
    the document by ``{"$npz": NAME}``; the rest of the document is stored as strict JSON text
    (array ``document``: its UTF-8 bytes). :func:`burstloc._validate.read_json_npz` reads it back.

    Raises:
        OutputError: a non-finite number (named), or the file cannot be written.
    """
    arrays: dict[str, np.ndarray] = {}

    def pack(value: Any) -> Any:
        if isinstance(value, Mapping):
            return {k: pack(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            try:
                array = np.asarray(value)
            except ValueError:  # ragged
                array = None
            if (
                array is not None
                and array.dtype.kind == "f"  # floats (ints, booleans, text stay JSON)
                and array.size >= min_size
                and np.isfinite(array).all()
            ):
                name = f"a{len(arrays)}"
                arrays[name] = array.astype(np.float64)
                return {NPZ_REFERENCE: name}
            return [pack(v) for v in value]
        return value

    packed = pack(document)
    try:
        text = json.dumps(packed, allow_nan=False, separators=(",", ":"))
    except ValueError:
        field, value = find_non_finite(document)
        raise OutputError(
            f"cannot write {os.fspath(path)}: field {field} is {value} (numbers must be finite)"
        ) from None
    utf8 = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    return write_npz(path, {**arrays, NPZ_DOCUMENT: utf8})
