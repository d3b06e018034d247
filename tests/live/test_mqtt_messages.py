"""``burstloc monitor --mqtt``'s operational messages, against a real Mosquitto broker: the
connection said when it is up, and a SIGTERM that is not taken for a lost broker."""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from mosquitto import broker

from burstloc.experiments.calibrate import calibrate


def test_connection_up_is_said_and_sigterm_is_not_a_lost_broker(tiny: Path, tmp_path: Path) -> None:
    cfg = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01).save(tmp_path / "c.json")
    (tmp_path / "mosquitto").mkdir()
    with broker(tmp_path / "mosquitto") as port:
        argv = [sys.executable, "-m", "burstloc", "monitor", str(tiny), "--config", str(cfg)]
        argv += ["--capture-interval", "0.2", "--mqtt", f"127.0.0.1:{port}"]
        argv += ["--topic", "plant/readings/#"]
        monitor = subprocess.Popen(
            argv, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True
        )
        lines: queue.Queue[str] = queue.Queue()
        assert monitor.stderr is not None
        reader = threading.Thread(target=lambda: [lines.put(x) for x in monitor.stderr or []])
        reader.start()
        said: list[str] = []
        deadline = time.monotonic() + 60  # waits for a line; never asserts on a duration
        try:
            while not any("connected to broker" in line for line in said):
                assert time.monotonic() < deadline, f"never said it connected: {said}"
                try:
                    said.append(lines.get(timeout=1))
                except queue.Empty:
                    continue
        finally:
            monitor.send_signal(signal.SIGTERM)
            monitor.wait(timeout=30)
            reader.join(timeout=30)
        while not lines.empty():
            said.append(lines.get())
    assert monitor.returncode == 0, said
    up = f"burstloc monitor: connected to broker 127.0.0.1:{port}, subscribed to plant/readings/#"
    assert said[0].rstrip("\n") == up, said
    assert not [line for line in said if "lost broker" in line], said  # was said before SIGTERM
    assert said[-1].startswith("burstloc monitor: stopped by SIGTERM"), said
