"""The incident store's schema, brought to the newest revision by Alembic's migrations
(``migrations/versions/``), from an empty database or any older revision.

:func:`upgrade` runs when a store is opened, in one transaction (on SQLite a write lock; on
PostgreSQL an advisory lock: two processes opening one new store create it once). A database at
a revision this burstloc does not know (made by a newer one) is refused, not touched.
"""

from __future__ import annotations

from typing import Any

from burstloc.incidents.errors import IncidentStoreError

__all__ = ["HEAD", "SCRIPTS", "current_revision", "upgrade"]

#: Where the migrations are (package-relative, as Alembic takes it).
SCRIPTS = "burstloc.incidents:migrations"
#: The newest revision.
HEAD = "0005"


def _config() -> Any:
    from alembic.config import Config

    config = Config()
    config.set_main_option("script_location", SCRIPTS)
    return config


def current_revision(connection: Any) -> str | None:
    """The schema revision of the database behind ``connection`` (``None``: empty)."""
    from alembic.runtime.migration import MigrationContext

    return MigrationContext.configure(connection).get_current_revision()


def upgrade(engine: Any, where: str) -> tuple[str | None, str]:
    """Bring the schema of ``engine``'s database (named ``where`` in errors) to :data:`HEAD`;
    return the revisions before and after.

    Raises:
        IncidentStoreError: the database is at a revision this burstloc does not know.
    """
    from alembic import command
    from alembic.script import ScriptDirectory

    config = _config()
    scripts = ScriptDirectory.from_config(config)
    known = {s.revision for s in scripts.walk_revisions()}
    with engine.connect().execution_options(burstloc_write=True) as connection:
        with connection.begin():
            if connection.dialect.name == "postgresql":
                connection.exec_driver_sql("SELECT pg_advisory_xact_lock(8127356401)")
            before = current_revision(connection)
            if before == HEAD:
                return before, HEAD
            if before is not None and before not in known:
                raise IncidentStoreError(
                    f"the incident store {where} has schema revision {before!r}, which this "
                    f"burstloc does not know (its newest is {HEAD!r}): it was written by a newer "
                    "burstloc; use that one"
                )
            config.attributes["connection"] = connection
            command.upgrade(config, "head")
        return before, HEAD
