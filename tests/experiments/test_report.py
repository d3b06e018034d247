"""burstloc.experiments.report: the paper's tables as text, the JSON and CSV files of an
evaluation, and the study's report."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import jsonschema
import pytest

from burstloc.experiments import paper
from burstloc.experiments.evaluate import Evaluation, evaluate
from burstloc.experiments.grid import StudySettings
from burstloc.experiments.report import (
    CSV_FIELDS,
    format_tables,
    write_csv,
    write_json,
)
from burstloc.experiments.runs import RunSpec
from burstloc.experiments.study_report import write_study_report
from burstloc.localize.detection import DetectorConfig, Mode
from conftest import PAPER15

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())


@pytest.fixture(scope="module")
def small() -> Evaluation:
    """Two real bursts on the paper's network at 0.2 s, both detectors (Tables I/II runs)."""
    runs = [
        RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, Mode.WINDOW, "S_C1"),
        RunSpec(DetectorConfig("shewhart", 1.5), 0.2, 5, Mode.WINDOW, "S_S1"),
    ]
    ev = evaluate(
        PAPER15,
        runs,
        pipes=["12", "P4"],
        phases=2,
        scenario=paper.ScenarioConfig(burst_start=2.0),
        workers=1,
        progress=False,
    )
    ev.warnings.append("a warning to print")
    return ev


def test_format_tables_sets_each_run_beside_the_paper(small: Evaluation) -> None:
    text = format_tables(small)
    lines = text.splitlines()
    # what the readings carried comes first: the paper's rules read noiseless readings
    assert lines[0] == "Sensor noise on the readings (paper's rules: none; seed 0; --noise sets it)"
    assert lines[1] == "" and lines[2].startswith("Table III (CUSUM, detection mode 'window')")
    assert any(line.startswith("Table IV (Shewhart, detection mode 'window')") for line in lines)
    # the paper's pipe order, whatever the order asked for
    rows = [line for line in lines if line.startswith(("P4 ", "12 "))]
    assert [r.split()[0] for r in rows] == ["P4", "12", "P4", "12"]
    p4_rows = {"cusum": rows[0], "shewhart": rows[2]}
    names = {"cusum": "CUSUM", "shewhart": "Shewhart"}
    for run, table in zip(small.runs, ("cusum", "shewhart"), strict=True):
        a = run.attempts["P4"][0]
        named = "not located" if a.predicted is None else f"{a.predicted[0]} - {a.predicted[1]}"
        assert named + (" *" if a.correct else "") in p4_rows[table]
        assert paper.published_prediction(table, "P4", 0.2) in p4_rows[table]
        counted, printed = paper.published_correct(table)[0], paper.PRINTED_TOTALS[table][0]
        assert f"{run.correct}/2" in text and f"{counted}/25 (printed {printed})" in text
        (summary,) = [line for line in lines if line.split()[:2] == [names[table], "window"]]
        assert f"{run.correct}/{run.total} = {100 * run.accuracy:.0f}%" in summary
        assert f"{paper.TABLE_V[table][0]:.0f}%" in summary
        tally = run.tally()
        ttl = tally.median_time()
        assert ("-" if ttl is None else f"{ttl:.2f} s") in summary
        assert f"{100 * tally.top1_fraction:.0f}% / {100 * tally.top3_fraction:.0f}%" in summary
    assert "over 2 phase(s) spread over one capture interval" in text
    assert lines[-1] == "warning: a warning to print"


