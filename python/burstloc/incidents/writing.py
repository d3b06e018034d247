"""The monitor's news as SQL: one :class:`~burstloc.incidents.intake.Observed` taken in an open
write transaction (:func:`take_one`), with statements built once.

Every statement here is a module constant executed with a dictionary of parameters, so
SQLAlchemy compiles each once and finds it in its cache by a key computed once per statement
object; a statement rebuilt per call (``insert().values(...)``) costs its coercion and cache key
on every write, most of the time of a write on SQLite (``benches/bench_incidents.py``). Imported
only once a store is opened (it imports SQLAlchemy).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

from sqlalchemy import bindparam, select

from burstloc.exceptions import InputError
from burstloc.incidents.counts import keep_alarmed
from burstloc.incidents.intake import MONITOR, Kept, Observed
from burstloc.incidents.lifecycle import CLOSED, DETECTED
from burstloc.incidents.schema import history as h
from burstloc.incidents.schema import incidents as t
from burstloc.incidents.schema import meter_shelves as m
from burstloc.incidents.shelving import SHELVED

__all__ = ["NAME_CHARS", "NOTE_CHARS", "OnNew", "add_history", "checked_text", "take_one"]

#: The longest operator name and note kept (characters).
NAME_CHARS, NOTE_CHARS = 200, 10_000

#: Called in the transaction that opened an incident: ``(connection, incident, item, shelved)``
#: (``shelved``: it arrived shelved, its meter being shelved).
OnNew = Callable[[Any, int, Observed, bool], None]

_COLUMNS = (t.c.id, t.c.state, t.c.record, t.c.active)
#: The newest incident of an alarm's key.
_LATEST = select(*_COLUMNS).where(t.c.key == bindparam("k")).order_by(t.c.id.desc()).limit(1)
#: The open incident of a meter fault's key.
_OPEN = (
    select(*_COLUMNS)
    .where(t.c.key == bindparam("k"), t.c.state != CLOSED)
    .order_by(t.c.id.desc())
    .limit(1)
)
#: A meter's shelving in force at ``at`` (wall clock), the newest.
_METER_SHELVED = (
    select(m.c.by, m.c.until, m.c.reason)
    .where(m.c.meter == bindparam("m"), m.c.ended_at.is_(None), m.c.until > bindparam("at"))
    .order_by(m.c.id.desc())
    .limit(1)
)
_INSERT = t.insert()
_HISTORY = h.insert()
#: An incident's columns changed by the monitor (the SET clause: the parameters' other keys).
_UPDATE = t.update().where(t.c.id == bindparam("incident"))


def add_history(
    connection: Any,
    incident: int,
    at: float,
    by: str,
    via: str,
    action: str,
    state: str,
    note: str | None,
    detail: str | None,
) -> None:
    """Append one history row to ``incident``."""
    connection.execute(
        _HISTORY,
        {
            "incident_id": incident, "at": at, "by": by, "via": via, "action": action,
            "state": state, "note": note, "detail": detail,
        },
    )  # fmt: skip


def take_one(connection: Any, item: Observed | Kept, on_new: OnNew | None = None) -> int:
    """Record ``item`` (:meth:`IncidentStore.take <burstloc.incidents.store.IncidentStore.take>`);
    the incident it changed, ``0`` when it changed nothing. ``on_new`` is told of an incident
    this opened, in the same transaction. Kept readings go to the newest incident of their key
    (no history row: they change nothing an operator acts on)."""
    if isinstance(item, Kept):
        kept = connection.execute(_LATEST, {"k": item.key}).first()
        if kept is None:
            return 0
        connection.execute(
            _UPDATE, {"incident": kept.id, "readings": item.path, "onset": item.onset}
        )
        return int(kept.id)
    query = _OPEN if item.is_fault else _LATEST
    row = connection.execute(query, {"k": item.key}).first()
    record = item.record_json()
    if item.is_fault:
        if row is None:
            return _insert(connection, item, record, on_new) if item.active else 0
        if bool(row.active) == item.active:
            return 0
        action = "recurred" if item.active else "cleared"
        _update(connection, row.id, row.state, action, item, record, {"active": item.active})
        return int(row.id)
    if row is not None and row.record == record:
        return 0  # already stored (a replay after a restart)
    if row is None or row.state == CLOSED:
        return _insert(connection, item, record, on_new)
    columns = {
        "kind": item.kind, "pipe": item.pipe, "summary": item.summary, "record": record,
        "alarmed": item.alarmed_json(),
    }  # fmt: skip
    _update(connection, row.id, row.state, "answered", item, record, columns)
    keep_alarmed(connection, row.id, item.alarmed)
    return int(row.id)


def _insert(connection: Any, item: Observed, record: str | None, on_new: OnNew | None) -> int:
    """A new incident; a meter fault of a shelved meter arrives shelved."""
    shelf = None
    if item.is_fault:
        shelf = connection.execute(_METER_SHELVED, {"m": item.meter, "at": item.at}).first()
    result = connection.execute(
        _INSERT,
        {
            "key": item.key, "kind": item.kind, "state": DETECTED, "detected_at": item.at,
            "updated_at": item.at, "reading_time": item.reading_time, "pipe": item.pipe,
            "meter": item.meter, "summary": item.summary, "record": record,
            "active": item.active, "alarmed": item.alarmed_json(),
            "shelved_until": None if shelf is None else shelf.until,
            "shelved_by": None if shelf is None else shelf.by,
            "shelved_reason": None if shelf is None else shelf.reason,
        },
    )  # fmt: skip
    incident = int(result.inserted_primary_key[0])
    keep_alarmed(connection, incident, item.alarmed, new=True)
    add_history(
        connection, incident, item.at, MONITOR, MONITOR, "detected", DETECTED, item.summary, record
    )
    if shelf is not None:
        detail = json.dumps({"until": shelf.until, "meter": item.meter})
        add_history(
            connection, incident, item.at, shelf.by, "meter shelved", SHELVED, DETECTED,
            shelf.reason, detail,
        )  # fmt: skip
    if on_new is not None:
        on_new(connection, incident, item, shelf is not None)
    return incident


def _update(
    connection: Any,
    incident: int,
    state: str,
    action: str,
    item: Observed,
    detail: str | None,
    columns: dict[str, Any],
) -> None:
    connection.execute(_UPDATE, {"incident": incident, "updated_at": item.at, **columns})
    add_history(
        connection, incident, item.at, MONITOR, MONITOR, action, state, item.summary, detail
    )


def checked_text(value: str | None, what: str, most: int, required: bool) -> str | None:
    """``value`` stripped, at most ``most`` characters; ``None`` when empty and not
    ``required``.

    Raises:
        InputError: empty and ``required``, or too long (naming ``what``).
    """
    if value is None or not value.strip():
        if required:
            raise InputError(f"{what} is required (who acts on an incident is recorded)")
        return None
    if len(value) > most:
        raise InputError(f"{what} is longer than {most} characters")
    return value.strip()
