"""Meter health on the live path: what each meter sends, whether it is believable, whether it is
on time.

A :class:`Health` stands between the parsed readings and the
:class:`~burstloc.live.feeds.StepFeed`. Every reading passes :meth:`Health.admit`, which
answers the reading to feed (its timestamp corrected for a known clock offset), a
:class:`~burstloc.live.parse.BadReading` (to report and skip) or ``None`` (held back while the
meter's clock is off). The rules:

* **Plausible range.** A value outside the meter's range
  (:class:`~burstloc.live.plausible.PlausibleRange`; default: below
  -10 m or above twice the highest steady head at the meters) is a bad reading: counted
  (``implausible``), reported, skipped. It never reaches the detectors, so it never starts an
  alarm.
* **Clock.** The reference time is the median of the meters' newest timestamps (every reading
  counts, so a gap in the whole feed moves it, a single skewed meter does not). A reading more
  than ``clock_tolerance`` seconds from it is held back (counted ``off_clock``). Once the last
  :data:`CLOCK_WINDOW` readings of a meter agree on an offset (at least 80 % within the
  tolerance of their median), the offset, rounded to the whole second (to the capture interval if
  longer: the arrival order within a step blurs it by one interval), is **corrected**: the
  meter's later timestamps are shifted by it, and the offset is reported in the health record.
  A meter's data is worth more than its clock; correcting keeps it in the localization.
* **Far from the clock.** A reading more than :data:`CLOCK_JUMP` (a day) from the reference time
  (before there is one, from the median of the newest timestamps so far) is a bad reading:
  counted (``bad``), reported, skipped; it moves no clock. No meter's clock slips by a day, no
  feed steps by one between two readings: such a timestamp is a wrong one (a line in another
  time form or origin, a year mistyped). Only the whole feed moves the clock that far (readings
  resumed after an outage of more than a day): when consecutive readings from more than half of
  the meters (at least two readings) are all that far from the reference and within a day of
  one another, the reference moves to them (:attr:`AdmittedRow.moved`); the few readings before
  that were skipped as bad.
* **Silence.** A meter with no reading for ``silent_after`` seconds of reference time is
  *silent*: it is excluded (the stream completes steps without it; the localizers run on the
  meters that report) until its next reading, when it is included again.
* **Replay after a restart.** A feed may send again what it sent before the monitor stopped (a
  broker's persistent session, a historian replaying the last minutes). After
  :meth:`Health.restore`, a meter's readings up to its last timestamp before the restart are
  *replayed*: counted (``replayed``), not fed again and taken neither for a clock offset nor
  for late readings; the meter's first newer reading ends its replay.
* **Counts.** Per meter: readings, bad, implausible, late (dropped by the stream), off-clock,
  filled, replayed, and the newest timestamp; :meth:`Health.record` is the JSON health record.
"""

from __future__ import annotations

import math
import statistics
from collections import deque
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from burstloc.exceptions import ConfigError
from burstloc.live.parse import BadReading, unknown_meter
from burstloc.live.plausible import PlausibleRange
from burstloc.readings import Reading

__all__ = ["CLOCK_JUMP", "CLOCK_WINDOW", "AdmittedRow", "Health", "MeterHealth"]

#: Readings of one meter that must agree before its clock offset is corrected.
CLOCK_WINDOW = 25

#: Seconds from the feed's clock beyond which a reading's timestamp is wrong, not a clock
#: offset (module docstring): a day.
CLOCK_JUMP = 86_400.0

_COUNTS = ("readings", "bad", "implausible", "late", "off_clock", "filled", "replayed")


class AdmittedRow(NamedTuple):
    """What :meth:`Health.admit_row` answers: the readings to feed (their ``positions`` in the
    row, clock-corrected ``times``, meter ``columns``, ``values``); the ``refused`` ones (a
    :class:`~burstloc.live.parse.BadReading`, or ``None``: held back, off the clock) as
    (position, column, what); the clock offsets found, as (position, column, offset); the
    replays that ended, as (position of the meter's first newer reading, column, readings
    replayed); the moves of the whole feed's clock (module docstring), as (position of the
    reading that moved it, the reference before, the reference after)."""

    positions: list[int]
    times: list[float]
    columns: list[int]
    values: list[float]
    refused: list[tuple[int, int, BadReading | None]]
    offsets: list[tuple[int, int, float]]
    replayed: list[tuple[int, int, int]]
    moved: list[tuple[int, float, float]]


