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

How far a set of meters can go on arrivals alone: :func:`arrival_separation` (and
:func:`meter_separation` on a network file, printed by ``burstloc place``) is the share of the
candidate burst points whose arrival pattern at the meters is at least one capture interval from
every point of every other pipe (4 of paper15's 15 junctions, N4 N7 1 8: 63 %; all 15: 82 %; 2 of
Net1's 9, 13 31: 17 %).

:func:`place_meters` runs either on a network file and returns a :class:`MeterSet`, which saves
as the documented JSON meter file (:data:`METERS_FORMAT`, read by ``burstloc evaluate``,
``calibrate`` and ``study`` with ``--meters-file``)::

    {
      "format": "burstloc-meters/1",
      "network": "networks/paper15.inp",      # informative
      "network_hash": "sha256:...",           # the INP file's SHA-256: checked on use
      "method": "arrival",                    # or "coverage", "region", "manual"
      "meters": ["2", "7", "11", "14"],       # junction IDs, in the network's order
      "junctions": 15                         # junctions the network has
    }
"""

from __future__ import annotations

import os
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
)
from burstloc.constants import WAVE_SPEED
from burstloc.exceptions import ConfigError
from burstloc.network import NetworkSource, as_network, identify
from burstloc.sim.placement._checks import check_meter_count, meter_geometry
from burstloc.sim.placement.arrival import ARRIVAL_POINTS, arrival_meters, arrival_separation
from burstloc.sim.placement.region import ambiguous_length, region_meters
from burstloc.sim.placement.scaled import DEFAULT_SCALING, Scaling, reduced_problem

__all__ = [
    "ARRIVAL_POINTS",
    "METERS_FORMAT",
    "PLACEMENT_METHODS",
    "MeterSet",
    "arrival_meters",
    "arrival_separation",
    "coverage_meters",
    "meter_ambiguity",
    "meter_scores",
    "meter_separation",
    "place_meters",
]

METERS_FORMAT = "burstloc-meters/1"
"""Format tag of a meter file."""

PLACEMENT_METHODS: tuple[str, ...] = ("coverage", "arrival", "region")
"""The placement methods of :func:`place_meters`."""

#: Limit on the meters of a meter file (the localization model's).
MAX_METERS = 10_000

#: Limit on the junctions of the network a meter file is for (BWSN_Network_2 has 12 523).
MAX_JUNCTIONS = 1_000_000


def coverage_meters(signatures: Any, count: int) -> tuple[str, ...]:
    """Choose ``count`` meters by greedy coverage of burst signatures (module docstring).

    Args:
        signatures: a :class:`burstloc.localize.signature.SignatureSet` over the candidate
            junctions.
        count: how many meters, 1..number of candidates.

    Returns:
        The chosen junctions, in the signature set's meter order.

    Raises:
        ConfigError: ``count`` out of range.
    """
    meters = list(signatures.meters)
    check_meter_count(count, len(meters))
    matrix = np.abs(np.asarray(signatures.matrix, dtype=np.float64))
    strength = matrix.sum(axis=0)
    chosen: list[int] = []
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
) -> MeterSet:
    """Place ``count`` meters on the junctions of ``network`` (or its INP file) by ``method``
    (module docstring); ``resolution`` (s) is the ``arrival`` and ``region`` methods' capture
    interval. On a network of more junctions than ``scaling.above`` those two methods run on
    a reduced problem (:mod:`burstloc.sim.placement.scaled`).

    Raises:
        NetworkError: missing or malformed network.
        ConfigError: unknown method, ``count`` out of range.
    """
    from burstloc.sim.model.prepare import arrival_geometry
    from burstloc.sim.signatures.compute import cached_signatures

    if method not in PLACEMENT_METHODS:
        raise ConfigError(f"unknown placement method {method!r}; use one of {PLACEMENT_METHODS}")
    read = as_network(network)
    wn = read.model
    junctions = list(read.junctions)
    check_meter_count(count, len(junctions))
    if method == "coverage":
        meters = coverage_meters(cached_signatures(read, junctions), count)
    elif scaling.applies(len(junctions)):
        problem = reduced_problem(wn, count, scaling)
        if method == "arrival":
            meters = arrival_meters(
                problem.arrival_pipes,
                problem.candidates,
                problem.distances,
                count,
                wave_speed=wave_speed,
                resolution=resolution,
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
            )
    else:
        pipes, distances = arrival_geometry(wn, junctions)
        place: Callable[..., tuple[str, ...]] = arrival_meters
        if method == "region":
            place = region_meters
        meters = place(
            pipes, junctions, distances, count, wave_speed=wave_speed, resolution=resolution
        )
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
