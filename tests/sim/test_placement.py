"""burstloc.sim.placement.methods: the coverage and arrival placements, the meter file, place_meters
on
the tiny network."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.localize.pipes import PipeGeometry
from burstloc.localize.signature import SignatureSet
from burstloc.sim.placement.methods import (
    METERS_FORMAT,
    MeterSet,
    arrival_meters,
    arrival_separation,
    coverage_meters,
    meter_separation,
    place_meters,
)
from conftest import write_tiny


def _signatures(matrix: list[list[float]]) -> SignatureSet:
    pipes = tuple(f"P{i}" for i in range(len(matrix)))
    meters = tuple(f"M{j}" for j in range(len(matrix[0])))
    return SignatureSet(
        network_hash="x",
        meters=meters,
        pipes=pipes,
        endpoints={p: ("a", "b") for p in pipes},
        matrix=np.array(matrix),
        baseline=np.zeros(len(meters)),
        params={},
    )


def test_coverage_meters_pick_the_meters_that_tell_pipes_apart() -> None:
    # M0 sees every burst alike (large but useless alone); M1 and M2 separate the pipes.
    sig = _signatures([[5.0, 1.0, 0.0], [5.0, 0.0, 1.0], [5.0, 1.0, 1.0]])
    assert coverage_meters(sig, 1) == ("M0",)  # one meter separates nothing: the strongest
    two = coverage_meters(sig, 2)
    assert "M0" in two and len(two) == 2
    assert coverage_meters(sig, 3) == ("M0", "M1", "M2")
    # With a meter that alone tells P0 from P1, it comes first.
    sig2 = _signatures([[1.0, 0.0], [0.0, 1.0]])
    assert coverage_meters(sig2, 2) == ("M0", "M1")
    with pytest.raises(ConfigError, match="meter count"):
        coverage_meters(sig, 4)


def test_coverage_meters_prefer_separation_over_signal_strength() -> None:
    # M1 carries the largest drops but M2 alone tells P0 from P1; then M0 separates them more
    # (unit-vector gap 0.32) than M1 would (0.20).
    sig = _signatures([[3.0, 5.0, 0.0], [3.0, 5.0, 1.0]])
    assert coverage_meters(sig, 1) == ("M2",)
    assert coverage_meters(sig, 2) == ("M0", "M2")


def _line(nodes: int, spacing: float = 500.0) -> tuple[list[PipeGeometry], list[str], dict]:
    """A line n0 - n1 - ... with every node a candidate junction."""
    names = [f"n{i}" for i in range(nodes)]
    pipes = [PipeGeometry(f"p{i}", names[i], names[i + 1], spacing) for i in range(nodes - 1)]
    distances = {
        a: np.array([spacing * abs(i - j) for j in range(nodes)], dtype=np.float64)
        for i, a in enumerate(names)
    }
    return pipes, names, distances


def test_arrival_placement_puts_two_meters_at_the_ends_of_a_line() -> None:
    # With meters at both ends the difference of arrival times changes along the whole line, so
    # every pair of pipes is told apart; any inner meter leaves the pipes beyond it alike.
    pipes, names, distances = _line(5)
    assert arrival_meters(pipes, names, distances, 2) == ("n0", "n4")
    # one meter separates nothing (the burst time is free): a peripheral junction
    assert arrival_meters(pipes, names, distances, 1) == ("n0",)
    three = arrival_meters(pipes, names, distances, 3)
    assert {"n0", "n4"} <= set(three) and len(three) == 3
    with pytest.raises(ConfigError, match="meter count"):
        arrival_meters(pipes, names, distances, 6)
    with pytest.raises(ConfigError, match="resolution"):
        arrival_meters(pipes, names, distances, 2, resolution=0.0)


def test_arrival_placement_covers_both_branches_of_a_tee() -> None:
    # A tee: c is the centre; arms to a, b and d. Two arm ends leave the third arm's pipes
    # alike to the meters only if they are on the same side; three arm ends separate them all.
    length = 400.0
    pipes = [
        PipeGeometry("ca", "c", "a", length),
        PipeGeometry("cb", "c", "b", length),
        PipeGeometry("cd", "c", "d", length),
    ]
    names = ["a", "b", "c", "d"]
    pos = {"a": 1, "b": 1, "d": 1, "c": 0}

    def dist(u: str, v: str) -> float:
        return 0.0 if u == v else length * (pos[u] + pos[v])

    distances = {u: np.array([dist(u, v) for v in names]) for u in names}
    chosen = arrival_meters(pipes, names, distances, 3)
    assert chosen == ("a", "b", "d")


def test_meter_file_round_trip_and_checks(tmp_path: Path) -> None:
    tiny = write_tiny(tmp_path / "tiny.inp")
    placed = place_meters(tiny, 2, method="arrival")
    assert placed.method == "arrival" and placed.junctions == 4 and len(placed.meters) == 2
    assert set(placed.meters) <= {"J1", "J2", "J3", "J4"}
    path = placed.save(tmp_path / "meters.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == METERS_FORMAT and doc["meters"] == list(placed.meters)
    loaded = MeterSet.load(path)
    assert loaded == placed
    assert loaded.check(tiny) == placed.meters
    other = write_tiny(tmp_path / "other.inp", head=70.0)
    with pytest.raises(ConfigError, match=r"made for network .*run `burstloc place`"):
        loaded.check(other)
    doc["meters"] = ["J1", "J1"]
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=r"meters.json: meters lists 'J1' more than once"):
        MeterSet.load(path)
    path.write_text(json.dumps({"format": "something/1"}))
    with pytest.raises(ConfigError, match="not a burstloc meter file"):
        MeterSet.load(path)
    with pytest.raises(ConfigError, match="unknown placement method"):
        place_meters(tiny, 2, method="random")


def test_coverage_placement_on_a_network_file(tmp_path: Path) -> None:
    tiny = write_tiny(tmp_path / "tiny.inp")
    placed = place_meters(tiny, 3, method="coverage")
    assert placed.method == "coverage" and len(placed.meters) == 3
    with pytest.raises(ConfigError, match="meter count must be between 1 and 4"):
        place_meters(tiny, 5, method="coverage")


def test_arrival_separation_counts_the_points_told_from_every_other_pipe() -> None:
    # A line of four 500 m pipes, meters at both ends: the difference of their arrival times
    # changes along the whole line. The points nearest an inner junction on its two pipes (10 %
    # from it, 100 m apart) differ by 200 m of travel, 0.17 s: told apart at 0.1 s, not at 0.2 s
    # (6 of the 36 points); a single meter tells nothing (the burst time is free).
    pipes, _, distances = _line(5)
    ends = {n: d[[0, 4]] for n, d in distances.items()}
    assert arrival_separation(pipes, ends, resolution=0.1) == 1.0
    assert arrival_separation(pipes, ends, resolution=0.2) == pytest.approx(30 / 36)
    middle = {n: d[[2]] for n, d in distances.items()}
    assert arrival_separation(pipes, middle, resolution=0.1) == 0.0
    with pytest.raises(ConfigError, match="resolution"):
        arrival_separation(pipes, ends, resolution=0.0)


def test_meter_separation_on_the_paper_network(paper15: Path) -> None:
    every = meter_separation(
        paper15, [f"N{i}" for i in range(2, 9)] + [str(i) for i in range(1, 9)]
    )
    four = meter_separation(paper15, ["N4", "N7", "1", "8"])
    assert 0.0 == meter_separation(paper15, ["N4"]) < four < every <= 1.0
    with pytest.raises(NetworkError):
        meter_separation(paper15, ["N4", "nowhere"])
    with pytest.raises(ConfigError, match="no meters"):
        meter_separation(paper15, [])


def _reference_arrival_meters(
    pipes: list[PipeGeometry],
    junctions: list[str],
    distances: dict[str, np.ndarray],
    count: int,
    resolution: float,
) -> tuple[str, ...]:
    """The arrival greedy evaluated directly: every candidate junction scored over all pairs of
    candidate points (a points x points matrix per candidate), as the placement was first
    written."""
    from burstloc.constants import WAVE_SPEED
    from burstloc.sim.placement.arrival import ARRIVAL_POINTS, _travel

    travel = _travel(pipes, distances, ARRIVAL_POINTS, WAVE_SPEED)
    n_pipes, n_points = len(pipes), len(ARRIVAL_POINTS)
    owner = np.repeat(np.arange(n_pipes), n_points)
    other_pipe = owner[:, None] != owner[None, :]
    upper = np.triu(np.ones((n_pipes, n_pipes), dtype=bool), k=1)

    def objective(s1: np.ndarray, s2: np.ndarray, k: int) -> float:
        spread = np.sqrt(np.maximum(s2 / k - (s1 / k) ** 2, 0.0))
        spread = np.where(other_pipe, spread, np.inf)
        per_pair = spread.reshape(n_pipes, n_points, n_pipes, n_points).min(axis=(1, 3))
        return float(np.minimum(per_pair[upper], resolution).sum())

    spread_of = travel.std(axis=0)
    chosen = [int(np.argmax(spread_of))]
    sum1 = travel[:, chosen[0]][:, None] - travel[:, chosen[0]][None, :]
    sum2 = sum1**2
    while len(chosen) < count:
        keys = []
        for j in range(len(junctions)):
            if j not in chosen:
                diff = travel[:, j][:, None] - travel[:, j][None, :]
                objective_j = objective(sum1 + diff, sum2 + diff**2, len(chosen) + 1)
                keys.append((objective_j, spread_of[j], -j))
        j = -max(keys)[2]
        diff = travel[:, j][:, None] - travel[:, j][None, :]
        sum1, sum2 = sum1 + diff, sum2 + diff**2
        chosen.append(j)
    return tuple(junctions[j] for j in sorted(chosen))


@pytest.mark.parametrize("network", ["paper15.inp", "awumah11.inp", "paper15_assets.inp"])
def test_arrival_placement_equals_the_direct_greedy(network: str) -> None:
    """Same meters as the direct evaluation, for every count and two capture intervals (ties
    between junctions, which happen when pairs saturate, included)."""
    from burstloc.network import load_network
    from burstloc.sim.model.prepare import arrival_geometry

    wn = load_network(Path(__file__).resolve().parents[2] / "networks" / network)
    junctions = list(wn.junction_name_list)
    pipes, distances = arrival_geometry(wn, junctions)
    for resolution in (0.2, 0.05):
        for count in range(1, len(junctions) + 1):
            expected = _reference_arrival_meters(pipes, junctions, distances, count, resolution)
            got = arrival_meters(pipes, junctions, distances, count, resolution=resolution)
            assert got == expected, (network, resolution, count)


def test_arrival_placement_equals_the_direct_greedy_on_a_symmetric_grid() -> None:
    """A 4 x 4 grid of equal pipes: many junctions tie in exact arithmetic, and the direct
    evaluation's sums decide between them; the placement must fall the same way."""
    import networkx as nx

    side, spacing = 4, 300.0
    grid = nx.grid_2d_graph(side, side)
    names = [f"g{r}{c}" for r, c in grid.nodes]
    label = dict(zip(grid.nodes, names, strict=True))
    pipes = [
        PipeGeometry(f"p{i}", label[u], label[v], spacing) for i, (u, v) in enumerate(grid.edges)
    ]
    hops = dict(nx.all_pairs_shortest_path_length(grid))
    distances = {
        label[u]: np.array([spacing * hops[u][v] for v in grid.nodes], dtype=np.float64)
        for u in grid.nodes
    }
    for resolution in (0.2, 0.05):
        for count in range(1, 9):
            expected = _reference_arrival_meters(pipes, names, distances, count, resolution)
            got = arrival_meters(pipes, names, distances, count, resolution=resolution)
            assert got == expected, (resolution, count)


