"""Readings from text: CSV lines and MQTT JSON payloads. Never raises on bad input.

Two forms, one result type. Each source item (a CSV line, an MQTT message) gives zero or more
:class:`~burstloc.readings.Reading` and zero or more :class:`BadReading` (what was wrong and
where: the line number or the message id); the live loop counts, reports and skips the bad ones
and goes on.

* **CSV line**: ``timestamp,meter,value`` (the time, the junction's name, metres of pressure
  head). The time is seconds (from any origin, e.g. the Unix epoch) or an ISO 8601 date and time
  with a UTC offset or ``Z`` (read as epoch seconds: :func:`burstloc.readings.timestamp_seconds`).
  A first line ``timestamp,meter,value`` is a header; blank lines and lines starting with ``#``
  are skipped; a UTF-8 byte-order mark and quotes around a field are removed.
* **JSON payload** (MQTT): one reading ``{"t": 12.4, "meter": "N2", "value": 181.2}``, or a
  batch: a list of such objects, or ``{"readings": [...]}``. A payload that is not JSON is read
  as CSV lines (the CSV line form over MQTT). ``t`` may also be an ISO 8601 string, as above.

Values must be finite numbers; meter names non-empty strings (a number is taken as its text).

**One timestamp form per feed.** A feed's first reading fixes its form, seconds or ISO 8601
(:class:`TimestampForm`); a reading whose timestamp is in the other form is a bad reading (a
line of ISO time in a feed of seconds is not a time on the feed's clock, and one in seconds
between ISO times may be seconds from any origin). :func:`parse_lines` keeps one form for its
lines; the live loop one for its whole feed, file or broker
(:attr:`burstloc.live.loop.LiveLoop.timestamps`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from burstloc.exceptions import ConfigError
from burstloc.readings import CSV_HEADER, Reading, timestamp_seconds

__all__ = [
    "ISO_8601",
    "SECONDS",
    "BadReading",
    "TimestampForm",
    "located_lines",
    "parse_csv_line",
    "parse_line",
    "parse_lines",
    "parse_payload",
    "parse_row",
    "unknown_meter",
]


@dataclass(frozen=True, slots=True)
class BadReading:
    """An input item that is not a reading: ``where`` (``"line 12"``, ``"message 7"``) and
    ``reason``; ``meter`` when known (bad readings are counted per meter)."""

    where: str
    reason: str
    meter: str | None = None

    def __str__(self) -> str:
        """``where: reason``."""
        return f"{self.where}: {self.reason}"


#: The two forms of a reading's timestamp (:func:`burstloc.readings.timestamp_seconds`).
SECONDS = "seconds"
ISO_8601 = "ISO 8601"


class TimestampForm:
    """The form of a feed's timestamps, :data:`SECONDS` or :data:`ISO_8601`: fixed by the feed's
    first reading (``form``, and ``since``: where that reading was), or given.

    >>> form = TimestampForm()
    >>> form.check(SECONDS, "line 2", "N2", "1.0,N2,180") is None
    True
    >>> form.check(ISO_8601, "line 3", "N2", "2026-11-26T10:00:00Z,N2,180").reason
    "timestamp in ISO 8601 in a feed of seconds (since line 2): '2026-11-26T10:00:00Z,N2,180'"

    Raises:
        ConfigError: ``form`` is neither form.
    """

    def __init__(self, form: str | None = None, since: str = "the start") -> None:
        if form not in (None, SECONDS, ISO_8601):
            raise ConfigError(f"timestamp form must be {SECONDS!r} or {ISO_8601!r}, got {form!r}")
        self.form: str | None = form
        self.since = since

    def check(self, form: str, where: str, meter: str | None, shown: str) -> BadReading | None:
        """``None`` if a reading at ``where`` with a timestamp in ``form`` fits the feed (the
        first reading fixes the form), else the bad reading (``shown``: the item as text)."""
        if self.form == form:
            return None
        if self.form is None:
            self.form, self.since = form, where
            return None
        reason = f"timestamp in {form} in a feed of {self.form} (since {self.since})"
        return BadReading(where, f"{reason}: {shown!r}", meter)


def _form(text: Any) -> str:
    """The form of a timestamp that :func:`timestamp_seconds` read."""
    return SECONDS if isinstance(text, (int, float)) or _number(text) is not None else ISO_8601


def _number(text: Any) -> float | None:
    try:
        x = float(text)
    except (TypeError, ValueError, OverflowError):
        return None
    return x if math.isfinite(x) else None


def parse_csv_line(
    text: str, where: str, form: TimestampForm | None = None
) -> Reading | BadReading | None:
    """One CSV line: a reading, a bad reading, or ``None`` (blank, comment or header); with
    ``form``, a reading whose timestamp is not in the feed's form is a bad reading."""
    text = text.lstrip("\ufeff").strip()
    if not text or text.startswith("#"):
        return None
    fields = [f.strip().strip('"').strip("'").strip() for f in text.split(",")]
    if tuple(f.lower() for f in fields) == CSV_HEADER:
        return None
    shown = text if len(text) <= 80 else text[:77] + "..."
    if len(fields) != 3:
        return BadReading(where, f"want 'timestamp,meter,value', got {shown!r}")
    meter = fields[1] or None
    if meter is None:
        return BadReading(where, f"no meter name: {shown!r}")
    try:
        t = timestamp_seconds(fields[0])
    except ValueError as exc:
        return BadReading(where, f"{exc}: {shown!r}", meter)
    value = _number(fields[2])
    if value is None:
        return BadReading(where, f"value is not a finite number: {shown!r}", meter)
    if form is not None:
        wrong = form.check(_form(fields[0]), where, meter, shown)
        if wrong is not None:
            return wrong
    return Reading(t, meter, value)


