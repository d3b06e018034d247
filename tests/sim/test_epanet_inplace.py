"""One EPANET project edited in place agrees with a copied, split model solved from scratch."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.network import load_network, split_pipe, steady_state
from burstloc.sim.signatures.epanet_inplace import InPlaceSplitter

REPO = Path(__file__).resolve().parents[2]

# The reference heads come from EPANET's binary output file, which stores single-precision
# floats: at 60-250 m of head that is 4e-6 - 3e-5 m of rounding per head, twice that per drop.
ATOL = 1e-4  # m


def _reference_drops(wn: object, pipe: str, fraction: float, coeff: float) -> dict[str, float]:
    base = steady_state(wn).heads  # type: ignore[arg-type]
    split = split_pipe(wn, pipe, fraction)  # type: ignore[arg-type]
    split.network.get_node(split.burst_node).emitter_coefficient = coeff
    heads = steady_state(split.network).heads
    return {n: base[n] - heads[n] for n in wn.junction_name_list}  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("network", "fraction"),
    [
        ("paper15.inp", 0.5),
        ("paper15.inp", 0.1),
        ("awumah11.inp", 0.9),
        ("paper15_assets.inp", 0.3),
    ],
)
def test_split_heads_match_a_copied_model_on_every_pipe(network: str, fraction: float) -> None:
    wn = load_network(REPO / "networks" / network)
    junctions = list(wn.junction_name_list)
    nodes_before = list(wn.node_name_list)
    largest = 0.0
    with InPlaceSplitter(wn) as splitter:
        base = splitter.heads(junctions)
        for pipe in wn.pipe_name_list:
            drops = base - splitter.split_heads(pipe, fraction, 0.01, junctions)
            expected = _reference_drops(wn, pipe, fraction, 0.01)
            np.testing.assert_allclose(drops, [expected[n] for n in junctions], rtol=0, atol=ATOL)
            largest = max(largest, float(np.max(drops)))
        # every edit was undone: the unmodified network's heads again
        np.testing.assert_allclose(splitter.heads(junctions), base, rtol=0, atol=1e-9)
    assert largest > 0.1  # the bursts moved the heads, so the comparison means something
    assert list(wn.node_name_list) == nodes_before  # the model itself is untouched


def test_a_check_valve_pipe_and_the_reservoir_end(tiny_network: Path) -> None:
    text = tiny_network.read_text(encoding="utf-8")
    tiny_network.write_text(text.replace("0          Open\n C", "0          CV\n C"), "utf-8")
    wn = load_network(tiny_network)
    assert wn.get_link("B").check_valve
    junctions = list(wn.junction_name_list)
    with InPlaceSplitter(wn) as splitter:
        base = splitter.heads(junctions)
        for pipe, fraction in (("A", 0.3), ("B", 0.6), ("E", 0.5)):  # A starts at the reservoir
            drops = base - splitter.split_heads(pipe, fraction, 0.004, junctions)
            expected = _reference_drops(wn, pipe, fraction, 0.004)
            np.testing.assert_allclose(drops, [expected[n] for n in junctions], rtol=0, atol=ATOL)


def test_bad_pipe_or_position_is_refused(tiny_network: Path) -> None:
    wn = load_network(tiny_network)
    with InPlaceSplitter(wn) as splitter:
        with pytest.raises(NetworkError, match="unknown pipe 'Z'"):
            splitter.split_heads("Z", 0.5, 0.01, ["J1"])
        with pytest.raises(ConfigError, match="position"):
            splitter.split_heads("A", 1.0, 0.01, ["J1"])
        with pytest.raises(NetworkError, match="unknown node 'Q'"):
            splitter.heads(["Q"])
    with pytest.raises(ConfigError, match="engine"):
        InPlaceSplitter(wn, engine="XX")
    # a name the spare junction needs is taken: refused, the model as it was
    wn.add_junction("~burst~", base_demand=0.0, elevation=0.0)
    before = (wn.options.hydraulic.demand_model, wn.options.time.duration, wn.num_nodes)
    with pytest.raises(NetworkError, match="no element named '~burst~'"), InPlaceSplitter(wn):
        pass
    assert (wn.options.hydraulic.demand_model, wn.options.time.duration, wn.num_nodes) == before
