"""Preparing the localization model offline (burstloc.sim.model.prepare): geometry, signatures."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from burstloc.constants import CANDIDATE_POSITIONS
from burstloc.exceptions import NetworkError
from burstloc.inp import network_hash
from burstloc.localize.decide import RankingLocalizers
from burstloc.network import load_network
from burstloc.sim.model.prepare import (
    arrival_geometry,
    arrival_localizer,
    connectors,
    length_graph,
    prepare_model,
    ranking_localizers,
    travel_time_spread,
    wave_fronts,
)
from burstloc.sim.signatures.compute import cached_signature_sets
from conftest import write_tiny


def test_travel_time_spread(tiny_network: Path) -> None:
    graph = length_graph(load_network(tiny_network))
    # J2 -> J4: via J3 (150 + 180) m
    assert travel_time_spread(graph, ["J2", "J4"], 1000.0) == pytest.approx(0.33)


def test_arrival_geometry_follows_the_flow_and_the_pipes(tiny_network: Path) -> None:
    pipes, distances = arrival_geometry(tiny_network, ["J2", "J4"])
    ends = {p.pipe: (p.start, p.end, p.length) for p in pipes}
    assert ends == {
        "A": ("R1", "J1", 300.0),
        "B": ("J1", "J2", 200.0),
        "C": ("J1", "J3", 250.0),
        "D": ("J2", "J3", 150.0),
        "E": ("J3", "J4", 180.0),
    }
    assert set(distances) == {"R1", "J1", "J2", "J3", "J4"}
    np.testing.assert_allclose(distances["R1"], [500.0, 730.0])  # R1-J1-J2, R1-J1-J3-J4
    np.testing.assert_allclose(distances["J2"], [0.0, 330.0])  # J2-J3-J4
    with pytest.raises(NetworkError, match="R1"):
        arrival_geometry(tiny_network, ["R1"])


def test_an_unreachable_meter_is_infinitely_far(tmp_path: Path) -> None:
    # two networks in one file: J9 hangs off its own reservoir
    inp = tmp_path / "two.inp"
    inp.write_text(
        "[JUNCTIONS]\n J1 0 1\n J2 0 1\n J9 0 1\n[RESERVOIRS]\n R1 50\n R2 50\n"
        "[PIPES]\n A R1 J1 100 200 100 0 Open\n B J1 J2 100 200 100 0 Open\n"
        " C R2 J9 100 200 100 0 Open\n"
        "[OPTIONS]\n Units LPS\n[END]\n"
    )
    _, distances = arrival_geometry(inp, ["J2", "J9"])
    assert distances["J1"][0] == 100.0 and math.isinf(distances["J1"][1])


def test_the_model_holds_geometry_and_signatures_of_the_meters(
    tiny_network: Path, tmp_path: Path
) -> None:
    meters = ["J4", "J2"]
    model = prepare_model(tiny_network, meters, cache_dir=tmp_path, wave_speed=1000.0)
    assert model.network_hash == network_hash(tiny_network)
    assert model.meters == ("J4", "J2") and model.wave_speed == 1000.0
    pipes, distances = arrival_geometry(tiny_network, meters)
    assert list(model.pipes) == pipes
    # nodes in pipe order (not a set's): the same network gives the same file, run after run
    assert list(model.node_distances) == ["R1", "J1", "J2", "J3", "J4"]
    for node, row in distances.items():
        np.testing.assert_array_equal(model.node_distances[node], row)
    sets = cached_signature_sets(tiny_network, meters, cache_dir=tmp_path)
    assert [s.params["position"] for s in model.signature_sets] == list(CANDIDATE_POSITIONS)
    for stored, cached in zip(model.signature_sets, sets, strict=True):
        assert stored.meters == ("J4", "J2")
        np.testing.assert_array_equal(stored.matrix, cached.matrix)


def test_conveniences_build_what_the_model_builds(tiny_network: Path) -> None:
    built = ranking_localizers(tiny_network, ["J1", "J3"])
    assert isinstance(built, RankingLocalizers)
    direct = arrival_localizer(tiny_network, ["J1", "J3"])
    assert built.arrival.meters == direct.meters == ("J1", "J3")
    assert built.arrival.pipes == direct.pipes
    np.testing.assert_array_equal(built.arrival._dist, direct._dist)
    assert built.signature.signatures.meters == ("J1", "J3")


def _area(diameter_mm: float) -> float:
    return math.pi * (diameter_mm / 1000.0) ** 2 / 4.0


def test_wave_fronts_follow_the_junction_transmission_along_the_shortest_path(
    tiny_network: Path,
) -> None:
    # tiny: A (300 mm) R1-J1; B, C (200 mm) J1-J2, J1-J3; D, E (150 mm) J2-J3, J3-J4 (dead end)
    wn = load_network(tiny_network)
    meters = ["J1", "J2", "J3", "J4"]
    pipes, _ = arrival_geometry(wn, meters)
    fronts = wave_fronts(wn, meters, pipes)
    a, b, d = _area(300), _area(200), _area(150)
    at_j1, at_j2, at_j3 = a + 2 * b, b + d, b + 2 * d  # cross-sections meeting at each node

    def share(entering: float, total: float) -> float:
        return 2 * entering / total

    e = dict(zip(meters, fronts["E"], strict=True))
    assert e["J4"] == pytest.approx(2.0)  # a dead end doubles the front
    assert e["J3"] == pytest.approx(share(d, at_j3))
    assert e["J2"] == pytest.approx(share(d, at_j3) * share(d, at_j2))  # J3 -> J2 along D
    assert e["J1"] == pytest.approx(share(d, at_j3) * share(b, at_j1))  # J3 -> J1 along C
    # the reservoir holds its head: a burst on A reaches the meters through J1 only
    assert fronts["A"][0] == pytest.approx(share(a, at_j1))
    assert fronts["A"][1] == pytest.approx(share(a, at_j1) * share(b, at_j2))
    # a closed pipe carries no front: with C closed, the path the arrivals are timed along
    # (J3 -> J1 by C) brings J1 nothing of E's wave, and J3 shares the front with D and E only
    from wntr.network.base import LinkStatus

    wn.get_link("C").initial_status = LinkStatus.Closed
    closed = dict(zip(meters, wave_fronts(wn, meters, pipes)["E"], strict=True))
    assert closed["J1"] == 0.0
    assert closed["J3"] == pytest.approx(share(d, 2 * d))


def test_parallel_mains_of_one_length_carry_the_front_side_by_side(tmp_path: Path) -> None:
    # F runs beside B (J1-J2, 200 m, 200 mm): a front from J2 to J1 crosses both at once
    path = write_tiny(tmp_path / "tiny.inp")
    text = path.read_text(encoding="utf-8")
    path.write_text(text.replace(" E    J3", " F    J1     J2     200     200       100\n E    J3"))
    wn = load_network(path)
    graph = length_graph(wn)
    assert graph["J1"]["J2"]["links"] == ("B", "F") and graph["J1"]["J2"]["length"] == 200
    pipes, _ = arrival_geometry(wn, ["J1"])
    fronts = wave_fronts(wn, ["J1"], pipes)
    a, b, d = _area(300), _area(200), _area(150)
    # a burst on D reaches J1 through J2 (200 m by B or F; 250 m by C from J3)
    assert fronts["D"][0] == pytest.approx(2 * d / (2 * b + d) * 2 * (2 * b) / (a + 3 * b))
    assert fronts["F"][0] == pytest.approx(fronts["B"][0])


def test_the_model_and_the_arrival_localizer_carry_the_fronts(
    tiny_network: Path, tmp_path: Path
) -> None:
    wn = load_network(tiny_network)
    pipes, _ = arrival_geometry(wn, ["J4", "J2"])
    expected = wave_fronts(wn, ["J4", "J2"], pipes)
    model = prepare_model(tiny_network, ["J4", "J2"], cache_dir=tmp_path)
    assert model.fronts is not None and set(model.fronts) == set(expected)
    for pipe, row in expected.items():
        np.testing.assert_array_equal(model.fronts[pipe], row)
    built = RankingLocalizers.from_model(model).arrival
    direct = arrival_localizer(tiny_network, ["J4", "J2"])
    np.testing.assert_array_equal(built._fronts, direct._fronts)  # type: ignore[arg-type]


def test_the_connectors_join_the_pipes_where_the_network_does(tmp_path: Path) -> None:
    """A zone behind a pressure-reducing valve: the valve is the connector, at no length; the
    pipes and the connectors join the pipes' end nodes as the whole network does (the pipes
    alone leave the zone an island), and the model and the arrival localizer carry them."""
    import networkx as nx

    inp = tmp_path / "zones.inp"
    inp.write_text(
        "[JUNCTIONS]\n J1 0 1\n J2 0 1\n J3 0 1\n J4 0 2\n[RESERVOIRS]\n R1 80\n"
        "[PIPES]\n A R1 J1 300 200 100 0 Open\n B J1 J2 300 200 100 0 Open\n"
        " C J3 J4 300 200 100 0 Open\n"
        "[VALVES]\n V J2 J3 200 PRV 40 0\n"
        "[OPTIONS]\n Units LPS\n[END]\n"
    )
    wn = load_network(inp)
    joined = connectors(wn)
    assert joined == [("J2", "J3", 0.0)]

    def parts(graph: nx.Graph) -> int:
        return nx.number_connected_components(graph.subgraph({"R1", "J1", "J2", "J3", "J4"}))

    pipes_only = nx.Graph([(wn.get_link(p).start_node_name, wn.get_link(p).end_node_name)
                           for p in wn.pipe_name_list])  # fmt: skip
    both = pipes_only.copy()
    both.add_edges_from((u, v) for u, v, _ in joined)
    assert parts(pipes_only) == 2 and parts(both) == parts(length_graph(wn)) == 1
    assert arrival_localizer(inp, ["J1", "J4"]).connectors == (("J2", "J3", 0.0),)
    model = prepare_model(inp, ["J1", "J4"], cache_dir=tmp_path / "cache")
    assert model.connectors == (("J2", "J3", 0.0),)
