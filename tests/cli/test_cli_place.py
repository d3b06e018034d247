"""``burstloc place`` and the meter file it writes, read by ``calibrate``, ``evaluate`` and
``study`` (``--meters-file``), on the tiny network (a real TSNet run)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import jsonschema
import pytest

from burstloc.cli import main
from burstloc.localize.config import Calibration
from burstloc.sim.placement.methods import meter_ambiguity, meter_separation
from conftest import write_tiny

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())


def test_place_then_calibrate_and_evaluate_with_the_meter_file(
    tiny: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meters_file = tmp_path / "meters.json"
    assert main(["place", str(tiny), "--meters", "3", "--out", str(meters_file)]) == 0
    out = capsys.readouterr().out
    assert "3 of 4 junctions (arrival)" in out and f"wrote {meters_file}" in out
    chosen = json.loads(meters_file.read_text())["meters"]
    assert len(chosen) == 3
    told = re.search(r"arrival separation at 0.2 s: (\d+) % of the candidate burst points", out)
    assert told is not None
    assert int(told.group(1)) == round(100 * meter_separation(tiny, chosen, resolution=0.2))
    ambiguous = re.search(r"expected ambiguous main at 0.2 s: (\d+) m", out)
    assert ambiguous is not None
    assert int(ambiguous.group(1)) == round(meter_ambiguity(tiny, chosen, resolution=0.2))

    config = tmp_path / "cal.json"
    argv = ["calibrate", str(tiny), "--out", str(config), "--capture-interval", "0.2"]
    assert main([*argv, "--meters-file", str(meters_file)]) == 0
    assert list(Calibration.load(config).meters) == chosen
    capsys.readouterr()

    result = tmp_path / "run.json"
    argv = [
        "evaluate",
        str(tiny),
        "--detector",
        "cusum",
        "--capture-interval",
        "0.2",
        "--localizer",
        "fused",
        "--config",
        str(config),
        "--meters-file",
        str(meters_file),
        "--pipes",
        "C",
        "--phases",
        "1",
        "--position",
        "0.3",
        "--json",
        str(result),
        "--quiet",
        "--workers",
        "1",
    ]
    assert main(argv) == 0
    assert "position error mean / p90" in capsys.readouterr().out
    doc = json.loads(result.read_text())
    jsonschema.validate(doc, SCHEMA)
    assert doc["meters"] == chosen
    assert doc["scenario"]["position"] == 0.3
    assert doc["runs"][0]["position_error_m"]["attempts"] == 1


def test_a_meter_file_for_another_network_is_refused(
    tiny: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    other = write_tiny(tmp_path / "other.inp", head=70.0)
    meters_file = tmp_path / "other-meters.json"
    argv = ["place", str(other), "--meters", "2", "--method", "coverage", "--out"]
    assert main([*argv, str(meters_file)]) == 0
    capsys.readouterr()
    calibrate = ["calibrate", str(tiny), "--out", str(tmp_path / "c.json")]
    assert main([*calibrate, "--meters-file", str(meters_file)]) == 2
    assert "run `burstloc place` for it" in capsys.readouterr().err
    assert main(["study", str(tiny), "--meters-file", str(meters_file)]) == 2
    assert "is for none of the study's networks" in capsys.readouterr().err
    assert main(["place", str(tiny), "--meters", "9"]) == 2
    assert "meter count must be between 1 and 4" in capsys.readouterr().err
    assert main(["place", str(tiny), "--meters", "0", "--method", "region"]) == 2
    assert "meter count must be between 1 and 4" in capsys.readouterr().err
    assert main(["place", str(tiny), "--meters", "2", "--method", "region"]) == 0
    assert "2 of 4 junctions (region)" in capsys.readouterr().out


def test_place_compare_evaluates_every_method(
    tiny: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["place", str(tiny), "--meters", "3", "--compare", "--phases", "1"]
    assert main([*argv, "--position", "0.3", "--quiet", "--workers", "1"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ")]
    assert lines[0].startswith("| method | meters | localizer | top-1 / top-3")
    body = [line.split(" | ") for line in lines[1:]]
    assert [(row[0], row[2]) for row in body] == [
        ("| coverage", "arrival"),
        ("| coverage", "fused"),
        ("| arrival", "arrival"),
        ("| arrival", "fused"),
        ("| region", "arrival"),
        ("| region", "fused"),
    ]
    for row in body:
        assert len(row[1].split()) == 3  # three meters
        assert row[5].endswith(" m |")  # every located burst has a position error
