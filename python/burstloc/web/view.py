"""The page side's state of the monitor: what a browser that opens the page is shown first.

A :class:`View` takes the items the monitor handed off (:class:`burstloc.web.hub.Hub`) on the
server's event loop, keeps the current state (the meters' recent readings, the current
incident: its alarms in order, its early ``transient`` record and its decision or event, the
latest health record, a log of decisions and events) and answers, for every batch, the news to
push to the browsers. Everything here runs on one thread: no locks.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Sequence
from typing import Any

from burstloc.readings import Step

__all__ = ["INCIDENT_GAP", "ROWS_PER_PUSH", "View"]

#: Seconds (reading time) after which a new alarm starts a new incident even when the last one
#: got no answer (its alarms were dismissed: one meter alone).
INCIDENT_GAP = 60.0

#: Newest readings pushed per batch at most (a feed replayed fast, or a backlog, is thinned for
#: the chart; the page side's work, which shares the monitor's interpreter, stays bounded).
ROWS_PER_PUSH = 50


def _clean(value: Any) -> Any:
    """``value`` with non-finite floats as ``None`` (strict JSON for the browser)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _row(step: Step, meters: Sequence[str]) -> tuple[float, list[float | None]]:
    """A step as the page's chart takes it: (time, values; ``None`` for a value the meter did
    not send: filled, or missing)."""
    values = [_clean(float(v)) for v in step.values]
    for meter in step.filled:
        values[meters.index(meter)] = None
    return float(step.timestamp), values


def _describe(record: dict[str, Any]) -> str:
    """One log line for a decision, transient or event record."""
    position = record.get("position") or {}
    where = f"pipe {record['pipes'][0]['pipe']}" if record.get("pipes") else "no pipe"
    if position.get("metres") is not None:
        where += f", {position['metres']:.0f} m from node {position.get('from')}"
    if record["type"] == "transient":
        what = "classified" if "classify_at" in record else "answered"
        wait = record.get("wait_s")
        since = "" if wait is None else f" (the burst's onset + {wait:g} s)"
        return f"alarm located on {where}; {what} at t = {record.get('answer_at', 0):g} s{since}"
    if record["type"] == "event":
        kind = record.get("classification") or {}
        return f"not a burst ({kind.get('class')}): {kind.get('reason', '')}; nearest {where}"
    delay = record.get("decision_delay_s")
    after = "" if delay is None else f" ({delay:.1f} s after the first alarm)"
    return f"burst located on {where}{after}"


class View:
    """The monitor's state as the page shows it (module docstring)."""

    def __init__(
        self,
        meters: Sequence[str],
        capture_interval: float,
        meta: dict[str, Any],
        *,
        window: float = 600.0,
        log: int = 400,
    ) -> None:
        self.meters = list(meters)
        self.meta = dict(meta, meters=self.meters, capture_interval=capture_interval)
        self.rows: deque[Step] = deque(  # as handed off: converted only when shown
            maxlen=max(math.ceil(window / capture_interval), 2)
        )
        self.log: deque[dict[str, Any]] = deque(maxlen=log)
        self.alarms: list[dict[str, Any]] = []
        self.transient: dict[str, Any] | None = None
        self.answer: dict[str, Any] | None = None  # the incident's decision or event record
        self.health: dict[str, Any] | None = None
        self.implausible_at: dict[str, float] = {}
        self.now: float | None = None  # the newest reading time

    def _log(self, time: float | None, kind: str, text: str) -> dict[str, Any]:
        entry = {"time": time, "kind": kind, "text": text}
        self.log.append(entry)
        return entry

    def _health(self, record: dict[str, Any]) -> None:
        before = (self.health or {}).get("meters", {})
        for meter, doc in record.get("meters", {}).items():
            if doc.get("implausible", 0) > before.get(meter, {}).get("implausible", 0):
                self.implausible_at[meter] = record.get("time") or self.now or 0.0
        self.health = _clean(record)

    def take(self, items: Iterable[Step | tuple[str, Any]]) -> list[dict[str, Any]]:
        """Apply the handed-off ``items``; return the news for the browsers (the newest
        :data:`ROWS_PER_PUSH` readings as one ``rows`` item, the rest in order)."""
        news: list[dict[str, Any]] = []
        steps = 0
        health = False
        for item in items:
            if isinstance(item, Step):
                self.rows.append(item)
                self.now = float(item.timestamp)
                steps += 1
                continue
            kind, payload = item
            if kind == "alarm":
                meter, t, onset, amplitude = payload
                last = self.alarms[-1]["time"] if self.alarms else None
                if self.answer is not None or (last is not None and t - last > INCIDENT_GAP):
                    self.alarms, self.transient, self.answer = [], None, None
                    news.append({"kind": "incident"})
                alarm = _clean(
                    {"meter": meter, "time": t, "onset": onset, "amplitude": float(amplitude)}
                )
                self.alarms.append(alarm)
                text = f"meter {meter} alarmed (change from t = {onset:g} s, {amplitude:+.2f} m)"
                news.append({"kind": "alarm", "alarm": alarm, "log": self._log(t, "alarm", text)})
            elif kind == "record":
                record = _clean(payload)
                if record["type"] == "health":
                    self._health(payload)
                    health = True
                    continue
                if record["type"] == "transient":
                    self.transient = record
                else:
                    self.answer = record
                entry = self._log(record.get("time"), record["type"], _describe(record))
                news.append({"kind": "record", "record": record, "log": entry})
            elif kind == "message":
                news.append({"kind": "message", "log": self._log(self.now, "message", payload)})
            elif kind == "health":
                self._health(payload)
                health = True
        if steps:
            newest = [
                self.rows[-k] for k in range(min(steps, ROWS_PER_PUSH, len(self.rows)), 0, -1)
            ]
            news.insert(0, {"kind": "rows", "rows": [_row(s, self.meters) for s in newest]})
        if health:
            news.append({"kind": "health", **self._health_news()})
        return news

    def _health_news(self) -> dict[str, Any]:
        return {"health": self.health, "implausible_at": dict(self.implausible_at)}

    def snapshot(self) -> dict[str, Any]:
        """Everything a browser that just opened the page needs."""
        return {
            "kind": "snapshot",
            "meta": self.meta,
            "rows": [_row(s, self.meters) for s in self.rows],
            "log": list(self.log),
            "alarms": list(self.alarms),
            "transient": self.transient,
            "answer": self.answer,
            **self._health_news(),
        }
