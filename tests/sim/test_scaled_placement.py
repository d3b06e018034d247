"""burstloc.sim.placement.scaled: the reduced problem of large networks (spread candidate
junctions, sampled bursts), tried on real networks with the threshold lowered."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.network import load_network
from burstloc.sim.model.prepare import arrival_geometry
from burstloc.sim.placement.methods import MeterSet, meter_ambiguity, meter_separation, place_meters
from burstloc.sim.placement.region import ambiguity_grid
from burstloc.sim.placement.scaled import (
    DEFAULT_SCALING,
    Scaling,
    candidate_geometry,
    reduced_problem,
    spread_junctions,
)

NETWORKS = Path(__file__).resolve().parents[2] / "networks"

#: Net3 (92 junctions, 117 pipes) reduced to 40 candidates, 60 sampled pipes, 300 points.
SMALL = Scaling(above=10, candidates=40, pipes=60, points=300)


@pytest.fixture(scope="module")
def net3() -> Path:
    path = NETWORKS / "public" / "Net3.inp"
    if not path.is_file():
        pytest.fail(f"{path} is missing: run `make setup` (it fetches the public networks)")
    return path


def test_candidate_lengths_are_the_exact_geometrys(net3: Path) -> None:
    """Sparse Dijkstra from the candidates gives arrival_geometry's path lengths to them, to
    the bit (Net3: pumps and valves weigh nothing; unreachable nodes stay infinite)."""
    wn = load_network(net3)
    pipes, names, distances = candidate_geometry(wn, 40)
    expected_pipes, expected = arrival_geometry(wn, names)
    assert pipes == expected_pipes
    assert distances.keys() == expected.keys()
    for node, row in expected.items():
        np.testing.assert_array_equal(distances[node], row)
    assert names == [j for j in wn.junction_name_list if j in set(names)]  # network order


def test_spread_junctions_cover_the_network_within_their_spacing(net3: Path) -> None:
    """Farthest-point sampling: every junction lies no farther from the chosen ones than
    any two chosen ones lie from each other, and more candidates cover more tightly."""
    wn = load_network(net3)
    junctions = list(wn.junction_name_list)
    radii = []
    for count in (5, 20, 60):
        names, lengths = spread_junctions(wn, count)
        assert len(set(names)) == count
        table = np.array([lengths[j] for j in junctions])  # (junctions, chosen)
        table = np.where(np.isfinite(table), table, np.nan)
        radius = float(np.nanmax(np.nanmin(table, axis=1)))
        between = np.array([lengths[n] for n in names])
        spacing = float(np.nanmin(np.where(np.eye(count, dtype=bool), np.nan, between)))
        assert radius <= spacing + 1e-9, count
        radii.append(radius)
    assert radii[0] > radii[1] > radii[2]


@pytest.mark.parametrize("method", ["arrival", "region"])
def test_without_reduction_the_scaled_path_gives_the_exact_meters(net3: Path, method: str) -> None:
    """Threshold lowered, but as many candidates, pipes and points as Net3 has: the same
    meters as the exact method (the pipeline adds nothing of its own)."""
    for count in (3, 8):
        exact = place_meters(net3, count, method=method)
        scaled = place_meters(net3, count, method=method, scaling=Scaling(above=10))
        assert scaled.meters == exact.meters, (method, count)


def test_scaled_arrival_placement_is_sensible_and_deterministic(net3: Path) -> None:
    """Reduced to 40 of 92 junctions and 60 of 117 pipes: meters among the candidates, the
    same on every run, their arrival separation close to the exact placement's."""
    wn = load_network(net3)
    candidates = set(spread_junctions(wn, SMALL.candidates)[0])
    exact = place_meters(net3, 8).meters
    scaled = place_meters(net3, 8, scaling=SMALL)
    assert scaled.method == "arrival" and len(scaled.meters) == 8
    assert set(scaled.meters) <= candidates
    assert scaled.meters != exact  # the reduction is in use
    assert place_meters(net3, 8, scaling=SMALL) == scaled
    problem = reduced_problem(wn, 8, SMALL)
    assert len(problem.arrival_pipes) == 60 and len(problem.candidates) == 40
    assert len(problem.pipes) == wn.num_pipes
    exact_told = meter_separation(net3, exact)
    assert meter_separation(net3, scaled.meters) >= 0.8 * exact_told > 0


