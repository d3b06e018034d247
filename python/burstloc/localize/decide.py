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

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import RANKING_LOCALIZERS, MeterModel
from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.arrival import ArrivalLocalizer, PipePosition
from burstloc.localize.center import posterior_center
from burstloc.localize.evidence import (
    BurstEvidence,
    Localizer,
    Ranking,
    evidence_at,
)
from burstloc.localize.fused import FusedLocalizer, decisive, quantisation_margin
from burstloc.localize.region import (
    REGION_CONFIDENCE,
    Posterior,
    SearchRegion,
    drop_fit,
    region_posterior,
)
from burstloc.localize.signature import SignatureLocalizer

if TYPE_CHECKING:
    from burstloc.localize.classify import Classification
    from burstloc.localize.config import IntervalCalibration
    from burstloc.localize.model import LocalizationModel

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


def _first_and_onset(alarms: Sequence[Any], times: np.ndarray) -> tuple[float, float]:
    first = min(float(times[a.index]) for a in alarms)
    onset = min(float(times[a.start if a.start < a.index else max(a.index - 1, 0)]) for a in alarms)
    return first, onset


def _arrival_first(
    localizer: str, calibration: IntervalCalibration, fused: FusedLocalizer | None
) -> bool:
    return localizer == "arrival" or (
        localizer == "fused" and fused is not None and fused.resolves(calibration.capture_interval)
    )


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
    first, onset = _first_and_onset(alarms, times)
    if _arrival_first(localizer, calibration, fused):
        return first + calibration.arrival_decision_delay
    return onset + calibration.decision_delay


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
    if localizer != "fused" or fused is None or _arrival_first(localizer, calibration, fused):
        return None
    if not alarms:
        raise InputError("no alarm: nothing to decide")
    first, _ = _first_and_onset(alarms, times)
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
    look and its named point (:func:`_named`: the region's centre, inside it). ``waited`` is
    set: the fused localizer answers when the lasting change has settled. While the readings
    end before that look, the decision's ``look_again`` says when to call again. ``None`` when
    the arrivals place the burst nowhere.

    Raises:
        InputError: no alarm.
    """
    if not alarms:
        raise InputError("no alarm: nothing to decide")
    first, _ = _first_and_onset(alarms, times)
    last = float(times[-1])

    def arrivals(decided: float) -> BurstEvidence:  # every alarm up to a later look counts
        window = max(calibration.arrival_decision_delay, decided - first)
        return evidence_at(
            decided, meters, times, readings, alarms, calibration, meter_model, alarm_window=window
        )

    start = first + calibration.arrival_decision_delay
    if resume is not None:
        start = max(start, resume)
    look = _look(fused.arrival, fused.margin, arrivals, start, first, last, calibration)
    if look.again is not None:
        return Decision(look.ranking, look.time, first, waited=True, look_again=look.again)
    posterior = region_posterior(fused.arrival, look.evidence, None)
    if posterior is None:
        return None
    fitted = _position(fused.arrival, look.evidence, look.ranking)
    ranking, at = _named(look.ranking, fitted, posterior)
    return Decision(ranking, look.time, first, waited=True, position=at, posterior=posterior)


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

    Raises:
        InputError: no alarm, or the localizer cannot answer from this evidence.
    """
    fused = fused_of(localizers)
    chosen = localizers[localizer]
    last = float(times[-1])
    first, onset = _first_and_onset(alarms, times)

    def evidence(decided: float) -> BurstEvidence:
        return evidence_at(decided, meters, times, readings, alarms, calibration, meter_model)

    def arrivals(decided: float) -> BurstEvidence:  # every alarm up to a later look counts
        window = max(calibration.arrival_decision_delay, decided - first)
        return evidence_at(
            decided, meters, times, readings, alarms, calibration, meter_model, alarm_window=window
        )

    decided = decision_time(localizer, alarms, times, calibration, fused)
    arrival = chosen if isinstance(chosen, ArrivalLocalizer) else None
    if localizer == "fused" and fused is not None and _arrival_first(localizer, calibration, fused):
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
        at = _position(fused.arrival, arrived, ranking)
        region = region_posterior(fused.arrival, arrived, drop)
        ranking, at = _named(ranking, at, region)
        return Decision(ranking, min(decided, last), first, position=at, posterior=region)
    margin = quantisation_margin(len(arrival.meters)) if fused is None else fused.margin
    start = decided if resume is None else max(decided, resume)
    look = _look(arrival, margin, arrivals, start, first, last, calibration)
    if fused is None or localizer != "fused":
        region = region_posterior(arrival, look.evidence, None)
        ranking, at = _named(look.ranking, _position(arrival, look.evidence, look.ranking), region)
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
        at = _position(arrival, look.evidence, ranking)
        region = region_posterior(arrival, look.evidence, drop)
        ranking, at = _named(ranking, at, region)
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
    at = _position(arrival, look.evidence, ranking)
    region = region_posterior(arrival, look.evidence, drop)
    ranking, at = _named(ranking, at, region)
    return Decision(ranking, min(later, last), first, waited=True, position=at, posterior=region)


def arrival_horizon(arrival: ArrivalLocalizer, calibration: IntervalCalibration) -> float:
    """Seconds after the first alarm of the last look at the arrivals: the arrival localizer's
    :attr:`~burstloc.localize.arrival.ArrivalLocalizer.horizon` (by then a burst's wave has
    reached every meter it will reach), at least the calibrated first look
    (``arrival_decision_delay``)."""
    return max(calibration.arrival_decision_delay, arrival.horizon)


def horizon_of(localizers: Mapping[str, Localizer], calibration: IntervalCalibration) -> float:
    """Seconds after the first alarm of the last look at the arrivals with ``localizers``: their
    ``"arrival"`` localizer's :func:`arrival_horizon`, without one the calibrated first look
    (``arrival_decision_delay``)."""
    arrival = localizers.get("arrival")
    if isinstance(arrival, ArrivalLocalizer):
        return arrival_horizon(arrival, calibration)
    return calibration.arrival_decision_delay


@dataclass(frozen=True)
class _Look:
    """The arrivals as last looked at: the ranking, its evidence and reading time, whether it
    was decisive, and the reading time of the next look if the readings ended before the
    horizon (``None`` otherwise)."""

    ranking: Ranking
    evidence: BurstEvidence
    time: float
    decisive: bool
    again: float | None


def _look(
    arrival: ArrivalLocalizer,
    margin: float,
    evidence: Callable[[float], BurstEvidence],
    decided: float,
    first: float,
    last: float,
    calibration: IntervalCalibration,
) -> _Look:
    """Rank the arrivals at ``decided``, then once every capture interval, until the ranking is
    decisive (:func:`burstloc.localize.fused.decisive` by ``margin``) or the horizon
    (:func:`arrival_horizon`) is reached. A look due after the last reading is not taken: its
    time is returned as ``again``, so that a caller with more readings takes the same looks."""
    dt = calibration.capture_interval
    horizon = first + arrival_horizon(arrival, calibration)
    at = min(decided, last)
    while True:
        seen = evidence(at)
        ranking = arrival.rank(seen)
        settled = decisive(ranking, margin)
        if settled or at >= horizon - 1e-9:
            return _Look(ranking, seen, at, settled, None)
        following = min(at + dt, horizon)
        if following > last + 1e-9:
            return _Look(ranking, seen, at, settled, following)
        at = following


CENTRE_SHARE = 0.25
"""Largest share of the network's main a 95 % search region may cover for its centre to be the
named point (:func:`_named`): a wider region is mostly the prior, and the ranking's best pipe
(the lasting drop's, at coarse capture intervals) names the burst better."""


def _named(
    ranking: Ranking, fitted: PipePosition | None, posterior: Posterior | None
) -> tuple[Ranking, PipePosition | None]:
    """The answer's named point and its ranking.

    Where the 95 % search region is narrow (at most :data:`CENTRE_SHARE` of the network's
    main), or the arrival fit's point on the ranking's best pipe (``fitted``) lies outside it,
    the named point is the posterior's centre (:func:`burstloc.localize.center.posterior_center`:
    the point of least expected distance to the burst, inside the region) and its pipe is
    placed first in the ranking; where ``fitted`` lies in the centre's stretch, it is the
    point (to a metre; the centre is known to one grid segment). Otherwise, and without a
    posterior, ``ranking`` and ``fitted`` as they are."""
    if posterior is None:
        return ranking, fitted
    region = posterior.region(REGION_CONFIDENCE)
    inside = fitted is not None and region.contains(
        fitted.pipe, fitted.start, fitted.metres, fitted.length
    )
    if inside and region.length > CENTRE_SHARE * float(posterior.grid.length.sum()):
        return ranking, fitted
    center = posterior_center(posterior, region).position
    if ranking.rank_of(center.pipe) is None:
        return ranking, fitted
    at = center
    if (
        fitted is not None
        and fitted.pipe == center.pipe
        and center.low - 1e-6 <= fitted.metres <= center.high + 1e-6
    ):
        at = replace(fitted, low=center.low, high=center.high)
    return Ranking(ranking, first=center.pipe), at


def _position(
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
