"""``burstloc monitor --db``: the incidents the monitor reports, kept in a store."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

from burstloc.exceptions import ConfigError

__all__ = ["add_arguments", "start", "stop"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The ``incidents`` option group of ``burstloc monitor``."""
    group = parser.add_argument_group("incidents")
    group.add_argument(
        "--db",
        nargs="?",
        const="",
        metavar="PATH|URL",
        help="keep every located burst, early record, event and meter fault as an incident "
        "with its history: in this SQLite file, in a PostgreSQL database (postgresql://...), "
        "or with --db alone in an SQLite file beside --state's file; the page then lists them "
        "and operators act on them (`burstloc incidents` too); needs burstloc[incidents]",
    )


def start(args: argparse.Namespace, say: Callable[[str], None]) -> Any:
    """The started :class:`~burstloc.incidents.recorder.Recorder` (``None`` without ``--db``);
    the store it writes is its ``store``; ``say`` tells the operator (called from the
    recorder's thread, never before this returns).

    Raises:
        ConfigError: ``--db`` alone without ``--state``; the incidents extra missing.
        IncidentStoreError: the store cannot be opened.
    """
    if args.db is None:
        return None
    from burstloc.incidents.engine import beside_state
    from burstloc.incidents.store import IncidentStore

    if args.db == "" and args.state is None:
        raise ConfigError("--db without a PATH or URL keeps the incidents beside --state: give one")
    try:
        import alembic  # noqa: F401
        import sqlalchemy  # noqa: F401
    except ImportError:
        raise ConfigError(
            "--db needs the incidents extra: pip install 'burstloc[incidents]' (SQLAlchemy, "
            "Alembic, psycopg)"
        ) from None
    from burstloc.incidents.recorder import Recorder

    store = IncidentStore.open(args.db or beside_state(args.state))
    print(f"burstloc monitor: incidents kept in {store.where}", file=sys.stderr, flush=True)
    return Recorder(store, lambda text: say(f"burstloc monitor: {text}"))


def stop(recorder: Any) -> None:
    """Store what the recorder has queued, then close its store (nothing without ``--db``)."""
    if recorder is not None:
        try:
            recorder.close()
        finally:
            recorder.store.close()
