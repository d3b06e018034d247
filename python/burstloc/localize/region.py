"""The search region: where to send a crew, how much main that is, and how sure we are.

With the few meters a utility has, one pipe is often not decidable from the data: several
stretches of main explain the alarms equally well. So every answer also carries a *search
region*: the smallest set of pipe stretches that holds the burst with a stated probability
(default 95 %), its total length in metres, and the probability of each stretch.

The probabilities come from a posterior over candidate points. Every pipe of the arrival
localizer is cut into segments of about :data:`GRID_STEP` metres (:class:`RegionGrid`); the
middle of each segment is a candidate point, with a prior proportional to the segment's length
(a burst is as likely on any metre of main). Its likelihood has two parts:

* **arrivals**: each meter's timing misfit, the distance from the burst time ``t0`` to the
  window its alarm allows (:meth:`burstloc.localize.arrival.ArrivalLocalizer.windows`: an alarm
  start is known to one capture interval ``dt``; a silent meter says the wave has not come
  yet), costed by the timing error of :mod:`burstloc.localize.timing_error` (a Student-t of
  the stated scale mixed with an outlier chance). The stated scale is a floor, not a promise:
  where the alarms' own misfits at the best-fitting point show a larger timing error (a model
  whose wave speeds, lengths or clocks are further off than stated, fronts heard late), every
  scale is widened towards what they show
  (:func:`~burstloc.localize.timing_error.widened_scale`), so the region's probability stays
  honest on networks whose errors nobody measured. A silence is weaker evidence: a meter the
  wave has reached may stay silent (:data:`SILENT_MISS`), so its misfit costs at most
  ``-log(SILENT_MISS)``. ``t0`` is the best of the least-squares fit and the window ends of the
  :data:`ANCHORS` earliest alarms;
* **the lasting drop**, once the readings have settled (:class:`DropFit`): the signature
  localizer's fit of each pipe (its best position), the same for every point of the pipe. With
  ``n`` meters and the burst size fitted, the residual has ``n - 1`` degrees of freedom and an
  unknown noise level: the profile likelihood is ``-(n - 1)/2 log(rss)``, with the hydraulic
  model's own error (:data:`DROP_MODEL_ERROR` of the drop, at least
  :data:`~burstloc.localize.fused.SIGNATURE_FLOOR`) added to every residual. The model's error
  is shared by the meters, so ``n - 1`` is at most :data:`DROP_DOF`: the drop narrows the
  region, it does not decide it alone. It counts with the fused localizer's signature weight at
  the capture interval: where the arrivals time the wave finely, they decide the region.

The region is the highest-density set: segments in decreasing posterior probability per metre
until they hold the stated probability (the shortest main that does). Adjacent segments of a
pipe merge into one stretch. Numpy only, from the stored localization model: on the live path.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import BurstEvidence, Ranking
from burstloc.localize.fused import SIGNATURE_FLOOR, FusedLocalizer
from burstloc.localize.signature import rank_drop
from burstloc.localize.timing_error import (
    OUTLIER,
    alarm_weakness,
    misfit_scale,
    timing_penalty,
    timing_scale,
    widened_scale,
)
from burstloc.localize.windows import fit_windows, window_misfit

__all__ = [
    "DROP_MODEL_ERROR",
    "GRID_STEP",
    "REGION_CONFIDENCE",
    "REGION_LEVELS",
    "DropFit",
    "Posterior",
    "RegionGrid",
    "SearchRegion",
    "Stretch",
    "drop_fit",
    "grid_of",
    "posterior",
    "region_posterior",
]

REGION_CONFIDENCE = 0.95
"""The probability a search region holds by default."""

REGION_LEVELS = (0.5, 0.8, 0.95)
"""The probabilities whose regions ``burstloc evaluate`` scores (coverage and length)."""

GRID_STEP = 25.0
"""Longest segment (m) a pipe is cut into for the posterior (more on a very large network:
:data:`MAX_GRID_POINTS`)."""

MAX_GRID_POINTS = 20_000
"""Most candidate points of a grid: beyond it the segments are made longer."""

SILENT_MISS = 0.2
"""Chance that a meter the burst's wave has reached stays silent: a front near the detection
threshold, weakened on its way (a silence is weaker evidence than an alarm: its misfit costs at
most ``-log(SILENT_MISS)``)."""

ANCHORS = 8
"""The burst time is also tried at the window ends of this many alarmed meters (the earliest):
a fit that takes one late meter as an outlier."""

DROP_MODEL_ERROR = 0.1
"""Error of the lasting drop's hydraulic model (EPANET's steady state against the settled
readings), as a fraction of the drop's RMS over the meters."""

