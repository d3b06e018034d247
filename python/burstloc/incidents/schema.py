"""The incident store's tables (SQLAlchemy Core): one row per incident, one per meter whose
alarms made it, one per history entry, one per webhook alert and URL, one per meter's shelving.

The schema is created and changed only by the migrations in ``migrations/versions/``
(:mod:`burstloc.incidents.migrate`); these tables describe the newest revision, for the
queries. Times are seconds since the epoch (UTC, wall clock) as floats; ``reading_time`` is the
feed's own time (the first alarm's reading time, or the meter's newest reading), as is
``onset``.
"""

from __future__ import annotations

from sqlalchemy import (
    Boolean,
    Column,
    Float,
    ForeignKey,
    Index,
    Integer,
    MetaData,
    String,
    Table,
    Text,
)

__all__ = ["alerts", "history", "incident_meters", "incidents", "metadata", "meter_shelves"]

metadata = MetaData()

#: One row per incident: what it is, its state now, its latest answer and its outcome.
incidents = Table(
    "incidents",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    # what identifies the incident across the monitor's records: "alarm:<first alarm>" (the
    # early record and the answer of one alarm) or "meter:<meter>:<fault>"
    Column("key", String(300), nullable=False),
    Column("kind", String(16), nullable=False),  # burst, event, alarm, meter
    Column("state", String(16), nullable=False),
    Column("detected_at", Float, nullable=False),
    Column("updated_at", Float, nullable=False),
    Column("reading_time", Float),
    Column("pipe", String(200)),
    Column("meter", String(200)),
    Column("summary", String(500), nullable=False),
    Column("record", Text),  # the latest record (JSON), for alarms
    Column("active", Boolean),  # a meter fault still present (None for alarms)
    Column("outcome", String(16)),  # found, false-alarm
    Column("found_x", Float),
    Column("found_y", Float),
    Column("closed_at", Float),
    # the meters whose alarms made it (JSON list; alarms only), from its latest record
    Column("alarmed", Text),
    # the feed file of the readings kept around the alarm (an absolute path; alarms only)
    Column("readings", String(1000)),
    Column("onset", Float),  # reading time: the first alarmed meter's change began after it
    # shelved (burstloc.incidents.shelving) until this wall-clock time, by whom, why (else None)
    Column("shelved_until", Float),
    Column("shelved_by", String(200)),
    Column("shelved_reason", Text),
    Index("ix_incidents_key", "key"),
    Index("ix_incidents_state_detected", "state", "detected_at"),
    Index("ix_incidents_shelved", "shelved_until"),
)

#: One row per incident and meter whose alarms made it: the ``alarmed`` column's meters
#: (:func:`~burstloc.incidents.outcomes.alarmed_meters`), replaced with it in the same
#: transaction, so that the database counts each meter's incidents
#: (:mod:`burstloc.incidents.counts`).
incident_meters = Table(
    "incident_meters",
    metadata,
    Column("incident_id", Integer, ForeignKey("incidents.id"), primary_key=True),
    Column("meter", Text, primary_key=True),
    Index("ix_incident_meters_meter", "meter", "incident_id"),  # covers the count's scan
)

#: One row per change: who did what when, and the state after it.
history = Table(
    "history",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("incident_id", Integer, ForeignKey("incidents.id"), nullable=False),
    Column("at", Float, nullable=False),
    Column("by", String(200), nullable=False),
    Column("via", String(100), nullable=False),  # monitor, cli, page <address>
    Column("action", String(16), nullable=False),
    Column("state", String(16), nullable=False),
    Column("note", Text),
    Column("detail", Text),  # JSON: the record (detected, answered), the outcome (closed)
    Index("ix_history_incident", "incident_id", "id"),
)

#: The webhook alerts' outbox (:mod:`burstloc.incidents.alerts`): one row per alert and URL, kept
#: after delivery. ``status``: ``waiting`` (an escalation not yet due), ``pending``,
#: ``delivered``, ``dead`` (given up: in the dead-letter file), ``cancelled`` (an escalation
#: of an incident acknowledged in time) or ``held`` (an escalation of a shelved incident,
#: waiting again from the incident's return). ``due_at`` and ``next_at`` are on the alerts' clock
#: (the monitor's); ``created_at`` and ``delivered_at`` wall-clock times.
alerts = Table(
    "alerts",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("key", String(64), nullable=False, unique=True),  # the Idempotency-Key header
    Column("url", String(2000), nullable=False),
    Column("incident_id", Integer, ForeignKey("incidents.id"), nullable=False),
    Column("event", String(16), nullable=False),  # new, escalated
    Column("status", String(16), nullable=False),
    Column("due_at", Float, nullable=False),  # when it became (becomes) due: its order
    Column("next_at", Float, nullable=False),  # the next attempt
    Column("attempts", Integer, nullable=False),
    Column("created_at", Float, nullable=False),
    Column("delivered_at", Float),
    Column("last_error", Text),
    Column("payload", Text),  # JSON, as sent (an escalation's: made when it is due)
    Index("ix_alerts_queue", "status", "url", "due_at", "id"),
)

#: One row per shelving of a meter (:mod:`burstloc.incidents.shelving`): in force while
#: ``ended_at`` is None and ``until`` (wall clock) is ahead.
meter_shelves = Table(
    "meter_shelves",
    metadata,
    Column("id", Integer, primary_key=True, autoincrement=True),
    Column("meter", String(200), nullable=False),
    Column("at", Float, nullable=False),
    Column("by", String(200), nullable=False),
    Column("via", String(100), nullable=False),
    Column("until", Float, nullable=False),
    Column("reason", Text, nullable=False),
    Column("ended_at", Float),  # unshelved by an operator before its time
    Column("ended_by", String(200)),
    Index("ix_meter_shelves_meter", "meter", "id"),
)
