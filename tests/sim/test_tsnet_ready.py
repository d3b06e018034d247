"""burstloc.sim.transient.tsnet_ready: a pump into a junction where pipes branch gets a connector
pipe, and
the network then starts steady under TSNet (it does not without one); a supply junction (a
negative demand) becomes a fixed inflow, and a burst near it then stays bounded (it does not as
TSNet models it)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from burstloc import network
from burstloc._diagnostics import capture_diagnostics
from burstloc.exceptions import SimulationError
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.steady import STEADY_TOLERANCE, steady_start
from burstloc.sim.transient.time_step import expected_time_step
from burstloc.sim.transient.tsnet import simulate_burst
from burstloc.sim.transient.tsnet_ready import (
    Connector,
    SupplyBoundary,
    add_connectors,
    prepare_for_tsnet,
    supply_junctions,
)
from burstloc.sim.transient.tsnet_run import TransientSettings, isolated_run, run_transient
from conftest import REPO

#: A pump from a reservoir into J1, where pipes A and B branch; a five-point pump curve
#: (EPANET's multi-point curve, which TSNet 0.3.1 alone refuses).
PUMP_AT_BRANCH_INP = """\
[JUNCTIONS]
 J1  0  0
 J2  0  10
 J3  0  10

[RESERVOIRS]
 R1  10

[PIPES]
 A  J1  J2  300  250  100  0  Open
 B  J1  J3  350  250  100  0  Open
 C  J2  J3  400  150  100  0  Open

[PUMPS]
 P1  R1  J1  HEAD 1

[CURVES]
 1  0  60
 1  10  58
 1  20  54
 1  30  47
 1  40  38

[OPTIONS]
 Units  LPS
 Headloss  H-W

