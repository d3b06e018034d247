"""The named point of a search posterior: where to send the crew first.

A crew sent to one point walks the main from there; what it pays is the network distance from
that point to the burst. The point that makes that distance smallest on average over the
posterior (:class:`burstloc.localize.region.Posterior`) is its *centre* (a medoid along the
pipes), the Bayes estimate for a mean position error. Where pipes are short (L-TOWN's median
pipe is about 40 m) no pipe is decidable from the arrivals, but the centre of the stretches
that explain them is: the unit is the metre of main, not the pipe.

:func:`posterior_center` takes the :data:`CANDIDATES` densest grid points of the posterior as
candidates (each inside the search region, whose segments are the densest ones), measures the
network distance from each to every point of the region along the candidate pipes and the
links joining them (Dijkstra from the candidates' end nodes on that graph, built once per arrival
localizer; each node's path lengths kept once found; a point no path reaches counts as the
farthest one reached) and
returns the candidate of least expected distance, as a position on its pipe (the segment's
middle, within the region's stretch that holds it). Numpy and NetworkX only: on the live path.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, replace

import networkx as nx
import numpy as np
from numpy.typing import NDArray

from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import Ranking
from burstloc.localize.pipes import PipePosition
from burstloc.localize.region import REGION_CONFIDENCE, Posterior, SearchRegion

__all__ = ["CANDIDATES", "CENTRE_SHARE", "Center", "named_point", "posterior_center"]

CANDIDATES = 24
"""Grid points tried as the centre: the densest ones of the posterior."""

MAX_MASS_POINTS = 4000
"""Most points of the region the expected distance is summed over (the most probable ones)."""


class _Paths:
    """Path lengths along the candidate pipes of one arrival localizer and the links joining
    them (its ``connectors``: valves and pumps, at no length), undirected, weighted by length,
    the shortest of parallel links: from a node to every node, one Dijkstra per node asked for,
    kept (a few kB each). Without the connectors a network's zones behind valves and pumps
    would be islands, and the mass of another zone out of every candidate's reach."""

    def __init__(self, arrival: ArrivalLocalizer) -> None:
        self.graph = nx.Graph()
        links = [(p.start, p.end, p.length) for p in arrival.pipes]
        for start, end, length in links + list(arrival.connectors):
            known = self.graph.get_edge_data(start, end)
            if known is None or known["length"] > length:
                self.graph.add_edge(start, end, length=float(length))
        self.index = {n: i for i, n in enumerate(self.graph.nodes)}
        self.starts = np.array([self.index[p.start] for p in arrival.pipes], dtype=np.int64)
        """Each candidate pipe's start node, as an index into :meth:`from_node`'s arrays."""
        self.ends = np.array([self.index[p.end] for p in arrival.pipes], dtype=np.int64)
        self._from: dict[str, NDArray[np.float64]] = {}

    def from_node(self, node: str) -> NDArray[np.float64]:
        """Path length (m) from ``node`` to every node (``inf`` where no path joins them)."""
        found = self._from.get(node)
        if found is None:
            found = np.full(len(self.index), np.inf)
            lengths = nx.single_source_dijkstra_path_length(self.graph, node, weight="length")
            found[[self.index[n] for n in lengths]] = list(lengths.values())
            self._from[node] = found
        return found


_PATHS: weakref.WeakKeyDictionary[ArrivalLocalizer, _Paths] = weakref.WeakKeyDictionary()


def _paths(arrival: ArrivalLocalizer) -> _Paths:
    """The localizer's :class:`_Paths`, made once."""
    paths = _PATHS.get(arrival)
    if paths is None:
        paths = _PATHS[arrival] = _Paths(arrival)
    return paths


@dataclass(frozen=True)
class Center:
    """A posterior's centre: the ``position`` on its pipe and the expected network distance
    (m) from it to the burst under the posterior (over the region's points)."""

    position: PipePosition
    expected_distance: float


