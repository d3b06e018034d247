"""A ranking localizer's answer: the ranking, when it was given, the named point and the
search posterior (:class:`Decision`), and how its times are written (:func:`json_time`). Numpy
only; on the live path."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from burstloc.localize.evidence import Ranking
from burstloc.localize.pipes import PipePosition
from burstloc.localize.region import REGION_CONFIDENCE, Posterior, SearchRegion

if TYPE_CHECKING:
    from burstloc.localize.classify import Classification

__all__ = ["Decision", "json_time"]


@dataclass(frozen=True)
class Decision:
    """A ranking localizer's answer: the ranking, the reading time it was given at, the reading
    time of the first alarm, whether the fused localizer waited for the signature (its
    arrivals were not decisive), where on the best pipe the burst is (from the arrival fit,
    :meth:`burstloc.localize.arrival.ArrivalLocalizer.position`; ``None`` for the signature
    localizer) and ``classification``, when the alarm was classified
    (:mod:`burstloc.localize.classify`): burst, other event or unsure. ``look_again`` is set
    when the answer is provisional: the readings ended before the arrivals were decisive or had
    reached their horizon (:func:`arrival_horizon`); the caller ranks again once it has the
    readings up to that reading time (the live monitor does)."""

    ranking: Ranking
    time: float
    first_alarm: float
    waited: bool = False
    position: PipePosition | None = None
    classification: Classification | None = None
    look_again: float | None = None
    posterior: Posterior | None = None

    @property
    def region(self) -> SearchRegion | None:
        """The search region holding the burst with :data:`~burstloc.localize.region.
        REGION_CONFIDENCE` (``None`` without a posterior: the signature localizer alone)."""
        return None if self.posterior is None else self.posterior.region(REGION_CONFIDENCE)

    @property
    def is_burst(self) -> bool:
        """Whether this is reported as a burst: unclassified, or classified ``burst``."""
        return self.classification is None or self.classification.is_burst

    @property
    def pipe(self) -> str | None:
        """The best-ranked pipe (``None`` for an empty ranking)."""
        best = self.ranking.best
        return None if best is None else best.pipe

    def to_json(self, top: int = 3) -> dict[str, Any]:
        """JSON-ready summary: time, first alarm, waited, the ``top`` best pipes, the position
        on the best one (``None`` when the localizer gives none), the search ``region``
        (:meth:`burstloc.localize.region.SearchRegion.to_json`, ``None`` without one) and the
        classification."""
        doc: dict[str, Any] = {
            "time": json_time(self.time),
            "first_alarm": json_time(self.first_alarm),
            "waited": self.waited,
            "position": None if self.position is None else self.position.to_json(),
            "region": None if self.region is None else self.region.to_json(),
            "pipes": [
                {"pipe": r.pipe, "start": r.start, "end": r.end, "score": round(r.score, 6)}
                for r in self.ranking.top(top)
            ],
        }
        if self.classification is not None:
            doc["classification"] = self.classification.to_json()
        return doc


def json_time(seconds: float) -> float:
    """A time in a JSON record: to the microsecond, without float noise (``10.600000000000001``
    is ``10.6``; epoch seconds keep their microseconds)."""
    return round(float(seconds), 6)