def parse_lines(lines: Iterable[str | bytes]) -> Iterator[Reading | BadReading]:
    """Readings (and bad readings) from CSV lines, numbered from 1; undecodable bytes are bad
    readings too, and so are timestamps in another form than the first reading's."""
    for _, item in located_lines(lines):
        yield item


def located_lines(lines: Iterable[str | bytes]) -> Iterator[tuple[str, Reading | BadReading]]:
    """:func:`parse_lines` with where each item comes from (``"line 12"``)."""
    form = TimestampForm()
    for number, line in enumerate(lines, start=1):
        where = f"line {number}"
        item = parse_line(line, where, form)
        if item is not None:
            yield where, item


def parse_line(
    line: str | bytes, where: str, form: TimestampForm | None = None
) -> Reading | BadReading | None:
    """One CSV line, text or bytes (``None``: a blank line, a comment or a header); bytes that
    are not UTF-8, or a NUL byte, make a bad reading; so does, with ``form``, a timestamp not in
    the feed's form."""
    if isinstance(line, bytes):
        try:
            line = line.decode("utf-8")
        except UnicodeDecodeError:
            return BadReading(where, "not UTF-8 text")
    if "\x00" in line:
        return BadReading(where, "binary data (NUL byte)")
    return parse_csv_line(line, where, form)


_NUMBER = (int, float)


def _plain(obj: Any) -> tuple[float, str, float] | None:
    """The common case, fast: ``{"t": float, "meter": str, "value": float}`` with finite
    numbers, as (t, meter, value); anything else is None (then :func:`_checked` says why)."""
    if type(obj) is dict:
        meter: Any = obj.get("meter")
        raw_t: Any = obj.get("t")
        raw_v: Any = obj.get("value")
        if type(meter) is str and meter and type(raw_t) in _NUMBER and type(raw_v) in _NUMBER:
            try:
                t, value = float(raw_t), float(raw_v)
            except OverflowError:  # an integer beyond the float range
                return None
            if math.isfinite(t) and math.isfinite(value):
                return t, meter, value
    return None


def _from_object(obj: Any, where: str, form: TimestampForm | None) -> Reading | BadReading:
    plain = _plain(obj)
    if plain is None:
        return _checked(obj, where, form)
    if form is not None and form.form != SECONDS:
        wrong = form.check(SECONDS, where, plain[1], _short(obj))
        if wrong is not None:
            return wrong
    return Reading(*plain)


def _short(x: Any) -> str:
    text = repr(x)
    return text if len(text) <= 40 else text[:37] + "..."


def _checked(obj: Any, where: str, form: TimestampForm | None = None) -> Reading | BadReading:
    if not isinstance(obj, dict):
        return BadReading(where, f"a reading must be a JSON object, got {type(obj).__name__}")
    meter = obj.get("meter")
    if isinstance(meter, (int, float)) and not isinstance(meter, bool):
        meter = str(meter)
    if not isinstance(meter, str) or not meter:
        return BadReading(where, f"'meter' must be a non-empty string, got {_short(meter)}")
    raw_t, raw_v = obj.get("t", obj.get("timestamp")), obj.get("value")
    ok = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in (raw_t, raw_v))
    if isinstance(raw_t, str) and isinstance(raw_v, (int, float)) and not isinstance(raw_v, bool):
        try:
            t: float | None = timestamp_seconds(raw_t)
            ok = True
        except ValueError:
            t = None
    else:
        t = _number(raw_t) if ok else None
    value = _number(raw_v) if ok else None
    if t is None:
        reason = f"'t' must be seconds or an ISO 8601 time with an offset, got {_short(raw_t)}"
        return BadReading(where, reason, meter)
    if value is None:
        return BadReading(where, f"'value' must be a finite number, got {_short(raw_v)}", meter)
    if form is not None:
        wrong = form.check(_form(raw_t), where, meter, _short(obj))
        if wrong is not None:
            return wrong
    return Reading(t, meter, value)


