"""The webhook alerts' outbox: a table of the incident store's database (``alerts``, made by
the migration ``0002``), on SQLite and PostgreSQL alike.

An incident's alerts are written **in the transaction that opens the incident**
(:meth:`Outbox.on_new`, the store's :attr:`~burstloc.incidents.store.IncidentStore.on_new`
hook): an incident committed always has its alerts, one per URL (``new``, due at once, its
payload made then), and with an escalation time one more per URL (``escalated``, ``waiting``
until due). So a ``kill -9`` at any moment loses no alert of a committed incident, and a
restart finds every undelivered one where it was. Each URL's queue is its ``pending`` rows in
the order they became due (``due_at``, then ``id``); the sender
(:mod:`burstloc.incidents.alerts.sender`) delivers its head, and only then the next.

An escalation becomes ``pending`` when due (:meth:`Outbox.promote`) if its incident is still
``detected`` (its payload made then, with the incident as it is), else ``cancelled``: each fires
at most once. A shelved incident is never escalated (:mod:`burstloc.incidents.shelving`): its
escalations are ``held`` (by the shelving, or here if one falls due meanwhile), and once it is
back (:meth:`Outbox.promote` first ends the shelvings that ran out) wait again the full
escalation time from then, on the alerts' clock; an incident that arrives shelved (a fault of a
shelved meter) gets no ``new`` alert, only its held escalations. Imported once a store is
opened (it imports SQLAlchemy).
"""

from __future__ import annotations

import json
import time
import uuid
from collections.abc import Callable
from typing import Any

from sqlalchemy import bindparam, func, select

from burstloc.incidents.alerts.config import WebhookSettings
from burstloc.incidents.alerts.payload import ESCALATED, NEW, payload
from burstloc.incidents.intake import Observed
from burstloc.incidents.lifecycle import DETECTED
from burstloc.incidents.schema import alerts as a
from burstloc.incidents.schema import incidents as t
from burstloc.incidents.store import IncidentStore

__all__ = ["STATUSES", "Clock", "Outbox"]

#: An alert's statuses (:data:`burstloc.incidents.schema.alerts`).
STATUSES = ("waiting", "pending", "delivered", "dead", "cancelled", "held")

#: The alerts' clock: seconds, or ``None`` while it has no time yet (a replay before its first
#: reading).
Clock = Callable[[], "float | None"]

_INSERT = a.insert()
_SET = a.update().where(a.c.id == bindparam("alert"))
_HEAD = (
    select(a)
    .where(a.c.status == "pending", a.c.url == bindparam("url"))
    .order_by(a.c.due_at, a.c.id)
    .limit(1)
)
_INCIDENT = ("id", "kind", "state", "detected_at", "reading_time", "summary", "pipe", "meter")
_DUE = (
    select(
        a.c.id.label("alert"),
        a.c.key.label("alert_key"),
        a.c.due_at.label("alert_due"),
        t.c.record,
        t.c.shelved_until,
        *(t.c[c] for c in _INCIDENT),
    )
    .join(t, t.c.id == a.c.incident_id)
    .where(a.c.status == "waiting", a.c.url == bindparam("url"), a.c.due_at <= bindparam("now"))
    .order_by(a.c.due_at, a.c.id)
)
#: The earliest time a URL's waiting escalations are due.
_WAITING = select(func.min(a.c.next_at)).where(a.c.url == bindparam("url"), a.c.status == "waiting")
#: The held escalations of incidents no longer shelved.
_BACK = (
    select(a.c.id.label("alert"), t.c.state)
    .join(t, t.c.id == a.c.incident_id)
    .where(a.c.status == "held", a.c.url == bindparam("url"), t.c.shelved_until.is_(None))
    .order_by(a.c.id)
)


