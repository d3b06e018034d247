"""Known events read for calibration: where and when each happened, and what the meters heard.

A known-events file (JSON) lists transients whose place and time are known, each with the
readings the meters sent around it (a feed in the form ``burstloc monitor --readings`` reads)::

    {"events": [
        {"name": "valve V12 closed", "readings": "v12.csv", "time": 10.0, "junction": "n54"},
        {"name": "burst dug up", "readings": "b7.csv", "time": 10.0,
         "pipe": "p233", "position": 0.5}
    ]}

``time`` is in the readings' own clock (seconds, or ISO 8601 like the readings);
``"time_known": false`` says it is not when the event happened but about when the first meter
heard it (a burst found later, ``burstloc incidents known-events``): the fit then takes the
event's time from its arrivals (:mod:`burstloc.localize.travel_fit`). The place is a
``junction`` or a ``pipe`` with the ``position`` along it (a fraction from its INP start node,
default 0.5); a relative ``readings`` path is read from the file's directory.
:func:`event_arrivals` runs the calibrated detector bank of the readings' capture interval over
each feed, as the monitor does, and keeps each meter's first alarm after the event: its onset
(the reading before the change) is that meter's arrival.
:func:`~burstloc.localize.travel_fit.fit_travel_times` then fits the wave speed and the clocks.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from burstloc.exceptions import ConfigError, StreamError
from burstloc.experiments.position import NetworkDistance, PipePoint
from burstloc.live.feeds import StepFeed
from burstloc.live.parse import BadReading, parse_lines
from burstloc.localize.config import Calibration
from burstloc.localize.evidence import IndexedAlarm, evidence_from_alarms
from burstloc.localize.interval import calibrated_bank
from burstloc.localize.travel_fit import EventArrivals
from burstloc.network import Network
from burstloc.readings import Reading, Step, step_values, timestamp_seconds

__all__ = ["KnownEvent", "event_arrivals", "onsets_after", "read_known_events"]


@dataclass(frozen=True)
class KnownEvent:
    """One entry of a known-events file: its ``name``, ``readings`` feed, ``time`` (s) and
    place: a ``junction``, or a ``pipe`` with ``position`` (fraction from its INP start);
    ``time_known=False``: ``time`` is about when the first meter heard it (module docstring)."""

    name: str
    readings: Path
    time: float
    junction: str | None = None
    pipe: str | None = None
    position: float = 0.5
    time_known: bool = True


def _event(entry: Any, index: int, base: Path, network: Network) -> KnownEvent:
    """One checked entry (``events[index]``)."""
    where = f"events[{index}]"
    if not isinstance(entry, dict):
        raise ConfigError(f"{where} must be an object, got {type(entry).__name__}")
    keys = {"name", "readings", "time", "time_known", "junction", "pipe", "position"}
    unknown = sorted(set(entry) - keys)
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown}")
    name = str(entry.get("name", where))
    if not isinstance(entry.get("readings"), str):
        raise ConfigError(f"{where} ({name}): 'readings' must name the feed file")
    readings = base / entry["readings"]
    if not readings.is_file():
        raise ConfigError(f"{where} ({name}): no readings file {str(readings)!r}")
    raw: Any = entry.get("time")
    if isinstance(raw, bool):
        raise ConfigError(f"{where} ({name}): 'time' must be seconds or ISO 8601, got {raw!r}")
    try:
        t = timestamp_seconds(raw) if isinstance(raw, str) else float(raw)
    except (TypeError, ValueError):
        raise ConfigError(
            f"{where} ({name}): 'time' must be seconds or ISO 8601, got {raw!r}"
        ) from None
    if not math.isfinite(t):
        raise ConfigError(f"{where} ({name}): 'time' must be finite, got {raw!r}")
    junction, pipe = entry.get("junction"), entry.get("pipe")
    if (junction is None) == (pipe is None):
        raise ConfigError(f"{where} ({name}): give the place as 'junction' or as 'pipe', once")
    if junction is not None and junction not in network.model.node_name_list:
        raise ConfigError(f"{where} ({name}): {junction!r} is not a node of the network")
    if pipe is not None and pipe not in network.model.pipe_name_list:
        raise ConfigError(f"{where} ({name}): {pipe!r} is not a pipe of the network")
    position = entry.get("position", 0.5)
    if isinstance(position, bool) or not isinstance(position, (int, float)):
        raise ConfigError(f"{where} ({name}): 'position' must be a number, got {position!r}")
    if not 0.0 <= position <= 1.0:
        raise ConfigError(f"{where} ({name}): 'position' must be within 0..1, got {position}")
    time_known = entry.get("time_known", True)
    if not isinstance(time_known, bool):
        raise ConfigError(
            f"{where} ({name}): 'time_known' must be true or false, got {time_known!r}"
        )
    return KnownEvent(name, readings, t, junction, pipe, float(position), time_known)


def read_known_events(path: str | Path, network: Network) -> list[KnownEvent]:
    """The events of a known-events file (module docstring), checked against ``network``.

    Raises:
        ConfigError: an unreadable file, a malformed entry (named), a place not in the network
            or a missing readings file.
    """
    path = Path(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(f"cannot read known events {str(path)!r}: {exc.strerror}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"known events {str(path)!r} is not JSON: {exc}") from None
    entries = doc.get("events") if isinstance(doc, dict) else None
    if not isinstance(entries, list) or not entries:
        raise ConfigError(f"known events {str(path)!r}: want {{'events': [...]}} with one or more")
    return [_event(e, i, path.parent, network) for i, e in enumerate(entries)]


def _distances(
    event: KnownEvent, network: Network, distance: NetworkDistance, meters: Sequence[str]
) -> dict[str, float]:
    """Shortest path (m) from the event's place to each meter, along ``network``'s pipes."""
    if event.junction is not None:
        return {m: distance.between_nodes(event.junction, m) for m in meters}
    link = network.model.get_link(event.pipe)
    point = PipePoint(str(event.pipe), link.start_node_name, event.position * float(link.length))
    return {m: distance.to_node(point, m) for m in meters}


def _readings(event: KnownEvent, meters: Sequence[str]) -> list[Reading]:
    """The event's readings of ``meters`` (others are not part of the model).

    Raises:
        ConfigError: a bad reading (the first named, the rest counted).
    """
    wanted = set(meters)
    found: list[Reading] = []
    bad: list[BadReading] = []
    with event.readings.open(encoding="utf-8", errors="replace") as lines:
        for item in parse_lines(lines):
            if isinstance(item, BadReading):
                bad.append(item)
            elif item.meter in wanted:
                found.append(item)
    if bad:
        raise ConfigError(
            f"known event {event.name!r}: {len(bad)} bad reading(s) in {str(event.readings)!r}, "
            f"first {bad[0]}"
        )
    return found


def _interval(event: KnownEvent, readings: Sequence[Reading], config: Calibration) -> float:
    """The readings' capture interval: the calibrated one their timestamps' spacing matches.

    Raises:
        ConfigError: fewer than two timestamps, or a spacing no calibrated interval has.
    """
    stamps = np.unique([r.timestamp for r in readings])
    if stamps.size < 2:
        raise ConfigError(f"known event {event.name!r}: its readings hold fewer than two times")
    spacing = float(np.median(np.diff(stamps)))
    intervals = [c.capture_interval for c in config.intervals]
    nearest = min(intervals, key=lambda c: abs(c - spacing))
    if abs(nearest - spacing) > 0.01 * nearest:
        raise ConfigError(
            f"known event {event.name!r}: its readings come every {spacing:g} s, not at a "
            f"calibrated capture interval ({', '.join(f'{c:g}' for c in intervals)} s)"
        )
    return nearest


def _onsets(
    event: KnownEvent, config: Calibration, detector: str
) -> tuple[dict[str, float], float]:
    """Each meter's first alarm onset (s) at or after the event, the calibrated bank run over
    its readings as the monitor runs it, and the readings' capture interval."""
    meters = list(config.meters)
    readings = _readings(event, meters)
    capture_interval = _interval(event, readings, config)
    bank = calibrated_bank(detector, len(meters), config.for_interval(capture_interval))
    feed = StepFeed(meters, period=capture_interval)
    times: list[float] = []
    rows: list[np.ndarray] = []
    alarms: list[IndexedAlarm] = []

    def run(steps: list[Step]) -> None:
        for step in steps:
            times.append(float(step.timestamp))
            rows.append(step_values(step))
            for alarm in bank.step(rows[-1]):
                start, channel = max(int(alarm.start), 0), int(alarm.channel or 0)
                alarms.append(IndexedAlarm(channel, len(times) - 1, start, float(alarm.amplitude)))

    try:
        for reading in readings:
            run(feed.push(reading))
        run(feed.flush())
    except StreamError as exc:
        raise ConfigError(f"known event {event.name!r}: {exc}") from None
    if not times or times[0] >= event.time:
        raise ConfigError(
            f"known event {event.name!r}: its readings must start before the event "
            f"(at {event.time:g} s) so that the detectors know the level before it"
        )
    readings_seen = (np.asarray(times), np.asarray(rows))
    return onsets_after(
        meters, readings_seen, alarms, event.time, capture_interval
    ), capture_interval


