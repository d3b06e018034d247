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
from burstloc.network import load_network
from burstloc.sim.placement.methods import (
    MeterScores,
    MeterSet,
    meter_ambiguity,
    place_meters,
    score_meters,
)
from burstloc.wave_speeds import read_wave_speeds
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
    ambiguous = re.search(r"the meters: expected ambiguous main at 0.2 s (\d+) m", out)
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


def test_place_compare_places_simulates_and_localizes_at_the_wave_speed_given(
    tiny: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import burstloc.experiments.placements as placements
    import burstloc.experiments.ranking as ranking

    seen: dict[str, list[float]] = {"placed": [], "simulated": [], "calibrated": []}
    place, evaluate, calibrate = placements.place_meters, placements.evaluate, ranking.calibrate

    def placing(*args: object, **kw: object) -> object:
        seen["placed"].append(float(kw["wave_speed"]))  # type: ignore[arg-type]
        return place(*args, **kw)  # type: ignore[arg-type]

    def evaluating(*args: object, **kw: object) -> object:
        seen["simulated"].append(kw["scenario"].wave_speed)  # type: ignore[attr-defined]
        return evaluate(*args, **kw)  # type: ignore[arg-type]

    def calibrating(*args: object, **kw: object) -> object:
        config = calibrate(*args, **kw)  # type: ignore[arg-type]
        seen["calibrated"].append(config.model.wave_speed)
        return config

    monkeypatch.setattr(placements, "place_meters", placing)
    monkeypatch.setattr(placements, "evaluate", evaluating)
    monkeypatch.setattr(ranking, "calibrate", calibrating)
    argv = ["place", str(tiny), "--meters", "2", "--compare", "--phases", "1", "--quiet"]
    assert main([*argv, "--wave-speed", "600", "--workers", "1"]) == 0
    assert "| coverage |" in capsys.readouterr().out
    assert seen["placed"] == seen["simulated"] == seen["calibrated"] == [600.0] * 3


def _scores(out: str, what: str) -> tuple[int, int, int]:
    """The expected ambiguous main, median and searchable share printed for ``what``."""
    found = re.search(
        re.escape(what) + r": expected ambiguous main at 0.2 s (\d+) m, median burst (\d+) m, "
        r"(\d+) % of bursts within 1 km",
        out,
    )
    assert found is not None, out
    return int(found.group(1)), int(found.group(2)), int(found.group(3))


def _printed(scores: MeterScores) -> tuple[int, int, int]:
    """What :func:`_scores` reads back for ``scores``."""
    return round(scores.ambiguous), round(scores.ambiguity.median), round(100 * scores.searchable)


def test_place_keep_keeps_the_owned_meters_and_reports_the_gain(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    owned = tmp_path / "owned.txt"
    owned.write_text("# the meters we have\nN4\n5  # at the tank\n")
    out_file = tmp_path / "more.json"
    argv = ["place", str(paper15), "--keep", str(owned), "--meters", "2", "--out", str(out_file)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    placed = MeterSet.load(out_file)
    assert placed.method == "region" and len(placed.meters) == 4
    assert {"N4", "5"} <= set(placed.meters)
    added = [m for m in placed.meters if m not in ("N4", "5")]
    assert f"4 of 15 junctions (region): the 2 kept and 2 added: {' '.join(added)}" in out
    before, after = score_meters(paper15, ("N4", "5")), score_meters(paper15, placed.meters)
    assert after.ambiguous < before.ambiguous
    for what, scores in (("the 2 kept", before), ("with the 2 added", after)):
        assert _scores(out, what) == _printed(scores)
    gain = before.ambiguous - after.ambiguous
    assert f"the 2 added rule out {gain:.0f} m ({100 * gain / before.ambiguous:.0f} %)" in out
    # the same owned meters as IDs, with another method
    argv = ["place", str(paper15), "--keep", "N4,5", "--meters", "1", "--method", "arrival"]
    assert main(argv) == 0
    assert "3 of 15 junctions (arrival): the 2 kept and 1 added:" in capsys.readouterr().out


def test_place_score_ranks_the_meters_by_what_each_adds(
    paper15: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meters = ["N4", "N7", "1", "8"]
    assert main(["place", str(paper15), "--score", *meters]) == 0
    out = capsys.readouterr().out
    whole = meter_ambiguity(paper15, meters)
    assert _scores(out, "4 meters")[0] == round(whole)
    ranked = re.findall(r"^ +(\d+)\. (\S+) +\+(\d+) m$", out, flags=re.M)
    assert [int(r[0]) for r in ranked] == [1, 2, 3, 4]
    gains = {m: meter_ambiguity(paper15, [o for o in meters if o != m]) - whole for m in meters}
    assert [r[1] for r in ranked] == sorted(meters, key=gains.__getitem__)
    assert [int(r[2]) for r in ranked] == [round(gains[r[1]]) for r in ranked]
    least = ranked[0][1]
    assert f"adds least: {least} (+{gains[least]:.0f} m" in out


def test_place_refuses_meter_lists_it_cannot_use(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    unknown = [f"x{i}" for i in range(9)]
    assert main(["place", str(paper15), "--keep", "N4", *unknown, "--meters", "2"]) == 2
    err = capsys.readouterr().err
    assert "9 meter(s) ['x0', 'x1', 'x2', 'x3', 'x4'] and 4 more are not junctions of" in err
    assert "x5" not in err
    assert main(["place", str(paper15), "--keep", "N4,N4", "--meters", "2"]) == 2
    assert "lists ['N4'] more than once" in capsys.readouterr().err
    empty = tmp_path / "empty.txt"
    empty.write_text("# nothing yet\n")
    assert main(["place", str(paper15), "--score", str(empty)]) == 2
    assert f"meter list {empty} names no meter" in capsys.readouterr().err
    assert main(["place", str(paper15), "--score", "N4", "--meters", "2"]) == 2
    assert "--meters does not apply" in capsys.readouterr().err
    assert main(["place", str(paper15)]) == 2
    assert "place needs --meters K" in capsys.readouterr().err
    assert main(["place", str(paper15), "--keep", "N4", "--meters", "15"]) == 2
    assert "meter count must be between 1 and 14" in capsys.readouterr().err


def test_place_times_paths_at_the_pipes_wave_speeds(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    speeds = tmp_path / "speeds.csv"
    speeds.write_text("pipe,wave_speed\nP7,400\nP8,400\n")  # two PE mains
    slow = read_wave_speeds(speeds)
    meters = ["N4", "N7", "1", "8"]
    assert main(["place", str(paper15), "--score", *meters, "--wave-speeds", str(speeds)]) == 0
    out = capsys.readouterr().out
    assert (
        f"travel times from {speeds}: 2 of 25 pipes at their own wave speed (400 m/s), the "
        "others at 1200 m/s" in out
    )
    timed, uniform = score_meters(paper15, meters, wave_speeds=slow), score_meters(paper15, meters)
    assert _scores(out, "4 meters") == _printed(timed)
    assert round(timed.ambiguous) != round(uniform.ambiguous)  # 417 m against 366 m

    # every pipe at 400 m/s is the run at --wave-speed 400: three times the travel time, a
    # capture interval rules out three times finer, the ambiguous main far shorter
    every = tmp_path / "every.csv"
    every.write_text("".join(f"{p},400\n" for p in load_network(paper15).pipe_name_list))
    assert main(["place", str(paper15), "--score", *meters, "--wave-speeds", str(every)]) == 0
    plastic = _scores(capsys.readouterr().out, "4 meters")
    assert main(["place", str(paper15), "--score", *meters, "--wave-speed", "400"]) == 0
    assert plastic == _scores(capsys.readouterr().out, "4 meters")
    assert plastic[0] < 0.5 * uniform.ambiguous

    # --keep and --out: placed with them, the meter file records them
    out_file = tmp_path / "more.json"
    argv = ["place", str(paper15), "--keep", "N4,5", "--meters", "2", "--out", str(out_file)]
    assert main([*argv, "--wave-speeds", str(speeds)]) == 0
    out = capsys.readouterr().out
    placed = MeterSet.load(out_file)
    assert placed.meters == (
        place_meters(paper15, 2, keep=("N4", "5"), method="region", wave_speeds=slow).meters
    )
    # N4 N8 1 5: at one speed the greedy adds N3 and N8 instead
    assert placed.meters != place_meters(paper15, 2, keep=("N4", "5"), method="region").meters
    doc = json.loads(out_file.read_text())
    assert doc["wave_speeds"] == {"pipes": {"P7": 400.0, "P8": 400.0}, "diameters": []}
    after = score_meters(paper15, placed.meters, wave_speeds=slow)
    assert _scores(out, "with the 2 added") == _printed(after)
    argv = ["place", str(paper15), "--meters", "2", "--out", str(tmp_path / "plain.json")]
    assert main(argv) == 0
    assert "wave_speeds" not in json.loads((tmp_path / "plain.json").read_text())


def test_place_refuses_a_bad_wave_speeds_file_naming_it(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    unknown = tmp_path / "unknown.csv"
    unknown.write_text("P7,600\nP99,500\n")
    malformed = tmp_path / "malformed.csv"
    malformed.write_text("pipe,wave_speed\nP7,fast\n")
    out_file = tmp_path / "m.json"
    for mode in (["--score", "N4", "8"], ["--meters", "2", "--out", str(out_file)]):
        argv = ["place", str(paper15), *mode, "--wave-speeds"]
        assert main([*argv, str(unknown)]) == 2
        err = capsys.readouterr().err
        assert f"wave speeds ({unknown}) name 1 pipe(s) the network does not have: ['P99']" in err
        assert str(paper15) in err
        assert main([*argv, str(malformed)]) == 2
        err = capsys.readouterr().err
        assert f"wave speeds {malformed} line 2: the wave speed 'fast' is not a number" in err
        assert main([*argv, str(tmp_path / "missing.csv")]) == 2
        assert f"cannot read wave speeds {tmp_path / 'missing.csv'}" in capsys.readouterr().err
    assert not out_file.exists()
