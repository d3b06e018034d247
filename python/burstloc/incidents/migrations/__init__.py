"""The incident store's schema migrations (Alembic): ``versions/`` holds one file per revision."""
