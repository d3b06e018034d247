"""Shelving in the incident store (:mod:`burstloc.incidents.shelving` says what it is): an
incident's shelving and its return, and the meters' shelvings, as SQL on the store's tables.

:class:`Shelves` is the store's :attr:`~burstloc.incidents.store.IncidentStore.shelves`. Each
operator's call is one durable transaction with its history row (who, when, until when, why).
:meth:`Shelves.expire` ends the shelvings that ran out, on the store's clock: the store calls it
before every read and every action, the webhook alerts before they escalate, so that no timer is
needed. Shelving an incident holds its escalations not yet sent (``held`` in the alerts'
outbox): :meth:`burstloc.incidents.alerts.outbox.Outbox.promote` makes them wait again, the full
escalation time, once the incident is back. Imported once a store is opened (SQLAlchemy).
"""

from __future__ import annotations

import json
from contextlib import AbstractContextManager
from typing import Any, Protocol

from sqlalchemy import bindparam, select

from burstloc.exceptions import InputError
from burstloc.incidents.errors import IncidentStateError, UnknownIncidentError
from burstloc.incidents.lifecycle import CLOSED, OPEN_STATES
from burstloc.incidents.schema import alerts as a
from burstloc.incidents.schema import incidents as t
from burstloc.incidents.schema import meter_shelves as m
from burstloc.incidents.shelving import (
    EXPIRY_BY,
    EXPIRY_VIA,
    SHELVED,
    UNSHELVED,
    check_shelving,
)
from burstloc.incidents.writing import NAME_CHARS, NOTE_CHARS, add_history, checked_text


class _Store(Protocol):
    """What shelving needs of :class:`~burstloc.incidents.store.IncidentStore` (which holds
    a :class:`Shelves`: named structurally, so that neither module imports the other)."""

    @property
    def where(self) -> str: ...
    def clock(self) -> float: ...
    def _read(self) -> AbstractContextManager[Any]: ...
    def _write(self, doing: str, sync: str = ...) -> AbstractContextManager[Any]: ...
    def _durable(self, durable: bool) -> None: ...
    def get(self, incident: int) -> dict[str, Any]: ...


__all__ = ["Shelves"]

_RAN_OUT = (
    select(t.c.id, t.c.state, t.c.shelved_until)
    .where(t.c.shelved_until.is_not(None), t.c.shelved_until <= bindparam("now"))
    .order_by(t.c.shelved_until, t.c.id)
)
_ENDED = {"shelved_until": None, "shelved_by": None, "shelved_reason": None}
#: The escalations of an incident not sent yet, held while it is shelved.
_HOLD = (
    a.update()
    .where(a.c.incident_id == bindparam("incident"), a.c.status == "waiting")
    .values(status="held")
)


