"""A content-addressed cache of NumPy arrays on disk.

An entry's key is the SHA-256 of everything that determines it: a namespace, the parameters,
the bytes of the input files and the versions of burstloc, TSNet, WNTR and NumPy
(:func:`cache_key`). Entries are ``.npz`` files written atomically (a temporary file in the
same directory, then ``os.replace``): a killed run never leaves a partial entry, and readers
never see one.

Entries are verified on read: each holds the SHA-256 of its arrays (names, dtypes, shapes and
bytes, :func:`arrays_sha256`) and only finite floating-point values. An entry that cannot be
read, whose checksum does not match or that holds a NaN or an infinity is corrupt: it is
reported on stderr (:func:`drop_corrupt`), deleted, and counts as a miss, so the caller
recomputes and stores it again.

Location: the ``directory`` argument, else ``$BURSTLOC_CACHE_DIR``, else the user's cache
directory (``platformdirs.user_cache_dir("burstloc")``, e.g. ``~/.cache/burstloc`` on Linux).
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import sys
import zipfile
from collections.abc import Iterable, Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np
import platformdirs

from burstloc._atomic import write_npz
from burstloc.inp import network_hash
from burstloc.network import Network

__all__ = [
    "ENV_VAR",
    "DiskCache",
    "arrays_sha256",
    "cache_key",
    "default_cache_dir",
    "drop_corrupt",
    "file_sha256",
    "network_cache_key",
    "package_versions",
]

#: Environment variable that overrides the default cache directory.
ENV_VAR = "BURSTLOC_CACHE_DIR"
#: Packages whose versions are part of every key.
KEY_PACKAGES = ("burstloc", "tsnet", "wntr", "numpy")


def default_cache_dir() -> Path:
    """Return ``$BURSTLOC_CACHE_DIR`` if set, else the user's cache directory for burstloc."""
    env = os.environ.get(ENV_VAR)
    return Path(env).expanduser() if env else Path(platformdirs.user_cache_dir("burstloc"))


@functools.lru_cache(maxsize=1)
def package_versions() -> dict[str, str]:
    """Return the installed versions of burstloc, tsnet, wntr and numpy (without importing)."""
    versions = {}
    for name in KEY_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "not-installed"
    return versions


def file_sha256(path: str | os.PathLike[str]) -> str:
    """Return the hex SHA-256 of a file's bytes (:func:`burstloc.inp.network_hash`: read once
    per process while the file's size and times are unchanged).

    Raises:
        NetworkError: the file is missing or cannot be read.
    """
    return network_hash(path).removeprefix("sha256:")


def cache_key(
    namespace: str,
    parameters: Mapping[str, Any],
    files: Iterable[str | os.PathLike[str] | Network] = (),
) -> str:
    """Return the hex SHA-256 key of an entry.

    Args:
        namespace: what kind of entry (with a schema version), e.g. ``"burst-scenario/1"``.
        parameters: every parameter that changes the entry; JSON-serialisable.
        files: input files, hashed by content (not by name); a network read already gives its
            fingerprint (:attr:`burstloc.network.Network.hash`).
    """
    document = {
        "namespace": namespace,
        "parameters": dict(parameters),
        "files": [
            f.hash.removeprefix("sha256:") if isinstance(f, Network) else file_sha256(f)
            for f in files
        ],
        "versions": package_versions(),
    }
    text = json.dumps(document, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def network_cache_key(namespace: str, parameters: Mapping[str, Any], network: str) -> str:
    """:func:`cache_key` of a scenario on one network file.

    Raises:
        NetworkError: the network file does not exist.
    """
    return cache_key(namespace, parameters, [network])


def arrays_sha256(arrays: Mapping[str, np.ndarray]) -> str:
    """The SHA-256 of named arrays: names, dtypes, shapes and bytes, in name order."""
    digest = hashlib.sha256()
    for name in sorted(arrays):
        values = np.ascontiguousarray(arrays[name])
        header = json.dumps([name, values.dtype.str, list(values.shape)])
        digest.update(header.encode("utf-8"))
        digest.update(values.tobytes())
    return digest.hexdigest()


def drop_corrupt(path: str | os.PathLike[str], reason: str) -> None:
    """Report a corrupt cache entry on stderr and delete it (it is then recomputed)."""
    print(
        f"burstloc: warning: cache entry {os.fspath(path)} is corrupt ({reason}); dropped, "
        "recomputing",
        file=sys.stderr,
    )
    try:
        Path(path).unlink(missing_ok=True)
    except OSError as exc:
        print(
            f"burstloc: warning: cannot delete {os.fspath(path)}: {exc.strerror}", file=sys.stderr
        )


class DiskCache:
    """Arrays stored under content-addressed keys in a directory.

    Args:
        directory: where entries live; default :func:`default_cache_dir`.
    """

    #: Bumped when the on-disk layout changes (v2: entries carry a checksum).
    LAYOUT = "v2"
    #: The array holding an entry's checksum.
    CHECKSUM = "__sha256__"

    def __init__(self, directory: str | os.PathLike[str] | None = None) -> None:
        base = Path(directory).expanduser() if directory is not None else default_cache_dir()
        self.directory: Path = base

    def __repr__(self) -> str:
        return f"DiskCache({str(self.directory)!r})"

    def path_for(self, key: str) -> Path:
        """Return the file an entry with this key lives in."""
        return self.directory / self.LAYOUT / key[:2] / f"{key}.npz"

    def get(self, key: str) -> dict[str, np.ndarray] | None:
        """Return the entry's arrays, or ``None`` if absent or corrupt (a corrupt entry is
        reported on stderr and deleted: module docstring)."""
        path = self.path_for(key)
        try:
            with np.load(path, allow_pickle=False) as data:
                arrays = {name: data[name] for name in data.files}
        except FileNotFoundError:
            return None
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            drop_corrupt(path, f"unreadable: {exc}")
            return None
        stored = arrays.pop(self.CHECKSUM, None)
        if stored is None or str(stored[()]) != arrays_sha256(arrays):
            drop_corrupt(path, "its checksum does not match its arrays")
            return None
        for name, array in arrays.items():
            if array.dtype.kind in "fc" and not np.isfinite(array).all():
                drop_corrupt(path, f"array {name!r} holds NaN or infinite values")
                return None
        return arrays

    def put(self, key: str, arrays: Mapping[str, np.ndarray]) -> Path:
        """Store an entry (with its checksum) atomically and return its path.

        Raises:
            ValueError: an array named like the checksum, or holding NaN or infinite values.
        """
        if self.CHECKSUM in arrays:
            raise ValueError(f"{self.CHECKSUM!r} is reserved for the entry's checksum")
        for name, array in arrays.items():
            values = np.asarray(array)
            if values.dtype.kind in "fc" and not np.isfinite(values).all():
                raise ValueError(f"array {name!r} holds NaN or infinite values; not cached")
        checksum = np.asarray(arrays_sha256(arrays))
        return write_npz(self.path_for(key), {**arrays, self.CHECKSUM: checksum})

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self.path_for(key).is_file()
