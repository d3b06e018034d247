"""The incident store: incidents and their history in SQLite (the default) or PostgreSQL.

:meth:`IncidentStore.open` takes a file path (SQLite), ``sqlite:///PATH`` or
``postgresql://USER@HOST:PORT/DB`` (psycopg 3), and brings the schema to the newest revision
(:mod:`burstloc.incidents.migrate`). The monitor's news goes in by :meth:`IncidentStore.take`
(:mod:`burstloc.incidents.intake`; normally from :class:`~burstloc.incidents.recorder.Recorder`'s
thread, never the monitor's); the operators' actions by :meth:`IncidentStore.act` (the life
cycle of :mod:`burstloc.incidents.lifecycle`, illegal transitions refused by a typed error).
Every change is one transaction that appends its history rows (who, when, through what, what):
once a call returns, what it wrote is committed.

**Durability.** SQLite runs in WAL mode. An operator's action commits with
``synchronous=FULL``: it is on disk when it returns, and neither a ``kill -9`` of any process
nor a power cut loses it (nor any record committed before it: the log is written in order). The
monitor's records commit with ``synchronous=NORMAL`` (:data:`MONITOR_SYNC`): in the log when
the call returns, so a ``kill -9`` of any process at any moment loses none, and the commit never
waits for the disk. :meth:`IncidentStore.sync` puts them on disk (the log fsync'ed); the recorder
calls it once :data:`SYNC_EVERY` s have passed since the last one with records committed since
(:meth:`IncidentStore.sync_due`, after each batch), after a quiet second and at its stop, so a
power cut may lose the monitor's records of about the last second (until the next sync), never
an operator's action. Every write transaction takes the write
lock at its start (``BEGIN IMMEDIATE``), so the monitor, the page and ``burstloc incidents`` in
another process never trip over each other (they wait, up to
:data:`~burstloc.incidents.engine.BUSY_TIMEOUT` s).
PostgreSQL commits durably by default; an operator's action locks its incident's row. Readers
never wait for writers.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from burstloc.exceptions import InputError
from burstloc.incidents.engine import fsync_size, make_engine, store_url
from burstloc.incidents.errors import IncidentStoreError, UnknownIncidentError
from burstloc.incidents.intake import MONITOR, Kept, Observed
from burstloc.incidents.lifecycle import CLOSED, DONE, Outcome, next_state

if TYPE_CHECKING:
    from burstloc.incidents.outcomes import MeterCounts
    from burstloc.incidents.writing import OnNew

__all__ = ["CHECKPOINT_BYTES", "MONITOR", "MONITOR_SYNC", "SYNC_EVERY", "IncidentStore"]

#: SQLite's ``synchronous`` for the monitor's records: ``NORMAL`` (WAL: durable against a
#: crash of any process; on disk within :data:`SYNC_EVERY` s, module docstring).
MONITOR_SYNC = "NORMAL"
#: Seconds the monitor's records may stay off the disk (SQLite) before :meth:`IncidentStore.sync`.
SYNC_EVERY = 1.0
#: Bytes of SQLite's log past which :meth:`IncidentStore.sync` checkpoints it into the database
#: (no commit checkpoints: a checkpoint, and the log's restart after it, each wait for the disk).
CHECKPOINT_BYTES = 16 << 20
#: The columns a listing shows (the record itself only with one incident).
_LISTED = (
    "id", "kind", "state", "detected_at", "updated_at", "reading_time", "pipe", "meter",
    "summary", "active", "outcome", "found_x", "found_y", "closed_at", "alarmed", "readings",
    "onset", "shelved_until", "shelved_by", "shelved_reason",
)  # fmt: skip


def _listed(mapping: Any) -> dict[str, Any]:
    """A row's listed columns, ``alarmed`` as a list of meters (``None``: not an alarm's)."""
    doc = {c: mapping[c] for c in _LISTED}
    if doc["alarmed"] is not None:
        doc["alarmed"] = json.loads(doc["alarmed"])
    return doc


def _is_open() -> Any:
    """The condition an open incident's row meets (any state but closed)."""
    from burstloc.incidents.schema import incidents as t

    return t.c.state != CLOSED


