"""A decision as the live monitor reports it: what was decided, by whom, with which meters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from burstloc.localize.decide import Decision
from burstloc.localize.evidence import Ranking

__all__ = ["LiveDecision"]


@dataclass(frozen=True)
class LiveDecision:
    """A decision as the monitor reports it: the localizer's :class:`Decision`, which meters
    took part (``meters``), which were excluded and which alarmed, and how long it waited after
    the first alarm. ``waited`` is true when the answer came later than the arrival localizer's
    own delay (plus one capture interval): the monitor waited for settled readings. (The live
    loop adds the health record at decision time to :meth:`to_json`'s record.)"""

    decision: Decision
    localizer: str
    meters: tuple[str, ...]
    excluded: tuple[str, ...]
    alarmed: tuple[str, ...]
    waited: bool

    @property
    def is_burst(self) -> bool:
        """Whether this is reported as a burst (unclassified, or classified ``burst``); the
        others are reported as events."""
        return self.decision.is_burst

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
        says which and why)."""
        kind = "decision" if self.is_burst else "event"
        doc: dict[str, Any] = {"type": kind, "burst": self.is_burst, **self.decision.to_json(top)}
        doc.update(
            waited=self.waited,
            decision_delay_s=self.delay,
            localizer=self.localizer,
            meters=list(self.meters),
            excluded=list(self.excluded),
            alarmed=list(self.alarmed),
        )
        return doc