DROP_DOF = 2
"""Most degrees of freedom the drop's residual counts: the model's error is shared by the
meters (one burst size, one steady state), not independent at each of them."""


@dataclass(frozen=True)
class DropFit:
    """The lasting drop's evidence: the signature localizer's ``ranking`` (score: minus the RMS
    residual, m) over ``meters`` meters, of a drop of RMS ``size`` m (``None``: not known, the
    model error is then :data:`~burstloc.localize.fused.SIGNATURE_FLOOR`), its log-likelihood
    counted with ``weight`` (the fused localizer's signature weight at the capture interval,
    :meth:`~burstloc.localize.fused.FusedLocalizer.weights`)."""

    ranking: Ranking
    meters: int
    size: float | None = None
    weight: float = 1.0

    def loglik(self, pipes: Sequence[str]) -> NDArray[np.float64]:
        """Log-likelihood of each of ``pipes`` (module docstring), times ``weight``; a pipe
        the ranking does not hold gets its worst."""
        floor = SIGNATURE_FLOOR
        if self.size is not None and math.isfinite(self.size):
            floor = max(floor, DROP_MODEL_ERROR * self.size)
        rss = {p.pipe: p.score * p.score + floor * floor for p in self.ranking}
        best = min(rss.values(), default=floor * floor)
        worst = max(rss.values(), default=floor * floor)
        dof = min(max(self.meters - 1, 1), DROP_DOF)
        values = np.array([rss.get(p, worst) for p in pipes], dtype=np.float64)
        return np.asarray(-0.5 * self.weight * dof * np.log(values / best), dtype=np.float64)


@dataclass(frozen=True)
class Stretch:
    """A stretch of a pipe: ``low`` to ``high`` metres from its flow-direction start node
    ``start``, holding the burst with ``probability``."""

    pipe: str
    start: str
    low: float
    high: float
    probability: float

    @property
    def length(self) -> float:
        """Metres of main."""
        return self.high - self.low

    def to_json(self) -> dict[str, Any]:
        """``pipe``, ``from`` (the start node), ``low``, ``high`` (m), ``probability``."""
        return {
            "pipe": self.pipe,
            "from": self.start,
            "low": round(self.low, 1),
            "high": round(self.high, 1),
            "probability": round(self.probability, 4),
        }


@dataclass(frozen=True)
class SearchRegion:
    """The stretches to search: together they hold the burst with ``probability`` (at least
    ``confidence``, the probability asked for), ``length`` metres of main; most probable
    first. ``pipes``: each pipe of the region with the probability the burst is on it (anywhere
    on it), most probable first."""

    confidence: float
    probability: float
    length: float
    stretches: tuple[Stretch, ...]
    pipes: tuple[tuple[str, float], ...]

    def contains(self, pipe: str, node: str, metres: float, length: float) -> bool:
        """Whether the point ``metres`` along ``pipe`` (of ``length`` m) from its end node
        ``node`` lies in the region."""
        for s in self.stretches:
            if s.pipe != pipe:
                continue
            along = metres if node == s.start else length - metres
            if s.low - 1e-6 <= along <= s.high + 1e-6:
                return True
        return False

    def to_json(self, stretches: int | None = None) -> dict[str, Any]:
        """JSON-ready record: ``confidence``, ``probability``, ``length_m``, ``pipe_count``,
        ``stretches`` (the first ``stretches`` of them; all by default) and ``pipes`` (pipe and
        probability, at most ten)."""
        shown = self.stretches if stretches is None else self.stretches[:stretches]
        return {
            "confidence": self.confidence,
            "probability": round(self.probability, 4),
            "length_m": round(self.length, 1),
            "pipe_count": len({s.pipe for s in self.stretches}),
            "stretches": [s.to_json() for s in shown],
            "pipes": [{"pipe": p, "probability": round(q, 4)} for p, q in self.pipes[:10]],
        }


