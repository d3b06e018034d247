"""burstloc.inp: INP files read as text, without WNTR."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from burstloc import inp
from burstloc.exceptions import ConfigError, NetworkError
from conftest import PAPER15, write_tiny


def test_network_hash_is_the_files_sha256(tmp_path: Path) -> None:
    import hashlib

    path = write_tiny(tmp_path / "a.inp")
    digest = inp.network_hash(path)
    assert digest == "sha256:" + hashlib.sha256(path.read_bytes()).hexdigest()
    assert inp.network_hash(write_tiny(tmp_path / "b.inp", head=61.0)) != digest
    with pytest.raises(NetworkError, match="cannot read network file"):
        inp.network_hash(tmp_path / "missing.inp")


def test_choose_pipes_defaults_to_every_pipe_and_checks_a_selection() -> None:
    known = inp.pipe_names_in_file(PAPER15)
    assert inp.choose_pipes(known, None, PAPER15) == known
    assert inp.choose_pipes(known, ["7", "P1"], PAPER15) == ["7", "P1"]
    with pytest.raises(NetworkError, match=r"unknown pipe\(s\) \['P99'\] in .*paper15.inp"):
        inp.choose_pipes(known, ["7", "P99"], PAPER15)
    with pytest.raises(NetworkError, match="no pipes to burst"):
        inp.choose_pipes(known, [], PAPER15)
    with pytest.raises(ConfigError, match="listed more than once"):
        inp.choose_pipes(known, ["7", "7"], PAPER15)


def test_reading_a_file_as_text_loads_no_wntr() -> None:
    code = (
        "import sys; from burstloc import inp; "
        f"print(len(inp.pipe_names_in_file({str(PAPER15)!r}))); "
        "print(sorted(m for m in sys.modules if m.split('.')[0] == 'wntr'))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split("\n")[:2] == ["25", "[]"]