def _history_row(r: Any) -> dict[str, Any]:
    return {
        "id": r.id, "at": r.at, "by": r.by, "via": r.via, "action": r.action, "state": r.state,
        "note": r.note, "detail": None if r.detail is None else json.loads(r.detail),
    }  # fmt: skip


class IncidentStore:
    """Incidents and their history in one database (module docstring). Thread-safe: each call
    takes a connection of its own from the engine's pool."""

    def __init__(self, url: str, *, clock: Callable[[], float] = time.time) -> None:
        """Use the database at SQLAlchemy ``url`` as it is (:meth:`open` also migrates it)."""
        try:
            import alembic  # noqa: F401  (the migrations)
            from sqlalchemy.engine import make_url

            if url.startswith("postgresql"):
                import psycopg  # noqa: F401
        except ImportError as exc:
            raise IncidentStoreError(
                f"the incident store needs the incidents extra ({exc}): pip install "
                "'burstloc[incidents]' (SQLAlchemy, Alembic, psycopg)"
            ) from None
        self.url = url
        #: The address, as told to a person (no password).
        self.where = make_url(url).render_as_string(hide_password=True)
        self.clock = clock
        #: SQLite's ``synchronous`` for the monitor's records (module docstring); the operators'
        #: actions always commit with ``FULL``.
        self.monitor_sync = MONITOR_SYNC
        #: Whether records were committed since the last durable commit (:meth:`sync`).
        self.unsynced = False
        self._synced = time.monotonic()
        #: Told of each incident :meth:`take` opens, in its transaction (the alerts' outbox).
        self.on_new: OnNew | None = None
        self.engine = make_engine(url)
        from burstloc.incidents.shelves import Shelves

        #: Shelving incidents and meters (:mod:`burstloc.incidents.shelving`).
        self.shelves = Shelves(self)

    @classmethod
    def open(cls, target: str, *, clock: Callable[[], float] = time.time) -> IncidentStore:
        """The store at ``target`` (:func:`store_url`), its schema brought to the newest
        revision (created in an empty database).

        Raises:
            IncidentStoreError: a bad ``target``, the extra missing, a database that cannot be
                reached or opened, or one made by a newer burstloc.
        """
        from burstloc.incidents.migrate import upgrade

        store = cls(store_url(target), clock=clock)
        try:
            with store._errors("open"):
                upgrade(store.engine, store.where)
        except BaseException:
            store.close()
            raise
        return store

    def close(self) -> None:
        """Close the store's connections."""
        self.engine.dispose()

    # ------------------------------------------------------------------ transactions
    @contextmanager
    def _errors(self, doing: str) -> Iterator[None]:
        from sqlalchemy.exc import SQLAlchemyError

        try:
            yield
        except SQLAlchemyError as exc:
            reason = str(getattr(exc, "orig", None) or exc).strip().splitlines()[0]
            raise IncidentStoreError(
                f"cannot {doing} the incident store {self.where}: {reason}"
            ) from exc

    @contextmanager
    def _write(self, doing: str, sync: str = "FULL") -> Iterator[Any]:
        """A connection in a write transaction, committed at the end (rolled back on error);
        on SQLite with ``synchronous=sync``."""
        with self._errors(doing), self.engine.connect() as connection:
            connection.execution_options(burstloc_write=True, burstloc_sync=sync)
            with connection.begin():
                yield connection

    @contextmanager
    def _read(self) -> Iterator[Any]:
        with self._errors("read"), self.engine.connect() as connection:
            yield connection

    @contextmanager
    def write(self, doing: str) -> Iterator[Any]:
        """A write transaction for a layer beside the store (the alerts' outbox), committed as
        the monitor's records are (:attr:`monitor_sync`: on disk by the next :meth:`sync`);
        ``doing`` names it in an error (``"write to"``).

        Raises:
            IncidentStoreError: the database cannot be written.
        """
        with self._write(doing, self.monitor_sync) as connection:
            yield connection
        self._durable(self.monitor_sync == "FULL")

    def read(self) -> Any:
        """A connection for reading (a context manager; errors as :class:`IncidentStoreError`)."""
        return self._read()

    # ------------------------------------------------------------------ the monitor's news
    def take(self, news: Sequence[Observed | Kept]) -> list[int]:
        """Record the monitor's ``news`` in one transaction; return the incidents each item
        changed (``0`` where it changed nothing: a record already stored, a fault already
        open). Idempotent: taking the same news again adds nothing. An incident it opens is
        told to :attr:`on_new` in the same transaction.

        On SQLite the commit is ``synchronous=NORMAL`` (:attr:`monitor_sync`): it never waits
        for the disk; :meth:`sync` puts it there (module docstring).

        Raises:
            IncidentStoreError: the database cannot be written.
        """
        from burstloc.incidents.writing import take_one

        sync = self.monitor_sync
        with self._write("write to", sync) as connection:
            changed = [take_one(connection, item, self.on_new) for item in news]
        self._durable(sync == "FULL")
        return changed

    def _durable(self, durable: bool) -> None:
        self.unsynced = not durable

    def sync_due(self) -> bool:
        """Whether :data:`SYNC_EVERY` s have passed since the last :meth:`sync` with records
        committed since (or, on SQLite, a log that may want its checkpoint)."""
        if time.monotonic() - self._synced < SYNC_EVERY:
            return False
        return self.unsynced or self.engine.dialect.name == "sqlite"

    def sync(self) -> None:
        """Put every committed record on disk (SQLite: the log fsync'ed, and checkpointed
        into the database once longer than :data:`CHECKPOINT_BYTES`; PostgreSQL's commits are
        on disk already).

        Raises:
            IncidentStoreError: the database cannot be written.
        """
        if self.engine.dialect.name == "sqlite":
            with self._errors("sync"), self.engine.connect() as connection:
                database = connection.exec_driver_sql("PRAGMA database_list").first()[2]
                if fsync_size(database + "-wal") >= CHECKPOINT_BYTES:
                    connection.exec_driver_sql("PRAGMA wal_checkpoint(PASSIVE)")
        self._synced = time.monotonic()
        self._durable(True)

    # ------------------------------------------------------------------ the operators
    def act(
        self,
        incident: int,
        action: str,
        *,
        by: str,
        via: str,
        note: str | None = None,
        outcome: Outcome | None = None,
    ) -> dict[str, Any]:
        """``action`` (acknowledge, dispatch, close, note) on ``incident`` by the operator
        ``by`` through ``via`` (``cli``, ``page 10.0.0.7``), with an optional ``note``; closing
        needs an ``outcome``. Committed when it returns; returns the incident as it is now.

        Raises:
            UnknownIncidentError: no such incident.
            IncidentStateError: the incident's state does not allow ``action``.
            InputError: no operator name, an overlong name or note, a close without outcome
                (or an outcome with another action), a note action without a note.
            IncidentStoreError: the database cannot be written.
        """
        from sqlalchemy import select

        from burstloc.incidents.schema import incidents as t
        from burstloc.incidents.writing import NAME_CHARS, NOTE_CHARS, add_history, checked_text

        name = checked_text(by, "the operator's name", NAME_CHARS, True)
        text = checked_text(note, "a note", NOTE_CHARS, action == "note")
        if (action == "close") != (outcome is not None):
            raise InputError(
                "closing an incident needs an outcome (found at a point, or a false alarm)"
                if action == "close"
                else f"an outcome is given only when closing, not to {action}"
            )
        self.shelves.expire()
        with self._write("write to") as connection:
            query = select(t.c.state).where(t.c.id == incident).with_for_update()
            row = connection.execute(query).first()
            if row is None:
                raise UnknownIncidentError(incident, self.where)
            state = next_state(incident, row.state, action)
            now = self.clock()
            values: dict[str, Any] = {"state": state, "updated_at": now}
            detail = None
            if outcome is not None:
                values.update(  # closing ends a shelving
                    outcome=outcome.kind, found_x=outcome.x, found_y=outcome.y, closed_at=now,
                    shelved_until=None, shelved_by=None, shelved_reason=None,
                )  # fmt: skip
                detail = json.dumps(outcome.to_json())
            connection.execute(t.update().where(t.c.id == incident).values(**values))
            add_history(
                connection, incident, now, str(name), via, DONE[action], state, text, detail
            )
        self._durable(True)
        return self.get(incident)

    def acknowledge(self, incident: int, by: str, via: str, note: str | None = None) -> Any:
        """:meth:`act` ``acknowledge``."""
        return self.act(incident, "acknowledge", by=by, via=via, note=note)

    def dispatch(self, incident: int, by: str, via: str, note: str | None = None) -> Any:
        """:meth:`act` ``dispatch``."""
        return self.act(incident, "dispatch", by=by, via=via, note=note)

    def close_incident(
        self, incident: int, by: str, via: str, outcome: Outcome, note: str | None = None
    ) -> Any:
        """:meth:`act` ``close`` with ``outcome``."""
        return self.act(incident, "close", by=by, via=via, note=note, outcome=outcome)

    # ------------------------------------------------------------------ reading
    def incidents(self, *, open_only: bool = False, limit: int | None = None) -> list[dict]:
        """The incidents, open ones first, newest first within each (without their records);
        the shelvings that ran out ended first (as by every read)."""
        from sqlalchemy import case, select

        from burstloc.incidents.schema import incidents as t

        self.shelves.expire()
        closed = case((t.c.state == CLOSED, 1), else_=0)
        query = select(*(t.c[c] for c in _LISTED)).order_by(
            closed, t.c.detected_at.desc(), t.c.id.desc()
        )
        if open_only:
            query = query.where(_is_open())
        if limit is not None:
            query = query.limit(limit)
        with self._read() as connection:
            return [_listed(row._mapping) for row in connection.execute(query)]

    def open_count(self) -> int:
        """How many incidents are open (those :meth:`incidents` lists with ``open_only``,
        shelved ones included: a shelving never changes whether an incident is open), counted
        by the database (``/metrics`` asks at every scrape)."""
        from sqlalchemy import func, select

        query = select(func.count()).where(_is_open())
        with self._read() as connection:
            return int(connection.execute(query).scalar_one())

    def meter_counts(self) -> list[MeterCounts]:
        """Per meter that alarmed, how many incidents its alarms made and how many of them were
        closed as false alarms and found, counted by the database (``/metrics`` asks at every
        scrape; :mod:`burstloc.incidents.counts`)."""
        from burstloc.incidents.counts import meter_counts

        with self._read() as connection:
            return meter_counts(connection)

    def get(self, incident: int) -> dict[str, Any]:
        """One incident with its latest record (parsed) and its history, oldest first.

        Raises:
            UnknownIncidentError: no such incident.
        """
        from sqlalchemy import select

        from burstloc.incidents.schema import history as h
        from burstloc.incidents.schema import incidents as t

        self.shelves.expire()
        with self._read() as connection:
            row = connection.execute(select(t).where(t.c.id == incident)).first()
            if row is None:
                raise UnknownIncidentError(incident, self.where)
            rows = connection.execute(
                select(h).where(h.c.incident_id == incident).order_by(h.c.id)
            ).all()
        doc = _listed(row._mapping)
        doc["record"] = None if row.record is None else json.loads(row.record)
        doc["history"] = [_history_row(r) for r in rows]
        return doc

    def histories(self) -> dict[int, list[dict[str, Any]]]:
        """Every incident's history rows, oldest first (one query: for exports)."""
        from sqlalchemy import select

        from burstloc.incidents.schema import history as h

        out: dict[int, list[dict[str, Any]]] = {}
        with self._read() as connection:
            for r in connection.execute(select(h).order_by(h.c.id)):
                out.setdefault(int(r.incident_id), []).append(_history_row(r))
        return out

    def records(self) -> dict[int, Any]:
        """Every incident's latest record, parsed (incidents without one left out)."""
        from sqlalchemy import select

        from burstloc.incidents.schema import incidents as t

        query = select(t.c.id, t.c.record).where(t.c.record.is_not(None))
        with self._read() as connection:
            return {int(r.id): json.loads(r.record) for r in connection.execute(query)}

    def version(self) -> int:
        """A number that grows with every change (the newest history row's id; 0 when empty):
        a reader that saw this number has seen everything up to it."""
        from sqlalchemy import func, select

        from burstloc.incidents.schema import history as h

        self.shelves.expire()  # a shelving that ran out is a change
        with self._read() as connection:
            return int(connection.execute(select(func.max(h.c.id))).scalar() or 0)