class RegionGrid:
    """Candidate points along every pipe of an arrival localizer: each pipe cut into equal
    segments of at most ``step`` metres (longer where the network would give more than
    :data:`MAX_GRID_POINTS`); ``pipe[i]`` (index into ``arrival.pipes``), ``low[i]`` /
    ``high[i]`` (m from the pipe's flow-direction start) and ``dist[i, j]``, the path length from
    the segment's middle to meter ``j`` (in metres of wave travel, as the localizer's)."""

    def __init__(self, arrival: ArrivalLocalizer, step: float = GRID_STEP) -> None:
        if not (math.isfinite(step) and step > 0):
            raise ConfigError(f"the grid step must be > 0 m, got {step}")
        lengths = np.array([p.length for p in arrival.pipes], dtype=np.float64)
        step = max(step, float(lengths.sum()) / MAX_GRID_POINTS)
        counts = np.maximum(np.ceil(lengths / step), 1).astype(np.int64)
        self.arrival = arrival
        self.pipe = np.repeat(np.arange(lengths.size), counts)
        k = np.arange(self.pipe.size) - np.repeat(np.cumsum(counts) - counts, counts)
        width = lengths[self.pipe] / counts[self.pipe]
        self.low = k * width
        self.high = self.low + width
        self.length = width
        mid = 0.5 * (self.low + self.high)
        d_start, d_end = arrival.end_distances
        wave = (mid * arrival.stretch[self.pipe])[:, None]
        total = (lengths * arrival.stretch)[self.pipe][:, None]
        self.dist = np.minimum(wave + d_start[self.pipe], (total - wave) + d_end[self.pipe])
        self.rows = self.pipe.tolist()

    def __len__(self) -> int:
        """The number of candidate points."""
        return int(self.pipe.size)


_GRIDS: weakref.WeakKeyDictionary[ArrivalLocalizer, RegionGrid] = weakref.WeakKeyDictionary()


def grid_of(arrival: ArrivalLocalizer) -> RegionGrid:
    """The default :class:`RegionGrid` of ``arrival``, built once per localizer."""
    grid = _GRIDS.get(arrival)
    if grid is None:
        grid = _GRIDS[arrival] = RegionGrid(arrival)
    return grid


@dataclass(frozen=True)
class Posterior:
    """Probabilities of the candidate points of ``grid`` (``probability``, summing to 1)."""

    grid: RegionGrid
    probability: NDArray[np.float64]

    def pipe_probabilities(self) -> dict[str, float]:
        """The probability that the burst is on each pipe (pipes with some probability)."""
        sums = np.bincount(self.grid.pipe, weights=self.probability)
        pipes = self.grid.arrival.pipes
        return {pipes[i].pipe: float(q) for i, q in enumerate(sums) if q > 0}

    def region(self, confidence: float = REGION_CONFIDENCE) -> SearchRegion:
        """The shortest set of segments holding at least ``confidence`` (module docstring).

        Raises:
            ConfigError: ``confidence`` is not in (0, 1].
        """
        if not (0 < confidence <= 1):
            raise ConfigError(f"a region's confidence must be in (0, 1], got {confidence}")
        grid, prob = self.grid, self.probability
        order = np.argsort(-(prob / grid.length), kind="stable")
        held = np.cumsum(prob[order])
        count = int(np.searchsorted(held, confidence * held[-1] - 1e-12)) + 1
        chosen = np.sort(order[: min(count, order.size)])
        stretches: list[Stretch] = []
        pipes = self.grid.arrival.pipes
        for i in chosen.tolist():
            p = pipes[int(grid.pipe[i])]
            low, high, mass = float(grid.low[i]), float(grid.high[i]), float(prob[i])
            last = stretches[-1] if stretches else None
            if last is not None and last.pipe == p.pipe and abs(last.high - low) < 1e-9:
                stretches[-1] = Stretch(p.pipe, p.start, last.low, high, last.probability + mass)
            else:
                stretches.append(Stretch(p.pipe, p.start, low, high, mass))
        stretches.sort(key=lambda s: -s.probability)
        on_pipe = self.pipe_probabilities()
        held_pipes = dict.fromkeys(s.pipe for s in stretches)  # most probable stretch first
        return SearchRegion(
            confidence=float(confidence),
            probability=float(prob[chosen].sum()),
            length=float(grid.length[chosen].sum()),
            stretches=tuple(stretches),
            pipes=tuple(sorted(((p, on_pipe[p]) for p in held_pipes), key=lambda t: -t[1])),
        )


