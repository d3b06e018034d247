"""Meter placement for search regions: the meters that leave the least main to search.

The search region (:mod:`burstloc.localize.region`) holds every point whose arrival pattern
explains the alarms; with the burst time unknown, a point ``q`` explains a burst at ``b`` as
well as ``b`` itself when the meters ``S`` cannot tell their arrival times apart. With
``delta_j = (d(q, j) - d(b, j)) / a`` (path lengths along the pipes over the wave speed ``a``)
for each meter ``j``, the *spread* ``max_j delta_j - min_j delta_j`` is what a free burst time
cannot absorb; ``q`` looks like ``b`` when it is below the capture interval ``resolution``.

The ``region`` method (:func:`region_meters`) minimises the *expected ambiguous main*
(:func:`ambiguous_length`): the mean over burst points ``b`` of the metres of main ``q`` with
``spread(b, q) < resolution``, a proxy of the expected length of the search region from the
arrivals alone (the lasting drop, which narrows it further, is left out). Points are the
middles of the :class:`~burstloc.localize.region.RegionGrid` segments at :data:`REGION_STEP`
metres (the posterior's own step), each weighing its length; bursts are all of
them, weighted by length, or on a larger network :data:`BURST_SAMPLES` of them drawn with
probability proportional to length (seeded: :data:`SAMPLE_SEED`, so the placement is
deterministic).

Greedy: the first meter is the junction whose travel times to the points spread most (a
peripheral one, as the ``arrival`` method starts: one meter separates nothing, the burst time is
free); then, one at a time, the junction that separates the most ambiguous main (weighted pairs
``(b, q)`` whose spread it lifts to ``resolution`` or more). A pair once separated stays so
(more meters only widen the spread), so each step keeps only the pairs still alike with their
running max and min of ``delta``: a candidate is one vectorized pass over those pairs, and all
candidates are evaluated exactly at every step (no bound needed: after the second meter few
pairs are left; ties: the larger spread of travel times, then the first junction). The
objective is not submodular (a meter can separate a pair only together with a later one), so
the greedy is followed by up to :data:`SWAP_PASSES` passes of swaps: each meter in turn is
replaced by the junction that separates the most given the others, when that beats it (the
first meter, chosen before the objective meant anything, most often). The result is never
worse than the greedy's.

Cost: L-TOWN (782 junctions, 905 pipes, 43 km of main; 2 148 points, 1 000 sampled bursts),
33 meters: 12-15 s of CPU (``benches/bench_region_placement.py``), most of it the second
meter's step, when every pair is still alike (1.7 million pairs x 781 candidates, in single
precision).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import WAVE_SPEED
from burstloc.exceptions import ConfigError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.pipes import PipeGeometry
from burstloc.localize.region import GRID_STEP, RegionGrid
from burstloc.sim.placement._checks import (
    check_meter_count,
    check_timing,
    kept_indices,
)

__all__ = [
    "BURST_SAMPLES",
    "REGION_STEP",
    "SAMPLE_SEED",
    "SWAP_PASSES",
    "AmbiguityGrid",
    "AmbiguityProfile",
    "ambiguity_grid",
    "ambiguity_profile",
    "ambiguous_length",
    "region_meters",
]

REGION_STEP = GRID_STEP
"""Longest segment (m) of the placement's points: the posterior's
(:data:`burstloc.localize.region.GRID_STEP`)."""

BURST_SAMPLES = 1000
"""Most burst points the objective averages over: a grid with at most this many points bursts
at every point, a larger one at a sample of this many."""

SAMPLE_SEED = 0
"""Seed of the burst sample."""

SWAP_PASSES = 2
"""Passes of single-meter swaps after the greedy (module docstring)."""

_TIE = 1e-6
"""Gains within this share of each other tie (single-precision sums)."""

_BLOCK = 2_000_000
"""Elements per vectorized pass (bounds the memory of a step)."""

_PAIRS = 4_000_000
"""Most (burst, point) pairs :func:`ambiguous_length` holds at once: a larger grid (a large
network's) is summed over blocks of bursts."""


@dataclass(frozen=True)
class AmbiguityGrid:
    """The placement's points and bursts: ``length[i]`` (m) of point ``i``'s segment,
    ``travel[i, j]`` (s, single precision: microseconds against a capture interval of
    tenths of a second) from point ``i`` to junction ``j``, the burst points ``bursts`` (indices
    of points) and their weights ``weight`` (summing to 1)."""

    length: NDArray[np.float64]
    travel: NDArray[np.float32]
    bursts: NDArray[np.int64]
    weight: NDArray[np.float64]


def ambiguity_grid(
    pipes: Sequence[PipeGeometry],
    junctions: Sequence[str],
    node_distances: dict[str, NDArray[np.float64]],
    *,
    wave_speed: float = WAVE_SPEED,
    step: float = REGION_STEP,
    samples: int = BURST_SAMPLES,
    seed: int = SAMPLE_SEED,
    points: int | None = None,
) -> AmbiguityGrid:
    """The points and bursts of the objective (module docstring) for ``junctions``;
    ``node_distances[n][j]`` is the path length (m) from pipe end node ``n`` to
    ``junctions[j]`` (:func:`burstloc.sim.model.prepare.arrival_geometry`; with its ``stretch``,
    metres of wave travel at ``wave_speed``, and ``pipes`` crossed in their travel, as the
    localizer's grid is: a point's ``length`` stays metres of main). An unreachable junction
    is ten times the longest reachable travel away (heard by no burst, alike for all).

    ``points``: at most this many points (default: every segment). A grid with more is
    replaced by a sample of ``points`` segments drawn with probability proportional to length
    (seeded by ``seed``; a segment drawn ``c`` times weighs ``c`` times the mean length of
    main per draw, so the ambiguous main keeps its scale); the bursts are then drawn from
    those (the scaled placement of large networks, :mod:`burstloc.sim.placement.scaled`).

    Raises:
        ConfigError: no pipe, a bad wave speed, step, sample or point count.
    """
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ConfigError(f"the burst sample count must be an integer >= 1, got {samples!r}")
    if points is not None and (
        isinstance(points, bool) or not isinstance(points, int) or points < 1
    ):
        raise ConfigError(f"the point count must be an integer >= 1, got {points!r}")
    localizer = ArrivalLocalizer(
        pipes, junctions, node_distances, wave_speed=wave_speed, positions=(0.5,)
    )
    grid = RegionGrid(localizer, step)
    travel = grid.dist / wave_speed
    finite = np.isfinite(travel)
    far = 10 * float(travel[finite].max()) if finite.any() else 1.0
    travel = np.where(finite, travel, far).astype(np.float32)
    length = np.asarray(grid.length, dtype=np.float64)
    if points is not None and length.size > points:
        share = length / length.sum()
        drawn = np.random.default_rng(seed).choice(length.size, size=points, p=share)
        kept, counts = np.unique(drawn, return_counts=True)
        travel, length = travel[kept], counts * (float(length.sum()) / points)
        seed += 1  # the bursts: another draw
    share = length / length.sum()
    if length.size <= samples:
        bursts, weight = np.arange(length.size, dtype=np.int64), share
    else:
        drawn = np.random.default_rng(seed).choice(length.size, size=samples, p=share)
        bursts, counts = np.unique(drawn, return_counts=True)
        weight = counts / samples
    return AmbiguityGrid(length, travel, bursts.astype(np.int64), weight.astype(np.float64))


class _Pairs:
    """The (burst, point) pairs still alike to the chosen meters: indices ``b`` and ``q`` into
    the points, weight ``w`` (burst weight x point length, m), running ``hi`` and ``lo`` of
    ``delta`` over the chosen meters."""

    def __init__(self, grid: AmbiguityGrid, chosen: Sequence[int], resolution: float) -> None:
        n = grid.length.size
        self.b = np.repeat(grid.bursts, n)
        self.q = np.tile(np.arange(n, dtype=np.int64), grid.bursts.size)
        self.w = np.repeat(grid.weight, n) * grid.length[self.q]
        self.hi = np.full(self.b.size, -np.inf, dtype=np.float32)
        self.lo = np.full(self.b.size, np.inf, dtype=np.float32)
        self.resolution = np.float32(resolution)
        for j in chosen:
            self.add(grid.travel, j)

    def add(self, travel: NDArray[np.float32], j: int) -> None:
        """Add meter ``j``; drop the pairs it separates."""
        delta = travel[self.q, j] - travel[self.b, j]
        self.hi = np.maximum(self.hi, delta)
        self.lo = np.minimum(self.lo, delta)
        keep = self.hi - self.lo < self.resolution
        self.b, self.q, self.w = self.b[keep], self.q[keep], self.w[keep]
        self.hi, self.lo = self.hi[keep], self.lo[keep]

    def ambiguous(self) -> float:
        """The expected ambiguous main (m): the weight of the pairs still alike."""
        return float(self.w.sum())

    def separated(self, travel: NDArray[np.float32], candidates: NDArray[np.int64]) -> NDArray:
        """Per candidate junction, the weight (m) of the pairs it would separate (summed in
        single precision within a block of pairs: four times faster; the ties of
        :func:`_best` absorb the rounding)."""
        out = np.zeros(candidates.size)
        if self.b.size == 0 or candidates.size == 0:
            return out
        columns = travel[:, candidates]
        rows = max(1, _BLOCK // candidates.size)
        for lo in range(0, self.b.size, rows):
            part = slice(lo, lo + rows)
            delta = columns[self.q[part]] - columns[self.b[part]]
            spread = np.maximum(delta, self.hi[part, None]) - np.minimum(delta, self.lo[part, None])
            weight = self.w[part].astype(np.float32)
            out += weight @ (spread >= self.resolution).astype(np.float32)
        return out


def _best(gain: NDArray[np.float64], spread_of: NDArray[np.float64], candidates: NDArray) -> int:
    """The candidate of the largest gain; gains within rounding of it tie, and ties go to the
    larger spread of travel times, then the first junction."""
    top = float(gain.max())
    tied = candidates[gain >= top - _TIE * max(abs(top), 1.0)]
    return int(max(tied.tolist(), key=lambda j: (spread_of[j], -j)))


def _swap_pass(
    grid: AmbiguityGrid,
    chosen: list[int],
    spread_of: NDArray[np.float64],
    resolution: float,
    fixed: int = 0,
) -> bool:
    """Each meter of ``chosen`` in turn (in the order chosen; the first ``fixed``, meters kept
    by the caller, never) replaced by the junction that separates the most given the others,
    if it beats the meter by more than rounding; whether any was replaced. ``chosen`` is
    changed in place."""
    everyone = np.arange(grid.travel.shape[1], dtype=np.int64)
    changed = False
    for i in range(fixed, len(chosen)):
        others = chosen[:i] + chosen[i + 1 :]
        candidates = np.setdiff1d(everyone, others)
        gain = _Pairs(grid, others, resolution).separated(grid.travel, candidates)
        kept = float(gain[candidates == chosen[i]][0])
        if float(gain.max()) > kept + _TIE * max(abs(kept), 1.0):
            chosen[i] = _best(gain, spread_of, candidates)
            changed = True
    return changed


def region_meters(
    pipes: Sequence[PipeGeometry],
    junctions: Sequence[str],
    node_distances: dict[str, NDArray[np.float64]],
    count: int,
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    step: float = REGION_STEP,
    samples: int = BURST_SAMPLES,
    points: int | None = None,
    seed: int = SAMPLE_SEED,
    keep: Sequence[str] = (),
) -> tuple[str, ...]:
    """Choose ``count`` of ``junctions`` that minimise the expected ambiguous main (module
    docstring); ``node_distances``, ``points`` and ``seed`` as for :func:`ambiguity_grid`.

    ``keep``: meters the network has already (junctions of ``junctions``): the greedy starts
    from them and adds ``count`` more; the swaps move the added meters only.

    Returns:
        The chosen junctions, kept ones included, in ``junctions`` order.

    Raises:
        ConfigError: ``count`` out of range, a kept meter not among ``junctions``, or a bad
            wave speed, resolution, step, sample or point count.
    """
    kept = kept_indices(keep, junctions)
    check_meter_count(count, len(junctions) - len(kept))
    check_timing(wave_speed, resolution)
    grid = ambiguity_grid(
        pipes,
        junctions,
        node_distances,
        wave_speed=wave_speed,
        step=step,
        samples=samples,
        seed=seed,
        points=points,
    )
    travel = grid.travel
    mean = grid.length @ travel / grid.length.sum()
    spread_of = np.sqrt(grid.length @ (travel - mean) ** 2 / grid.length.sum())
    # peripheral: one meter separates nothing alone
    chosen = list(kept) or [int(np.argmax(spread_of))]
    pairs = _Pairs(grid, chosen, resolution)
    everyone = np.arange(travel.shape[1], dtype=np.int64)
    while len(chosen) < count + len(kept):
        candidates = np.setdiff1d(everyone, chosen)
        j = _best(pairs.separated(travel, candidates), spread_of, candidates)
        chosen.append(j)
        pairs.add(travel, j)
    for _ in range(SWAP_PASSES):
        if not _swap_pass(grid, chosen, spread_of, resolution, fixed=len(kept)):
            break
    return tuple(junctions[j] for j in sorted(chosen))


def ambiguous_length(
    pipes: Sequence[PipeGeometry],
    meters: Sequence[str],
    node_distances: dict[str, NDArray[np.float64]],
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    step: float = REGION_STEP,
    samples: int = BURST_SAMPLES,
    seed: int = SAMPLE_SEED,
) -> float:
    """The expected ambiguous main (m) of ``meters`` (module docstring): the objective the
    ``region`` method minimises, on the same points and bursts (``seed``: another sample of
    them, on a network with more than ``samples`` points). ``node_distances[n][j]`` is the path
    length from pipe end node ``n`` to ``meters[j]``.

    Raises:
        ConfigError: no meter, or a bad wave speed, resolution, step or sample count.
    """
    if not meters:
        raise ConfigError("no meters to separate bursts with")
    check_timing(wave_speed, resolution)
    grid = ambiguity_grid(
        pipes, meters, node_distances, wave_speed=wave_speed, step=step, samples=samples, seed=seed
    )
    bursts = max(1, _PAIRS // grid.length.size)  # per block: bounded memory
    if grid.bursts.size <= bursts:
        return _Pairs(grid, range(len(meters)), resolution).ambiguous()
    total = 0.0
    for lo in range(0, grid.bursts.size, bursts):
        part = slice(lo, lo + bursts)
        block = replace(grid, bursts=grid.bursts[part], weight=grid.weight[part])
        total += _Pairs(block, range(len(meters)), resolution).ambiguous()
    return total


@dataclass(frozen=True)
class AmbiguityProfile:
    """A meter set's ambiguous main burst by burst (:func:`ambiguity_profile`): ``length[i]``
    (m) of main whose arrival pattern is within a capture interval of burst point ``i``'s
    (its own segment included), ``weight[i]`` the burst point's weight (summing to 1)."""

    length: NDArray[np.float64]
    weight: NDArray[np.float64]

    @property
    def mean(self) -> float:
        """The expected ambiguous main (m): :func:`ambiguous_length`."""
        return float(self.weight @ self.length)

    @property
    def median(self) -> float:
        """The weighted median of the bursts' ambiguous main (m)."""
        order = np.argsort(self.length, kind="stable")
        cumulative = np.cumsum(self.weight[order])
        return float(self.length[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])

    def share_within(self, limit: float) -> float:
        """The weighted share of bursts whose ambiguous main is at most ``limit`` m."""
        return float(self.weight[self.length <= limit].sum())


def _profile(grid: AmbiguityGrid, columns: Sequence[int], resolution: float) -> NDArray:
    """Per burst of ``grid``, the metres of main still alike to the meters ``columns`` (columns
    of ``grid.travel``), summed over blocks of bursts (bounded memory)."""
    out = np.zeros(grid.bursts.size)
    bursts = max(1, _PAIRS // grid.length.size)
    for lo in range(0, grid.bursts.size, bursts):
        part = slice(lo, lo + bursts)
        block = replace(grid, bursts=grid.bursts[part], weight=grid.weight[part])
        pairs = _Pairs(block, columns, resolution)
        where = np.searchsorted(block.bursts, pairs.b)  # bursts are sorted, unique
        out[part] = np.bincount(where, grid.length[pairs.q], minlength=block.bursts.size)
    return out


def ambiguity_profile(
    pipes: Sequence[PipeGeometry],
    meters: Sequence[str],
    node_distances: dict[str, NDArray[np.float64]],
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    leave_out: bool = False,
) -> tuple[AmbiguityProfile, tuple[AmbiguityProfile, ...]]:
    """The ambiguous main of ``meters`` burst by burst, on the points and bursts of
    :func:`ambiguous_length` (its mean is that function's value), and with ``leave_out`` the
    same without each meter in turn (one profile per meter, in ``meters`` order; a meter whose
    absence leaves the mean unchanged adds nothing the others do not give).

    Raises:
        ConfigError: no meter, or a bad wave speed or resolution.
    """
    if not meters:
        raise ConfigError("no meters to separate bursts with")
    check_timing(wave_speed, resolution)
    grid = ambiguity_grid(pipes, meters, node_distances, wave_speed=wave_speed)
    weight = grid.weight
    every = list(range(len(meters)))
    whole = AmbiguityProfile(_profile(grid, every, resolution), weight)
    if not leave_out:
        return whole, ()
    without = tuple(
        AmbiguityProfile(_profile(grid, every[:i] + every[i + 1 :], resolution), weight)
        for i in every
    )
    return whole, without
