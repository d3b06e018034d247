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
from burstloc.experiments import paper
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
                "--time-step",
                "0.09",
            ],
            "finer than the simulation time step",
        ),
        (["--time-step", "0", "--pipes", "P4"], "--time-step must be a positive number"),
        (["--time-step", "nan", "--pipes", "P4"], "--time-step must be a positive number"),
        (["--time-step", "-0.1", "--pipes", "P4"], "--time-step must be a positive number"),
        (["--burst-coeff", "0", "--pipes", "P4"], "--burst-coeff must be a positive number"),
        (["--burst-coeff", "inf", "--pipes", "P4"], "--burst-coeff must be a positive number"),
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


#: Pipes of 1000 m or more: a burst at mid-pipe leaves 500 m halves, and TSNet's own time step
#: (0.208 s) is coarser than the paper's finest capture interval (0.2 s), as on todini6.
LONG_PIPES_INP = """\
[JUNCTIONS]
 J1  0  10
 J2  0  10
 J3  0  10

[RESERVOIRS]
 R1  80

[PIPES]
 A  R1  J1  1200  400  100  0  Open
 B  J1  J2  1000  300  100  0  Open
 C  J1  J3  1000  300  100  0  Open
 D  J2  J3  1100  200  100  0  Open

[OPTIONS]
 Units  LPS
 Headloss  H-W

[END]
"""


def _evaluate_long_pipes(tmp_path: Path, *options: str) -> int:
    inp = tmp_path / "long.inp"
    inp.write_text(LONG_PIPES_INP, encoding="utf-8")
    args = ["evaluate", str(inp), "--localizer", "paper", "--detector", "cusum", "--pipes", "B"]
    args += ["--capture-interval", "0.2", "--phases", "1", "--workers", "1", "--quiet"]
    return main([*args, "--json", str(tmp_path / "r.json"), *options])


