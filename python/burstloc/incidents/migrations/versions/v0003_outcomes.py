"""What closed incidents teach: which meters alarmed, and the readings kept around each alarm.

Revision ID: 0003
Revises: 0002
"""

from __future__ import annotations

import json

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    """Add ``alarmed``, ``readings`` and ``onset`` to ``incidents``; fill ``alarmed`` from the
    records already stored."""
    op.add_column("incidents", sa.Column("alarmed", sa.Text))
    op.add_column("incidents", sa.Column("readings", sa.String(1000)))
    op.add_column("incidents", sa.Column("onset", sa.Float))
    table = sa.table(
        "incidents", sa.column("id", sa.Integer), sa.column("record", sa.Text),
        sa.column("alarmed", sa.Text),
    )  # fmt: skip
    connection = op.get_bind()
    stored = sa.select(table.c.id, table.c.record).where(table.c.record.is_not(None))
    rows = connection.execute(stored)
    for incident, record in rows.all():
        try:
            alarmed = json.loads(record).get("alarmed")
        except (ValueError, AttributeError):
            continue
        if isinstance(alarmed, list):
            connection.execute(
                table.update()
                .where(table.c.id == incident)
                .values(alarmed=json.dumps([str(m) for m in alarmed]))
            )


def downgrade() -> None:
    """Drop them."""
    with op.batch_alter_table("incidents") as batch:
        batch.drop_column("onset")
        batch.drop_column("readings")
        batch.drop_column("alarmed")
