"""The monitor's own health for the utility's monitoring: ``GET /metrics`` in Prometheus' text
format.

:class:`MonitorMetrics` reads, when scraped, the counters the live loop keeps anyway (no work
on the monitor's path: :class:`~burstloc.live.loop.LiveLoop`, its
:class:`~burstloc.live.health.Health` and step feed, the MQTT link), and the histograms of the
:class:`~burstloc.live.timing.RecordTimer` in front of the page's hub; each server has its own
``prometheus_client`` registry (with the process's CPU and memory). The metrics:

============================================ ========= =====================================
name                                         type      what
============================================ ========= =====================================
``burstloc_info``                            gauge     1, labels: version, network, detector,
                                                       localizer
``burstloc_meters``                          gauge     meters configured
``burstloc_readings_total``                  counter   readings of configured meters read
                                                       (``rate()`` of it: readings/s)
``burstloc_meter_readings_total``            counter   the same per ``meter``
``burstloc_bad_readings_total``              counter   bad readings skipped, by ``reason``:
                                                       ``bad``, ``implausible``, ``off_clock``,
                                                       ``unknown_meter``
``burstloc_late_readings_total``             counter   readings too late for their step
``burstloc_filled_readings_total``           counter   missing readings filled (``--missing``)
``burstloc_replayed_readings_total``         counter   readings sent again after a restart
``burstloc_steps_total``                     counter   complete time steps fed to the detectors
``burstloc_skipped_steps_total``             counter   incomplete steps skipped
``burstloc_silent_meters``                   gauge     meters silent now (excluded)
``burstloc_meter_silent``                    gauge     1 when ``meter`` is silent
``burstloc_decisions_total``                 counter   bursts located (decision records)
``burstloc_transients_total``                counter   early records
``burstloc_events_total``                    counter   alarms classified not a burst
``burstloc_dismissed_alarms_total``          counter   one meter's alarms dismissed
``burstloc_decision_latency_seconds``        histogram wall clock from the step that completed
                                                       a ``record`` (decision, transient,
                                                       event) to its output
``burstloc_decision_delay_seconds``          histogram reading time from the first alarm to
                                                       the decision
``burstloc_pending``                         gauge     1 while a detected burst awaits its
                                                       decision
``burstloc_holding_off``                     gauge     1 during the hold-off after a decision
``burstloc_feed_time_seconds``               gauge     the feed's clock (its readings' time)
``burstloc_queue_depth``                     gauge     messages waiting, by ``queue``: ``mqtt``
                                                       (readings in), ``page`` (the page's
                                                       inbox)
``burstloc_queue_capacity``                  gauge     the same queues' bounds
``burstloc_dropped_messages_total``          counter   MQTT messages dropped (queue full)
``burstloc_unsent_records_total``            counter   records MQTT could not queue
``burstloc_state_save_failures_total``       counter   state saves that failed
``burstloc_settings_reloads_total``          counter   settings re-read on SIGHUP, by
                                                       ``outcome`` (``applied``, ``refused``)
``burstloc_incidents_open``                  gauge     open incidents (only with an incident
                                                       store: :attr:`MonitorMetrics.incidents_open`)
``burstloc_meter_false_alarms``              gauge     per ``meter``: incidents its alarms made
                                                       that were closed as false alarms (only
                                                       with an incident store, which counts
                                                       them: :attr:`MonitorMetrics.meter_counts`)
``burstloc_meter_alarmed_incidents``         gauge     per ``meter``: incidents its alarms made
``burstloc_webhook_pending``                 gauge     webhook alerts due and not yet delivered
                                                       (only with ``--webhook``:
                                                       :attr:`MonitorMetrics.webhooks`)
``burstloc_webhook_waiting``                 gauge     escalations scheduled, not yet due
``burstloc_webhook_delivered_total``         counter   alerts delivered (a 2xx answer)
``burstloc_webhook_failed_attempts_total``   counter   attempts that failed (retried or not)
``burstloc_webhook_dead_lettered_total``     counter   alerts given up (the dead-letter file)
============================================ ========= =====================================

The webhook counters count since the monitor started; the gauges are read from the outbox.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from burstloc.live.timing import HistogramSnapshot, RecordTimer

if TYPE_CHECKING:
    from burstloc.incidents.outcomes import MeterCounts

__all__ = ["CONTENT_TYPE", "MonitorMetrics"]

#: The exposition's media type (Prometheus' text format 0.0.4).
CONTENT_TYPE = "text/plain; version=0.0.4; charset=utf-8"


@dataclass
class MonitorMetrics:
    """The metrics of one running monitor (module docstring); read on the server's thread.

    ``loop`` is the :class:`~burstloc.live.loop.LiveLoop`, ``timer`` the
    :class:`~burstloc.live.timing.RecordTimer` it tells, ``link`` the
    :class:`~burstloc.live.mqtt.MqttLink` (``None`` for a file or stdin), ``inbox`` the page's
    hub inbox (a bounded ``deque``), ``info`` the labels of ``burstloc_info``.
    """

    loop: Any
    timer: RecordTimer
    link: Any = None
    inbox: Any = None
    info: dict[str, str] = field(default_factory=dict)
    #: How many incidents are open (set by an incident store; ``None``: the gauge is absent).
    incidents_open: Callable[[], int] | None = None
    #: Per meter, its alarms' incidents and their outcomes counted (set with an incident store:
    #: :meth:`~burstloc.incidents.store.IncidentStore.meter_counts`; ``None``: the gauges are
    #: absent).
    meter_counts: Callable[[], list[MeterCounts]] | None = None
    #: The webhook alerts' sender (:class:`~burstloc.incidents.alerts.sender.WebhookSender`;
    #: ``None``: the ``burstloc_webhook_*`` metrics are absent).
    webhooks: Any = None
    #: Settings re-read on SIGHUP, by outcome (``applied``, ``refused``).
    reloads: dict[str, int] = field(default_factory=lambda: {"applied": 0, "refused": 0})
    _registry: Any = field(default=None, init=False, repr=False)

    def exposition(self) -> bytes:
        """The metrics now, in Prometheus' text format (:data:`CONTENT_TYPE`).

        Raises:
            ImportError: ``prometheus_client`` (the ``web`` extra) is not installed.
        """
        from prometheus_client import generate_latest

        if self._registry is None:
            from prometheus_client import CollectorRegistry, ProcessCollector

            registry = CollectorRegistry(auto_describe=False)
            registry.register(_Collector(self))
            ProcessCollector(registry=registry)
            self._registry = registry
        return bytes(generate_latest(self._registry))

    def families(self) -> Iterator[Any]:
        """The monitor's metric families (``prometheus_client`` metric objects)."""
        from prometheus_client.core import (
            CounterMetricFamily,
            GaugeMetricFamily,
            HistogramMetricFamily,
        )

        loop = self.loop
        health = loop.health
        meters = list(health.meters)
        per_meter = [(m, dict(health.meter[m].counts), health.meter[m].silent) for m in meters]

        def total(kind: str) -> int:
            return sum(counts[kind] for _, counts, _ in per_meter)

        def counter(name: str, text: str, value: float) -> Any:
            return CounterMetricFamily(name, text, value=value)

        def gauge(name: str, text: str, value: float) -> Any:
            return GaugeMetricFamily(name, text, value=value)

        info = GaugeMetricFamily("burstloc_info", "the running monitor", labels=sorted(self.info))
        info.add_metric([self.info[k] for k in sorted(self.info)], 1)
        yield info
        yield gauge("burstloc_meters", "meters configured", len(meters))
        yield counter("burstloc_readings", "readings of configured meters read", loop.readings)
        each = CounterMetricFamily(
            "burstloc_meter_readings", "readings read, per meter", labels=["meter"]
        )
        for m, counts, _ in per_meter:
            each.add_metric([m], counts["readings"])
        yield each
        bad = CounterMetricFamily(
            "burstloc_bad_readings", "bad readings skipped, by reason", labels=["reason"]
        )
        for reason in ("bad", "implausible", "off_clock"):
            bad.add_metric([reason], total(reason))
        bad.add_metric(["unknown_meter"], health.bad_unknown)
        yield bad
        yield counter("burstloc_late_readings", "readings too late for their step", total("late"))
        yield counter("burstloc_filled_readings", "missing readings filled", total("filled"))
        yield counter(
            "burstloc_replayed_readings", "readings sent again after a restart", total("replayed")
        )
        stats = loop.stream.stats
        yield counter("burstloc_steps", "complete time steps fed to the detectors", stats.steps)
        yield counter("burstloc_skipped_steps", "incomplete steps skipped", stats.skipped_steps)
        silent = [m for m, _, is_silent in per_meter if is_silent]
        yield gauge("burstloc_silent_meters", "meters silent now (excluded)", len(silent))
        flags = GaugeMetricFamily("burstloc_meter_silent", "1 when silent", labels=["meter"])
        for m, _, is_silent in per_meter:
            flags.add_metric([m], int(is_silent))
        yield flags
        yield counter("burstloc_decisions", "bursts located", loop.decisions)
        yield counter("burstloc_transients", "early records", loop.transients)
        yield counter("burstloc_events", "alarms classified not a burst", loop.events)
        yield counter(
            "burstloc_dismissed_alarms", "alarms of one meter dismissed", loop.monitor.dismissed
        )
        latency = HistogramMetricFamily(
            "burstloc_decision_latency_seconds",
            "wall clock from the step that completed a record to its output",
            labels=["record"],
        )
        for kind, histogram in self.timer.latency.items():
            latency.add_metric([kind], *_histogram(histogram.snapshot()))
        yield latency
        delay = HistogramMetricFamily(
            "burstloc_decision_delay_seconds", "reading time from the first alarm to the decision"
        )
        delay.add_metric([], *_histogram(self.timer.delay.snapshot()))
        yield delay
        monitor = loop.monitor
        yield gauge("burstloc_pending", "1 while a burst awaits its decision", monitor.pending)
        yield gauge("burstloc_holding_off", "1 during a hold-off", monitor.holding_off)
        if health.reference is not None:
            yield gauge("burstloc_feed_time_seconds", "the feed's clock", health.reference)
        yield from self._queues()
        yield counter("burstloc_state_save_failures", "state saves that failed", loop.failed_saves)
        reloads = CounterMetricFamily(
            "burstloc_settings_reloads", "settings re-read on SIGHUP", labels=["outcome"]
        )
        for outcome, count in self.reloads.items():
            reloads.add_metric([outcome], count)
        yield reloads
        if self.incidents_open is not None:
            yield gauge("burstloc_incidents_open", "open incidents", self.incidents_open())
        if self.meter_counts is not None:
            yield from _outcomes(meters, self.meter_counts())
        if self.webhooks is not None:
            yield from _webhooks(self.webhooks)

    def _queues(self) -> Iterator[Any]:
        from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily

        depth = GaugeMetricFamily("burstloc_queue_depth", "messages waiting", labels=["queue"])
        capacity = GaugeMetricFamily("burstloc_queue_capacity", "queue bounds", labels=["queue"])
        if self.link is not None:
            depth.add_metric(["mqtt"], self.link.queued)
            capacity.add_metric(["mqtt"], self.link.capacity)
        if self.inbox is not None:
            depth.add_metric(["page"], len(self.inbox))
            capacity.add_metric(["page"], self.inbox.maxlen or 0)
        yield depth
        yield capacity
        if self.link is not None:
            yield CounterMetricFamily(
                "burstloc_dropped_messages", "MQTT messages dropped", value=self.link.dropped
            )
            yield CounterMetricFamily(
                "burstloc_unsent_records", "records MQTT could not queue", value=self.link.unsent
            )


