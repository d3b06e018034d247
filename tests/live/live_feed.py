"""Drive a :class:`burstloc.live.loop.LiveLoop` in the tests: records and messages collected."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from burstloc.live.health import Health
from burstloc.live.loop import LiveLoop
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading
from burstloc.live.plausible import PlausibleRange
from burstloc.live.reporter import Reporter
from burstloc.readings import Reading, Step


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


def burst_steps(
    network: Any,
    meters: tuple[str, ...],
    pipe: str,
    *,
    capture_interval: float = 0.2,
    before: float = 60.0,
    after: float = 300.0,
    sigma: float = 0.0,
    seed: int = 0,
    duration: float = 30.0,
) -> list[Step]:
    """Steps of a real TSNet burst on ``pipe`` (burst at ``before`` + 2 s), steady readings
    ``before`` it and the final readings held ``after`` it, plus seeded noise ``sigma``."""
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

    scenario = BurstScenario(str(network), pipe, burst_start=2.0, duration=duration)
    result = simulate_burst(scenario).resample(capture_interval)
    heads = result.heads[:, [result.junctions.index(m) for m in meters]]
    pre = np.repeat(heads[:1], round(before / capture_interval), axis=0)
    post = np.repeat(heads[-1:], round(after / capture_interval), axis=0)
    values = np.vstack([pre, heads, post])
    values = values + np.random.default_rng(seed).normal(0.0, sigma, values.shape)
    return [Step(round(k * capture_interval, 9), v) for k, v in enumerate(values)]


def readings(steps: list[Step], meters: tuple[str, ...]) -> list[Reading]:
    """Every step as per-meter readings, meter order within a step."""
    return [
        Reading(s.timestamp, m, float(x))
        for s in steps
        for m, x in zip(meters, s.values, strict=True)
    ]
