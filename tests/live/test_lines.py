"""A feed file's lines as rows (``burstloc.live.lines``, what ``burstloc monitor --readings``
reads) answer exactly what the same lines fed one by one answer: decisions, health records and
counters, reports (each naming its line), and the whole saved state; through the real CLI, the
file read whole, in a pipe's small pieces and paced line by line print the same."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from live_feed import Collected

from burstloc.live.lines import rows_of_lines
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading, TimestampForm, parse_line
from burstloc.localize.config import Calibration
from burstloc.readings import Reading

PIPE = "C"  # the burst pipe of the tiny_feed fixture
LONGEST = 200  # bytes in a line (the CLI's limit is 64 kB: a short one makes long lines cheap)


def _lines(feed: list[Reading], seed: int) -> list[bytes]:
    """``feed`` as CSV lines made dirty: a header, a meter's clock 2 s ahead (found and
    corrected), J4 silent for 60 s, readings late, duplicated and dropped, and among them blank
    lines, comments, quoted and spaced fields, CRLF endings, an unknown meter, implausible and
    non-finite values, an ISO 8601 time in a feed of seconds, a timestamp days off, bytes that
    are not UTF-8, a NUL byte, a line too long, a line without three fields."""
    rng = np.random.default_rng(seed)
    burst = next(r.timestamp for r in feed if r.timestamp >= 60.0)
    out = [b"timestamp,meter,value"]
    for k, r in enumerate(feed):
        if r.meter == "J4" and burst + 40.0 <= r.timestamp < burst + 100.0:
            continue  # silent: excluded, then included again
        if rng.random() < 0.01:
            continue  # dropped
        t = r.timestamp + (2.0 if r.meter == "J2" else 0.0)
        out.append(f"{t!r},{r.meter},{r.value!r}".encode())
        if rng.random() < 0.005:
            out.append(f"{t!r},{r.meter},{r.value + 1.0!r}".encode())  # duplicate
        if rng.random() < 0.004 and k > 100:
            old = feed[k - 60]  # 3 s late
            out.append(f"{old.timestamp!r},{old.meter},{old.value!r}".encode())
        if rng.random() < 0.01:
            out.append(
                [
                    b"",
                    b"# a comment",
                    f'"{t!r}", "{r.meter}" ,{r.value!r}'.encode(),  # quoted and spaced: a reading
                    f"{t!r},{r.meter},{r.value!r}\r".encode(),  # CRLF: a reading
                    f"{t!r},nowhere,1.0".encode(),
                    f"{t!r},J3,1e6".encode(),
                    f"{t!r},J1,nan".encode(),
                    f"{t!r},J1,inf".encode(),
                    b"1970-01-01T00:00:40Z,J1,50.0",
                    f"{t + 9e6!r},J1,50.0".encode(),
                    f"{t!r},J1,\xff\xfe".encode("latin-1"),
                    f"{t!r},J1\x00,50.0".encode(),
                    f"{t!r},J1,{'5' * LONGEST}".encode(),
                    f"{t!r},J1".encode(),
                ][rng.integers(14)]
            )
    return out


def _loop(tiny: Path, config: Calibration) -> Collected:
    monitor = BurstMonitor(tiny, config, capture_interval=0.2)
    return Collected(monitor, silent_after=10.0, health_every=20.0)


def _one_by_one(done: Collected, lines: list[bytes]) -> None:
    """Each line parsed and fed alone, sharing the loop's timestamp form (the CLI before)."""
    for number, line in enumerate(lines, start=1):
        where = f"line {number}"
        if len(line) > LONGEST:
            item: Any = BadReading(where, f"line longer than {LONGEST} bytes")
        else:
            item = parse_line(line, where, done.loop.timestamps)
        if item is not None:
            done.loop.feed(item, where)
    done.loop.finish()


