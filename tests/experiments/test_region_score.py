"""Search regions scored as a utility scores them (burstloc.experiments.region_score): on the
line network's posteriors, and through ``burstloc evaluate`` on the tiny network (real TSNet)."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from burstloc.experiments import paper
from burstloc.experiments.evaluate import evaluate
from burstloc.experiments.harness import Attempt
from burstloc.experiments.position import PipePoint, PositionOutcome
from burstloc.experiments.region_score import (
    RegionOutcome,
    RegionScores,
    region_cells,
    score_region,
)
from burstloc.experiments.report import format_tables
from burstloc.experiments.runs import RunSpec
from burstloc.localize.decide import Decision
from burstloc.localize.detection import DetectorConfig
from burstloc.localize.evidence import BurstEvidence, MeterAlarm, Ranking
from burstloc.localize.region import posterior
from line_network import METERS, WAVE, line_arrival

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())


def _decision(x: float, heard: tuple[str, ...], at: float) -> Decision:
    """The answer at reading time ``at`` to a burst at ``x`` m along the line at t = 1 s, heard
    by the meters ``heard`` (alarms stamped to 0.05 s)."""
    alarms = {
        m: MeterAlarm(m, np.floor((1.0 + abs(x - 600.0 * i) / WAVE) / 0.05 - 1e-9) * 0.05, -1.0)
        for i, m in enumerate(METERS)
        if m in heard
    }
    t = np.arange(0.0, 1.3, 0.05)
    evidence = BurstEvidence(METERS, t, np.zeros((t.size, 4)), 1.0, 0.05, alarms=alarms)
    return Decision(Ranking([]), at, 1.0, posterior=posterior(line_arrival(), evidence))


def test_an_attempt_is_scored_at_each_confidence_and_for_its_first_short_region() -> None:
    truth = PipePoint("p12", "m1", 100.0)  # 700 m along the line
    near = PositionOutcome(error=40.0)
    # the early record, heard by one meter: the others' silence keeps it near that meter, but a
    # silence is weak evidence (a reached meter may stay silent): over a kilometre; the answer,
    # heard by every meter, is short
    early, answer = _decision(700.0, ("m1",), 1.2), _decision(700.0, METERS, 151.0)
    assert early.region is not None and answer.region is not None
    assert early.region.length > 1000.0 > 300.0 > answer.region.length
    assert early.region.contains("p12", "m1", 100.0, 600.0)
    attempt = Attempt("p12", 0.0, 1.0, decision=answer, early=(early,))
    outcome = score_region(attempt, truth, 600.0, near)
    assert outcome.covered == (True, True, True)
    assert outcome.lengths[0] <= outcome.lengths[1] <= outcome.lengths[2]
    assert outcome.lengths[2] == pytest.approx(answer.region.length)
    assert outcome.first_after == pytest.approx(0.2)  # the early record's region
    assert outcome.searchable_after == pytest.approx(150.0)  # the first of at most 1 km
    late = score_region(Attempt("p12", 0.0, 1.0, decision=answer), truth, 600.0, near)
    assert late.searchable_after == late.first_after == pytest.approx(150.0)
    # a burst elsewhere is outside the short region; an attempt without an answer holds nothing
    missed = score_region(attempt, PipePoint("p23", "m2", 500.0), 600.0, PositionOutcome(900.0))
    assert missed.covered == (False, False, False)
    none = score_region(Attempt("p12", 0.0, 1.0), truth, 600.0, PositionOutcome())
    assert none == RegionOutcome()
    scores = RegionScores.of([late, missed, none])
    assert (scores.attempts, scores.answered) == (3, 2)
    assert scores.coverage == pytest.approx((1 / 3, 1 / 3, 1 / 3))
    assert scores.within == pytest.approx((1 / 3, 1 / 3))  # 40 m; 900 m; no position
    assert scores.searchable == pytest.approx(2 / 3)
    assert scores.median_time_to_searchable == pytest.approx(150.0)
    assert scores.median_time_to_region == pytest.approx(150.0)  # late's 150, missed's 0.2, none
    assert scores.median_length[2] == pytest.approx(answer.region.length)
    cells = region_cells(scores)
    assert cells[2] == "33% / 33% / 33%" and cells[4] == "33% / 33%"
    # the first answer: the early record's region held the burst; its named point's distance
    # comes from the scorer given (the answer's own, when the answer is the first record)
    assert outcome.first_covered and outcome.first_error is None
    assert late.first_covered and late.first_error == 40.0
    assert not missed.first_covered
    scored = score_region(attempt, truth, 600.0, near, error_of=lambda at: 25.0)
    assert scored.first_error == 25.0 and scored.error == 40.0
    assert scores.first_coverage == pytest.approx(1 / 3) and scores.first_mean_error == 40.0
    assert scores.first_within == pytest.approx((1 / 3, 1 / 3))
    assert cells[1] == "33%, 33%, 40 m"
    assert RegionScores.of([none]).median_time_to_searchable is None


def test_evaluate_scores_the_search_regions(tiny: Path) -> None:
    scenario = paper.ScenarioConfig(burst_start=2.0, position=0.3)
    spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival")
    ev = evaluate(tiny, [spec], pipes=["B", "E"], phases=2, scenario=scenario, progress=False)
    doc = ev.to_json()
    jsonschema.validate(doc, SCHEMA)
    (run,) = ev.runs
    scores = run.region_scores()
    assert scores.attempts == scores.answered == 4
    outcomes = [o for p in run.pipes for o in run.regions[p]]
    for o in outcomes:  # every region of a lower confidence is no longer
        assert o.lengths[0] <= o.lengths[1] <= o.lengths[2]
    held = sum(o.covered[2] for o in outcomes)
    assert scores.coverage[2] == pytest.approx(held / 4)
    errors = [o.error for p in run.pipes for o in run.positions[p]]
    assert scores.within[1] == pytest.approx(sum(e <= 300.0 for e in errors) / 4)
    record = doc["runs"][0]
    assert record["region"]["levels"][2]["coverage"] == scores.coverage[2]
    for pipe_record in record["pipes"]:
        region = pipe_record["region"]
        assert region["confidence"] == 0.95 and region["probability"] >= 0.95
        assert region["length_m"] == pytest.approx(
            sum(s["high"] - s["low"] for s in region["stretches"]), abs=1.0
        )
    assert "Search regions" in format_tables(ev)
