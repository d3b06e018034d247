"""Search regions scored as a utility scores them: is the burst inside, how much main to search.

Every answer of the arrival and fused localizers carries a posterior over points of the network
(:mod:`burstloc.localize.region`) and its search regions. ``burstloc evaluate`` scores, per
attempt (:func:`score_region`):

* **coverage**: whether the true burst point lies in the region of each probability of
  :data:`~burstloc.localize.region.REGION_LEVELS` (50, 80 and 95 %); a region that says 95 %
  should hold the burst in 95 % of bursts;
* the region's **length** in metres of main at each of those probabilities;
* whether the **named point** (the position on the best pipe) is within 100 m and within
  300 m network distance of the truth (BattLeDIM counts a localization within 300 m as found),
  from the position errors of :mod:`burstloc.experiments.position`;
* the **time to the first region**: seconds from the burst to the first record with one, the
  monitor's first early (transient) record or its answer;
* the **time to a region of at most 1 km** (:data:`SEARCHABLE`): seconds from the burst to the
  first record whose 95 % region is that short: the monitor's early (transient) records, then
  its answer (``None`` when none is);
* the **first answer**: whether the first record with a region (early or not) held the burst
  in its 95 % region, and its named point's network distance to the truth: what the control
  room has seconds after the burst.

An attempt without an answer counts as a burst outside every region, not within any distance
and without a region. :class:`RegionScores` summarises a run.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import SEARCHABLE
from burstloc.localize.region import REGION_LEVELS

if TYPE_CHECKING:
    from burstloc.experiments.harness import Attempt
    from burstloc.experiments.position import PipePoint, PositionOutcome
    from burstloc.localize.pipes import PipePosition

__all__ = [
    "NEAR",
    "REGION_HEADER",
    "SEARCHABLE",
    "RegionOutcome",
    "RegionScores",
    "region_cells",
    "score_region",
    "score_regions",
]

NEAR = (100.0, 300.0)
"""Network distances (m) within which a named point counts as found."""


@dataclass(frozen=True)
class RegionOutcome:
    """One attempt's region against the true point: per level of ``levels``, whether the region
    holds it (``covered``) and its length (m, ``lengths``; empty without a region), the named
    point's network distance to the truth (``error``, m, ``None`` without one), the seconds from
    the burst to the first record with a region (``first_after``) and to the first whose 95 %
    region is at most :data:`SEARCHABLE` m long (``searchable_after``); whether that first
    record's 95 % region held the burst (``first_covered``) and its named point's distance to
    the truth (``first_error``, m)."""

    covered: tuple[bool, ...] = ()
    lengths: tuple[float, ...] = ()
    error: float | None = None
    searchable_after: float | None = None
    first_after: float | None = None
    first_covered: bool = False
    first_error: float | None = None


def score_region(
    attempt: Attempt,
    truth: PipePoint,
    truth_length: float,
    position: PositionOutcome,
    levels: Sequence[float] = REGION_LEVELS,
    error_of: Callable[[PipePosition | None], float | None] | None = None,
) -> RegionOutcome:
    """Score ``attempt``'s regions against the burst's true point ``truth`` (on a pipe of
    ``truth_length`` m); ``position`` is the attempt's scored position, ``error_of`` the
    network distance (m) from a named point to the truth (for the first record's; without it,
    the answer's ``position.error`` when the answer is the first record)."""
    decision = attempt.decision
    post = None if decision is None else decision.posterior
    if decision is None or post is None:
        return RegionOutcome(error=position.error)
    regions = [post.region(level) for level in levels]
    covered = tuple(r.contains(truth.pipe, truth.node, truth.metres, truth_length) for r in regions)
    lengths = tuple(r.length for r in regions)
    after = first = None
    first_covered, first_error = False, None
    for answer in (*attempt.early, decision):  # the early records first, then the answer
        post = None if answer is None else answer.posterior
        if answer is None or post is None:
            continue
        if first is None:
            first = answer.time - attempt.burst_start
            first_covered = post.region().contains(
                truth.pipe, truth.node, truth.metres, truth_length
            )
            if error_of is not None:
                first_error = error_of(answer.position)
            elif answer is decision:
                first_error = position.error
        if post.region().length <= SEARCHABLE:
            after = answer.time - attempt.burst_start
            break
    return RegionOutcome(covered, lengths, position.error, after, first, first_covered, first_error)


def score_regions(
    attempts: Mapping[str, Sequence[Attempt]],
    points: Mapping[str, PipePoint],
    lengths: Mapping[str, float],
    positions: Mapping[str, Sequence[PositionOutcome]],
    error_of: Callable[[PipePoint, PipePosition | None], float | None] | None = None,
) -> dict[str, list[RegionOutcome]]:
    """Per pipe, the region outcome of each attempt (``attempts[pipe][k]``); ``error_of(truth,
    position)``: the network distance (m) from a named point to the truth."""

    def scorer(truth: PipePoint) -> Callable[[PipePosition | None], float | None] | None:
        if error_of is None:
            return None
        return lambda position: error_of(truth, position)

    return {
        p: [
            score_region(a, points[p], lengths[p], positions[p][k], error_of=scorer(points[p]))
            for k, a in enumerate(runs)
        ]
        for p, runs in attempts.items()
    }


def _share(flags: Iterable[bool], total: int) -> float | None:
    return sum(flags) / total if total else None


def _median_time(times: Iterable[float | None]) -> float | None:
    """The median of ``times``, a ``None`` counting as never; ``None`` if that is never."""
    values = [np.inf if t is None else t for t in times]
    middle = float(np.median(values)) if values else np.inf
    return middle if np.isfinite(middle) else None


@dataclass(frozen=True)
class RegionScores:
    """A run's regions over its ``attempts``: ``coverage[level]`` (share of attempts whose
    region of that probability held the burst), ``median_length`` / ``p90_length`` (m, of the
    regions given, per level), ``within`` (share of attempts whose named point is within each
    distance of :data:`NEAR`), ``searchable`` (share whose answer's 95 % region is at most
    :data:`SEARCHABLE` m) and ``median_time_to_searchable`` (s from the burst, over every
    attempt, ``None`` when half of them never get one); ``median_time_to_region``: the same for
    the first region of any length. ``first_coverage``, ``first_within`` and
    ``first_mean_error``: the first record's 95 % coverage, named point within each distance of
    :data:`NEAR` (shares of every attempt) and mean distance (m, over the attempts that have
    one)."""

    attempts: int
    answered: int
    levels: tuple[float, ...]
    coverage: tuple[float | None, ...]
    median_length: tuple[float | None, ...]
    p90_length: tuple[float | None, ...]
    within: tuple[float | None, ...]
    searchable: float | None
    median_time_to_searchable: float | None
    median_time_to_region: float | None
    first_coverage: float | None = None
    first_within: tuple[float | None, ...] = ()
    first_mean_error: float | None = None

    @classmethod
    def of(
        cls, outcomes: Iterable[RegionOutcome], levels: Sequence[float] = REGION_LEVELS
    ) -> RegionScores:
        """Summarise the region outcomes of a run's attempts."""
        items = list(outcomes)
        total = len(items)
        answered = [o for o in items if o.lengths]
        coverage, median, p90 = [], [], []
        for i in range(len(levels)):
            coverage.append(_share((o.covered[i] for o in answered), total))
            lengths = np.array([o.lengths[i] for o in answered], dtype=np.float64)
            median.append(float(np.median(lengths)) if lengths.size else None)
            p90.append(float(np.percentile(lengths, 90)) if lengths.size else None)
        within = tuple(
            _share((o.error is not None and o.error <= d for o in items), total) for d in NEAR
        )
        return cls(
            attempts=total,
            answered=len(answered),
            levels=tuple(levels),
            coverage=tuple(coverage),
            median_length=tuple(median),
            p90_length=tuple(p90),
            within=within,
            searchable=_share((o.searchable_after is not None for o in items), total),
            median_time_to_searchable=_median_time(o.searchable_after for o in items),
            median_time_to_region=_median_time(o.first_after for o in items),
            first_coverage=_share((o.first_covered for o in items), total),
            first_within=tuple(
                _share((o.first_error is not None and o.first_error <= d for o in items), total)
                for d in NEAR
            ),
            first_mean_error=(
                float(np.mean(errors))
                if (errors := [o.first_error for o in items if o.first_error is not None])
                else None
            ),
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready record (``tests/evaluate_schema.json``, ``region``)."""
        return {
            "attempts": self.attempts,
            "answered": self.answered,
            "levels": [
                {
                    "confidence": level,
                    "coverage": self.coverage[i],
                    "median_length_m": self.median_length[i],
                    "p90_length_m": self.p90_length[i],
                }
                for i, level in enumerate(self.levels)
            ],
            "within_m": {f"{d:g}": share for d, share in zip(NEAR, self.within, strict=True)},
            "searchable_m": SEARCHABLE,
            "searchable": self.searchable,
            "median_time_to_searchable_s": self.median_time_to_searchable,
            "median_time_to_region_s": self.median_time_to_region,
            "first_answer": {
                "coverage_95": self.first_coverage,
                "within_m": {
                    f"{d:g}": share for d, share in zip(NEAR, self.first_within, strict=True)
                },
                "mean_error_m": self.first_mean_error,
            },
        }


REGION_HEADER = [
    "first region",
    "first: 95 % held, within 300 m, mean",
    "coverage 50 / 80 / 95 %",
    "95 % region median / p90",
    "within 100 / 300 m",
    "<= 1 km: share, median time",
]
"""The columns of :func:`region_cells`."""


def _percent(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f}%"


def region_cells(scores: RegionScores) -> list[str]:
    """A run's search regions as table cells (:data:`REGION_HEADER`)."""
    last = len(scores.levels) - 1
    median, p90 = scores.median_length[last], scores.p90_length[last]
    time = scores.median_time_to_searchable
    first = scores.median_time_to_region
    mean = scores.first_mean_error
    near = scores.first_within[-1] if scores.first_within else None
    return [
        "-" if first is None else f"{first:.1f} s",
        f"{_percent(scores.first_coverage)}, {_percent(near)}, "
        + ("-" if mean is None else f"{mean:.0f} m"),
        " / ".join(_percent(c) for c in scores.coverage),
        "-" if median is None or p90 is None else f"{median:.0f} / {p90:.0f} m",
        " / ".join(_percent(w) for w in scores.within),
        f"{_percent(scores.searchable)}, " + ("-" if time is None else f"{time:.1f} s"),
    ]
