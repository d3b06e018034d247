"""Readings played at their own pace: a recorded feed replayed at ``speed`` times real time.

:func:`paced` passes the items of a feed on, holding each reading back until its timestamp,
counted from the first reading's, is due on the wall clock at ``speed`` times real time (a demo or
a training session shows the burst being located as it would have been). While it waits it
yields ``None`` every :data:`IDLE` seconds (the live loop's idle tick) and stops early when
``stopped()`` says so.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from burstloc.exceptions import ConfigError
from burstloc.readings import Reading

__all__ = ["IDLE", "paced"]

#: Longest wait (s) without an idle tick.
IDLE = 0.5


def paced(
    items: Iterable[Any], speed: float, stopped: Callable[[], bool] = lambda: False
) -> Iterator[Any]:
    """``items`` (readings, ``(where, reading)`` pairs, anything else passed on at once) at
    ``speed`` times the pace of their timestamps.

    Raises:
        ConfigError: ``speed`` is not a finite number > 0.
    """
    if not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0):
        raise ConfigError(f"replay speed must be a finite number > 0, got {speed!r}")
    origin: tuple[float, float] | None = None  # (first timestamp, wall clock then)
    for item in items:
        reading = item[1] if isinstance(item, tuple) else item
        if isinstance(reading, Reading) and math.isfinite(reading.timestamp):
            if origin is None:
                origin = (reading.timestamp, time.monotonic())
            due = origin[1] + (reading.timestamp - origin[0]) / speed
            while (wait := due - time.monotonic()) > 0:
                if stopped():
                    return
                time.sleep(min(wait, IDLE))
                if wait > IDLE:
                    yield None
        if stopped():
            return
        yield item
