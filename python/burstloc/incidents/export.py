"""Incidents written out for other tools: CSV (one row per incident; wall-clock times in ISO
8601 UTC; ``alarmed``: the meters whose alarms made it, space-separated; ``readings``: the feed
file kept around its alarm; ``shelved_until``, ``shelved_by``, ``shelved_reason``: its shelving
in force, empty when it is not shelved) or JSON (every incident with its latest record and its
history; wall-clock times as seconds since the epoch)."""

from __future__ import annotations

import csv
import io
import json
from datetime import datetime, timezone
from typing import Any

from burstloc.incidents.store import IncidentStore

__all__ = ["CSV_COLUMNS", "FORMATS", "export", "iso"]

#: The export formats.
FORMATS = ("csv", "json")
#: The CSV's columns, in order.
CSV_COLUMNS = (
    "id", "kind", "state", "detected_at", "updated_at", "closed_at", "reading_time", "pipe",
    "meter", "summary", "outcome", "found_x", "found_y", "acknowledged_by", "dispatched_by",
    "closed_by", "notes", "alarmed", "readings", "shelved_until", "shelved_by", "shelved_reason",
)  # fmt: skip


def iso(seconds: float | None) -> str:
    """Seconds since the epoch as an ISO 8601 UTC time to the second ('' for ``None``)."""
    if seconds is None:
        return ""
    return datetime.fromtimestamp(seconds, tz=timezone.utc).isoformat(timespec="seconds")


def _by(history: list[dict[str, Any]], action: str) -> str:
    return next((h["by"] for h in reversed(history) if h["action"] == action), "")


def export(store: IncidentStore, form: str) -> str:
    """Every incident of ``store`` as ``form`` (``csv`` or ``json``), open ones first.

    Raises:
        ValueError: an unknown format.
    """
    if form not in FORMATS:
        raise ValueError(f"format must be one of {FORMATS}, got {form!r}")
    rows = store.incidents()
    histories = store.histories()
    if form == "json":
        records = store.records()
        docs = [
            {**row, "record": records.get(row["id"]), "history": histories.get(row["id"], [])}
            for row in rows
        ]
        return json.dumps(docs, indent=1) + "\n"
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for row in rows:
        history = histories.get(row["id"], [])
        notes = " | ".join(
            f"{h['by']}: {h['note']}" for h in history if h["note"] and h["by"] != "monitor"
        )
        doc = {
            **row,
            "detected_at": iso(row["detected_at"]),
            "updated_at": iso(row["updated_at"]),
            "closed_at": iso(row["closed_at"]),
            "shelved_until": iso(row["shelved_until"]),
            "acknowledged_by": _by(history, "acknowledged"),
            "dispatched_by": _by(history, "dispatched"),
            "closed_by": _by(history, "closed"),
            "notes": notes,
            "alarmed": " ".join(row["alarmed"] or ()),
        }
        writer.writerow(["" if doc[c] is None else doc[c] for c in CSV_COLUMNS])
    return out.getvalue()
