"""The readings around each alarm, kept beside the incident store: what a burst found later
needs to become a known event for calibration (``burstloc incidents known-events``).

On the monitor's thread, :class:`ReadingsKeeper` holds the steps of the last twice
:data:`BEFORE` seconds (reading time: an onset may come well before its alarm). A meter's first
alarm toward a decision opens a *capture* when none is being filled: the steps held since
:data:`BEFORE` s before the alarm's onset, then every step up to :data:`AFTER` s after the
newest of its alarms (at most :data:`LONGEST` s after its first). An alarm's record (the early
record, the decision or the event) claims the capture holding its first alarm; a claimed capture
is handed on once, when it is complete (or at the stop, with what it holds). Captures nobody
claims (a lone meter's alarms, dismissed) are let go once :data:`CAPTURES` newer ones exist.
Nothing here waits: the recorder's writer thread writes a handed capture (:func:`write_feed`) as
a feed file (CSV ``timestamp,meter,value``, as ``burstloc monitor --readings`` reads it; filled
values left out) into the readings directory beside the store (:func:`readings_dir`),
atomically, and the store records the file and the onset on the incident
(:class:`~burstloc.incidents.intake.Kept`). The file's text is made in Rust, about
:data:`CHUNK` readings per call (``burstloc._core.feed_lines``: every number as ``repr`` writes
it, so it reads back exactly), which holds the GIL only to read the steps and makes the text
without it, so that the writer thread leaves the GIL to the monitor's thread: a longest capture
(33 meters at 250 Hz, :data:`LONGEST` s) is 5 million lines, and the same lines written by a
Python loop held the monitor up for a quarter of a second at a time; made by NumPy, whose every
operation gives the GIL up and takes it back, they cost the writer four to five times the CPU
(``benches/bench_kept.py``).
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

from burstloc._core import feed_lines
from burstloc.incidents.intake import Kept
from burstloc.readings import CSV_HEADER, Step

__all__ = [
    "AFTER",
    "BEFORE",
    "CAPTURES",
    "CHUNK",
    "LONGEST",
    "Capture",
    "ReadingsKeeper",
    "readings_dir",
    "write_feed",
]

#: Seconds of readings kept before an alarm's onset: the detectors' level before the change
#: (calibration runs the calibrated detectors over the file from its start).
BEFORE = 30.0
#: Seconds of readings kept after the newest alarm: every meter's wave has arrived by then on
#: the networks shipped (their arrival horizons are a few seconds).
AFTER = 30.0
#: Seconds after its first alarm past which a capture takes no more steps.
LONGEST = 600.0
#: Unclaimed captures kept (a record may claim one after it is complete).
CAPTURES = 4
#: Readings a feed file's text is made of per call (:func:`feed_bytes`): each call holds the GIL
#: while it reads its steps (about half a millisecond for 32 768 readings), then makes their text
#: without it.
CHUNK = 1 << 15
#: Seconds within which an alarm's reading time and a record's ``first_alarm`` agree (records
#: write times to the microsecond).
_SAME = 1e-5


@dataclass
class Capture:
    """The steps around one run of alarms: ``first`` (reading time of its first alarm), the
    steps up to ``end``, the ``(time, onset)`` of each alarm; ``key`` the incident that claimed
    it and ``first_alarm`` that incident's first alarm."""

    first: float
    end: float
    steps: list[Step]
    alarms: list[tuple[float, float]]
    complete: bool = False
    key: str | None = None
    first_alarm: float | None = None
    handed: bool = False

    def holds(self, first_alarm: float) -> bool:
        """Whether one of its alarms is the record's first alarm."""
        return any(abs(t - first_alarm) <= _SAME for t, _ in self.alarms)

    @property
    def onset(self) -> float | None:
        """The earliest onset of the alarms from the claiming record's first alarm on."""
        since = self.first if self.first_alarm is None else self.first_alarm
        onsets = [o for t, o in self.alarms if t >= since - _SAME]
        return min(onsets) if onsets else None


