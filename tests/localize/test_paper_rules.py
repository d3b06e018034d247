"""The paper's localization rules (IV.B), one test per rule on small hand-made graphs."""

from __future__ import annotations

import networkx as nx
import pytest

from burstloc.exceptions import NetworkError
from burstloc.localize.evidence import Change
from burstloc.localize.paper_rules import Rule, locate, node_amplitudes, trigger_node
from paper_graph import MEANS, METERS, changes, tnet1_like


def test_nothing_alarmed_decides_nothing() -> None:
    assert locate(tnet1_like(), changes(), MEANS, 2.0) is None
    assert trigger_node(changes()) is None


def test_trigger_is_the_largest_absolute_amplitude() -> None:
    ch = changes(N4=3.0, N6=-4.0, N5=-1.0)
    ch["N4"].append(Change("N4", 1.2, -3.5))
    assert node_amplitudes(ch) == {"N4": 3.5, "N6": 4.0, "N5": 1.0}
    assert trigger_node(ch) == "N6"


def test_rule_two_alarms_takes_the_alarmed_neighbour() -> None:
    loc = locate(tnet1_like(), changes(N4=-5.0, N6=-2.0), MEANS, 2.0, order=METERS)
    assert loc is not None
    assert (loc.pipe, loc.start_node, loc.end_node) == ("P4", "N4", "N6")
    assert loc.rule is Rule.TWO_ALARMS and loc.trigger_node == "N4"
    assert loc.decision_time == 2.0
    assert set(loc.evidence) == {"N4", "N6"}
    assert loc.evidence["N6"][0].amplitude == -2.0


def test_rule_two_alarms_needs_exactly_two() -> None:
    # Three alarms: the neighbour rule does not apply; N4's single predecessor decides.
    loc = locate(tnet1_like(), changes(N4=-5.0, N6=-2.0, N5=-1.0), MEANS, 2.0)
    assert loc is not None
    assert (loc.pipe, loc.rule) == ("P2", Rule.SINGLE_PREDECESSOR)


def test_rule_two_alarms_with_a_predecessor_gives_the_same_pipe() -> None:
    # The other alarmed node is upstream, not a (successor) neighbour: the predecessor rules
    # name the same pipe an undirected reading of "neighbour" would.
    loc = locate(tnet1_like(), changes(N2=-5.0, N4=-2.0), MEANS, 2.0)
    assert loc is not None
    assert (loc.pipe, loc.start_node, loc.end_node) == ("P5", "N4", "N2")
    assert loc.rule is Rule.ALARMED_PREDECESSOR


def test_rule_single_predecessor_may_be_the_reservoir() -> None:
    loc = locate(tnet1_like(), changes(N3=-6.0, N2=-3.0, N4=-2.0), MEANS, 2.0)
    assert loc is not None
    assert (loc.pipe, loc.start_node, loc.end_node) == ("P1", "R1", "N3")
    assert loc.rule is Rule.SINGLE_PREDECESSOR


def test_rule_alarmed_predecessor_with_largest_amplitude() -> None:
    loc = locate(tnet1_like(), changes(N2=-6.0, N3=-1.0, N4=2.5, N6=-2.0), MEANS, 2.0)
    assert loc is not None
    assert (loc.pipe, loc.start_node, loc.end_node) == ("P5", "N4", "N2")
    assert loc.rule is Rule.ALARMED_PREDECESSOR


def test_rule_lowest_mean_pressure_predecessor() -> None:
    # N5's predecessors N2 and N6 did not alarm; N6 has the lower mean pressure.
    loc = locate(tnet1_like(), changes(N5=-6.0, N3=-1.0, N4=-1.0), MEANS, 2.0)
    assert loc is not None
    assert (loc.pipe, loc.start_node, loc.end_node) == ("P8", "N6", "N5")
    assert loc.rule is Rule.LOWEST_MEAN_PRESSURE
    means = dict(MEANS, N6=155.0)
    loc = locate(tnet1_like(), changes(N5=-6.0, N3=-1.0, N4=-1.0), means, 2.0)
    assert loc is not None and loc.pipe == "P6"


def test_lowest_mean_ignores_unmetered_predecessors() -> None:
    g = tnet1_like()
    g.add_edge("T1", "N5", pipe="PT", flow=1.0)  # a tank feeding N5: no meter, no mean
    loc = locate(g, changes(N5=-6.0, N3=-1.0, N4=-1.0), MEANS, 2.0)
    assert loc is not None and loc.start_node == "N6"


