"""`burstloc calibrate` as a user runs it: what it says on stderr."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from conftest import write_tiny


def test_a_simulator_warning_is_said_once_per_run(tmp_path: Path) -> None:
    """WNTR warns about an unused curve each time it reads the network (here ten times: the
    calibration, then once per candidate burst position); the run says it once."""
    network = write_tiny(tmp_path / "curve.inp")
    text = network.read_text().replace("[END]", "[CURVES]\n C9   0   50\n\n[END]")
    network.write_text(text)
    out = tmp_path / "cal.json"
    done = subprocess.run(
        [sys.executable, "-m", "burstloc.cli", "calibrate", str(network), "--out", str(out)],
        capture_output=True, text=True, check=False,
        env={**os.environ, "BURSTLOC_CACHE_DIR": str(tmp_path / "cache")},  # nothing cached
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    said = [ln for ln in done.stderr.splitlines() if "Warning: Not all curves were used" in ln]
    assert len(said) == 1, done.stderr
    assert f'"{network}"' in said[0]
    assert json.loads(out.read_text())["meters"] == ["J1", "J2", "J3", "J4"]