def _arrival_penalty(
    arrival: ArrivalLocalizer, grid: RegionGrid, evidence: BurstEvidence, timing_factor: float
) -> NDArray[np.float64]:
    """Each grid point's timing penalty (module docstring), ``inf`` where it explains no
    alarm; a weak alarm's timing error wider and its outlier chance larger
    (:func:`~burstloc.localize.timing_error.alarm_weakness`; a silence's as stated), every
    one ``timing_factor`` times the stated; the timing error widened to what the alarms'
    misfits at the best point show when that is more than the stated one
    (:func:`misfit_scale`, each misfit over its alarm's widening)."""
    lo, hi, _, count = arrival.windows(grid.dist[:, None, :], evidence, grid.rows)
    lo, hi = lo[:, 0, :], hi[:, 0, :]
    says = np.isfinite(lo)
    alarmed, silent = arrival.columns(evidence)
    stated_scale = timing_scale(
        evidence.capture_interval,
        grid.dist[:, alarmed + silent] / arrival.wave_speed,
        arrival.wave_speed_tolerance,
        arrival.clock_tolerance,
    )
    widening, outlier = np.ones(says.shape[1]), np.full(says.shape[1], OUTLIER)
    widening[:count], outlier[:count] = alarm_weakness(
        evidence, [arrival.meters[j] for j in alarmed]
    )
    scale = np.asarray(stated_scale, dtype=np.float64) * (widening * timing_factor)
    horizon = max(arrival.horizon, 10 * evidence.capture_interval)
    gap, placed = fit_windows(lo, hi, count, evidence.capture_interval)
    cap = np.full(says.shape[1], np.inf)
    cap[count:] = -math.log(SILENT_MISS)
    starts = [evidence.alarms[m].start for m in arrival.meters if m in evidence.alarms]
    anchors = np.argsort(starts, kind="stable")[:ANCHORS].tolist()

    def penalty(scale: NDArray[np.float64]) -> NDArray[np.float64]:
        def total(miss: NDArray[np.float64]) -> NDArray[np.float64]:
            pen = np.minimum(timing_penalty(miss, scale, horizon, outlier), cap)
            return np.asarray(np.sum(np.where(says, pen, 0.0), axis=1), dtype=np.float64)

        best = total(gap)
        for j in anchors:
            for t0 in (lo[:, j], hi[:, j]):
                miss = window_misfit(lo, hi, np.where(np.isfinite(t0), t0, 0.0)[:, None])
                best = np.minimum(best, np.where(says[:, j], total(miss), np.inf))
        return np.asarray(np.where(placed, best, np.inf), dtype=np.float64)

    first = penalty(scale)
    if not np.isfinite(first).any():
        return first
    at = int(np.argmin(first))
    shown, dof = misfit_scale((gap[at, :count] / widening[:count])[says[at, :count]])
    stated = timing_factor * float(np.mean(np.broadcast_to(stated_scale, gap.shape)[at, :count]))
    widened = widened_scale(stated, shown, dof)
    if widened <= stated:
        return first
    return penalty(scale * (widened / stated))


def posterior(
    arrival: ArrivalLocalizer,
    evidence: BurstEvidence | None,
    *,
    drop: DropFit | None = None,
    grid: RegionGrid | None = None,
    timing_factor: float | None = None,
) -> Posterior:
    """The posterior over ``grid``'s points (default :func:`grid_of`) from the arrivals of
    ``evidence`` (``None``: none) and the lasting ``drop`` (``None``: not yet settled); see the
    module docstring. ``timing_factor``: the timing error over the stated one (default the
    localizer's :attr:`~burstloc.localize.arrival.ArrivalLocalizer.timing_factor`).

    Raises:
        InputError: neither evidence is given, or no alarmed meter is one of the model's.
    """
    grid = grid_of(arrival) if grid is None else grid
    loglik = np.log(grid.length)
    if evidence is None and drop is None:
        raise InputError("a search region needs arrivals or a lasting drop")
    if evidence is not None:
        factor = arrival.timing_factor if timing_factor is None else float(timing_factor)
        loglik = loglik - _arrival_penalty(arrival, grid, evidence, factor)
    if drop is not None:
        per_pipe = drop.loglik([p.pipe for p in arrival.pipes])
        loglik = loglik + per_pipe[grid.pipe]
    if not np.isfinite(loglik).any():
        raise InputError("no candidate point explains the alarms")
    weight = np.exp(loglik - loglik.max())
    return Posterior(grid, weight / weight.sum())


def drop_fit(
    fused: FusedLocalizer, evidence: BurstEvidence, given: Ranking | None
) -> DropFit | None:
    """The lasting drop the fused localizer weighs at ``evidence``, with its signature weight
    at the capture interval: ``given`` (the caller's signature ranking of these readings), else
    the signature localizer's fit when the readings have settled and signatures weigh at this
    capture interval, else ``None``."""
    meters = len(fused.signature.signatures.meters)
    weight = fused.weights(evidence.capture_interval)[1]
    if given is not None:
        return DropFit(given, meters, weight=weight)
    if weight > 0 and fused.signature_ready(evidence):
        drop = fused.signature.drop(evidence)
        ranking = rank_drop(drop, fused.signature.signature_sets)
        return DropFit(ranking, meters, float(np.sqrt(np.mean(drop**2))), weight)
    return None


def region_posterior(
    arrival: ArrivalLocalizer, evidence: BurstEvidence, drop: DropFit | None
) -> Posterior | None:
    """The search posterior (:func:`posterior`) from the arrivals of ``evidence`` and the
    lasting ``drop``, or ``None`` when they place the burst nowhere (no alarmed meter of the
    model)."""
    try:
        return posterior(arrival, evidence, drop=drop)
    except InputError:
        return None
