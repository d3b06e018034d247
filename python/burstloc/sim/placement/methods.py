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

:func:`place_meters` runs either on a network file and returns a :class:`MeterSet`, which saves
as the documented JSON meter file (:data:`METERS_FORMAT`, read by ``burstloc evaluate``,
``calibrate``, ``simulate`` and ``study`` with ``--meters-file`` or ``--meters FILE``)::

    {
      "format": "burstloc-meters/1",
      "network": "networks/paper15.inp",      # informative
      "network_hash": "sha256:...",           # the INP file's SHA-256: checked on use
      "method": "arrival",                    # "coverage", "arrival", "region" or "manual"
      "meters": ["2", "7", "11", "14"],       # junction IDs
      "junctions": 15                         # junctions the network has
    }

``method`` says how the meters were chosen: by one of :data:`PLACEMENT_METHODS`, or ``"manual"``
for a set written by hand (a utility's own meters). A hand-made set needs no JSON at all:
wherever a command takes ``--meters IDS|FILE`` (and ``place --keep`` / ``--score``) it takes the
IDs themselves (``--meters n1,n4,n31``) or a text file of them (:func:`meter_list`)::

    # BattLeDIM's pressure sensors on L-TOWN
    n1, n4, n31
    n54 n105   # any mix of commas, spaces and lines
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from burstloc._atomic import write_json
from burstloc._validate import (
    Fields,
    attributes,
    check_count,
    check_names,
    check_string,
    read_json,
    some_names,
)
from burstloc.constants import SEARCHABLE, WAVE_SPEED
from burstloc.exceptions import ConfigError
from burstloc.network import NetworkSource, as_network, identify
from burstloc.sim.placement._checks import check_meter_count, kept_indices, meter_geometry
from burstloc.sim.placement.arrival import ARRIVAL_POINTS, arrival_meters, arrival_separation
from burstloc.sim.placement.region import (
    AmbiguityProfile,
    ambiguity_profile,
    ambiguous_length,
    region_meters,
)
from burstloc.sim.placement.scaled import DEFAULT_SCALING, Scaling, reduced_problem

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

METERS_FORMAT = "burstloc-meters/1"
"""Format tag of a meter file."""

PLACEMENT_METHODS: tuple[str, ...] = ("coverage", "arrival", "region")
"""The placement methods of :func:`place_meters`."""

#: Limit on the meters of a meter file (the localization model's).
MAX_METERS = 10_000

#: Limit on the junctions of the network a meter file is for (BWSN_Network_2 has 12 523).
MAX_JUNCTIONS = 1_000_000


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


@dataclass(frozen=True)
class MeterSet:
    """Meters chosen for one network: the junction IDs, how they were chosen, and the network's
    fingerprint (:data:`METERS_FORMAT`).

    Raises:
        ConfigError: a bad field (named).
    """

    network: str
    network_hash: str
    method: str
    meters: tuple[str, ...]
    junctions: int

    def __post_init__(self) -> None:
        check_string(self.network, "network")
        check_string(self.network_hash, "network_hash", max_length=128)
        if self.method not in (*PLACEMENT_METHODS, "manual"):
            raise ConfigError(
                f"method must be one of {[*PLACEMENT_METHODS, 'manual']}, got {self.method!r}"
            )
        object.__setattr__(self, "meters", check_names(self.meters, "meters", high=MAX_METERS))
        check_count(self.junctions, "junctions", high=MAX_JUNCTIONS)

    def check(self, network: NetworkSource) -> tuple[str, ...]:
        """The meters, once the file is known to be for ``network`` (ConfigError otherwise)."""
        where, found = identify(network)
        if found != self.network_hash:
            raise ConfigError(
                f"the meter file was made for network {self.network} ({self.network_hash}), "
                f"not for {where} ({found}); run `burstloc place` for it"
            )
        return self.meters

    def to_json(self) -> dict[str, Any]:
        """The meter file's document."""
        return {
            "format": METERS_FORMAT,
            **attributes(self, "network", "network_hash", "method"),
            "meters": list(self.meters),
            "junctions": self.junctions,
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the meter file (atomically)."""
        return write_json(path, self.to_json())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> MeterSet:
        """Read a meter file; every field is checked (ConfigError naming the file and field)."""
        source = f"meter file {os.fspath(path)}"
        fields = Fields(read_json(path, "meter file"), source)
        if fields.data.get("format") != METERS_FORMAT:
            raise ConfigError(
                f"{source}: not a burstloc meter file (format {fields.data.get('format')!r}, "
                f"want {METERS_FORMAT!r}); write one with `burstloc place`"
            )
        return fields.build(cls, ("network", "network_hash", "method", "meters", "junctions"))


def place_meters(
    network: NetworkSource,
    count: int,
    *,
    method: str = "arrival",
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    scaling: Scaling = DEFAULT_SCALING,
    keep: Sequence[str] = (),
) -> MeterSet:
    """Place ``count`` meters on the junctions of ``network`` (or its INP file) by ``method``
    (module docstring); ``resolution`` (s) is the ``arrival`` and ``region`` methods' capture
    interval. On a network of more junctions than ``scaling.above`` those two methods run on
    a reduced problem (:mod:`burstloc.sim.placement.scaled`; the kept meters among its
    candidates). ``keep``: meters the network has already; each method's greedy starts from
    them and adds ``count`` more (the set returned holds both).

    Raises:
        NetworkError: missing or malformed network.
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
    if method == "coverage":
        meters = coverage_meters(cached_signatures(read, junctions), count, keep)
    elif scaling.applies(len(junctions)):
        problem = reduced_problem(wn, count, scaling, keep)
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
        pipes, distances = arrival_geometry(wn, junctions)
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
    return MeterSet(read.path, read.hash, method, meters, len(junctions))


def meter_separation(network: NetworkSource, meters: Sequence[str], **timing: float) -> float:
    """:func:`arrival_separation` of ``meters`` on ``network`` (:func:`meter_scores`' first,
    alone; ``timing``: ``wave_speed``, ``resolution``)."""
    return meter_scores(network, meters, scores=("separation",), **timing)[0]


def meter_ambiguity(network: NetworkSource, meters: Sequence[str], **timing: float) -> float:
    """:func:`~burstloc.sim.placement.region.ambiguous_length` of ``meters`` on ``network`` (m;
    :func:`meter_scores`' second, alone; ``timing``: ``wave_speed``, ``resolution``)."""
    return meter_scores(network, meters, scores=("ambiguity",), **timing)[0]


def meter_scores(
    network: NetworkSource,
    meters: Sequence[str],
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    scores: Sequence[str] = ("separation", "ambiguity"),
) -> tuple[float, ...]:
    """The ``scores`` of ``meters`` on ``network`` from one arrival geometry (what ``burstloc
    place`` prints): ``"separation"``, :func:`arrival_separation`; ``"ambiguity"``,
    :func:`~burstloc.sim.placement.region.ambiguous_length` (m).

    Raises:
        NetworkError: missing or malformed network, or a meter that is not a junction.
        ConfigError: no meter, a bad wave speed or resolution, an unknown score.
    """
    unknown = [s for s in scores if s not in ("separation", "ambiguity")]
    if unknown:
        raise ConfigError(f"unknown meter score(s) {unknown}: use 'separation', 'ambiguity'")
    pipes, distances = meter_geometry(network, meters)
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
) -> MeterScores:
    """:class:`MeterScores` of ``meters`` on ``network``; with ``each`` also
    every meter's contribution (the set scored without it).

    Raises:
        NetworkError: missing or malformed network, or a meter that is not a junction.
        ConfigError: no meter, a bad wave speed or resolution.
    """
    pipes, distances = meter_geometry(network, meters)
    whole, without = ambiguity_profile(
        pipes,
        tuple(meters),
        distances,
        wave_speed=wave_speed,
        resolution=resolution,
        leave_out=each,
    )
    return MeterScores(tuple(meters), resolution, whole, tuple(p.mean for p in without))


def meter_list(values: Sequence[str], network: NetworkSource) -> tuple[str, ...]:
    """The meters ``values`` name on ``network``, in the order given.

    ``values`` are junction IDs (each may hold several, separated by commas), or one file: a
    meter file (:data:`METERS_FORMAT`, refused if made for another network) or a text file of
    junction IDs separated by spaces, commas or new lines (``#`` starts a comment). What a
    utility's list of its own meters looks like, e.g. ``n1,n4,n31`` or ``owned.txt``.

    Raises:
        ConfigError: no ID, an ID that is not a junction of ``network`` (the first
            :data:`~burstloc._validate.LISTED` named, the rest counted) or listed twice, an
            unreadable or malformed file.
        NetworkError: missing or malformed network.
    """
    from burstloc.inp import check_meters

    read = as_network(network)
    if len(values) == 1 and os.path.isfile(values[0]):
        names = _meters_in_file(values[0], read)
        source = f"meter list {values[0]}"
    else:
        names = [n for value in values for n in value.split(",") if n]
        source = "the meter list"
    if not names:
        raise ConfigError(f"{source} names no meter")
    check_meters(names, read.junctions, read.path, ConfigError)
    twice = sorted(n for n, c in Counter(names).items() if c > 1)
    if twice:
        raise ConfigError(f"{source} lists {some_names(twice)} more than once")
    return tuple(names)


def _meters_in_file(path: str, network: NetworkSource) -> list[str]:
    """The junction IDs of a meter file or of a text file of IDs (:func:`meter_list`)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read meter list {path}: {exc}") from None
    if text.lstrip().startswith("{"):
        return list(MeterSet.load(path).check(network))
    words = (line.split("#", 1)[0].replace(",", " ").split() for line in text.splitlines())
    return [w for line in words for w in line]