[END]
"""


@pytest.fixture
def pump_at_branch(tmp_path: Path) -> Path:
    path = tmp_path / "pump_at_branch.inp"
    path.write_text(PUMP_AT_BRANCH_INP, encoding="utf-8")
    return path


def test_a_pump_into_a_branch_gets_one_connector(pump_at_branch: Path) -> None:
    wn = network.load_network(pump_at_branch)
    added = add_connectors(wn)
    assert added == [Connector("P1", "J1", "P1_E", "P1_EP", 300.0, 0.25)]
    pump = wn.get_link("P1")
    assert (pump.start_node_name, pump.end_node_name) == ("R1", "P1_E")
    assert sorted(wn.get_links_for_node("J1")) == ["A", "B", "P1_EP"]
    assert wn.get_node("P1_E").elevation == wn.get_node("J1").elevation
    assert add_connectors(wn) == []  # nothing left to mend


def test_pumps_and_valves_between_single_pipes_need_none() -> None:
    wn = network.load_network(REPO / "networks" / "paper15_assets.inp")
    assert wn.num_pumps == 1 and wn.num_valves == 1
    assert add_connectors(wn) == []


def _pre_event_movement(path: Path, prepare: Callable[[Any], object] | None) -> float:
    """The largest head movement over 2 s of TSNet with no event, after ``prepare(network)``."""
    source = os.path.abspath(path)
    with isolated_run() as tmp:
        wn = network.load_network(source)
        meters = network.junction_names(wn)
        if prepare is not None:
            prepare(wn)
        settings = TransientSettings(1200.0, 2.0, None, "PDD", "steady")
        steps, heads, _ = run_transient(
            wn, meters, os.path.join(tmp, "n.inp"), settings, lambda tm: None, where=source
        )
    return steady_start(steps, heads, meters, onset=2.0).movement


def test_tsnet_starts_steady_only_with_the_connector(pump_at_branch: Path) -> None:
    assert _pre_event_movement(pump_at_branch, None) > 1.0  # 7.2 m at J3
    assert _pre_event_movement(pump_at_branch, prepare_for_tsnet) < STEADY_TOLERANCE  # 0.1 mm


def test_a_burst_simulation_records_its_connectors(pump_at_branch: Path) -> None:
    scenario = BurstScenario(pump_at_branch, "C", burst_start=1.0, duration=2.0)
    result = simulate_burst(scenario)
    assert result.time_step == pytest.approx(expected_time_step(scenario), rel=1e-12)
    assert [c["junction"] for c in result.metadata["connectors"]] == ["P1_E"]
    assert result.metadata["steady_start"]["max_movement_m"] < STEADY_TOLERANCE
    assert list(result.junctions) == ["J1", "J2", "J3"]  # the connector junction is no meter
    # Nodes the simulation added are named as a user knows them; the network's keep their names.
    assert result.node_label("P1_E") == "the junction added between link P1 and node J1"
    assert result.node_label(result.metadata["burst_node"]) == "the burst point on pipe C"
    assert result.node_label("J2") == "J2"


def test_a_closed_pipe_is_removed_and_the_start_is_steady(tmp_path: Path) -> None:
    closed = tmp_path / "closed_pipe.inp"
    closed_pipe = " D  J1  J3  200  150  100  0  Closed\n"
    closed.write_text(
        PUMP_AT_BRANCH_INP.replace("\n[PUMPS]", closed_pipe + "\n[PUMPS]"), encoding="utf-8"
    )
    wn = network.load_network(closed)
    prepared = prepare_for_tsnet(wn)
    assert prepared.removed_closed_links == ["D"] and "D" not in wn.link_name_list
    assert [c.link for c in prepared.connectors] == ["P1"]
    # TSNet lets water through the closed pipe: with the connector alone J3 moves 4.7 cm
    assert _pre_event_movement(closed, add_connectors) > 0.02
    assert _pre_event_movement(closed, prepare_for_tsnet) < 0.005  # removed: 0.1 mm


def test_a_closed_pump_is_removed_unless_it_is_kept(tmp_path: Path) -> None:
    closed = tmp_path / "closed_pump.inp"
    text = PUMP_AT_BRANCH_INP.replace(" R1  10\n", " R1  10\n R2  100\n")
    text = text.replace(" P1  R1  J1  HEAD 1\n", " P1  R1  J1  HEAD 1\n P2  R2  J3  HEAD 1\n")
    text = text.replace("[OPTIONS]", "[STATUS]\n P2  Closed\n\n[OPTIONS]\n Quality  Trace R2")
    closed.write_text(text, encoding="utf-8")
    wn = network.load_network(closed)
    prepared = prepare_for_tsnet(wn)
    assert prepared.removed_closed_links == ["P2"]
    assert "R2" not in wn.node_name_list  # left with no link
    assert wn.options.quality.parameter == "NONE"  # R2 was the trace node (as Net3's Lake)
    assert [c.link for c in prepared.connectors] == ["P1"]
    kept = network.load_network(closed)
    assert prepare_for_tsnet(kept, keep=("P2",)).removed_closed_links == []
    # a closed pump holding back a reservoir above J3: TSNet runs it on its curve, and with the
    # connectors alone J3 moves by metres
    assert _pre_event_movement(closed, add_connectors) > 1.0
    assert _pre_event_movement(closed, prepare_for_tsnet) < STEADY_TOLERANCE


#: Net2's supply in small: junction S takes in 40 L/s x 0.9 (its pattern at the start), the
#: tank T is the only fixed head, and the demands of J1-J3 (25 L/s) leave 11 L/s to fill it.
SUPPLY_INP = """\
[JUNCTIONS]
 S   0  -40  2
 J1  5   10
 J2  8   10
 J3  6    5

[TANKS]
 T   40  10  0  20  15  0

[PIPES]
 P1  S   J1  600  300  100  0  Open
 P2  J1  J2  400  250  100  0  Open
 P3  J2  J3  300  200  100  0  Open
 P4  J1  J3  500  200  100  0  Open
 P5  J3  T   200  300  100  0  Open

[PATTERNS]
 2  0.9  1.0

