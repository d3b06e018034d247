"""burstloc.experiments.position: true burst points, network distances, position errors; and
``burstloc evaluate``'s position errors on the tiny network (a real TSNet run)."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from burstloc.cli import main
from burstloc.exceptions import NetworkError
from burstloc.experiments import paper
from burstloc.experiments.evaluate import evaluate
from burstloc.experiments.position import (
    NetworkDistance,
    PipePoint,
    PositionErrors,
    PositionOutcome,
    score_position,
)
from burstloc.experiments.runs import RunSpec
from burstloc.localize.detection import DetectorConfig
from burstloc.localize.pipes import PipePosition
from burstloc.network import load_network

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())


def test_network_distance_follows_the_pipes(tiny: Path) -> None:
    # tiny: B = J1-J2 (200 m), C = J1-J3 (250 m), D = J2-J3 (150 m), E = J3-J4 (180 m)
    distance = NetworkDistance(load_network(tiny))
    on_b = PipePoint("B", "J1", 50.0)
    # same pipe, measured from either end
    assert distance.between(on_b, PipePoint("B", "J2", 30.0)) == pytest.approx(120.0)
    # 50 m on B from J1: to J3 via J1 (50 + 250) or via J2 (150 + 150); then 30 m along E
    assert distance.between(on_b, PipePoint("E", "J3", 30.0)) == pytest.approx(330.0)
    assert distance.between(PipePoint("E", "J3", 30.0), on_b) == pytest.approx(330.0)
    with pytest.raises(NetworkError, match="not an end of pipe"):
        distance.between(on_b, PipePoint("E", "J1", 0.0))
    with pytest.raises(NetworkError, match="not a pipe"):
        distance.between(on_b, PipePoint("Z", "J1", 0.0))


def test_position_errors_summarise_the_attempts(tiny: Path) -> None:
    distance = NetworkDistance(load_network(tiny))
    truth = PipePoint("B", "J1", 60.0)
    inside = PipePosition("B", "J1", "J2", 200.0, 80.0, 40.0, 120.0)
    from_other_end = PipePosition("B", "J2", "J1", 200.0, 100.0, 0.0, 130.0)  # 100 m from J1
    elsewhere = PipePosition("C", "J1", "J3", 250.0, 10.0, 0.0, 250.0)
    scored = [
        score_position(distance, truth, inside),
        score_position(distance, truth, from_other_end),
        score_position(distance, truth, elsewhere),
        score_position(distance, truth, None),
    ]
    assert [(o.error, o.inside, o.width) for o in scored] == [
        (pytest.approx(20.0), True, 80.0),
        (pytest.approx(40.0), False, 130.0),
        (pytest.approx(70.0), None, 250.0),
        (None, None, None),
    ]
    summary = PositionErrors.of(scored)
    assert summary.mean_width == pytest.approx(460.0 / 3)
    assert (summary.attempts, summary.count, summary.on_pipe, summary.interval_hits) == (4, 3, 2, 1)
    assert summary.mean == pytest.approx(130.0 / 3)
    assert 40.0 < summary.p90 <= 70.0
    assert PositionErrors.of([PositionOutcome()]).to_json()["mean"] is None


def test_evaluate_reports_position_errors_off_centre(tiny: Path) -> None:
    scenario = paper.ScenarioConfig(burst_start=2.0, position=0.3)
    spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival")
    paper_spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5)
    ev = evaluate(
        tiny, [spec, paper_spec], pipes=["B", "E"], phases=2, scenario=scenario, progress=False
    )
    doc = ev.to_json()
    jsonschema.validate(doc, SCHEMA)
    run, rules = ev.runs
    wn = load_network(tiny)
    for p in run.pipes:
        truth = run.points[p]
        link = wn.get_link(p)
        along = 0.3 if truth.node == link.start_node_name else 0.7
        assert truth.metres == pytest.approx(along * link.length)
    errors = run.position_errors()
    assert errors.count == errors.attempts == 4  # every burst located, every one with a place
    # a 0.2 s capture step is 240 m of wave travel at 1200 m/s: no worse than one pipe away
    assert errors.mean is not None and errors.mean < 240.0
    assert errors.p90 is not None and errors.mean <= errors.p90 + 1e-9
    record = doc["runs"][0]["pipes"][0]
    assert record["position"]["pipe"] == record["predicted_pipe"]
    assert record["true_position"]["metres"] == pytest.approx(run.points[record["pipe"]].metres)
    # the paper's rules give no position
    assert rules.position_errors().count == 0
    assert doc["runs"][1]["position_error_m"]["mean"] is None


def test_cli_evaluate_position(
    tiny: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["evaluate", str(tiny), "--pipes", "B", "--position", "1.5", "--quiet"]
    assert main(argv) == 2
    assert "--position must be strictly between 0 and 1" in capsys.readouterr().err