def _as_rows(done: Collected, lines: list[bytes], rng: np.random.Generator) -> None:
    """The lines cut into pieces of 1 to 500, each piece one row (as each read gives them)."""
    columns = {m: j for j, m in enumerate(done.loop.monitor.meters)}
    items: list[Any] = []
    first = 0
    while first < len(lines):
        piece = lines[first : first + int(rng.integers(1, 501))]
        row = rows_of_lines(piece, first + 1, columns, done.loop.timestamps, LONGEST)
        items.append((f"lines {first + 1}-{first + len(piece)}", row))
        first += len(piece)
    done.loop.run(items)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rows_of_lines_give_exactly_what_lines_one_by_one_give(
    tiny, tiny_config, tiny_feed, seed
) -> None:
    lines = _lines(tiny_feed, seed)
    one, rows = _loop(tiny, tiny_config), _loop(tiny, tiny_config)
    _one_by_one(one, lines)
    _as_rows(rows, lines, np.random.default_rng(seed))

    assert rows.messages == one.messages
    text = "\n".join(one.messages)
    for said in [
        "clock offset +2 s found",
        "is off the clock",
        "late reading from meter",
        "unknown meter 'nowhere'",
        "implausible value 1e+06 m",
        "value is not a finite number",
        "timestamp in ISO 8601 in a feed of seconds",
        "days from the feed's clock",
        "not UTF-8 text",
        "binary data (NUL byte)",
        f"line longer than {LONGEST} bytes",
        "want 'timestamp,meter,value'",
        "meter 'J4' silent",
        "meter 'J4' reports again",
    ]:
        assert said in text, said  # the feed exercised every rule
    # every report of a reading names the line it came from
    late = next(m for m in one.messages if "late reading from meter" in m)
    number = int(late.split("line ", 1)[1].split(":")[0])
    meter = late.split("meter '", 1)[1].split("'")[0]
    assert f",{meter}," in lines[number - 1].decode()
    assert rows.health_records == one.health_records and len(one.health_records) > 5
    assert rows.loop.to_state() == one.loop.to_state()
    assert rows.health.record() == one.health.record()
    assert rows.loop.readings == one.loop.readings
    (decision,) = one.decisions
    assert decision["pipes"][0]["pipe"] == PIPE
    strip = [{k: v for k, v in d.items() if k != "health"} for d in rows.decisions]
    assert strip == [{k: v for k, v in d.items() if k != "health"} for d in one.decisions]


def test_the_feed_s_form_is_fixed_by_its_first_reading_inside_a_row() -> None:
    columns = {"a": 0, "b": 1}
    form = TimestampForm()
    row = rows_of_lines(
        [b"timestamp,meter,value", b"", b"2026-11-26T10:00:00Z,a,1.0", b"5.0,b,2.0", b"x"],
        10,
        columns,
        form,
        LONGEST,
    )
    assert form.form == "ISO 8601"
    assert row.positions == [0] and row.size == 3 and row.lines == [12, 13, 14]
    assert [(p, str(b)) for p, b in row.bad] == [
        (1, "line 13: timestamp in seconds in a feed of ISO 8601 (since line 12): '5.0,b,2.0'"),
        (2, "line 14: want 'timestamp,meter,value', got 'x'"),
    ]


def _cli(tiny: Path, config: Path, *extra: str, stdin: Any = None) -> tuple[str, str]:
    done = subprocess.run(
        [
            sys.executable, "-m", "burstloc", "monitor", str(tiny), "--config", str(config),
            "--capture-interval", "0.2", "--health-every", "20", "--silent-after", "10",
            *extra,
        ],
        capture_output=True, text=True, check=False, env=dict(os.environ), stdin=stdin,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout, done.stderr


def test_the_cli_reads_a_file_whole_in_a_pipe_s_pieces_and_paced_alike(
    tiny, tiny_config, tiny_feed, tmp_path
) -> None:
    config = tiny_config.save(tmp_path / "tiny.json")
    path = tmp_path / "feed.csv"
    lines = [line for line in _lines(tiny_feed, 4) if len(line) <= LONGEST]
    path.write_bytes(b"\n".join(lines) + b"\n")
    whole = _cli(tiny, config, "--readings", str(path))
    paced = _cli(tiny, config, "--readings", str(path), "--replay-speed", "1e9")
    # stdin in pieces that cut lines in two: a writer sending 4 kB at a time
    writer = subprocess.Popen([sys.executable, "-c", _PIECES, str(path)], stdout=subprocess.PIPE)
    with writer:
        piped = _cli(tiny, config, "--readings", "-", stdin=writer.stdout)
    assert writer.returncode == 0
    assert '"pipe": "C"' in whole[0] and "late reading from meter" in whole[1]
    assert whole == piped  # a pipe's pieces cut lines anywhere: the same rows' answers
    assert whole[1] == paced[1]  # every report, in order, naming the same lines
    # records alike; the health inside a decision (or an early, transient record) is taken
    # after the read's readings up to the next periodic check (line by line: after the reading
    # that completed the decision)
    assert _records(whole[0]) == _records(paced[0])


def _records(stdout: str) -> list[dict[str, Any]]:
    records = [json.loads(line) for line in stdout.splitlines()]
    return [
        {k: v for k, v in r.items() if r["type"] not in ("decision", "transient") or k != "health"}
        for r in records
    ]


_PIECES = """
import os, sys, time
data = open(sys.argv[1], "rb").read()
for k in range(0, len(data), 4096):
    os.write(1, data[k : k + 4096])
    time.sleep(0.001)
"""
