"""The paper's localization rules (IV.B), one test per rule on small hand-made graphs."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from burstloc.exceptions import NetworkError, StreamError
from burstloc.live.stream import Step, Window
from burstloc.localize.paper_rules import (
    BurstLocator,
    Change,
    Rule,
    locate,
    node_amplitudes,
    trigger_node,
)


def tnet1_like() -> nx.DiGraph:
    """The upstream part of the paper's network, edges in flow direction.

    R1 -> N3 -> {N4, N2};  N4 -> {N2, N6};  N2 -> {N6, N5};  N6 -> N5
    """
    g = nx.DiGraph()
    for pipe, u, v in [
        ("P1", "R1", "N3"),
        ("P2", "N3", "N4"),
        ("P3", "N3", "N2"),
        ("P5", "N4", "N2"),
        ("P4", "N4", "N6"),
        ("P9", "N2", "N6"),
        ("P6", "N2", "N5"),
        ("P8", "N6", "N5"),
    ]:
        g.add_edge(u, v, pipe=pipe, flow=1.0)
    return g


METERS = ("N2", "N3", "N4", "N5", "N6")


def changes(**amps: float | tuple[float, float]) -> dict[str, list[Change]]:
    """``node=amplitude`` or ``node=(amplitude, start_time)``; every meter present."""
    out: dict[str, list[Change]] = {m: [] for m in METERS}
    for node, a in amps.items():
        amp, start = a if isinstance(a, tuple) else (a, 1.0)
        out[node] = [Change(node, start, amp)]
    return out


MEANS = {"N2": 150.0, "N3": 180.0, "N4": 160.0, "N5": 140.0, "N6": 145.0}


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


def test_localization_as_dict_is_json_ready() -> None:
    loc = locate(tnet1_like(), changes(N4=-5.0, N6=-2.0), MEANS, 2.0)
    assert loc is not None
    d = loc.as_dict()
    assert d["pipe"] == "P4" and d["rule"] == "two_alarms" and d["trigger_node"] == "N4"
    assert d["evidence"]["N4"][0]["amplitude"] == -5.0


class ThresholdDetector:
    """A stand-in detector: a meter alarms when its window range exceeds 1 m."""

    def __init__(self) -> None:
        self.calls = 0

    def detect(self, window: Window) -> dict[str, list[Change]]:
        self.calls += 1
        out: dict[str, list[Change]] = {}
        for j, m in enumerate(window.meters):
            x = window.values[:, j]
            span = float(x[-1] - x[0])
            out[m] = [Change(m, float(window.times[0]), span)] if abs(span) > 1.0 else []
        return out

    def reset(self) -> None:
        self.calls = 0


def test_burst_locator_streams_detects_and_locates() -> None:
    meters = list(METERS)
    base = np.array([MEANS[m] for m in meters])
    drop = np.array([0.0, 0.0, 3.0, 0.0, 1.5])  # N4 drops most, then N6: two alarms
    steps = [Step(0.2 * k, base - (drop if k >= 6 else 0.0)) for k in range(12)]
    locator = BurstLocator(tnet1_like(), meters, ThresholdDetector(), interval=2)
    first = locator.first(steps)
    assert first is not None
    loc = first.localization
    assert loc is not None and loc.pipe == "P4" and loc.rule is Rule.TWO_ALARMS
    assert loc.decision_time == pytest.approx(0.2 * 7)  # first window holding the drop
    assert [x.pipe for x in BurstLocator(tnet1_like(), meters, ThresholdDetector(), 2).run(steps)]
    assert locator.detector.calls == 4  # windows ending at steps 1, 3, 5, 7


def test_burst_locator_rejects_meters_outside_the_network() -> None:
    with pytest.raises(StreamError, match="'Z9' is not a junction"):
        BurstLocator(tnet1_like(), ["N2", "Z9"], ThresholdDetector(), interval=1)


def test_burst_locator_async_feed_gives_the_same_localizations() -> None:
    import asyncio

    meters = list(METERS)
    base = np.array([MEANS[m] for m in meters])
    drop = np.array([0.0, 0.0, 3.0, 0.0, 1.5])
    steps = [Step(0.2 * k, base - (drop if k >= 6 else 0.0)) for k in range(12)]

    async def feed():
        for s in steps:
            await asyncio.sleep(0)
            yield s

    async def collect():
        locator = BurstLocator(tnet1_like(), meters, ThresholdDetector(), 2)
        return [loc async for loc in locator.arun(feed())]

    got = asyncio.run(collect())
    want = list(BurstLocator(tnet1_like(), meters, ThresholdDetector(), 2).run(steps))
    assert [(x.pipe, x.decision_time) for x in got] == [(x.pipe, x.decision_time) for x in want]
    assert got
