"""End to end, on a real simulated burst on the paper's network: ``burstloc monitor --db`` keeps
the incident and the readings around it; operators close it as found at the burst pipe's
midpoint; ``burstloc incidents known-events`` writes the known-events file that calibration
reads, the event on the right pipe; the same alarm replayed and closed as a false alarm counts
against its meters in ``burstloc incidents meters``."""

from __future__ import annotations

import csv
import io
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from burstloc.cli import main
from burstloc.experiments.known_events import event_arrivals, read_known_events
from burstloc.layout import drawn_lengths, read_layout
from burstloc.localize.config import Calibration
from burstloc.network_file import read_network

PIPE = "P7"  # the simulated burst's pipe


@pytest.fixture(scope="module")
def burst(paper15: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(configuration, feed): paper15 calibrated at 0.2 s, and a burst on P7 at 10 s."""
    from burstloc.experiments.calibrate import calibrate

    folder = tmp_path_factory.mktemp("outcomes")
    config = calibrate(paper15, capture_intervals=(0.2,)).save(folder / "paper15.json")
    feed = folder / "feed.csv"
    args = ["simulate", str(paper15), "--pipe", PIPE, "--duration", "16", "--quiet"]
    args += ["--capture-interval", "0.2", "--noise", "0.01", "--seed", "3"]
    assert main([*args, "--feed", str(feed), "--out", str(folder / "out")]) == 0
    return config, feed


def _burstloc(*argv: str) -> Any:
    return subprocess.run(
        [sys.executable, "-m", "burstloc", *argv],
        capture_output=True,
        text=True,
        check=False,
        env=dict(os.environ),
    )


def _monitor(
    paper15: Path, burst: tuple[Path, Path], db: Path, feed: Path | None = None
) -> dict[str, Any]:
    config, feed = burst[0], feed or burst[1]
    done = _burstloc(
        "monitor", str(paper15), "--config", str(config), "--capture-interval", "0.2",
        "--readings", str(feed), "--health-every", "0", "--db", str(db),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert f"the readings around each alarm kept in {db.with_suffix('.readings')}" in done.stderr
    (decision,) = [json.loads(line) for line in done.stdout.splitlines()]
    return dict(decision)


def _midpoint(paper15: Path, pipe: str) -> tuple[float, float]:
    line = read_layout(paper15).line(pipe)
    along = drawn_lengths(line)
    half = along[-1] / 2
    k = next(i for i in range(1, len(line)) if along[i] >= half)
    t = (half - along[k - 1]) / (along[k] - along[k - 1])
    (x0, y0), (x1, y1) = line[k - 1], line[k]
    return x0 + t * (x1 - x0), y0 + t * (y1 - y0)


def test_a_burst_found_becomes_a_known_event_and_a_false_alarm_counts_per_meter(
    paper15: Path,
    burst: tuple[Path, Path],
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    db = tmp_path / "incidents.sqlite"
    decision = _monitor(paper15, burst, db)
    store = ["--db", str(db)]
    x, y = _midpoint(paper15, PIPE)
    assert main(["incidents", "ack", "1", *store, "--by", "ann"]) == 0
    assert main(["incidents", "close", "1", *store, "--by", "ann", "--found", f"{x},{y}"]) == 0
    out = tmp_path / "calibration" / "events.json"
    out.parent.mkdir()
    capsys.readouterr()
    assert main(["incidents", "known-events", *store, "--network", str(paper15),
                 "--out", str(out)]) == 0  # fmt: skip
    said = capsys.readouterr().err
    assert f"wrote {out}: 1 known event(s), 0 found incident(s) left out" in said
    doc = json.loads(out.read_text(encoding="utf-8"))
    (entry,) = doc["events"]
    # relative to the file, as the reader wants
    assert entry["readings"].startswith("../incidents.readings/alarm-")
    network = read_network(paper15)
    (event,) = read_known_events(out, network)
    assert event.pipe == PIPE and event.position == pytest.approx(0.5, abs=1e-6)
    assert 9.0 <= event.time < decision["first_alarm"]  # the burst began at 10 s
    assert not event.time_known  # the first change, not the burst's time: fitted
    # calibration hears the event in the kept readings, as the monitor heard it
    (arrivals,) = event_arrivals([event], network, Calibration.load(burst[0]))
    assert set(arrivals.onsets) >= set(decision["alarmed"])
    assert not arrivals.time_known
    assert all(event.time <= t < event.time + 3.0 for t in arrivals.onsets.values())

    # the same burst an hour later: a new incident, closed as a false alarm
    later = tmp_path / "later.csv"
    with burst[1].open(encoding="utf-8") as lines:
        rows = [line.rstrip("\n").split(",") for line in lines][1:]
    later.write_text("".join(f"{float(t) + 3600:g},{m},{v}\n" for t, m, v in rows), "utf-8")
    assert _monitor(paper15, burst, db, later)["alarmed"] == decision["alarmed"]
    assert main(["incidents", "ack", "2", *store, "--by", "bob"]) == 0
    assert main(["incidents", "close", "2", *store, "--by", "bob", "--false-alarm"]) == 0
    capsys.readouterr()
    assert main(["incidents", "meters", *store, "--format", "csv"]) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert {r["meter"] for r in rows} == set(decision["alarmed"])
    for r in rows:
        assert (r["alarmed"], r["false_alarms"], r["found"]) == ("2", "1", "1")
        assert (r["incidents"], r["false_alarm_incidents"], r["found_incidents"]) == (
            "1 2",
            "2",
            "1",
        )
    assert main(["incidents", "meters", *store]) == 0
    table = capsys.readouterr().out.splitlines()
    assert table[0].split() == ["METER", "ALARMED", "FALSE", "ALARMS", "FOUND", "INCIDENTS"]
    assert table[1].split()[1:] == ["2", "1", "1", "1,", "2*"]
    assert main(["incidents", "meters", *store, "--format", "json"]) == 0
    docs = json.loads(capsys.readouterr().out)
    assert {d["meter"]: d["false_alarms"] for d in docs} == {m: 1 for m in decision["alarmed"]}
    # the found incident is still the one event; the false alarm is none
    assert main(["incidents", "known-events", *store, "--network", str(paper15),
                 "--out", str(out)]) == 0  # fmt: skip
    assert len(json.loads(out.read_text(encoding="utf-8"))["events"]) == 1


def test_found_incidents_that_cannot_be_events_are_said_and_none_writes_nothing(
    paper15: Path, tiny: Path, burst: tuple[Path, Path], tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    db = tmp_path / "incidents.sqlite"
    _monitor(paper15, burst, db)
    store = ["--db", str(db)]
    assert main(["incidents", "ack", "1", *store, "--by", "ann"]) == 0
    far = ["--found", "1e6,1e6"]  # nowhere near the paper's network
    assert main(["incidents", "close", "1", *store, "--by", "ann", *far]) == 0
    capsys.readouterr()
    out = tmp_path / "events.json"
    known = ["incidents", "known-events", *store, "--out", str(out)]
    assert main([*known, "--network", str(paper15)]) == 1
    said = capsys.readouterr().err
    assert "not a known event: incident 1 (found at 1e+06,1e+06): the point is" in said
    assert "farther than 50 (the network's coordinates)" in said
    assert "no found incident can become a known event" in said and not out.exists()
    assert main([*known, "--network", str(paper15), "--within", "1e7"]) == 0  # told so
    for path in db.with_suffix(".readings").iterdir():
        path.unlink()  # the readings kept, lost
    assert main([*known, "--network", str(paper15), "--within", "1e7"]) == 1
    assert "is gone" in capsys.readouterr().err
    assert main([*known, "--network", str(paper15), "--within", "-1"]) == 2
    assert "--within must be a finite distance > 0, got -1" in capsys.readouterr().err
