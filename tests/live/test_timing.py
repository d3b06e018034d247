"""burstloc.live.timing: histograms with Prometheus' cumulative buckets, and a record timer that
times each record from its step and hands everything on to the observer behind it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from burstloc.live.observe import LiveObserver
from burstloc.live.timing import LATENCY_BUCKETS, Histogram, RecordTimer
from burstloc.readings import Step


def test_histogram_buckets_are_cumulative_and_upper_bounds_inclusive() -> None:
    h = Histogram([1.0, 2.0, 5.0])
    for value in [0.5, 1.0, 1.5, 2.0, 7.0, float("nan"), float("inf")]:
        h.observe(value)
    snap = h.snapshot()
    assert snap.bounds == (1.0, 2.0, 5.0)
    assert snap.cumulative == (2, 4, 4, 5)  # le=1: 0.5, 1.0; le=2: +1.5, 2.0; +Inf: +7.0
    assert snap.number == 5 and snap.total == pytest.approx(12.0)
    with pytest.raises(ValueError, match="increasing"):
        Histogram([2.0, 1.0])


class _Seen(LiveObserver):
    def __init__(self) -> None:
        self.seen: list[tuple[str, Any]] = []

    def step(self, step: Step) -> None:
        self.seen.append(("step", step.timestamp))

    def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
        self.seen.append(("alarm", meter))

    def record(self, record: dict[str, Any]) -> None:
        self.seen.append(("record", record["type"]))

    def message(self, text: str) -> None:
        self.seen.append(("message", text))

    def tick(self, health: Any) -> None:
        self.seen.append(("tick", health()))


def test_each_record_is_timed_from_the_step_that_made_it_and_everything_handed_on() -> None:
    now = [100.0]
    inner = _Seen()
    timer = RecordTimer(inner, clock=lambda: now[0])
    timer.step(Step(1.0, np.zeros(2)))
    now[0] = 100.004
    timer.alarm("N4", 1.0, 0.8, -1.5)
    timer.record({"type": "decision", "decision_delay_s": 1.4})
    timer.step(Step(1.2, np.zeros(2)))
    now[0] = 100.3
    timer.record({"type": "transient"})
    timer.record({"type": "health"})  # not timed
    timer.message("meter 'N4' silent")
    timer.tick(lambda: {"type": "health"})
    assert inner.seen == [
        ("step", 1.0), ("alarm", "N4"), ("record", "decision"), ("step", 1.2),
        ("record", "transient"), ("record", "health"), ("message", "meter 'N4' silent"),
        ("tick", {"type": "health"}),
    ]  # fmt: skip
    decision = timer.latency["decision"].snapshot()
    assert decision.number == 1 and decision.total == pytest.approx(0.004)
    assert decision.cumulative[LATENCY_BUCKETS.index(0.005)] == 1
    assert decision.cumulative[LATENCY_BUCKETS.index(0.0025)] == 0
    assert timer.latency["transient"].snapshot().total == pytest.approx(0.296)  # from step 2
    assert timer.latency["event"].snapshot().number == 0
    assert timer.delay.snapshot().total == pytest.approx(1.4)
    alone = RecordTimer()  # nobody behind it
    alone.step(Step(0.0, np.zeros(1)))
    alone.record({"type": "event"})
    assert alone.latency["event"].snapshot().number == 1
