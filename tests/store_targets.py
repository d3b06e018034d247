"""Fixtures of the incident store's tests (a plugin of ``conftest.py``): ``postgresql``, a real
PostgreSQL server for the session (:mod:`postgres`), and ``target``, a fresh store's address on
SQLite and on that server, so that every test using it runs on both."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from postgres import Server, server


@pytest.fixture(scope="session")
def postgresql() -> Iterator[Server]:
    """A PostgreSQL server for the session (started at the first test that needs it)."""
    with server() as running:
        yield running


@pytest.fixture(params=["sqlite", "postgresql"])
def target(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A fresh, empty store's address: an SQLite file, or a new PostgreSQL database."""
    if request.param == "sqlite":
        return str(tmp_path / "incidents.sqlite")
    return str(request.getfixturevalue("postgresql").database())
