"""Looking at the arrivals: when, how often, and the fused localizer's early answer.

The arrival localizer, and the fused one where its arrivals can time a wave along its pipes,
look at the arrivals at the first alarm's reading time plus the calibrated
``arrival_decision_delay``, then every :func:`look_interval` (every reading, or every few
readings at high rates) until a look is *decisive*
(:func:`burstloc.localize.fused.decisive`) or the arrival *horizon* is reached
(:func:`arrival_horizon`: by then a burst's wave has reached every meter it will reach):
:func:`look_at`. Where the fused localizer answers with the lasting drop, it gives the same looks'
answer early as a transient record (:func:`early_time`, :func:`early_answer`). Numpy only; on
the live path.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import MeterModel
from burstloc.exceptions import InputError
from burstloc.localize.answer import Decision
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.center import named_point
from burstloc.localize.evidence import BurstEvidence, Localizer, Ranking, evidence_at
from burstloc.localize.fused import FusedLocalizer, decisive
from burstloc.localize.pipes import PipePosition
from burstloc.localize.region import region_posterior

if TYPE_CHECKING:
    from burstloc.localize.interval import IntervalCalibration

__all__ = [
    "ALARM_LAG",
    "ALARM_LAG_SECONDS",
    "LOOK_INTERVAL",
    "Look",
    "arrival_evidence",
    "arrival_first",
    "arrival_horizon",
    "early_answer",
    "early_time",
    "first_and_onset",
    "fitted_position",
    "horizon_of",
    "look_at",
    "look_interval",
]

LOOK_INTERVAL = 0.05
"""Shortest time (s) between two looks at the arrivals: the wave travels 60 m in it at
1 200 m/s, about one of L-TOWN's short pipes. Each look fits every candidate point of the
network again (about 30 ms on L-TOWN's 905 pipes), so a look at every reading would cost more
than the readings' own time at 100 Hz and above; a look every 0.05 s delays an answer by at
most that."""


def look_interval(capture_interval: float) -> float:
    """Time (s) between two looks at the arrivals: the capture interval, or the whole number of
    them nearest :data:`LOOK_INTERVAL` where it is finer (every 5th reading at 100 Hz, every
    12th at 250 Hz), so that every look falls on a reading."""
    return capture_interval * max(1, round(LOOK_INTERVAL / capture_interval))


def first_and_onset(alarms: Sequence[Any], times: np.ndarray) -> tuple[float, float]:
    first = min(float(times[a.index]) for a in alarms)
    onset = min(float(times[a.start if a.start < a.index else max(a.index - 1, 0)]) for a in alarms)
    return first, onset


def arrival_evidence(
    meters: Sequence[str],
    times: np.ndarray,
    readings: np.ndarray,
    alarms: Sequence[Any],
    calibration: IntervalCalibration,
    meter_model: MeterModel,
    first: float,
) -> Callable[[float], BurstEvidence]:
    """The evidence of a look at the arrivals at a reading time: every alarm from the first
    alarm's reading time ``first`` up to the look counts (at least the calibrated
    ``arrival_decision_delay`` of them)."""

    def at(decided: float) -> BurstEvidence:
        window = max(calibration.arrival_decision_delay, decided - first)
        return evidence_at(
            decided, meters, times, readings, alarms, calibration, meter_model, alarm_window=window
        )

    return at


def arrival_first(
    localizer: str, calibration: IntervalCalibration, fused: FusedLocalizer | None
) -> bool:
    return localizer == "arrival" or (
        localizer == "fused" and fused is not None and fused.resolves(calibration.capture_interval)
    )


ALARM_LAG = 2
"""Readings from a front's arrival at a meter to its alarm, allowed for in the horizon: the
reading within which the front arrives and the next. Without them an alarm raised just past
the bare travel time was dismissed with the first meter's (paper15, 2 meters, 5 phases of pipe
17's burst: corroborated instead by the first meter's later ringing, and located 1.4 km off).
At most :data:`ALARM_LAG_SECONDS`, and never less than one reading."""

ALARM_LAG_SECONDS = 0.4
"""Longest lag (s) :data:`ALARM_LAG` readings may add when a reading is shorter than that: at
coarse intervals (1-10 s) a front arrives whole within one reading and its alarm is raised at
that reading, so one reading is allowed; two would hold every first answer back by a reading
more (at 2 s, 2 s per answer)."""


def arrival_horizon(arrival: ArrivalLocalizer, calibration: IntervalCalibration) -> float:
    """Seconds after the first alarm of the last look at the arrivals: the arrival localizer's
    :attr:`~burstloc.localize.arrival.ArrivalLocalizer.horizon` (by then a burst's wave has
    reached every meter it will reach) at the slowest speed its tolerance states, plus
    :data:`ALARM_LAG` readings (the last meter's alarm is raised after its wave arrives; at most
    :data:`ALARM_LAG_SECONDS` but one reading at least), at least the calibrated first look
    (``arrival_decision_delay``)."""
    spread = arrival.horizon / max(1.0 - arrival.wave_speed_tolerance, 1e-9)
    interval = calibration.capture_interval
    lag = max(interval, min(ALARM_LAG * interval, ALARM_LAG_SECONDS))
    return max(calibration.arrival_decision_delay, spread + lag)


def horizon_of(localizers: Mapping[str, Localizer], calibration: IntervalCalibration) -> float:
    """Seconds after the first alarm of the last look at the arrivals with ``localizers``: their
    ``"arrival"`` localizer's :func:`arrival_horizon`, without one the calibrated first look
    (``arrival_decision_delay``)."""
    arrival = localizers.get("arrival")
    if isinstance(arrival, ArrivalLocalizer):
        return arrival_horizon(arrival, calibration)
    return calibration.arrival_decision_delay


@dataclass(frozen=True)
class Look:
    """The arrivals as last looked at: the ranking, its evidence and reading time, whether it
    was decisive, and the reading time of the next look if the readings ended before the
    horizon (``None`` otherwise)."""

    ranking: Ranking
    evidence: BurstEvidence
    time: float
    decisive: bool
    again: float | None


def look_at(
    arrival: ArrivalLocalizer,
    margin: float,
    evidence: Callable[[float], BurstEvidence],
    decided: float,
    first: float,
    last: float,
    calibration: IntervalCalibration,
) -> Look:
    """Rank the arrivals at ``decided``, then once every :func:`look_interval`, until the ranking is
    decisive (:func:`burstloc.localize.fused.decisive` by ``margin``) or the horizon
    (:func:`arrival_horizon`) is reached. A look due after the last reading is not taken: its
    time is returned as ``again``, so that a caller with more readings takes the same looks."""
    step = look_interval(calibration.capture_interval)
    horizon = first + arrival_horizon(arrival, calibration)
    at = min(decided, last)
    while True:
        seen = evidence(at)
        ranking = arrival.rank(seen)
        settled = decisive(ranking, margin)
        if settled or at >= horizon - 1e-9:
            return Look(ranking, seen, at, settled, None)
        following = min(at + step, horizon)
        if following > last + 1e-9:
            return Look(ranking, seen, at, settled, following)
        at = following


def early_time(
    localizer: str,
    alarms: Sequence[Any],
    times: np.ndarray,
    calibration: IntervalCalibration,
    fused: FusedLocalizer | None = None,
) -> float | None:
    """When the fused localizer first looks at the arrivals for its early answer
    (:func:`early_answer`) where it does not look at them first (a capture interval too coarse
    for them to time the wave along its pipes): the first alarm's reading time plus
    ``arrival_decision_delay``, as the arrival localizer does. ``None`` for the other
    localizers and where the fused localizer looks at the arrivals first (its looks give the
    early record then).

    Raises:
        InputError: no alarm.
    """
    if localizer != "fused" or fused is None or arrival_first(localizer, calibration, fused):
        return None
    if not alarms:
        raise InputError("no alarm: nothing to decide")
    first, _ = first_and_onset(alarms, times)
    return first + calibration.arrival_decision_delay


def early_answer(
    fused: FusedLocalizer,
    meters: Sequence[str],
    times: np.ndarray,
    readings: np.ndarray,
    alarms: Sequence[Any],
    calibration: IntervalCalibration,
    meter_model: MeterModel,
    *,
    resume: float | None = None,
) -> Decision | None:
    """The arrivals' answer before the lasting drop has settled, as the arrival localizer gives
    it: looks from :func:`early_time` (or ``resume``, an earlier call's ``look_again``) at every
    reading until one is decisive or the arrival horizon is reached; the search region of that
    look and its named point (:func:`named_point`: the region's centre, inside it). ``waited`` is
    set: the fused localizer answers when the lasting change has settled. While the readings
    end before that look, the decision's ``look_again`` says when to call again. ``None`` when
    the arrivals place the burst nowhere.

    Raises:
        InputError: no alarm.
    """
    if not alarms:
        raise InputError("no alarm: nothing to decide")
    first, _ = first_and_onset(alarms, times)
    last = float(times[-1])
    arrivals = arrival_evidence(meters, times, readings, alarms, calibration, meter_model, first)
    start = first + calibration.arrival_decision_delay
    if resume is not None:
        start = max(start, resume)
    look = look_at(fused.arrival, fused.margin, arrivals, start, first, last, calibration)
    if look.again is not None:
        return Decision(look.ranking, look.time, first, waited=True, look_again=look.again)
    posterior = region_posterior(fused.arrival, look.evidence, None)
    if posterior is None:
        return None
    fitted = fitted_position(fused.arrival, look.evidence, look.ranking)
    ranking, at = named_point(look.ranking, fitted, posterior)
    return Decision(ranking, look.time, first, waited=True, position=at, posterior=posterior)


def fitted_position(
    arrival: ArrivalLocalizer | None, evidence: BurstEvidence, ranking: Ranking
) -> PipePosition | None:
    """The burst's position on ``ranking``'s best pipe from the arrival fit of ``evidence``
    (``None`` without an arrival localizer, a best pipe, or an alarm it knows)."""
    best = ranking.best
    if arrival is None or best is None:
        return None
    try:
        return arrival.position(evidence, best.pipe)
    except InputError:
        return None
