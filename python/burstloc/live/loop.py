"""The live loop: parsed readings in, decision and health records out; bad data never stops it.

:class:`LiveLoop` wires :class:`~burstloc.live.health.Health` (plausible range, clock, silence),
:class:`~burstloc.live.feeds.StepFeed` (complete steps; silent meters excluded) and
:class:`~burstloc.live.monitor.BurstMonitor`. For every input item:

* a :class:`~burstloc.live.parse.BadReading` (a timestamp in another form than the feed's
  included), an implausible reading, a reading from an unknown meter, a timestamp more than a
  day from the feed's clock (:data:`~burstloc.live.health.CLOCK_JUMP`), a step the monitor
  refuses: counted, reported (rate-limited, :class:`~burstloc.live.reporter.Reporter`),
  skipped; the loop goes on;
* a meter that goes silent or comes back, a clock offset found and corrected: reported;
  the monitor and the stream exclude / include the meter;
* a decision: emitted as a record (``"type": "decision"``, with the health at decision time;
  with a classifier, an alarm that is not a burst is an ``"event"`` record, counted apart);
* every ``health_every`` seconds of reading time: a health record (``"type": "health"``).

Records go to ``emit`` (stdout, MQTT: the caller's choice); both kinds go the same way and
neither waits for the other. With a :class:`~burstloc.live.state.StateFile` the whole state is
saved every ``save_every`` seconds (wall clock) and by :meth:`LiveLoop.save`.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import time
from collections.abc import Callable, Iterable
from typing import Any

from burstloc.exceptions import InputError, OutputError
from burstloc.live.feeds import StepFeed
from burstloc.live.health import AdmittedRow, Health
from burstloc.live.monitor import BurstMonitor
from burstloc.live.monitor_state import monitor_state, restore_monitor
from burstloc.live.observe import LiveObserver
from burstloc.live.parse import BadReading, Row, TimestampForm, parse_row, unknown_meter
from burstloc.live.reporter import Reporter
from burstloc.live.state import StateFile
from burstloc.readings import Reading, Step

__all__ = ["LiveLoop"]

Record = dict[str, Any]
Item = Reading | BadReading | tuple[str, Reading | BadReading | bytes | Row] | None


def _position(item: tuple[int, BadReading]) -> int:
    return item[0]


def _finite(x: object) -> bool:
    try:
        return math.isfinite(x)  # type: ignore[arg-type]
    except TypeError:
        return False


class LiveLoop:
    """Health gate + stream + monitor, never stopped by bad data (module docstring)."""

    def __init__(
        self,
        monitor: BurstMonitor,
        health: Health,
        emit: Callable[[Record], None],
        report: Reporter,
        *,
        timeout: int = 3,
        missing: str = "hold",
        health_every: float = 60.0,
        state: StateFile | None = None,
        save_every: float = 5.0,
        observer: LiveObserver | None = None,
    ) -> None:
        self.monitor = monitor
        #: Told of every step, alarm and record (:mod:`burstloc.live.observe`).
        self.observer = observer
        monitor.observer = observer
        self.health = health
        self.emit = emit
        self.report = report
        #: State saves that failed (reported; the previous state file is kept).
        self.failed_saves = 0
        period = monitor.calibration.capture_interval
        self.stream = StepFeed(monitor.meters, timeout=timeout, missing=missing, period=period)
        self.health_every = health_every
        self.state = state
        self.save_every = save_every
        self._next_health: float | None = None
        self._last_save = time.monotonic()
        self._items = 0
        self._readings = 0  # items that were readings of a configured meter
        self._columns = {m: j for j, m in enumerate(monitor.meters)}
        #: The form of the feed's timestamps (seconds or ISO 8601), fixed by its first reading
        #: in this run (not kept across a restart: a feed may change its form while the monitor
        #: is down): the messages (:meth:`feed_payload`) and whoever parses the feed's lines
        #: share it.
        self.timestamps = TimestampForm()
        self.decisions = 0
        self.events = 0  # alarms classified other or unsure (with a classifier)
        self.transients = 0  # early records of alarms still to be classified

    def feed(self, item: Reading | BadReading, where: str | None = None) -> None:
        """One parsed input item (module docstring); ``where`` names it in reports (default:
        ``"reading N"``, counting the items fed)."""
        where = f"reading {self._items + 1}" if where is None else where
        if isinstance(item, BadReading):
            self._feed_row(Row([], [], [], [], [(0, item)], 1), where)
        else:
            self.feed_reading(item, where)

    def feed_reading(self, reading: Reading, where: str) -> None:
        """One reading (``where`` names it in reports)."""
        j = self._columns.get(reading.meter)
        t, value = reading.timestamp, reading.value
        if not (_finite(t) and _finite(value)):
            what = f"not a finite reading ({t!r} s, {value!r} m) from meter {reading.meter!r}"
            row = Row([], [], [], [], [(0, BadReading(where, what, reading.meter))], 1)
        elif j is None:
            row = Row([], [], [], [], [(0, unknown_meter(where, reading.meter))], 1)
        else:
            row = Row([0], [float(t)], [j], [float(value)], [], 1)
        self._feed_row(row, where)

    def feed_payload(self, payload: bytes, where: str) -> None:
        """One message (:func:`~burstloc.live.parse.parse_payload`: a JSON reading, a batch,
        CSV lines), taken as a row (:func:`~burstloc.live.parse.parse_row`): the same
        decisions, health and reports as its items fed one by one (:meth:`feed`), at a fraction
        of the cost. The health in a decision record is the health after the readings of the
        message up to the next periodic check (one by one: up to the reading that completed
        the decision)."""
        self._feed_row(parse_row(payload, where, self._columns, self.timestamps), where)

    def feed_row(self, row: Row, where: str) -> None:
        """A parsed row over the configuration's meters (a file's lines,
        :func:`~burstloc.live.lines.rows_of_lines`, or a message, as :meth:`feed_payload`
        parses it), as its items fed one by one; reports name each item's line when the row
        has them, else ``where``."""
        self._feed_row(row, where)

    def _feed_row(self, row: Row, where: str) -> None:
        """The items of ``row`` in order, as one by one: the periodic check (:meth:`tick`)
        follows every ``len(meters)``-th item when it is an admitted reading, so the row is
        taken in parts that end there, each admitted by the health gate, assembled into steps
        and the steps fed to the monitor."""
        first, n = self._items, len(self.monitor.meters)
        good = bad = 0
        for end in [*range((-first - 1) % n, row.size, n), row.size - 1]:
            if end < 0 or (good == len(row.positions) and bad == len(row.bad)):
                break
            upto = bisect.bisect_right(row.positions, end)
            stop = bisect.bisect_right(row.bad, end, key=_position) if row.bad else 0
            self._part(row, where, slice(good, upto), row.bad[bad:stop], end)
            good, bad = upto, stop
        self._items = first + row.size
        self._readings += len(row.positions)

    def _part(
        self, row: Row, where: str, part: slice, bad: list[tuple[int, BadReading]], end: int
    ) -> None:
        """Items of ``row`` up to position ``end``: its readings ``part`` and ``bad`` items."""
        meters = self.monitor.meters
        lines = row.lines

        def at(position: int) -> str:  # what a report names: the item's line, or the payload
            return where if lines is None else f"line {lines[position]}"

        events: list[tuple[int, int, str, str]] = []  # (position, order, kind, message)
        for position, item in bad:
            self.health.bad(item)
            events.append((position, 0, "bad-input", f"bad reading skipped: {item}"))
        ok = self.health.admit_row(
            row.times[part], row.columns[part], row.values[part], where, row.positions[part]
        )
        for position, j, offset in ok.offsets:
            message = (
                f"meter {meters[j]!r}: clock offset {offset:+g} s found; its timestamps are "
                "corrected by it"
            )
            events.append((position, 0, "clock-offset", message))
        for position, before, after in ok.moved:
            message = (
                f"{at(position)}: the feed's clock moved by "
                f"{(after - before) / 86_400.0:+.4g} days "
                f"(t = {before:.12g} s to {after:.12g} s): readings of most meters agree; the "
                "readings far from the clock before them were skipped"
            )
            events.append((position, 0, "clock", message))
        for position, j, count in ok.replayed:
            message = (
                f"meter {meters[j]!r}: {count} readings sent again after the restart (seen "
                "before it) skipped"
            )
            events.append((position, 0, "replay", message))
        for position, j, refused in ok.refused:
            if refused is None:
                message = f"{at(position)}: meter {meters[j]!r} is off the clock; reading held back"
                events.append((position, 1, "clock", message))
            else:
                if lines is not None:
                    refused = dataclasses.replace(refused, where=at(position))
                events.append((position, 1, "bad-input", f"bad reading skipped: {refused}"))
        if events:
            events.sort()
        tick = (
            bool(ok.positions)
            and ok.positions[-1] == end
            and (self._items + end + 1) % len(meters) == 0
        )
        if ok.positions:
            self._segment(ok, at, events, end if tick else None)
        self._report_until(events, end + 1)

    def _segment(
        self,
        ok: AdmittedRow,
        at: Callable[[int], str],
        events: list[tuple[int, int, str, str]],
        tick: int | None,
    ) -> None:
        """Admitted readings to the step feed and their steps to the monitor, reports in the
        order of the items (``at(position)`` names an item); then the periodic check after
        position ``tick``."""
        columns = ok.columns
        steps, late = self.stream.push_admitted(ok.times, columns, ok.values)
        if late:
            for k in late:
                meter = self.monitor.meters[columns[k]]
                self.health.late(meter)
                message = f"{at(ok.positions[k])}: late reading from meter {meter!r} dropped"
                events.append((ok.positions[k], 2, "late", message))
            events.sort()
        for position, step in steps:
            self._report_until(events, position + 1)
            self._step(step)
        if tick is not None:
            self._report_until(events, tick + 1)
            self._tick()

    def _report_until(self, events: list[tuple[int, int, str, str]], end: int) -> None:
        """Report (and remove) the events of the items before position ``end``."""
        if not events:
            return
        done = 0
        while done < len(events) and events[done][0] < end:
            self.report(events[done][2], events[done][3])
            done += 1
        del events[:done]

    def _step(self, step: Step) -> None:
        if step.filled:
            self.health.filled(step.filled)
        if self.observer is not None:
            self.observer.step(step)
        try:
            decided = self.monitor.push(step)
        except InputError as exc:
            self.report("step", str(exc))
            return
        if decided is not None:
            self.transients += decided.transient
            self.decisions += decided.is_burst
            self.events += not (decided.is_burst or decided.transient)
            record = decided.to_json()
            record["health"] = self.health_record()
            self._emit(record)

    def _tick(self) -> None:
        gone, back = self.health.update_silence()
        for m in gone:
            self.monitor.exclude(m)
            self.stream.excluded.add(m)
            last = self.health.meter[m].last
            what = "never heard from" if last is None else f"silent since t = {last:g} s"
            self.report("silence", f"meter {m!r} {what}: excluded from localization")
        for m in back:
            self.monitor.include(m)
            self.stream.excluded.discard(m)
            self.report("silence", f"meter {m!r} reports again: included")
        if gone:
            for step in self.stream.drain():  # steps that waited only for the silent meters
                self._step(step)
        ref = self.health.reference
        if ref is not None and self.health_every > 0:
            if self._next_health is None:
                self._next_health = ref
            if ref >= self._next_health:
                self._emit(self.health_record())
                self._next_health = ref + self.health_every
        if self.observer is not None:
            self.observer.tick(self.health_record)
        if self.state is not None and time.monotonic() - self._last_save >= self.save_every:
            self.save()

    def _emit(self, record: Record) -> None:
        self.emit(record)
        if self.observer is not None:
            self.observer.record(record)

    @property
    def readings(self) -> int:
        """Items fed so far that were readings of a configured meter (bad ones not counted)."""
        return self._readings

    def tick(self) -> None:
        """Periodic work without input (silence, health, state save): call when idle."""
        self._tick()

    def run(self, items: Iterable[Item]) -> None:
        """Feed every item, or ``(where, item)`` pair (an item: a reading, a bad reading, a
        message's payload as bytes, or a parsed row; ``None``: an idle tick), then
        :meth:`finish`."""
        for item in items:
            if item is None:
                self._tick()
            elif isinstance(item, tuple):
                where, what = item
                if isinstance(what, Row):
                    self.feed_row(what, where)
                elif isinstance(what, bytes):
                    self.feed_payload(what, where)
                else:
                    self.feed(what, where)
            else:
                self.feed(item)
        self.finish()

    def finish(self) -> None:
        """End of feed: resolve pending steps, say what was held back (and that the feed was empty,
        if it was), save the state."""
        for step in self.stream.flush():
            self._step(step)
        replaying = self.health.replaying()
        if replaying:  # a replay is said when a newer reading ends it: this one never ended
            self.report(
                "replay",
                f"the feed ended in its replay: {sum(replaying.values())} readings of "
                f"{len(replaying)} meter(s) sent again after the restart (seen before it) "
                "skipped, none newer",
            )
        if self._items == 0:
            self.report("input", "the feed held no readings: nothing was monitored")
        elif self._readings == 0:
            self.report(
                "input",
                f"the feed held no usable readings ({self._items} bad, skipped): "
                "nothing was monitored",
            )
        self.report.close()
        self.save()

    def health_record(self) -> Record:
        """The health record with the monitor's state and the stream's counters."""
        record = self.health.record()
        stats = self.stream.stats
        record.update(
            excluded=sorted(self.monitor.excluded),
            pending=self.monitor.pending,
            holding_off=self.monitor.holding_off,
            steps=stats.steps,
            skipped_steps=stats.skipped_steps,
            decisions=self.decisions,
            events=self.events,
            transients=self.transients,
        )
        return record

    # ------------------------------------------------------------------ state
    def save(self) -> None:
        """Write the whole state to the state file (if any), atomically.

        A write that fails (a full disk, a directory gone) keeps the previous state file, is
        counted in :attr:`failed_saves` and reported, and the loop goes on: monitoring matters
        more than its checkpoint.
        """
        self._last_save = time.monotonic()
        if self.state is not None:
            try:
                self.state.save(self.to_state())
            except (OutputError, OSError) as exc:
                self.failed_saves += 1
                self.report("state", f"state not saved ({self.failed_saves} so far): {exc}")

    def to_state(self) -> Record:
        """Monitor, stream, health and loop state, JSON-ready."""
        return {
            "monitor": monitor_state(self.monitor),
            "stream": self.stream.to_state(),
            "health": self.health.to_state(),
            "loop": {
                "next_health": self._next_health,
                "decisions": self.decisions,
                "events": self.events,
                "transients": self.transients,
            },
        }

    def restore(self, state: Record) -> None:
        """Carry on from :meth:`to_state`."""
        restore_monitor(self.monitor, state["monitor"])
        self.stream.restore(state["stream"])
        self.health.restore(state["health"])
        nxt = state["loop"]["next_health"]
        self._next_health = None if nxt is None or not math.isfinite(nxt) else float(nxt)
        self.decisions = int(state["loop"]["decisions"])
        self.events = int(state["loop"].get("events", 0))  # states saved before classifying
        self.transients = int(state["loop"].get("transients", 0))
