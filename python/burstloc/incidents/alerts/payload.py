"""The JSON a webhook receives: one document per alert (:func:`payload`). Pure functions.

::

    {"event": "incident.new",            # or "incident.escalated"
     "alert": "5f0c...",                  # also the Idempotency-Key header
     "incident": {"id": 12, "kind": "burst", "state": "detected",
                  "detected_at": "2026-11-28T06:02:00Z", "reading_time": 62.4,
                  "summary": "burst located on pipe 9, 310 m from node N5 (...)",
                  "pipe": "9", "meter": null,
                  "point": {"pipe": "9", "from": "N5", "metres": 310.0, ...},
                  "region": {"length_m": 420.0, "confidence": 0.95, "pipes": ["9", "8"]}},
     "at": 1795932120.0,                  # when it became due, on the alerts' clock
     "unacknowledged_minutes": 15.0,      # escalations only
     "link": "http://host:8080/#incident=12",   # null without the page
     "source": "burstloc 0.9.0"}
"""

from __future__ import annotations

import json
import math
from datetime import datetime, timezone
from typing import Any

from burstloc.incidents.intake import clean

__all__ = ["ESCALATED", "NEW", "payload"]

#: The two events (the outbox's ``event``; ``"incident." + event`` in the payload).
NEW, ESCALATED = "new", "escalated"


def _iso(t: float | None) -> str | None:
    if t is None or not math.isfinite(t):
        return None
    return datetime.fromtimestamp(t, timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _point(record: dict[str, Any] | None) -> dict[str, Any] | None:
    position = (record or {}).get("position")
    return dict(position) if isinstance(position, dict) else None


def _region(record: dict[str, Any] | None) -> dict[str, Any] | None:
    if not record:
        return None
    found = record.get("region")
    region: dict[str, Any] = found if isinstance(found, dict) else {}
    pipes = [p.get("pipe") for p in record.get("pipes") or [] if isinstance(p, dict)]
    if not region and not pipes:
        return None
    doc: dict[str, Any] = {k: region.get(k) for k in ("length_m", "confidence") if k in region}
    doc["pipes"] = pipes
    stretches = region.get("stretches")
    if isinstance(stretches, list):
        doc["stretches"] = len(stretches)
    return doc


def payload(
    event: str,
    key: str,
    incident: dict[str, Any],
    at: float,
    *,
    link: str | None,
    source: str,
    unacknowledged: float | None = None,
) -> str:
    """The JSON text of one alert (module docstring) of ``event`` (:data:`NEW`,
    :data:`ESCALATED`): ``incident`` holds the incident's
    columns (``id``, ``kind``, ``state``, ``detected_at``, ``reading_time``, ``summary``,
    ``pipe``, ``meter``) and its latest ``record`` (a dict, or ``None``); ``at``: when the
    alert became due; ``unacknowledged``: seconds (escalations)."""
    record = incident.get("record")
    doc: dict[str, Any] = {
        "event": f"incident.{event}",
        "alert": key,
        "incident": {
            "id": incident["id"],
            "kind": incident["kind"],
            "state": incident["state"],
            "detected_at": _iso(incident.get("detected_at")),
            "reading_time": incident.get("reading_time"),
            "summary": incident["summary"],
            "pipe": incident.get("pipe"),
            "meter": incident.get("meter"),
            "point": _point(record),
            "region": _region(record),
        },
        "at": at,
        "link": link,
        "source": source,
    }
    if unacknowledged is not None:
        doc["unacknowledged_minutes"] = round(unacknowledged / 60, 3)
    return json.dumps(clean(doc), allow_nan=False)
