"""Each meter's incidents counted by the database: the ``incident_meters`` rows, written with
an incident's ``alarmed`` meters (:func:`keep_alarmed`, in the transaction that writes them),
and the one query that counts them (:func:`meter_counts`).

``alarmed`` is a JSON list, which no database counts; its meters are also kept as rows, one per
incident and meter (:func:`~burstloc.incidents.outcomes.alarmed_meters`: the one definition of
an incident a meter's alarms made), and replaced when a later record of the incident changes
them. :func:`meter_counts` is then one ``GROUP BY`` over them joined to the incidents' outcomes:
``/metrics`` asks for it at every scrape, where :func:`~burstloc.incidents.outcomes.meter_outcomes`
needs every incident read (``benches/bench_incidents.py``, section 2). The two agree
(``tests/incidents/test_counts.py``). Statements are built once (:mod:`burstloc.incidents.writing`
says why); imported only once a store is opened (it imports SQLAlchemy).
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from sqlalchemy import bindparam, case, func, select

from burstloc.incidents.lifecycle import FALSE_ALARM, FOUND
from burstloc.incidents.outcomes import MeterCounts, alarmed_meters, rank
from burstloc.incidents.schema import incident_meters as im
from burstloc.incidents.schema import incidents as t

__all__ = ["keep_alarmed", "meter_counts"]

_INSERT = im.insert()
_DELETE = im.delete().where(im.c.incident_id == bindparam("incident"))


def _tally(outcome: str) -> Any:
    """How many of a meter's incidents were closed with ``outcome``."""
    return func.sum(case((t.c.outcome == outcome, 1), else_=0))


#: Per meter: its incidents, those closed as false alarms, those found.
_COUNTS = (
    select(im.c.meter, func.count(), _tally(FALSE_ALARM), _tally(FOUND))
    .select_from(im.join(t, t.c.id == im.c.incident_id))
    .group_by(im.c.meter)
)


def keep_alarmed(
    connection: Any, incident: int, alarmed: Iterable[str] | None, *, new: bool = False
) -> None:
    """Make ``incident``'s rows its ``alarmed`` meters (as the ``alarmed`` column is written, in
    its transaction); ``new``: an incident just inserted, with no rows yet."""
    if not new:
        connection.execute(_DELETE, {"incident": incident})
    rows = [{"incident_id": incident, "meter": m} for m in alarmed_meters(alarmed)]
    if rows:
        connection.execute(_INSERT, rows)


def meter_counts(connection: Any) -> list[MeterCounts]:
    """Per meter that alarmed, its incidents and their outcomes counted (one query), in
    :func:`~burstloc.incidents.outcomes.rank`'s order."""
    counts = [
        MeterCounts(str(meter), int(alarmed), int(false_alarms or 0), int(found or 0))
        for meter, alarmed, false_alarms, found in connection.execute(_COUNTS)
    ]
    return sorted(counts, key=lambda m: rank(m.meter, m.false_alarms))
