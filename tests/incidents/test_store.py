"""The incident store on SQLite and on a real PostgreSQL server (every test runs on both): the
schema from empty, the monitor's news, the life cycle and its refusals, listings, races."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from burstloc.exceptions import InputError
from burstloc.incidents import (
    IncidentStateError,
    IncidentStore,
    IncidentStoreError,
    Outcome,
    UnknownIncidentError,
)
from burstloc.incidents.intake import from_record, meter_fault
from burstloc.incidents.migrate import HEAD

EARLY = {
    "type": "transient", "burst": None, "time": 63.0, "first_alarm": 62.4, "answer_at": 75.0,
    "pipes": [{"pipe": "9", "score": 0.0}, {"pipe": "8", "score": -1.1}],
    "region": {"length_m": 210.0, "confidence": 0.95},
}  # fmt: skip
ANSWER = {**EARLY, "type": "decision", "burst": True, "time": 75.0, "region": {"length_m": 80.0}}
del ANSWER["answer_at"]


class Clock:
    """A wall clock the test moves."""

    def __init__(self) -> None:
        self.now = 1_800_000_000.0

    def __call__(self) -> float:
        self.now += 1.0
        return self.now


@pytest.fixture
def store(target: str) -> Any:
    opened = IncidentStore.open(target, clock=Clock())
    yield opened
    opened.close()


def _burst(store: IncidentStore, first_alarm: float = 62.4, at: float = 1e9) -> int:
    early = from_record({**EARLY, "first_alarm": first_alarm}, at)
    answer = from_record({**ANSWER, "first_alarm": first_alarm}, at + 5)
    assert early is not None and answer is not None
    (incident,) = store.take([early])
    assert store.take([answer]) == [incident]
    return incident


def test_the_schema_is_made_from_empty_and_opening_again_changes_nothing(target: str) -> None:
    from sqlalchemy import inspect

    from burstloc.incidents.migrate import current_revision

    store = IncidentStore.open(target)
    try:
        with store.engine.connect() as connection:
            assert current_revision(connection) == HEAD
            tables = set(inspect(connection).get_table_names())
        assert {"incidents", "history", "alerts", "alembic_version"} <= tables
        incident = _burst(store)
    finally:
        store.close()
    again = IncidentStore.open(target)
    try:
        assert [r["id"] for r in again.incidents()] == [incident]
    finally:
        again.close()


def test_a_store_made_by_a_newer_burstloc_is_refused_and_left_alone(target: str) -> None:
    store = IncidentStore.open(target)
    with store.engine.begin() as connection:
        connection.exec_driver_sql("UPDATE alembic_version SET version_num = '9999'")
    store.close()
    with pytest.raises(IncidentStoreError, match=r"revision '9999'.*newer burstloc"):
        IncidentStore.open(target)
    store = IncidentStore(store.url)  # as it is: not migrated
    with store.engine.connect() as connection:
        version = connection.exec_driver_sql("SELECT version_num FROM alembic_version").scalar()
    store.close()
    assert version == "9999"


def test_the_early_record_and_the_answer_are_one_incident(store: IncidentStore) -> None:
    incident = _burst(store)
    doc = store.get(incident)
    assert doc["kind"] == "burst" and doc["state"] == "detected" and doc["pipe"] == "9"
    assert doc["record"]["type"] == "decision" and doc["reading_time"] == 62.4
    assert [(h["action"], h["by"], h["state"]) for h in doc["history"]] == [
        ("detected", "monitor", "detected"),
        ("answered", "monitor", "detected"),
    ]
    assert doc["history"][0]["detail"]["type"] == "transient"
    assert "search region 80 m" in doc["summary"]
    # the same news again (a replay after a restart): nothing new
    assert store.take([from_record(ANSWER, 2e9)]) == [0]  # type: ignore[list-item]
    assert len(store.get(incident)["history"]) == 2
    assert len(store.incidents()) == 1


def test_a_new_alarm_is_a_new_incident_and_so_is_news_of_a_closed_one(
    store: IncidentStore,
) -> None:
    first = _burst(store, 62.4)
    second = _burst(store, 900.0)
    assert second != first
    store.acknowledge(first, "ann", "cli")
    store.close_incident(first, "ann", "cli", Outcome.false_alarm())
    later = from_record({**ANSWER, "pipes": [{"pipe": "3", "score": 0.0}]}, 3e9)
    assert later is not None
    (third,) = store.take([later])
    assert third not in (0, first, second)
    assert store.get(first)["state"] == "closed" and store.get(third)["pipe"] == "3"


def test_the_life_cycle_records_who_did_what_and_when(store: IncidentStore) -> None:
    incident = _burst(store)
    assert store.acknowledge(incident, " ann ", "page 127.0.0.1")["state"] == "acknowledged"
    assert store.dispatch(incident, "ann", "cli", note="crew 3 sent")["state"] == "dispatched"
    store.act(incident, "note", by="bob", via="cli", note="valve V12 closed")
    doc = store.close_incident(
        incident, "bob", "page 10.0.0.7", Outcome.found(412.5, -33.0), note="under Main St"
    )
    assert doc["state"] == "closed" and doc["outcome"] == "found"
    assert (doc["found_x"], doc["found_y"]) == (412.5, -33.0)
    rows = [(h["action"], h["by"], h["via"], h["state"], h["note"]) for h in doc["history"]]
    assert rows[2:] == [
        ("acknowledged", "ann", "page 127.0.0.1", "acknowledged", None),
        ("dispatched", "ann", "cli", "dispatched", "crew 3 sent"),
        ("note", "bob", "cli", "dispatched", "valve V12 closed"),
        ("closed", "bob", "page 10.0.0.7", "closed", "under Main St"),
    ]
    assert doc["history"][-1]["detail"] == {"outcome": "found", "found_at": [412.5, -33.0]}
    times = [h["at"] for h in doc["history"][2:]]
    assert times == sorted(times) and len(set(times)) == 4  # each its own time, in order
    assert doc["closed_at"] == times[-1]
    # a closed incident still takes notes
    store.act(incident, "note", by="carol", via="cli", note="road repaired")
    assert store.get(incident)["history"][-1]["note"] == "road repaired"


@pytest.mark.parametrize(
    ("steps", "action", "state"),
    [
        ([], "dispatch", "detected"),
        ([], "close", "detected"),
        (["acknowledge"], "acknowledge", "acknowledged"),
        (["acknowledge", "dispatch"], "acknowledge", "dispatched"),
        (["acknowledge", "dispatch"], "dispatch", "dispatched"),
        (["acknowledge", "close"], "acknowledge", "closed"),
        (["acknowledge", "close"], "dispatch", "closed"),
        (["acknowledge", "close"], "close", "closed"),
    ],
)
def test_an_illegal_transition_is_refused_by_name_and_changes_nothing(
    store: IncidentStore, steps: list[str], action: str, state: str
) -> None:
    incident = _burst(store)
    for step in steps:
        outcome = Outcome.false_alarm() if step == "close" else None
        store.act(incident, step, by="ann", via="cli", outcome=outcome)
    before = store.get(incident)
    outcome = Outcome.false_alarm() if action == "close" else None
    with pytest.raises(IncidentStateError) as refused:
        store.act(incident, action, by="bob", via="cli", outcome=outcome)
    error = refused.value
    assert (error.incident, error.state, error.action) == (incident, state, action)
    assert f"incident {incident} is {state}" in str(error)
    assert all(s in str(error) for s in error.allowed)
    assert store.get(incident) == before


def test_bad_requests_are_refused_by_name(store: IncidentStore) -> None:
    incident = _burst(store)
    with pytest.raises(UnknownIncidentError, match=r"no incident 4242 in the incident store"):
        store.acknowledge(4242, "ann", "cli")
    with pytest.raises(InputError, match="operator's name is required"):
        store.acknowledge(incident, "  ", "cli")
    with pytest.raises(InputError, match="needs an outcome"):
        store.act(incident, "close", by="ann", via="cli")
    with pytest.raises(InputError, match="only when closing"):
        store.act(incident, "acknowledge", by="ann", via="cli", outcome=Outcome.false_alarm())
    with pytest.raises(InputError, match="a note is required"):
        store.act(incident, "note", by="ann", via="cli")
    with pytest.raises(InputError, match="unknown action 'shelve'"):
        store.act(incident, "shelve", by="ann", via="cli")
    with pytest.raises(InputError, match="longer than"):
        store.acknowledge(incident, "x" * 201, "cli")
    with pytest.raises(InputError, match="finite point"):
        Outcome.found(float("nan"), 1.0)
    assert len(store.get(incident)["history"]) == 2


def test_listing_puts_open_incidents_first_newest_first(store: IncidentStore) -> None:
    ids = [_burst(store, 100.0 * k, at=1e9 + k) for k in range(1, 6)]
    for incident in ids[1:3]:  # the second and third are closed
        store.acknowledge(incident, "ann", "cli")
        store.close_incident(incident, "ann", "cli", Outcome.false_alarm())
    listed = [r["id"] for r in store.incidents()]
    assert listed == [ids[4], ids[3], ids[0], ids[2], ids[1]]
    assert [r["id"] for r in store.incidents(open_only=True)] == [ids[4], ids[3], ids[0]]
    assert [r["id"] for r in store.incidents(limit=2)] == [ids[4], ids[3]]
    assert store.version() == max(h["id"] for i in ids for h in store.get(i)["history"])


def test_the_open_count_is_the_open_listings_length_through_the_life_cycle(
    store: IncidentStore,
) -> None:
    def counted() -> tuple[int, int]:
        return store.open_count(), len(store.incidents(open_only=True))

    assert counted() == (0, 0)
    ids = [_burst(store, 100.0 * k, at=1e9 + k) for k in range(1, 6)]
    (fault,) = store.take([meter_fault("N8", "silent", True, 1e9, 10.0)])
    assert counted() == (6, 6)
    store.acknowledge(ids[0], "ann", "cli")
    store.dispatch(ids[0], "ann", "cli")
    store.acknowledge(ids[1], "ann", "cli")
    store.shelves.shelve(ids[2], 3600.0, by="ann", via="cli", reason="hydrant flushing")
    store.shelves.shelve(fault, 60.0, by="ann", via="cli", reason="radio link down")
    assert counted() == (6, 6)  # acknowledged, dispatched and shelved incidents are open
    store.close_incident(ids[1], "bob", "cli", Outcome.found(412.5, -33.0))
    store.acknowledge(ids[2], "bob", "cli")  # a shelved incident, closed
    store.close_incident(ids[2], "bob", "cli", Outcome.false_alarm())
    assert counted() == (4, 4)
    store.clock.now += 120.0  # type: ignore[attr-defined]  # the fault's shelving ran out
    assert store.shelves.expire() == 1
    store.acknowledge(fault, "bob", "cli")
    store.close_incident(fault, "bob", "cli", Outcome.false_alarm())
    assert counted() == (3, 3)
    assert {r["id"] for r in store.incidents(open_only=True)} == {ids[0], ids[3], ids[4]}


def test_a_meter_fault_is_one_incident_while_open(store: IncidentStore) -> None:
    (incident,) = store.take([meter_fault("N8", "silent", True, 1e9, 10.0)])
    assert store.take([meter_fault("N8", "silent", True, 1e9 + 1, 11.0)]) == [0]
    assert store.take([meter_fault("N8", "silent", False, 1e9 + 2, 30.0)]) == [incident]
    assert store.take([meter_fault("N8", "silent", True, 1e9 + 3, 50.0)]) == [incident]
    other = store.take([meter_fault("N3", "implausible", True, 1e9 + 4, 55.0)])[0]
    doc = store.get(incident)
    assert doc["kind"] == "meter" and doc["meter"] == "N8" and doc["active"] is True
    assert [h["action"] for h in doc["history"]] == ["detected", "cleared", "recurred"]
    assert "silent" in doc["summary"] and other != incident
    store.acknowledge(incident, "ann", "cli")
    store.close_incident(incident, "ann", "cli", Outcome.false_alarm(), note="radio link fixed")
    (again,) = store.take([meter_fault("N8", "silent", True, 1e9 + 9, 90.0)])
    assert again not in (0, incident)  # the old one is closed: a new fault, a new incident


def test_racing_operators_acknowledge_once(target: str) -> None:
    stores = [IncidentStore.open(target) for _ in range(2)]  # two processes' worth of engines
    incident = _burst(stores[0])
    results: list[str] = []
    lock = threading.Lock()

    def ack(k: int) -> None:
        try:
            stores[k % 2].acknowledge(incident, f"op{k}", "cli")
            outcome = "ok"
        except IncidentStateError:
            outcome = "refused"
        with lock:
            results.append(outcome)

    threads = [threading.Thread(target=ack, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    try:
        assert sorted(results) == ["ok"] + ["refused"] * 7
        acks = [h for h in stores[1].get(incident)["history"] if h["action"] == "acknowledged"]
        assert len(acks) == 1
    finally:
        for s in stores:
            s.close()


def test_a_bad_address_is_refused_by_name(tmp_path: Any) -> None:
    with pytest.raises(IncidentStoreError, match="postgresql:// URL"):
        IncidentStore.open("mysql://localhost/x")
    with pytest.raises(IncidentStoreError, match="no directory"):
        IncidentStore.open(str(tmp_path / "missing" / "incidents.sqlite"))
    with pytest.raises(IncidentStoreError, match="cannot open the incident store"):
        IncidentStore.open("postgresql://nobody@127.0.0.1:1/none")
