"""What closed incidents teach: false alarms per meter, and bursts found as known events.

* :func:`meter_outcomes`: per meter, the incidents its alarms made (:func:`alarmed_meters`: an
  alarm's ``alarmed`` meters, from its latest record) and which of them were closed as false
  alarms or found; :class:`MeterCounts`, the same counted (the store counts them in SQL for
  ``/metrics``: :meth:`~burstloc.incidents.store.IncidentStore.meter_counts`);
* :func:`known_events`: each incident closed as *found* as an entry of a known-events file
  (:mod:`burstloc.experiments.known_events`, which ``burstloc calibrate --known-events``
  reads): the found point snapped to the nearest pipe of the network's drawing
  (:meth:`burstloc.layout.Layout.nearest_pipe`) and its position along it (a fraction from the
  pipe's INP start node), the time the first alarmed meter's change began (the incident's
  ``onset``, the readings' clock; marked ``time_known: false``: calibration fits the burst's
  own time from the arrivals) and the readings kept around it
  (:mod:`burstloc.incidents.kept`), as a path relative to the file written. A found incident
  that cannot become an event is named with the reason, never left out silently.

Pure functions over the store's rows (:meth:`~burstloc.incidents.store.IncidentStore.incidents`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from burstloc.incidents.lifecycle import FALSE_ALARM, FOUND
from burstloc.layout import Layout

__all__ = [
    "SNAP_WITHIN",
    "MeterCounts",
    "MeterOutcomes",
    "alarmed_meters",
    "known_events",
    "meter_outcomes",
    "rank",
]

#: How far (the network's coordinates) a found point may lie from the nearest pipe's drawing.
SNAP_WITHIN = 50.0


def alarmed_meters(alarmed: Iterable[str] | None) -> list[str]:
    """The meters whose alarms made an incident, each once, in order: its ``alarmed`` (the
    meters its latest record names; ``None``, not an alarm's: none). The one definition of an
    incident a meter's alarms made, for :func:`meter_outcomes` and for the store's
    ``incident_meters`` rows (:mod:`burstloc.incidents.counts`)."""
    return list(dict.fromkeys(alarmed or ()))


@dataclass(frozen=True)
class MeterCounts:
    """One meter's alarms counted: the incidents they made (``alarmed``), those closed as
    ``false_alarms`` and those ``found``."""

    meter: str
    alarmed: int
    false_alarms: int
    found: int


def rank(meter: str, false_alarms: int) -> tuple[int, str]:
    """The sort key of every listing of meters: most false alarms first, then by name (in
    Python: a database's collation may order names otherwise)."""
    return -false_alarms, meter


@dataclass
class MeterOutcomes:
    """One meter's alarms: the ``incidents`` they made, those closed as ``false_alarms`` and
    those ``found`` (incident numbers, oldest first)."""

    meter: str
    incidents: list[int] = field(default_factory=list)
    false_alarms: list[int] = field(default_factory=list)
    found: list[int] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        """``meter``, the counts (``alarmed``, ``false_alarms``, ``found``) and the lists."""
        return {
            "meter": self.meter, "alarmed": len(self.incidents),
            "false_alarms": len(self.false_alarms), "found": len(self.found),
            "incidents": self.incidents, "false_alarm_incidents": self.false_alarms,
            "found_incidents": self.found,
        }  # fmt: skip

    def counts(self) -> MeterCounts:
        """The counts of the lists."""
        return MeterCounts(self.meter, len(self.incidents), len(self.false_alarms), len(self.found))


def meter_outcomes(rows: Iterable[dict[str, Any]]) -> list[MeterOutcomes]:
    """Per meter that alarmed, its incidents and their outcomes (:func:`rank`'s order)."""
    meters: dict[str, MeterOutcomes] = {}
    for row in sorted(rows, key=lambda r: r["id"]):
        for meter in alarmed_meters(row.get("alarmed")):
            doc = meters.setdefault(meter, MeterOutcomes(meter))
            doc.incidents.append(row["id"])
            if row["outcome"] == FALSE_ALARM:
                doc.false_alarms.append(row["id"])
            elif row["outcome"] == FOUND:
                doc.found.append(row["id"])
    return sorted(meters.values(), key=lambda m: rank(m.meter, len(m.false_alarms)))


def known_events(
    rows: Iterable[dict[str, Any]],
    layout: Layout,
    out: str | os.PathLike[str],
    *,
    within: float = SNAP_WITHIN,
) -> tuple[list[dict[str, Any]], list[str]]:
    """The known-events entries of the incidents in ``rows`` closed as found, for a file
    written to ``out`` (its readings paths relative to its directory), and why each other
    found incident cannot be one: ``(entries, refusals)``. ``within``: the farthest a found
    point may be from the nearest pipe (the network's coordinates)."""
    base = Path(out).resolve().parent
    entries: list[dict[str, Any]] = []
    refusals: list[str] = []
    for row in sorted(rows, key=lambda r: r["id"]):
        if row["outcome"] != FOUND:
            continue
        entry = _entry(row, layout, base, within)
        if isinstance(entry, str):
            where = f"{row['found_x']:g},{row['found_y']:g}"
            refusals.append(f"incident {row['id']} (found at {where}): {entry}")
        else:
            entries.append(entry)
    return entries, refusals


def _entry(row: dict[str, Any], layout: Layout, base: Path, within: float) -> dict[str, Any] | str:
    """The known-events entry of a found incident, or why it cannot be one."""
    x, y = row["found_x"], row["found_y"]
    if not row["readings"]:
        return (
            "no readings were kept around its alarm (a PostgreSQL store without --state, or a "
            "monitor that kept none then)"
        )
    if not os.path.isfile(row["readings"]):
        return f"its readings file {row['readings']!r} is gone"
    if row["onset"] is None:
        return "the onset of its first alarm is unknown"
    nearest = layout.nearest_pipe(x, y)
    if nearest is None:
        return "the network has no pipes"
    pipe, fraction, gap = nearest
    if gap > within:
        return (
            f"the point is {gap:.1f} from the nearest pipe ({pipe}), farther than {within:g} "
            "(the network's coordinates): a point of another network?"
        )
    return {
        "name": f"incident {row['id']}: burst found at {x:g},{y:g}",
        "readings": os.path.relpath(row["readings"], base),
        "time": row["onset"],  # the first meter's change, not the burst's own time:
        "time_known": False,  # calibration fits that from the arrivals
        "pipe": pipe,
        "position": round(fraction, 6),
    }
