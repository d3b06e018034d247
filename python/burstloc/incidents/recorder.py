"""The monitor's side of the incident store: a :class:`~burstloc.live.observe.LiveObserver`
that hands each incident to a writer thread and never makes the monitor wait.

On the monitor's thread, :class:`Recorder` turns a decision, transient or event record into an
:class:`~burstloc.incidents.intake.Observed` (the wall-clock time it was seen included) and puts
it on a bounded queue (``put_nowait``: no wait). Meter faults are found in the health records
the loop emits and, at most every :data:`FAULT_EVERY` seconds of wall-clock time, in the health
the periodic check offers: a meter that turns silent, or whose implausible readings grow, opens
a fault; a silent meter that reports again, or :data:`IMPLAUSIBLE_CLEARS` seconds of reading
time without an implausible reading, clears it.

The writer thread takes what is queued, up to :data:`BATCH` items, and stores it in one
transaction (:meth:`burstloc.incidents.store.IncidentStore.take`, SQLite's
``synchronous=NORMAL``: no wait for the disk). It syncs the store
(:meth:`~burstloc.incidents.store.IncidentStore.sync`) after a batch when a second has passed
since the last sync, after a second without news, and at the stop: the monitor's records are on
disk within about a second. A store that cannot be
written (a PostgreSQL server down) is retried with back-off, every failure said; nothing is
dropped while the queue has room. When it has none, the item is dropped, counted in
:attr:`Recorder.dropped` and said at once (at most one message a second, with the count).
:meth:`Recorder.close` stores what is queued and says what could not be stored.

Given a readings directory, the recorder also keeps the readings around each alarm
(:mod:`burstloc.incidents.kept`): the monitor's thread only holds steps and hands a claimed
capture to the queue; the writer thread writes its feed file and stores it on the incident.
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from burstloc.exceptions import OutputError
from burstloc.incidents.errors import IncidentStoreError
from burstloc.incidents.intake import Kept, Observed, from_record, meter_fault
from burstloc.incidents.kept import Capture, ReadingsKeeper, write_feed
from burstloc.incidents.store import SYNC_EVERY, IncidentStore
from burstloc.live.observe import LiveObserver

__all__ = ["BATCH", "FAULT_EVERY", "IMPLAUSIBLE_CLEARS", "QUEUE", "Recorder"]

#: Items the queue holds before new ones are dropped (and said).
QUEUE = 10_000
#: Items stored in one transaction at most.
BATCH = 256
#: Seconds (wall clock) between looks at the periodic check's health for meter faults.
FAULT_EVERY = 1.0
#: Seconds of reading time without a new implausible reading that clear that fault.
IMPLAUSIBLE_CLEARS = 60.0
#: Seconds between retries of a store that cannot be written, doubling up to the second.
RETRY = (0.5, 30.0)

_STOP = object()


class Recorder(LiveObserver):
    """Incidents from the monitor's records to ``store`` on a thread (module docstring).

    ``say`` gets the messages for the operator (stderr); ``committed`` (tests, benchmarks) is
    called on the writer thread with each stored batch and the incidents it changed. With
    ``readings`` (a directory) and ``meters`` (the steps' columns, the configuration's order),
    the readings around each alarm are kept there.
    """

    def __init__(
        self,
        store: IncidentStore,
        say: Callable[[str], None],
        *,
        size: int = QUEUE,
        committed: Callable[[list[Observed | Kept], list[int]], None] | None = None,
        meters: Sequence[str] = (),
        readings: Path | None = None,
    ) -> None:
        self.store = store
        self.say = say
        self.committed = committed
        self.meters = tuple(meters)
        #: Where the readings around each alarm are kept (``None``: not kept).
        self.readings = readings if meters else None
        #: The readings keeper (``None`` without a readings directory).
        self.keeper = None if self.readings is None else ReadingsKeeper(self._put)
        if self.keeper is not None:  # the step of every reading: the cheapest call there is
            self.step = self.keeper.step  # type: ignore[method-assign]
        self.queue: queue.Queue[Any] = queue.Queue(maxsize=size)
        #: Items dropped because the queue was full; items stored; failed writes (retried).
        self.dropped = self.stored = self.failures = 0
        #: Items put on the queue (the monitor's thread) and items taken and stored or left
        #: behind (the writer's): :meth:`flush` waits until the second reaches the first.
        self.queued = self.handled = 0
        self._handled = threading.Condition()
        self._said_drop = 0.0
        self._faults: dict[tuple[str, str], bool] = {}  # (meter, fault) -> active
        self._implausible: dict[str, tuple[int, float | None]] = {}  # count, reading time
        self._next_look = 0.0
        self._closing = threading.Event()
        self._thread = threading.Thread(target=self._run, name="burstloc-incidents", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ the monitor's thread
    def _put(self, item: Observed | Capture) -> None:
        try:
            self.queue.put_nowait(item)
            self.queued += 1
        except queue.Full:
            self.dropped += 1
            now = time.monotonic()
            if now - self._said_drop >= 1.0:
                self._said_drop = now
                self.say(
                    f"the incident store is behind ({self.store.where}): an incident record "
                    f"was not stored ({self.dropped} so far)"
                )

    def record(self, record: dict[str, Any]) -> None:
        """A decision, transient or event: queued; a health record: looked at for faults."""
        if record.get("type") == "health":
            self._look(record)
            return
        item = from_record(record, time.time())
        if item is not None:
            self._put(item)
            if self.keeper is not None and item.reading_time is not None:
                self.keeper.claim(item.key, item.reading_time)
        health = record.get("health")
        if isinstance(health, dict):
            self._look(health)

    def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
        """A meter's first alarm toward a decision: the readings around it are kept."""
        if self.keeper is not None:
            self.keeper.alarm(time, onset)

    def tick(self, health: Callable[[], dict[str, Any]]) -> None:
        """Look at the health for meter faults every :data:`FAULT_EVERY` s (wall clock)."""
        now = time.monotonic()
        if now >= self._next_look:
            self._next_look = now + FAULT_EVERY
            self._look(health())

    def _look(self, health: dict[str, Any]) -> None:
        """Faults that began or cleared since the last look."""
        t = health.get("time")
        meters = health.get("meters") or {}
        silent = set(health.get("silent") or ()) | set(health.get("excluded") or ())
        for meter, doc in meters.items():
            self._set(meter, "silent", meter in silent, t)
            count = int(doc.get("implausible", 0) or 0)
            before, since = self._implausible.get(meter, (0, None))
            if count > before:
                self._implausible[meter] = (count, t)
                self._set(meter, "implausible", True, t)
            elif since is not None and t is not None and t - since >= IMPLAUSIBLE_CLEARS:
                self._implausible[meter] = (count, None)
                self._set(meter, "implausible", False, t)
            else:
                self._implausible.setdefault(meter, (count, since))

    def _set(self, meter: str, fault: str, active: bool, t: float | None) -> None:
        if self._faults.get((meter, fault), False) == active:
            return
        self._faults[(meter, fault)] = active
        self._put(meter_fault(meter, fault, active, time.time(), t))

    # ------------------------------------------------------------------ the writer thread
    def _run(self) -> None:
        delay = RETRY[0]
        batch: list[Any] = []
        taken = 0  # the queue's items in ``batch``
        while True:
            if not batch:
                try:  # records not on disk yet (SQLite): synced after a quiet second
                    item = self.queue.get(timeout=SYNC_EVERY if self.store.unsynced else None)
                except queue.Empty:
                    self._sync("incidents not synced to disk, tried again later")
                    continue
                if item is _STOP:
                    self._sync_last()
                    return
                batch.append(item)
                stop = False
                while len(batch) < BATCH:
                    try:
                        more = self.queue.get_nowait()
                    except queue.Empty:
                        break
                    if more is _STOP:
                        stop = True
                        break
                    batch.append(more)
                taken = len(batch)
            else:
                stop = False
            batch = self._written(batch)
            try:
                changed = self.store.take(batch)
            except IncidentStoreError as exc:
                self.failures += 1
                self.say(f"incidents not stored yet, retried in {delay:g} s: {exc}")
                if self._closing.wait(delay):
                    self._closing.clear()  # closing: one more try now, then give up
                    try:
                        changed = self.store.take(batch)
                    except IncidentStoreError:
                        self.say(f"{len(batch) + self.queue.qsize()} incident records not stored")
                        self._handle(self.queued - self.handled)
                        return
                else:
                    delay = min(2 * delay, RETRY[1])
                    continue
            delay = RETRY[0]
            self.stored += len(batch)
            if self.committed is not None:
                self.committed(batch, changed)
            batch = []
            self._handle(taken)
            if self.store.sync_due():  # busy: on disk once a second all the same
                self._sync("incidents not synced to disk, tried again later")
            if stop:
                self._sync_last()
                return

    def _handle(self, count: int) -> None:
        with self._handled:
            self.handled += count
            self._handled.notify_all()

    def flush(self, timeout: float = 10.0) -> bool:
        """Wait until everything queued so far is stored (``False`` if it was not within
        ``timeout`` s: the store is down, or behind). A replayed file's alerts follow its clock
        with it (:mod:`burstloc.incidents.alerts.pacing`); the live monitor never waits."""
        target = self.queued
        with self._handled:
            return self._handled.wait_for(lambda: self.handled >= target, timeout)

    def _written(self, batch: list[Any]) -> list[Observed | Kept]:
        """``batch`` with each capture written to its feed file (a file that cannot be written
        is said, and its incident keeps no readings)."""
        out: list[Observed | Kept] = []
        for item in batch:
            if isinstance(item, Capture):
                assert self.readings is not None  # captures come only from the keeper
                try:
                    out.append(write_feed(item, self.meters, self.readings))
                except OutputError as exc:
                    what = f"the readings around the alarm at t = {item.first:g} s"
                    self.say(f"{what} not kept: {exc}")
            else:
                out.append(item)
        return out

    def _sync(self, failed: str) -> None:
        """What was committed, on disk; a failure said (``failed``: what it means)."""
        try:
            self.store.sync()
        except IncidentStoreError as exc:
            self.say(f"{failed}: {exc}")

    def _sync_last(self) -> None:
        """At the stop: what was committed, on disk."""
        if self.store.unsynced:
            self._sync("the last incidents may not be on disk")

    def close(self, timeout: float = 60.0) -> None:
        """Store what is queued, stop the thread (waiting up to ``timeout`` s) and say what was
        not stored."""
        if self.keeper is not None:
            self.keeper.flush()  # the readings of an alarm whose span the feed did not reach
        with contextlib.suppress(queue.Full):  # the writer is stuck: said below
            self.queue.put(_STOP, timeout=timeout)
        self._closing.set()
        self._thread.join(timeout)
        if self._thread.is_alive():
            self.say(f"the incident store is still writing after {timeout:g} s; left behind")
        if self.dropped:
            self.say(f"{self.dropped} incident records were not stored (the queue was full)")