def test_ties_break_by_earliest_start_then_meter_order() -> None:
    ch = changes(N4=(-5.0, 1.4), N6=(5.0, 1.2), N5=-1.0)
    assert trigger_node(ch, METERS) == "N6"
    ch = changes(N4=(-5.0, 1.2), N6=(5.0, 1.2), N5=-1.0)
    assert trigger_node(ch, METERS) == "N4"
    assert trigger_node(ch, ("N6", "N4", "N5")) == "N6"
    # equal alarmed predecessors: meter order
    loc = locate(tnet1_like(), changes(N2=-6.0, N3=-2.0, N4=-2.0, N5=-1.0), MEANS, 2.0)
    assert loc is not None and loc.start_node == "N3"
    # equal means: meter order
    means = dict(MEANS, N2=145.0)
    loc = locate(tnet1_like(), changes(N5=-6.0, N3=-1.0, N4=-1.0), means, 2.0, order=METERS)
    assert loc is not None and loc.start_node == "N2"


def test_no_predecessor_decides_nothing() -> None:
    g = nx.DiGraph()
    g.add_edge("A", "B", pipe="1")
    g.add_edge("A", "C", pipe="2")
    assert (
        locate(
            g,
            {
                "A": [Change("A", 0.0, -3.0)],
                "C": [Change("C", 0.0, -1.0)],
                "B": [Change("B", 0.0, -1.0)],
            },
            {},
            1.0,
        )
        is None
    )


def test_several_unmetered_unalarmed_predecessors_decide_nothing() -> None:
    g = nx.DiGraph()
    g.add_edge("R1", "A", pipe="1")
    g.add_edge("R2", "A", pipe="2")
    g.add_edge("A", "B", pipe="3")
    g.add_edge("B", "C", pipe="4")
    ch = {
        "A": [Change("A", 0.0, -3.0)],
        "B": [Change("B", 0.0, -1.0)],
        "C": [Change("C", 0.0, -1.0)],
    }
    assert locate(g, ch, {"A": 1.0, "B": 1.0, "C": 1.0}, 1.0) is None


def test_unknown_node_and_missing_pipe_attribute_are_network_errors() -> None:
    with pytest.raises(NetworkError, match="'X'"):
        locate(tnet1_like(), {"X": [Change("X", 0.0, -1.0)]}, {}, 0.0)
    g = nx.DiGraph()
    g.add_edge("A", "B")
    with pytest.raises(NetworkError, match="no 'pipe'"):
        locate(g, {"B": [Change("B", 0.0, -1.0)]}, {}, 0.0)


def test_multidigraph_edges_are_supported() -> None:
    g = nx.MultiDiGraph(tnet1_like())
    loc = locate(g, changes(N3=-6.0), MEANS, 2.0)
    assert loc is not None and loc.pipe == "P1"


def test_parallel_links_name_a_pipe_then_the_larger_flow() -> None:
    # N3's only predecessor R1 is joined to it by P1 and, beside it, a valve and a smaller main
    g = nx.MultiDiGraph(tnet1_like())
    g.add_edge("R1", "N3", key="V1", pipe="V1", flow=9.0, link_type="valve")
    g.add_edge("R1", "N3", key="P1b", pipe="P1b", flow=0.001, link_type="pipe")
    g.edges["R1", "N3", 0]["flow"] = 0.5  # P1, keyed 0 by the conversion
    loc = locate(g, changes(N3=-6.0), MEANS, 2.0)
    assert loc is not None and (loc.pipe, loc.rule) == ("P1", Rule.SINGLE_PREDECESSOR)
    g.edges["R1", "N3", "P1b"]["flow"] = 1.0
    loc = locate(g, changes(N3=-6.0), MEANS, 2.0)
    assert loc is not None and loc.pipe == "P1b"


def test_localization_as_dict_is_json_ready() -> None:
    loc = locate(tnet1_like(), changes(N4=-5.0, N6=-2.0), MEANS, 2.0)
    assert loc is not None
    d = loc.as_dict()
    assert d["pipe"] == "P4" and d["rule"] == "two_alarms" and d["trigger_node"] == "N4"
    assert d["evidence"]["N4"][0]["amplitude"] == -5.0
