"""When a ranking localizer answers, and its answer, from a detector bank's alarms.

One place for the decision rule shared by ``burstloc evaluate`` and ``burstloc study`` (and any
live caller holding the readings so far):

* ``arrival``: at the first alarm's reading time plus the calibrated
  ``arrival_decision_delay`` (about one wave travel time along a pipe);
* ``signature``: at the onset (the earliest alarm start, the last reading before the change) plus
  the calibrated ``decision_delay`` (150 s: the lasting drop needs settled readings);
* ``fused``: where arrivals carry most of the weight (``w_arrival >= 0.5``, short capture
  intervals) it first ranks at the arrival time. If that ranking is *decisive* (the runner-up's
  log-likelihood is at least :attr:`burstloc.localize.fused.FusedLocalizer.margin` below the best)
  that is
  the answer; otherwise (a burst near a junction fits several of the junction's pipes almost
  equally well in time) it waits for the signature's decision time and answers with both. At
  coarse intervals it answers at the signature's time.

Numpy only; on the live path.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import MeterModel
from burstloc.exceptions import InputError
from burstloc.localize.evidence import BurstEvidence, Ranking, evidence_from_alarms

if TYPE_CHECKING:
    from burstloc.experiments.calibrate import IntervalCalibration
    from burstloc.localize.fused import FusedLocalizer

__all__ = ["Decision", "decision_time", "rank_alarms", "ranking_localizers"]


@dataclass(frozen=True)
class Decision:
    """A ranking localizer's answer: the ranking, the reading time it was given at, and whether
    the fused localizer waited for the signature (its arrivals were not decisive)."""

    ranking: Ranking
    time: float
    waited: bool = False


def ranking_localizers(network: str | os.PathLike[str], meters: Sequence[str]) -> dict[str, Any]:
    """The ranking localizers of ``meters`` on ``network``, by name (``arrival``, ``signature``,
    ``fused``): the shortest-path graph and the cached steady-state signature sets (one WNTR
    run per pipe and candidate position the first time; see :mod:`burstloc.localize.signature`).

    Raises:
        NetworkError: missing or malformed network, or a meter that is not one of its junctions.
    """
    from burstloc.localize.arrival import ArrivalLocalizer
    from burstloc.localize.fused import FusedLocalizer
    from burstloc.localize.signature import SignatureLocalizer, cached_signature_sets

    arrival = ArrivalLocalizer.from_network(network, meters)
    signature = SignatureLocalizer(cached_signature_sets(network, meters))
    return {"arrival": arrival, "signature": signature, "fused": FusedLocalizer(arrival, signature)}


def _first_and_onset(alarms: Sequence[Any], times: np.ndarray) -> tuple[float, float]:
    first = min(float(times[a.index]) for a in alarms)
    onset = min(float(times[a.start if a.start < a.index else max(a.index - 1, 0)]) for a in alarms)
    return first, onset


def _arrival_first(
    localizer: str, calibration: IntervalCalibration, fused: FusedLocalizer | None
) -> bool:
    return localizer == "arrival" or (
        localizer == "fused"
        and fused is not None
        and fused.weights(calibration.capture_interval)[0] >= 0.5
    )


def decision_time(
    localizer: str,
    alarms: Sequence[Any],
    times: np.ndarray,
    calibration: IntervalCalibration,
    fused: FusedLocalizer | None = None,
) -> float:
    """When a ranking localizer first looks at the evidence (no truth used).

    ``arrival`` (and ``fused`` while its arrival weight is at least 0.5): the first alarm's
    reading time plus ``calibration.arrival_decision_delay``. ``signature`` (and ``fused``
    otherwise): the onset plus ``calibration.decision_delay``, so the answer comes within that
    delay of the burst itself. (:func:`rank_alarms` may defer a fused answer; see the module.)

    Raises:
        InputError: no alarm.
    """
    if not alarms:
        raise InputError("no alarm: nothing to decide")
    first, onset = _first_and_onset(alarms, times)
    if _arrival_first(localizer, calibration, fused):
        return first + calibration.arrival_decision_delay
    return onset + calibration.decision_delay


def rank_alarms(
    localizer: str,
    localizers: Mapping[str, Any],
    meters: Sequence[str],
    times: np.ndarray,
    readings: np.ndarray,
    alarms: Sequence[Any],
    calibration: IntervalCalibration,
    meter_model: MeterModel,
    *,
    signature_ranking: Ranking | None = None,
) -> Decision:
    """Rank the pipes with ``localizers[localizer]`` at its decision time (module docstring).

    ``times`` / ``readings`` (T,) / (T, M) are the captured readings of ``meters``; ``alarms`` the
    calibrated bank's alarms on them. The decision time is capped at the last reading.
    ``signature_ranking``: for ``fused``, the ranking of the ``signature`` decision on these same
    readings and alarms, if the caller has it (the fused localizer looks at the signatures at
    that same time, so it need not fit them again); ignored otherwise.

    Raises:
        InputError: no alarm, or the localizer cannot answer from this evidence.
    """
    fused: FusedLocalizer | None = localizers.get("fused")
    chosen = localizers[localizer]
    last = float(times[-1])

    def evidence(decided: float) -> BurstEvidence:
        return evidence_from_alarms(
            meters,
            times,
            readings,
            alarms,
            capture_interval=calibration.capture_interval,
            meter_model=meter_model,
            decision_time=decided,
            alarm_window=calibration.arrival_decision_delay,
        )

    decided = decision_time(localizer, alarms, times, calibration, fused)
    early = evidence(decided)
    if fused is None or localizer != "fused":
        return Decision(chosen.rank(early), min(decided, last))
    if not _arrival_first(localizer, calibration, fused):
        # at the signature's own decision time
        return Decision(fused.rank(early, signature_ranking=signature_ranking), min(decided, last))
    arrivals = fused.arrival.rank(early)
    _, onset = _first_and_onset(alarms, times)
    later = onset + calibration.decision_delay
    if fused.decisive(arrivals) or later <= decided:
        return Decision(fused.rank(early, arrival_ranking=arrivals), min(decided, last))
    ranking = fused.rank(
        evidence(later), arrival_ranking=arrivals, signature_ranking=signature_ranking
    )
    return Decision(ranking, min(later, last), waited=True)
