"""The meters whose alarms made each incident, as rows the database counts.

Revision ID: 0005
Revises: 0004
"""

from __future__ import annotations

import json

import sqlalchemy as sa
from alembic import op

from burstloc.incidents.outcomes import alarmed_meters

revision = "0005"
down_revision = "0004"
branch_labels = None
depends_on = None


def upgrade() -> None:
    """Create ``incident_meters`` (an index on ``meter``); fill it from the ``alarmed`` meters
    of the incidents already stored (a list that is not one: none)."""
    table = op.create_table(
        "incident_meters",
        sa.Column("incident_id", sa.Integer, sa.ForeignKey("incidents.id"), primary_key=True),
        sa.Column("meter", sa.Text, primary_key=True),
    )
    # (meter, incident_id): the count scans it alone, never the table
    op.create_index("ix_incident_meters_meter", "incident_meters", ["meter", "incident_id"])
    incidents = sa.table("incidents", sa.column("id", sa.Integer), sa.column("alarmed", sa.Text))
    connection = op.get_bind()
    stored = sa.select(incidents.c.id, incidents.c.alarmed).where(incidents.c.alarmed.is_not(None))
    rows: list[dict[str, object]] = []
    for incident, text in connection.execute(stored).all():
        try:
            alarmed = json.loads(text)
        except ValueError:
            continue
        if isinstance(alarmed, list):
            meters = alarmed_meters(str(m) for m in alarmed)
            rows.extend({"incident_id": incident, "meter": m} for m in meters)
    if rows:
        op.bulk_insert(table, rows)


def downgrade() -> None:
    """Drop it."""
    op.drop_index("ix_incident_meters_meter", "incident_meters")
    op.drop_table("incident_meters")
