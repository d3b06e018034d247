"""A decision as the live monitor reports it: what was decided, by whom, with which meters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from burstloc.localize.decide import Decision, json_time
from burstloc.localize.evidence import Ranking

__all__ = ["LiveDecision"]


@dataclass(frozen=True)
class LiveDecision:
    """A decision as the monitor reports it: the localizer's :class:`Decision`, which meters
    took part (``meters``), which were excluded and which alarmed, and how long it waited after
    the first alarm. ``waited`` is true when the answer came later than the arrival localizer's
    last look (:func:`burstloc.localize.decide.arrival_horizon`, plus one capture interval): the
    monitor waited for settled readings. (The live
    loop adds the health record at decision time to :meth:`to_json`'s record.)

    The answer comes in two records when it waits for the lasting change: a *transient*
    located as soon as the arrival localizer can, with its search region (``answer_at`` is then
    the reading time at which the lasting change will have settled: the burst's onset plus
    ``wait``, the signature's decision delay), then the decision or event
    at that time, with the region narrowed by the lasting drop. That is so with a classifier
    (``classifying``: the alarm is classified then) and when the fused localizer's arrivals were
    not decisive. A transient is neither a burst report nor an event."""

    decision: Decision
    localizer: str
    meters: tuple[str, ...]
    excluded: tuple[str, ...]
    alarmed: tuple[str, ...]
    waited: bool
    answer_at: float | None = None
    classifying: bool = False
    wait: float | None = None

    @property
    def transient(self) -> bool:
        """Whether this is the early record of an alarm still to be answered."""
        return self.answer_at is not None

    @property
    def is_burst(self) -> bool:
        """Whether this is reported as a burst (unclassified, or classified ``burst``); the
        others are reported as events."""
        return not self.transient and self.decision.is_burst

    @property
    def pipe(self) -> str | None:
        """The best-ranked pipe."""
        return self.decision.pipe

    @property
    def ranking(self) -> Ranking:
        """The ranking."""
        return self.decision.ranking

    @property
    def time(self) -> float:
        """Reading time of the decision (s)."""
        return self.decision.time

    @property
    def first_alarm(self) -> float:
        """Reading time of the first alarm (s)."""
        return self.decision.first_alarm

    @property
    def delay(self) -> float:
        """Seconds from the first alarm to the decision."""
        return self.decision.time - self.decision.first_alarm

    def to_json(self, top: int = 3) -> dict[str, Any]:
        """The record that ``burstloc monitor`` prints: ``"type": "decision"`` for a burst,
        ``"event"`` for an alarm classified as another event or unsure (its ``classification``
        says which and why), ``"transient"`` for the early record of an alarm still to be
        answered (``"burst": null`` and ``answer_at``, the reading time of its answer; also as
        ``classify_at`` when that answer is a classification; ``wait_s``, the seconds from the
        burst's onset to ``answer_at``, when known)."""
        if self.transient:
            kind, burst = "transient", None
        else:
            kind, burst = ("decision" if self.is_burst else "event"), self.is_burst
        doc: dict[str, Any] = {"type": kind, "burst": burst, **self.decision.to_json(top)}
        if self.answer_at is not None:
            doc["answer_at"] = json_time(self.answer_at)
            if self.classifying:
                doc["classify_at"] = json_time(self.answer_at)
            if self.wait is not None:
                doc["wait_s"] = json_time(self.wait)
        doc.update(
            waited=self.waited,
            decision_delay_s=json_time(self.delay),
            localizer=self.localizer,
            meters=list(self.meters),
            excluded=list(self.excluded),
            alarmed=list(self.alarmed),
        )
        return doc
