"""burstloc.experiments.specificity and `burstloc evaluate --events`: bursts and other events
classified, on the tiny network (demand steps) and paper15_assets' asset nodes."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest

from burstloc.cli import main
from burstloc.experiments.event_set import DEMAND_JUNCTIONS, asset_nodes, default_events
from burstloc.experiments.specificity import Outcome, Specificity

REPO = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((REPO / "tests" / "evaluate_schema.json").read_text())


def test_the_asset_nodes_are_the_valve_and_pump_ends() -> None:
    assert asset_nodes(REPO / "networks" / "paper15_assets.inp") == {
        "V1": "V16",
        "V2": "V16",
        "PS": "PU1",
    }


def test_the_events_operate_every_asset_and_the_largest_consumers() -> None:
    events = default_events(REPO / "networks" / "paper15_assets.inp", 220.0)
    kinds = [e.kind for e in events]
    assert kinds.count("valve-closure") == 4 and kinds.count("valve-opening") == 3
    assert kinds.count("pump-trip") == 2 and kinds.count("pump-start") == 2
    steps = [e for e in events if e.kind == "demand-step"]
    assert len(steps) == 2 * DEMAND_JUNCTIONS + 1
    assert steps[0].asset == "N8" and steps[0].demand_change == pytest.approx(0.1)  # doubled


def test_a_non_burst_reported_as_a_burst_is_listed() -> None:
    spec = Specificity()
    spec.add("burst", 2.0, Outcome("burst", "p", ("p", "q")), "p", "p")
    spec.add("burst", 2.0, Outcome("unsure", "p", ("p", "q")), "q", "q")
    declared = Outcome("other", reason="declared operation")
    step = Outcome("burst", "p", evidence={"scale": 1.0}, reason="fits p")
    spec.add("demand-step", 2.0, step, "step", None, declared=declared)
    spec.add("demand-step", 2.0, Outcome("other"), "other step", None, declared=step)
    spec.add("pump-trip", 2.0, Outcome("other", "p", reason="beside the pump"), "trip", None)
    doc = spec.to_json()
    rows = {(r["type"], r["capture_interval"]): r for r in doc["table"]}
    assert rows["burst", 2.0]["burst"] == 1 and rows["burst", 2.0]["unsure"] == 1
    assert rows["demand-step", 2.0]["reported_as_burst"] == 0.5
    # one of the two steps was still called a burst with its operation declared
    assert rows["demand-step", 2.0]["reported_as_burst_declared"] == 0.5
    # no declared run for the pump trip: no declared figure, rather than a made-up 0
    assert rows["pump-trip", 2.0]["reported_as_burst_declared"] is None
    assert doc["burst_top1"] == {"2.0": 0.5} and doc["burst_top3"] == {"2.0": 1.0}
    assert doc["false_burst_reports"] == [
        {"event": "step", "capture_interval": 2.0, "pipe": "p", "scale": 1.0}
    ]
    # every event is listed, whatever its answer, with why and its declared answer
    listed = {e["event"]: e for e in doc["events"]}
    assert set(listed) == {"step", "other step", "trip"}
    assert listed["step"]["class"] == "burst" and listed["step"]["reason"] == "fits p"
    assert listed["step"]["class_declared"] == "other"
    assert listed["trip"]["class"] == "other" and listed["trip"]["class_declared"] is None
    assert listed["trip"]["reason"] == "beside the pump" and listed["trip"]["type"] == "pump-trip"
    assert "reported as a burst: step at 2 s" in spec.format_table()


def test_evaluate_events_on_the_tiny_network(tiny: Path, tmp_path: Path, capsys) -> None:
    out = tmp_path / "ev.json"
    classifier = tmp_path / "classifier.json"
    args = ["evaluate", str(tiny), "--events", "--detector", "cusum", "--capture-interval", "2"]
    args += ["--phases", "1", "--workers", "1", "--quiet", "--json", str(out)]
    args += ["--classifier-out", str(classifier), "--normal-hours", "2"]
    assert main(args) == 0
    doc = json.loads(out.read_text())
    jsonschema.validate(doc, SCHEMA)
    spec = doc["specificity"]
    rows = {r["type"]: r for r in spec["table"]}
    assert set(rows) == {"burst", "demand-step"}  # the tiny network has no valve or pump
    assert rows["burst"]["scenarios"] == 5 and rows["demand-step"]["scenarios"] == 9
    # the classifier was calibrated on these same bursts: none is refused as "other"
    assert rows["burst"]["other"] == 0
    # a declared operation explains every demand step
    assert rows["demand-step"]["reported_as_burst_declared"] == 0.0
    # each step is listed with its answer, and those answers make the table's counts
    steps = [e for e in spec["events"] if e["type"] == "demand-step"]
    assert len(steps) == 9 and all(e["class_declared"] in ("other", "quiet") for e in steps)
    for answer in ("quiet", "burst", "other", "unsure"):
        assert sum(e["class"] == answer for e in steps) == rows["demand-step"][answer]
    assert json.loads(classifier.read_text())["provenance"]["bursts"] == 5
    # two hours of normal operation (diurnal demand, noise) through the monitor: no burst
    (day,) = spec["normal_operation"]
    assert day["hours"] == 2 and day["capture_interval"] == 2.0
    assert day["burst_reports"] == 0
    assert day["simulator_warnings"] == []  # the tiny network sets EPANET's required pressure
    assert "as burst" in capsys.readouterr().out


def test_the_classifier_is_calibrated_on_another_network_s_bursts(
    tiny: Path, tmp_path: Path
) -> None:
    other = tmp_path / "other.inp"
    other.write_bytes(tiny.read_bytes().replace(b"[JUNCTIONS]", b"; another town\n[JUNCTIONS]"))
    classifier = tmp_path / "classifier.json"
    args = ["evaluate", str(tiny), "--events", "--detector", "cusum", "--capture-interval", "2"]
    args += ["--phases", "1", "--workers", "1", "--quiet", "--normal-hours", "0"]
    args += ["--classifier-network", str(other), "--classifier-out", str(classifier)]
    assert main([*args, "--burst-flow", "1"]) == 0  # bursts sized per pipe: each its own coeff
    assert json.loads(classifier.read_text())["provenance"]["bursts"] == 5


def test_an_event_that_cannot_be_simulated_is_left_out_and_said(
    tiny: Path, tmp_path: Path, capsys, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Anytown's pump start does not start steady (junction 20 moves 0.19 m before it): such an
    event is left out, said and listed; the evaluation goes on."""
    from burstloc.exceptions import UnsteadyStartError
    from burstloc.sim.events import operations as events

    first = default_events(tiny, 40.0)[0]
    real = events.simulate_event

    def unsteady_first(scenario: events.EventScenario, cache: object = True) -> object:
        if scenario.label == first.label:
            raise UnsteadyStartError(str(tiny), "J3", 0.19, 6.4, 10.0, 0.05)
        return real(scenario, cache=cache)  # type: ignore[arg-type]

    monkeypatch.setattr(events, "simulate_event", unsteady_first)
    out = tmp_path / "ev.json"
    args = ["evaluate", str(tiny), "--events", "--detector", "cusum", "--capture-interval", "2"]
    args += ["--phases", "1", "--workers", "1", "--quiet", "--json", str(out)]
    args += ["--normal-hours", "0"]
    assert main(args) == 0
    doc = json.loads(out.read_text())
    jsonschema.validate(doc, SCHEMA)
    spec = doc["specificity"]
    [skipped] = spec["events_not_simulated"]
    assert skipped["event"] == first.label and "does not start steady" in skipped["error"]
    rows = {r["type"]: r for r in spec["table"]}
    assert rows["demand-step"]["scenarios"] == 8  # nine steps, one left out
    captured = capsys.readouterr()
    assert f"{first.label} left out" in captured.err
    assert f"left out, not simulated: {first.label}" in captured.out
