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
    with pytest.raises(NetworkError, match="network file not found"):
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


def test_junctions_in_file_are_wntrs_and_meters_must_be_among_them(tmp_path: Path) -> None:
    from burstloc.network import junction_names, load_network

    for network in (write_tiny(tmp_path / "tiny.inp"), PAPER15):
        junctions = inp.junction_names_in_file(network)
        assert junctions == junction_names(load_network(network))
        assert inp.check_meters(junctions[:2], junctions, network) == junctions[:2]
    tiny = tmp_path / "tiny.inp"
    unknown = r"2 meter\(s\) \['R1', 'Z'\] are not junctions of .*tiny"
    with pytest.raises(NetworkError, match=unknown):
        inp.check_meters(["J1", "R1", "Z"], inp.junction_names_in_file(tiny), tiny)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda t: "", r"no junctions"),
        (lambda t: "[JUNCTIONS]\n[RESERVOIRS]\n R1 60\n[END]\n", r"no junctions"),
        (
            lambda t: t.replace("[RESERVOIRS]\n R1   60.0\n", "").replace(
                " A    R1     J1     300     300       100        0          Open\n", ""
            ),
            r"no source: the network needs a reservoir or a tank",
        ),
        (
            lambda t: t.replace(" A    R1     J1     300", " A    R1     J1     -300"),
            r"tiny\.inp:16: pipe 'A' has length -300 \(must be > 0\)",
        ),
        (
            lambda t: t.replace(" B    J1     J2     200     200", " B    J1     J2     200     0"),
            r"tiny\.inp:17: pipe 'B' has diameter 0 \(must be > 0\)",
        ),
        (
            lambda t: t.replace(" C    J1     J3     250", " C    J1     J3     nan"),
            r"tiny\.inp:18: pipe 'C' has length nan \(must be > 0\)",
        ),
    ],
)
def test_a_network_without_junctions_or_source_or_with_bad_pipes_is_refused(
    tmp_path: Path, edit, message: str
) -> None:  # type: ignore[no-untyped-def]
    path = write_tiny(tmp_path / "tiny.inp")
    path.write_text(edit(path.read_text()))
    with pytest.raises(NetworkError, match=message):
        inp.pipe_names_in_file(path)


def test_a_file_that_is_not_utf8_is_named_with_its_line(tmp_path: Path) -> None:
    path = write_tiny(tmp_path / "tiny.inp")
    path.write_bytes(path.read_bytes().replace(b" J3   0      5", b" J\xe93   0      5"))
    with pytest.raises(NetworkError, match=r"tiny\.inp:8: not UTF-8 text \(byte 0xe9\)"):
        inp.pipe_names_in_file(path)


def test_names_read_once_follow_the_file_content(tmp_path: Path) -> None:
    path = write_tiny(tmp_path / "tiny.inp")
    junctions, pipes = inp.junction_names_in_file(path), inp.pipe_names_in_file(path)
    junctions.append("changed by the caller")  # a fresh list each time
    assert inp.junction_names_in_file(path) == junctions[:-1]
    path.write_text(
        path.read_text(encoding="utf-8").replace(" J4 ", " J9 "), encoding="utf-8"
    )  # the same path, another content
    assert "J9" in inp.junction_names_in_file(path)
    assert inp.pipe_names_in_file(path) == pipes
    path.write_text("[JUNCTIONS]\n J1 abc\n", encoding="utf-8")
    for _ in range(2):  # a malformed file is refused each time, naming its line
        with pytest.raises(NetworkError, match=r"tiny\.inp:2"):
            inp.junction_names_in_file(path)