def test_scaled_region_placement_is_sensible_and_deterministic(net3: Path) -> None:
    """The region method on 40 candidates and 300 sampled points: deterministic, and its
    expected ambiguous main (on the whole grid) close to the exact placement's."""
    wn = load_network(net3)
    candidates = set(spread_junctions(wn, SMALL.candidates)[0])
    exact = place_meters(net3, 8, method="region").meters
    scaled = place_meters(net3, 8, method="region", scaling=SMALL)
    assert set(scaled.meters) <= candidates
    assert place_meters(net3, 8, method="region", scaling=SMALL) == scaled
    assert 0 < meter_ambiguity(net3, scaled.meters) <= 1.25 * meter_ambiguity(net3, exact)


def test_a_sampled_grid_keeps_the_length_of_main(net3: Path) -> None:
    """``points``: a length-weighted sample of segments standing for all the main."""
    pipes, distances = arrival_geometry(net3, ["10", "15"])
    full = ambiguity_grid(pipes, ["10", "15"], distances)
    sampled = ambiguity_grid(pipes, ["10", "15"], distances, points=200)
    assert full.length.size > 200 >= sampled.length.size
    assert sampled.length.sum() == pytest.approx(full.length.sum())
    assert sampled.bursts.max() < sampled.length.size
    assert sampled.weight.sum() == pytest.approx(1.0)
    again = ambiguity_grid(pipes, ["10", "15"], distances, points=200)
    np.testing.assert_array_equal(again.travel, sampled.travel)
    np.testing.assert_array_equal(again.bursts, sampled.bursts)


def test_scaled_placement_names_bad_input(net3: Path) -> None:
    for bad in (
        {"candidates": 0},
        {"pipes": True},
        {"points": 2.5},
        {"above": -1},
        {"seed": -3},
    ):
        with pytest.raises(ConfigError, match="scaling"):
            Scaling(**bad)  # type: ignore[arg-type]
    wn = load_network(net3)
    with pytest.raises(ConfigError, match="candidate count"):
        spread_junctions(wn, 0)
    with pytest.raises(ConfigError, match="candidate count"):
        spread_junctions(wn, wn.num_junctions + 1)
    with pytest.raises(ConfigError, match="meter count"):
        place_meters(net3, wn.num_junctions + 1, scaling=SMALL)
    with pytest.raises(ConfigError, match="meter count"):
        reduced_problem(wn, 0)
    pipes, distances = arrival_geometry(net3, ["10"])
    with pytest.raises(ConfigError, match="point count"):
        ambiguity_grid(pipes, ["10"], distances, points=0)
    assert not DEFAULT_SCALING.applies(782) and DEFAULT_SCALING.applies(12_523)


def test_a_meter_file_for_a_network_of_more_than_ten_thousand_junctions(tmp_path: Path) -> None:
    """BWSN_Network_2 has 12 523 junctions: its meter file is valid (it was refused)."""
    placed = MeterSet("BWSN_Network_2.inp", "sha256:x", "arrival", ("J1", "J2"), 12_523)
    assert MeterSet.load(placed.save(tmp_path / "meters.json")) == placed


def test_ambiguous_length_in_blocks_of_bursts(
    paper15: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A large grid's objective is summed over blocks of bursts (bounded memory): the same
    value as all pairs at once."""
    from burstloc.sim.placement import region as region_placement
    from burstloc.sim.placement.region import ambiguous_length

    meters = ["N4", "N7", "1", "8"]
    pipes, distances = arrival_geometry(paper15, meters)
    whole = ambiguous_length(pipes, meters, distances)
    points = ambiguity_grid(pipes, meters, distances).length.size
    monkeypatch.setattr(region_placement, "_PAIRS", 7 * points)  # blocks of 7 bursts
    assert ambiguous_length(pipes, meters, distances) == pytest.approx(whole, rel=1e-12)
    assert whole > 0


@pytest.mark.parametrize("method", ["arrival", "region"])
def test_the_seed_draws_another_sample(net3: Path, method: str) -> None:
    """``Scaling.seed`` reaches both methods' samples: another seed, other meters (Net3
    reduced), each the same on every run."""
    from dataclasses import replace

    first = place_meters(net3, 8, method=method, scaling=SMALL).meters
    other = place_meters(net3, 8, method=method, scaling=replace(SMALL, seed=1)).meters
    assert first != other
    assert place_meters(net3, 8, method=method, scaling=replace(SMALL, seed=1)).meters == other