def _outcomes(meters: list[str], outcomes: list[MeterCounts]) -> Iterator[Any]:
    """The per-meter outcome gauges: every configured meter (0 when it never alarmed), and any
    other meter the store names."""
    from prometheus_client.core import GaugeMetricFamily

    known = {m.meter: m for m in outcomes}
    names = meters + sorted(set(known) - set(meters))
    false = GaugeMetricFamily(
        "burstloc_meter_false_alarms",
        "incidents the meter's alarms made, closed as false alarms",
        labels=["meter"],
    )
    alarmed = GaugeMetricFamily(
        "burstloc_meter_alarmed_incidents", "incidents the meter's alarms made", labels=["meter"]
    )
    for name in names:
        doc = known.get(name)
        false.add_metric([name], 0 if doc is None else doc.false_alarms)
        alarmed.add_metric([name], 0 if doc is None else doc.alarmed)
    yield false
    yield alarmed


def _webhooks(sender: Any) -> Iterator[Any]:
    """The ``burstloc_webhook_*`` families of ``sender``."""
    from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily

    counts = sender.outbox.counts()
    yield GaugeMetricFamily(
        "burstloc_webhook_pending", "webhook alerts due, not delivered", value=counts["pending"]
    )
    yield GaugeMetricFamily(
        "burstloc_webhook_waiting", "escalations scheduled, not due", value=counts["waiting"]
    )
    yield CounterMetricFamily(
        "burstloc_webhook_delivered", "webhook alerts delivered", value=sender.delivered
    )
    yield CounterMetricFamily(
        "burstloc_webhook_failed_attempts",
        "webhook attempts that failed",
        value=sender.failed_attempts,
    )
    yield CounterMetricFamily(
        "burstloc_webhook_dead_lettered", "webhook alerts given up", value=sender.dead_lettered
    )


def _histogram(snap: HistogramSnapshot) -> tuple[list[tuple[str, float]], float]:
    """(buckets, sum) as ``HistogramMetricFamily.add_metric`` takes them."""
    from prometheus_client.utils import floatToGoString

    bounds = [floatToGoString(b) for b in snap.bounds] + ["+Inf"]
    return list(zip(bounds, snap.cumulative, strict=True)), snap.total


class _Collector:
    """The registry's collector of one :class:`MonitorMetrics`."""

    def __init__(self, metrics: MonitorMetrics) -> None:
        self.metrics = metrics

    def collect(self) -> Iterator[Any]:
        """The metric families, read now."""
        return self.metrics.families()
