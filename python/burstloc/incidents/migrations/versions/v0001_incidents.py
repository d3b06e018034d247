"""The incidents and their history.

Revision ID: 0001
Revises:
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None


def upgrade() -> None:
    """Create the two tables and their indexes."""
    op.create_table(
        "incidents",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("key", sa.String(300), nullable=False),
        sa.Column("kind", sa.String(16), nullable=False),
        sa.Column("state", sa.String(16), nullable=False),
        sa.Column("detected_at", sa.Float, nullable=False),
        sa.Column("updated_at", sa.Float, nullable=False),
        sa.Column("reading_time", sa.Float),
        sa.Column("pipe", sa.String(200)),
        sa.Column("meter", sa.String(200)),
        sa.Column("summary", sa.String(500), nullable=False),
        sa.Column("record", sa.Text),
        sa.Column("active", sa.Boolean),
        sa.Column("outcome", sa.String(16)),
        sa.Column("found_x", sa.Float),
        sa.Column("found_y", sa.Float),
        sa.Column("closed_at", sa.Float),
    )
    op.create_index("ix_incidents_key", "incidents", ["key"])
    op.create_index("ix_incidents_state_detected", "incidents", ["state", "detected_at"])
    op.create_table(
        "history",
        sa.Column("id", sa.Integer, primary_key=True, autoincrement=True),
        sa.Column("incident_id", sa.Integer, sa.ForeignKey("incidents.id"), nullable=False),
        sa.Column("at", sa.Float, nullable=False),
        sa.Column("by", sa.String(200), nullable=False),
        sa.Column("via", sa.String(100), nullable=False),
        sa.Column("action", sa.String(16), nullable=False),
        sa.Column("state", sa.String(16), nullable=False),
        sa.Column("note", sa.Text),
        sa.Column("detail", sa.Text),
    )
    op.create_index("ix_history_incident", "history", ["incident_id", "id"])


def downgrade() -> None:
    """Drop them."""
    op.drop_table("history")
    op.drop_table("incidents")
