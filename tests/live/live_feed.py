"""Drive a :class:`burstloc.live.loop.LiveLoop` in the tests: records and messages collected."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from burstloc.live.health import Health, PlausibleRange
from burstloc.live.loop import LiveLoop, Reporter
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading
from burstloc.readings import Reading


class Collected:
    """A loop over ``monitor`` with its records and stderr messages kept in lists."""

    def __init__(self, monitor: BurstMonitor, **options: Any) -> None:
        self.records: list[dict[str, Any]] = []
        self.messages: list[str] = []
        health_options = {
            k: options.pop(k) for k in ("silent_after", "clock_tolerance") if k in options
        }
        plausible = options.pop(
            "plausible", PlausibleRange.default(monitor.meters, monitor.steady.tolist())
        )
        self.health = Health(
            monitor.meters,
            plausible,
            capture_interval=monitor.calibration.capture_interval,
            **health_options,
        )
        self.report = Reporter(self.messages.append, burst=10_000)
        self.loop = LiveLoop(monitor, self.health, self.records.append, self.report, **options)

    def run(self, items: Iterable[Reading | BadReading | None]) -> Collected:
        self.loop.run(items)
        return self

    @property
    def decisions(self) -> list[dict[str, Any]]:
        return [r for r in self.records if r["type"] == "decision"]

    @property
    def health_records(self) -> list[dict[str, Any]]:
        return [r for r in self.records if r["type"] == "health"]
