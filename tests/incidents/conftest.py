"""The incident store's fixtures: ``target``, a fresh store's address on SQLite and on a real
PostgreSQL server (one per session, :mod:`postgres`), so that every test using it runs on
both."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).parents[1] / "live"))  # live_feed: a real burst's readings

from postgres import Server, server


@pytest.fixture(scope="session")
def postgresql() -> Iterator[Server]:
    """A PostgreSQL server for the session."""
    with server() as running:
        yield running


@pytest.fixture(params=["sqlite", "postgresql"])
def target(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A fresh, empty store's address: an SQLite file, or a new PostgreSQL database."""
    if request.param == "sqlite":
        return str(tmp_path / "incidents.sqlite")
    return request.getfixturevalue("postgresql").database()
