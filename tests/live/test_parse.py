"""burstloc.live.parse: CSV lines and MQTT payloads to readings; bad input named, never raised."""

from __future__ import annotations

import json

from burstloc.live.parse import (
    SECONDS,
    BadReading,
    TimestampForm,
    parse_lines,
    parse_payload,
    parse_row,
)
from burstloc.readings import Reading


def test_csv_lines_header_bom_quotes_and_comments() -> None:
    lines = ["\ufefftimestamp,meter,value", "# note", "", '0.2,"N2",181.5', "0.4, N3 ,180"]
    assert list(parse_lines(lines)) == [Reading(0.2, "N2", 181.5), Reading(0.4, "N3", 180.0)]


def test_iso_8601_and_epoch_timestamps_are_read_as_epoch_seconds() -> None:
    # what historians export: ISO 8601 with an offset or Z; before, every such line was bad
    epoch = 1_795_687_200.0  # 2026-11-26T10:00:00Z
    lines = [
        "2026-11-26T10:00:00.2Z,N2,181.5",
        "2026-11-26T12:00:00.400+02:00,N2,181.4",
        "oops,N2,1.0",
    ]
    items = list(parse_lines(lines))
    assert [(i.meter, i.value) for i in items[:2]] == [("N2", 181.5), ("N2", 181.4)]
    times = [i.timestamp for i in items[:2] if isinstance(i, Reading)]
    assert abs(times[0] - (epoch + 0.2)) < 1e-6 and abs(times[1] - (epoch + 0.4)) < 1e-6
    assert isinstance(items[2], BadReading) and "neither seconds nor an ISO 8601" in items[2].reason
    assert list(parse_lines([f"{epoch + 0.6},N2,181.3"])) == [Reading(epoch + 0.6, "N2", 181.3)]
    payload = json.dumps({"t": "2026-11-26T10:00:01Z", "meter": "N3", "value": 1.0}).encode()
    assert parse_payload(payload, "m") == [Reading(epoch + 1.0, "N3", 1.0)]


def test_every_kind_of_bad_line_is_named_with_its_line_and_skipped() -> None:
    lines = [
        "0.2,N2,abc",
        "0.2,N2,nan",
        "2026-01-01T00:00:00,N2,1.0",
        "0.2,N2",
        "0.2,,1.0",
        b"\xff\xfe0.2,N2,1.0",
        "0.2,N2\x00,1.0",
        "0.4,N2,1.5",
    ]
    items = list(parse_lines(lines))
    bad = [i for i in items if isinstance(i, BadReading)]
    assert [b.where for b in bad] == [f"line {k}" for k in range(1, 8)]
    assert "value is not a finite number" in bad[0].reason and bad[0].meter == "N2"
    assert "ISO 8601 timestamp without a UTC offset" in bad[2].reason  # its zone is unknown
    assert "want 'timestamp,meter,value'" in bad[3].reason
    assert "no meter name" in bad[4].reason
    assert bad[5].reason == "not UTF-8 text" and "binary" in bad[6].reason
    assert items[-1] == Reading(0.4, "N2", 1.5)


def test_json_payloads_single_batch_and_csv_form() -> None:
    one = json.dumps({"t": 1.0, "meter": "N2", "value": 180.0}).encode()
    assert parse_payload(one, "message 1") == [Reading(1.0, "N2", 180.0)]
    batch = json.dumps({"readings": [{"t": 1.0, "meter": 2, "value": 3}, {"t": "x"}]}).encode()
    got = parse_payload(batch, "message 2")
    assert got[0] == Reading(1.0, "2", 3.0)
    assert isinstance(got[1], BadReading) and got[1].where == "message 2 item 1"
    listed = json.dumps([{"timestamp": 2.0, "meter": "N3", "value": 1e400}]).encode()
    assert isinstance(parse_payload(listed, "m")[0], BadReading)
    assert parse_payload(b"1.0,N2,180\n1.2,N2,181", "m") == [
        Reading(1.0, "N2", 180.0),
        Reading(1.2, "N2", 181.0),
    ]
    for payload, reason in [
        (b"{not json", "not valid JSON"),
        (b"\xff", "not UTF-8"),
        (b"", "empty payload"),
        (b'{"t": true, "meter": "N2", "value": 1}', "'t' must be"),
        (b'{"readings": 3}', "'readings' must be a list"),
    ]:
        (item,) = parse_payload(payload, "message 9")
        assert isinstance(item, BadReading) and reason in item.reason, (payload, item)


def test_a_feed_keeps_the_timestamp_form_of_its_first_reading() -> None:
    # one line in ISO 8601 among seconds, at the same instant: only its form tells it apart
    lines = ["timestamp,meter,value", "39.8,N2,181.5", "1970-01-01T00:00:40Z,N2,181.4", "40.2,N2,1"]
    items = list(parse_lines(lines))
    assert items[0] == Reading(39.8, "N2", 181.5) and items[2] == Reading(40.2, "N2", 1.0)
    bad = items[1]
    assert isinstance(bad, BadReading) and bad.where == "line 3" and bad.meter == "N2"
    assert bad.reason == (
        "timestamp in ISO 8601 in a feed of seconds (since line 2): '1970-01-01T00:00:40Z,N2,181.4'"
    )
    # a bad line does not fix the form; the first reading does
    items = list(parse_lines(["x,N2,1", "2026-11-26T10:00:00Z,N2,1", "1795687200.2,N2,1"]))
    assert isinstance(items[0], BadReading) and isinstance(items[1], Reading)
    assert isinstance(items[2], BadReading) and "in seconds in a feed of ISO 8601" in str(items[2])


def test_json_messages_keep_the_feed_s_timestamp_form_inline_path_included() -> None:
    form = TimestampForm()
    columns = {"N2": 0, "N3": 1}
    first = json.dumps([{"t": 40.0, "meter": "N2", "value": 1.0}]).encode()
    assert parse_row(first, "message 1", columns, form).times == [40.0]
    assert form.form == SECONDS and form.since == "message 1 item 0"
    mixed = [
        {"t": 40.2, "meter": "N3", "value": 2.0},
        {"t": "1970-01-01T00:00:40.2Z", "meter": "N2", "value": 2.0},
    ]
    row = parse_row(json.dumps(mixed).encode(), "message 2", columns, form)
    assert row.positions == [0] and [p for p, _ in row.bad] == [1]
    assert "timestamp in ISO 8601 in a feed of seconds" in str(row.bad[0][1])
    assert row.bad[0][1].meter == "N2"
    # a feed of ISO times: a number among them is bad, on the inline path too
    form = TimestampForm()
    iso = [{"t": "2026-11-26T10:00:00Z", "meter": "N2", "value": 1.0}, *mixed[:1]]
    row = parse_row(json.dumps(iso).encode(), "message 1", columns, form)
    assert row.positions == [0] and [p for p, _ in row.bad] == [1]
    assert "timestamp in seconds in a feed of ISO 8601" in str(row.bad[0][1])
    assert isinstance(parse_payload(b"40.4,N3,2.0", "message 2", form)[0], BadReading)
    assert parse_payload(b"40.4,N3,2.0", "message 2") == [Reading(40.4, "N3", 2.0)]  # no form
