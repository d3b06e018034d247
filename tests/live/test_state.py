"""burstloc.live.state: the monitor survives kill -9 and SIGTERM; a foreign state is refused."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from live_feed import burst_steps, readings

from burstloc.exceptions import ConfigError
from burstloc.experiments.calibrate import calibrate
from burstloc.live.state import StateFile, identity
from burstloc.localize.config import Calibration

PIPE = "C"
#: Seconds after which a test that waits for the monitor gives up: a guard against a hang, far
#: beyond what the slowest machine needs (nothing here is timed).
HANG_GUARD = 600


@pytest.fixture(scope="module")
def setup(tiny: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    config = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)
    folder = tmp_path_factory.mktemp("state")
    steps = burst_steps(tiny, config.meters, PIPE, sigma=0.002)
    lines = [f"{r.timestamp!r},{r.meter},{r.value!r}\n" for r in readings(steps, config.meters)]
    return {"config": config, "path": config.save(folder / "tiny.json"), "lines": lines}


def _start(tiny: Path, setup: dict[str, object], state: Path) -> subprocess.Popen[str]:
    argv = [sys.executable, "-m", "burstloc", "monitor", str(tiny), "--config"]
    argv += [str(setup["path"]), "--capture-interval", "0.2", "--localizer", "signature"]
    argv += ["--state", str(state), "--save-every", "0.1", "--health-every", "0"]
    return subprocess.Popen(
        argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )


def _saved(state: Path) -> dict[str, object] | None:
    try:
        return json.loads(state.read_text())["state"]
    except (OSError, ValueError):
        return None


def _saved_up_to(state: Path, timestamp: float) -> bool:
    """Whether the state saved in ``state`` has taken in the readings up to ``timestamp``."""
    saved = _saved(state)
    newest = None if saved is None else saved["stream"]["newest"]  # type: ignore[index]
    return newest is not None and newest * 0.2 >= timestamp - 1e-9


def _decisions(out: str) -> list[dict[str, object]]:
    records = [json.loads(line) for line in out.splitlines()]
    return [{k: r[k] for k in ("time", "first_alarm", "pipes")} for r in records]


def test_kill_9_mid_burst_then_restart_gives_the_same_decision(
    tiny: Path, setup: dict[str, object], tmp_path: Path
) -> None:
    lines: list[str] = setup["lines"]  # type: ignore[assignment]
    whole = _start(tiny, setup, tmp_path / "whole.json")
    out, err = whole.communicate("".join(lines), timeout=HANG_GUARD)
    expected = _decisions(out)
    assert len(expected) == 1 and expected[0]["pipes"][0]["pipe"] == PIPE, err

    state = tmp_path / "state.json"
    first = _start(tiny, setup, state)
    assert first.stdin is not None
    cut = next(i for i, line in enumerate(lines) if float(line.split(",")[0]) > 90.0)
    for k in range(0, cut, 200):  # in pieces, so that the state is saved as readings flow
        first.stdin.write("".join(lines[k : min(k + 200, cut)]))
        first.stdin.flush()
        time.sleep(0.15)
    hang = time.monotonic() + HANG_GUARD
    while True:  # wait for a saved state with the burst detected and its decision pending
        saved = _saved(state)
        if saved is not None and saved["monitor"]["due"] is not None:  # type: ignore[index]
            break
        assert time.monotonic() < hang, "no saved state with a pending decision"
        time.sleep(0.1)
    first.kill()  # SIGKILL: no chance to save anything more
    first.wait(timeout=30)
    assert first.returncode == -signal.SIGKILL
    assert first.stdout is not None and first.stdout.read() == ""  # not decided yet

    saved = _saved(state)
    assert saved is not None
    newest = 0.2 * saved["stream"]["newest"]  # type: ignore[index]
    rest = [line for line in lines if float(line.split(",")[0]) > newest - 1e-9]
    second = _start(tiny, setup, state)  # the feed goes on from the last saved step
    out, err = second.communicate("".join(rest), timeout=HANG_GUARD)
    assert second.returncode == 0, err
    assert _decisions(out) == expected
    assert f"resumed from state file {state}" in err


def test_sigterm_saves_the_state_and_exits_cleanly(
    tiny: Path, setup: dict[str, object], tmp_path: Path
) -> None:
    lines: list[str] = setup["lines"]  # type: ignore[assignment]
    state = tmp_path / "state.json"
    proc = _start(tiny, setup, state)
    assert proc.stdin is not None
    proc.stdin.write("".join(lines[:4000]))
    proc.stdin.flush()
    last = float(lines[3999].split(",")[0])
    hang = time.monotonic() + HANG_GUARD
    while not _saved_up_to(state, last):  # every reading sent has been taken in
        assert proc.poll() is None and time.monotonic() < hang, "the monitor never saved"
        time.sleep(0.1)
    state.unlink()  # so that what is checked below is the state saved on SIGTERM
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=HANG_GUARD)
    assert proc.returncode == 0, err
    assert "stopped by SIGTERM; state saved to" in err
    saved = _saved(state)
    assert saved is not None
    newest = saved["stream"]["newest"]  # type: ignore[index]
    assert newest is not None and newest * 0.2 == pytest.approx(float(lines[3999].split(",")[0]))


def test_a_state_of_another_setup_is_refused_by_name(
    setup: dict[str, object], tmp_path: Path
) -> None:
    config: Calibration = setup["config"]  # type: ignore[assignment]
    ident = identity(
        config,
        capture_interval=0.2,
        detector="cusum",
        localizer="fused",
        meter_model="instantaneous",
    )
    path = tmp_path / "s.json"
    assert StateFile(path, ident).load() is None
    StateFile(path, ident).save({"x": 1})
    assert StateFile(path, ident).load() == {"x": 1}
    with pytest.raises(ConfigError, match=r"another network or configuration \(localizer"):
        StateFile(path, {**ident, "localizer": "arrival"}).load()
    with pytest.raises(ConfigError, match="network_hash"):
        StateFile(path, {**ident, "network_hash": "sha256:0"}).load()
    path.write_text('{"format": "burstloc-monitor-state/0"}')
    with pytest.raises(ConfigError, match="has format 'burstloc-monitor-state/0'"):
        StateFile(path, ident).load()
    path.write_text("{")
    with pytest.raises(ConfigError, match="is not JSON"):
        StateFile(path, ident).load()
    assert os.path.exists(path)
