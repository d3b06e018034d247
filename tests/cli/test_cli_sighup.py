"""SIGHUP to a real `burstloc monitor --settings FILE` process: the reloadable settings change
between two readings, the others are named as needing a restart, the command line keeps its
own, a broken file changes nothing; the metrics count both. No timing: each step waits for the
monitor's own output."""

from __future__ import annotations

import json
import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from burstloc.experiments.calibrate import calibrate

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="no SIGHUP here")
DEADLINE = 60.0  # generous: the test waits for output, it never times it


@pytest.fixture(scope="module")
def cfg(tiny: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    config = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)
    return config.save(tmp_path_factory.mktemp("cfg") / "tiny.json")


class _Process:
    """The monitor with its records and stderr lines collected by threads."""

    def __init__(self, argv: list[str]) -> None:
        self.proc = subprocess.Popen(
            argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True, bufsize=1,
        )  # fmt: skip
        self.records: queue.Queue[dict[str, Any]] = queue.Queue()
        self.errors: queue.Queue[str] = queue.Queue()
        self.stderr: list[str] = []
        threading.Thread(target=self._out, daemon=True).start()
        threading.Thread(target=self._err, daemon=True).start()

    def _out(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.records.put(json.loads(line))

    def _err(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self.stderr.append(line)
            self.errors.put(line)

    def feed(self, start: int, stop: int) -> None:
        """Steady readings of J1..J4 for steps ``start`` to ``stop`` (0.2 s apart)."""
        rows = [f"{0.2 * k:.1f},J{j},{59.8 - 0.01 * j}" for k in range(start, stop + 1)
                for j in range(1, 5)]  # fmt: skip
        assert self.proc.stdin is not None
        self.proc.stdin.write("\n".join(rows) + "\n")
        self.proc.stdin.flush()

    def health_until(self, time_s: float) -> list[float]:
        """The times of the health records up to the one at ``time_s``."""
        times: list[float] = []
        while not times or times[-1] < time_s:
            record = self.records.get(timeout=DEADLINE)
            if record["type"] == "health":
                times.append(record["time"])
        return times

    def said(self, pattern: str) -> str:
        """The next stderr line matching ``pattern``."""
        end = time.monotonic() + DEADLINE
        while time.monotonic() < end:
            try:
                line = self.errors.get(timeout=0.5)
            except queue.Empty:
                continue
            if re.search(pattern, line):
                return line
        raise AssertionError(f"never said {pattern!r}; stderr: {''.join(self.stderr)}")


@pytest.fixture
def started() -> Iterator[list[_Process]]:
    processes: list[_Process] = []
    yield processes
    for p in processes:
        if p.proc.poll() is None:
            p.proc.kill()
        p.proc.wait(30)


def _metric(url: str, name: str) -> float:
    with urllib.request.urlopen(url + "metrics", timeout=30) as response:
        text = response.read().decode()
    return float(re.search(rf"^{re.escape(name)} (\S+)$", text, flags=re.M).group(1))  # type: ignore[union-attr]


def test_sighup_applies_what_can_change_and_names_the_rest(
    tiny: Path, cfg: Path, tmp_path: Path, started: list[_Process]
) -> None:
    settings = tmp_path / "monitor.toml"
    head = f'network = "{tiny}"\nconfig = "{cfg}"\ncapture-interval = 0.2\nreadings = "-"\n'
    settings.write_text(head + 'health-every = 10\nqueue-size = 100000\nweb = "127.0.0.1:0"\n')
    argv = [sys.executable, "-m", "burstloc", "monitor", "--settings", str(settings),
            "--save-every", "5"]  # fmt: skip
    monitor = _Process(argv)
    started.append(monitor)
    url = re.search(r"control room at (http://\S+)", monitor.said("control room at")).group(1)  # type: ignore[union-attr]
    monitor.feed(0, 300)
    assert monitor.health_until(60.0) == [0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0]

    settings.write_text(
        head + "health-every = 2\nsilent-after = 45\nqueue-size = 5\nsave-every = 1\n"
        'web = "127.0.0.1:0"\n'
    )
    os.kill(monitor.proc.pid, signal.SIGHUP)
    line = monitor.said("SIGHUP")
    assert f"re-read settings file {settings}" in line, line
    assert "health-every 10.0 -> 2.0" in line and "silent-after 30.0 -> 45.0" in line, line
    assert "changed but needs a restart: queue-size" in line, line
    assert "kept from the command line: save-every" in line, line
    monitor.feed(301, 400)  # to t = 80 s
    assert monitor.health_until(80.0) == [70.0, 72.0, 74.0, 76.0, 78.0, 80.0]  # 70: due before

    settings.write_text(head + 'health-every = "often"\n')  # broken: nothing changes
    os.kill(monitor.proc.pid, signal.SIGHUP)
    line = monitor.said("SIGHUP")
    assert "key 'health-every': want a number, got a string; nothing changed" in line, line
    monitor.feed(401, 430)
    assert monitor.health_until(86.0) == [82.0, 84.0, 86.0]
    assert _metric(url, 'burstloc_settings_reloads_total{outcome="applied"}') == 1
    assert _metric(url, 'burstloc_settings_reloads_total{outcome="refused"}') == 1

    monitor.proc.send_signal(signal.SIGTERM)
    assert monitor.proc.wait(DEADLINE) == 0
    assert "Traceback" not in "".join(monitor.stderr)
