"""``burstloc monitor --db``: the incidents the monitor reports, kept in a store; ``--webhook``:
alerts of them POSTed to receivers (:mod:`burstloc.incidents.alerts`)."""

from __future__ import annotations

import argparse
import math
import os
import socket
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from burstloc.exceptions import ConfigError

__all__ = ["add_arguments", "stamp", "start", "start_alerts", "stop"]


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
    group.add_argument(
        "--webhook",
        action="append",
        type=_url,
        metavar="URL",
        help="POST a JSON alert to this http(s) URL for every new incident (and escalations); "
        "repeatable; needs --db, whose database keeps the alerts until each is delivered, in "
        "order, once (retried with back-off; given up to --webhook-dead-letter after 100 "
        "attempts or 6 h)",
    )
    group.add_argument(
        "--webhook-escalate-minutes",
        type=float,
        metavar="M",
        help="alert again about an incident still unacknowledged M minutes after it was "
        "detected (the monitor's clock: a replayed file's reading time)",
    )
    group.add_argument(
        "--webhook-dead-letter",
        metavar="FILE",
        help="JSON lines of the alerts given up (default: beside the SQLite store, or beside "
        "--state with PostgreSQL)",
    )


def _url(text: str) -> str:
    from burstloc.incidents.alerts.config import check_url

    try:
        return check_url(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _check_webhooks(args: argparse.Namespace) -> None:
    """The webhook options, before anything starts.

    Raises:
        ConfigError: one that needs another, or a bad number (naming the option and its key).
    """
    if not args.webhook:
        for option, value in [
            ("--webhook-escalate-minutes", args.webhook_escalate_minutes),
            ("--webhook-dead-letter", args.webhook_dead_letter),
        ]:
            if value is not None:
                raise ConfigError(f"{option} needs --webhook")
        return
    if args.db is None:
        raise ConfigError(
            "--webhook needs --db: the alerts not yet delivered are kept in the incident "
            "store's database"
        )
    minutes = args.webhook_escalate_minutes
    if minutes is not None and not (math.isfinite(minutes) and minutes > 0):
        raise ConfigError(
            "--webhook-escalate-minutes (settings key webhook-escalate-minutes) must be a "
            f"finite number of minutes > 0, got {minutes}"
        )


def start(args: argparse.Namespace, say: Callable[[str], None], meters: Sequence[str] = ()) -> Any:
    """The started :class:`~burstloc.incidents.recorder.Recorder` (``None`` without ``--db``);
    the store it writes is its ``store``; ``say`` tells the operator (called from the
    recorder's thread, never before this returns). The readings around each alarm of
    ``meters`` (the steps' columns) are kept beside the store
    (:func:`~burstloc.incidents.kept.readings_dir`), or said not to be.

    Raises:
        ConfigError: ``--db`` alone without ``--state``; the incidents extra missing.
        IncidentStoreError: the store cannot be opened.
    """
    _check_webhooks(args)
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
    from burstloc.incidents.kept import readings_dir
    from burstloc.incidents.recorder import Recorder

    store = IncidentStore.open(args.db or beside_state(args.state))
    print(f"burstloc monitor: incidents kept in {store.where}", file=sys.stderr, flush=True)
    readings = readings_dir(store, args.state)
    if readings is None:
        kept = "not kept (a PostgreSQL store: give --state to keep them beside its file)"
    else:
        kept = f"kept in {readings}"
    print(f"burstloc monitor: the readings around each alarm {kept}", file=sys.stderr, flush=True)
    return Recorder(
        store, lambda text: say(f"burstloc monitor: {text}"), meters=meters, readings=readings
    )


def _dead_letter(args: argparse.Namespace, store: Any) -> str:
    """The dead-letter file: ``--webhook-dead-letter``, else beside the SQLite store, else
    beside ``--state``.

    Raises:
        ConfigError: none of them, or a file in a directory that does not exist.
    """
    path = args.webhook_dead_letter
    if path is None:
        if store.engine.dialect.name == "sqlite" and store.engine.url.database:
            path = os.path.splitext(store.engine.url.database)[0] + ".webhook-dead.jsonl"
        elif args.state is not None:
            path = os.path.splitext(args.state)[0] + ".webhook-dead.jsonl"
        else:
            raise ConfigError(
                "--webhook with a PostgreSQL --db needs --webhook-dead-letter FILE (or --state, "
                "to keep it beside the state file)"
            )
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ConfigError(f"--webhook-dead-letter {path!r}: no directory {folder!r}")
    return path


def start_alerts(
    args: argparse.Namespace, recorder: Any, loop: Any, web: Any, say: Callable[[str], None]
) -> Any:
    """The started :class:`~burstloc.incidents.alerts.sender.WebhookSender` of ``--webhook``
    (``None`` without it), its outbox attached to the recorder's store. Its clock is the
    monitor's: the feed's reading time when a file is replayed (``--readings FILE``; the loop
    then waits for the alerts due, :mod:`burstloc.incidents.alerts.pacing`), else the wall
    clock. ``web``: the page's server (the alerts link to it), or ``None``.

    Raises:
        ConfigError: no place for the dead-letter file.
    """
    if not args.webhook or recorder is None:
        return None
    from burstloc import __version__
    from burstloc.incidents.alerts.config import WebhookSettings
    from burstloc.incidents.alerts.outbox import Outbox
    from burstloc.incidents.alerts.sender import WebhookSender

    minutes = args.webhook_escalate_minutes
    settings = WebhookSettings(
        tuple(args.webhook),
        dead_letter=Path(_dead_letter(args, recorder.store)),
        escalate_after=None if minutes is None else 60.0 * minutes,
    )
    replay = args.mqtt is None and args.readings != "-"
    clock = (lambda: loop.health.reference) if replay else time.time
    base = None if web is None else _page(web)
    outbox = Outbox(
        recorder.store,
        settings,
        clock=clock,
        link=lambda incident: None if base is None else f"{base}#incident={incident}",
        source=f"burstloc {__version__}",
    )
    outbox.attach()

    def told(text: str) -> None:
        say(f"burstloc monitor: {text}")

    sender = WebhookSender(outbox, told, paced=replay).start()
    recorder.committed = lambda batch, changed: sender.wake()
    if replay:  # the alerts follow the file's clock, not the machine's speed
        from burstloc.incidents.alerts.pacing import ReplayPacing
        from burstloc.live.observe import fan_out

        loop.observer = fan_out(loop.observer, ReplayPacing(recorder, sender, clock, told))
    print(
        f"burstloc monitor: webhook alerts to {len(settings.urls)} URL(s); given up to "
        f"{settings.dead_letter}",
        file=sys.stderr,
        flush=True,
    )
    return sender


def _page(web: Any) -> str:
    """The page's address without its token; a wildcard host named by this machine's name."""
    host = web.host
    if host in ("0.0.0.0", "::", ""):
        host = socket.getfqdn()
    host = f"[{host}]" if ":" in host else host
    return f"http://{host}:{web.port}/"


def stop(recorder: Any, sender: Any = None) -> None:
    """Store what the recorder has queued, deliver what is due, then close the store (nothing
    without ``--db``)."""
    if recorder is not None:
        try:
            recorder.close()
            if sender is not None:
                sender.close()
        finally:
            recorder.store.close()


def stamp(seconds: float | None) -> str:
    """A wall-clock time as ISO 8601 UTC (``2026-11-28T06:02:00Z``)."""
    from burstloc.incidents.export import iso

    return iso(seconds).replace("+00:00", "Z")
