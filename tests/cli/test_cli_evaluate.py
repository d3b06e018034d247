"""``burstloc evaluate``: the CLI contract (options, tables, JSON, CSV, plots, errors)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import jsonschema
import pytest

from burstloc.cli import build_parser, main
from burstloc.constants import METER_MODELS
from burstloc.exceptions import ConfigError
from burstloc.experiments.evaluate import DEFAULT_LOCALIZER
from burstloc.experiments.report import CSV_FIELDS
from burstloc.experiments.runs import RANKING_LOCALIZATION_INTERVAL, ranking_runs
from conftest import PAPER15

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())


def test_evaluate_writes_tables_json_csv_and_plots(tmp_path: Path, capsys) -> None:
    out_json, out_csv, plots = tmp_path / "r.json", tmp_path / "r.csv", tmp_path / "plots"
    status = main(
        [
            "evaluate",
            str(PAPER15),
            "--localizer",
            "paper",
            "--pipes",
            "P2",
            "P4",
            "--capture-interval",
            "0.2",
            "--phases",
            "2",
            "--mode",
            "both",
            "--json",
            str(out_json),
            "--csv",
            str(out_csv),
            "--plot",
            str(plots),
            "--workers",
            "1",
            "--quiet",
        ]
    )
    assert status == 0
    text = capsys.readouterr().out
    assert "Table III (CUSUM, detection mode 'window')" in text
    assert "Table IV (Shewhart, detection mode 'stream')" in text
    assert "Table V" in text and "22/25 (printed 23)" in text and "24/25 (printed 24)" in text

    doc = json.loads(out_json.read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc["network"] == str(PAPER15)
    assert [(r["detector"], r["mode"]) for r in doc["runs"]] == [
        ("cusum", "window"),
        ("cusum", "stream"),
        ("shewhart", "window"),
        ("shewhart", "stream"),
    ]
    assert {r["params"]["threshold"] for r in doc["runs"]} == {0.3, 1.5}  # Tables I/II
    assert all(r["params"]["localization_interval"] == 5 for r in doc["runs"])
    assert doc["scenario"]["duration"] == 13.0  # 10 s onset + 11 x 0.2 s, rounded up

    with out_csv.open() as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == list(CSV_FIELDS)
    assert len(rows) == 4 * 2 and {r["pipe"] for r in rows} == {"P2", "P4"}

    pngs = sorted(p.name for p in plots.glob("*.png"))
    assert len(pngs) == 8
    assert "paper15_cusum_window_0p2s_network.png" in pngs
    assert "paper15_shewhart_stream_0p2s_traces_P2.png" in pngs
    assert all((plots / p).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--pipes", "P99"], "unknown pipe"),
        (
            ["--localization-interval", "0", "--pipes", "P4"],
            "localization_interval must be an integer in [1, 100000], got 0",
        ),
        (["--capture-interval", "-1", "--pipes", "P4"], "capture interval must be > 0"),
        (["--capture-interval", "3"], "not one of the paper's"),
        (["--phases", "0"], "phases must be an integer in [1, 1000], got 0"),
        (["--min-pipe-length", "-1", "--pipes", "P4"], "min_pipe_length must be > 0 m, got -1"),
        (["--detector", "cusum", "--sigma", "2"], "Shewhart chart only"),
        (
            [
                "--capture-interval",
                "0.02",
                "--threshold",
                "0.3",
                "--localization-interval",
                "5",
                "--pipes",
                "P4",
                "--workers",
                "1",
            ],
            "finer than the simulation time step",
        ),
    ],
)
def test_evaluate_bad_input_exits_2_with_a_clear_message(args, message, capsys) -> None:
    assert main(["evaluate", str(PAPER15), "--quiet", "--localizer", "paper", *args]) == 2
    assert message in capsys.readouterr().err


def test_the_default_localizer_is_fused_and_paper_options_need_the_paper_localizer(
    capsys,
) -> None:
    args = build_parser().parse_args(["evaluate", str(PAPER15)])
    assert args.localizer == [DEFAULT_LOCALIZER] == ["fused"]
    for option, value in [
        ("--threshold", "0.3"),
        ("--drift", "0.1"),
        ("--sigma", "2"),
        ("--localization-interval", "5"),
        ("--mode", "stream"),
    ]:
        assert main(["evaluate", str(PAPER15), "--quiet", option, value]) == 2
        err = capsys.readouterr().err
        assert f"{option} apply to the paper's rules only" in err and "--config" in err


def test_ranking_runs_take_any_capture_interval_and_keep_the_paper_record() -> None:
    runs = ranking_runs(["cusum"], [0.2, 3.0], ["arrival", "fused"], METER_MODELS)
    assert [(r.capture_interval, r.localizer, r.meter_model) for r in runs] == [
        (ci, name, model)
        for ci in (0.2, 3.0)
        for name in ("arrival", "fused")
        for model in METER_MODELS
    ]
    assert {r.capture_interval: r.detector.threshold for r in runs} == {0.2: 0.3, 3.0: 1.0}
    assert {r.capture_interval: r.localization_interval for r in runs} == {
        0.2: 5,
        3.0: RANKING_LOCALIZATION_INTERVAL,
    }
    # the calibrated bank is fed once per reading and never reset: a streaming run
    assert {r.params()["mode"] for r in runs} == {"stream"}
    with pytest.raises(ConfigError, match="paper_runs"):
        ranking_runs(["cusum"], None, ["paper"])
    with pytest.raises(ConfigError, match="capture interval must be > 0"):
        ranking_runs(["cusum"], [0.0], ["fused"])


def test_evaluate_unknown_detector_is_an_argparse_error(capsys) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["evaluate", str(PAPER15), "--detector", "ewma"])
    assert exc.value.code == 2
    assert "invalid choice: 'ewma'" in capsys.readouterr().err
