"""burstloc.incidents.outcomes and migration 0003, on SQLite and PostgreSQL: the meters whose
alarms made each incident are kept (and filled in for records stored before), false alarms are
counted per meter, and a burst found at a point becomes a known event on the nearest pipe, or
is named with the reason it cannot."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from revisions import migrate

from burstloc.incidents import IncidentStore, Outcome
from burstloc.incidents.intake import Kept, from_record
from burstloc.incidents.outcomes import known_events, meter_outcomes
from burstloc.layout import read_layout

RECORD = {
    "type": "decision", "burst": True, "time": 75.0, "first_alarm": 62.4,
    "pipes": [{"pipe": "C", "score": 0.0}], "alarmed": ["J1", "J3"],
}  # fmt: skip


def _alarm(
    store: IncidentStore, first: float, alarmed: list[str] | None, kind: str = "decision"
) -> int:
    """The incident of an alarm first at ``first`` (a record of type ``kind``) naming
    ``alarmed`` (``None``: a record without them)."""
    record = {**RECORD, "type": kind, "first_alarm": first, "alarmed": alarmed}
    item = from_record(record, 1e9 + first)
    assert item is not None
    (incident,) = store.take([item])
    return incident


def _close(store: IncidentStore, incident: int, outcome: Outcome) -> None:
    store.acknowledge(incident, "ann", "cli")
    store.close_incident(incident, "ann", "cli", outcome)


def test_false_alarms_are_counted_per_meter_that_alarmed(target: str) -> None:
    store = IncidentStore.open(target)
    try:
        a = _alarm(store, 10.0, ["J1", "J3"])
        b = _alarm(store, 500.0, ["J3", "J4"])
        c = _alarm(store, 900.0, ["J1", "J3"])
        _alarm(store, 1300.0, ["J2", "J4"])  # still open
        _close(store, a, Outcome.false_alarm())
        _close(store, b, Outcome.false_alarm())
        _close(store, c, Outcome.found(400.0, -50.0))
        got = {m.meter: m.to_json() for m in meter_outcomes(store.incidents())}
        assert [m.meter for m in meter_outcomes(store.incidents())] == ["J3", "J1", "J4", "J2"]
        assert got["J3"]["false_alarm_incidents"] == [a, b] and got["J3"]["found_incidents"] == [c]
        assert (got["J1"]["alarmed"], got["J1"]["false_alarms"], got["J1"]["found"]) == (2, 1, 1)
        assert (got["J4"]["alarmed"], got["J4"]["false_alarms"]) == (2, 1)
        assert (got["J2"]["alarmed"], got["J2"]["false_alarms"]) == (1, 0)
        assert store.get(a)["alarmed"] == ["J1", "J3"]
    finally:
        store.close()


def test_the_answer_replaces_the_early_records_alarmed_meters(target: str) -> None:
    store = IncidentStore.open(target)
    try:
        early = from_record({**RECORD, "type": "transient", "alarmed": ["J1", "J3"]}, 1e9)
        answer = from_record({**RECORD, "alarmed": ["J1", "J3", "J4"]}, 1e9 + 5)
        assert early is not None and answer is not None
        (incident,) = store.take([early])
        store.take([answer])
        assert store.get(incident)["alarmed"] == ["J1", "J3", "J4"]
    finally:
        store.close()


def test_kept_readings_go_to_the_newest_incident_of_their_key(target: str) -> None:
    store = IncidentStore.open(target)
    try:
        incident = _alarm(store, 62.4, ["J1", "J3"])
        version = store.version()
        kept = Kept("alarm:62.400000", "/data/alarm-62.400000.csv", 61.8)
        assert store.take([kept, Kept("alarm:1.000000", "/elsewhere.csv", 0.5)]) == [incident, 0]
        doc = store.get(incident)
        assert (doc["readings"], doc["onset"]) == ("/data/alarm-62.400000.csv", 61.8)
        assert store.version() == version  # no history row: nothing an operator acts on
        assert len(store.incidents()) == 1
    finally:
        store.close()


def test_migration_0003_fills_in_the_alarmed_meters_of_records_stored_before(
    target: str,
) -> None:
    from sqlalchemy import text

    from burstloc.incidents.engine import make_engine, store_url

    engine = make_engine(store_url(target))
    with engine.connect().execution_options(burstloc_write=True) as connection:
        migrate(connection, "0002")  # a store as the burstloc before this one made it
        with connection.begin():
            for key, record in [("alarm:1", json.dumps(RECORD)), ("meter:J2:silent", None)]:
                connection.execute(
                    text(
                        "INSERT INTO incidents (key, kind, state, detected_at, updated_at, "
                        "summary, record) VALUES (:k, 'burst', 'detected', 1, 1, 's', :r)"
                    ),
                    {"k": key, "r": record},
                )
    engine.dispose()
    store = IncidentStore.open(target)  # upgraded to 0003
    try:
        rows = {r["id"]: r for r in store.incidents()}
        assert all(r["readings"] is None and r["onset"] is None for r in rows.values())
        assert [rows[k]["alarmed"] for k in sorted(rows)] == [["J1", "J3"], None]
    finally:
        store.close()


def _found(tmp_path: Path, **row: Any) -> dict[str, Any]:
    feed = tmp_path / "kept" / "alarm-62.400000.csv"
    feed.parent.mkdir(exist_ok=True)
    feed.write_text("timestamp,meter,value\n0,J1,50\n", encoding="utf-8")
    base = {"id": 1, "outcome": "found", "found_x": 400.0, "found_y": -50.0,
            "readings": str(feed), "onset": 61.8}  # fmt: skip
    return {**base, **row}


def test_a_found_point_becomes_an_event_on_the_nearest_pipe(tiny: Path, tmp_path: Path) -> None:
    layout = read_layout(tiny)  # pipe C runs from J1 (300, 0) to J3 (500, -100)
    out = tmp_path / "out" / "events.json"
    rows = [
        _found(tmp_path),  # C's midpoint
        _found(tmp_path, id=2, found_x=462.0, found_y=-76.0),  # 4.5 beside C, 80 % along it
        {"id": 3, "outcome": "false-alarm", "found_x": None, "found_y": None},
    ]
    entries, refusals = known_events(rows, layout, out)
    assert not refusals
    assert [(e["pipe"], e["position"], e["time"]) for e in entries] == [
        ("C", 0.5, 61.8), (("C", pytest.approx(0.8, abs=1e-6), 61.8)),
    ]  # fmt: skip
    assert all(e["time_known"] is False for e in entries)
    assert entries[0]["readings"] == "../kept/alarm-62.400000.csv"
    assert entries[0]["name"] == "incident 1: burst found at 400,-50"


def test_each_found_incident_that_cannot_be_an_event_is_named_with_why(
    tiny: Path, tmp_path: Path
) -> None:
    layout = read_layout(tiny)
    rows = [
        _found(tmp_path, id=1, readings=None),
        _found(tmp_path, id=2, readings=str(tmp_path / "gone.csv")),
        _found(tmp_path, id=3, onset=None),
        _found(tmp_path, id=4, found_x=680.0, found_y=-300.0),  # 200 below J4, the end of E
        _found(tmp_path, id=5),
    ]
    entries, refusals = known_events(rows, layout, tmp_path / "e.json", within=50.0)
    assert [e["name"].split(":")[0] for e in entries] == ["incident 5"]
    assert len(refusals) == 4
    assert refusals[0].startswith("incident 1 (found at 400,-50): no readings were kept")
    assert "gone.csv" in refusals[1] and "is gone" in refusals[1]
    assert "onset of its first alarm is unknown" in refusals[2]
    assert "the point is 200.0 from the nearest pipe (E), farther than 50" in refusals[3]
