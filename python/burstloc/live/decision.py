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

    With a classifier the answer comes in two records: a *transient* located as soon as the
    arrival localizer can (``classify_at`` is then the reading time at which the lasting change
    will have settled and the alarm will be classified), then the decision or event at that
    time. A transient is neither a burst report nor an event."""

    decision: Decision
    localizer: str
    meters: tuple[str, ...]
    excluded: tuple[str, ...]
    alarmed: tuple[str, ...]
    waited: bool
    classify_at: float | None = None

    @property
    def transient(self) -> bool:
        """Whether this is the early record of an alarm still to be classified."""
        return self.classify_at is not None

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
        classified (``"burst": null`` and ``classify_at``, the reading time of its answer)."""
        if self.transient:
            kind, burst = "transient", None
        else:
            kind, burst = ("decision" if self.is_burst else "event"), self.is_burst
        doc: dict[str, Any] = {"type": kind, "burst": burst, **self.decision.to_json(top)}
        if self.transient and self.classify_at is not None:
            doc["classify_at"] = json_time(self.classify_at)
        doc.update(
            waited=self.waited,
            decision_delay_s=json_time(self.delay),
            localizer=self.localizer,
            meters=list(self.meters),
            excluded=list(self.excluded),
            alarmed=list(self.alarmed),
        )
        return doc