def test_arrival_separation_equals_the_direct_evaluation(paper15: Path) -> None:
    """The k-d tree's candidate pairs miss no pair closer than the capture interval: the same
    share as comparing every point with every other point."""
    from burstloc.constants import CANDIDATE_POSITIONS, WAVE_SPEED
    from burstloc.sim.model.prepare import arrival_geometry
    from burstloc.sim.placement.arrival import _travel

    shares = []
    for meters in (["N4", "N7", "1", "8"], ["N3", "5"], ["N2", "N5", "N8", "2", "4", "6", "7"]):
        pipes, distances = arrival_geometry(paper15, meters)
        travel = _travel(pipes, distances, CANDIDATE_POSITIONS, WAVE_SPEED)
        owner = np.repeat(np.arange(len(pipes)), len(CANDIDATE_POSITIONS))
        diff = travel[:, None, :] - travel[None, :, :]
        spread = diff.max(axis=2) - diff.min(axis=2)
        spread[owner[:, None] == owner[None, :]] = np.inf
        for resolution in (0.05, 0.2, 1.0):
            expected = float((spread.min(axis=1) >= resolution).mean())
            got = arrival_separation(pipes, distances, resolution=resolution)
            assert got == expected, (meters, resolution)
            shares.append(expected)
    assert len({*shares}) > 3  # neither all told nor none: the comparisons mean something