def parse_payload(
    payload: bytes, where: str, form: TimestampForm | None = None
) -> list[Reading | BadReading]:
    """The readings of one MQTT message (module docstring); never raises. With ``form``, a
    reading whose timestamp is not in the feed's form is a bad reading."""
    try:
        text = payload.decode("utf-8")
    except UnicodeDecodeError:
        return [BadReading(where, "payload is not UTF-8 text")]
    stripped = text.lstrip("\ufeff").strip()
    if stripped[:1] in ("{", "["):
        try:
            doc = json.loads(stripped)
        except (ValueError, RecursionError):
            return [BadReading(where, "payload is not valid JSON")]
        items = doc.get("readings", doc) if isinstance(doc, dict) else doc
        if isinstance(items, dict):
            return [_from_object(items, where, form)]
        if not isinstance(items, list):
            return [BadReading(where, "'readings' must be a list")]
        return [_from_object(o, f"{where} item {i}", form) for i, o in enumerate(items)]
    out: list[Reading | BadReading] = []
    for i, line in enumerate(stripped.splitlines()):
        item = parse_csv_line(line, where if i == 0 else f"{where} line {i + 1}", form)
        if item is not None:
            out.append(item)
    if not out:
        out.append(BadReading(where, "empty payload"))
    return out


def unknown_meter(where: str, meter: str) -> BadReading:
    """The bad reading of a meter the configuration does not have."""
    return BadReading(where, f"unknown meter {meter!r}")


class Row(NamedTuple):
    """The readings of one payload as parallel lists: their ``positions`` among the payload's
    items, ``times``, meter ``columns`` and ``values``; the ``bad`` items as (position, bad
    reading); ``size``, the number of items (readings and bad ones); ``lines``, each item's line
    number when the row is a file's lines (:mod:`burstloc.live.lines`: reports name the line),
    else ``None`` (reports name the payload)."""

    positions: list[int]
    times: list[float]
    columns: list[int]
    values: list[float]
    bad: list[tuple[int, BadReading]]
    size: int
    lines: list[int] | None = None


def parse_row(
    payload: bytes, where: str, columns: Mapping[str, int], form: TimestampForm | None = None
) -> Row:
    """:func:`parse_payload` as one :class:`Row` over the meters ``columns`` (name → column):
    the same items in the same order, without an object per reading. A reading from a meter
    not in ``columns`` is a bad item (:func:`unknown_meter`). Never raises."""
    try:
        text = payload.decode("utf-8")
        items = json.loads(text) if text[:1] == "[" else None
    except (UnicodeDecodeError, ValueError, RecursionError):
        items = None
    row = Row([], [], [], [], [], 0)
    if not isinstance(items, list):  # not the common form: a JSON list of readings
        parsed = parse_payload(payload, where, form)
        for i, item in enumerate(parsed):
            if isinstance(item, BadReading):
                row.bad.append((i, item))
            else:
                _add(row, i, (item.timestamp, item.meter, item.value), where, columns)
        return row._replace(size=len(parsed))
    positions, times, cols, values = row.positions, row.times, row.columns, row.values
    seconds = form is None or form.form == SECONDS  # the inline case's timestamps are seconds
    unfixed = form is not None and form.form is None  # the feed's first reading is still to come
    for i, obj in enumerate(items):
        if type(obj) is dict:  # the commonest case inline: float t and value, a known meter
            t: Any = obj.get("t")
            value: Any = obj.get("value")
            meter: Any = obj.get("meter")
            j = columns.get(meter) if type(meter) is str else None
            # t - t == 0.0: finite (NaN and infinities give NaN)
            finite = type(t) is float and type(value) is float and t - t == value - value == 0.0
            if j is not None and finite and (seconds or unfixed):
                if unfixed and form is not None:  # the form is fixed by now, or by this one
                    unfixed = False
                    seconds = form.check(SECONDS, f"{where} item {i}", meter, "") is None
                if seconds:
                    positions.append(i)
                    times.append(t)
                    cols.append(j)
                    values.append(value)
                    continue
        item = _from_object(obj, f"{where} item {i}", form)
        if isinstance(item, BadReading):
            row.bad.append((i, item))
            continue
        _add(row, i, (item.timestamp, item.meter, item.value), where, columns)
    return row._replace(size=len(items))


def _add(
    row: Row, i: int, plain: tuple[float, str, float], where: str, columns: Mapping[str, int]
) -> None:
    j = columns.get(plain[1])
    if j is None:
        row.bad.append((i, unknown_meter(where, plain[1])))
        return
    row.positions.append(i)
    row.times.append(plain[0])
    row.columns.append(j)
    row.values.append(plain[2])
