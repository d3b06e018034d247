"""`burstloc calibrate --known-events`: the wave speed and the clocks learnt from real
simulations of transients whose place and time are known."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from burstloc.cli import main
from burstloc.localize.config import Calibration

PIPES = ("P7", "3", "12")  # three places far apart on the paper's network


@pytest.fixture(scope="module")
def known(paper15: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three simulated bursts at 10 s, their feeds at 0.2 s with noise, and the events file."""
    where = tmp_path_factory.mktemp("known")
    for pipe in PIPES:
        args = ["simulate", str(paper15), "--pipe", pipe, "--duration", "16", "--quiet"]
        args += ["--capture-interval", "0.2", "--noise", "0.01", "--seed", "3"]
        args += ["--feed", str(where / f"{pipe}.csv"), "--out", str(where / "out")]
        assert main(args) == 0
    events = [
        {"name": f"burst on {p}", "readings": f"{p}.csv", "time": 10.0, "pipe": p} for p in PIPES
    ]
    (where / "events.json").write_text(json.dumps({"events": events}), encoding="utf-8")
    return where


def _calibrate(paper15: Path, out: Path, *options: str) -> int:
    args = ["calibrate", str(paper15), "--out", str(out), "--capture-interval", "0.2"]
    return main([*args, *options])


def test_a_wave_speed_15_percent_off_is_learnt_back(
    paper15: Path, known: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    events = str(known / "events.json")
    assert (
        _calibrate(paper15, tmp_path / "c.json", "--wave-speed", "1020", "--known-events", events)
        == 0
    )
    said = capsys.readouterr().out
    found = re.search(r"wave speed 1020 -> (\d+) m/s", said)
    assert found is not None, said
    learnt = int(found.group(1))
    # the simulation's waves run at 1 200 m/s; a detector hears a front a little late
    assert 1080 <= learnt <= 1250
    config = Calibration.load(tmp_path / "c.json")
    assert round(config.model.wave_speed) == learnt
    assert config.provenance["known_events"] == 3
    assert set(config.model.clock_offsets or {}) == set(config.meters)
    assert all(v == 0.0 for v in (config.model.clock_offsets or {}).values())  # tolerance 0
    # with a clock tolerance the offsets are fitted, each within a few capture intervals
    assert (
        _calibrate(
            paper15, tmp_path / "d.json", "--known-events", events, "--clock-tolerance", "0.01"
        )
        == 0
    )
    offsets = Calibration.load(tmp_path / "d.json").model.clock_offsets or {}
    assert any(v != 0.0 for v in offsets.values()) and all(abs(v) < 0.1 for v in offsets.values())


def test_fronts_heard_slower_than_the_wave_leave_the_wave_speed_to_learn(
    paper15: Path, known: Path
) -> None:
    from dataclasses import replace

    from burstloc.experiments.calibrate import calibrate
    from burstloc.experiments.known_events import event_arrivals, read_known_events
    from burstloc.network import read_network

    network = read_network(paper15)
    plain = calibrate(network, capture_intervals=[0.2])
    slower = replace(plain, intervals=(replace(plain.intervals[0], front_factor=0.8),))
    events = read_known_events(known / "events.json", network)
    for seen, timed in zip(
        event_arrivals(events, network, plain),
        event_arrivals(events, network, slower),
        strict=True,
    ):
        assert seen.onsets == timed.onsets and seen.onsets
        for meter, metres in seen.distances.items():
            assert timed.distances[meter] == pytest.approx(metres / 0.8)


@pytest.mark.parametrize(
    ("entry", "words"),
    [
        ({"readings": "missing.csv", "time": 10.0, "pipe": "P7"}, "no readings file"),
        ({"readings": "P7.csv", "time": 10.0, "pipe": "nope"}, "'nope' is not a pipe"),
        ({"readings": "P7.csv", "time": 10.0}, "as 'junction' or as 'pipe'"),
        ({"readings": "P7.csv", "time": -5.0, "pipe": "P7"}, "must start before the event"),
        ({"readings": "P7.csv", "time": "soon", "pipe": "P7"}, "'time' must be seconds"),
        ({"readings": "P7.csv", "time": True, "pipe": "P7"}, "'time' must be seconds"),
        ({"readings": "P7.csv", "time": 10.0, "pipe": "P7", "position": 2}, "within 0..1"),
        ({"readings": "P7.csv", "time": 10.0, "pipe": "P7", "when": 1}, "unknown key(s) ['when']"),
        (
            {"readings": "P7.csv", "time": 10.0, "pipe": "P7", "time_known": "no"},
            "'time_known' must be true or false, got 'no'",
        ),
    ],
)
def test_a_bad_event_is_named(
    paper15: Path,
    known: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    entry: dict[str, object],
    words: str,
) -> None:
    good = {"readings": "3.csv", "time": 10.0, "pipe": "3"}
    events = known / f"bad-{abs(hash(words))}.json"
    events.write_text(json.dumps({"events": [good, entry]}), encoding="utf-8")
    assert _calibrate(paper15, tmp_path / "c.json", "--known-events", str(events)) == 2
    err = capsys.readouterr().err
    assert words in err, err
    assert not (tmp_path / "c.json").exists()  # nothing written
