"""burstloc.experiments.study: scoring through the harness and a tiny end-to-end
study (the grid itself: test_grid.py)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest

from burstloc.cli import main
from burstloc.exceptions import ConfigError
from burstloc.experiments.grid import StudyPoint, StudySettings, study_grid
from burstloc.experiments.study import run_study
from burstloc.experiments.study_report import write_study_report as write_report
from burstloc.wave_speeds import WaveSpeeds


def test_tiny_study_end_to_end(tiny_network: Path, tmp_path: Path) -> None:
    # Arrivals only: the signature localizer's fits cost seconds per burst (tested in
    # test_signature.py); the pipeline around them is the same.
    settings = StudySettings(
        capture_intervals=(0.2,),
        detectors=("cusum",),
        localizers=("arrival",),
        phases=1,
        duration=90.0,
        pipes=("B", "C"),
    )
    points = study_grid([tiny_network], {"meter_fraction": (1.0, 0.5)})
    assert len(points) == 2
    rows, problems = run_study(points, settings, workers=1, progress=False)
    assert problems == []
    # 2 points x 1 detector x 1 localizer x 2 meter models x 1 interval
    assert len(rows) == 2 * 2
    for row in rows:
        assert 0.0 <= row["top1"] <= row["top3"] <= 1.0
        assert row["attempts"] == 2
    by = {(r["point"], r["meter_model"]): r for r in rows}
    name = tiny_network.stem
    # Noise-free, every meter, 0.2 s: the burst pipe is among the arrival localizer's best
    # three (of five) within a second or two of the burst.
    arrival = by[(f"{name}: default", "instantaneous")]
    assert arrival["top3"] == 1.0 and arrival["not_located"] == 0
    assert arrival["median_time_s"] is not None and 0.0 < arrival["median_time_s"] < 2.0
    assert arrival["meters"] == 4
    assert by[(f"{name}: meter_fraction=0.5", "instantaneous")]["meters"] == 2
    report = write_report(rows, settings, tmp_path / "out", problems)
    text = report.read_text()
    assert "| point | meters | meter_model | 0.2 s |" in text
    assert f"{name}: meter_fraction=0.5" in text
    assert (tmp_path / "out" / f"{name}_defaults.png").stat().st_size > 0
    assert (tmp_path / "out" / "factor_meter_fraction.png").stat().st_size > 0
    saved = json.loads((tmp_path / "out" / "results.json").read_text())
    assert len(saved["rows"]) == len(rows)


def test_failed_simulations_leave_the_point_out(tiny_network: Path) -> None:
    settings = StudySettings(capture_intervals=(0.2,), phases=1, duration=90.0, pipes=("ZZ",))
    rows, problems = run_study(
        [StudyPoint(str(tiny_network), "default")], settings, workers=1, progress=False
    )
    assert rows == []
    assert len(problems) == 1 and "left out" in problems[0] and "ZZ" in problems[0]


def test_cli_refuses_an_unknown_factor(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["study", "x.inp", "--factors", "colour"]) == 2
    assert "unknown factor(s) ['colour']" in capsys.readouterr().err


def test_cli_study_and_calibrate_commands(
    tiny_network: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from burstloc.cli import main as cli
    from burstloc.localize.config import Calibration

    config = tmp_path / "tiny.json"
    argv = ["calibrate", str(tiny_network), "--out", str(config), "--capture-interval", "2"]
    assert cli([*argv, "--noise", "0.02", "--false-alarm-rate", "1"]) == 0
    loaded = Calibration.load(config, network=tiny_network)
    assert loaded.for_interval(2.0).capture_interval == 2.0
    assert cli(["calibrate", str(tiny_network), "--out", str(config), "--noise", "-1"]) == 2
    out = tmp_path / "study"
    status = cli(
        [
            "study",
            str(tiny_network),
            "--out",
            str(out),
            "--capture-interval",
            "0.2",
            "--detector",
            "shewhart",
            "--localizer",
            "arrival",
            "--phases",
            "1",
            "--duration",
            "90",
            "--factors",
            "--pipes",
            "C",
            "--workers",
            "1",
            "--quiet",
        ]
    )
    assert status == 0
    assert "## Summary (arrival localizer, shewhart)" in (out / "report.md").read_text()
    assert "wrote" in capsys.readouterr().out


def _arrivals_at_fine_capture(**settings: Any) -> StudySettings:
    """A quick study: CUSUM, the arrival localizer, instantaneous readings at 0.2 s, one
    phase, 90 s bursts; ``settings`` the rest."""
    return StudySettings(
        capture_intervals=(0.2,),
        detectors=("cusum",),
        localizers=("arrival",),
        meter_models=("instantaneous",),
        phases=1,
        duration=90.0,
        **settings,
    )


def test_study_takes_a_meter_file_and_a_placement_method(tiny_network: Path) -> None:
    from burstloc.sim.placement.methods import place_meters

    meter_set = place_meters(tiny_network, 3, method="arrival")
    settings = _arrivals_at_fine_capture(pipes=("B",), placement="arrival", meter_sets=(meter_set,))
    assert settings.meters_for(tiny_network) == meter_set.meters
    points = study_grid([tiny_network], {"meter_fraction": (1.0, 0.5)})
    rows, problems = run_study(points, settings, workers=1, progress=False)
    assert problems == []
    meters = {r["point"]: r["meters"] for r in rows}
    name = tiny_network.stem
    # the meter file at full coverage; the placement method below it
    assert meters == {f"{name}: default": 3, f"{name}: meter_fraction=0.5": 2}
    with pytest.raises(ConfigError, match="placement must be one of"):
        StudySettings(placement="random")


def test_a_study_simulates_and_localizes_at_the_pipes_wave_speeds(
    tiny_network: Path, tmp_path: Path
) -> None:
    plastic = WaveSpeeds(tuple((p, 400.0) for p in "ABCDE"), source="pe.csv")  # every main PE
    settings = _arrivals_at_fine_capture(pipes=("B", "C", "D", "E"), wave_speeds=plastic)
    points = study_grid([tiny_network], {"position": (0.5, 0.2)})
    rows, problems = run_study(points, settings, workers=1, progress=False)
    plain, _ = run_study(points, replace(settings, wave_speeds=None), workers=1, progress=False)
    assert problems == [] and len(rows) == len(plain) == 2
    nearest = {"tiny: default": 75.0, "tiny: position=0.2": 30.0}  # m: D at 0.5 and 0.2 to J2
    for row in rows:
        # simulated at 400 m/s: no meter hears a burst before its wave has come at 400 m/s
        # (at 1 200 m/s the nearest would have heard it a third of that time after it)
        assert row["median_time_s"] >= nearest[row["point"]] / 400.0
        # and the localizer, timing each path at 400 m/s, names every burst's pipe first
        # (told one speed of 1200 m/s it names half of them at 0.2 of the pipe)
        assert row["top1"] == 1.0
    report = write_report(rows, settings, tmp_path / "out", problems).read_text()
    assert "Wave speeds per pipe from pe.csv: 5 pipe(s) and 0 diameter class(es)" in report
    saved = json.loads((tmp_path / "out" / "results.json").read_text())
    assert saved["settings"]["wave_speeds"] == plastic.to_json()


def test_cli_study_refuses_a_wave_speeds_file_naming_what_is_wrong(
    tiny_network: Path, paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    speeds = tmp_path / "speeds.csv"
    speeds.write_text("pipe,wave_speed\nD,250\n")  # a pipe of the tiny network, not paper15's
    argv = ["study", str(tiny_network), str(paper15), "--out", str(tmp_path / "s")]
    assert main([*argv, "--wave-speeds", str(speeds)]) == 2
    err = capsys.readouterr().err
    assert f"wave speeds ({speeds}) name 1 pipe(s) the network does not have: ['D']" in err
    assert str(paper15) in err
    bad = tmp_path / "bad.json"
    bad.write_text('{"pipes": {"D": 9000}}')
    assert main([*argv, "--wave-speeds", str(bad)]) == 2
    assert f"wave speeds {bad}: pipes.D" in capsys.readouterr().err
