"""Incidents that last: every located burst, early alarm record, event and meter fault the
monitor reports, with its history (detected, answered, acknowledged, dispatched, closed with an
outcome, operators' notes), kept in SQLite (the default) or PostgreSQL.

* :mod:`~burstloc.incidents.lifecycle`: the states, the operators' actions, the outcomes;
* :mod:`~burstloc.incidents.shelving`, :mod:`~burstloc.incidents.shelves`: shelving an incident
  or a meter's faults for a while, with a reason (what it is; its SQL);
* :mod:`~burstloc.incidents.intake`: the monitor's records as the store takes them;
* :mod:`~burstloc.incidents.schema`, :mod:`~burstloc.incidents.migrate` (and ``migrations/``):
  the tables and their Alembic migrations;
* :mod:`~burstloc.incidents.engine`: the address and the connection (SQLite set up for durability);
* :mod:`~burstloc.incidents.store`: the store (SQLAlchemy Core; durable commits);
* :mod:`~burstloc.incidents.writing`: the monitor's news as SQL, statements built once;
* :mod:`~burstloc.incidents.counts`: each meter's incidents counted by the database (its
  ``incident_meters`` rows, written with the incident);
* :mod:`~burstloc.incidents.recorder`: the monitor's observer, writing on a thread of its own;
* :mod:`~burstloc.incidents.kept`: the readings around each alarm, kept beside the store;
* :mod:`~burstloc.incidents.outcomes`: what closed incidents teach (false alarms per meter,
  bursts found as known events for calibration);
* :mod:`~burstloc.incidents.export`: CSV and JSON;
* :mod:`~burstloc.incidents.errors`: the typed errors;
* :mod:`burstloc.incidents.alerts`: webhook alerts of new and unacknowledged incidents, from a
  durable outbox in the store's database.

This layer imports the base and :mod:`burstloc.live` (the observer protocol) only. SQLAlchemy,
Alembic and psycopg (the ``incidents`` extra) are imported when a store is opened, so this
package imports without them; opening a store without them says how to install them.
"""

from __future__ import annotations

from burstloc.incidents.engine import store_url
from burstloc.incidents.errors import (
    IncidentError,
    IncidentStateError,
    IncidentStoreError,
    UnknownIncidentError,
)
from burstloc.incidents.lifecycle import OPEN_STATES, STATES, Outcome
from burstloc.incidents.store import IncidentStore

__all__ = [
    "OPEN_STATES",
    "STATES",
    "IncidentError",
    "IncidentStateError",
    "IncidentStore",
    "IncidentStoreError",
    "Outcome",
    "UnknownIncidentError",
    "store_url",
]
