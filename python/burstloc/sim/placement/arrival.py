"""The ``arrival`` placement: meters that separate the wave arrival-time patterns of bursts.

A burst at a point ``x`` reaches meter ``j`` after ``d(x, j) / a`` (path length along the pipes
over the wave speed); the burst time is unknown, so two points look alike to the meters ``S``
when the differences of their travel times are nearly the same at every meter of ``S``: their
*separation* is the RMS of those differences about their mean. :func:`arrival_meters` is the
greedy placement (:mod:`burstloc.sim.placement.methods` describes it with the other methods);
:func:`arrival_separation` the share of candidate burst points the meters tell from every other
pipe's by a capture interval.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import CANDIDATE_POSITIONS, WAVE_SPEED
from burstloc.exceptions import ConfigError
from burstloc.localize.pipes import PipeGeometry
from burstloc.sim.placement._checks import check_meter_count, check_timing, kept_indices

__all__ = ["ARRIVAL_POINTS", "MAX_EXACT", "arrival_meters", "arrival_separation"]

ARRIVAL_POINTS: tuple[float, ...] = (0.1, 0.5, 0.9)
"""Candidate burst points along each pipe (fractions) the ``arrival`` method separates."""

MAX_EXACT = 48
"""At most this many junctions are evaluated exactly per step of the ``arrival`` greedy
(best bound first); below it, and on every network with no more junctions, the choice is the
exact greedy one (see :func:`arrival_meters`)."""


def arrival_meters(
    pipes: Sequence[PipeGeometry],
    junctions: Sequence[str],
    node_distances: dict[str, NDArray[np.float64]],
    count: int,
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
    keep: Sequence[str] = (),
) -> tuple[str, ...]:
    """Choose ``count`` of ``junctions`` by greedy separation of arrival patterns (module
    docstring).

    ``node_distances[n][j]`` is the path length (m) from pipe end node ``n`` to
    ``junctions[j]`` (:func:`burstloc.sim.model.prepare.arrival_geometry` over every junction;
    with its ``stretch``, metres of wave travel at ``wave_speed``, as ``pipes``' travel).
    ``keep``: meters the network has already (junctions of ``junctions``): the greedy starts
    from them and adds ``count`` more.

    Returns:
        The chosen junctions, kept ones included, in ``junctions`` order.

    Raises:
        ConfigError: ``count`` out of range, a kept meter not among ``junctions``, or a bad
            wave speed or resolution.
    """
    kept = kept_indices(keep, junctions)
    check_meter_count(count, len(junctions) - len(kept))
    check_timing(wave_speed, resolution)
    travel = _travel(pipes, node_distances, ARRIVAL_POINTS, wave_speed)
    spread_of = travel.std(axis=0)
    # peripheral: one meter separates nothing alone
    chosen = list(kept) or [int(np.argmax(spread_of))]
    count += len(kept)
    while len(chosen) < count:
        chosen.append(_next_arrival_meter(travel, len(pipes), chosen, spread_of, resolution))
    return tuple(junctions[j] for j in sorted(chosen))


def _next_arrival_meter(
    travel: NDArray[np.float64],
    n_pipes: int,
    chosen: list[int],
    spread_of: NDArray[np.float64],
    resolution: float,
) -> int:
    """The junction whose addition to ``chosen`` most increases the arrival objective (module
    docstring; ties: the larger spread of travel times, then the first junction).

    The objective is ``sum over pipe pairs of min(separation, resolution)``. Adding a meter to
    ``k`` shrinks a point pair's variance by at most ``k / (k + 1)``, so a pair whose centred
    arrival vectors at the chosen meters lie ``resolution * sqrt(k + 1)`` or more apart stays
    separated whatever is added: only the pairs nearer than that (a k-d tree query) are
    *active*, the others count ``resolution`` for every candidate. Every candidate then gets an
    upper bound of its objective (each active pipe pair's separation at its nearest point pair
    only: a minimum over fewer pairs is no smaller), all candidates at once; candidates are
    evaluated exactly, highest bound first, until no bound left can beat the best exact value
    (the exact greedy choice) or :data:`MAX_EXACT` have been evaluated (then the best of those).
    The exact value is summed over all pipe pairs in the order of a direct evaluation, so that
    junctions tying in exact arithmetic are told apart the same way.
    """
    from scipy.spatial import cKDTree

    n_points = travel.shape[0] // n_pipes
    k = len(chosen)
    sub = travel[:, chosen]
    if k == 1:  # one meter: every pair is alike (centred vectors are all zero)
        a, b = np.triu_indices(travel.shape[0], k=1)
    else:
        centred = sub - sub.mean(axis=1, keepdims=True)
        radius = resolution * math.sqrt(k + 1) * (1 + 1e-9)
        found = cKDTree(centred).query_pairs(radius, output_type="ndarray")
        a, b = np.sort(found, axis=1).T
    owner_a, owner_b = a // n_points, b // n_points
    keep = owner_a != owner_b
    a, b = a[keep], b[keep]
    key = owner_a[keep] * n_pipes + owner_b[keep]
    order = np.argsort(key, kind="stable")
    a, b, key = a[order], b[order], key[order]
    s1 = np.zeros(a.size)
    s2 = np.zeros(a.size)
    for m in chosen:  # sums in the order the meters were chosen
        diff = travel[a, m] - travel[b, m]
        s1 += diff
        s2 += diff**2
    # each active pipe pair's place in the row-major upper triangle of all pipe pairs
    p, q = key // n_pipes, key % n_pipes
    slot = p * n_pipes - p * (p + 1) // 2 + q - p - 1
    n_pairs = n_pipes * (n_pipes - 1) // 2

    def per_pair(j: int, rows: NDArray[np.int64] | slice) -> tuple[NDArray[np.int64], Any]:
        """The active pipe pairs' separations with junction ``j`` added (their slots, values)."""
        ra, rb, rk = a[rows], b[rows], key[rows]
        if ra.size == 0:
            return np.zeros(0, dtype=np.int64), np.zeros(0)
        diff = travel[ra, j] - travel[rb, j]
        kk = k + 1
        spread = np.sqrt(np.maximum((s2[rows] + diff**2) / kk - ((s1[rows] + diff) / kk) ** 2, 0.0))
        starts = np.flatnonzero(np.r_[True, rk[1:] != rk[:-1]])
        return slot[rows][starts], np.minimum.reduceat(spread, starts)

    def objective(j: int) -> float:
        """The objective, summed over every pipe pair in the same order as a direct evaluation
        (so that ties between junctions fall the same way)."""
        full = np.full(n_pairs, resolution)
        slots, values = per_pair(j, slice(None))
        full[slots] = np.minimum(values, resolution)
        return float(full.sum())

    candidates = np.array([j for j in range(travel.shape[1]) if j not in chosen], dtype=np.int64)
    bounds = _objective_bounds(travel, a, b, key, s1, s2, k, resolution, candidates, n_points)
    bounds += resolution * (n_pairs - np.unique(key).size)  # the pairs separated whatever
    ranked = sorted(zip(-bounds, -spread_of[candidates], candidates, strict=True))
    margin = 1e-9 * resolution * max(n_pairs, 1)  # far above the rounding of the sums
    best: tuple[float, float, int] | None = None
    for neg_bound, _, j in ranked[:MAX_EXACT]:
        if best is not None and -neg_bound + margin < best[0]:
            break  # no junction left can beat the best: the exact greedy choice
        exact = (objective(int(j)), float(spread_of[j]), -int(j))
        if best is None or exact > best:
            best = exact
    assert best is not None
    return -best[2]


def _objective_bounds(
    travel: NDArray[np.float64],
    a: NDArray[np.int64],
    b: NDArray[np.int64],
    key: NDArray[np.int64],
    s1: NDArray[np.float64],
    s2: NDArray[np.float64],
    k: int,
    resolution: float,
    candidates: NDArray[np.int64],
    n_points: int,
) -> NDArray[np.float64]:
    """Per candidate, an upper bound of the active pipe pairs' part of the objective: each pipe
    pair's separation taken at one point pair only (a minimum over fewer pairs is no smaller),
    the pair nearest with the chosen meters (the middle points' when all are alike), all
    candidates at once in blocks of pairs."""
    total = np.zeros(candidates.size)
    if a.size == 0:
        return total
    k1 = k + 1
    var = s2 / k - (s1 / k) ** 2
    centre = (a % n_points == n_points // 2) & (b % n_points == n_points // 2)
    order = np.lexsort((~centre, var, key))  # per pipe pair: nearest first, middle on ties
    first = order[np.r_[True, key[order][1:] != key[order][:-1]]]
    ra, rb, r1, r2 = a[first], b[first], s1[first], s2[first]
    block = max(1, 4_000_000 // max(1, candidates.size))
    for lo in range(0, ra.size, block):
        hi = lo + block
        diff = travel[np.ix_(ra[lo:hi], candidates)] - travel[np.ix_(rb[lo:hi], candidates)]
        spread = np.sqrt(
            np.maximum((r2[lo:hi, None] + diff**2) / k1 - ((r1[lo:hi, None] + diff) / k1) ** 2, 0.0)
        )
        total += np.minimum(spread, resolution).sum(axis=0)
    return total


def _travel(
    pipes: Sequence[PipeGeometry],
    node_distances: dict[str, NDArray[np.float64]],
    fractions: Sequence[float],
    wave_speed: float,
) -> NDArray[np.float64]:
    """Wave travel times (s) from points at ``fractions`` along every pipe to every junction of
    ``node_distances``, shape (pipes x points, junctions), pipe by pipe; an unreachable junction
    is ten times the longest reachable travel away (heard by no burst, alike for all). A pipe
    of its own wave speed is crossed in its travel (:attr:`PipeGeometry.travel`), as the paths
    of ``node_distances`` are."""
    frac = np.asarray(fractions, dtype=np.float64)
    length = np.array([p.travel for p in pipes])[:, None, None]
    d_start = np.array([node_distances[p.start] for p in pipes])[:, None, :]
    d_end = np.array([node_distances[p.end] for p in pipes])[:, None, :]
    along = frac[None, :, None] * length
    travel = np.minimum(along + d_start, length - along + d_end) / wave_speed
    travel = travel.reshape(len(pipes) * frac.size, -1)
    finite = np.isfinite(travel)
    far = 10 * float(travel[finite].max()) if finite.any() else 1.0
    return np.asarray(np.where(finite, travel, far), dtype=np.float64)


def arrival_separation(
    pipes: Sequence[PipeGeometry],
    node_distances: dict[str, NDArray[np.float64]],
    *,
    wave_speed: float = WAVE_SPEED,
    resolution: float = 0.2,
) -> float:
    """The fraction of candidate burst points the arrivals at the meters tell from every other
    pipe's, by a capture interval ``resolution`` (s) or more.

    ``node_distances[n][j]`` is the path length (m) from pipe end node ``n`` to meter ``j``
    (metres of wave travel at ``wave_speed`` where pipes have their own speeds, as for
    :func:`arrival_meters`).
    Candidate points are :data:`burstloc.constants.CANDIDATE_POSITIONS` along every pipe; two
    points look alike when their arrival times at the meters differ by nearly the same amount at
    every meter (the burst time is unknown): their separation is the spread (largest minus
    smallest) of those differences. A point closer than ``resolution`` to some point of another
    pipe is a burst the arrivals cannot place on its pipe: the fused localizer waits for the
    signature there.

    Raises:
        ConfigError: a bad wave speed or resolution, or no pipe.
    """
    check_timing(wave_speed, resolution)
    if not pipes:
        raise ConfigError("no pipes to separate")
    from scipy.spatial import cKDTree

    travel = _travel(pipes, node_distances, CANDIDATE_POSITIONS, wave_speed)
    owner = np.repeat(np.arange(len(pipes)), len(CANDIDATE_POSITIONS))
    # The spread of d = t_a - t_b is at least |d_j - d_0| for every meter j: only points whose
    # travel times relative to the first meter lie within ``resolution`` of each other (a k-d
    # tree query, maximum norm) can be closer than that; their spread is then computed exactly.
    relative = travel - travel[:, :1]
    a, b = cKDTree(relative).query_pairs(resolution * (1 + 1e-9), p=np.inf, output_type="ndarray").T
    other = owner[a] != owner[b]
    a, b = a[other], b[other]
    told = np.ones(owner.size, dtype=bool)
    block = max(1, 4_000_000 // max(1, travel.shape[1]))  # pairs per step: bounded memory
    for lo in range(0, a.size, block):
        ra, rb = a[lo : lo + block], b[lo : lo + block]
        diff = travel[ra] - travel[rb]
        near = diff.max(axis=1) - diff.min(axis=1) < resolution
        told[ra[near]] = False
        told[rb[near]] = False
    return float(told.mean())
