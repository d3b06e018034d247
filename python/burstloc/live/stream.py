"""The real-time feed: pressure readings in, localization windows out (paper IV.B, "Fetching data").

Meters report readings ``(timestamp, meter, value)``, one per meter per capture interval. A
*time step* is complete when every meter has reported it. The loop waits for ``interval`` new
complete steps, then hands on a :class:`Window`: the previous ``interval`` steps concatenated
with the current ``interval`` steps (the very first window has no previous part).

One interface serves two sources: :func:`replay` turns arrays (a simulated scenario, already
captured or sampled here at a capture interval) into :class:`Step` objects, and live readings
come from any iterable or async iterator of :class:`Reading` (or :class:`Step`). Both go through
:class:`ReadingStream`; this module imports nothing from the simulator.

Rules for imperfect feeds (each case is counted in :class:`StreamStats`, never silently mixed):

* **Step identity.** A reading belongs to the step with the same timestamp. With ``period``
  set, timestamps are snapped to the clock ``origin + k * period`` (nearest ``k``), so meters
  with jittery clocks still meet in one step; without it, timestamps must match exactly.
* **Order.** Steps are emitted in timestamp order. Readings may arrive out of order as long as
  their step has not been emitted yet: they wait in a pending buffer.
* **Late.** A reading for a step at or before the newest emitted (or skipped) step is dropped
  and counted in ``late``.
* **Duplicate.** A second reading from the same meter for the same pending step is dropped
  (the first value wins) and counted in ``duplicates``.
* **Missing.** The oldest pending step blocks emission until it is complete, or until readings
  for more than ``timeout`` newer steps have arrived (its *timeout*, measured in steps; with
  ``timeout=0`` any reading of a newer step gives up on it). Then the
  ``missing`` policy decides: ``"skip"`` drops the step (counted in ``skipped_steps``; the
  window simply lacks it, visible as a gap in :attr:`Window.times`), ``"hold"`` fills each
  missing meter with its last emitted value (counted in ``filled_readings``; the step records
  which meters were filled in :attr:`Step.filled`). A step that cannot be held (a meter has
  never reported) is skipped. Without a ``period`` the stream only knows the steps it has
  heard of; with one, a step nobody reported (a gap on the clock) also waits for its timeout
  and is then skipped, never filled. :meth:`ReadingStream.flush` applies the same policy to every
  pending step at the end of a feed.
* **Excluded meters.** Meters in :attr:`ReadingStream.excluded` (e.g. silent ones, see
  :mod:`burstloc.live.health`) are not waited for: a step is complete when every other meter has
  reported; an excluded meter that did not report gets its last value (NaN if it never reported)
  and is named in :attr:`Step.filled`.
* **Errors.** A reading from a meter that is not configured, or with a non-finite timestamp or
  value, raises :class:`~burstloc.exceptions.StreamError` naming it; the stream's state is left
  unchanged.
"""

from __future__ import annotations

import math
from collections.abc import AsyncIterable, AsyncIterator, Iterable, Iterator, Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np
import numpy.typing as npt

from burstloc.exceptions import ConfigError, StreamError
from burstloc.readings import FloatArray, Item, Reading, Step, Window

__all__ = [
    "MissingPolicy",
    "ReadingStream",
    "StreamStats",
    "readings_of",
    "replay",
]


@dataclass(slots=True)
class StreamStats:
    """Counters of what a :class:`ReadingStream` accepted, dropped, skipped or filled."""

    readings: int = 0
    steps: int = 0
    windows: int = 0
    late: int = 0
    duplicates: int = 0
    skipped_steps: int = 0
    filled_readings: int = 0


class MissingPolicy(str, Enum):
    """What to do with a step that is still incomplete when it times out."""

    SKIP = "skip"
    HOLD = "hold"


@dataclass(slots=True)
class _Pending:
    timestamp: float
    values: dict[int, float]


