"""How wide the search regions' timing error must be for their stated probability to hold, per
capture interval, from simulated bursts.

A search region's probability rests on the timing error it allows each alarm
(:mod:`burstloc.localize.timing_error`: the capture interval, the model's floor, the stated
wave-speed and clock tolerances, weak alarms widened). On a network of many short pipes and few
meters, fronts weaken and are heard late by amounts no stated tolerance follows: on L-TOWN with
BattLeDIM's 33 sensors at 0.2 s the 95 % region held 92.5 % of 200 bursts, at 0.01 s 96 %.

:func:`fit_timing_factors` measures, on bursts simulated on the network itself (the bursts the
fronts' speed is fitted on, :func:`burstloc.experiments.front_speed.simulate_front_bursts`), the
smallest factor on the stated timing error (one of :data:`FACTORS`) at which the regions of the
stated probability hold that share of the bursts: each burst is looked at as the arrival
localizer of the monitor looks at it (two meters corroborating, looks until one is decisive or
the arrival horizon is reached, paths timed at the fronts' speed), and the smallest factor whose
region holds its burst point is kept per burst. A few bursts cannot tell 92 % from 95 %: of 24
bursts, regions that hold 95 % leave two or more outside one time in three. So the interval's
factor is the smallest that leaves outside no more bursts than regions of the stated
probability would in nine samples of ten of that size (:func:`allowed_misses`: 3 of 24, 8 of
96, 14 of 200 at 95 %): a region is widened where the bursts show it overconfident, not where
they could be chance; never below 1 (a region is never made narrower than stated). It is
stored per interval (:attr:`~burstloc.localize.interval.IntervalCalibration.timing_factor`)
and every search region at that interval (the arrival localizer's, the fused localizer's early
record and answer) uses it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from burstloc.constants import MAX_TIMING_FACTOR
from burstloc.experiments.front_speed import FrontBurst
from burstloc.localize.config import Calibration
from burstloc.localize.corroborate import CORROBORATE, corroborated_at, corroboration_deadline
from burstloc.localize.decide import RankingLocalizers, decision_time
from burstloc.localize.evidence import BurstEvidence
from burstloc.localize.interval import IntervalCalibration
from burstloc.localize.looks import arrival_evidence, first_and_onset, look_at
from burstloc.localize.region import REGION_CONFIDENCE, posterior

__all__ = [
    "FACTORS",
    "SpreadFit",
    "allowed_misses",
    "choose_factor",
    "fit_timing_factors",
    "with_timing_factors",
]

FACTORS = (1.0, 1.1, 1.2, 1.3, 1.45, 1.6, 1.8, 2.0, 2.5, 3.0, 4.0, 5.0, MAX_TIMING_FACTOR)
"""The factors tried, in increasing order."""

SAMPLES = 0.9
"""The share of samples of bursts in which regions of the stated probability leave outside no
more bursts than :func:`allowed_misses`."""


def allowed_misses(bursts: int, confidence: float, samples: float = SAMPLES) -> int:
    """The most of ``bursts`` that regions holding each burst with probability ``confidence``
    leave outside in a share ``samples`` of samples (the binomial quantile)."""
    from scipy.stats import binom

    return int(binom.ppf(samples, bursts, 1.0 - confidence))


@dataclass(frozen=True)
class SpreadFit:
    """What the simulated bursts showed at one capture interval: of ``bursts``, ``placed`` were
    placed by the arrivals; ``needed`` holds, per placed burst, the smallest factor of
    :data:`FACTORS` whose region held it (``inf``: none did); ``factor`` is the one chosen for
    ``confidence`` (module docstring)."""

    capture_interval: float
    confidence: float
    bursts: int
    needed: tuple[float, ...]
    factor: float

    @property
    def placed(self) -> int:
        """Bursts the arrivals placed."""
        return len(self.needed)

    def held(self, factor: float) -> int:
        """Placed bursts the regions hold with the timing error widened by ``factor``."""
        return sum(n <= factor for n in self.needed)


def _look(
    localizers: RankingLocalizers,
    meters: Sequence[str],
    burst: FrontBurst,
    cal: IntervalCalibration,
) -> BurstEvidence | None:
    """The arrivals the monitor's arrival localizer answers from (``None``: no two meters
    corroborated the alarms)."""
    alarms, times = burst.alarms, burst.times
    if not alarms:
        return None
    by = corroboration_deadline("arrival", localizers, alarms, times, cal)
    corroborated = corroborated_at(alarms, times, CORROBORATE, by)
    if corroborated is None:
        return None
    first, _ = first_and_onset(alarms, times)
    arrivals = arrival_evidence(meters, times, burst.values, alarms, cal, "instantaneous", first)
    start = max(decision_time("arrival", alarms, times, cal), corroborated)
    last = float(times[-1])
    look = look_at(localizers.arrival, localizers.fused.margin, arrivals, start, first, last, cal)
    return look.evidence


def _needed(
    localizers: RankingLocalizers,
    evidence: BurstEvidence,
    burst: FrontBurst,
    confidence: float,
    factors: Sequence[float],
) -> float:
    """The smallest of ``factors`` whose ``confidence`` region holds ``burst`` (``inf``:
    none)."""
    truth = burst.truth
    for factor in factors:
        region = posterior(localizers.arrival, evidence, timing_factor=factor).region(confidence)
        if region.contains(truth.pipe, truth.node, truth.metres, burst.length):
            return float(factor)
    return math.inf


def choose_factor(
    needed: Sequence[float], confidence: float, factors: Sequence[float] = FACTORS
) -> float:
    """The smallest of ``factors`` that leaves outside no more of the bursts than
    :func:`allowed_misses` (``needed``: each burst's smallest factor that holds it, ``inf``:
    none); the largest where none does."""
    wanted = len(needed) - allowed_misses(len(needed), confidence)
    chosen = next((f for f in factors if sum(n <= f for n in needed) >= wanted), factors[-1])
    return float(chosen)


def fit_timing_factors(
    config: Calibration,
    bursts: Mapping[float, Sequence[FrontBurst]],
    confidence: float = REGION_CONFIDENCE,
    factors: Sequence[float] = FACTORS,
) -> list[SpreadFit]:
    """Each capture interval's timing factor from its simulated ``bursts`` (module docstring),
    the paths timed as ``config`` times them there (its fronts' speed)."""
    fits = []
    for dt, heard in bursts.items():
        cal = config.for_interval(dt)
        localizers = RankingLocalizers.from_model(config.model_at(dt))
        needed = []
        for burst in heard:
            evidence = _look(localizers, config.meters, burst, cal)
            if evidence is not None:
                needed.append(_needed(localizers, evidence, burst, confidence, factors))
        chosen = choose_factor(needed, confidence, factors)
        fits.append(SpreadFit(dt, confidence, len(heard), tuple(needed), chosen))
    return fits


def with_timing_factors(config: Calibration, fits: Sequence[SpreadFit]) -> Calibration:
    """``config`` with each fitted interval's timing factor, recorded in its provenance."""
    changes = {f.capture_interval: {"timing_factor": f.factor} for f in fits}
    provenance = {
        "region_timing": {
            f"{f.capture_interval:g}": {
                "factor": f.factor,
                "confidence": f.confidence,
                "bursts": f.bursts,
                "placed": f.placed,
                "held_at_1": f.held(1.0),
                "held": f.held(f.factor),
            }
            for f in fits
        },
    }
    return config.with_fitted(changes, provenance)
