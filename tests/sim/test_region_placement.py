"""burstloc.sim.placement.region: the ``region`` placement (the least expected ambiguous main)
and its objective, on shipped and hand-made networks."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.localize.pipes import PipeGeometry
from burstloc.network import load_network
from burstloc.sim.model.prepare import arrival_geometry
from burstloc.sim.placement.methods import MeterSet, arrival_meters, meter_ambiguity, place_meters
from burstloc.sim.placement.region import (
    BURST_SAMPLES,
    ambiguity_grid,
    ambiguous_length,
    region_meters,
)

NETWORKS = Path(__file__).resolve().parents[2] / "networks"

#: A tee: the reservoir feeds the centre C; three arms of two 400 m pipes each (A1 - A2, ...).
TEE_INP = """\
[JUNCTIONS]
 C   0  1
 A1  0  1
 A2  0  1
 B1  0  1
 B2  0  1
 D1  0  1
 D2  0  1

[RESERVOIRS]
 R   50

[PIPES]
 P0  R   C   10   300  100  0  Open
 PA1 C   A1  400  200  100  0  Open
 PA2 A1  A2  400  200  100  0  Open
 PB1 C   B1  400  200  100  0  Open
 PB2 B1  B2  400  200  100  0  Open
 PD1 C   D1  400  200  100  0  Open
 PD2 D1  D2  400  200  100  0  Open

[OPTIONS]
 Units  LPS
 Headloss  H-W

