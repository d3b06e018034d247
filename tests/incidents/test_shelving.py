"""Shelving (burstloc.incidents.shelving, .shelves) on SQLite and on a real PostgreSQL server:
a shelved incident is recorded with who, when, until when and why, is not escalated, comes back
by itself when its time is up (on the store's clock, moved by the test) and is escalated again
only the full escalation time after its return; refusals name the problem; a shelved meter's
new faults arrive shelved, without a webhook alert. Escalations are promoted by calling the
outbox directly, on the alerts' clock the test moves: no sender thread, no waiting."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from revisions import migrate
from sqlalchemy import select

from burstloc.exceptions import InputError
from burstloc.incidents import IncidentStateError, IncidentStore, Outcome, UnknownIncidentError
from burstloc.incidents.alerts import WebhookSettings
from burstloc.incidents.alerts.outbox import Outbox
from burstloc.incidents.intake import from_record, meter_fault
from burstloc.incidents.schema import alerts as a
from burstloc.incidents.shelving import (
    MOST_SHELVED,
    action_label,
    check_shelving,
    parse_duration,
)

URL = "http://receiver.invalid/hook"
START = 1_800_000_000.0
RECORD = {
    "type": "decision", "burst": True, "time": 75.0,
    "pipes": [{"pipe": "9", "score": 0.0}], "region": {"length_m": 80.0},
}  # fmt: skip


class Clock:
    """A clock the test sets (the store's wall clock, or the alerts' clock)."""

    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def wall() -> Clock:
    return Clock(START)


@pytest.fixture
def store(target: str, wall: Clock) -> Iterator[IncidentStore]:
    opened = IncidentStore.open(target, clock=wall)
    yield opened
    opened.close()


def _burst(store: IncidentStore, first_alarm: float) -> int:
    item = from_record({**RECORD, "first_alarm": first_alarm}, START)
    assert item is not None
    (incident,) = store.take([item])
    return incident


def _escalations(store: IncidentStore, incident: int) -> list[tuple[str, float]]:
    query = select(a.c.status, a.c.due_at).where(
        a.c.incident_id == incident, a.c.event == "escalated"
    )
    with store.read() as connection:
        return [(r.status, r.due_at) for r in connection.execute(query)]


def _alerts(store: IncidentStore, incident: int) -> list[str]:
    query = select(a.c.event).where(a.c.incident_id == incident).order_by(a.c.id)
    with store.read() as connection:
        return [r.event for r in connection.execute(query)]


def _outbox(store: IncidentStore, alerts: Clock, tmp_path: Path) -> Outbox:
    settings = WebhookSettings((URL,), dead_letter=tmp_path / "dead.jsonl", escalate_after=900.0)
    outbox = Outbox(store, settings, clock=alerts)
    outbox.attach()
    return outbox


# ---------------------------------------------------------------------- pure
@pytest.mark.parametrize(
    ("text", "seconds"),
    [("30m", 1800.0), ("2h", 7200.0), ("1h30m", 5400.0), ("90 s", 90.0), ("24h", MOST_SHELVED),
     ("45min", 2700.0), ("1d", 86_400.0)],
)  # fmt: skip
def test_durations_are_read_with_their_units(text: str, seconds: float) -> None:
    assert parse_duration(text) == seconds


@pytest.mark.parametrize(
    ("text", "said"),
    [("", "a number with a unit"), ("30", "a number with a unit"),
     ("2 weeks", "a number with a unit"), ("-5m", "a number with a unit"),
     ("0m", "more than 0 and at most 24 h"), ("24h1s", "more than 0 and at most 24 h"),
     ("2d", "more than 0 and at most 24 h")],
)  # fmt: skip
def test_a_bad_duration_is_refused_by_name(text: str, said: str) -> None:
    with pytest.raises(InputError, match=said) as caught:
        parse_duration(text)
    assert repr(text) in str(caught.value)


def test_a_shelving_needs_a_reason_and_a_bounded_time() -> None:
    assert check_shelving(60.0, "  pump swap  ") == "pump swap"
    for reason in (None, "", "   "):
        with pytest.raises(InputError, match="shelving needs a reason"):
            check_shelving(60.0, reason)
    for seconds in (0.0, -1.0, MOST_SHELVED + 1, float("nan"), float("inf")):
        with pytest.raises(InputError, match="at most 24 h"):
            check_shelving(seconds, "why")
    assert action_label("unshelved", "expiry") == "unshelved (expired)"
    assert action_label("unshelved", "cli") == "unshelved"


# ---------------------------------------------------------------------- the store
def test_a_shelving_is_recorded_listed_and_expires_by_itself(
    store: IncidentStore, wall: Clock
) -> None:
    n = _burst(store, 62.4)
    other = _burst(store, 900.0)
    doc = store.shelves.shelve(n, 1800.0, by="ann", via="cli", reason="  flushing hydrant  ")
    assert (doc["shelved_until"], doc["shelved_by"], doc["shelved_reason"]) == (
        START + 1800.0, "ann", "flushing hydrant",
    )  # fmt: skip
    assert doc["state"] == "detected"  # shelving is apart from the life cycle
    last = doc["history"][-1]
    assert (last["action"], last["by"], last["via"], last["at"], last["note"]) == (
        "shelved", "ann", "cli", START, "flushing hydrant",
    )  # fmt: skip
    assert last["detail"] == {"until": START + 1800.0, "seconds": 1800.0}
    listed = {r["id"]: r["shelved_until"] for r in store.incidents()}
    assert listed == {n: START + 1800.0, other: None}

    wall.now = START + 1799.0
    version = store.version()
    assert store.get(n)["shelved_until"] == START + 1800.0  # not yet
    wall.now = START + 1800.0
    assert store.version() > version  # the return is a change the page sees
    doc = store.get(n)
    assert doc["shelved_until"] is None and doc["shelved_by"] is None
    back = doc["history"][-1]
    assert (back["action"], back["by"], back["via"], back["at"], back["note"]) == (
        "unshelved", "burstloc", "expiry", START + 1800.0, "expired",
    )  # fmt: skip
    assert action_label(back["action"], back["via"]) == "unshelved (expired)"
    assert store.shelves.expire() == 0  # once
    assert [h["action"] for h in store.get(n)["history"]] == ["detected", "shelved", "unshelved"]


def test_an_operator_unshelves_early_and_actions_go_on_while_shelved(
    store: IncidentStore, wall: Clock
) -> None:
    n = _burst(store, 62.4)
    store.shelves.shelve(n, 3600.0, by="ann", via="cli", reason="crew on site")
    wall.now += 60.0
    assert store.acknowledge(n, "bob", "cli")["shelved_until"] == START + 3600.0
    wall.now += 60.0
    doc = store.shelves.unshelve(n, by="bob", via="page 10.0.0.7", note="done early")
    assert doc["shelved_until"] is None and doc["state"] == "acknowledged"
    last = doc["history"][-1]
    assert (last["action"], last["by"], last["via"], last["note"]) == (
        "unshelved", "bob", "page 10.0.0.7", "done early",
    )  # fmt: skip
    wall.now = START + 7200.0  # its old time passes: nothing more happens
    assert [h["action"] for h in store.get(n)["history"]] == [
        "detected", "shelved", "acknowledged", "unshelved",
    ]  # fmt: skip


def test_closing_ends_a_shelving_and_a_closed_incident_cannot_be_shelved(
    store: IncidentStore,
) -> None:
    n = _burst(store, 62.4)
    store.shelves.shelve(n, 600.0, by="ann", via="cli", reason="checking")
    store.acknowledge(n, "ann", "cli")
    doc = store.close_incident(n, "ann", "cli", Outcome.false_alarm())
    assert doc["state"] == "closed" and doc["shelved_until"] is None
    with pytest.raises(IncidentStateError, match=f"incident {n} is closed: it cannot be shelved"):
        store.shelves.shelve(n, 600.0, by="ann", via="cli", reason="again")
    with pytest.raises(IncidentStateError, match="cannot be unshelved"):
        store.shelves.unshelve(n, by="ann", via="cli")
    assert [h["action"] for h in store.get(n)["history"]][-1] == "closed"


def test_bad_shelving_requests_are_refused_by_name_and_change_nothing(
    store: IncidentStore,
) -> None:
    n = _burst(store, 62.4)
    shelves = store.shelves
    with pytest.raises(InputError, match="shelving needs a reason"):
        shelves.shelve(n, 600.0, by="ann", via="cli", reason=" ")
    with pytest.raises(InputError, match="at most 24 h"):
        shelves.shelve(n, 25 * 3600.0, by="ann", via="cli", reason="long job")
    with pytest.raises(InputError, match="the operator's name is required"):
        shelves.shelve(n, 600.0, by="", via="cli", reason="why")
    with pytest.raises(UnknownIncidentError, match="no incident 999"):
        shelves.shelve(999, 600.0, by="ann", via="cli", reason="why")
    with pytest.raises(IncidentStateError, match=f"incident {n} is detected and not shelved"):
        shelves.unshelve(n, by="ann", via="cli")
    doc = store.get(n)
    assert doc["shelved_until"] is None and [h["action"] for h in doc["history"]] == ["detected"]


# ---------------------------------------------------------------------- escalation
def test_a_shelved_incident_is_not_escalated_and_its_clock_restarts_at_its_return(
    store: IncidentStore, wall: Clock, tmp_path: Path
) -> None:
    alerts = Clock(0.0)
    outbox = _outbox(store, alerts, tmp_path)
    shelved, plain = _burst(store, 62.4), _burst(store, 900.0)
    assert _escalations(store, shelved) == [("waiting", 900.0)]
    alerts.now = 100.0
    store.shelves.shelve(shelved, 1800.0, by="ann", via="cli", reason="known work")
    assert _escalations(store, shelved) == [("held", 900.0)]

    alerts.now = 1000.0  # both were due at 900: only the one not shelved is escalated
    assert outbox.promote(URL, alerts.now) == 1
    assert _escalations(store, plain) == [("pending", 900.0)]
    assert _escalations(store, shelved) == [("held", 900.0)]

    wall.now = START + 1800.0  # its time is up: back, unacknowledged
    alerts.now = 2000.0
    assert outbox.promote(URL, alerts.now) == 0  # back, its escalation 900 s from now
    assert store.get(shelved)["history"][-1]["via"] == "expiry"
    assert _escalations(store, shelved) == [("waiting", 2900.0)]
    assert outbox.promote(URL, 2899.0) == 0
    assert outbox.promote(URL, 2900.0) == 1
    assert _escalations(store, shelved) == [("pending", 2900.0)]


def test_an_incident_acknowledged_while_shelved_is_never_escalated(
    store: IncidentStore, wall: Clock, tmp_path: Path
) -> None:
    alerts = Clock(0.0)
    outbox = _outbox(store, alerts, tmp_path)
    n = _burst(store, 62.4)
    store.shelves.shelve(n, 600.0, by="ann", via="cli", reason="looking")
    store.acknowledge(n, "ann", "cli")
    store.shelves.unshelve(n, by="ann", via="cli")
    assert outbox.promote(URL, 5000.0) == 0
    assert _escalations(store, n) == [("cancelled", 900.0)]


# ---------------------------------------------------------------------- meters
def test_a_shelved_meters_new_faults_arrive_shelved_without_an_alert(
    store: IncidentStore, wall: Clock, tmp_path: Path
) -> None:
    alerts = Clock(0.0)
    outbox = _outbox(store, alerts, tmp_path)
    shelf = store.shelves.shelve_meter(" N3 ", 4 * 3600.0, by="ann", via="cli", reason="recal")
    assert shelf == {"at": START, "by": "ann", "until": START + 4 * 3600.0, "reason": "recal"}
    assert list(store.shelves.meters()) == ["N3"]
    wall.now = START + 60.0
    quiet, loud = store.take(
        [meter_fault("N3", "silent", True, wall.now, 10.0),
         meter_fault("N4", "silent", True, wall.now, 10.0)]
    )  # fmt: skip
    doc = store.get(quiet)
    assert (doc["shelved_until"], doc["shelved_by"], doc["shelved_reason"]) == (
        START + 4 * 3600.0, "ann", "recal",
    )  # fmt: skip
    assert [(h["action"], h["by"], h["via"]) for h in doc["history"]] == [
        ("detected", "monitor", "monitor"), ("shelved", "ann", "meter shelved"),
    ]  # fmt: skip
    assert store.get(loud)["shelved_until"] is None
    assert _alerts(store, quiet) == ["escalated"] and _escalations(store, quiet)[0][0] == "held"
    assert _alerts(store, loud) == ["new", "escalated"]
    assert outbox.promote(URL, 5000.0) == 1  # the loud one's escalation only

    store.shelves.unshelve_meter("N3", by="bob", via="cli")
    assert store.shelves.meters() == {}
    with pytest.raises(InputError, match="meter 'N3' is not shelved"):
        store.shelves.unshelve_meter("N3", by="bob", via="cli")
    (again,) = store.take([meter_fault("N3", "implausible", True, wall.now, 11.0)])
    assert store.get(again)["shelved_until"] is None and _alerts(store, again)[0] == "new"


def test_a_meters_shelving_runs_out_and_bad_requests_are_refused(
    store: IncidentStore, wall: Clock
) -> None:
    store.shelves.shelve_meter("N3", 600.0, by="ann", via="cli", reason="valve work")
    wall.now = START + 600.0
    assert store.shelves.meters() == {}
    (fault,) = store.take([meter_fault("N3", "silent", True, wall.now, 1.0)])
    assert store.get(fault)["shelved_until"] is None
    with pytest.raises(InputError, match="which meter"):
        store.shelves.shelve_meter(" ", 600.0, by="ann", via="cli", reason="x")
    with pytest.raises(InputError, match="shelving needs a reason"):
        store.shelves.shelve_meter("N3", 600.0, by="ann", via="cli", reason="")
    with pytest.raises(InputError, match="at most 24 h"):
        store.shelves.shelve_meter("N3", 0.0, by="ann", via="cli", reason="x")
    assert store.shelves.meters() == {}


def test_a_shelving_survives_reopening_the_store(target: str, wall: Clock) -> Any:
    first = IncidentStore.open(target, clock=wall)
    n = _burst(first, 62.4)
    first.shelves.shelve(n, 600.0, by="ann", via="cli", reason="kept")
    first.close()
    again = IncidentStore.open(target, clock=wall)
    try:
        assert again.get(n)["shelved_until"] == START + 600.0
    finally:
        again.close()


def test_migration_0004_upgrades_a_store_of_0003_and_goes_back(target: str, wall: Clock) -> None:
    from sqlalchemy import inspect, text

    from burstloc.incidents.engine import make_engine, store_url

    engine = make_engine(store_url(target))
    with engine.connect().execution_options(burstloc_write=True) as connection:
        migrate(connection, "0003")  # a store as the burstloc before this one made it
        with connection.begin():
            connection.execute(
                text(
                    "INSERT INTO incidents (key, kind, state, detected_at, updated_at, summary) "
                    "VALUES ('alarm:1', 'burst', 'detected', 1, 1, 's')"
                )
            )
    store = IncidentStore.open(target, clock=wall)  # upgraded to 0004
    try:
        (row,) = store.incidents()
        assert row["shelved_until"] is None
        assert (
            store.shelves.shelve(row["id"], 60.0, by="ann", via="cli", reason="r")["shelved_until"]
            == START + 60.0
        )
    finally:
        store.close()
    with engine.connect().execution_options(burstloc_write=True) as connection:
        migrate(connection, "0003", down=True)
        columns = {c["name"] for c in inspect(connection).get_columns("incidents")}
        assert "shelved_until" not in columns and "alarmed" in columns
        assert "meter_shelves" not in inspect(connection).get_table_names()
    engine.dispose()
