"""`burstloc calibrate` as a user runs it: what it says on stderr."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

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


def test_calibrate_ends_with_a_summary_an_engineer_checks(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from burstloc.cli import main
    from burstloc.localize.config import Calibration

    network = write_tiny(tmp_path / "tiny.inp")
    owned = tmp_path / "owned.txt"
    owned.write_text("J2, J3\nJ4  # the end of the line\n")
    out = tmp_path / "cal.json"
    argv = ["calibrate", str(network), "--out", str(out), "--capture-interval", "0.2", "2"]
    assert main([*argv, "--meters", str(owned), "--false-alarm-rate", "0.05"]) == 0
    lines = capsys.readouterr().out.splitlines()
    config = Calibration.load(out)
    assert config.meters == ("J2", "J3", "J4")  # the file's order
    assert lines[0] == (
        f"configuration 'tiny-calibrated': 3 meters of {network} (['J2', 'J3', 'J4']), "
        "sensor noise 0.01 m, signatures epanet"
    )
    for line, item in zip(lines[1:3], config.intervals, strict=True):
        low, high = min(item.cusum_threshold.values()), max(item.cusum_threshold.values())
        cusum = f"{low:.3g} m" if low == high else f"{low:.3g}-{high:.3g} m"
        assert line.startswith(f"  capture {item.capture_interval:g} s: CUSUM threshold {cusum}")
        assert f"every {item.localization_interval} readings" in line
    assert lines[3].startswith(
        "expected false alarms: 0.05 per meter per hour, 3.6 a day over the 3 meters"
    )
    assert lines[4].startswith("calibrated in ") and lines[4].endswith(f" s; wrote {out}")


def test_the_timing_tolerances_are_stored_and_checked_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from burstloc.cli import main
    from burstloc.constants import CLOCK_TOLERANCE, WAVE_SPEED_TOLERANCE
    from burstloc.localize.config import Calibration

    network = write_tiny(tmp_path / "tiny.inp")
    out = tmp_path / "cal.json"
    argv = ["calibrate", str(network), "--out", str(out), "--capture-interval", "0.2"]
    assert main(argv) == 0
    model = Calibration.load(out).model
    assert (model.wave_speed_tolerance, model.clock_tolerance) == (
        WAVE_SPEED_TOLERANCE,
        CLOCK_TOLERANCE,
    )
    assert main([*argv, "--wave-speed-tolerance", "0.12", "--clock-tolerance", "0.005"]) == 0
    model = Calibration.load(out).model
    assert (model.wave_speed_tolerance, model.clock_tolerance) == (0.12, 0.005)
    capsys.readouterr()
    out.unlink()
    assert main([*argv, "--wave-speed-tolerance", "1.5"]) == 2
    assert "wave_speed_tolerance" in capsys.readouterr().err and not out.exists()