[END]
"""


def _geometry(network: Path) -> tuple[list[PipeGeometry], list[str], dict[str, np.ndarray]]:
    wn = load_network(network)
    junctions = list(wn.junction_name_list)
    pipes, distances = arrival_geometry(wn, junctions)
    return pipes, junctions, distances


def _objective(
    pipes: list[PipeGeometry],
    junctions: list[str],
    distances: dict,
    meters: tuple[str, ...],
    **options: int,
) -> float:
    columns = [junctions.index(m) for m in meters]
    return ambiguous_length(pipes, meters, {n: d[columns] for n, d in distances.items()}, **options)


def test_region_placement_is_deterministic_and_distinct(paper15: Path, tmp_path: Path) -> None:
    junctions = list(load_network(paper15).junction_name_list)
    for count in (1, 3, 15):
        placed = place_meters(paper15, count, method="region")
        assert placed.method == "region" and len(set(placed.meters)) == count
        assert set(placed.meters) <= set(junctions)
        assert list(placed.meters) == [j for j in junctions if j in placed.meters]  # file order
        assert place_meters(paper15, count, method="region") == placed
    saved = MeterSet.load(placed.save(tmp_path / "meters.json"))
    assert saved == placed and saved.method == "region"


@pytest.mark.parametrize("network", ["paper15.inp", "awumah11.inp", "paper15_assets.inp"])
def test_region_placement_is_no_worse_than_arrival_by_its_objective(network: str) -> None:
    pipes, junctions, distances = _geometry(NETWORKS / network)
    better = 0
    for count in (2, 3, 4, 6, len(junctions)):
        region = region_meters(pipes, junctions, distances, count)
        arrival = arrival_meters(pipes, junctions, distances, count)
        mine = _objective(pipes, junctions, distances, region)
        theirs = _objective(pipes, junctions, distances, arrival)
        assert mine <= theirs * (1 + 1e-9), (network, count, region, arrival)
        better += mine < theirs * (1 - 1e-6)
    # every junction metered leaves a floor: the main within a capture interval of the burst
    floor = _objective(pipes, junctions, distances, tuple(junctions))
    assert 0 < floor <= _objective(pipes, junctions, distances, region)
    if network != "awumah11.inp":  # the two methods agree everywhere on the smallest network
        assert better > 0


@pytest.mark.parametrize("samples", [BURST_SAMPLES, 40])
def test_ambiguous_length_equals_the_direct_evaluation(paper15: Path, samples: int) -> None:
    """The expected ambiguous main, compared with every (burst, point) pair at once; every
    point bursts on a small network, a seeded sample weighted by length on fewer samples."""
    pipes, junctions, distances = _geometry(paper15)
    grid = ambiguity_grid(pipes, junctions, distances, samples=samples)
    assert grid.weight.sum() == pytest.approx(1.0)
    if samples == BURST_SAMPLES:
        assert grid.bursts.size == grid.length.size
    else:
        assert 1 < grid.bursts.size <= samples < grid.length.size
        again = ambiguity_grid(pipes, junctions, distances, samples=samples)
        assert np.array_equal(again.bursts, grid.bursts)
        other = ambiguity_grid(pipes, junctions, distances, samples=samples, seed=1)
        assert not np.array_equal(other.bursts, grid.bursts)
    values = set()
    for meters in (("N4",), ("N4", "8"), ("N4", "N7", "1", "8"), tuple(junctions)):
        columns = [junctions.index(m) for m in meters]
        travel = grid.travel[:, columns]
        delta = travel[None, :, :] - travel[grid.bursts][:, None, :]  # (bursts, points, meters)
        alike = delta.max(axis=2) - delta.min(axis=2) < 0.2
        expected = float(grid.weight @ (alike * grid.length[None, :]).sum(axis=1))
        got = _objective(pipes, junctions, distances, meters, samples=samples)
        assert got == pytest.approx(expected, rel=1e-12)
        values.add(round(got))
    # one meter tells nothing (the whole main); more meters, less main
    assert max(values) == round(sum(p.length for p in pipes))
    assert len(values) == 4


def test_region_placement_picks_the_ends_of_a_line() -> None:
    # A line of four 500 m pipes: meters at both ends tell every point from those more than
    # 120 m away (0.2 s of travel difference); an inner meter leaves the pipes beyond it alike.
    names = [f"n{i}" for i in range(5)]
    pipes = [PipeGeometry(f"p{i}", names[i], names[i + 1], 500.0) for i in range(4)]
    distances = {a: np.array([500.0 * abs(i - j) for j in range(5)]) for i, a in enumerate(names)}
    assert region_meters(pipes, names, distances, 2) == ("n0", "n4")
    assert region_meters(pipes, names, distances, 1) == ("n0",)  # peripheral


def test_region_placement_meters_the_three_arm_ends_of_a_tee(tmp_path: Path) -> None:
    # Any meter inside an arm leaves the stretch beyond it alike: the arm ends are the answer.
    tee = tmp_path / "tee.inp"
    tee.write_text(TEE_INP)
    placed = place_meters(tee, 3, method="region")
    assert placed.meters == ("A2", "B2", "D2")
    pipes, junctions, distances = _geometry(tee)
    best = _objective(pipes, junctions, distances, placed.meters)
    for other in (("A1", "B2", "D2"), ("C", "B2", "D2"), ("A2", "B1", "D1")):
        assert _objective(pipes, junctions, distances, other) > best


def test_region_placement_names_bad_input(paper15: Path) -> None:
    pipes, junctions, distances = _geometry(paper15)
    for count in (0, 16, True, 2.0):
        with pytest.raises(ConfigError, match="meter count must be between 1 and 15"):
            region_meters(pipes, junctions, distances, count)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="resolution"):
        region_meters(pipes, junctions, distances, 2, resolution=0.0)
    with pytest.raises(ConfigError, match="wave_speed"):
        region_meters(pipes, junctions, distances, 2, wave_speed=-1.0)
    with pytest.raises(ConfigError, match="grid step"):
        region_meters(pipes, junctions, distances, 2, step=0.0)
    with pytest.raises(ConfigError, match="burst sample count"):
        region_meters(pipes, junctions, distances, 2, samples=0)
    with pytest.raises(ConfigError, match="no meters"):
        ambiguous_length(pipes, (), distances)
    with pytest.raises(ConfigError, match="meter count must be between 1 and 15"):
        place_meters(paper15, 16, method="region")
    with pytest.raises(ConfigError, match="no meters"):
        meter_ambiguity(paper15, [])
    with pytest.raises(NetworkError):
        meter_ambiguity(paper15, ["N4", "nowhere"])


def test_kept_meters_stay_and_the_greedy_completes_them() -> None:
    # A meter the utility owns mid-line: the two ends are still what separates the rest.
    names = [f"n{i}" for i in range(5)]
    pipes = [PipeGeometry(f"p{i}", names[i], names[i + 1], 500.0) for i in range(4)]
    distances = {a: np.array([500.0 * abs(i - j) for j in range(5)]) for i, a in enumerate(names)}
    assert region_meters(pipes, names, distances, 2, keep=["n2"]) == ("n0", "n2", "n4")
    assert arrival_meters(pipes, names, distances, 2, keep=["n2"]) == ("n0", "n2", "n4")
    # one end owned: the other end, whatever the peripheral start would have been
    assert region_meters(pipes, names, distances, 1, keep=["n4"]) == ("n0", "n4")
    assert arrival_meters(pipes, names, distances, 1, keep=["n4"]) == ("n0", "n4")
    with pytest.raises(ConfigError, match="meter count must be between 1 and 3"):
        region_meters(pipes, names, distances, 4, keep=["n1", "n2"])
    with pytest.raises(ConfigError, match=r"kept meter\(s\) \['x'\] are not candidate"):
        region_meters(pipes, names, distances, 1, keep=["x"])
    with pytest.raises(ConfigError, match=r"kept meter\(s\) \['n1'\] listed twice"):
        arrival_meters(pipes, names, distances, 1, keep=["n1", "n1"])


@pytest.mark.parametrize("method", ["coverage", "arrival", "region"])
def test_place_meters_keeps_the_owned_meters_on_a_network_file(paper15: Path, method: str) -> None:
    placed = place_meters(paper15, 2, method=method, keep=("5", "N4"))
    assert {"N4", "5"} <= set(placed.meters) and len(placed.meters) == 4
    junctions = list(load_network(paper15).junction_name_list)
    assert list(placed.meters) == sorted(placed.meters, key=junctions.index)
    if method == "region":  # the added meters are the best the greedy finds beside the kept
        pipes, _, distances = _geometry(paper15)
        kept = _objective(pipes, junctions, distances, ("N4", "5"))
        assert _objective(pipes, junctions, distances, placed.meters) < kept


@pytest.mark.parametrize("method", ["arrival", "region"])
def test_the_scaled_placement_keeps_the_owned_meters_among_its_candidates(
    paper15: Path, method: str
) -> None:
    from burstloc.sim.placement.scaled import Scaling, spread_junctions

    wn = load_network(paper15)
    names, lengths = spread_junctions(wn, 6, first=("N4", "5"))
    assert {"N4", "5"} <= set(names) and len(names) == 6
    assert lengths["N4"][names.index("N4")] == 0.0
    scaling = Scaling(above=5, candidates=6, pipes=10, points=50)
    placed = place_meters(paper15, 2, method=method, keep=("N4", "5"), scaling=scaling)
    assert {"N4", "5"} <= set(placed.meters) and len(placed.meters) == 4


def test_the_ambiguity_profile_burst_by_burst_and_without_each_meter(paper15: Path) -> None:
    from burstloc.sim.placement.region import ambiguity_profile

    pipes, junctions, distances = _geometry(paper15)
    meters = ("N4", "N7", "1", "8")
    columns = [junctions.index(m) for m in meters]
    mine = {n: d[columns] for n, d in distances.items()}
    whole, without = ambiguity_profile(pipes, meters, mine, leave_out=True)
    assert whole.mean == pytest.approx(ambiguous_length(pipes, meters, mine), rel=1e-9)
    assert whole.weight.sum() == pytest.approx(1.0)
    grid = ambiguity_grid(pipes, meters, mine)
    # every burst is alike at least to its own segment, at most to the whole main
    assert np.all(whole.length >= grid.length[grid.bursts] - 1e-9)
    assert np.all(whole.length <= grid.length.sum() + 1e-6)
    assert whole.share_within(np.inf) == pytest.approx(1.0)
    assert min(whole.length) <= whole.median <= max(whole.length)
    assert len(without) == 4
    for i, profile in enumerate(without):
        others = meters[:i] + meters[i + 1 :]
        direct = _objective(pipes, junctions, distances, others)
        assert profile.mean == pytest.approx(direct, rel=1e-9)
        assert profile.mean >= whole.mean  # a meter never adds ambiguity