def posterior_center(
    posterior: Posterior, region: SearchRegion | None = None, candidates: int = CANDIDATES
) -> Center:
    """The grid point of least expected network distance to the burst (module docstring).

    ``region``: the posterior's search region (default: at :data:`REGION_CONFIDENCE`); the
    distances are summed over its points, and the position's interval is its stretch that holds
    the centre.
    """
    grid, prob = posterior.grid, posterior.probability
    arrival = grid.arrival
    region = posterior.region(REGION_CONFIDENCE) if region is None else region
    density = prob / grid.length
    order = np.argsort(-density, kind="stable")
    count = int(np.searchsorted(np.cumsum(prob[order]), region.probability - 1e-12)) + 1
    mass = order[: min(count, MAX_MASS_POINTS, order.size)]
    tried = order[: min(candidates, mass.size)]
    pipes = arrival.pipes
    lengths = np.array([p.length for p in pipes], dtype=np.float64)
    mid = 0.5 * (grid.low + grid.high)
    paths = _paths(arrival)
    tried_pipes = [pipes[int(grid.pipe[i])] for i in tried.tolist()]
    ends = sorted({n for p in tried_pipes for n in (p.start, p.end)})
    # path lengths from each candidate end node to the two end nodes of each mass point
    m_pipe = grid.pipe[mass]
    m_start, m_end = paths.starts[m_pipe], paths.ends[m_pipe]
    m_off = mid[mass]
    m_len = lengths[m_pipe]
    reach: dict[str, NDArray[np.float64]] = {}
    for node in ends:
        lengths_from = paths.from_node(node)
        # from the node to each mass point, entering its pipe at either end
        reach[node] = np.minimum(
            lengths_from[m_start] + m_off, lengths_from[m_end] + (m_len - m_off)
        )
    weights = prob[mass] / prob[mass].sum()
    dists = []
    for i in tried.tolist():
        p = pipes[int(grid.pipe[i])]
        x = float(mid[i])
        dist = np.minimum(x + reach[p.start], (p.length - x) + reach[p.end])
        same = m_pipe == grid.pipe[i]
        dists.append(np.where(same, np.minimum(dist, np.abs(m_off - x)), dist))
    table = np.array(dists)  # (candidates, mass points)
    reached = np.isfinite(table)
    # a point no path reaches (a zone the network's links do not join) is as far as the
    # farthest point any candidate reaches: never free
    far = float(table[reached].max()) if reached.any() else 0.0
    costs = np.where(reached, table, far) @ weights
    best = int(np.argmin(costs))
    best_i, best_cost = int(tried[best]), float(costs[best])
    p = pipes[int(grid.pipe[best_i])]
    x = float(mid[best_i])
    low, high = float(grid.low[best_i]), float(grid.high[best_i])
    for s in region.stretches:
        if s.pipe == p.pipe:
            a, b = (s.low, s.high) if s.start == p.start else (p.length - s.high, p.length - s.low)
            if a - 1e-6 <= x <= b + 1e-6:
                low, high = a, b
                break
    return Center(PipePosition(p.pipe, p.start, p.end, p.length, x, low, high), best_cost)


CENTRE_SHARE = 0.25
"""Largest share of the network's main a 95 % search region may cover for its centre to be the
named point (:func:`named_point`): a wider region is mostly the prior, and the ranking's best pipe
(the lasting drop's, at coarse capture intervals) names the burst better."""


def named_point(
    ranking: Ranking, fitted: PipePosition | None, posterior: Posterior | None
) -> tuple[Ranking, PipePosition | None]:
    """The answer's named point and its ranking.

    Where the 95 % search region is narrow (at most :data:`CENTRE_SHARE` of the network's
    main), or the arrival fit's point on the ranking's best pipe (``fitted``) lies outside it,
    the named point is the posterior's centre (:func:`posterior_center`:
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
