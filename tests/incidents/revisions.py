"""Moving a test's incident database to a schema revision, as the stores of earlier burstloc
versions left it (the migrations' upgrade and downgrade tests)."""

from __future__ import annotations

from typing import Any


def migrate(connection: Any, revision: str, *, down: bool = False) -> None:
    """Upgrade (``down``: downgrade) the database behind ``connection`` to ``revision``, in a
    transaction of its own."""
    from alembic import command

    from burstloc.incidents.migrate import _config

    config = _config()
    with connection.begin():
        config.attributes["connection"] = connection
        (command.downgrade if down else command.upgrade)(config, revision)