class Shelves:
    """The shelvings of ``store``'s incidents and meters (module docstring)."""

    def __init__(self, store: _Store) -> None:
        self.store = store

    def expire(self) -> int:
        """End every shelving that ran out by the store's clock (a history row ``unshelved``
        by :data:`~burstloc.incidents.shelving.EXPIRY_BY` through ``expiry``, at the time it
        ran out); how many. Reads only, when none did.

        Raises:
            IncidentStoreError: the database cannot be used.
        """
        store = self.store
        now = store.clock()
        with store._read() as connection:
            if connection.execute(_RAN_OUT, {"now": now}).first() is None:
                return 0
        with store._write("write to") as connection:
            rows = connection.execute(_RAN_OUT.with_for_update(), {"now": now}).all()
            for row in rows:
                connection.execute(
                    t.update().where(t.c.id == row.id).values(updated_at=now, **_ENDED)
                )
                detail = json.dumps({"expired": True, "until": row.shelved_until})
                add_history(
                    connection, row.id, row.shelved_until, EXPIRY_BY, EXPIRY_VIA, UNSHELVED,
                    row.state, "expired", detail,
                )  # fmt: skip
        store._durable(True)
        return len(rows)

    def shelve(
        self, incident: int, seconds: float, *, by: str, via: str, reason: str
    ) -> dict[str, Any]:
        """Shelve open ``incident`` for ``seconds`` (a shelving in force is replaced), by
        ``by`` through ``via`` for ``reason``; the incident as it is now.

        Raises:
            UnknownIncidentError: no such incident.
            IncidentStateError: the incident is closed.
            InputError: no operator name, no reason, a time out of bounds.
            IncidentStoreError: the database cannot be written.
        """
        store = self.store
        name = str(checked_text(by, "the operator's name", NAME_CHARS, True))
        why = check_shelving(seconds, reason)
        self.expire()
        with store._write("write to") as connection:
            row = self._lock(connection, incident)
            if row.state == CLOSED:
                raise IncidentStateError(incident, row.state, "shelve", OPEN_STATES)
            now = store.clock()
            until = now + seconds
            connection.execute(
                t.update()
                .where(t.c.id == incident)
                .values(shelved_until=until, shelved_by=name, shelved_reason=why, updated_at=now)
            )
            connection.execute(_HOLD, {"incident": incident})
            detail = json.dumps({"until": until, "seconds": seconds})
            add_history(connection, incident, now, name, via, SHELVED, row.state, why, detail)
        store._durable(True)
        return store.get(incident)

    def unshelve(
        self, incident: int, *, by: str, via: str, note: str | None = None
    ) -> dict[str, Any]:
        """Bring shelved ``incident`` back before its time, by ``by`` through ``via``.

        Raises:
            UnknownIncidentError: no such incident.
            IncidentStateError: it is not shelved.
            InputError: no operator name.
            IncidentStoreError: the database cannot be written.
        """
        store = self.store
        name = str(checked_text(by, "the operator's name", NAME_CHARS, True))
        text = checked_text(note, "a note", NOTE_CHARS, False)
        self.expire()
        with store._write("write to") as connection:
            row = self._lock(connection, incident)
            if row.shelved_until is None:
                state = row.state if row.state == CLOSED else f"{row.state} and not shelved"
                raise IncidentStateError(incident, state, "unshelve", ("shelved",))
            now = store.clock()
            connection.execute(
                t.update().where(t.c.id == incident).values(updated_at=now, **_ENDED)
            )
            detail = json.dumps({"until": row.shelved_until})
            add_history(connection, incident, now, name, via, UNSHELVED, row.state, text, detail)
        store._durable(True)
        return store.get(incident)

    def _lock(self, connection: Any, incident: int) -> Any:
        query = select(t.c.state, t.c.shelved_until).where(t.c.id == incident).with_for_update()
        row = connection.execute(query).first()
        if row is None:
            raise UnknownIncidentError(incident, self.store.where)
        return row

    # ------------------------------------------------------------------ meters
    def shelve_meter(
        self, meter: str, seconds: float, *, by: str, via: str, reason: str
    ) -> dict[str, Any]:
        """Shelve ``meter`` for ``seconds`` (its shelving in force, if any, is replaced): its
        meter faults opened meanwhile arrive shelved. The shelving (:meth:`meters`' form).

        Raises:
            InputError: no meter, no operator name, no reason, a time out of bounds.
            IncidentStoreError: the database cannot be written.
        """
        store = self.store
        name = str(checked_text(by, "the operator's name", NAME_CHARS, True))
        which = _meter(meter)
        why = check_shelving(seconds, reason)
        with store._write("write to") as connection:
            now = store.clock()
            self._end_meter(connection, which, now, name)
            connection.execute(
                m.insert(),
                {"meter": which, "at": now, "by": name, "via": via, "until": now + seconds,
                 "reason": why},
            )  # fmt: skip
        store._durable(True)
        return self.meters()[which]

    def unshelve_meter(self, meter: str, *, by: str, via: str) -> None:
        """End ``meter``'s shelving before its time (its incidents already shelved stay so
        until their own time or until unshelved).

        Raises:
            InputError: no meter, no operator name, a meter not shelved.
            IncidentStoreError: the database cannot be written.
        """
        store = self.store
        name = str(checked_text(by, "the operator's name", NAME_CHARS, True))
        which = _meter(meter)
        with store._write("write to") as connection:
            if not self._end_meter(connection, which, store.clock(), name):
                raise InputError(f"meter {which!r} is not shelved")
        store._durable(True)

    @staticmethod
    def _end_meter(connection: Any, meter: str, now: float, by: str) -> int:
        ended = connection.execute(
            m.update()
            .where(m.c.meter == meter, m.c.ended_at.is_(None), m.c.until > now)
            .values(ended_at=now, ended_by=by)
        )
        return int(ended.rowcount)

    def meters(self) -> dict[str, dict[str, Any]]:
        """The meters shelved now: ``{meter: {"at", "by", "until", "reason"}}``."""
        with self.store._read() as connection:
            rows = connection.execute(
                select(m.c.meter, m.c.at, m.c.by, m.c.until, m.c.reason)
                .where(m.c.ended_at.is_(None), m.c.until > self.store.clock())
                .order_by(m.c.id)
            ).all()
        return {
            r.meter: {"at": r.at, "by": r.by, "until": r.until, "reason": r.reason} for r in rows
        }


def _meter(meter: str) -> str:
    if not isinstance(meter, str) or not meter.strip():
        raise InputError("which meter? its name is required")
    if len(meter) > 200:
        raise InputError("a meter's name is longer than 200 characters")
    return meter.strip()