def test_the_default_time_step_follows_the_finest_capture_interval(tmp_path: Path) -> None:
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.time_step import capture_time_step, expected_time_step

    inp = tmp_path / "long.inp"
    inp.write_text(LONG_PIPES_INP, encoding="utf-8")
    scenario = BurstScenario(inp, "B", duration=13.0)
    assert expected_time_step(scenario) > 0.2  # 500 m halves: 0.208 s, adjusted to 0.222 s
    assert capture_time_step(scenario, 0.2) == 0.1  # the rule `burstloc study` uses
    assert capture_time_step(scenario, 0.5) is None  # TSNet's own step is fine
    assert capture_time_step(scenario, 0.2, requested=0.15) == 0.15

    assert _evaluate_long_pipes(tmp_path) == 0
    doc = json.loads((tmp_path / "r.json").read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc["scenario"]["time_step"] is None  # the rule, not a requested step
    assert len(doc["runs"]) == 1 and doc["runs"][0]["capture_interval"] == 0.2


def test_an_explicit_time_step_reaches_the_simulation(tmp_path: Path, capsys) -> None:
    assert _evaluate_long_pipes(tmp_path, "--time-step", "0.15") == 0
    assert json.loads((tmp_path / "r.json").read_text())["scenario"]["time_step"] == 0.15
    capsys.readouterr()
    # above TSNet's stability limit: the pipe's simulation fails, naming the limit and the pipe
    # (exit 1, as from `burstloc simulate`)
    assert _evaluate_long_pipes(tmp_path, "--time-step", "0.3") == 1
    err = capsys.readouterr().err
    assert "time_step 0.3 s exceeds TSNet's stability limit 0.20833 s for pipe 'B'" in err


def test_the_burst_size_reaches_the_simulation_and_the_record(tmp_path: Path) -> None:
    assert _evaluate_long_pipes(tmp_path, "--burst-coeff", "0.002") == 0
    doc = json.loads((tmp_path / "r.json").read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc["scenario"]["burst_coeff"] == 0.002  # the parameters the bursts were built with
    # the paper's experiment keeps the paper's burst; any other run's default is 5 % of the
    # demand (three junctions of 10 L/s), at most 5 L/s
    assert _evaluate_long_pipes(tmp_path) == 0
    default = json.loads((tmp_path / "r.json").read_text())["scenario"]["burst_coeff"]
    assert default == paper.SCENARIO.burst_coeff == 0.02
    assert _evaluate_long_pipes(tmp_path, "--localizer", "arrival") == 0
    scenario = json.loads((tmp_path / "r.json").read_text())["scenario"]
    assert scenario["burst_flow_lps"] == pytest.approx(1.5, rel=1e-4)
    assert "burst_coeff" not in scenario
    assert scenario["burst_flows_lps"] == {"B": pytest.approx(1.5, rel=1e-4)}
    assert scenario["burst_sizing"] == "5 % of the network's demand, at most 5 L/s"


def test_evaluate_takes_the_configurations_meters_or_the_ones_given(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from burstloc.experiments.calibrate import calibrate

    meters = ("N4", "N7", "1", "8")
    config = calibrate(PAPER15, capture_intervals=(0.2,), meters=meters).save(tmp_path / "c.json")
    argv = ["evaluate", str(PAPER15), "--config", str(config), "--pipes", "P7", "--phases", "1"]
    argv += ["--detector", "cusum", "--capture-interval", "0.2", "--quiet", "--workers", "1"]
    # before, without --meters-file every junction was metered and the configuration refused
    assert main([*argv, "--json", str(tmp_path / "a.json")]) == 0
    assert json.loads((tmp_path / "a.json").read_text())["meters"] == list(meters)
    # the same meters in another order, as IDs
    assert main([*argv, "--meters", "8,1", "N7", "N4", "--json", str(tmp_path / "b.json")]) == 0
    assert json.loads((tmp_path / "b.json").read_text())["meters"] == list(meters)
    capsys.readouterr()
    assert main([*argv, "--meters", "N4,N7,N2"]) == 2
    err = capsys.readouterr().err
    assert "was calibrated for 4 other meters (2 missing ['1', '8'], 1 extra ['N2'])" in err
    assert main([*argv, "--meters", "N4", "--meters-file", str(config)]) == 2
    assert "--meters or --meters-file, not both" in capsys.readouterr().err


def test_bursts_sized_by_flow_and_every_bursts_flow_recorded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from burstloc.network import load_network
    from burstloc.sim.signatures.burst_size import burst_sizes

    assert _evaluate_long_pipes(tmp_path, "--burst-flow", "5") == 0
    doc = json.loads((tmp_path / "r.json").read_text())
    jsonschema.validate(doc, SCHEMA)
    scenario = doc["scenario"]
    (size,) = burst_sizes(load_network(tmp_path / "long.inp"), ["B"], 0.5, flow=0.005)
    assert scenario["burst_flow_lps"] == 5.0 and "burst_coeff" not in scenario
    assert scenario["burst_coeffs"] == {"B": pytest.approx(size.coeff)}
    assert scenario["burst_flows_lps"] == {"B": pytest.approx(5.0)}
    assert "the bursts drew 5-5 L/s (median 5)" in capsys.readouterr().out
    # by coefficient: the flow it draws recorded and said too
    assert _evaluate_long_pipes(tmp_path, "--burst-coeff", "0.002") == 0
    scenario = json.loads((tmp_path / "r.json").read_text())["scenario"]
    drawn = 0.002 * size.pressure**0.5 * 1000
    assert scenario["burst_flows_lps"] == {"B": pytest.approx(drawn, abs=1e-3)}
    assert f"the bursts drew {drawn:.3g}-{drawn:.3g} L/s" in capsys.readouterr().out
    with pytest.raises(SystemExit) as exit_:
        _evaluate_long_pipes(tmp_path, "--burst-coeff", "0.002", "--burst-flow", "5")
    assert exit_.value.code == 2
    assert "--burst-flow: not allowed with argument --burst-coeff" in capsys.readouterr().err
    assert _evaluate_long_pipes(tmp_path, "--burst-flow", "0") == 2
    assert "--burst-flow must be a positive number of L/s" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--truth-wave-speed-spread", "1"], "--truth-wave-speed-spread must be in [0, 1), got 1"),
        (["--truth-wave-speed-spread", "-0.1"], "--truth-wave-speed-spread must be a finite"),
        (["--truth-roughness-spread", "1.5"], "--truth-roughness-spread must be in [0, 1)"),
        (["--truth-clock-offset", "-0.005"], "--truth-clock-offset must be a finite number"),
        (["--truth-clock-offset", "inf"], "--truth-clock-offset must be a finite number"),
        (["--truth-silent-meter", "-2"], "--truth-silent-meter must be a finite number"),
        (["--truth-seed", "-1", "--truth-clock-offset", "0.005"], "--truth-seed must be a whole"),
        (
            ["--truth-silent-meter", "1", "--localizer", "paper"],
            "--truth-silent-meter needs a ranking localizer",
        ),
    ],
)
def test_evaluate_refuses_a_bad_truth_naming_the_option(args, message, capsys) -> None:
    assert main(["evaluate", str(PAPER15), "--quiet", "--pipes", "P7", *args]) == 2
    assert message in capsys.readouterr().err


def test_evaluate_on_a_perturbed_truth_records_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["evaluate", str(PAPER15), "--pipes", "P7", "--phases", "1", "--detector", "cusum"]
    argv += ["--capture-interval", "0.2", "--quiet", "--workers", "1", "--json"]
    assert main([*argv, str(tmp_path / "plain.json")]) == 0
    plain = json.loads((tmp_path / "plain.json").read_text())
    assert "truth" not in plain["scenario"] and "truth perturbed" not in capsys.readouterr().out
    truth = ["--truth-wave-speed-spread", "0.15", "--truth-roughness-spread", "0.3"]
    truth += ["--truth-clock-offset", "0.005", "--truth-silent-meter", "0.4", "--truth-seed", "3"]
    assert main([*argv, str(tmp_path / "a.json"), *truth]) == 0
    out = capsys.readouterr().out
    assert out.count("truth perturbed: wave speeds ±15 % per pipe, roughness ±30 % per pipe, ") == 1
    assert "the meter nearest each burst silent 0.4 s after it starts (seed 3)" in out
    doc = json.loads((tmp_path / "a.json").read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc["scenario"]["truth"] == {
        "wave_speed_spread": 0.15,
        "roughness_spread": 0.3,
        "clock_offset": 0.005,
        "silent_meter": 0.4,
        "seed": 3,
    }
    assert doc["scenario"]["truth_silent_meters"] == {"P7": "N5"}
    # the same seed, the same truth (simulated again: the cache keys it apart from the plain
    # burst, whose result is not taken for it)
    assert main([*argv, str(tmp_path / "b.json"), *truth, "--no-cache"]) == 0
    again = json.loads((tmp_path / "b.json").read_text())
    assert again["runs"] == doc["runs"]
    assert doc["runs"] != plain["runs"]


def test_evaluate_simulates_the_pipes_wave_speeds_and_says_what_the_localizers_keep(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    speeds = tmp_path / "speeds.csv"
    speeds.write_text("pipe,wave_speed\nP7,600\n")
    knows, assumes = tmp_path / "knows.npz", tmp_path / "assumes.npz"
    calibrate = ["calibrate", str(PAPER15), "--capture-interval", "0.05", "--signatures", "linear"]
    assert main([*calibrate, "--out", str(assumes)]) == 0
    assert main([*calibrate, "--out", str(knows), "--wave-speeds", str(speeds)]) == 0
    capsys.readouterr()
    argv = ["evaluate", str(PAPER15), "--pipes", "P7", "--phases", "1", "--detector", "cusum"]
    argv += ["--capture-interval", "0.05", "--quiet", "--workers", "1", "--position", "0.25"]
    argv += ["--localizer", "arrival", "--wave-speeds", str(speeds), "--json"]
    assert main([*argv, str(tmp_path / "k.json"), "--config", str(knows)]) == 0
    assert "the localizers keep" not in capsys.readouterr().out  # the same speeds
    doc = json.loads((tmp_path / "k.json").read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc["scenario"]["wave_speeds"] == {"pipes": {"P7": 600.0}, "diameters": []}
    assert main([*argv, str(tmp_path / "a.json"), "--config", str(assumes)]) == 0
    out = capsys.readouterr().out
    assert (
        "the bursts are simulated with the --wave-speeds file's; the localizers keep the "
        "configuration's one wave speed" in out
    )
    # the same simulated burst: the model that times P7 at its speed places it nearer
    err = {
        name: json.loads((tmp_path / f"{name}.json").read_text())["runs"][0]["pipes"][0][
            "position_error_m"
        ]
        for name in ("k", "a")
    }
    assert err["k"] < err["a"]


def test_evaluate_refuses_a_bad_wave_speeds_file_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    speeds = tmp_path / "speeds.csv"
    speeds.write_text("P7,600\nP99,500\n")
    argv = ["evaluate", str(PAPER15), "--pipes", "P7", "--quiet", "--wave-speeds", str(speeds)]
    assert main(argv) == 2
    assert "name 1 pipe(s) the network does not have: ['P99']" in capsys.readouterr().err