class ReadingsKeeper:
    """The readings around each alarm (module docstring); every method returns at once.

    ``hand`` takes each claimed capture once (the recorder queues it for its writer thread).
    """

    def __init__(self, hand: Callable[[Capture], None]) -> None:
        self.hand = hand
        self._recent: deque[Step] = deque()
        self._captures: deque[Capture] = deque()

    def step(self, step: Step) -> None:
        """A step: held for twice :data:`BEFORE` s, and added to the capture being filled."""
        recent = self._recent
        recent.append(step)
        t = step.timestamp
        while recent[0].timestamp < t - 2.0 * BEFORE:  # an onset may come well before its alarm
            recent.popleft()
        if self._captures and not self._captures[-1].complete:
            capture = self._captures[-1]
            if t <= capture.end:
                capture.steps.append(step)
            else:
                capture.complete = True
                self._hand(capture)

    def alarm(self, time: float, onset: float) -> None:
        """A meter's first alarm toward a decision, raised at ``time``, its change after
        ``onset`` (reading times)."""
        last = self._captures[-1] if self._captures else None
        if last is not None and not last.complete:
            last.alarms.append((time, onset))
            last.end = max(last.end, min(time + AFTER, last.first + LONGEST))
            return
        since = onset - BEFORE
        steps = [s for s in self._recent if s.timestamp >= since]
        self._captures.append(Capture(time, time + AFTER, steps, [(time, onset)]))
        while len(self._captures) > CAPTURES + 1:
            self._captures.popleft()

    def claim(self, key: str, first_alarm: float) -> None:
        """An alarm's record (incident ``key``) whose first alarm is at ``first_alarm``."""
        for capture in reversed(self._captures):
            if capture.holds(first_alarm):
                if capture.key is None:
                    capture.key, capture.first_alarm = key, first_alarm
                    if capture.complete:
                        self._hand(capture)
                return

    def flush(self) -> None:
        """At the stop: hand on every claimed capture not handed yet, with what it holds."""
        for capture in self._captures:
            capture.complete = True
            self._hand(capture)

    def _hand(self, capture: Capture) -> None:
        if capture.key is not None and not capture.handed:
            capture.handed = True
            self.hand(capture)


def readings_dir(store: Any, state: str | None) -> Path | None:
    """Where the readings of ``store``'s incidents are kept: beside an SQLite store
    (``incidents.sqlite`` → ``incidents.readings/``), else beside the monitor's ``state`` file
    (``monitor.json`` → ``monitor.readings/``); ``None`` when neither is on this machine."""
    database = store.engine.url.database if store.engine.dialect.name == "sqlite" else None
    if database:
        return Path(os.path.splitext(os.path.abspath(database))[0] + ".readings")
    if state is not None:
        return Path(os.path.splitext(os.path.abspath(state))[0] + ".readings")
    return None


def write_feed(capture: Capture, meters: Sequence[str], directory: Path) -> Kept:
    """Write ``capture``'s steps (columns ``meters``) as a feed file in ``directory``,
    atomically; the :class:`Kept` the store takes.

    Raises:
        OutputError: the file cannot be written.
    """
    from burstloc._atomic import atomic_write

    assert capture.key is not None  # only claimed captures are handed on
    first = capture.first if capture.first_alarm is None else capture.first_alarm
    path = directory / f"alarm-{first:.6f}.csv"

    def write(f: IO[bytes]) -> None:
        for chunk in feed_bytes(capture.steps, meters):
            f.write(chunk)

    atomic_write(path, write)
    return Kept(capture.key, str(path.resolve()), capture.onset)


def feed_bytes(steps: Sequence[Step], meters: Sequence[str]) -> Iterator[bytes]:
    """The feed file of ``steps`` (columns ``meters``) in pieces of about :data:`CHUNK`
    readings: the header, then ``timestamp,meter,value`` per reading (filled values and values
    that are not finite left out), each number as ``repr`` writes it (it reads back exactly).

    Raises:
        InputError: a step without one value per meter (a :class:`ValueError`).
    """
    yield (",".join(CSV_HEADER) + "\n").encode("utf-8")
    names = list(meters)
    every = max(1, CHUNK // max(1, len(names)))
    for start in range(0, len(steps), every):
        yield feed_lines(steps[start : start + every], names)
