"""The *fused* localizer: arrivals and signatures, weighted by what the capture interval resolves.

Arrival times tell pipes apart only while the capture interval ``dt`` is short against the wave's
travel time along a pipe; the lasting drop (signature) needs a settled window but does not care
about ``dt``. So the fused localizer weighs the two by

    w_arrival = exp(-dt / tau),    w_signature = 1 - w_arrival,

with ``tau`` the median travel time of the wave along one candidate pipe (median pipe length /
wave speed; about 0.5 s on paper15): at 0.2 s arrivals weigh 0.7, at 2 s 0.03, at 10 s nothing.
Where meters are few, far apart, the arrivals must place a burst among the meters rather than tell
a pipe from its neighbour, and ``tau`` is the longer wave travel time from a pipe's middle to its
nearest meter (the median over the candidate pipes): 0.15 s on L-TOWN with BattLeDIM's 33
sensors, where its 50 m pipes alone would make it 0.04 s and leave the arrivals a weight of 0.29
at 0.05 s, though they place a burst there within 45 m on average and the lasting drop within
80 m. The same weights temper the lasting drop in the search region
(:func:`burstloc.localize.region.drop_fit`).

Each localizer's ranking is turned into a log-likelihood-like score that is 0 for its best pipe:

* arrival: ``(score - best) / 0.5``: the arrival score is the RMS misfit in capture intervals
  (plus the amplitude tie-breaker), and half a capture interval is the quantisation noise of an
  alarm start;
* signature: ``-(rms^2 - rms_best^2) / (2 sigma^2)`` with ``sigma = max(rms_best, 1 mm)``: the
  best pipe's residual is the noise level of the drop estimate.

The fused score is ``w_arrival * L_arrival + w_signature * L_signature`` (over the weights'
sum), less the best pipe's: 0 for the best pipe, as each part's is, even where the two parts'
best pipes differ.

When the localizer answers: signatures need ``settle`` seconds of settled readings, so the fused
localizer first looks at the arrivals at the arrival localizer's (short) delay where they can time
the wave along some candidate pipe (:meth:`FusedLocalizer.resolves`: ``exp(-dt / T) >= 0.5`` with
``T`` the wave's travel time along the longest pipe; networks mix pipes of 30 m and 3 km, and
with meters at most junctions the arrivals tell even a short pipe from its neighbours by the
order in which the meters beyond its ends hear the wave), and again at every reading until the
arrival horizon (the wave of a burst anywhere has reached every meter it will reach: with few
meters far apart, the first look sees one or two of them). It answers at the first look whose
arrivals are *decisive* (:meth:`FusedLocalizer.decisive`: the runner-up is at least ``margin``
log-likelihood units behind, by default the quantisation noise of the RMS arrival misfit,
:func:`quantisation_margin`), and at the signature localizer's delay otherwise, with the arrival
ranking of the last look (:func:`burstloc.localize.decide.rank_alarms`). A burst near a
junction fits every pipe at that junction about equally well in time; the lasting drop then tells
them apart. Numpy only; on the live path."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import BurstEvidence, RankedPipe, Ranking
from burstloc.localize.signature import SignatureLocalizer

__all__ = [
    "FusedLocalizer",
    "arrival_loglik",
    "decisive",
    "quantisation_margin",
    "signature_loglik",
]

ARRIVAL_SCALE = 0.5
"""Misfit (capture intervals) worth one unit of arrival log-likelihood."""

SIGNATURE_FLOOR = 0.001
"""Smallest noise level (m) assumed for a drop estimate."""


def quantisation_margin(meters: int) -> float:
    """Default arrival lead that makes an early answer decisive, for ``meters`` meters.

    An alarm start is known to one capture interval: uniform quantisation noise of standard
    deviation ``1 / sqrt(12)`` intervals per meter, ``1 / sqrt(12 M)`` for an RMS over ``M``
    meters. A runner-up whose RMS misfit is within that of the best is not told apart by the
    arrivals; in log-likelihood units (misfit / :data:`ARRIVAL_SCALE`) the margin is
    ``2 / sqrt(12 M)``, about 0.15 for 15 meters.
    """
    if meters < 1:
        raise ConfigError(f"meters must be >= 1, got {meters}")
    return 1.0 / (ARRIVAL_SCALE * math.sqrt(12.0 * meters))


def arrival_loglik(ranking: Ranking) -> dict[str, float]:
    """Arrival scores as log-likelihoods: 0 for the best pipe, ``(score - best) / 0.5`` else."""
    best = ranking.best
    if best is None:
        return {}
    return {p.pipe: (p.score - best.score) / ARRIVAL_SCALE for p in ranking}


def decisive(arrival_ranking: Ranking, margin: float) -> bool:
    """Whether an arrival ranking's best pipe leads the runner-up by at least ``margin``
    log-likelihood units (:func:`arrival_loglik`; a ranking of fewer than two pipes is)."""
    loglik = sorted(arrival_loglik(arrival_ranking).values(), reverse=True)
    return len(loglik) < 2 or loglik[0] - loglik[1] >= margin


def signature_loglik(ranking: Ranking) -> dict[str, float]:
    """Signature scores (-RMS, m) as Gaussian log-likelihoods relative to the best pipe."""
    best = ranking.best
    if best is None:
        return {}
    sigma = max(-best.score, SIGNATURE_FLOOR)
    return {p.pipe: -(p.score**2 - best.score**2) / (2 * sigma**2) for p in ranking}


def _arrival_weight(capture_interval: float, travel: float) -> float:
    """``exp(-dt / travel)``: how far arrivals captured every ``dt`` s can time a wave that
    takes ``travel`` s (validates ``dt``)."""
    if not (math.isfinite(capture_interval) and capture_interval > 0):
        raise InputError(f"capture_interval must be > 0, got {capture_interval}")
    return math.exp(-capture_interval / travel)


class FusedLocalizer:
    """Combine an :class:`ArrivalLocalizer` and a :class:`SignatureLocalizer` (module docstring).

    ``tau`` (s) defaults to the longer of the median wave travel time along one of the arrival
    localizer's pipes and from a pipe's middle to its nearest meter (module docstring);
    ``margin`` is the arrival log-likelihood lead that makes an early answer decisive (default
    :func:`quantisation_margin` of the arrival localizer's meter count).
    """

    def __init__(
        self,
        arrival: ArrivalLocalizer,
        signature: SignatureLocalizer,
        *,
        tau: float | None = None,
        margin: float | None = None,
    ) -> None:
        if tau is None:
            tau = max(arrival.pipe_travel, arrival.meter_travel)
        if not (math.isfinite(tau) and tau > 0):
            raise ConfigError(f"tau must be > 0 s, got {tau}")
        if margin is None:
            margin = quantisation_margin(len(arrival.meters))
        if not (math.isfinite(margin) and margin >= 0):
            raise ConfigError(f"margin must be >= 0, got {margin}")
        self.margin = float(margin)
        common = {p.pipe for p in arrival.pipes} & set(signature.signatures.pipes)
        if not common:
            raise ConfigError("the arrival and signature localizers share no pipe")
        self.arrival = arrival
        self.signature = signature
        self.tau = float(tau)
        self.longest_travel = arrival.longest_travel
        """Wave travel time (s) along the arrival localizer's longest pipe."""

    def weights(self, capture_interval: float) -> tuple[float, float]:
        """``(w_arrival, w_signature)`` at a capture interval (s)."""
        w_arrival = _arrival_weight(capture_interval, self.tau)
        return w_arrival, 1.0 - w_arrival

    def resolves(self, capture_interval: float) -> bool:
        """Whether arrivals captured every ``capture_interval`` s can time the wave along the
        longest candidate pipe (``exp(-dt / travel) >= 0.5``): the condition for looking at them
        early."""
        return _arrival_weight(capture_interval, self.longest_travel) >= 0.5

    def decision_delay(self, capture_interval: float) -> float:
        """Seconds after the first alarm (arrivals) or the onset (signatures) at which the fused
        localizer first looks at the evidence at this interval: the arrival localizer's delay
        where the arrivals can resolve some pipe (:meth:`resolves`), else the signature's."""
        if self.resolves(capture_interval):
            return self.arrival.decision_delay
        return self.signature.decision_delay

    def decisive(self, arrival_ranking: Ranking) -> bool:
        """Whether an arrival ranking's best pipe leads the runner-up by at least ``margin``
        (:func:`decisive`)."""
        return decisive(arrival_ranking, self.margin)

    def signature_ready(self, evidence: BurstEvidence) -> bool:
        """Whether ``evidence`` holds readings before the onset and at least three settled
        ones: what the signature localizer needs."""
        settled = evidence.times >= evidence.onset + self.signature.settle
        return bool(np.count_nonzero(settled) >= 3 and np.any(evidence.times <= evidence.onset))

    def rank(
        self,
        evidence: BurstEvidence,
        *,
        arrival_ranking: Ranking | None = None,
        signature_ranking: Ranking | None = None,
    ) -> Ranking:
        """Pipes known to both localizers, best first, scored by the weighted log-likelihoods.

        ``arrival_ranking``, if given, is used instead of ranking ``evidence``'s arrivals (the
        arrivals as seen at an earlier decision time). ``signature_ranking``, if given, must be
        the signature localizer's ranking of this same ``evidence`` (computed already, e.g. by a
        caller scoring both localizers); it saves fitting the readings twice. A localizer that
        cannot answer (no alarm for arrivals; no settled readings or no baseline for signatures)
        is left out and the other one decides alone.
        """
        w_arrival, w_signature = self.weights(evidence.capture_interval)
        parts: list[tuple[float, Mapping[str, float], Ranking]] = []
        if arrival_ranking is not None and w_arrival > 0:
            parts.append((w_arrival, arrival_loglik(arrival_ranking), arrival_ranking))
        elif evidence.alarms and w_arrival > 0:
            ranking = self.arrival.rank(evidence)
            parts.append((w_arrival, arrival_loglik(ranking), ranking))
        if self.signature_ready(evidence) and w_signature > 0:
            ranking = (
                self.signature.rank(evidence) if signature_ranking is None else signature_ranking
            )
            parts.append((w_signature, signature_loglik(ranking), ranking))
        if not parts:
            raise InputError(
                "neither arrivals (no alarm) nor signatures (no settled readings) can localize"
            )
        pipes = set.intersection(*(set(loglik) for _, loglik, _ in parts))
        ends = {p.pipe: (p.start, p.end) for _, _, r in parts for p in r}
        total = sum(w for w, _, _ in parts)
        fused = {p: sum(w * loglik[p] for w, loglik, _ in parts) / total for p in pipes}
        best = max(fused.values(), default=0.0)  # 0 for the best pipe, as each part's is
        return Ranking(RankedPipe(pipe, *ends[pipe], score=s - best) for pipe, s in fused.items())
