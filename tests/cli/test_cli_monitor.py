"""`burstloc monitor`: bad input of every kind is reported and skipped, never fatal; bad
options and foreign state files stop it with a message naming them."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from burstloc.experiments.calibrate import calibrate


@pytest.fixture(scope="module")
def cfg(tiny: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    config = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)
    return config.save(tmp_path_factory.mktemp("cfg") / "tiny.json")


def _monitor(tiny: Path, cfg: Path, *extra: str, stdin: bytes = b"") -> subprocess.CompletedProcess:
    argv = [sys.executable, "-m", "burstloc", "monitor", str(tiny), "--config", str(cfg)]
    argv += ["--capture-interval", "0.2", *extra]
    return subprocess.run(argv, input=stdin, capture_output=True, check=False)


def _steady(steps: int) -> bytes:
    rows = [f"{0.2 * k:.1f},J{j},{59.8 - 0.01 * j}" for k in range(steps) for j in range(1, 5)]
    return ("\n".join(rows) + "\n").encode()


def test_garbage_of_every_kind_is_reported_and_skipped(tiny: Path, cfg: Path) -> None:
    garbage = (
        b"\xef\xbb\xbftimestamp,meter,value\n"
        b"0.0,J1,abc\n"
        b"0.0,J1,nan\n"
        b"2026-01-01T00:00:00,J1,59.8\n"
        b"0.0,J1\n"
        b'0.0,"J9",59.8\n'
        b"\x00\x01\x02\xff\xfe\n"
        b"0.0,J2,1000000\n"
    )
    done = _monitor(tiny, cfg, "--health-every", "10", stdin=garbage + _steady(200))
    assert done.returncode == 0, done.stderr
    err = done.stderr.decode()
    for text in [
        "line 2: value is not a finite number",
        "line 3: value is not a finite number",
        "line 4: ISO 8601 timestamp without a UTC offset",
        "line 5: want 'timestamp,meter,value'",
        "line 6: unknown meter 'J9'",
        "2 more bad-input messages not shown",  # at most 5 of a kind per 10 s; none silent
    ]:
        assert text in err, (text, err)
    assert "Traceback" not in err
    records = [json.loads(line) for line in done.stdout.decode().splitlines()]
    health = [r for r in records if r["type"] == "health"]
    assert health and not [r for r in records if r["type"] == "decision"]
    last = health[-1]
    assert last["meters"]["J1"]["bad"] == 3 and last["meters"]["J2"]["implausible"] == 1
    assert last["bad_unknown_meter"] == 3  # the short line, J9 and the binary line


def test_an_overlong_line_is_one_bad_reading_and_the_lines_after_it_count(
    tiny: Path, cfg: Path
) -> None:
    feed = b"0.0,J1," + b"9" * 200_000 + b"\n0.0,J1,abc\n" + _steady(50)
    done = _monitor(tiny, cfg, "--health-every", "1", stdin=feed)
    assert done.returncode == 0, done.stderr
    err = done.stderr.decode()
    assert "line 1: line longer than 65536 bytes" in err, err
    assert "line 2: value is not a finite number" in err, err
    health = [json.loads(line) for line in done.stdout.decode().splitlines()]
    assert health[-1]["meters"]["J1"]["bad"] == 1 and health[-1]["steps"] >= 45


@pytest.mark.parametrize("feed", [b"", b"timestamp,meter,value\n", b"# only a comment\n\n"])
def test_an_empty_feed_is_said_and_is_bad_input(tiny: Path, cfg: Path, feed: bytes) -> None:
    done = _monitor(tiny, cfg, stdin=feed)
    assert done.returncode == 2, done.stderr  # was 0: a run that monitored nothing "succeeded"
    assert "the feed held no readings: nothing was monitored" in done.stderr.decode()
    assert "burstloc: error: no usable readings in stdin" in done.stderr.decode()
    assert done.stdout == b""


def test_a_feed_of_only_bad_readings_is_said(tiny: Path, cfg: Path) -> None:
    feed = b"t,meter,value\n0.0,J9,60.0\n\xff\xfe0,J1,\x9960\n"
    done = _monitor(tiny, cfg, stdin=feed)
    assert done.returncode == 2, done.stderr
    err = done.stderr.decode()
    assert "the feed held no usable readings (3 bad, skipped): nothing was monitored" in err, err
    assert "line 3: not UTF-8 text" in err, err


def test_bad_options_and_a_foreign_state_stop_it_by_name(
    tiny: Path, cfg: Path, tmp_path: Path
) -> None:
    done = _monitor(tiny, cfg, "--readings", str(tmp_path / "missing.csv"))
    assert done.returncode == 2 and b"cannot read readings" in done.stderr
    done = _monitor(tiny, cfg, "--plausible", "J1=5")
    assert done.returncode == 2 and b"want [METER=]LOW:HIGH" in done.stderr
    done = _monitor(tiny, cfg, "--plausible", "J7=0:10")
    assert done.returncode == 2 and b"plausible range for unknown meter 'J7'" in done.stderr
    done = _monitor(tiny, cfg, "--mqtt", "host:0")
    assert done.returncode == 2 and b"--mqtt wants HOST:PORT" in done.stderr
    state = tmp_path / "state.json"
    assert _monitor(tiny, cfg, "--state", str(state), stdin=_steady(50)).returncode == 0
    done = _monitor(tiny, cfg, "--state", str(state), "--detector", "shewhart")
    assert done.returncode == 2
    assert b"belongs to another network or configuration (detector" in done.stderr
    doc = json.loads(state.read_text())
    doc["state"]["monitor"] = {}
    state.write_text(json.dumps(doc))
    done = _monitor(tiny, cfg, "--state", str(state))
    assert done.returncode == 2 and b"is malformed" in done.stderr
    done = _monitor(tiny, cfg, "--queue-size", "0")
    assert done.returncode == 2 and b"--queue-size must be >= 1" in done.stderr
    done = _monitor(tiny, cfg, "--save-every", "nan")
    assert done.returncode == 2 and b"--save-every must be a finite number" in done.stderr


def test_classify_and_operations_options(tiny: Path, cfg: Path, tmp_path: Path) -> None:
    from burstloc.localize.classify import ClassifierConfig

    classifier = ClassifierConfig(max_residual=1.0, min_scale=0.0, rise_tolerance=0.05)
    path = classifier.save(tmp_path / "classifier.json")
    ops = tmp_path / "ops.csv"
    ops.write_text("asset,time,action\nJ1,5,demand on\n")
    done = _monitor(tiny, cfg, "--classify", str(path), "--operations", str(ops),
                    "--health-every", "10", stdin=_steady(100))  # fmt: skip
    assert done.returncode == 0, done.stderr
    health = [json.loads(line) for line in done.stdout.decode().splitlines()]
    assert health[-1]["decisions"] == 0 and health[-1]["events"] == 0
    alone = _monitor(tiny, cfg, "--operations", str(ops), stdin=_steady(10))
    assert alone.returncode != 0 and b"--operations needs --classify" in alone.stderr
    ops.write_text("asset,time,action\nJ1,soon,demand on\n")
    bad = _monitor(tiny, cfg, "--classify", str(path), "--operations", str(ops))
    assert bad.returncode != 0 and b"line 2" in bad.stderr


@pytest.mark.parametrize("node", ["R1", "J9"])
def test_a_configuration_whose_meter_is_not_a_junction_is_refused_by_name(
    tiny: Path, cfg: Path, tmp_path: Path, node: str
) -> None:
    """A configuration edited by hand: meter J4 renamed everywhere (so the file is consistent
    and still bound to the network's SHA-256) to the reservoir R1 or to a node the network does
    not have. The monitor refuses it before reading anything, as `calibrate` refuses such
    meters."""
    edited = tmp_path / "edited.json"
    edited.write_text(cfg.read_text().replace('"J4"', f'"{node}"'))
    assert node in json.loads(edited.read_text())["meters"]
    done = _monitor(tiny, edited, stdin=_steady(50))
    assert done.returncode == 2, done.stderr
    assert done.stderr.decode().splitlines() == [
        f"burstloc: error: 1 meter(s) ['{node}'] are not junctions of {tiny} (in configuration "
        "'tiny-calibrated')"
    ]
    assert done.stdout == b""


def test_a_feed_line_in_another_time_form_is_named_counted_and_skipped(
    tiny: Path, cfg: Path, tmp_path: Path
) -> None:
    feed = tmp_path / "feed.csv"
    argv = [sys.executable, "-m", "burstloc", "simulate", str(tiny), "--pipe", "C"]
    argv += ["--capture-interval", "0.2", "--feed", str(feed), "--noise", "0.002"]
    argv += ["--out", str(tmp_path / "sims")]
    subprocess.run(argv, capture_output=True, check=True)
    lines = feed.read_bytes().splitlines(keepends=True)
    odd = next(k for k, line in enumerate(lines) if line.startswith(b"40,J2,"))
    runs = {}
    for name, stamp in [("clean", b"40"), ("mixed", b"1970-01-01T00:00:40Z")]:
        lines[odd] = stamp + lines[odd][2:]
        runs[name] = done = _monitor(tiny, cfg, "--health-every", "1000", stdin=b"".join(lines))
        assert done.returncode == 0, done.stderr
    err = runs["mixed"].stderr.decode()
    said = (
        f"burstloc monitor: bad reading skipped: line {odd + 1}: timestamp in ISO 8601 in a "
        "feed of seconds (since line 2): '1970-01-01T00:00:40Z,J2,"
    )
    assert said in err, err
    others = [line for line in err.splitlines() if not line.startswith(said)]
    assert others == runs["clean"].stderr.decode().splitlines()  # nothing else said
    records = {
        name: [json.loads(line) for line in done.stdout.decode().splitlines()]
        for name, done in runs.items()
    }
    decisions = {
        name: [r for r in found if r["type"] == "decision"] for name, found in records.items()
    }
    assert decisions["mixed"][-1]["pipes"][0]["pipe"] == "C"
    assert [d["time"] for d in decisions["mixed"]] == [d["time"] for d in decisions["clean"]]
    health = {name: found[-1]["health"]["meters"] for name, found in decisions.items()}
    assert health["mixed"]["J2"]["bad"] == health["clean"]["J2"]["bad"] + 1
    assert health["mixed"]["J2"]["readings"] == health["clean"]["J2"]["readings"] - 1
