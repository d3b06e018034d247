"""What the monitor reports, as the incident store takes it: one :class:`Observed` per record.

A located burst (``"type": "decision"``), the early record of an alarm still being answered
(``"transient"``) and an alarm classified as another event (``"event"``) are all one incident
per alarm, keyed by the first alarm's reading time: the early record opens it and the answer
updates it. A meter fault (a meter gone silent, implausible readings) is one incident per meter
and fault while it is open: the fault clearing and coming back are history rows of the same
incident. The readings the recorder keeps around an alarm (:mod:`burstloc.incidents.kept`)
reach the store as a :class:`Kept`. Pure functions, no database.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

__all__ = [
    "ALARM_RECORDS",
    "FAULTS",
    "MONITOR",
    "Kept",
    "Observed",
    "clean",
    "from_record",
    "meter_fault",
    "summary",
]

#: The monitor's record types that are incidents (health records are not).
ALARM_RECORDS = ("decision", "transient", "event")
#: The meter faults that are incidents.
FAULTS = ("silent", "implausible")
#: Who the monitor's own history rows are by.
MONITOR = "monitor"


@dataclass(frozen=True)
class Observed:
    """One thing the monitor saw, as the store takes it.

    ``key`` names the incident it belongs to; ``kind`` is ``burst``, ``event``, ``alarm`` (an
    early record still being answered) or ``meter``; ``at`` the wall-clock time it was seen (s
    since the epoch); ``reading_time`` the feed's time; ``record`` the monitor's record (alarms);
    ``active`` whether a meter fault is present (``True``) or has cleared (``False``);
    ``alarmed`` the meters whose alarms made an alarm's record (its ``"alarmed"``).
    """

    key: str
    kind: str
    at: float
    summary: str
    reading_time: float | None = None
    pipe: str | None = None
    meter: str | None = None
    record: dict[str, Any] | None = None
    active: bool | None = None
    alarmed: tuple[str, ...] | None = None

    @property
    def is_fault(self) -> bool:
        """Whether this is a meter fault (else an alarm's record)."""
        return self.kind == "meter"

    def alarmed_json(self) -> str | None:
        """The alarmed meters as a JSON list (``None`` when the record names none)."""
        return None if self.alarmed is None else json.dumps(list(self.alarmed))

    def record_json(self) -> str | None:
        """The record as strict, stable JSON (keys sorted; non-finite numbers as null)."""
        if self.record is None:
            return None
        try:  # most records hold no non-finite number: no copy
            return json.dumps(self.record, sort_keys=True, separators=(",", ":"), allow_nan=False)
        except (ValueError, TypeError):
            return json.dumps(
                clean(self.record), sort_keys=True, separators=(",", ":"), allow_nan=False
            )


@dataclass(frozen=True)
class Kept:
    """The readings kept around the alarm of incident ``key``: the feed file ``path`` (absolute)
    and ``onset``, the reading time after which the first alarmed meter's change began (the
    reading before it), or ``None`` when unknown."""

    key: str
    path: str
    onset: float | None


def clean(value: Any) -> Any:
    """``value`` with non-finite floats as ``None`` (strict JSON)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    return value


def _number(value: Any) -> float | None:
    return float(value) if isinstance(value, (int, float)) and math.isfinite(value) else None


def summary(record: dict[str, Any]) -> str:
    """One line for an alarm's record: what it is and where."""
    pipes = record.get("pipes") or []
    position = record.get("position") or {}
    where = f"pipe {pipes[0]['pipe']}" if pipes else "no pipe"
    metres = _number(position.get("metres"))
    if metres is not None:
        where += f", {metres:.0f} m from node {position.get('from')}"
    region = record.get("region") or {}
    length = _number(region.get("length_m"))
    if length is not None:
        where += f" (search region {length:.0f} m)"
    kind = record.get("type")
    if kind == "transient":
        return f"alarm located on {where}; answer due at t = {record.get('answer_at')} s"
    if kind == "event":
        doc = record.get("classification") or {}
        return f"not a burst ({doc.get('class')}): nearest {where}"
    return f"burst located on {where}"


def from_record(record: dict[str, Any], at: float) -> Observed | None:
    """The incident news in one of the monitor's records (``None`` for a health record or a
    record without a first alarm)."""
    kind = record.get("type")
    first = _number(record.get("first_alarm"))
    if kind not in ALARM_RECORDS or first is None:
        return None
    pipes = record.get("pipes") or []
    alarmed = record.get("alarmed")
    return Observed(
        key=f"alarm:{first:.6f}",
        kind={"decision": "burst", "transient": "alarm", "event": "event"}[kind],
        at=at,
        summary=summary(record),
        reading_time=first,
        pipe=str(pipes[0]["pipe"]) if pipes else None,
        record=record,
        alarmed=tuple(str(m) for m in alarmed) if isinstance(alarmed, list) else None,
    )


def meter_fault(
    meter: str, fault: str, active: bool, at: float, reading_time: float | None
) -> Observed:
    """A meter fault that began (``active``) or cleared."""
    what = {"silent": "silent: excluded from localization", "implausible": "implausible readings"}
    return Observed(
        key=f"meter:{meter}:{fault}",
        kind="meter",
        at=at,
        summary=f"meter {meter} {what[fault]}",
        reading_time=reading_time,
        meter=meter,
        active=active,
    )