@dataclass
class MeterHealth:
    """What one meter has sent (module docstring)."""

    last: float | None = None
    silent: bool = False
    clock_offset: float = 0.0
    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(_COUNTS, 0))
    deviations: deque[float] = field(default_factory=lambda: deque(maxlen=CLOCK_WINDOW))

    def to_json(self) -> dict[str, Any]:
        """JSON-ready: newest timestamp, silent, clock offset (s) and the counts."""
        return {
            "last": self.last,
            "silent": self.silent,
            "clock_offset": self.clock_offset,
            **self.counts,
        }


def _seconds(t: float) -> str:
    """A timestamp in seconds, to the millisecond, without trailing zeros."""
    return f"{t:.3f}".rstrip("0").rstrip(".")


class Health:
    """The health of every meter of one feed, and the gate readings pass (module docstring).

    Raises:
        ConfigError: a non-positive capture interval, ``silent_after`` or ``clock_tolerance``.
    """

    def __init__(
        self,
        meters: Sequence[str],
        plausible: PlausibleRange,
        *,
        capture_interval: float,
        silent_after: float = 30.0,
        clock_tolerance: float | None = None,
    ) -> None:
        tolerance = max(3 * capture_interval, 1.0) if clock_tolerance is None else clock_tolerance
        for name, x in [
            ("capture interval", capture_interval),
            ("silent_after", silent_after),
            ("clock tolerance", tolerance),
        ]:
            if not (math.isfinite(x) and x > 0):
                raise ConfigError(f"{name} must be a positive number of seconds, got {x}")
        self.meters = tuple(meters)
        self.capture_interval = float(capture_interval)
        self.silent_after = float(silent_after)
        self.clock_tolerance = float(tolerance)
        self.meter: dict[str, MeterHealth] = {m: MeterHealth() for m in self.meters}
        self.plausible = plausible
        self._low = dict(plausible.low)
        self._high = dict(plausible.high)
        self._newest = [math.nan] * len(self.meters)
        self._index = {m: j for j, m in enumerate(self.meters)}
        self._health = [self.meter[m] for m in self.meters]  # by column
        self._lows = [self._low[m] for m in self.meters]
        self._highs = [self._high[m] for m in self.meters]
        self._replay: list[float | None] = [None] * len(self.meters)  # replayed up to (restart)
        self._replayed = [0] * len(self.meters)  # readings replayed since the restart
        self._reference: float | None = None
        #: The first reference time: a meter never heard from is silent ``silent_after`` s later.
        self._start: float | None = None
        self._lead: deque[float] = deque(maxlen=8 * CLOCK_WINDOW)
        self._since = 0
        self.bad_unknown = 0  # bad input naming no meter of the configuration
        #: Consecutive readings far from the clock, as (column, corrected timestamp): the
        #: whole feed moving when they come from enough meters (module docstring).
        self._far: list[tuple[int, float]] = []

    # ------------------------------------------------------------------ gate
    @property
    def reference(self) -> float | None:
        """The reference time: the median of the meters' newest timestamps (None at first)."""
        return self._reference

    def bad(self, item: BadReading) -> None:
        """Count a bad input item (per meter when it names one)."""
        h = self.meter.get(item.meter) if item.meter is not None else None
        if h is None:
            self.bad_unknown += 1
        else:
            h.counts["bad"] += 1

    def admit(self, r: Reading, where: str) -> Reading | BadReading | None:
        """The reading to feed (clock-corrected), a bad reading, or None (held back)."""
        j = self._index.get(r.meter)
        if j is None:
            self.bad_unknown += 1
            return unknown_meter(where, r.meter)
        row = self.admit_row([r.timestamp], [j], [r.value], where)
        if row.refused:
            return row.refused[0][2]
        t = row.times[0]
        return r if t == r.timestamp else Reading(t, r.meter, r.value)

    def admit_row(
        self,
        times: Sequence[float],
        columns: Sequence[int],
        values: Sequence[float],
        where: str,
        positions: Sequence[int] | None = None,
    ) -> AdmittedRow:
        """:meth:`admit` for a row of readings of known meters (columns into :attr:`meters`,
        finite timestamps and values, as :func:`~burstloc.live.parse.parse_row` gives), in
        order; ``positions`` name them in the answer (default: 0, 1, ...)."""
        out = AdmittedRow([], [], [], [], [], [], [], [])
        meters, health, low, high = self.meters, self._health, self._lows, self._highs
        newest, tolerance, m = self._newest, self.clock_tolerance, len(meters)
        lead, corrected, refused = self._lead.append, out.times, out.refused
        replay, skipped = self._replay, []
        since, ref = self._since, self._reference
        for k in range(len(times)):
            j, ts, value = columns[k], times[k], values[k]
            h = health[j]
            until = replay[j]
            if until is not None:  # after a restart: readings seen before it come again
                if ts - h.clock_offset <= until:
                    h.counts["replayed"] += 1
                    self._replayed[j] += 1
                    skipped.append(k)
                    continue
                replay[j] = None  # the meter's first newer reading: its replay is over
                if self._replayed[j]:
                    out.replayed.append((k, j, self._replayed[j]))
            clock = ref if ref is not None else self._median_newest()
            if clock is not None and abs(ts - h.clock_offset - clock) > CLOCK_JUMP:
                moved = self._moved(j, ts - h.clock_offset)
                if moved is None:
                    h.counts["bad"] += 1
                    refused.append((k, j, self._far_off(where, meters[j], ts, clock)))
                    continue
                out.moved.append((k, clock, moved))
                since, ref = 0, moved
            elif self._far:
                self._far.clear()  # a reading on the clock: the far ones were wrong timestamps
            if not (low[j] <= value <= high[j]):
                h.counts["implausible"] += 1
                refused.append((k, j, self._implausible(where, meters[j], value)))
                continue
            h.counts["readings"] += 1
            t = ts - h.clock_offset
            if not t <= newest[j]:  # NaN at first; every reading moves the reference, so a
                newest[j] = t  # gap in the whole feed moves it too (one skewed meter cannot)
            since += 1
            if ref is None or since >= m:
                self._update_reference()  # (since: 0)
                since, ref = 0, self._reference
            if ref is not None:
                h.deviations.append(ts - ref)
                if abs(t - ref) > tolerance:
                    before = h.clock_offset
                    # the meter's clock as it was (offset unchanged): this reading alone is off
                    if not self._settle_clock(h, ref) or h.clock_offset == before:
                        h.counts["off_clock"] += 1
                        refused.append((k, j, None))
                        continue
                    out.offsets.append((k, j, h.clock_offset))
                    t = ts - h.clock_offset
                lead(t - ref)  # how far on-time readings lead the reference
            if h.last is None or t > h.last:
                h.last = t
            corrected.append(t)
        self._since = since
        at = range(len(times)) if positions is None else positions
        if not (refused or skipped or out.offsets or out.replayed or out.moved):
            out.positions.extend(at)
            out.columns.extend(columns)
            out.values.extend(values)
            return out
        gone = {k for k, _, _ in refused} | set(skipped)
        kept = [k for k in range(len(times)) if k not in gone]
        out.positions.extend(at[k] for k in kept)
        out.columns.extend(columns[k] for k in kept)
        out.values.extend(values[k] for k in kept)
        out.refused[:] = [(at[k], j, what) for k, j, what in refused]
        out.offsets[:] = [(at[k], j, offset) for k, j, offset in out.offsets]
        out.replayed[:] = [(at[k], j, count) for k, j, count in out.replayed]
        out.moved[:] = [(at[k], before, after) for k, before, after in out.moved]
        return out

    def _median_newest(self) -> float | None:
        """Before there is a reference time: the median of the newest timestamps so far."""
        known = [t for t in self._newest if t == t]  # not NaN
        return float(statistics.median(known)) if known else None

    def _far_off(self, where: str, meter: str, ts: float, clock: float) -> BadReading:
        days = abs(ts - clock) / 86_400.0
        return BadReading(
            where,
            f"timestamp {_seconds(ts)} s from meter {meter!r} is {days:.4g} days from the feed's "
            f"clock (t = {_seconds(clock)} s; more than {CLOCK_JUMP / 86_400.0:g} day is a wrong "
            "timestamp)",
            meter,
        )

    def _moved(self, j: int, t: float) -> float | None:
        """Note a reading of column ``j`` at ``t`` far from the clock; if the whole feed has
        moved (module docstring), move the reference and return it, else None."""
        far = [(i, x) for i, x in self._far if abs(x - t) <= CLOCK_JUMP][-4 * len(self.meters) :]
        far.append((j, t))
        latest = dict(far)
        if len(latest) * 2 <= len(self.meters) or len(far) < 2:
            self._far = far
            return None
        self._far = []
        self._newest[:] = [latest.get(i, math.nan) for i in range(len(self.meters))]
        self._reference = self._start = float(statistics.median(latest.values()))
        self._since = 0
        for i, h in enumerate(self._health):
            h.last = latest.get(i)
            h.deviations.clear()
        self._lead.clear()
        return self._reference

    def _implausible(self, where: str, meter: str, value: float) -> BadReading:
        return BadReading(
            where,
            f"implausible value {value:g} m from meter {meter!r} (believable: "
            f"{self._low[meter]:g} to {self._high[meter]:g} m)",
            meter,
        )

    def _settle_clock(self, h: MeterHealth, ref: float) -> bool:
        """Estimate the meter's clock offset from its recent deviations; True if now on time."""
        if len(h.deviations) < CLOCK_WINDOW:
            return False
        mid = statistics.median(h.deviations)
        agree = sum(abs(d - mid) <= self.clock_tolerance for d in h.deviations)
        if agree < 0.8 * len(h.deviations):
            return False
        lead = statistics.median(self._lead) if self._lead else 0.0
        unit = max(self.capture_interval, 1.0)  # clocks slip by whole seconds (or hours)
        h.clock_offset = round(round((mid - lead) / unit) * unit, 9)
        h.deviations.clear()
        return True

    def _update_reference(self) -> None:
        self._since = 0
        known = [t for t in self._newest if t == t]  # not NaN
        if len(known) * 2 > len(self.meters):
            self._reference = float(statistics.median(known))
            if self._start is None:
                self._start = self._reference

    # ------------------------------------------------------------ bookkeeping
    def late(self, meter: str, count: int = 1) -> None:
        """Count readings of ``meter`` the stream dropped as late."""
        self.meter[meter].counts["late"] += count

    def filled(self, meters: Sequence[str]) -> None:
        """Count readings filled for ``meters`` (a step completed without them)."""
        for m in meters:
            self.meter[m].counts["filled"] += 1

    def update_silence(self) -> tuple[list[str], list[str]]:
        """Mark meters silent (no reading for ``silent_after`` s of reference time) or back;
        return (newly silent, back)."""
        ref = self._reference
        gone: list[str] = []
        back: list[str] = []
        if ref is None:
            return gone, back
        for m, h in self.meter.items():
            since = h.last if h.last is not None else self._start
            silent = since is None or ref - since > self.silent_after
            if silent and not h.silent:
                gone.append(m)
            elif h.silent and not silent:
                back.append(m)
            h.silent = silent
        return gone, back

    @property
    def silent(self) -> tuple[str, ...]:
        """The meters currently silent."""
        return tuple(m for m, h in self.meter.items() if h.silent)

    def replaying(self) -> dict[str, int]:
        """The meters still in their replay after a restart (no newer reading yet), with the
        readings of theirs replayed so far."""
        return {
            m: self._replayed[j]
            for j, m in enumerate(self.meters)
            if self._replay[j] is not None and self._replayed[j]
        }

    def record(self) -> dict[str, Any]:
        """The health record (JSON-ready, ``"type": "health"``)."""
        return {
            "type": "health",
            "time": self._reference,
            "silent": list(self.silent),
            "clock_corrected": {
                m: h.clock_offset for m, h in self.meter.items() if h.clock_offset != 0.0
            },
            "bad_unknown_meter": self.bad_unknown,
            "meters": {m: h.to_json() for m, h in self.meter.items()},
        }

    # ------------------------------------------------------------------ state
    def to_state(self) -> dict[str, Any]:
        """Everything needed to carry on after a restart (JSON-ready)."""
        return {
            "reference": self._reference,
            "start": self._start,
            "bad_unknown": self.bad_unknown,
            "meters": {
                m: {**h.to_json(), "deviations": list(h.deviations)} for m, h in self.meter.items()
            },
        }

    def restore(self, state: Mapping[str, Any]) -> None:
        """Inverse of :meth:`to_state` (same meters)."""
        self._reference = state["reference"]
        self._start = state.get("start", self._reference)
        self.bad_unknown = int(state["bad_unknown"])
        for m, doc in state["meters"].items():
            h = self.meter[m]
            h.last = doc["last"]
            h.silent = bool(doc["silent"])
            h.clock_offset = float(doc["clock_offset"])
            h.counts = {k: int(doc.get(k, 0)) for k in _COUNTS}  # "replayed": newer
            h.deviations = deque(doc["deviations"], maxlen=CLOCK_WINDOW)
            self._replay[self._index[m]] = h.last
            self._replayed[self._index[m]] = 0
            if h.last is not None:
                self._newest[self._index[m]] = h.last
