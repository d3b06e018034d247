"""burstloc.experiments.paper: the paper's tables as data, consistent with each other and with
the shipped network."""

from __future__ import annotations

import inspect

import pytest

from burstloc.constants import CAPTURE_INTERVALS
from burstloc.experiments import paper
from burstloc.network import flow_direction_graph, load_network
from burstloc.sim.scenarios.scenario import BurstScenario
from conftest import PAPER15


def test_tables_i_and_ii_cover_every_capture_interval_once() -> None:
    for detector, table, prefix in (
        ("cusum", paper.TABLE_I, "S_C"),
        ("shewhart", paper.TABLE_II, "S_S"),
    ):
        assert [r.capture_interval for r in table] == list(CAPTURE_INTERVALS)
        assert {r.detector for r in table} == {detector}
        assert [r.scenario for r in table] == [f"{prefix}{k}" for k in range(1, 5)]
        assert all(r.threshold > 0 and r.localization_interval >= 1 for r in table)
    assert paper.PAPER_RUNS == paper.TABLE_I + paper.TABLE_II


def test_table_v_is_the_printed_totals_over_25_pipes_and_its_average() -> None:
    assert len(paper.PAPER_PIPES) == len(set(paper.PAPER_PIPES)) == 25
    for detector in ("cusum", "shewhart"):
        printed = paper.PRINTED_TOTALS[detector]
        assert paper.TABLE_V[detector] == tuple(100.0 * n / 25 for n in printed)
        assert paper.TABLE_V_AVERAGE[detector] == pytest.approx(
            sum(paper.TABLE_V[detector]) / len(CAPTURE_INTERVALS)
        )
    # The paper's text: CUSUM 92/72/52/64 %, Shewhart 96/72/32/60 %, averages 70 % and 65 %.
    assert paper.TABLE_V["cusum"][0] == 92.0 and paper.TABLE_V["shewhart"][0] == 96.0
    assert paper.TABLE_V_AVERAGE == {"cusum": 70.0, "shewhart": 65.0}


def test_the_tables_entries_count_fewer_correct_pipes_than_printed() -> None:
    # Counting the bold (true) entries of Tables III/IV by hand: 22/18/13/14 and 24/18/8/14.
    assert paper.published_correct("cusum") == (22, 18, 13, 14)
    assert paper.published_correct("shewhart") == (24, 18, 8, 14)
    for detector in ("cusum", "shewhart"):
        counted = paper.published_correct(detector)
        printed = paper.PRINTED_TOTALS[detector]
        assert all(c <= p <= c + 2 for c, p in zip(counted, printed, strict=True))


def test_every_published_prediction_is_a_pipe_of_the_network_in_flow_direction() -> None:
    pipes = set(paper.TRUE_PIPES.values())
    for table in (paper.TABLE_III, paper.TABLE_IV):
        assert list(table) == list(paper.PAPER_PIPES)
        for row in table.values():
            assert len(row) == len(CAPTURE_INTERVALS)
            assert set(row) <= pipes
    graph = flow_direction_graph(load_network(PAPER15))
    directed = {d["pipe"]: f"{u} - {v}" for u, v, d in graph.edges(data=True)}
    assert {p: directed[p] for p in paper.PAPER_PIPES} == paper.TRUE_PIPES


def test_published_prediction_reads_the_tables_by_capture_interval() -> None:
    for k, ci in enumerate(CAPTURE_INTERVALS):
        assert paper.published_prediction("cusum", "P3", ci) == paper.TABLE_III["P3"][k]
        assert paper.published_prediction("shewhart", "17", ci) == paper.TABLE_IV["17"][k]
    assert paper.published_prediction("cusum", "P1", 2.0) == "N7 - 7"
    with pytest.raises(ValueError):
        paper.published_prediction("cusum", "P1", 3.0)


def test_scenario_parameters_are_burst_scenario_fields() -> None:
    fields = inspect.signature(BurstScenario).parameters
    params = paper.SCENARIO.parameters()
    assert set(params) <= set(fields)
    scenario = BurstScenario(str(PAPER15), "P4", **{**params, "duration": 20.0})
    assert (scenario.burst_start, scenario.opening_time, scenario.burst_coeff) == (10.0, 0.3, 0.02)
    assert paper.SCENARIO.duration is None  # chosen by the evaluation from its runs
