"""Where the incident store is and how it is connected: an address (a file path, an
``sqlite:///`` or a ``postgresql://`` URL) to a SQLAlchemy URL, and the engine, SQLite set up
for durability (WAL; ``synchronous=FULL`` unless a write asks for less; write transactions
``BEGIN IMMEDIATE``; no checkpoint inside a commit: :mod:`burstloc.incidents.store` says
why)."""

from __future__ import annotations

import os
from typing import Any

from burstloc.incidents.errors import IncidentStoreError

__all__ = ["BUSY_TIMEOUT", "beside_state", "fsync_size", "make_engine", "store_url"]

#: Seconds a writer waits for another's lock (SQLite) or a connection (PostgreSQL).
BUSY_TIMEOUT = 30.0


def store_url(target: str) -> str:
    """The SQLAlchemy URL of ``target``: a file path (SQLite), ``sqlite:///PATH`` or
    ``postgresql://...`` (driven by psycopg 3).

    Raises:
        IncidentStoreError: another kind of URL, or a file in a directory that does not exist.
    """
    if target.startswith(("postgresql://", "postgres://")):
        return "postgresql+psycopg://" + target.split("://", 1)[1]
    if target.startswith(("postgresql+psycopg://", "sqlite://")):
        return target
    if "://" in target:
        raise IncidentStoreError(
            f"--db takes a file path (SQLite) or a postgresql:// URL, got {target!r}"
        )
    path = os.path.abspath(os.path.expanduser(target))
    folder = os.path.dirname(path)
    if not os.path.isdir(folder):
        raise IncidentStoreError(f"the incident store {target!r}: no directory {folder!r}")
    return "sqlite:///" + path


def make_engine(url: str) -> Any:
    """An engine for ``url``, SQLite configured for durability (module docstring)."""
    from sqlalchemy import create_engine, event

    if url.startswith("sqlite"):
        engine = create_engine(
            url, connect_args={"timeout": BUSY_TIMEOUT, "check_same_thread": False}
        )

        @event.listens_for(engine, "connect")
        def _on_connect(dbapi: Any, record: Any) -> None:
            dbapi.isolation_level = None  # transactions are begun below, not by the driver
            for pragma in (
                "journal_mode=WAL",
                "synchronous=FULL",
                "wal_autocheckpoint=0",  # checkpoints by IncidentStore.sync, off the commits
                "foreign_keys=ON",
                f"busy_timeout={int(BUSY_TIMEOUT * 1000)}",
            ):
                dbapi.execute(f"PRAGMA {pragma}")

        @event.listens_for(engine, "begin")
        def _on_begin(connection: Any) -> None:
            options = connection.get_execution_options()
            if options.get("burstloc_write"):
                sync = options.get("burstloc_sync", "FULL")
                if connection.info.get("burstloc_sync") != sync:  # kept per DBAPI connection
                    connection.exec_driver_sql(f"PRAGMA synchronous={sync}")
                    connection.info["burstloc_sync"] = sync
                connection.exec_driver_sql("BEGIN IMMEDIATE")
            else:
                connection.exec_driver_sql("BEGIN")

        return engine
    return create_engine(
        url, pool_pre_ping=True, connect_args={"connect_timeout": int(BUSY_TIMEOUT)}
    )


def fsync_size(path: str) -> int:
    """``path`` on disk (nothing when it does not exist); its size in bytes (SQLite's log, put
    on disk by :meth:`IncidentStore.sync <burstloc.incidents.store.IncidentStore.sync>`)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        return 0
    try:
        os.fsync(fd)
        return os.fstat(fd).st_size
    finally:
        os.close(fd)


def beside_state(state: str) -> str:
    """The SQLite file of the incidents of a monitor whose state file is ``state``: beside it,
    ``monitor.json`` → ``monitor.incidents.sqlite``."""
    return os.path.splitext(state)[0] + ".incidents.sqlite"
