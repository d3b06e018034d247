"""burstloc.incidents.counts and migration 0005, on SQLite and PostgreSQL: the database counts
each meter's incidents, false alarms and found bursts exactly as
:func:`~burstloc.incidents.outcomes.meter_outcomes` does over every incident read (an answer
that changes the alarmed meters, an alarm that names none, a meter fault, a meter named twice),
a store of the revision before is filled in, and ``/metrics`` shows the counts."""

from __future__ import annotations

import json

from revisions import migrate
from test_outcomes import RECORD, _alarm, _close

from burstloc.incidents import IncidentStore, Outcome
from burstloc.incidents.intake import from_record, meter_fault
from burstloc.incidents.outcomes import MeterCounts, alarmed_meters, meter_outcomes


def _rows(store: IncidentStore) -> dict[int, list[str]]:
    """The ``incident_meters`` rows, per incident."""
    from sqlalchemy import select

    from burstloc.incidents.schema import incident_meters as im

    out: dict[int, list[str]] = {}
    with store.read() as connection:
        for incident, meter in connection.execute(select(im).order_by(im.c.meter)):
            out.setdefault(int(incident), []).append(meter)
    return out


def _agree(store: IncidentStore) -> list[MeterCounts]:
    """The database's counts, checked equal to meter_outcomes over every incident."""
    counted = store.meter_counts()
    assert counted == [m.counts() for m in meter_outcomes(store.incidents())]
    return counted


def test_the_database_counts_what_meter_outcomes_counts(target: str) -> None:
    store = IncidentStore.open(target)
    try:
        assert _agree(store) == []
        false = _alarm(store, 10.0, ["J1", "J3"])
        changed = _alarm(store, 500.0, ["J1", "J3"], "transient")  # the early record...
        assert _alarm(store, 500.0, ["J3", "J4"]) == changed  # ...and its answer: J1 is gone
        found = _alarm(store, 900.0, ["J4", "J2", "J4"])  # J4 named twice: one incident
        still_open = _alarm(store, 1300.0, ["J2"])
        none = _alarm(store, 1700.0, [])  # an alarm that names no meter
        unnamed = _alarm(store, 2100.0, None, "event")  # a record without "alarmed"
        fault = meter_fault("J1", "silent", True, 1e9, 2200.0)
        (silent,) = store.take([fault])  # a meter fault: no alarm's meters
        emptied = _alarm(store, 2500.0, ["J5"], "transient")
        assert _alarm(store, 2500.0, []) == emptied  # an answer that names none any more
        _close(store, false, Outcome.false_alarm())
        _close(store, changed, Outcome.false_alarm())
        _close(store, found, Outcome.found(400.0, -50.0))
        _close(store, none, Outcome.false_alarm())
        _close(store, silent, Outcome.false_alarm())
        assert store.get(changed)["alarmed"] == ["J3", "J4"]
        rows = _rows(store)
        assert rows == {false: ["J1", "J3"], changed: ["J3", "J4"], found: ["J2", "J4"],
                        still_open: ["J2"]}  # fmt: skip
        assert unnamed not in rows and emptied not in rows
        assert _agree(store) == [
            MeterCounts("J3", 2, 2, 0),
            MeterCounts("J1", 1, 1, 0),
            MeterCounts("J4", 2, 1, 1),
            MeterCounts("J2", 2, 0, 1),
        ]
    finally:
        store.close()


def test_taking_the_same_news_again_keeps_one_row_per_meter(target: str) -> None:
    store = IncidentStore.open(target)
    try:
        record = {**RECORD, "alarmed": ["J1", "J3"]}
        item = from_record(record, 1e9)
        assert item is not None
        (incident,) = store.take([item])
        assert store.take([item]) == [0]  # already stored
        assert _rows(store) == {incident: ["J1", "J3"]}
        assert _agree(store) == [MeterCounts("J1", 1, 0, 0), MeterCounts("J3", 1, 0, 0)]
    finally:
        store.close()


def test_the_metrics_gauges_are_the_stores_counts(target: str) -> None:
    from burstloc.web.metrics import _outcomes

    store = IncidentStore.open(target)
    try:
        a = _alarm(store, 10.0, ["J1", "J3"])
        _alarm(store, 500.0, ["J3", "X9"])
        _close(store, a, Outcome.false_alarm())
        samples = {
            (family.name, s.labels["meter"]): s.value
            for family in _outcomes(["J1", "J2", "J3"], store.meter_counts())
            for s in family.samples
        }
    finally:
        store.close()
    assert samples == {
        ("burstloc_meter_false_alarms", "J1"): 1, ("burstloc_meter_false_alarms", "J2"): 0,
        ("burstloc_meter_false_alarms", "J3"): 1, ("burstloc_meter_false_alarms", "X9"): 0,
        ("burstloc_meter_alarmed_incidents", "J1"): 1,
        ("burstloc_meter_alarmed_incidents", "J2"): 0,
        ("burstloc_meter_alarmed_incidents", "J3"): 2,
        ("burstloc_meter_alarmed_incidents", "X9"): 1,
    }  # fmt: skip


def test_alarmed_meters_are_each_meter_once_in_order() -> None:
    assert alarmed_meters(None) == [] and alarmed_meters([]) == []
    assert alarmed_meters(["J4", "J2", "J4", "J1"]) == ["J4", "J2", "J1"]


def test_migration_0005_fills_in_the_meters_of_incidents_stored_before(target: str) -> None:
    from sqlalchemy import inspect, text

    from burstloc.incidents.engine import make_engine, store_url

    engine = make_engine(store_url(target))
    stored = [  # (alarmed, outcome)
        (["J1", "J3"], "false-alarm"),
        (["J3", "J4", "J3"], "found"),
        (["J4"], None),
        ([], "false-alarm"),
        (None, "false-alarm"),  # a meter fault's
        ({"not": "a list"}, None),
    ]
    with engine.connect().execution_options(burstloc_write=True) as connection:
        migrate(connection, "0004")  # a store as the burstloc before this one made it
        with connection.begin():
            for k, (alarmed, outcome) in enumerate(stored):
                connection.execute(
                    text(
                        "INSERT INTO incidents (key, kind, state, detected_at, updated_at, "
                        "summary, alarmed, outcome) VALUES (:k, 'burst', :s, 1, 1, 's', :a, :o)"
                    ),
                    {"k": f"alarm:{k}", "s": "closed" if outcome else "detected", "o": outcome,
                     "a": None if alarmed is None else json.dumps(alarmed)},
                )  # fmt: skip
    store = IncidentStore.open(target)  # upgraded to 0005
    try:
        assert _rows(store) == {1: ["J1", "J3"], 2: ["J3", "J4"], 3: ["J4"]}
        assert store.meter_counts() == [
            MeterCounts("J1", 1, 1, 0), MeterCounts("J3", 2, 1, 1), MeterCounts("J4", 2, 0, 1),
        ]  # fmt: skip
        rows = [r for r in store.incidents() if isinstance(r["alarmed"], list | None)]
        assert store.meter_counts() == [m.counts() for m in meter_outcomes(rows)]
        later = _alarm(store, 62.4, ["J1"])  # and written with every incident from now on
        assert _rows(store)[later] == ["J1"]
    finally:
        store.close()
    with engine.connect().execution_options(burstloc_write=True) as connection:
        migrate(connection, "0004", down=True)
        assert "incident_meters" not in inspect(connection).get_table_names()
    engine.dispose()