class ReadingStream:
    """Assemble readings into complete steps and steps into localization windows.

    Parameters
    ----------
    meters:
        The meters (network junctions with a pressure meter), in column order.
    interval:
        The paper's localization interval: new complete steps per window (>= 1).
    timeout:
        How many newer steps may arrive while an incomplete step is still waited for (>= 0);
        the next one gives up on it.
    missing:
        ``"skip"`` (default) or ``"hold"``: the policy for a step that times out.
    period, origin:
        Optional capture clock: timestamps are snapped to ``origin + k * period``.

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
        meters = tuple(str(m) for m in meters)
        if not meters:
            raise ConfigError("a stream needs at least one meter")
        if len(set(meters)) != len(meters):
            dup = sorted({m for m in meters if meters.count(m) > 1})
            raise ConfigError(f"meters listed more than once: {dup}")
        if isinstance(interval, bool) or not isinstance(interval, (int, np.integer)):
            raise ConfigError(f"localization interval must be an integer, got {interval!r}")
        if interval < 1:
            raise ConfigError(f"localization interval must be >= 1, got {interval}")
        if isinstance(timeout, bool) or not isinstance(timeout, (int, np.integer)) or timeout < 0:
            raise ConfigError(f"timeout must be an integer number of steps >= 0, got {timeout!r}")
        try:
            policy = MissingPolicy(missing)
        except ValueError:
            raise ConfigError(f"missing policy must be 'skip' or 'hold', got {missing!r}") from None
        if period is not None and not (math.isfinite(period) and period > 0):
            raise ConfigError(f"period must be a positive finite number of seconds, got {period}")
        if not math.isfinite(origin):
            raise ConfigError(f"origin must be finite, got {origin}")
        self.meters: tuple[str, ...] = meters
        self.interval: int = int(interval)
        self.timeout: int = int(timeout)
        self.missing: MissingPolicy = policy
        self.period: float | None = period
        self.origin: float = float(origin)
        self.stats: StreamStats = StreamStats()
        self._index = {m: j for j, m in enumerate(meters)}
        self._pending: dict[float, _Pending] = {}
        self._newest: float = -math.inf  # key of the newest emitted or skipped step
        self._last: FloatArray | None = None  # last emitted values (for "hold")
        self._previous: list[Step] = []
        self._current: list[Step] = []
        self._emitted = 0
        self.excluded: set[str] = set()

    # ----------------------------------------------------------------- input
    def push(self, item: Item) -> list[Window]:
        """Feed one reading (or one whole step); return the windows it completes (often none)."""
        steps = self._push_step(item) if isinstance(item, Step) else self._push_reading(item)
        return self._windows_from(steps)

    def flush(self) -> list[Window]:
        """End of feed: resolve every pending step by the missing policy; return the windows.

        A trailing partial window (fewer than ``interval`` new steps) is not emitted, as in the
        paper's loop, which waits for ``interval`` new complete steps.
        """
        steps: list[Step] = []
        while self._pending:
            steps.extend(self._resolve_head(force=True) or ())
        return self._windows_from(steps)

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

    # ------------------------------------------------------------ internals
    def _key(self, timestamp: float) -> float:
        if self.period is None:
            return timestamp
        return float(round((timestamp - self.origin) / self.period))

    def _timestamp(self, key: float) -> float:
        if self.period is None:
            return key
        return self.origin + key * self.period

    def _check_time(self, timestamp: float, what: str) -> float:
        try:
            t = float(timestamp)
        except (TypeError, ValueError):
            raise StreamError(f"{what}: timestamp {timestamp!r} is not a number") from None
        if not math.isfinite(t):
            raise StreamError(f"{what}: timestamp {t} is not finite")
        return self._key(t)

    def _push_reading(self, r: Reading) -> list[Step]:
        if not isinstance(r, Reading):
            raise StreamError(f"expected a Reading or a Step, got {type(r).__name__}")
        j = self._index.get(r.meter)
        if j is None:
            raise StreamError(
                f"reading from unknown meter {r.meter!r} at t={r.timestamp} "
                f"(meters: {', '.join(self.meters)})"
            )
        key = self._check_time(r.timestamp, f"meter {r.meter!r}")
        try:
            value = float(r.value)
        except (TypeError, ValueError):
            raise StreamError(
                f"meter {r.meter!r} at t={r.timestamp}: value {r.value!r} is not a number"
            ) from None
        if not math.isfinite(value):
            raise StreamError(f"meter {r.meter!r} at t={r.timestamp}: value {value} is not finite")
        self.stats.readings += 1
        if key <= self._newest:
            self.stats.late += 1
            return []
        pending = self._pending.get(key)
        if pending is None:
            pending = self._pending[key] = _Pending(key, {})
        if j in pending.values:
            self.stats.duplicates += 1
            return []
        pending.values[j] = value
        return self._drain()

    def _push_step(self, step: Step) -> list[Step]:
        key = self._check_time(step.timestamp, "step")
        values = np.asarray(step.values, dtype=np.float64)
        if values.shape != (len(self.meters),):
            raise StreamError(
                f"step at t={step.timestamp} has {values.size} values, expected "
                f"{len(self.meters)} (one per meter)"
            )
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            j = int(bad[0])
            raise StreamError(
                f"meter {self.meters[j]!r} at t={step.timestamp}: value {values[j]} is not finite"
            )
        in_order = key > self._newest and (
            self.period is None or self._newest == -math.inf or key == self._newest + 1
        )
        if in_order and not self._pending:
            # Fast path: the next complete step.
            self.stats.readings += values.size
            return [self._emit(key, values.copy(), step.filled)]
        out: list[Step] = []
        for j, m in enumerate(self.meters):
            out.extend(self._push_reading(Reading(step.timestamp, m, float(values[j]))))
        return out

    def _drain(self) -> list[Step]:
        out: list[Step] = []
        while self._pending:
            resolved = self._resolve_head(force=False)
            if resolved is None:
                break
            out.extend(resolved)
        return out

    def _resolve_head(self, *, force: bool) -> list[Step] | None:
        key = min(self._pending)
        if self.period is not None and self._newest > -math.inf and key > self._newest + 1:
            # On a known clock, steps newest+1 .. key-1 exist but nobody reported them: they
            # wait like any incomplete step, then are skipped (a step with no reading at all is
            # never filled, whatever the policy).
            if not force and len(self._pending) <= self.timeout:
                return None
            self.stats.skipped_steps += int(key - self._newest - 1)
            self._newest = key - 1
            return []
        head = self._pending[key]
        m = len(self.meters)
        if len(head.values) == m:
            del self._pending[key]
            values = np.array([head.values[j] for j in range(m)], dtype=np.float64)
            return [self._emit(key, values, ())]
        if self.excluded and all(
            self.meters[j] in self.excluded for j in range(m) if j not in head.values
        ):
            del self._pending[key]
            values = np.full(m, np.nan) if self._last is None else self._last.copy()
            for j, v in head.values.items():
                values[j] = v
            filled = tuple(self.meters[j] for j in range(m) if j not in head.values)
            self.stats.filled_readings += len(filled)
            return [self._emit(key, values, filled)]
        newer = len(self._pending) - 1
        if not force and newer <= self.timeout:
            return None
        del self._pending[key]
        self._newest = key
        if self.missing is MissingPolicy.HOLD and self._last is not None:
            values = self._last.copy()
            for j, v in head.values.items():
                values[j] = v
            filled = tuple(self.meters[j] for j in range(m) if j not in head.values)
            self.stats.filled_readings += len(filled)
            return [self._emit(key, values, filled)]
        self.stats.skipped_steps += 1
        return []

    # ---------------------------------------------------------------- state
    def to_state(self) -> dict[str, object]:
        """The assembly state (pending steps, newest step, last values, counters), JSON-ready.

        Only for a stream of single-step windows (``interval=1``), as the monitor uses.
        """
        return {
            "pending": [
                [p.timestamp, {str(j): v for j, v in p.values.items()}]
                for p in self._pending.values()
            ],
            "newest": None if self._newest == -math.inf else self._newest,
            "last": None if self._last is None else [float(x) for x in self._last],
            "excluded": sorted(self.excluded),
            "stats": {name: getattr(self.stats, name) for name in StreamStats.__slots__},
        }

    def restore(self, state: dict[str, object]) -> None:
        """Inverse of :meth:`to_state` on a stream with the same meters and clock."""
        pending = state["pending"]
        assert isinstance(pending, list)
        self._pending = {
            float(k): _Pending(float(k), {int(j): float(v) for j, v in vals.items()})
            for k, vals in pending
        }
        newest = state["newest"]
        self._newest = -math.inf if newest is None else float(newest)  # type: ignore[arg-type]
        last = state["last"]
        self._last = None if last is None else np.array(last, dtype=np.float64)
        self.excluded = set(state["excluded"])  # type: ignore[call-overload]
        stats = state["stats"]
        assert isinstance(stats, dict)
        for name, value in stats.items():
            setattr(self.stats, name, int(value))

    def _emit(self, key: float, values: FloatArray, filled: tuple[str, ...]) -> Step:
        self._newest = key
        self._last = values
        self.stats.steps += 1
        return Step(self._timestamp(key), values, tuple(filled))

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
    (a simulated timeline is sampled first, e.g. with :func:`burstloc.sim.capture.capture`).
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
