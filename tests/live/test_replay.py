"""burstloc.live.replay: a recorded feed played at its own pace."""

from __future__ import annotations

import math

import pytest

from burstloc.exceptions import ConfigError
from burstloc.live.replay import paced
from burstloc.readings import Reading


def test_everything_is_passed_on_in_order() -> None:
    items = [
        ("line 1", Reading(0.0, "a", 1.0)),
        None,
        ("line 2", b"payload"),
        Reading(0.2, "b", 2.0),
        ("line 3", Reading(math.nan, "a", 1.0)),  # not a time to wait for: passed on
    ]
    assert list(paced(items, 1e9)) == items


def test_a_long_wait_ticks_and_stops_when_told() -> None:
    items = [Reading(0.0, "a", 1.0), Reading(1000.0, "a", 1.0)]  # 1000 s apart, at 1x
    ticks = 0

    def stopped() -> bool:
        return ticks >= 2

    out = []
    for item in paced(items, 1.0, stopped):
        out.append(item)
        ticks += item is None
    assert out == [items[0], None, None]  # the second reading is still 999 s away


@pytest.mark.parametrize("speed", [0, -1, math.inf, math.nan])
def test_a_bad_speed_is_refused(speed: float) -> None:
    with pytest.raises(ConfigError, match="replay speed"):
        list(paced([], speed))