[OPTIONS]
 Units  LPS
 Headloss  H-W
 Required Pressure  0.1

[END]
"""


@pytest.fixture
def supply(tmp_path: Path) -> Path:
    path = tmp_path / "supply.inp"
    path.write_text(SUPPLY_INP, encoding="utf-8")
    return path


def _steady_heads(wn: Any) -> dict[str, float]:
    """EPANET's (pressure-driven) heads at the start, by node."""
    import wntr

    wn.options.hydraulic.demand_model = "PDD"
    with isolated_run():
        heads = wntr.sim.EpanetSimulator(wn).run_sim().node["head"].loc[0]
    return {name: float(head) for name, head in heads.items()}


def test_a_supply_junction_becomes_a_fixed_inflow_with_the_same_steady_state(
    supply: Path,
) -> None:
    wn = network.load_network(supply)
    assert supply_junctions(wn) == {"S": pytest.approx(0.036)}  # 40 L/s x 0.9
    before = _steady_heads(wn)
    prepared = prepare_for_tsnet(wn)
    assert prepared.supply_boundaries == [SupplyBoundary("S", "S_S", "S_SV", pytest.approx(0.036))]
    assert prepared.connectors == []  # S joins one pipe; S_S is the network's edge
    assert wn.get_node("S").demand_timeseries_list.at(0.0) == 0.0
    assert wn.get_node("S_S").demand_timeseries_list.at(0.0) == pytest.approx(-0.036)
    assert wn.get_node("S_S").elevation == wn.get_node("S").elevation
    valve = wn.get_link("S_SV")
    assert (valve.valve_type, valve.initial_status.name) == ("TCV", "Open")
    assert (valve.start_node_name, valve.end_node_name) == ("S_S", "S")
    assert valve.diameter == pytest.approx(0.3)  # P1, the widest pipe at S
    after = _steady_heads(wn)
    for name, head in before.items():
        assert after[name] == pytest.approx(head, abs=1e-3)
    assert supply_junctions(wn) == {"S_S": pytest.approx(0.036)}  # the inflow, moved
    kept = network.load_network(supply)
    assert prepare_for_tsnet(kept, keep=("S",)).supply_boundaries == []


def _burst_pressures(
    path: Path, prepare: Callable[[Any], object], also: tuple[str, ...] = ()
) -> tuple[Any, list[str]]:
    """Pressure heads (T, M) of the junctions and the nodes ``also`` in a 20 s run of TSNet's own
    solver (these tests show what TSNet does with each preparation) with a
    burst mid-P3 from 1 s (coefficient 0.002, about 13 L/s), after ``prepare(network)``, and
    the junctions TSNet reported at negative pressure."""
    source = os.path.abspath(path)
    with isolated_run() as tmp, capture_diagnostics() as diag:
        wn = network.load_network(source)
        meters = [*network.junction_names(wn), *also]
        split = network.split_pipe(wn, "P3", 0.5)
        prepare(split.network)
        settings = TransientSettings(1200.0, 20.0, None, "PDD", "steady", "tsnet")
        _, heads, _ = run_transient(
            split.network,
            meters,
            os.path.join(tmp, "n.inp"),
            settings,
            lambda tm: tm.add_burst(split.burst_node, 1.0, 0.5, 0.002),
            where=source,
        )
    return heads, diag.negative_pressure_nodes()


def test_a_burst_near_a_supply_stays_bounded_only_as_a_fixed_inflow(supply: Path) -> None:
    # TSNet's own model, k sqrt(p) with k < 0, amplifies every wave reaching S: heads swing to
    # 119 m from 51 m and J1, J2 and S go below zero pressure
    heads, negative = _burst_pressures(supply, add_connectors)
    assert heads.max() > heads[0].max() + 40.0
    assert {"J1", "J2"} <= set(negative)
    # a fixed inflow: the burst lowers every head (by at most 14 m), nothing rises past 58 m
    heads, negative = _burst_pressures(supply, prepare_for_tsnet)
    assert heads.max() < heads[0].max() + 10.0
    assert heads.min() > 20.0
    assert negative == []


