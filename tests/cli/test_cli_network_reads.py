"""A command reads its network file once: ``burstloc place --compare`` and ``burstloc evaluate``
open the INP file exactly once in their process (at the command's edge,
:func:`burstloc.network.read_network`); every floor below takes the loaded
:class:`~burstloc.network.Network`, and the simulations, which name the file in their scenario
(a path is what a worker process is sent), find it read already (once per process).

Every open of the file is counted, whoever opens it (``sys.addaudithook``'s ``open`` event:
``open``, ``io.open``, ``os.open``, ``Path.read_bytes``...), so a floor that reads the file
again, hashes it again or lets WNTR read it counts. Nothing else reads it: WNTR reads a
temporary copy of its hydraulic text, TSNet and EPANET the files WNTR writes. The simulations
run in this process (``--workers 1``); the network is the tiny one (``conftest.TINY_INP``),
written to a fresh path (a file this process never read) an hour before the command runs.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
import traceback
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from burstloc.cli import main
from conftest import write_tiny

#: The real path watched and the stacks that opened it.
_WATCHED: dict[str, list[str]] = {}


def _audit(event: str, args: tuple[Any, ...]) -> None:
    if event != "open" or not _WATCHED or not args:
        return
    target = args[0]
    if isinstance(target, bytes):
        target = os.fsdecode(target)
    if not isinstance(target, (str, os.PathLike)):
        return  # a file descriptor
    opened = _WATCHED.get(os.path.realpath(target))
    if opened is not None:
        opened.append("".join(traceback.format_stack(limit=12)[:-1]))


sys.addaudithook(_audit)  # cannot be removed: it does nothing while no file is watched


@contextlib.contextmanager
def opens_of(path: Path) -> Iterator[list[str]]:
    """The stacks that open ``path`` while the block runs."""
    opened: list[str] = []
    _WATCHED[os.path.realpath(path)] = opened
    try:
        yield opened
    finally:
        _WATCHED.clear()


def _network(tmp_path: Path) -> Path:
    """The tiny network, last written an hour ago (as a network file is, not just now)."""
    path = write_tiny(tmp_path / "tiny.inp")
    hour_ago = time.time() - 3600
    os.utime(path, (hour_ago, hour_ago))
    return path


def test_place_compare_reads_the_network_once(
    tmp_path: Path, capsys: Any, monkeypatch: Any
) -> None:
    monkeypatch.setenv("BURSTLOC_CACHE_DIR", str(tmp_path / "cache"))  # every burst simulated
    path = _network(tmp_path)
    argv = ["place", str(path), "--meters", "3", "--compare", "--phases", "1", "--quiet"]
    with opens_of(path) as opened:
        assert main([*argv, "--workers", "1"]) == 0
    assert "| region | " in capsys.readouterr().out  # three placements, each evaluated
    assert len(opened) == 1, "\n".join(opened)
    assert "read_network" in opened[0]


def test_evaluate_reads_the_network_once(tmp_path: Path, capsys: Any, monkeypatch: Any) -> None:
    monkeypatch.setenv("BURSTLOC_CACHE_DIR", str(tmp_path / "cache"))  # every burst simulated
    path = _network(tmp_path)
    argv = ["evaluate", str(path), "--localizer", "fused", "--capture-interval", "0.2"]
    with opens_of(path) as opened:
        assert main([*argv, "--phases", "1", "--quiet", "--workers", "1"]) == 0
    assert "fused" in capsys.readouterr().out
    assert len(opened) == 1, "\n".join(opened)
    assert "read_network" in opened[0]


@pytest.mark.parametrize(
    "mode",
    [
        ["--meters", "2", "--compare", "--phases", "1"],
        ["--keep", "J1", "--meters", "1"],
        ["--score", "J1", "J4"],
    ],
    ids=["compare", "keep", "score"],
)
def test_place_with_wave_speeds_reads_the_network_once(
    mode: list[str], tmp_path: Path, capsys: Any, monkeypatch: Any
) -> None:
    monkeypatch.setenv("BURSTLOC_CACHE_DIR", str(tmp_path / "cache"))  # every burst simulated
    path = _network(tmp_path)
    speeds = tmp_path / "speeds.csv"
    speeds.write_text("D,250\n")
    argv = ["place", str(path), *mode, "--wave-speeds", str(speeds), "--quiet", "--workers", "1"]
    with opens_of(path) as opened:
        assert main(argv) == 0
    assert "1 of 5 pipes at their own wave speed (250 m/s)" in capsys.readouterr().out
    assert len(opened) == 1, "\n".join(opened)
    assert "read_network" in opened[0]