def onsets_after(
    meters: Sequence[str],
    readings: tuple[np.ndarray, np.ndarray],
    alarms: Sequence[Any],
    time: float,
    capture_interval: float,
) -> dict[str, float]:
    """Each meter's first alarm start (s) at or after ``time``, as the monitor's localizers
    read it (:func:`~burstloc.localize.evidence.evidence_from_alarms`), from a bank's
    ``alarms`` over ``readings`` ``(times, values)``; ``{}`` where none starts then."""
    times, values = readings
    kept = [a for a in alarms if times[max(int(a.start), 0)] + capture_interval >= time]
    if not kept:
        return {}
    heard = evidence_from_alarms(meters, times, values, kept, capture_interval=capture_interval)
    return {meter: float(alarm.start) for meter, alarm in heard.alarms.items()}


def event_arrivals(
    events: Sequence[KnownEvent],
    network: Network,
    config: Calibration,
    detector: str = "cusum",
) -> list[EventArrivals]:
    """What the meters heard of each event (module docstring); each feed's capture interval is
    the calibrated one its readings' spacing matches. Where the fronts are heard slower than
    the wave at that interval (its ``front_factor``), the distances are divided by it: the fit
    then finds the wave's own speed, and the calibrated factors still hold.

    Raises:
        ConfigError: a readings file that cannot be read as a feed, readings at no calibrated
            capture interval, or readings that start after the event.
    """
    found = []
    # one graph and path cache for every event, timed as the model times paths
    stretch = {p.pipe: p.stretch for p in config.model.pipes if p.stretch != 1.0}
    distance = NetworkDistance(network.model, stretch)
    for e in events:
        onsets, interval = _onsets(e, config, detector)
        # at the speed the fronts are heard at this interval, so that the fit gives the wave's
        factor = config.for_interval(interval).front_factor
        paths = _distances(e, network, distance, config.meters)
        found.append(
            EventArrivals(
                name=e.name,
                time=e.time,
                distances={m: d / factor for m, d in paths.items()},
                onsets=onsets,
                capture_interval=interval,
                time_known=e.time_known,
            )
        )
    return found
