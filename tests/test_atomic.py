"""burstloc._atomic: the one atomic writer (old file intact on failure, no NaN in JSON)."""

from __future__ import annotations

import errno
import gc
import io
import json
import math
import re
import sys
from pathlib import Path
from typing import IO, Any

import numpy as np
import pytest

from burstloc import _atomic
from burstloc._atomic import atomic_write, check_output, write_json, write_npz, write_text
from burstloc.exceptions import OutputError


def test_interrupted_write_leaves_no_entry_and_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "d" / "entry.npz"
    write_npz(target, {"x": np.zeros(3)})
    before = target.read_bytes()

    def killed(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt  # the run is killed mid-write

    monkeypatch.setattr(np.lib.format, "write_array", killed)
    with pytest.raises(KeyboardInterrupt):
        write_npz(target, {"x": np.ones(3)})
    assert target.read_bytes() == before  # the old entry is intact
    assert sorted(p.name for p in target.parent.iterdir()) == ["entry.npz"]
    with pytest.raises(KeyboardInterrupt):
        write_npz(tmp_path / "d" / "new.npz", {"x": np.ones(3)})
    assert not (tmp_path / "d" / "new.npz").exists()


def test_json_refuses_nan_and_infinity_and_keeps_the_old_file(tmp_path: Path) -> None:
    target = tmp_path / "config.json"
    write_json(target, {"threshold": 0.5})
    before = target.read_bytes()
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(OutputError, match=r"config\.json: field threshold is (NaN|-?Infinity)"):
            write_json(target, {"threshold": bad})
        assert target.read_bytes() == before
    with pytest.raises(OutputError, match=r"field runs\[1\]\.delays\.J2 is NaN"):
        write_json(target, {"runs": [{"a": 1.0}, {"delays": {"J1": 2.0, "J2": math.nan}}]})
    assert json.loads(before) == {"threshold": 0.5}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["config.json"]


def test_text_replaces_the_whole_file_and_creates_the_directory(tmp_path: Path) -> None:
    target = tmp_path / "new" / "report.md"
    write_text(target, "a long first version\n")
    write_text(target, "short\n")
    assert target.read_text() == "short\n"


def test_permissions_are_an_ordinary_files_or_the_old_ones(tmp_path: Path) -> None:
    import os

    mask = os.umask(0o022)
    try:
        fresh = write_text(tmp_path / "fresh.txt", "x")
        assert fresh.stat().st_mode & 0o777 == 0o644  # mkstemp alone would give 0o600
        kept = tmp_path / "kept.txt"
        kept.write_text("old")
        kept.chmod(0o640)
        write_text(kept, "new")
        assert kept.stat().st_mode & 0o777 == 0o640
    finally:
        os.umask(mask)


def test_check_output_names_the_path_and_the_reason(tmp_path: Path) -> None:
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    assert check_output(tmp_path / "new.json") == tmp_path / "new.json"
    assert check_output(tmp_path / "a" / "b", directory=True) == tmp_path / "a" / "b"
    assert check_output(tmp_path / "adir", directory=True) == tmp_path / "adir"
    cases = [
        (tmp_path / "missing" / "x.json", False, "directory .*missing does not exist"),
        (tmp_path / "adir", False, "is a directory"),
        (tmp_path / "afile" / "x.json", False, ".*afile is not a directory"),
        (tmp_path / "afile" / "sub", True, ".*afile is not a directory"),
        (tmp_path / "afile", True, ".*afile is not a directory"),
        (Path("/proc/x.json"), False, "directory /proc is not writable"),
        (Path("/proc/new/dir"), True, "directory /proc is not writable"),
    ]
    for path, directory, reason in cases:
        with pytest.raises(OutputError, match=f"cannot write {re.escape(str(path))}: {reason}"):
            check_output(path, directory=directory)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["adir", "afile"]  # nothing left


def test_a_failing_write_is_an_output_error_and_keeps_the_old_file(tmp_path: Path) -> None:
    target = tmp_path / "r.txt"
    write_text(target, "good\n")

    def full_disk(f: IO[bytes]) -> None:
        f.write(b"partial")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OutputError, match=r"cannot write .*r\.txt: No space left on device"):
        atomic_write(target, full_disk)
    assert target.read_text() == "good\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.txt"]


def test_a_full_disk_during_an_npz_write_closes_the_archive(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The write fails with ENOSPC midway: one OutputError, and nothing left for the garbage
    collector to trip on (an unclosed archive writing into the closed file)."""
    target = tmp_path / "s.npz"
    write_npz(target, {"x": np.zeros(3)})
    before = target.read_bytes()

    class FullDisk(io.FileIO):
        def write(self, b: Any) -> int:
            if self.tell() + len(b) > 4096:
                raise OSError(errno.ENOSPC, "No space left on device")
            return super().write(b)

    unraisable: list[Any] = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    monkeypatch.setattr(_atomic.os, "fdopen", lambda fd, mode: FullDisk(fd, mode))
    with pytest.raises(OutputError, match=r"cannot write .*s\.npz: No space left on device"):
        write_npz(target, {"a": np.ones(10), "b": np.arange(100_000.0)})
    gc.collect()
    assert [str(u.exc_value) for u in unraisable] == []
    assert target.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.npz"]
