"""burstloc.sim.signatures.burst_size: a burst sized by its flow, on shipped networks (real
EPANET steady states)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from burstloc._diagnostics import capture_diagnostics
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.network import load_network, steady_state
from burstloc.sim.scenarios.scenario import burst_scenarios
from burstloc.sim.signatures.burst_size import (
    DEFAULT_BURST,
    BurstFlow,
    burst_point_pressure,
    burst_sizes,
    coeff_for_flow,
    sized_scenarios,
)
from burstloc.sim.signatures.epanet_inplace import InPlaceSplitter, split_elevation

NETWORKS = Path(__file__).resolve().parents[2] / "networks"


def test_a_flow_maps_to_the_coefficient_that_draws_it() -> None:
    assert coeff_for_flow(0.01, 25.0) == pytest.approx(0.002)
    for flow in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ConfigError, match="burst flow must be a positive number"):
            coeff_for_flow(flow, 25.0)
    with pytest.raises(ConfigError, match="no positive pressure"):
        coeff_for_flow(0.01, -0.5)


@pytest.mark.parametrize(
    ("network", "pipe", "position"),
    [("paper15.inp", "P7", 0.5), ("paper15.inp", "15", 0.2), ("public/Net1.inp", "110", 0.7)],
)
def test_the_burst_points_pressure_is_epanets_at_the_split_junction(
    network: str, pipe: str, position: float
) -> None:
    # EPANET itself, the pipe split at the point by a junction without a burst (a tiny emitter)
    wn = load_network(NETWORKS / network)
    heads = steady_state(wn).heads
    with capture_diagnostics(), InPlaceSplitter(wn) as splitter:
        (split,) = splitter.split_heads(pipe, position, 1e-12, ["~burst~"])
    expected = split - split_elevation(wn.get_link(pipe), position)
    assert burst_point_pressure(wn, heads, pipe, position) == pytest.approx(expected, abs=0.01)
    with pytest.raises(NetworkError, match="unknown pipe 'nope'"):
        burst_point_pressure(wn, heads, "nope", position)
    with pytest.raises(ConfigError, match="strictly between 0 and 1"):
        burst_point_pressure(wn, heads, pipe, 1.0)


def test_bursts_sized_by_flow_draw_it_and_a_larger_one_lowers_the_pressures_more() -> None:
    wn = load_network(NETWORKS / "public" / "Net1.inp")
    pipes = ["10", "110", "122"]
    small = burst_sizes(wn, pipes, 0.5, flow=0.005, check=True)
    large = burst_sizes(wn, pipes, 0.5, flow=0.05, check=True)
    base = steady_state(wn).heads
    lowest = min(base[j] - wn.get_node(j).elevation for j in wn.junction_name_list)
    for s, b in zip(small, large, strict=True):
        assert s.flow_lps == pytest.approx(5.0) and b.flow_lps == pytest.approx(50.0)
        assert s.coeff * math.sqrt(s.pressure) == pytest.approx(0.005)
        assert s.pressure == pytest.approx(b.pressure)  # the same point before the burst
        assert b.lowest_pressure is not None and s.lowest_pressure is not None
        assert b.lowest_pressure < s.lowest_pressure <= lowest + 1e-6
        assert s.lowest_junction in wn.junction_name_list
        assert s.below_zero == b.below_zero == 0  # Net1 keeps its pressures at 50 L/s
    # a burst far beyond what the network can feed (3 m^3/s, 43 times its demand) draws less as
    # the pressure falls: the steady state holds its lowest junction just above zero
    (huge,) = burst_sizes(wn, ["121"], 0.5, flow=3.0, check=True)
    assert huge.lowest_pressure is not None and 0.0 <= huge.lowest_pressure < 3.0
    assert huge.below_zero == 0
    by_coeff = burst_sizes(wn, pipes, 0.5, coeff=0.02)
    assert [x.lowest_pressure for x in by_coeff] == [None] * 3
    assert by_coeff[0].flow == pytest.approx(0.02 * math.sqrt(by_coeff[0].pressure))
    with pytest.raises(ConfigError, match="one of them"):
        burst_sizes(wn, pipes, 0.5, coeff=0.02, flow=0.01)
    with pytest.raises(ConfigError, match="one of them"):
        burst_sizes(wn, pipes, 0.5)


def test_scenarios_sized_by_flow_get_each_pipes_coefficient(paper15: Path) -> None:
    scenarios = burst_scenarios(paper15, ["P7", "15"], position=0.3)
    same, sizes = sized_scenarios(scenarios)
    assert same == scenarios
    assert [s.coeff for s in sizes] == [x.burst_coeff for x in scenarios]
    sized, sizes = sized_scenarios(scenarios, 0.012)
    assert [s.pipe for s in sized] == ["P7", "15"]
    for scenario, size in zip(sized, sizes, strict=True):
        assert scenario.burst_coeff == size.coeff == pytest.approx(0.012 / np.sqrt(size.pressure))
        assert scenario.position == size.position == 0.3
    assert sizes[0].coeff != sizes[1].coeff  # each pipe's own pressure


def test_the_default_burst_is_a_share_of_the_demand_capped() -> None:
    from burstloc.constants import BURST_FLOW, BURST_SHARE

    # awumah11: 12 junctions of 5 L/s (55 L/s with its pressure-driven demand): 5 % is below
    # the cap; paper15 (248 L/s): capped at 5 L/s
    small = NETWORKS / "awumah11.inp"
    demand = sum(q for q in steady_state(load_network(small)).demands.values() if q > 0)
    assert 0.05 < demand < 0.1
    (_, pipe) = load_network(small).pipe_name_list[:2]
    _, (size,) = sized_scenarios(burst_scenarios(small, [pipe]), DEFAULT_BURST)
    assert size.flow == pytest.approx(BURST_SHARE * demand) and size.flow < BURST_FLOW
    _, (capped,) = sized_scenarios(burst_scenarios(NETWORKS / "paper15.inp", ["P7"]), DEFAULT_BURST)
    assert capped.flow == pytest.approx(BURST_FLOW)
    assert DEFAULT_BURST.describe() == "5 % of the network's demand, at most 5 L/s"
    assert BurstFlow(share=0.01).of(0.248) == pytest.approx(0.00248)
    assert BurstFlow(flow=0.002).of(10.0) == 0.002
    with pytest.raises(ConfigError, match="draws no water"):
        DEFAULT_BURST.of(0.0)
    with pytest.raises(ConfigError, match="one of them"):
        BurstFlow(flow=0.001, share=0.05)
    with pytest.raises(ConfigError, match=r"share of the demand must be in \(0, 1\]"):
        BurstFlow(share=1.5)
    with pytest.raises(ConfigError, match="cap must be a positive number"):
        BurstFlow(share=0.05, cap=-1.0)
