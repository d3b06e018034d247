"""docs/api.md's monitor example runs as written and names the burst pipe."""

from __future__ import annotations

import contextlib
import io
import os
import re
from pathlib import Path

import pytest

from burstloc.cli import main

API_PAGE = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def _example() -> str:
    match = re.search(r"<!-- example: monitor -->\n```python\n(.*?)```", API_PAGE.read_text(), re.S)
    assert match, "docs/api.md has no monitor example"
    return match.group(1)


def test_the_monitor_example_runs_and_names_the_burst_pipe(
    paper15: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Before, the documented way (ReadingStream's windows into BurstMonitor.push) raised
    # AttributeError, and the way that worked (StepFeed) was not public.
    (tmp_path / "networks").mkdir()
    (tmp_path / "networks" / "paper15.inp").write_bytes(paper15.read_bytes())
    monkeypatch.chdir(tmp_path)
    network = os.path.join("networks", "paper15.inp")
    assert main(["calibrate", network, "--out", "paper15.json", "--capture-interval", "0.2"]) == 0
    simulate = ["simulate", network, "--pipe", "P7", "--duration", "14", "--quiet"]
    assert main([*simulate, "--capture-interval", "0.2", "--feed", "feed.csv"]) == 0
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(_example(), str(API_PAGE), "exec"), {})
    (line,) = out.getvalue().splitlines()
    time, pipes = line.split(" ", 1)
    assert pipes.startswith("['P7'") and 10.0 < float(time) < 12.0, line


def test_a_window_is_refused_by_name(paper15: Path, tmp_path: Path) -> None:
    import numpy as np

    import burstloc
    from burstloc.experiments.calibrate import calibrate
    from burstloc.readings import Window

    config = calibrate(paper15, capture_intervals=(0.2,))
    monitor = burstloc.BurstMonitor(paper15, config, capture_interval=0.2)
    window = Window(0, monitor.meters, np.zeros(1), np.zeros((1, len(monitor.meters))), 1, 0)
    with pytest.raises(burstloc.InputError, match=r"complete time step .* got Window"):
        monitor.push(window)  # type: ignore[arg-type]
