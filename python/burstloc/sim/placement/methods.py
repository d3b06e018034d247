"""Meter placement: which junctions should carry pressure meters, and the meter file.

Three methods, all deterministic and computed from the network model alone (no burst is
simulated), all greedy: starting from no meter, add one junction at a time.

* ``coverage`` (:func:`coverage_meters`): separation of the steady-state burst signatures. Add
  the junction that most increases the smallest distance between any two pipes' unit-normalised
  signatures (:mod:`burstloc.sim.signatures.compute`) restricted to the chosen meters (ties: the
  larger
  total signature); every added meter separates the pair of pipes hardest to tell apart so far.
  It serves the signature localizer, which reads the lasting drop.
* ``arrival`` (:func:`arrival_meters`): separation of wave arrival-time patterns. A burst at a
  point ``x`` reaches meter ``j`` after ``d(x, j) / a`` (path length along the pipes over the wave
  speed); the burst time is unknown, so two points ``x`` and ``y`` look alike to the meters ``S``
  when the differences ``d(x, j) / a - d(y, j) / a`` are nearly the same for every ``j`` in
  ``S``: their *separation* is the RMS of those differences about their mean. Two pipes are as
  separated as their closest pair of candidate points (:data:`ARRIVAL_POINTS` along each);
  the method adds the junction that most increases ``sum over pipe pairs of min(separation,
  resolution)``, a count of pipe pairs told apart within the capture interval ``resolution``
  (default 0.2 s), saturating so that no single pair dominates. One meter separates nothing (the
  burst time is free): the first is the junction whose travel times to the candidate points
  spread most, a peripheral one. It serves the arrival and fused localizers, which answer from
  arrival times at fine capture intervals. Each step looks only at the pairs of points some
  junction could still leave closer than ``resolution``, and evaluates the junctions exactly
  in the order of a cheap upper bound until the bound settles the choice (at most
  :data:`~burstloc.sim.placement.arrival.MAX_EXACT` of them): the exact greedy placement on
  every network with no more junctions than that, and wherever the bound settles it (L-TOWN,
  33 meters: about 30 s). Its own module, :mod:`burstloc.sim.placement.arrival`.

* ``region`` (:func:`burstloc.sim.placement.region.region_meters`): the shortest expected search
  region. Add the junction that most reduces the expected length of main whose arrival pattern
  is within a capture interval of the burst point's (the points a search region cannot rule out
  from the arrivals); its own module.

On a network of more than :data:`~burstloc.sim.placement.scaled.SCALE_JUNCTIONS` junctions
(1 000; BWSN_Network_2 has 12 523) ``arrival`` and ``region`` choose among a well-spread subset
of the junctions and evaluate their objective on a seeded sample of burst points
(:mod:`burstloc.sim.placement.scaled`): an approximation, deterministic; every smaller network
gets the exact greedy above.

**The meters a utility has.** Every method takes ``keep``: the greedy starts from those
meters instead of from none and adds ``count`` more (``burstloc place --keep IDS|FILE --meters
K``; with ``--keep`` the command's default method is ``region``, the measure the search regions
are scored by). A junction next to an owned meter is added only when the measure says it pays:
two meters one short pipe apart hear almost the same arrival times, so each separates little of
what the other does not; the greedy chooses one only where it splits a stretch of main the
others leave alike (on L-TOWN the arrival method, which counts pipe pairs told apart rather than
metres of main, did choose such neighbours: n347/n348/n349). :func:`score_meters` rates a given
set on the ``region`` measure: the expected ambiguous main, its median over the bursts, the
share of bursts it leaves at most :data:`~burstloc.constants.SEARCHABLE` m to search, and each
meter's contribution (the expected ambiguous main without it minus with it: the meter that adds
least is the first to move).

How far a set of meters can go on arrivals alone, pipe by pipe: :func:`arrival_separation` (and
:func:`meter_separation` on a network file) is the share of the candidate burst points whose
arrival pattern at the meters is at least one capture interval from every point of every other
pipe (4 of paper15's 15 junctions, N4 N7 1 8: 63 %; all 15: 82 %; 2 of Net1's 9, 13 31: 17 %).
It is 0 % on a network of short pipes whatever the meters (L-TOWN: a pipe's candidate points
lie within half a capture interval's travel, 120 m at 0.2 s, of another pipe's), which is why
``burstloc place`` prints the ``region`` measure instead.

:func:`place_meters` runs either on a network file and returns a
:class:`~burstloc.sim.placement.meter_file.MeterSet`, which saves as the meter file
(:mod:`burstloc.sim.placement.meter_file`, whose names this module re-exports).

**Pipes of their own wave speed.** ``arrival``, ``region`` and the scores time every path at
``wave_speed``; with ``wave_speeds`` (:class:`burstloc.wave_speeds.WaveSpeeds`: PE and PVC mains
at 300-500 m/s among iron at 1 200) each pipe is crossed at its own speed instead, the paths
weighted by travel time (:func:`burstloc.sim.model.prepare.length_graph`): a pipe at 400 m/s
takes as long as three times its length at 1 200 m/s, as the localizers time it once
``burstloc calibrate`` is given the same speeds. ``coverage`` reads steady states: wave speeds
do not enter it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from burstloc.constants import SEARCHABLE, WAVE_SPEED
from burstloc.exceptions import ConfigError
from burstloc.network import NetworkSource, as_network
from burstloc.sim.placement._checks import check_meter_count, kept_indices, meter_geometry
from burstloc.sim.placement.arrival import ARRIVAL_POINTS, arrival_meters, arrival_separation
from burstloc.sim.placement.meter_file import (
    METERS_FORMAT,
    PLACEMENT_METHODS,
    MeterSet,
    meter_list,
)
from burstloc.sim.placement.region import (
    AmbiguityProfile,
    ambiguity_profile,
    ambiguous_length,
    region_meters,
)
from burstloc.sim.placement.scaled import DEFAULT_SCALING, Scaling, reduced_problem
from burstloc.wave_speeds import WaveSpeeds, stretch_of

__all__ = [
    "ARRIVAL_POINTS",
    "METERS_FORMAT",
    "PLACEMENT_METHODS",
    "MeterScores",
    "MeterSet",
    "arrival_meters",
    "arrival_separation",
    "coverage_meters",
    "meter_ambiguity",
    "meter_list",
    "meter_scores",
    "meter_separation",
    "place_meters",
    "score_meters",
]


def coverage_meters(signatures: Any, count: int, keep: Sequence[str] = ()) -> tuple[str, ...]:
    """Choose ``count`` meters by greedy coverage of burst signatures (module docstring).

    Args:
        signatures: a :class:`burstloc.localize.signature.SignatureSet` over the candidate
            junctions.
        count: how many meters to add, 1..number of candidates not kept.
        keep: meters the network has already: the greedy starts from them.

    Returns:
        The chosen junctions, kept ones included, in the signature set's meter order.

    Raises:
        ConfigError: ``count`` out of range, a kept meter that is not a candidate.
    """
    meters = list(signatures.meters)
    chosen = kept_indices(keep, meters)
    check_meter_count(count, len(meters) - len(chosen))
    matrix = np.abs(np.asarray(signatures.matrix, dtype=np.float64))
    strength = matrix.sum(axis=0)
    pairs = np.triu_indices(matrix.shape[0], k=1)
    for _ in range(count):
        keys = []
        for j in range(len(meters)):
            if j in chosen:
                continue
            sub = matrix[:, [*chosen, j]]
            norm = np.linalg.norm(sub, axis=1, keepdims=True)
            unit = np.divide(sub, norm, out=np.zeros_like(sub), where=norm > 0)
            gaps = np.linalg.norm(unit[pairs[0]] - unit[pairs[1]], axis=1)
            keys.append((float(gaps.min()) if gaps.size else 0.0, float(strength[j]), -j))
        chosen.append(-max(keys)[2])
    return tuple(meters[j] for j in sorted(chosen))


def place_meters(
    network: NetworkSource,
    count: int,
    *,
    method: str = "arrival",
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    scaling: Scaling = DEFAULT_SCALING,
    keep: Sequence[str] = (),
    wave_speeds: WaveSpeeds | None = None,
) -> MeterSet:
    """Place ``count`` meters on the junctions of ``network`` (or its INP file) by ``method``
    (module docstring); ``resolution`` (s) is the ``arrival`` and ``region`` methods' capture
    interval. On a network of more junctions than ``scaling.above`` those two methods run on
    a reduced problem (:mod:`burstloc.sim.placement.scaled`; the kept meters among its
    candidates). ``keep``: meters the network has already; each method's greedy starts from
    them and adds ``count`` more (the set returned holds both). ``wave_speeds``: pipes of their
    own wave speed, the others at ``wave_speed`` (module docstring); the set records them where
    they timed the paths (not for ``coverage``).

    Raises:
        NetworkError: missing or malformed network, or wave speeds of pipes it does not have.
        ConfigError: unknown method, ``count`` out of range, a kept meter that is not a
            junction.
    """
    from burstloc.sim.model.prepare import arrival_geometry
    from burstloc.sim.signatures.compute import cached_signatures

    if method not in PLACEMENT_METHODS:
        raise ConfigError(f"unknown placement method {method!r}; use one of {PLACEMENT_METHODS}")
    read = as_network(network)
    wn = read.model
    junctions = list(read.junctions)
    keep = tuple(keep)
    kept_indices(keep, junctions)
    check_meter_count(count, len(junctions) - len(keep))
    stretch = stretch_of(wave_speeds, wn, wave_speed)
    if method == "coverage":
        meters = coverage_meters(cached_signatures(read, junctions), count, keep)
    elif scaling.applies(len(junctions)):
        problem = reduced_problem(wn, count, scaling, keep, stretch)
        if method == "arrival":
            meters = arrival_meters(
                problem.arrival_pipes,
                problem.candidates,
                problem.distances,
                count,
                wave_speed=wave_speed,
                resolution=resolution,
                keep=keep,
            )
        else:
            meters = region_meters(
                problem.pipes,
                problem.candidates,
                problem.distances,
                count,
                wave_speed=wave_speed,
                resolution=resolution,
                points=scaling.points,
                seed=scaling.seed,
                keep=keep,
            )
    else:
        pipes, distances = arrival_geometry(wn, junctions, stretch)
        place: Callable[..., tuple[str, ...]] = arrival_meters
        if method == "region":
            place = region_meters
        meters = place(
            pipes,
            junctions,
            distances,
            count,
            wave_speed=wave_speed,
            resolution=resolution,
            keep=keep,
        )
    order = {name: i for i, name in enumerate(junctions)}
    meters = tuple(sorted(meters, key=order.__getitem__))  # the network's order
    timed = (wave_speeds or None) if method != "coverage" else None  # steady states: untimed
    return MeterSet(read.path, read.hash, method, meters, len(junctions), timed)


def meter_separation(
    network: NetworkSource,
    meters: Sequence[str],
    *,
    wave_speeds: WaveSpeeds | None = None,
    **timing: float,
) -> float:
    """:func:`arrival_separation` of ``meters`` on ``network`` (:func:`meter_scores`' first,
    alone; ``timing``: ``wave_speed``, ``resolution``)."""
    scores = ("separation",)
    return meter_scores(network, meters, scores=scores, wave_speeds=wave_speeds, **timing)[0]


def meter_ambiguity(
    network: NetworkSource,
    meters: Sequence[str],
    *,
    wave_speeds: WaveSpeeds | None = None,
    **timing: float,
) -> float:
    """:func:`~burstloc.sim.placement.region.ambiguous_length` of ``meters`` on ``network`` (m;
    :func:`meter_scores`' second, alone; ``timing``: ``wave_speed``, ``resolution``)."""
    scores = ("ambiguity",)
    return meter_scores(network, meters, scores=scores, wave_speeds=wave_speeds, **timing)[0]


def meter_scores(
    network: NetworkSource,
    meters: Sequence[str],
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    scores: Sequence[str] = ("separation", "ambiguity"),
    wave_speeds: WaveSpeeds | None = None,
) -> tuple[float, ...]:
    """The ``scores`` of ``meters`` on ``network`` from one arrival geometry (what ``burstloc
    place`` prints): ``"separation"``, :func:`arrival_separation`; ``"ambiguity"``,
    :func:`~burstloc.sim.placement.region.ambiguous_length` (m). ``wave_speeds``: pipes of
    their own wave speed (module docstring).

    Raises:
        NetworkError: missing or malformed network, a meter that is not a junction, or wave
            speeds of pipes it does not have.
        ConfigError: no meter, a bad wave speed or resolution, an unknown score.
    """
    unknown = [s for s in scores if s not in ("separation", "ambiguity")]
    if unknown:
        raise ConfigError(f"unknown meter score(s) {unknown}: use 'separation', 'ambiguity'")
    pipes, distances = meter_geometry(network, meters, wave_speed, wave_speeds)
    return tuple(
        arrival_separation(pipes, distances, wave_speed=wave_speed, resolution=resolution)
        if score == "separation"
        else ambiguous_length(
            pipes, tuple(meters), distances, wave_speed=wave_speed, resolution=resolution
        )
        for score in scores
    )


@dataclass(frozen=True)
class MeterScores:
    """How far a meter set narrows a burst down from arrival times alone, on the measure the
    ``region`` method minimises (:func:`score_meters`; ``burstloc place`` prints it).

    Attributes:
        meters: the meters scored.
        resolution: the capture interval (s) the scores are for.
        ambiguity: per burst point, the metres of main a search region cannot rule out from
            the arrivals (:class:`~burstloc.sim.placement.region.AmbiguityProfile`).
        without: with ``each``, the expected ambiguous main (m) without each meter in turn,
            in ``meters`` order (empty otherwise).
    """

    meters: tuple[str, ...]
    resolution: float
    ambiguity: AmbiguityProfile
    without: tuple[float, ...] = ()

    @property
    def ambiguous(self) -> float:
        """The expected ambiguous main (m): what the ``region`` method minimises."""
        return self.ambiguity.mean

    @property
    def searchable(self) -> float:
        """The share of bursts whose ambiguous main is at most
        :data:`~burstloc.constants.SEARCHABLE` m (a search a crew is sent on)."""
        return self.ambiguity.share_within(SEARCHABLE)

    def contributions(self) -> list[tuple[str, float]]:
        """Per meter, the metres of expected ambiguous main it alone rules out (how much
        longer the search would be without it), least first (ties: the network's order)."""
        gains = [(m, w - self.ambiguous) for m, w in zip(self.meters, self.without, strict=True)]
        return sorted(gains, key=lambda item: item[1])


def score_meters(
    network: NetworkSource,
    meters: Sequence[str],
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    each: bool = False,
    wave_speeds: WaveSpeeds | None = None,
) -> MeterScores:
    """:class:`MeterScores` of ``meters`` on ``network``; with ``each`` also
    every meter's contribution (the set scored without it). ``wave_speeds``: pipes of their own
    wave speed (module docstring): the travel times, not the metres of main, change.

    Raises:
        NetworkError: missing or malformed network, a meter that is not a junction, or wave
            speeds of pipes it does not have.
        ConfigError: no meter, a bad wave speed or resolution.
    """
    pipes, distances = meter_geometry(network, meters, wave_speed, wave_speeds)
    whole, without = ambiguity_profile(
        pipes,
        tuple(meters),
        distances,
        wave_speed=wave_speed,
        resolution=resolution,
        leave_out=each,
    )
    return MeterScores(tuple(meters), resolution, whole, tuple(p.mean for p in without))
