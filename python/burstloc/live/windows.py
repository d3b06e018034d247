"""Localization windows from a feed of readings (paper IV.B, "Fetching data").

The loop waits for ``interval`` new complete steps, then hands on a :class:`Window`: the previous
``interval`` steps concatenated with the current ``interval`` steps (the very first window has no
previous part). The steps come from a :class:`~burstloc.live.feeds.StepFeed` (its rules for late,
duplicate, missing and excluded readings apply unchanged).

One interface serves two sources: :func:`replay` turns arrays (a simulated scenario, already
captured or sampled here at a capture interval) into :class:`Step` objects, and live readings
come from any iterable or async iterator of :class:`Reading` (or :class:`Step`). Both go through
:class:`ReadingStream`; this module imports nothing from the simulator.
"""

from __future__ import annotations

from collections.abc import AsyncIterable, AsyncIterator, Iterable, Iterator, Sequence

import numpy as np
import numpy.typing as npt

from burstloc.exceptions import ConfigError, StreamError
from burstloc.live.feeds import MissingPolicy, StepFeed, StreamStats
from burstloc.readings import Item, Reading, Step, Window

__all__ = [
    "MissingPolicy",
    "ReadingStream",
    "StreamStats",
    "readings_of",
    "replay",
]


class ReadingStream:
    """Assemble readings into complete steps (a :class:`~burstloc.live.feeds.StepFeed`) and
    steps into localization windows.

    Parameters
    ----------
    meters:
        The meters (network junctions with a pressure meter), in column order.
    interval:
        The paper's localization interval: new complete steps per window (>= 1).
    timeout, missing, period, origin:
        The step feed's options (:class:`~burstloc.live.feeds.StepFeed`).

    Examples
    --------
    >>> s = ReadingStream(["a", "b"], interval=1)
    >>> s.push(Reading(0.0, "a", 10.0))
    []
    >>> [w.values.tolist() for w in s.push(Reading(0.0, "b", 20.0))]
    [[[10.0, 20.0]]]
    >>> [w.values.tolist() for w in s.push(Step(0.2, np.array([11.0, 21.0])))]
    [[[10.0, 20.0], [11.0, 21.0]]]
    """

    def __init__(
        self,
        meters: Sequence[str],
        interval: int,
        *,
        timeout: int = 3,
        missing: MissingPolicy | str = MissingPolicy.SKIP,
        period: float | None = None,
        origin: float = 0.0,
    ) -> None:
        if isinstance(interval, bool) or not isinstance(interval, (int, np.integer)):
            raise ConfigError(f"localization interval must be an integer, got {interval!r}")
        if interval < 1:
            raise ConfigError(f"localization interval must be >= 1, got {interval}")
        self.feed = StepFeed(meters, timeout=timeout, missing=missing, period=period, origin=origin)
        self.meters: tuple[str, ...] = self.feed.meters
        self.interval: int = int(interval)
        self._previous: list[Step] = []
        self._current: list[Step] = []
        self._emitted = 0

    @property
    def stats(self) -> StreamStats:
        """The feed's counters, with the windows made."""
        return self.feed.stats

    @property
    def excluded(self) -> set[str]:
        """Meters not waited for (the feed's :attr:`~burstloc.live.feeds.StepFeed.excluded`)."""
        return self.feed.excluded

    @property
    def timeout(self) -> int:
        """Newer steps an incomplete step may wait for."""
        return self.feed.timeout

    @property
    def missing(self) -> MissingPolicy:
        """The policy for a step that times out."""
        return self.feed.missing

    @property
    def period(self) -> float | None:
        """The capture clock's period, if any."""
        return self.feed.period

    @property
    def origin(self) -> float:
        """The capture clock's origin."""
        return self.feed.origin

    # ----------------------------------------------------------------- input
    def push(self, item: Item) -> list[Window]:
        """Feed one reading (or one whole step); return the windows it completes (often none)."""
        return self._windows_from(self.feed.push(item))

    def flush(self) -> list[Window]:
        """End of feed: resolve every pending step by the missing policy; return the windows.

        A trailing partial window (fewer than ``interval`` new steps) is not emitted, as in the
        paper's loop, which waits for ``interval`` new complete steps.
        """
        return self._windows_from(self.feed.flush())

    def windows(self, source: Iterable[Item]) -> Iterator[Window]:
        """Yield the windows of a live or replayed feed, flushing at its end."""
        for item in source:
            yield from self.push(item)
        yield from self.flush()

    async def awindows(self, source: AsyncIterable[Item] | Iterable[Item]) -> AsyncIterator[Window]:
        """Async twin of :meth:`windows` for an async iterator (or a plain iterable) of items."""
        if isinstance(source, AsyncIterable):
            async for item in source:
                for w in self.push(item):
                    yield w
        else:
            for item in source:
                for w in self.push(item):
                    yield w
        for w in self.flush():
            yield w

    def _windows_from(self, steps: list[Step]) -> list[Window]:
        out: list[Window] = []
        for step in steps:
            self._current.append(step)
            if len(self._current) < self.interval:
                continue
            parts = self._previous + self._current
            times = np.array([s.timestamp for s in parts], dtype=np.float64)
            values = np.vstack([s.values for s in parts])
            times.flags.writeable = False
            values.flags.writeable = False
            first = self._emitted - len(self._previous)
            out.append(
                Window(
                    index=self.stats.windows,
                    meters=self.meters,
                    times=times,
                    values=values,
                    new=len(self._current),
                    first_step=first,
                    filled=tuple(s.filled for s in parts),
                )
            )
            self.stats.windows += 1
            self._emitted += len(self._current)
            self._previous, self._current = self._current, []
        return out


def replay(times: npt.ArrayLike, values: npt.ArrayLike) -> Iterator[Step]:
    """Replay recorded readings as a feed of complete steps.

    ``times`` (T,) and ``values`` (T, M) are readings already captured at the capture interval
    (a simulated timeline is sampled first, e.g. with
    :func:`burstloc.sim.scenarios.capture.capture`).
    Columns must follow the stream's meter order.
    """
    t = np.asarray(times, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if t.ndim != 1 or v.ndim != 2 or v.shape[0] != t.shape[0]:
        raise StreamError(
            f"replay needs times (T,) and values (T, M); got shapes {t.shape} and {v.shape}"
        )
    for i in range(t.shape[0]):
        yield Step(float(t[i]), v[i])


def readings_of(steps: Iterable[Step], meters: Sequence[str]) -> Iterator[Reading]:
    """Explode steps into per-meter readings (meter order within a step), e.g. to test a feed."""
    for s in steps:
        for m, x in zip(meters, s.values, strict=True):
            yield Reading(s.timestamp, m, float(x))
