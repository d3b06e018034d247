"""Meter placement on large networks: the ``arrival`` and ``region`` methods at utility scale.

The exact methods (:mod:`burstloc.sim.placement.methods`, :mod:`burstloc.sim.placement.region`) hold
the path length from every pipe end to every junction and compare every pair of candidate
burst points: on BWSN_Network_2 (12 523 junctions, 14 822 pipes) that is 1.2 GB of path lengths
and 10^9 pairs of points before the first meter. Above :attr:`Scaling.above` junctions
(default :data:`SCALE_JUNCTIONS`), :func:`burstloc.sim.placement.methods.place_meters` runs them on
a
reduced problem instead; below it nothing changes (the exact greedy, the same meters):

* **candidate junctions**: :attr:`Scaling.candidates` of the junctions, spread over the network
  by farthest-point sampling on path length (:func:`spread_junctions`: the junction farthest
  from the first junction, then each time the junction farthest from those chosen; a
  junction no chosen one reaches comes first, so every part of a disconnected network has
  candidates). Path lengths are measured from those candidates only (SciPy's sparse Dijkstra
  on :func:`burstloc.sim.model.prepare.length_graph`, the graph the exact methods use: pipes weigh
  their length (a pipe of its own wave speed its travel), valves and pumps nothing, parallel
  links their shortest; lengths are symmetric
  on it, so they are the lengths from the pipe ends to the candidates). Meters are chosen
  among the candidates.
* **bursts**: the ``arrival`` objective is summed over the pairs of a seeded sample of
  :attr:`Scaling.pipes` pipes (each pipe as likely; the exact objective's pipe pairs, sampled);
  the ``region`` objective over a seeded, length-weighted sample of :attr:`Scaling.points`
  points of its grid (:func:`burstloc.sim.placement.region.ambiguity_grid`), its bursts drawn
  from those.

Deterministic: the sampling is seeded (:attr:`Scaling.seed`) and the farthest-point sampling
breaks ties by network order. The approximation: the meters are the greedy's on the reduced
problem, not on the whole network. Measured (``benches/bench_place_scale.py``, 2 cores): on
BWSN_Network_2, 33 meters, ``arrival`` 13 s of CPU and 1.1 GB peak, ``region`` 24 s and 1.2 GB
(100 meters: 17 s, 32 s); on L-TOWN forced onto half its junctions, pipes and points, the
objectives of the scaled meters are within 1-3 % of the exact greedy's at a fifth of its CPU.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError
from burstloc.localize.pipes import PipeGeometry
from burstloc.sim.placement._checks import check_meter_count, kept_indices

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

__all__ = [
    "DEFAULT_SCALING",
    "SCALE_JUNCTIONS",
    "ReducedProblem",
    "Scaling",
    "candidate_geometry",
    "reduced_problem",
    "spread_junctions",
]

SCALE_JUNCTIONS = 1000
"""Networks with more junctions than this are placed on the reduced problem (module
docstring); L-TOWN (782) and every smaller network keep the exact methods."""


@dataclass(frozen=True)
class Scaling:
    """When and how far :func:`burstloc.sim.placement.methods.place_meters` reduces the problem
    (module docstring): above ``above`` junctions, ``candidates`` candidate junctions (at least
    the meter count), ``pipes`` sampled pipes (``arrival``), ``points`` sampled grid points
    (``region``), sampling seeded by ``seed``.

    Raises:
        ConfigError: a count below 1 (``above``: below 0) or not an integer, a negative seed.
    """

    above: int = SCALE_JUNCTIONS
    candidates: int = 800
    pipes: int = 1000
    points: int = 4000
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("above", "candidates", "pipes", "points", "seed"):
            value = getattr(self, name)
            low = 0 if name in ("above", "seed") else 1
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ConfigError(f"scaling {name} must be an integer >= {low}, got {value!r}")

    def applies(self, junctions: int) -> bool:
        """Whether a network of ``junctions`` junctions is placed on the reduced problem."""
        return junctions > self.above


DEFAULT_SCALING = Scaling()
"""The scaling :func:`burstloc.sim.placement.methods.place_meters` uses by default."""


def _node_graph(
    wn: WaterNetworkModel, stretch: Mapping[str, float] | None = None
) -> tuple[list[str], object]:
    """The nodes of :func:`burstloc.sim.model.prepare.length_graph` (with ``stretch``) and its
    sparse matrix (one entry per edge, zero-length valves and pumps kept as explicit zeros:
    SciPy counts them as edges)."""
    from scipy.sparse import csr_matrix

    from burstloc.sim.model.prepare import length_graph

    graph = length_graph(wn, stretch)
    nodes = list(graph.nodes)
    index = {n: i for i, n in enumerate(nodes)}
    rows, cols, weights = [], [], []
    for u, v, length in graph.edges(data="length"):
        if u != v:
            rows.append(index[u])
            cols.append(index[v])
            weights.append(float(length))
    matrix = csr_matrix((weights, (rows, cols)), shape=(len(nodes), len(nodes)))
    return nodes, matrix


def spread_junctions(
    wn: WaterNetworkModel,
    count: int,
    first: Sequence[str] = (),
    stretch: Mapping[str, float] | None = None,
) -> tuple[list[str], dict[str, NDArray[np.float64]]]:
    """``count`` junctions spread by farthest-point sampling on path length (module
    docstring), in the network's junction order, and the path lengths (m) from every node to
    them (``inf`` without a path): ``lengths[node][j]`` to the ``j``-th chosen junction.
    ``first``: junctions taken before the sampling starts (a network's own meters; the others
    are then spread away from them); ``count`` includes them. ``stretch``: pipes of their own
    wave speed (:func:`burstloc.sim.model.prepare.length_graph`): the lengths are then metres
    of wave travel, and the junctions spread by travel time.

    Raises:
        ConfigError: ``count`` is not an integer in ``[1, junctions]``, or below the number of
            ``first``; one of ``first`` is not a junction.
    """
    from scipy.sparse.csgraph import dijkstra

    junctions = list(wn.junction_name_list)
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= len(junctions):
        raise ConfigError(
            f"the candidate count must be between 1 and {len(junctions)}, got {count!r}"
        )
    nodes, matrix = _node_graph(wn, stretch)
    index = {n: i for i, n in enumerate(nodes)}
    columns = np.array([index[j] for j in junctions], dtype=np.int64)
    start = dijkstra(matrix, directed=False, indices=int(columns[0]))[columns]
    reached = np.isfinite(start)
    seeds = kept_indices(first, junctions) or [int(np.argmax(np.where(reached, start, -1.0)))]
    if count < len(seeds):
        raise ConfigError(f"the candidate count {count} is below the {len(seeds)} kept meters")
    chosen: list[int] = []
    rows: list[NDArray[np.float64]] = []
    nearest = np.full(len(junctions), math.inf)
    for pick in seeds[:-1]:
        chosen.append(pick)
        row = np.asarray(dijkstra(matrix, directed=False, indices=int(columns[pick])))
        rows.append(row)
        nearest = np.minimum(nearest, row[columns])
    nearest[seeds[:-1]] = -1.0
    pick = seeds[-1]
    while True:
        chosen.append(pick)
        row = np.asarray(dijkstra(matrix, directed=False, indices=int(columns[pick])))
        rows.append(row)
        nearest = np.minimum(nearest, row[columns])
        nearest[pick] = -1.0  # chosen (a zero-length link can put another at 0)
        if len(chosen) == count:
            break
        pick = int(np.argmax(nearest))  # inf first: a part no chosen junction reaches
    order = np.argsort(chosen, kind="stable")
    table = np.stack([rows[i] for i in order], axis=1)  # (nodes, candidates)
    names = [junctions[chosen[i]] for i in order]
    return names, {n: table[i] for i, n in enumerate(nodes)}


def candidate_geometry(
    wn: WaterNetworkModel,
    count: int,
    first: Sequence[str] = (),
    stretch: Mapping[str, float] | None = None,
) -> tuple[list[PipeGeometry], list[str], dict[str, NDArray[np.float64]]]:
    """Every pipe's geometry (:func:`burstloc.sim.model.prepare.pipe_geometry`), ``count`` spread
    candidate junctions (:func:`spread_junctions`, ``first`` among them) and the path lengths
    from every pipe end node to them: the arguments of the exact placements, on the candidates
    (``stretch``: pipes of their own wave speed, as for :func:`spread_junctions`).

    Raises:
        ConfigError: ``count`` out of range.
    """
    from burstloc.sim.model.prepare import pipe_geometry

    pipes = pipe_geometry(wn, stretch)
    names, lengths = spread_junctions(wn, count, first, stretch)
    ends = dict.fromkeys(n for p in pipes for n in (p.start, p.end))
    return pipes, names, {n: lengths[n] for n in ends}


def _sample(items: Sequence[PipeGeometry], count: int, seed: int) -> list[PipeGeometry]:
    """A seeded uniform sample of ``count`` of ``items`` without replacement, in their order
    (all of them when there are no more)."""
    if len(items) <= count:
        return list(items)
    keep = np.sort(np.random.default_rng(seed).choice(len(items), size=count, replace=False))
    return [items[i] for i in keep]


@dataclass(frozen=True)
class ReducedProblem:
    """The reduced problem of a large network (module docstring): every pipe (``pipes``, for
    the ``region`` grid), the spread candidate junctions (``candidates``, network order), the
    path lengths (m) from every pipe end node to them (``distances``) and the sampled pipes of
    the ``arrival`` objective (``arrival_pipes``)."""

    pipes: list[PipeGeometry]
    candidates: list[str]
    distances: dict[str, NDArray[np.float64]]
    arrival_pipes: list[PipeGeometry]


def reduced_problem(
    wn: WaterNetworkModel,
    count: int,
    scaling: Scaling = DEFAULT_SCALING,
    keep: Sequence[str] = (),
    stretch: Mapping[str, float] | None = None,
) -> ReducedProblem:
    """The reduced problem for ``count`` meters on the WNTR model ``wn``: ``scaling.candidates``
    candidates (at least ``count``, at most every junction), ``scaling.pipes`` sampled pipes.
    ``keep``: meters the network has, always candidates (``count`` more are to be added);
    ``stretch``: pipes of their own wave speed (:func:`spread_junctions`).

    Raises:
        ConfigError: ``count`` out of range, a kept meter that is not a junction.
    """
    junctions = wn.num_junctions
    check_meter_count(count, junctions - len(keep))
    wanted = min(junctions, max(scaling.candidates, count + len(keep)))
    pipes, names, distances = candidate_geometry(wn, wanted, keep, stretch)
    return ReducedProblem(pipes, names, distances, _sample(pipes, scaling.pipes, scaling.seed))
