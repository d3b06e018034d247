"""burstloc.live.paper_locator: the paper's real-time loop over a feed of steps."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

from burstloc.exceptions import StreamError
from burstloc.live.paper_locator import BurstLocator
from burstloc.localize.evidence import Change
from burstloc.localize.paper_rules import Rule
from burstloc.readings import Step, Window
from paper_graph import MEANS, METERS, tnet1_like


class ThresholdDetector:
    """A stand-in detector: a meter alarms when its window range exceeds 1 m."""

    def __init__(self) -> None:
        self.calls = 0

    def detect(self, window: Window) -> dict[str, list[Change]]:
        self.calls += 1
        out: dict[str, list[Change]] = {}
        for j, m in enumerate(window.meters):
            x = window.values[:, j]
            span = float(x[-1] - x[0])
            out[m] = [Change(m, float(window.times[0]), span)] if abs(span) > 1.0 else []
        return out

    def reset(self) -> None:
        self.calls = 0


def test_burst_locator_streams_detects_and_locates() -> None:
    meters = list(METERS)
    base = np.array([MEANS[m] for m in meters])
    drop = np.array([0.0, 0.0, 3.0, 0.0, 1.5])  # N4 drops most, then N6: two alarms
    steps = [Step(0.2 * k, base - (drop if k >= 6 else 0.0)) for k in range(12)]
    locator = BurstLocator(tnet1_like(), meters, ThresholdDetector(), interval=2)
    first = locator.first(steps)
    assert first is not None
    loc = first.localization
    assert loc is not None and loc.pipe == "P4" and loc.rule is Rule.TWO_ALARMS
    assert loc.decision_time == pytest.approx(0.2 * 7)  # first window holding the drop
    assert [x.pipe for x in BurstLocator(tnet1_like(), meters, ThresholdDetector(), 2).run(steps)]
    assert locator.detector.calls == 4  # windows ending at steps 1, 3, 5, 7


def test_burst_locator_rejects_meters_outside_the_network() -> None:
    with pytest.raises(StreamError, match="'Z9' is not a junction"):
        BurstLocator(tnet1_like(), ["N2", "Z9"], ThresholdDetector(), interval=1)


def test_burst_locator_async_feed_gives_the_same_localizations() -> None:

    meters = list(METERS)
    base = np.array([MEANS[m] for m in meters])
    drop = np.array([0.0, 0.0, 3.0, 0.0, 1.5])
    steps = [Step(0.2 * k, base - (drop if k >= 6 else 0.0)) for k in range(12)]

    async def feed():
        for s in steps:
            await asyncio.sleep(0)
            yield s

    async def collect():
        locator = BurstLocator(tnet1_like(), meters, ThresholdDetector(), 2)
        return [loc async for loc in locator.arun(feed())]

    got = asyncio.run(collect())
    want = list(BurstLocator(tnet1_like(), meters, ThresholdDetector(), 2).run(steps))
    assert [(x.pipe, x.decision_time) for x in got] == [(x.pipe, x.decision_time) for x in want]
    assert got
