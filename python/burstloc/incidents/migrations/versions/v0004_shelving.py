"""Shelving: an incident's shelving (until when, by whom, why) and the meters' shelvings.

Revision ID: 0004
Revises: 0003
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None


def upgrade() -> None:
    """Add ``shelved_until``, ``shelved_by`` and ``shelved_reason`` to ``incidents`` (with an
    index: expiry looks for the shelvings that ran out); create ``meter_shelves``."""
    op.add_column("incidents", sa.Column("shelved_until", sa.Float))
    op.add_column("incidents", sa.Column("shelved_by", sa.String(200)))
    op.add_column("incidents", sa.Column("shelved_reason", sa.Text))
    op.create_index("ix_incidents_shelved", "incidents", ["shelved_until"])
    op.create_table(
        "meter_shelves",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("meter", sa.String(200), nullable=False),
        sa.Column("at", sa.Float, nullable=False),
        sa.Column("by", sa.String(200), nullable=False),
        sa.Column("via", sa.String(100), nullable=False),
        sa.Column("until", sa.Float, nullable=False),
        sa.Column("reason", sa.Text, nullable=False),
        sa.Column("ended_at", sa.Float),
        sa.Column("ended_by", sa.String(200)),
    )
    op.create_index("ix_meter_shelves_meter", "meter_shelves", ["meter", "id"])


def downgrade() -> None:
    """Drop them (``ALTER TABLE ... DROP COLUMN`` on SQLite too, 3.35 and later: a table copy
    would fail on the history's foreign key)."""
    op.drop_table("meter_shelves")
    op.drop_index("ix_incidents_shelved", "incidents")
    for column in ("shelved_reason", "shelved_by", "shelved_until"):
        op.drop_column("incidents", column)