def test_a_supply_at_a_branch_gets_a_connector_and_starts_steady(tmp_path: Path) -> None:
    branch = tmp_path / "supply_branch.inp"
    text = SUPPLY_INP.replace(" P5  J3  T", " P6  S   J2  700  200  100  0  Open\n P5  J3  T")
    branch.write_text(text, encoding="utf-8")
    wn = network.load_network(branch)
    prepared = prepare_for_tsnet(wn)
    assert [s.junction for s in prepared.supply_boundaries] == ["S"]
    assert [(c.link, c.node) for c in prepared.connectors] == [("S_SV", "S")]
    assert _pre_event_movement(branch, prepare_for_tsnet) < STEADY_TOLERANCE


def test_a_burst_simulation_records_its_supplies(supply: Path) -> None:
    result = simulate_burst(BurstScenario(supply, "P3", burst_start=1.0, duration=2.0))
    assert [s["junction"] for s in result.metadata["supply_boundaries"]] == ["S"]
    assert list(result.junctions) == ["S", "J1", "J2", "J3"]  # the source is no meter


#: A reservoir R feeds J1; the tank T is joined by two pipes (P4, P5), which TSNet 0.3.1 solves
#: as a junction with a pressure-dependent demand instead of a fixed head.
TANK_AT_BRANCH_INP = """\
[JUNCTIONS]
 J1  5   10
 J2  8   10
 J3  6    5

[RESERVOIRS]
 R  60

[TANKS]
 T   40  10  0  20  15  0

[PIPES]
 P1  R   J1  600  300  100  0  Open
 P2  J1  J2  400  250  100  0  Open
 P3  J2  J3  300  200  100  0  Open
 P4  J1  T   500  200  100  0  Open
 P5  J3  T   200  300  100  0  Open

[OPTIONS]
 Units  LPS
 Headloss  H-W
 Required Pressure  0.1

[END]
"""


def test_a_tank_at_a_branch_gets_a_connector_and_holds_its_head(tmp_path: Path) -> None:
    path = tmp_path / "tank_at_branch.inp"
    path.write_text(TANK_AT_BRANCH_INP, encoding="utf-8")
    wn = network.load_network(path)
    assert add_connectors(wn) == [Connector("T", "T", "T_C", "T_CP", 200.0, 0.3)]
    assert sorted(wn.get_links_for_node("T_C")) == ["P4", "P5", "T_CP"]
    assert wn.get_links_for_node("T") == ["T_CP"]
    assert wn.get_node("T_C").elevation == wn.get_node("T").elevation
    # as TSNet has it, the 15 m wide tank's level falls by metres within seconds
    heads, _ = _burst_pressures(path, lambda wn: None, also=("T",))
    assert abs(heads[:, -1] - heads[0, -1]).max() > 1.0
    heads, _ = _burst_pressures(path, prepare_for_tsnet, also=("T",))
    assert abs(heads[:, -1] - heads[0, -1]).max() < 1e-6


def test_a_reservoir_at_a_branch_gets_a_connector_and_runs(tmp_path: Path) -> None:
    path = tmp_path / "reservoir_at_branch.inp"
    text = TANK_AT_BRANCH_INP.replace(" P5  J3", " P6  R   J2  700  200  100  0  Open\n P5  J3")
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SimulationError, match="'Reservoir' object has no attribute 'elevation'"):
        _burst_pressures(path, lambda wn: None)
    wn = network.load_network(path)
    assert [(c.link, c.node) for c in prepare_for_tsnet(wn).connectors] == [("T", "T"), ("R", "R")]
    assert wn.get_node("R_C").elevation == 5.0  # J1, the lower of R's neighbours
    assert _pre_event_movement(path, prepare_for_tsnet) < STEADY_TOLERANCE