def test_another_network_is_not_framed_as_the_papers_tables(small: Evaluation, tiny: Path) -> None:
    # Before, any network got "Table III / Table V" and an empty "paper" column.
    runs = [RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, Mode.WINDOW, "S_C1")]
    ev = evaluate(
        tiny,
        runs,
        pipes=["C"],
        phases=1,
        scenario=paper.ScenarioConfig(burst_start=2.0),
        workers=1,
        progress=False,
    )
    text = format_tables(ev)
    assert "Table" not in text and "S_C1" not in text, text
    headers = [line.split() for line in text.splitlines() if line.startswith(("pipe", "detector"))]
    assert len(headers) == 2 and not any("paper" in header for header in headers), text
    assert text.startswith("Sensor noise on the readings (paper's rules: none;")
    assert text.splitlines()[2].startswith("CUSUM, detection mode 'window'")
    assert "Summary: accuracy" in text
    assert "Table III" in format_tables(ev, paper_tables=True)  # when asked
    assert "Table III" in format_tables(small)  # the paper's network, some of its pipes


def test_write_json_is_the_schema_document(small: Evaluation, tmp_path: Path) -> None:
    path = write_json(small, tmp_path / "deep" / "r.json")
    assert path == tmp_path / "deep" / "r.json"
    doc = json.loads(path.read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc == json.loads(json.dumps(small.to_json()))
    assert [r["correct"] for r in doc["runs"]] == [r.correct for r in small.runs]
    assert list(tmp_path.joinpath("deep").iterdir()) == [path]  # no temporary file left


def test_write_csv_has_one_row_per_run_and_pipe(small: Evaluation, tmp_path: Path) -> None:
    path = write_csv(small, tmp_path / "r.csv")
    with path.open(newline="", encoding="utf-8") as f:
        reader = csv.DictReader(f)
        assert tuple(reader.fieldnames or ()) == CSV_FIELDS
        rows = list(reader)
    assert [(r["detector"], r["pipe"]) for r in rows] == [
        (run.spec.detector.kind, p) for run in small.runs for p in run.pipes
    ]
    for r in rows:
        run = next(x for x in small.runs if x.spec.detector.kind == r["detector"])
        attempts = run.attempts[r["pipe"]]
        assert r["correct"] == str(attempts[0].correct)
        assert int(r["phases_correct"]) == sum(a.correct for a in attempts)
        assert r["phases"] == "2" and r["threshold"] == str(run.spec.detector.threshold)
        assert (r["true_start"], r["true_end"]) == run.truth[r["pipe"]]


def _row(point: str, factor: str, localizer: str, dt: float, top1: float) -> dict[str, object]:
    return {
        "network": "net",
        "point": point,
        "factor": factor,
        "level": None,
        "meters": 4,
        "detector": "cusum",
        "localizer": localizer,
        "meter_model": "instantaneous",
        "capture_interval": dt,
        "top1": top1,
        "top3": 1.0,
        "attempts": 10,
        "not_located": 0,
        "median_time_s": 1.25 if dt == 0.2 else None,
    }


def test_write_study_report_tables_json_and_plots(tmp_path: Path) -> None:
    settings = StudySettings(capture_intervals=(0.2, 2.0), detectors=("cusum",), phases=2)
    rows = [
        _row(point, factor, name, dt, top1)
        for point, factor, top1 in (
            ("net: default", "default", 0.9),
            ("net: position=0.1", "position", 0.5),
        )
        for name in ("arrival", "fused")
        for dt in (0.2, 2.0)
    ]
    report = write_study_report(rows, settings, tmp_path / "out", ["net: x: left out"])
    text = report.read_text()
    assert "over 2 phases of the capture clock" in text
    assert "- net: x: left out" in text
    assert "## Summary (fused localizer, cusum)" in text
    assert "| net: position=0.1 | 4 | instantaneous | 50 / 100 | 50 / 100 |" in text
    assert "| net | cusum | arrival | instantaneous | 90 / 100 | 90 / 100 |" in text
    assert "- net cusum fused instantaneous: 1.25 s" in text
    saved = json.loads((tmp_path / "out" / "results.json").read_text())
    assert saved["rows"] == rows and saved["problems"] == ["net: x: left out"]
    assert saved["settings"]["capture_intervals"] == [0.2, 2.0]
    for name in ("net_defaults.png", "factor_position.png"):
        assert f"]({name})" in text
        assert (tmp_path / "out" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
