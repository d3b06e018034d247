"""burstloc.incidents.export on SQLite and on a real PostgreSQL server: the CSV has a column
for each of its names, in order, read back with the csv module; an incident shelved through the
store carries its shelving (until when in ISO 8601 UTC, by whom, why), the others and one
unshelved carry empty cells; the JSON carries the same shelving."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Iterator

import pytest

from burstloc.incidents import IncidentStore
from burstloc.incidents.export import CSV_COLUMNS, export
from burstloc.incidents.intake import from_record, meter_fault

START = 1_800_000_000.0  # 2027-01-15T08:00:00Z
RECORD = {
    "type": "decision", "burst": True, "time": 75.0,
    "pipes": [{"pipe": "9", "score": 0.0}], "region": {"length_m": 80.0},
}  # fmt: skip
SHELVING = ("shelved_until", "shelved_by", "shelved_reason")


@pytest.fixture
def now() -> list[float]:
    """The store's wall clock, set by the test."""
    return [START]


@pytest.fixture
def store(target: str, now: list[float]) -> Iterator[IncidentStore]:
    opened = IncidentStore.open(target, clock=lambda: now[0])
    yield opened
    opened.close()


def _incidents(store: IncidentStore) -> tuple[int, int, int]:
    """Two bursts and a meter fault."""
    items = [from_record({**RECORD, "first_alarm": t}, START) for t in (62.4, 900.0)]
    items.append(meter_fault("N8", "silent", True, START, 10.0))
    first, second, fault = store.take([item for item in items if item is not None])
    return first, second, fault


def _csv(store: IncidentStore) -> tuple[list[str], dict[int, dict[str, str]]]:
    reader = csv.reader(io.StringIO(export(store, "csv")))
    header = next(reader)
    rows = {int(row[0]): dict(zip(header, row, strict=True)) for row in reader}
    return header, rows


def test_a_shelved_incident_is_exported_with_its_shelving(store: IncidentStore) -> None:
    first, second, fault = _incidents(store)
    store.shelves.shelve(first, 5400.0, by="ann", via="cli", reason="hydrant flushing, Main St")
    store.shelves.shelve(fault, 600.0, by="bob", via="page 10.0.0.7", reason="radio link down")
    store.shelves.unshelve(fault, by="bob", via="cli")
    header, rows = _csv(store)
    assert header == list(CSV_COLUMNS) and set(SHELVING) <= set(header)
    assert [rows[first][c] for c in SHELVING] == [
        "2027-01-15T09:30:00+00:00", "ann", "hydrant flushing, Main St",
    ]  # fmt: skip
    assert [rows[second][c] for c in SHELVING] == ["", "", ""]  # never shelved
    assert [rows[fault][c] for c in SHELVING] == ["", "", ""]  # shelved, then back
    assert rows[first]["state"] == "detected"  # shelving does not change the state
    docs = {doc["id"]: doc for doc in json.loads(export(store, "json"))}
    assert [docs[first][c] for c in SHELVING] == [
        START + 5400.0, "ann", "hydrant flushing, Main St",
    ]  # fmt: skip
    assert [docs[k][c] for k in (second, fault) for c in SHELVING] == [None] * 6


def test_a_shelving_that_ran_out_leaves_the_export(store: IncidentStore, now: list[float]) -> None:
    first, _, _ = _incidents(store)
    store.shelves.shelve(first, 60.0, by="ann", via="cli", reason="crew on site")
    assert _csv(store)[1][first]["shelved_by"] == "ann"
    now[0] += 61.0
    rows = _csv(store)[1]
    assert [rows[first][c] for c in SHELVING] == ["", "", ""]
    assert json.loads(export(store, "json"))[0]["shelved_until"] is None
