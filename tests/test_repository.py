"""The repository's tracked files: no binary file that nobody declared (a scratch file of EPANET's,
an output left by a test or a benchmark, committed by mistake)."""

from __future__ import annotations

import fnmatch
import subprocess

from conftest import REPO

#: Where binary files belong (``git ls-files`` paths, :mod:`fnmatch` patterns): the networks,
#: the documentation's images and the study's plots, the detectors' golden snapshots (CBOR),
#: TSNet's reference heads.
DECLARED = (
    "networks/*",
    "docs/img/*",
    "docs/study/*.png",
    "crates/cpd-core/tests/data/snapshots/*.cbor",
    "tests/sim/tsnet_reference.npz",
)


def _tracked() -> list[str]:
    listed = subprocess.run(
        ["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True
    ).stdout
    return [name.decode() for name in listed.split(b"\0") if name]


def _binary(path: str) -> bool:
    """Whether a tracked file holds a NUL byte (text files never do); a file deleted from the
    working tree and not yet from the index is not there to hold one."""
    try:
        return b"\0" in (REPO / path).read_bytes()
    except FileNotFoundError:
        return False


def test_every_binary_file_in_the_tree_is_declared() -> None:
    tracked = _tracked()
    assert "README.md" in tracked and "python/burstloc/network.py" in tracked
    binary = [path for path in tracked if _binary(path)]
    assert binary, "the declared binaries (the snapshots, the images) are found"
    stray = [p for p in binary if not any(fnmatch.fnmatch(p, d) for d in DECLARED)]
    assert stray == [], f"binary files outside {DECLARED}: {stray}"


def test_each_declared_place_holds_a_binary_file() -> None:
    # a declaration that matches nothing is stale (the file moved): say so, not nothing
    binary = [path for path in _tracked() if _binary(path)]
    for declared in DECLARED[1:]:  # networks/ holds text INP files only, so far
        assert any(fnmatch.fnmatch(p, declared) for p in binary), declared
