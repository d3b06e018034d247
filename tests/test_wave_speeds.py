"""burstloc.wave_speeds: reading a utility's wave speeds per pipe and per diameter class."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.network import load_network
from burstloc.wave_speeds import WaveSpeeds, read_wave_speeds


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_a_csv_with_a_header_and_comments_gives_each_pipe_its_speed(tmp_path: Path) -> None:
    path = _write(tmp_path, "speeds.csv", "# from the GIS\npipe,wave_speed\nP7, 420\n\nP2,1250\n")
    speeds = read_wave_speeds(path)
    assert speeds.pipes == (("P2", 1250.0), ("P7", 420.0))
    assert speeds.speed("P7", 0.3, 1200.0) == 420.0
    assert speeds.speed("P3", 0.3, 1200.0) == 1200.0  # not named: the run's speed
    assert speeds.source == str(path)


def test_json_pipes_take_precedence_over_diameter_classes(tmp_path: Path) -> None:
    doc = {
        "pipes": {"P7": 1300},
        "diameters": [{"up_to_mm": 110, "wave_speed": 400}, {"up_to_mm": 300, "wave_speed": 900}],
    }
    speeds = read_wave_speeds(_write(tmp_path, "speeds.json", json.dumps(doc)))
    assert speeds.speed("P1", 0.1, 1200.0) == 400.0  # 100 mm: the first class
    assert speeds.speed("P1", 0.11, 1200.0) == 400.0  # at the bound, included
    assert speeds.speed("P1", 0.2, 1200.0) == 900.0
    assert speeds.speed("P1", 0.5, 1200.0) == 1200.0  # above every class
    assert speeds.speed("P7", 0.1, 1200.0) == 1300.0  # named: its own
    assert WaveSpeeds.from_json(speeds.to_json()) == WaveSpeeds(speeds.pipes, speeds.diameters)


def test_every_pipe_of_a_network_gets_a_speed_and_the_stretch_times_paths(
    paper15: Path,
) -> None:
    wn = load_network(paper15)
    d7 = float(wn.get_link("P7").diameter)
    speeds = WaveSpeeds((("P7", 600.0),), ((d7 / 2, 300.0),))
    every = speeds.of(wn, 1200.0)
    assert set(every) == set(wn.pipe_name_list)
    assert every["P7"] == 600.0
    small = [p for p in wn.pipe_name_list if p != "P7" and wn.get_link(p).diameter <= d7 / 2]
    assert all(every[p] == 300.0 for p in small)
    stretch = speeds.stretch(wn, 1200.0)
    assert stretch["P7"] == pytest.approx(2.0)  # a metre of P7 takes two at 1200 m/s
    assert set(stretch) == {"P7", *small}  # pipes at the run's speed are left out


@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("a.csv", "P7,fast\n", "no 'pipe,wave_speed' line"),  # read as the header
        ("a.csv", "pipe,wave_speed\nP7,fast\n", "line 2: the wave speed 'fast' is not a number"),
        ("a.csv", "P7,20\n", "the wave speed of pipe 'P7' must be in [50, 2000] m/s, got 20"),
        ("a.csv", "P7,400,PE\n", "line 1: expected 'pipe,wave_speed'"),
        ("a.csv", "P7,400\nP7,500\n", "pipe(s) listed twice: ['P7']"),
        ("a.csv", "# nothing\n", "no 'pipe,wave_speed' line"),
        ("a.json", '{"pipes": {"P7": "fast"}}', "pipes.P7 must be a number"),
        ("a.json", '{"pipes": {"P7": 5000}}', "pipes.P7 must be a finite number in [50, 2000]"),
        ("a.json", '{"speeds": {}}', "unknown key(s) ['speeds']"),
        ("a.json", '{"diameters": [{"up_to_mm": 100}]}', "diameters[0] must be"),
        (
            "a.json",
            '{"diameters": [{"up_to_mm": 300, "wave_speed": 900}, '
            '{"up_to_mm": 100, "wave_speed": 400}]}',
            "diameter classes must increase",
        ),
        ("a.json", "[1, 2]", "must be a JSON object"),
    ],
)
def test_a_bad_file_is_refused_naming_the_file_and_the_problem(
    tmp_path: Path, name: str, text: str, message: str
) -> None:
    path = _write(tmp_path, name, text)
    with pytest.raises(ConfigError) as caught:
        read_wave_speeds(path)
    assert str(path) in str(caught.value)
    assert message in str(caught.value)


def test_a_missing_file_and_an_unknown_pipe_are_named(tmp_path: Path, paper15: Path) -> None:
    with pytest.raises(ConfigError, match=r"cannot read wave speeds .*nowhere\.csv"):
        read_wave_speeds(tmp_path / "nowhere.csv")
    speeds = read_wave_speeds(_write(tmp_path, "s.csv", "P7,400\nP99,400\n"))
    with pytest.raises(
        NetworkError, match=r"name 1 pipe\(s\) the network does not have: \['P99'\]"
    ):
        speeds.of(load_network(paper15), 1200.0)
