"""burstloc.live.observe.fan_out: several observers of one live loop, each told only what it
listens to."""

from __future__ import annotations

from typing import Any

import numpy as np

from burstloc.live.observe import LiveObserver, fan_out
from burstloc.readings import Step


class Records(LiveObserver):
    def __init__(self) -> None:
        self.records: list[dict[str, Any]] = []
        self.ticks = 0

    def record(self, record: dict[str, Any]) -> None:
        self.records.append(record)

    def tick(self, health: Any) -> None:
        self.ticks += 1


class Steps(LiveObserver):
    def __init__(self) -> None:
        self.steps: list[Step] = []
        self.step = self.steps.append  # type: ignore[method-assign, assignment]
        self.records: list[dict[str, Any]] = []

    def record(self, record: dict[str, Any]) -> None:
        self.records.append(record)


def test_none_one_or_many() -> None:
    one = Records()
    assert fan_out() is None and fan_out(None, None) is None
    assert fan_out(None, one) is one


def test_each_observer_is_told_what_it_listens_to() -> None:
    records, steps = Records(), Steps()
    both = fan_out(records, None, steps)
    assert both is not None
    # the step goes straight to the one observer that takes steps (no loop in between)
    assert both.step == steps.steps.append
    step = Step(1.0, np.array([1.0, 2.0]))
    both.step(step)
    both.record({"type": "decision"})
    both.tick(lambda: {})
    both.alarm("N1", 1.0, 0.8, -2.0)
    both.message("hello")
    assert steps.steps == [step]
    assert records.records == steps.records == [{"type": "decision"}]
    assert records.ticks == 1
