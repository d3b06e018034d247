"""burstloc.localize.center: a posterior's centre is the grid point of least expected network
distance to the burst, checked against every point by brute force on a small network."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.center import posterior_center
from burstloc.localize.pipes import PipeGeometry
from burstloc.localize.region import Posterior, RegionGrid

# A loop with a tail: a-b-c-d-a (100 m sides) and d-e (300 m), one meter at a and one at e.
PIPES = [
    PipeGeometry("ab", "a", "b", 100.0),
    PipeGeometry("bc", "b", "c", 100.0),
    PipeGeometry("cd", "c", "d", 100.0),
    PipeGeometry("da", "d", "a", 100.0),
    PipeGeometry("de", "d", "e", 300.0),
]


def _localizer() -> ArrivalLocalizer:
    graph = nx.Graph()
    for p in PIPES:
        graph.add_edge(p.start, p.end, length=p.length)
    meters = ["a", "e"]
    lengths = {m: nx.single_source_dijkstra_path_length(graph, m, weight="length") for m in meters}
    distances = {n: np.array([lengths[m][n] for m in meters]) for n in graph}
    return ArrivalLocalizer(PIPES, meters, distances)


def _brute_force(grid: RegionGrid, prob: np.ndarray) -> np.ndarray:
    """Expected network distance from every grid point to the posterior, by subdividing."""
    graph = nx.Graph()
    mids = 0.5 * (grid.low + grid.high)
    pipes = grid.arrival.pipes
    for i, (k, x) in enumerate(zip(grid.pipe.tolist(), mids.tolist(), strict=True)):
        p = pipes[k]
        graph.add_edge(("g", i), p.start, length=x)
        graph.add_edge(("g", i), p.end, length=p.length - x)
    same = grid.pipe[:, None] == grid.pipe[None, :]
    out = np.empty(len(grid))
    for i in range(len(grid)):
        lengths = nx.single_source_dijkstra_path_length(graph, ("g", i), weight="length")
        d = np.array([lengths[("g", j)] for j in range(len(grid))])
        d = np.where(same[i], np.minimum(d, np.abs(mids - mids[i])), d)
        out[i] = float(np.sum(prob * d))
    return out


@pytest.mark.parametrize("seed", range(6))
def test_the_centre_is_the_point_of_least_expected_distance(seed: int) -> None:
    arrival = _localizer()
    grid = RegionGrid(arrival, step=25.0)
    rng = np.random.default_rng(seed)
    prob = rng.random(len(grid)) ** 8  # a few points carry most of the mass
    prob /= prob.sum()
    posterior = Posterior(grid, prob)
    region = posterior.region(1.0)  # every point: the expected distance over all of them
    center = posterior_center(posterior, region, candidates=len(grid))
    expected = _brute_force(grid, prob)
    assert center.expected_distance == pytest.approx(expected.min(), rel=1e-9)
    best = int(np.argmin(expected))
    at = center.position
    assert at.pipe == PIPES[int(grid.pipe[best])].pipe
    assert at.metres == pytest.approx(0.5 * (grid.low[best] + grid.high[best]))
    assert region.contains(at.pipe, at.start, at.metres, at.length)


def test_the_centre_lies_in_the_region_between_two_likely_places() -> None:
    """Mass split between both ends of the 300 m tail: the centre is on the tail, in the
    region, not at either end's pipe alone when the two carry the same mass."""
    arrival = _localizer()
    grid = RegionGrid(arrival, step=25.0)
    prob = np.full(len(grid), 1e-9)
    tail = np.flatnonzero(grid.pipe == 4)
    prob[tail] = 1.0  # uniform along the tail
    prob /= prob.sum()
    posterior = Posterior(grid, prob)
    center = posterior_center(posterior)
    assert center.position.pipe == "de"
    assert 125.0 <= center.position.metres <= 175.0  # the middle of the tail
    assert posterior.region().contains("de", "d", center.position.metres, 300.0)


# Two zones joined by a valve (d-v, no length): the loop a-b-c-d and a tail v-x-y (200 m each).
ZONES = [
    *PIPES[:4],
    PipeGeometry("vx", "v", "x", 200.0),
    PipeGeometry("xy", "x", "y", 200.0),
]
VALVE = ("d", "v", 0.0)


def _zoned(connectors: tuple[tuple[str, str, float], ...]) -> ArrivalLocalizer:
    graph = nx.Graph()
    for p in ZONES:
        graph.add_edge(p.start, p.end, length=p.length)
    graph.add_edge(VALVE[0], VALVE[1], length=0.0)  # the meters hear through the valve
    meters = ["a", "y"]
    lengths = {m: nx.single_source_dijkstra_path_length(graph, m, weight="length") for m in meters}
    distances = {n: np.array([lengths[m][n] for m in meters]) for n in graph}
    return ArrivalLocalizer(ZONES, meters, distances, connectors=connectors)


@pytest.mark.parametrize("joined", [True, False])
def test_mass_behind_a_valve_is_not_out_of_reach(joined: bool) -> None:
    """85 % of the mass on ab, 15 % at the far end of the other zone (xy): the centre is on
    the loop, whether the valve joins the zones (the network's connectors) or not (a model
    stored without them: the other zone's mass counts as the farthest reached, never free).
    Counted free, as it once was, the far zone's candidates paid for its 15 % only."""
    arrival = _zoned((VALVE,) if joined else ())
    grid = RegionGrid(arrival, step=25.0)
    prob = np.full(len(grid), 1e-12)
    ab, xy = np.flatnonzero(grid.pipe == 0), np.flatnonzero(grid.pipe == 5)
    prob[ab] = 0.85 / ab.size
    prob[xy] = 0.15 / xy.size
    posterior = Posterior(grid, prob / prob.sum())
    center = posterior_center(posterior, posterior.region(0.99), candidates=len(grid))
    assert center.position.pipe in ("ab", "bc", "da")
    if joined:  # the expected distance walks through the valve: finite, and less than 200 m
        assert center.expected_distance < 200.0
