"""The batch path (``parse_row`` → ``Health.admit_row`` → ``StepFeed.push_row`` →
``LiveLoop.feed_payload``) answers exactly what feeding the same items one by one answers:
decisions, health records and counters, reports, and the whole saved state."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from live_feed import Collected

from burstloc.live.feeds import StepFeed
from burstloc.live.health import Health
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading, parse_payload, parse_row
from burstloc.live.plausible import PlausibleRange
from burstloc.localize.config import Calibration
from burstloc.readings import Reading

PIPE = "C"  # the burst pipe of the tiny_feed fixture


def _messages(feed: list[Reading], seed: int) -> list[bytes]:
    """``feed`` made dirty and cut into messages of 1 to 40 items: a meter's clock 2 s ahead
    (found and corrected), J4 silent for 60 s, readings late, duplicated and dropped, bad items
    inside batches (unknown meter, implausible, NaN, wrong types), malformed messages, single
    readings, CSV payloads and ``{"readings": [...]}`` batches."""
    rng = np.random.default_rng(seed)
    burst = next(r.timestamp for r in feed if r.timestamp >= 60.0)
    items: list[Any] = []
    for k, r in enumerate(feed):
        if r.meter == "J4" and burst + 40.0 <= r.timestamp < burst + 100.0:
            continue  # silent: excluded, then included again
        if rng.random() < 0.01:
            continue  # dropped
        t = r.timestamp + (2.0 if r.meter == "J2" else 0.0)
        items.append({"t": t, "meter": r.meter, "value": r.value})
        if rng.random() < 0.005:
            items.append({"t": t, "meter": r.meter, "value": r.value + 1.0})  # duplicate
        if rng.random() < 0.004 and k > 100:
            old = feed[k - 60]  # 3 s late
            items.append({"t": old.timestamp, "meter": old.meter, "value": old.value})
        if rng.random() < 0.003:
            items.append(
                [
                    {"t": t, "meter": "nowhere", "value": 1.0},
                    {"t": t, "meter": "J3", "value": 1e6},
                    {"t": t, "meter": "J1", "value": "NaN"},
                    {"t": "soon", "meter": "J1", "value": 50.0},
                    {"t": t, "meter": ["J1"], "value": 50.0},
                    {"t": int(t), "meter": 7, "value": 50},
                    17,
                ][rng.integers(7)]
            )
    out: list[bytes] = []
    i = 0
    while i < len(items):
        size = int(rng.integers(1, 41))
        batch, i = items[i : i + size], i + size
        form = rng.random()
        if form < 0.03:
            out.append(b"{malformed")
        if form < 0.1 and isinstance(batch[0], dict) and isinstance(batch[0]["t"], float):
            out.extend(json.dumps(b).encode() for b in batch)  # one reading per message
        elif form < 0.15:
            lines = [f"{o['t']},{o['meter']},{o['value']}" for o in batch if isinstance(o, dict)]
            out.append("\n".join(lines).encode())
        elif form < 0.2:
            out.append(json.dumps({"readings": batch}).encode())
        else:
            out.append(json.dumps(batch).encode())
    return out


def _loop(tiny: Path, config: Calibration) -> Collected:
    monitor = BurstMonitor(tiny, config, capture_interval=0.2)
    return Collected(monitor, silent_after=10.0, health_every=20.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rows_give_exactly_what_items_one_by_one_give(tiny, tiny_config, tiny_feed, seed) -> None:
    config, feed = tiny_config, tiny_feed
    messages = _messages(feed, seed)
    one, rows = _loop(tiny, config), _loop(tiny, config)
    for n, payload in enumerate(messages):
        where = f"message {n}"
        for item in parse_payload(payload, where):
            one.loop.feed(item, where)
        rows.loop.feed_payload(payload, where)
    one.loop.finish()
    rows.loop.finish()

    assert rows.messages == one.messages
    text = "\n".join(one.messages)
    for said in [
        "clock offset +2 s found",
        "is off the clock",
        "late reading from meter",
        "unknown meter 'nowhere'",
        "implausible value 1e+06 m",
        "payload is not valid JSON",
        "'t' must be seconds or an ISO 8601 time",
        "meter 'J4' silent",
        "meter 'J4' reports again",
    ]:
        assert said in text  # the feed exercised every rule
    assert rows.health_records == one.health_records and len(one.health_records) > 5
    assert rows.loop.to_state() == one.loop.to_state()
    assert rows.health.record() == one.health.record()
    (decision,) = one.decisions
    assert decision["pipes"][0]["pipe"] == PIPE
    # The health inside a decision record is taken after the message's readings up to the
    # next periodic check (one by one: after the reading that completed the decision).
    strip = [{k: v for k, v in d.items() if k != "health"} for d in rows.decisions]
    assert strip == [{k: v for k, v in d.items() if k != "health"} for d in one.decisions]
    for a, b in zip(rows.decisions, one.decisions, strict=True):
        for key in ("silent", "clock_corrected", "excluded", "pending", "holding_off"):
            assert a["health"][key] == b["health"][key]


def test_parse_row_is_parse_payload_in_columns() -> None:
    columns = {"a": 0, "b": 1}
    payload = json.dumps(
        [
            {"t": 1.0, "meter": "b", "value": 2.5},
            {"t": 1, "meter": "a", "value": 3},
            {"t": 1.0, "meter": "c", "value": 1.0},
            {"t": float("nan"), "meter": "a", "value": 1.0},
            {"t": 1.0, "meter": "a", "value": 1e400},
        ]
    ).encode()
    row = parse_row(payload, "message 3", columns)
    assert (row.positions, row.times, row.columns, row.values) == (
        [0, 1],
        [1.0, 1.0],
        [1, 0],
        [2.5, 3.0],
    )
    assert row.size == 5 and [p for p, _ in row.bad] == [2, 3, 4]
    assert str(row.bad[0][1]) == "message 3: unknown meter 'c'"
    items = parse_payload(payload, "message 3")
    assert [str(b) for _, b in row.bad[1:]] == [str(i) for i in items[3:]]
    csv = parse_row(b"1.0,a,2.0\n1.0,zz,3.0\n", "message 4", columns)
    assert (csv.times, csv.columns, csv.values, csv.size) == ([1.0], [0], [2.0], 2)
    for junk in [b"", b"\xff\xfe", b"[1, 2", b'{"readings": 5}', b"[[[[" * 10_000]:
        row = parse_row(junk, "m", columns)
        assert not row.positions and len(row.bad) == row.size >= 1


def test_a_row_is_the_same_as_its_readings_one_by_one() -> None:
    rng = np.random.default_rng(3)
    meters = ("a", "b", "c")
    one, rows = (StepFeed(meters, timeout=2, missing="hold", period=0.5) for _ in range(2))
    items = [(round(k * 0.5, 3), j, float(rng.normal())) for k in range(200) for j in range(3)]
    items = [x for x in items if rng.random() > 0.1]
    rng.shuffle(items[100:160])  # out of order, late readings among them
    items += items[50:55]  # late ones
    for k in (31, 77, 190):
        items.insert(k, (items[k - 1][0], items[k - 1][1], 9.9))  # duplicates
    got: list[Any] = []
    for t, j, v in items:
        got += [
            (s.timestamp, s.values.tolist(), s.filled) for s in one.push(Reading(t, meters[j], v))
        ]
    row, late = rows.push_row(*(list(x) for x in zip(*items, strict=True)))
    assert [(s.timestamp, s.values.tolist(), s.filled) for _, s in row] == got
    assert len(late) == one.stats.late > 0 and one.stats.duplicates > 0
    assert rows.to_state() == one.to_state()


def test_health_admit_row_refuses_by_position() -> None:
    health = Health(
        ("a", "b"), PlausibleRange({"a": 0, "b": 0}, {"a": 10, "b": 10}), capture_interval=1.0
    )
    row = health.admit_row([0.0, 0.0, 1.0], [0, 1, 1], [5.0, 50.0, 6.0], "m", [4, 7, 9])
    assert row.positions == [4, 9] and row.times == [0.0, 1.0] and row.values == [5.0, 6.0]
    ((position, column, bad),) = row.refused
    assert (position, column) == (7, 1) and isinstance(bad, BadReading)
    assert "implausible value 50 m from meter 'b'" in str(bad)
    assert health.meter["b"].counts["implausible"] == 1


def test_a_reading_fed_with_a_non_finite_number_is_reported_and_skipped(tiny, tiny_config) -> None:
    done = _loop(tiny, tiny_config)
    good = Reading(0.0, "J1", 50.0)
    done.run([Reading(float("nan"), "J1", 50.0), Reading(0.0, "J2", float("inf")), good])
    assert done.loop.stream.stats.readings == 1
    assert [m.split(": ", 1)[1] for m in done.messages[:2]] == [
        "bad reading skipped: reading 1: not a finite reading (nan s, 50.0 m) from meter 'J1'",
        "bad reading skipped: reading 2: not a finite reading (0.0 s, inf m) from meter 'J2'",
    ]
    assert done.health.meter["J1"].counts["bad"] == 1 and done.health.meter["J2"].counts["bad"] == 1
