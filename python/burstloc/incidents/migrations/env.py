"""Alembic's environment for the incident store: run the migrations on the connection
:func:`burstloc.incidents.migrate.upgrade` hands over (in its transaction)."""

from __future__ import annotations

from alembic import context

connection = context.config.attributes["connection"]
# (the caller holds the lock: burstloc.incidents.migrate.upgrade)
context.configure(connection=connection, target_metadata=None, render_as_batch=True)
context.run_migrations()
