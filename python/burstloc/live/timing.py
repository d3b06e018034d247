"""How long the monitor takes to answer: each record timed from the step that produced it.

A :class:`RecordTimer` is a :class:`~burstloc.live.observe.LiveObserver` that notes the wall
clock at every step fed to the monitor and, when a decision, transient or event record comes
out, observes the time since (the localization and the record's output: stdout, MQTT) in a
:class:`Histogram` per record type; a decision's ``decision_delay_s`` (reading time from the
first alarm to the answer) goes into its own histogram. Everything else it is told it hands on
to ``inner`` (the page's hub), so it sits in front of another observer at the cost of one call
and one clock reading per step. The service's metrics (:mod:`burstloc.web.metrics`) read the
histograms from another thread: each :meth:`Histogram.observe` and :meth:`Histogram.snapshot`
holds the histogram's lock (records are rare; steps take no lock).
"""

from __future__ import annotations

import bisect
import math
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

from burstloc.live.observe import LiveObserver
from burstloc.readings import Step

__all__ = ["DELAY_BUCKETS", "LATENCY_BUCKETS", "TIMED", "Histogram", "HistogramSnapshot",
           "RecordTimer"]  # fmt: skip

#: Upper bounds (s, wall clock) of the latency histogram's buckets: from half a millisecond
#: (a decision on a small network) to 2.5 s (far beyond any measured).
LATENCY_BUCKETS = (0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5)

#: Upper bounds (s of reading time) of the decision delay's buckets: first alarm to answer.
DELAY_BUCKETS = (0.5, 1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 60.0, 120.0, 300.0)

#: The record types timed.
TIMED = ("decision", "transient", "event")


class HistogramSnapshot(NamedTuple):
    """A histogram at one instant: ``bounds`` and the ``cumulative`` count at or below each
    (then the count of every observation, the ``+Inf`` bucket), their ``total`` and ``number``."""

    bounds: tuple[float, ...]
    cumulative: tuple[int, ...]
    total: float
    number: int


class Histogram:
    """Observations counted in buckets of fixed upper ``bounds`` (thread-safe)."""

    def __init__(self, bounds: Sequence[float]) -> None:
        if list(bounds) != sorted(set(bounds)) or not all(math.isfinite(b) for b in bounds):
            raise ValueError(f"bucket bounds must be finite and increasing, got {bounds!r}")
        self.bounds = tuple(float(b) for b in bounds)
        self._counts = [0] * (len(self.bounds) + 1)
        self._total = 0.0
        self._lock = threading.Lock()

    def observe(self, value: float) -> None:
        """Count ``value`` (a non-finite one is not counted)."""
        if not math.isfinite(value):
            return
        k = bisect.bisect_left(self.bounds, value)
        with self._lock:
            self._counts[k] += 1
            self._total += value

    def snapshot(self) -> HistogramSnapshot:
        """The counts now, cumulative as Prometheus' buckets are."""
        with self._lock:
            counts, total = list(self._counts), self._total
        cumulative, running = [], 0
        for c in counts:
            running += c
            cumulative.append(running)
        return HistogramSnapshot(self.bounds, tuple(cumulative), total, running)


class RecordTimer(LiveObserver):
    """Times the records, tells ``inner`` everything (module docstring)."""

    def __init__(
        self, inner: LiveObserver | None = None, *, clock: Callable[[], float] = time.perf_counter
    ) -> None:
        self.inner = inner
        #: Wall-clock seconds from the step to the record, per record type (:data:`TIMED`).
        self.latency = {kind: Histogram(LATENCY_BUCKETS) for kind in TIMED}
        #: A decision's ``decision_delay_s``: reading time from its first alarm.
        self.delay = Histogram(DELAY_BUCKETS)
        self._clock = clock
        self._started = clock()
        self._step = inner.step if inner is not None else None

    def step(self, step: Step) -> None:
        """Note the time; hand the step on."""
        self._started = self._clock()
        forward = self._step
        if forward is not None:
            forward(step)

    def record(self, record: dict[str, Any]) -> None:
        """Time a decision, transient or event record; hand it on."""
        kind = record.get("type")
        if kind in self.latency:
            self.latency[kind].observe(self._clock() - self._started)
            delay = record.get("decision_delay_s")
            if kind == "decision" and isinstance(delay, (int, float)):
                self.delay.observe(float(delay))
        if self.inner is not None:
            self.inner.record(record)

    def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
        """Hand the alarm on."""
        if self.inner is not None:
            self.inner.alarm(meter, time, onset, amplitude)

    def message(self, text: str) -> None:
        """Hand the message on."""
        if self.inner is not None:
            self.inner.message(text)

    def tick(self, health: Callable[[], dict[str, Any]]) -> None:
        """Hand the periodic check on."""
        if self.inner is not None:
            self.inner.tick(health)
