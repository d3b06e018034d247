"""Complete time steps from a feed of readings (paper IV.B, "Fetching data").

Meters report readings ``(timestamp, meter, value)``, one per meter per capture interval. A
*time step* is complete when every meter has reported it. :class:`StepFeed` assembles them; the
windows of the paper's loop are made from its steps by
:class:`~burstloc.live.windows.ReadingStream`. This module imports nothing from the simulator.

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
  ``missing`` policy decides: ``"skip"`` drops the step (counted in ``skipped_steps``; a window
  simply lacks it, visible as a gap in :attr:`Window.times`), ``"hold"`` fills each
  missing meter with its last emitted value (counted in ``filled_readings``; the step records
  which meters were filled in :attr:`Step.filled`). A step that cannot be held (a meter has
  never reported) is skipped. Without a ``period`` the feed only knows the steps it has
  heard of; with one, a step nobody reported (a gap on the clock) also waits for its timeout
  and is then skipped, never filled. :meth:`StepFeed.flush` applies the same policy to every
  pending step at the end of a feed.
* **Excluded meters.** Meters in :attr:`StepFeed.excluded` (e.g. silent ones, see
  :mod:`burstloc.live.health`) are not waited for: a step is complete when every other meter has
  reported; an excluded meter that did not report gets its last value (NaN if it never reported)
  and is named in :attr:`Step.filled`.
* **Errors.** A reading from a meter that is not configured, or with a non-finite timestamp or
  value, raises :class:`~burstloc.exceptions.StreamError` naming it; the feed's state is left
  unchanged.

Readings come one at a time (:meth:`StepFeed.push`) or as a row of arrays
(:meth:`StepFeed.push_row`: a batch of readings, e.g. one MQTT message), with the same result.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum

import numpy as np

from burstloc.exceptions import ConfigError, StreamError
from burstloc.readings import FloatArray, Item, Reading, Step, step_values

__all__ = ["MissingPolicy", "StepFeed", "StreamStats"]


@dataclass(slots=True)
class StreamStats:
    """Counters of what a feed accepted, dropped, skipped or filled (``windows``: made by a
    :class:`~burstloc.live.windows.ReadingStream`)."""

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


class StepFeed:
    """Assemble readings into complete time steps (module docstring).

    Parameters
    ----------
    meters:
        The meters (network junctions with a pressure meter), in column order.
    timeout:
        How many newer steps may arrive while an incomplete step is still waited for (>= 0);
        the next one gives up on it.
    missing:
        ``"skip"`` (default) or ``"hold"``: the policy for a step that times out.
    period, origin:
        Optional capture clock: timestamps are snapped to ``origin + k * period``.

    Raises:
        ConfigError: no meter, a meter listed twice, a bad timeout, policy, period or origin.

    Examples
    --------
    >>> f = StepFeed(["a", "b"])
    >>> f.push(Reading(0.0, "a", 10.0))
    []
    >>> [s.values.tolist() for s in f.push(Reading(0.0, "b", 20.0))]
    [[10.0, 20.0]]
    >>> steps, late = f.push_row([0.2, 0.2, 0.0], [1, 0, 0], [21.0, 11.0, 12.0])
    >>> [(position, s.values.tolist()) for position, s in steps], late
    ([(1, [11.0, 21.0])], [2])
    """

    def __init__(
        self,
        meters: Sequence[str],
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
        self.timeout: int = int(timeout)
        self.missing: MissingPolicy = policy
        self.period: float | None = period
        self.origin: float = float(origin)
        self.stats: StreamStats = StreamStats()
        self.excluded: set[str] = set()
        self._index = {m: j for j, m in enumerate(meters)}
        self._pending: dict[float, _Pending] = {}
        self._newest: float = -math.inf  # key of the newest emitted or skipped step
        self._last: FloatArray | None = None  # last emitted values (for "hold")

    # ----------------------------------------------------------------- input
    def push(self, item: Item) -> list[Step]:
        """Feed one reading (or one whole step); return the steps it completes (often none).

        Raises:
            StreamError: an unknown meter, a non-finite timestamp or value, a step of the wrong
                size (the feed is left unchanged).
        """
        if isinstance(item, Step):
            return self._push_step(item)
        if not isinstance(item, Reading):
            raise StreamError(f"expected a Reading or a Step, got {type(item).__name__}")
        j = self._index.get(item.meter)
        if j is None:
            raise StreamError(
                f"reading from unknown meter {item.meter!r} at t={item.timestamp} "
                f"(meters: {', '.join(self.meters)})"
            )
        self._check_time(item.timestamp, f"meter {item.meter!r}")
        try:
            value = float(item.value)
        except (TypeError, ValueError):
            raise StreamError(
                f"meter {item.meter!r} at t={item.timestamp}: value {item.value!r} is not a number"
            ) from None
        if not math.isfinite(value):
            raise StreamError(
                f"meter {item.meter!r} at t={item.timestamp}: value {value} is not finite"
            )
        return [s for _, s in self.push_row([float(item.timestamp)], [j], [value])[0]]

    def push_row(
        self, times: Sequence[float], columns: Sequence[int], values: Sequence[float]
    ) -> tuple[list[tuple[int, Step]], list[int]]:
        """Feed a row of readings (timestamps, meter columns, values), in order, as
        :meth:`push` would one by one; return the steps completed, each with the position of
        the reading that completed it, and the positions of the late readings.

        Raises:
            StreamError: rows of different lengths, a column that is not a meter's, a
                non-finite timestamp or value (the feed is left unchanged).
        """
        n = len(times)
        if len(columns) != n or len(values) != n:
            raise StreamError(
                f"a row needs as many meters and values as timestamps, got "
                f"{n}, {len(columns)} and {len(values)}"
            )
        if not n:
            return [], []
        if min(columns) < 0 or max(columns) >= len(self.meters):
            raise StreamError(f"a row names meter columns outside 0..{len(self.meters) - 1}")
        # One sum per row: NaN and infinities propagate (a huge finite sum is checked in full).
        if not math.isfinite(math.fsum(times) + math.fsum(values)):
            for t, v in zip(times, values, strict=True):
                if not (math.isfinite(t) and math.isfinite(v)):
                    raise StreamError(f"a row has a non-finite timestamp or value ({t}, {v})")
        return self.push_admitted(times, columns, values)

    def push_admitted(
        self, times: Sequence[float], columns: Sequence[int], values: Sequence[float]
    ) -> tuple[list[tuple[int, Step]], list[int]]:
        """:meth:`push_row` without its checks, for a row already checked: as many meter
        columns (each ``0 <= j < len(meters)``) and finite values as finite timestamps (what
        :meth:`burstloc.live.health.Health.admit_row` answers)."""
        stats, pending, m = self.stats, self._pending, len(self.meters)
        needed = m - len(self.excluded)  # readings a step needs before it can be let go
        period, origin = self.period, self.origin
        keys = times if period is None else [float(round((t - origin) / period)) for t in times]
        steps: list[tuple[int, Step]] = []
        late: list[int] = []
        newest = self._newest
        for position, key in enumerate(keys):
            if key <= newest:
                late.append(position)
                continue
            j = columns[position]
            step = pending.get(key)
            if step is None:
                pending[key] = _Pending(key, {j: values[position]})
                if len(pending) <= self.timeout and needed > 1:
                    continue  # a new step lets the oldest go only past the timeout
            else:
                got = step.values
                if j in got:
                    stats.duplicates += 1
                    continue
                got[j] = values[position]
                # Only a step with a reading from every meter not excluded can let the oldest
                # pending step go (a change of the excluded meters: :meth:`drain`).
                if len(got) < needed:
                    continue
            steps.extend((position, s) for s in self._drain())
            newest = self._newest
        stats.readings += len(keys)
        stats.late += len(late)
        return steps, late

    def drain(self) -> list[Step]:
        """The steps that can be let go now: call after changing :attr:`excluded` (a step that
        waited only for meters now excluded is complete)."""
        return self._drain()

    def flush(self) -> list[Step]:
        """End of feed: resolve every pending step by the missing policy; return the steps."""
        steps: list[Step] = []
        while self._pending:
            steps.extend(self._resolve_head(force=True) or ())
        return steps

    # ------------------------------------------------------------ internals
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
        return t if self.period is None else float(round((t - self.origin) / self.period))

    def _push_step(self, step: Step) -> list[Step]:
        key = self._check_time(step.timestamp, "step")
        values = step_values(step)
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
        m = len(self.meters)
        row = self.push_row([float(step.timestamp)] * m, list(range(m)), values.tolist())
        return [s for _, s in row[0]]

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
            got = head.values
            values = np.array([got[j] for j in range(m)], dtype=np.float64)
            return [self._emit(key, values, ())]
        if self.excluded and all(
            self.meters[j] in self.excluded for j in range(m) if j not in head.values
        ):
            del self._pending[key]
            return [self._filled(key, head, np.full(m, np.nan))]
        newer = len(self._pending) - 1
        if not force and newer <= self.timeout:
            return None
        del self._pending[key]
        self._newest = key
        if self.missing is MissingPolicy.HOLD and self._last is not None:
            return [self._filled(key, head, self._last)]
        self.stats.skipped_steps += 1
        return []

    def _filled(self, key: float, head: _Pending, fill: FloatArray) -> Step:
        """The step of ``head`` with its missing meters filled (from the last step if any)."""
        values = fill.copy() if self._last is None else self._last.copy()
        for j, v in head.values.items():
            values[j] = v
        filled = tuple(self.meters[j] for j in range(len(self.meters)) if j not in head.values)
        self.stats.filled_readings += len(filled)
        return self._emit(key, values, filled)

    def _emit(self, key: float, values: FloatArray, filled: tuple[str, ...]) -> Step:
        self._newest = key
        self._last = values
        self.stats.steps += 1
        return Step(self._timestamp(key), values, tuple(filled))

    # ---------------------------------------------------------------- state
    def to_state(self) -> dict[str, object]:
        """The assembly state (pending steps, newest step, last values, counters), JSON-ready."""
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
        """Inverse of :meth:`to_state` on a feed with the same meters and clock."""
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