class Outbox:
    """The alerts of ``store`` for ``settings``'s URLs (module docstring); ``clock`` is the
    alerts' clock, ``link(incident)`` the incident's address on the page (``None``: no page),
    ``source`` names the sender in the payloads."""

    def __init__(
        self,
        store: IncidentStore,
        settings: WebhookSettings,
        *,
        clock: Clock,
        link: Callable[[int], str | None] = lambda incident: None,
        source: str = "burstloc",
    ) -> None:
        self.store, self.settings, self.clock = store, settings, clock
        self.link, self.source = link, source

    def attach(self) -> None:
        """Write the alerts of every incident the store opens from now on."""
        self.store.on_new = self.on_new

    # ------------------------------------------------------------------ in the recorder's
    def on_new(self, connection: Any, incident: int, item: Observed, shelved: bool) -> None:
        """The alerts of ``incident``, just opened from ``item``, in its transaction (only its
        held escalations when it arrived ``shelved``)."""
        now = self.clock()
        if now is None:  # a replay's clock before its first reading: the record's own time
            now = item.reading_time if item.reading_time is not None else 0.0
        doc = {
            "id": incident, "kind": item.kind, "state": DETECTED, "detected_at": item.at,
            "reading_time": item.reading_time, "summary": item.summary, "pipe": item.pipe,
            "meter": item.meter, "record": item.record,
        }  # fmt: skip
        wall = time.time()
        rows = []
        for url in self.settings.urls:
            key = uuid.uuid4().hex
            if not shelved:
                body = payload(NEW, key, doc, now, link=self.link(incident), source=self.source)
                rows.append(_row(key, url, incident, NEW, "pending", now, wall, body))
            if self.settings.escalate_after is not None:
                due = now + self.settings.escalate_after
                status = "held" if shelved else "waiting"
                rows.append(_row(uuid.uuid4().hex, url, incident, ESCALATED, status, due, wall))
        if rows:
            connection.execute(_INSERT, rows)

    # ------------------------------------------------------------------ in the sender's
    def promote(self, url: str, now: float) -> int:
        """``url``'s escalations due by ``now``: pending (their payload made now) if their
        incident is still unacknowledged, held if it is shelved, else cancelled; how many became
        pending. First the shelvings that ran out are ended, and the held escalations of the
        incidents back wait again (the full escalation time from ``now``) or are cancelled."""
        self.store.shelves.expire()
        with self.store.read() as connection:
            due = connection.execute(_DUE, {"url": url, "now": now}).first()
            if due is None and connection.execute(_BACK, {"url": url}).first() is None:
                return 0  # the common case: no write lock taken
        promoted = 0
        with self.store.write("write to") as connection:
            for row in connection.execute(_BACK, {"url": url}).all():
                if row.state == DETECTED and self.settings.escalate_after is not None:
                    again = now + self.settings.escalate_after
                    values = {"status": "waiting", "due_at": again, "next_at": again}
                else:
                    values = {"status": "cancelled"}
                connection.execute(_SET, {"alert": row.alert, **values})
            for row in connection.execute(_DUE, {"url": url, "now": now}).all():
                if row.state != DETECTED or row.shelved_until is not None:
                    status = "cancelled" if row.state != DETECTED else "held"
                    connection.execute(_SET, {"alert": row.alert, "status": status})
                    continue
                doc = {c: row._mapping[c] for c in _INCIDENT}
                doc["record"] = None if row.record is None else json.loads(row.record)
                body = payload(
                    ESCALATED, row.alert_key, doc, row.alert_due, link=self.link(row.id),
                    source=self.source, unacknowledged=self.settings.escalate_after,
                )  # fmt: skip
                connection.execute(_SET, {"alert": row.alert, "status": "pending", "payload": body})
                promoted += 1
        return promoted

    def head(self, url: str) -> Any:
        """``url``'s first pending alert (a row), ``None`` when none."""
        with self.store.read() as connection:
            return connection.execute(_HEAD, {"url": url}).first()

    def next_due(self, url: str) -> float | None:
        """When ``url``'s next alert is due on the alerts' clock: its queue head's next attempt
        or its first waiting escalation, the earlier (``None``: neither; held ones wait for the
        wall clock)."""
        with self.store.read() as connection:
            head = connection.execute(_HEAD, {"url": url}).first()
            waiting = connection.execute(_WAITING, {"url": url}).scalar()
        due = [float(t) for t in (None if head is None else head.next_at, waiting) if t is not None]
        return min(due) if due else None

    def delivered(self, alert: int, attempts: int) -> None:
        """``alert`` was answered with a 2xx."""
        self._set(alert, status="delivered", attempts=attempts, delivered_at=time.time())

    def failed(self, alert: int, attempts: int, next_at: float, error: str) -> None:
        """``alert``'s attempt failed: tried again at ``next_at`` (the alerts' clock)."""
        self._set(alert, attempts=attempts, next_at=next_at, last_error=error[:2000])

    def dead(self, alert: int, attempts: int, error: str) -> None:
        """``alert`` was given up (it is in the dead-letter file)."""
        self._set(alert, status="dead", attempts=attempts, last_error=error[:2000])

    def _set(self, alert: int, **values: Any) -> None:
        with self.store.write("write to") as connection:
            connection.execute(_SET, {"alert": alert, **values})

    def counts(self) -> dict[str, int]:
        """Alerts per status (every status present, 0 when none)."""
        query = select(a.c.status, func.count()).group_by(a.c.status)
        with self.store.read() as connection:
            got = {str(s): int(n) for s, n in connection.execute(query)}
        return {s: got.get(s, 0) for s in STATUSES}

    def strays(self) -> list[Any]:
        """Undelivered alerts (pending, waiting or held) to URLs no longer configured."""
        query = (
            select(a)
            .where(
                a.c.status.in_(("pending", "waiting", "held")), a.c.url.not_in(self.settings.urls)
            )
            .order_by(a.c.due_at, a.c.id)
        )
        with self.store.read() as connection:
            return list(connection.execute(query).all())


def _row(
    key: str,
    url: str,
    incident: int,
    event: str,
    status: str,
    due: float,
    wall: float,
    body: str | None = None,
) -> dict[str, Any]:
    return {
        "key": key, "url": url, "incident_id": incident, "event": event, "status": status,
        "due_at": due, "next_at": due, "attempts": 0, "created_at": wall, "payload": body,
    }  # fmt: skip
