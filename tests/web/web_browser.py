"""The control-room tests' real parts: Debian's Chromium driven by Selenium, a real
``burstloc monitor --web`` process fed on its stdin, and a feed from a real small simulation."""

from __future__ import annotations

import json
import os
import queue
import re
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "live"))  # live_feed: a real burst's readings

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver") or (
    "/usr/lib/chromium/chromedriver" if Path("/usr/lib/chromium/chromedriver").exists() else None
)
#: Generous: the tests wait for a state, they never time it (a loaded machine is slow).
DEADLINE = 60.0


@contextmanager
def chromium(folder: Path) -> Iterator[Any]:
    """A headless Chromium (Debian's) driven by Selenium; quit after."""
    if CHROMIUM is None or CHROMEDRIVER is None:
        raise RuntimeError(
            "Chromium and its driver are not installed: run scripts/install-chromium.sh "
            "(or `apt-get install chromium chromium-driver`)"
        )
    from selenium import webdriver
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service

    options = Options()
    options.binary_location = CHROMIUM
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-crash-reporter",
        "--disable-breakpad",
        "--window-size=1400,900",
        f"--user-data-dir={folder}",
    ):
        options.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    try:
        yield driver
    finally:
        driver.quit()


def page_state(driver: Any) -> dict[str, Any]:
    """The page's own state (``window.burstloc``), as JSON."""
    text = driver.execute_script("return JSON.stringify(window.burstloc || null)")
    return json.loads(text) or {}


def wait_for(what: Callable[[], Any], message: str, deadline: float = DEADLINE) -> Any:
    """Poll ``what()`` until it is truthy (its value is returned); fail after ``deadline`` s."""
    end = time.monotonic() + deadline
    while True:
        value = what()
        if value:
            return value
        if time.monotonic() > end:
            raise AssertionError(f"not within {deadline:g} s: {message}")
        time.sleep(0.05)


class Monitor:
    """``burstloc monitor --web 127.0.0.1:0`` reading its stdin; records and stderr collected."""

    def __init__(
        self, network: Path, config: Path, *options: str, env: dict[str, str] | None = None
    ) -> None:
        command = [
            sys.executable, "-m", "burstloc", "monitor", str(network), "--config", str(config),
            "--capture-interval", "0.2", "--readings", "-", *options,
        ]  # fmt: skip
        self.proc = subprocess.Popen(
            command,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            env={**os.environ, **(env or {})},
            text=True,
            bufsize=1,
        )
        self.records: queue.Queue[dict[str, Any]] = queue.Queue()
        self.stderr: list[str] = []
        self._url: queue.Queue[str] = queue.Queue()
        self._address: str | None = None
        threading.Thread(target=self._read_out, daemon=True).start()
        threading.Thread(target=self._read_err, daemon=True).start()

    def _read_out(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.records.put(json.loads(line))

    def _read_err(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            self.stderr.append(line)
            found = re.search(r"control room at (http://\S+)", line)
            if found:
                self._url.put(found.group(1))

    @property
    def url(self) -> str:
        """The page's address (once the server listens)."""
        if self._address is None:
            try:
                self._address = self._url.get(timeout=DEADLINE)
            except queue.Empty:
                stderr = "".join(self.stderr)
                raise AssertionError(f"no page address; stderr: {stderr}") from None
        return self._address

    def feed(self, lines: list[str]) -> None:
        """Readings 'timestamp,meter,value' to the monitor's stdin."""
        assert self.proc.stdin is not None
        self.proc.stdin.write("".join(f"{line}\n" for line in lines))
        self.proc.stdin.flush()

    def record(self, kind: str) -> dict[str, Any]:
        """The next record of type ``kind`` (others are skipped)."""
        end = time.monotonic() + DEADLINE
        while time.monotonic() < end:
            try:
                record = self.records.get(timeout=0.5)
            except queue.Empty:
                continue
            if record["type"] == kind:
                return record
        raise AssertionError(f"no {kind} record; stderr: {''.join(self.stderr)}")

    def stop(self) -> None:
        """End the feed and the process."""
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            self.proc.wait(timeout=30)
        finally:
            for stream in (self.proc.stdin, self.proc.stdout, self.proc.stderr):
                if stream is not None:
                    stream.close()


def csv_lines(steps: list[Any], meters: tuple[str, ...]) -> list[str]:
    """The steps as CSV readings 'timestamp,meter,value', meter order within a step."""
    return [
        f"{s.timestamp:.1f},{m},{float(v):.4f}"
        for s in steps
        for m, v in zip(meters, s.values, strict=True)
    ]
