"""burstloc._atomic: the one atomic writer (old file intact on failure, no NaN in JSON)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from burstloc._atomic import write_json, write_npz, write_text


def test_interrupted_write_leaves_no_entry_and_no_temporary(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    target = tmp_path / "d" / "entry.npz"
    write_npz(target, {"x": np.zeros(3)})
    before = target.read_bytes()

    def killed(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt  # the run is killed mid-write

    monkeypatch.setattr(np, "savez", killed)
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
        with pytest.raises(ValueError):
            write_json(target, {"threshold": bad})
        assert target.read_bytes() == before
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
