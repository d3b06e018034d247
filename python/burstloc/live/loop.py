"""The live loop: parsed readings in, decision and health records out; bad data never stops it.

:class:`LiveLoop` wires :class:`~burstloc.live.health.Health` (plausible range, clock, silence),
:class:`~burstloc.live.stream.ReadingStream` (complete steps; silent meters excluded) and
:class:`~burstloc.live.monitor.BurstMonitor`. For every input item:

* a :class:`~burstloc.live.parse.BadReading`, an implausible reading, a reading from an unknown
  meter, a step the monitor refuses: counted, reported (rate-limited, :class:`Reporter`),
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

import math
import time
from collections.abc import Callable, Iterable
from typing import Any

from burstloc.exceptions import InputError, OutputError, StreamError
from burstloc.live.health import Health
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading
from burstloc.live.state import StateFile
from burstloc.live.stream import ReadingStream
from burstloc.readings import Reading, Step

__all__ = ["LiveLoop", "Reporter"]

Record = dict[str, Any]
Item = Reading | BadReading | tuple[str, Reading | BadReading] | None


class Reporter:
    """Rate-limited messages: per kind, at most ``burst`` messages per ``every`` seconds; the
    number held back is told with the next message of that kind and by :meth:`close`."""

    def __init__(
        self, write: Callable[[str], None], *, burst: int = 5, every: float = 10.0
    ) -> None:
        self.write = write
        self.burst = burst
        self.every = every
        self._window: dict[str, tuple[float, int]] = {}
        self._held: dict[str, int] = {}
        self.counts: dict[str, int] = {}

    def __call__(self, kind: str, message: str) -> None:
        """Report ``message`` of ``kind`` unless too many of that kind came lately."""
        self.counts[kind] = self.counts.get(kind, 0) + 1
        now = time.monotonic()
        start, sent = self._window.get(kind, (now, 0))
        if now - start >= self.every:
            start, sent = now, 0
        if sent >= self.burst:
            self._held[kind] = self._held.get(kind, 0) + 1
            self._window[kind] = (start, sent)
            return
        held = self._held.pop(kind, 0)
        suffix = f" ({held} more {kind} messages not shown)" if held else ""
        self.write(f"burstloc monitor: {message}{suffix}")
        self._window[kind] = (start, sent + 1)

    def close(self) -> None:
        """Tell how many messages of each kind were held back and not yet told."""
        for kind, held in sorted(self._held.items()):
            self.write(f"burstloc monitor: {held} more {kind} messages not shown")
        self._held.clear()


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
    ) -> None:
        self.monitor = monitor
        self.health = health
        self.emit = emit
        self.report = report
        #: State saves that failed (reported; the previous state file is kept).
        self.failed_saves = 0
        period = monitor.calibration.capture_interval
        self.stream = ReadingStream(
            monitor.meters, 1, timeout=timeout, missing=missing, period=period
        )
        self.health_every = health_every
        self.state = state
        self.save_every = save_every
        self._next_health: float | None = None
        self._last_save = time.monotonic()
        self._items = 0
        self.decisions = 0
        self.events = 0  # alarms classified other or unsure (with a classifier)

    def feed(self, item: Reading | BadReading, where: str | None = None) -> None:
        """One parsed input item (module docstring); ``where`` names it in reports (default:
        ``"reading N"``, counting the items fed)."""
        self._items += 1
        if isinstance(item, BadReading):
            self.health.bad(item)
            self.report("bad-input", f"bad reading skipped: {item}")
            return
        self.feed_reading(item, f"reading {self._items}" if where is None else where)

    def feed_reading(self, reading: Reading, where: str) -> None:
        """One reading (``where`` names it in reports)."""
        h = self.health.meter.get(reading.meter)
        offset = None if h is None else h.clock_offset
        admitted = self.health.admit(reading, where)
        if h is not None and h.clock_offset != offset:
            self.report(
                "clock-offset",
                f"meter {reading.meter!r}: clock offset {h.clock_offset:+g} s found; its "
                "timestamps are corrected by it",
            )
        if admitted is None:
            self.report(
                "clock", f"{where}: meter {reading.meter!r} is off the clock; reading held back"
            )
            return
        if isinstance(admitted, BadReading):
            self.report("bad-input", f"bad reading skipped: {admitted}")
            return
        late = self.stream.stats.late
        try:
            windows = self.stream.push(admitted)
        except StreamError as exc:
            self.report("bad-input", f"{where}: {exc}")
            return
        if self.stream.stats.late > late:
            self.health.late(admitted.meter)
            self.report("late", f"{where}: late reading from meter {admitted.meter!r} dropped")
        for w in windows:
            self._step(Step(float(w.times[-1]), w.values[-1], w.filled[-1]))
        if self._items % len(self.monitor.meters) == 0:
            self._tick()

    def _step(self, step: Step) -> None:
        if step.filled:
            self.health.filled(step.filled)
        try:
            decided = self.monitor.push(step)
        except InputError as exc:
            self.report("step", str(exc))
            return
        if decided is not None:
            self.decisions += decided.is_burst
            self.events += not decided.is_burst
            record = decided.to_json()
            record["health"] = self.health_record()
            self.emit(record)

    def _tick(self) -> None:
        gone, back = self.health.update_silence()
        for m in gone:
            self.monitor.exclude(m)
            self.stream.excluded.add(m)
            last = self.health.meter[m].last
            since = "ever" if last is None else f"since t = {last:g} s"
            self.report("silence", f"meter {m!r} silent {since}: excluded from localization")
        for m in back:
            self.monitor.include(m)
            self.stream.excluded.discard(m)
            self.report("silence", f"meter {m!r} reports again: included")
        ref = self.health.reference
        if ref is not None and self.health_every > 0:
            if self._next_health is None:
                self._next_health = ref
            if ref >= self._next_health:
                self.emit(self.health_record())
                self._next_health = ref + self.health_every
        if self.state is not None and time.monotonic() - self._last_save >= self.save_every:
            self.save()

    def tick(self) -> None:
        """Periodic work without input (silence, health, state save): call when idle."""
        self._tick()

    def run(self, items: Iterable[Item]) -> None:
        """Feed every item, or ``(where, item)`` pair (``None``: an idle tick), then
        :meth:`finish`."""
        for item in items:
            if item is None:
                self._tick()
            elif isinstance(item, tuple):
                self.feed(item[1], item[0])
            else:
                self.feed(item)
        self.finish()

    def finish(self) -> None:
        """End of feed: resolve pending steps, say what was held back, save the state."""
        for w in self.stream.flush():
            self._step(Step(float(w.times[-1]), w.values[-1], w.filled[-1]))
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
            "monitor": self.monitor.to_state(),
            "stream": self.stream.to_state(),
            "health": self.health.to_state(),
            "loop": {
                "next_health": self._next_health,
                "decisions": self.decisions,
                "events": self.events,
            },
        }

    def restore(self, state: Record) -> None:
        """Carry on from :meth:`to_state`."""
        self.monitor.restore(state["monitor"])
        self.stream.restore(state["stream"])
        self.health.restore(state["health"])
        nxt = state["loop"]["next_health"]
        self._next_health = None if nxt is None or not math.isfinite(nxt) else float(nxt)
        self.decisions = int(state["loop"]["decisions"])
        self.events = int(state["loop"].get("events", 0))  # states saved before classifying
