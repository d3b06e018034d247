"""When a ranking localizer answers, and its answer, from a detector bank's alarms.

One place for the decision rule shared by ``burstloc evaluate`` and ``burstloc study`` (and any
live caller holding the readings so far):

* ``arrival``: it first looks at the arrivals at the first alarm's reading time plus the
  calibrated ``arrival_decision_delay`` (about one wave travel time along a pipe), then again
  at every reading, and answers at the first look whose ranking is *decisive* (the runner-up's
  log-likelihood is at least the margin below the best,
  :func:`burstloc.localize.fused.decisive`; the fused localizer's
  :attr:`~burstloc.localize.fused.FusedLocalizer.margin`), at the latest at the arrival
  *horizon* (:func:`arrival_horizon`: by then the wave of a burst anywhere has reached every
  meter it will reach). With meters at most junctions the first look is usually decisive; with
  few meters, far apart, the wave has reached one or two of them by then, and the pipes that
  fit those alone are many;
* ``signature``: at the onset (the earliest alarm start, the last reading before the change) plus
  the calibrated ``decision_delay`` (150 s: the lasting drop needs settled readings);
* ``fused``: where the capture interval is short enough for the arrivals to time the wave along
  some candidate pipe (:meth:`burstloc.localize.fused.FusedLocalizer.resolves`) it looks at the
  arrivals as the arrival localizer does. A decisive look is the answer; if none is by the
  horizon (a burst near a junction fits several of the junction's pipes almost equally well in
  time) it waits for the signature's decision time and answers with both, the arrivals as of
  the horizon. At coarse intervals it answers at the signature's time, and gives an *early
  answer* (:func:`early_answer`, from :func:`early_time`) as the arrival localizer answers: the
  search region of its first decisive look at the arrivals (or of the horizon's) and the
  region's centre as the named point (:func:`burstloc.localize.center.posterior_center`),
  seconds after the burst, whatever the pipe lengths.

Every answer of the arrival and fused localizers carries the burst's position on the named pipe
(metres from its flow-direction start node, with an interval) from the arrival fit at the last
look at the arrivals, whenever the answer comes
(:meth:`burstloc.localize.arrival.ArrivalLocalizer.position`).

The localizers come as a :class:`RankingLocalizers` (built from a stored
:class:`burstloc.localize.model.LocalizationModel` by :meth:`RankingLocalizers.from_model`, or any
mapping of names to :class:`burstloc.localize.evidence.Localizer`); every answer is a
:class:`Decision`. Numpy only; on the live path.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import RANKING_LOCALIZERS, MeterModel
from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.answer import Decision, json_time
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.center import named_point
from burstloc.localize.evidence import BurstEvidence, Localizer, Ranking, evidence_at
from burstloc.localize.fused import FusedLocalizer, quantisation_margin
from burstloc.localize.looks import (
    arrival_evidence,
    arrival_first,
    arrival_horizon,
    early_answer,
    early_time,
    first_and_onset,
    fitted_position,
    horizon_of,
    look_at,
)
from burstloc.localize.region import drop_fit, region_posterior
from burstloc.localize.signature import SignatureLocalizer

if TYPE_CHECKING:
    from burstloc.localize.interval import IntervalCalibration
    from burstloc.localize.model import LocalizationModel

# Decision and json_time (burstloc.localize.answer), arrival_horizon, horizon_of, early_time and
# early_answer (burstloc.localize.looks) are named here too: the decision's front door.
__all__ = [
    "Decision",
    "RankingLocalizers",
    "arrival_horizon",
    "decision_time",
    "early_answer",
    "early_time",
    "fused_of",
    "horizon_of",
    "json_time",
    "rank_alarms",
]


@dataclass(frozen=True)
class RankingLocalizers(Mapping[str, Localizer]):
    """The three ranking localizers of one network and meter set, also readable by name
    (``localizers["fused"]``; names :data:`burstloc.constants.RANKING_LOCALIZERS`)."""

    arrival: ArrivalLocalizer
    signature: SignatureLocalizer
    fused: FusedLocalizer

    @classmethod
    def from_model(cls, model: LocalizationModel) -> RankingLocalizers:
        """Build the localizers from a stored model (numpy only: no hydraulic model runs).

        Raises:
            ConfigError: the model's parts do not make localizers (e.g. no shared pipe).
        """
        arrival = ArrivalLocalizer(
            model.pipes,
            model.meters,
            model.node_distances,
            wave_speed=model.wave_speed,
            fronts=model.fronts,
            wave_speed_tolerance=model.wave_speed_tolerance,
            clock_tolerance=model.clock_tolerance,
            clock_offsets=model.clock_offsets,
            timing_factor=model.timing_factor,
            connectors=model.connectors or (),
        )
        signature = SignatureLocalizer(model.signature_sets)
        return cls(arrival, signature, FusedLocalizer(arrival, signature))

    def __getitem__(self, name: str) -> Localizer:
        """The localizer called ``name``."""
        if name not in RANKING_LOCALIZERS:
            raise KeyError(name)
        localizer: Localizer = getattr(self, name)
        return localizer

    def __iter__(self) -> Iterator[str]:
        """The names, in :data:`burstloc.constants.RANKING_LOCALIZERS` order."""
        return iter(RANKING_LOCALIZERS)

    def __len__(self) -> int:
        """Three."""
        return len(RANKING_LOCALIZERS)


def fused_of(localizers: Mapping[str, Localizer]) -> FusedLocalizer | None:
    """The ``"fused"`` localizer of ``localizers``, if there is one.

    Raises:
        ConfigError: ``"fused"`` is not a :class:`~burstloc.localize.fused.FusedLocalizer`.
    """
    fused = localizers.get("fused")
    if fused is not None and not isinstance(fused, FusedLocalizer):
        raise ConfigError(f"the 'fused' localizer must be a FusedLocalizer, got {type(fused)}")
    return fused


def decision_time(
    localizer: str,
    alarms: Sequence[Any],
    times: np.ndarray,
    calibration: IntervalCalibration,
    fused: FusedLocalizer | None = None,
) -> float:
    """When a ranking localizer first looks at the evidence (no truth used).

    ``arrival`` (and ``fused`` where the arrivals can resolve some pipe): the first alarm's
    reading time plus ``calibration.arrival_decision_delay``. ``signature`` (and ``fused``
    otherwise): the onset plus ``calibration.decision_delay``, so the answer comes within that
    delay of the burst itself. (:func:`rank_alarms` may look again later; see the module.)

    Raises:
        InputError: no alarm.
    """
    if not alarms:
        raise InputError("no alarm: nothing to decide")
    first, onset = first_and_onset(alarms, times)
    if arrival_first(localizer, calibration, fused):
        return first + calibration.arrival_decision_delay
    return onset + calibration.decision_delay


def rank_alarms(
    localizer: str,
    localizers: Mapping[str, Localizer],
    meters: Sequence[str],
    times: np.ndarray,
    readings: np.ndarray,
    alarms: Sequence[Any],
    calibration: IntervalCalibration,
    meter_model: MeterModel,
    *,
    signature_ranking: Ranking | None = None,
    resume: float | None = None,
    provisional: bool = True,
) -> Decision:
    """Rank the pipes with ``localizers[localizer]`` at its decision time (module docstring).

    ``times`` / ``readings`` (T,) / (T, M) are the captured readings of ``meters``; ``alarms`` the
    calibrated bank's alarms on them. The decision time is capped at the last reading.
    ``signature_ranking``: for ``fused``, the ranking of the ``signature`` decision on these same
    readings and alarms, if the caller has it (the fused localizer looks at the signatures at
    that same time, so it need not fit them again); ignored otherwise. ``resume``: the
    ``look_again`` of an earlier call on the same burst, whose looks were not decisive: the looks
    start there instead of being taken again (a look depends only on the readings up to it, so
    the answer is the same; the live monitor, whose readings grow by one step per call, would
    otherwise repeat every earlier look at every reading); or a reading time before which no look
    is taken (the monitor's, and the events evaluation's, first look at alarms that a second meter
    corroborated after the decision time: :mod:`burstloc.localize.corroborate`).
    ``provisional=False``: where the looks are not decisive yet (``look_again`` set), only the
    arrivals' ranking and ``look_again`` are returned, without the region, the named point or
    the lasting drop's fit: for a caller that discards a provisional answer and calls again
    (the live monitor, which would otherwise compute a whole search region at every look
    while it waits).

    Raises:
        InputError: no alarm, or the localizer cannot answer from this evidence.
    """
    fused = fused_of(localizers)
    chosen = localizers[localizer]
    last = float(times[-1])
    first, onset = first_and_onset(alarms, times)

    def evidence(decided: float) -> BurstEvidence:
        return evidence_at(decided, meters, times, readings, alarms, calibration, meter_model)

    arrivals = arrival_evidence(meters, times, readings, alarms, calibration, meter_model, first)
    decided = decision_time(localizer, alarms, times, calibration, fused)
    arrival = chosen if isinstance(chosen, ArrivalLocalizer) else None
    if localizer == "fused" and fused is not None and arrival_first(localizer, calibration, fused):
        arrival = fused.arrival
    if arrival is None:
        early = evidence(decided)
        if fused is None or localizer != "fused":
            return Decision(chosen.rank(early), min(decided, last), first)
        # at the signature's own decision time; the position from the arrivals at their
        # horizon (by the signature's time every meter's wave has come)
        drop = drop_fit(fused, early, signature_ranking)
        ranking = fused.rank(early, signature_ranking=None if drop is None else drop.ranking)
        arrived = arrivals(min(first + arrival_horizon(fused.arrival, calibration), last))
        at = fitted_position(fused.arrival, arrived, ranking)
        region = region_posterior(fused.arrival, arrived, drop)
        ranking, at = named_point(ranking, at, region)
        return Decision(ranking, min(decided, last), first, position=at, posterior=region)
    margin = quantisation_margin(len(arrival.meters)) if fused is None else fused.margin
    start = decided if resume is None else max(decided, resume)
    look = look_at(arrival, margin, arrivals, start, first, last, calibration)
    if look.again is not None and not provisional:
        return Decision(look.ranking, look.time, first, look_again=look.again)
    if fused is None or localizer != "fused":
        region = region_posterior(arrival, look.evidence, None)
        ranking, at = named_point(
            look.ranking, fitted_position(arrival, look.evidence, look.ranking), region
        )
        return Decision(
            ranking, look.time, first, position=at, look_again=look.again, posterior=region
        )
    later = onset + calibration.decision_delay
    if look.decisive or look.again is not None or later <= look.time:
        drop = drop_fit(fused, look.evidence, None)
        ranking = fused.rank(
            look.evidence,
            arrival_ranking=look.ranking,
            signature_ranking=None if drop is None else drop.ranking,
        )
        at = fitted_position(arrival, look.evidence, ranking)
        region = region_posterior(arrival, look.evidence, drop)
        ranking, at = named_point(ranking, at, region)
        return Decision(
            ranking, look.time, first, position=at, look_again=look.again, posterior=region
        )
    settled = evidence(later)
    drop = drop_fit(fused, settled, signature_ranking)
    ranking = fused.rank(
        settled,
        arrival_ranking=look.ranking,
        signature_ranking=None if drop is None else drop.ranking,
    )
    at = fitted_position(arrival, look.evidence, ranking)
    region = region_posterior(arrival, look.evidence, drop)
    ranking, at = named_point(ranking, at, region)
    return Decision(ranking, min(later, last), first, waited=True, position=at, posterior=region)
