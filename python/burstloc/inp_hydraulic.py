"""An INP file's text as WNTR must read it for a hydraulic model: times as EPANET reads them,
water quality left out.

EPANET accepts a time in [TIMES], [CONTROLS] and [RULES] as decimal hours, ``H:MM`` or
``H:MM:SS``, followed by a unit (``SEC``, ``MIN``, ``HOURS``, ``DAYS``, any word starting with
those letters) or, for a clock time, ``AM``/``PM`` (EPANET 2.2's ``hour()`` in ``input3.c``).
WNTR 1.3.2 reads fewer forms: a rule's ``SYSTEM CLOCKTIME >= 6 AM`` stops it ("could not convert
string to float: '6 AM'", MICROPOLIS), it takes ``Duration 30 MIN`` as 30 hours, and reads
``12:00 AM`` in a rule as noon. A hydraulic model also has no use for the water-quality
options and sections, which WNTR rejects when it does not know their units (BWSN_Network_1's
``Quality Chemical TIME``).

:func:`hydraulic_text` returns the text with each such time written as ``H:MM:SS`` (24-hour, or
12-hour with ``AM``/``PM`` where WNTR needs it) and the water-quality lines (``Quality``,
``Diffusivity``, ``Tolerance``, ``Segments`` in [OPTIONS]; a report ``Statistic`` WNTR does
not know and a ``Report Start`` after time 0 (reporting only: the transient starts at time
0); every line of [QUALITY], [REACTIONS], [SOURCES]
and [MIXING]) turned into comments. Every line keeps its number, so an error WNTR reports names
the line of the original file. :func:`burstloc.network.load_network` reads the file through it.
"""

from __future__ import annotations

import math
import re
from functools import partial
from pathlib import Path

from burstloc.exceptions import NetworkError
from burstloc.inp import _section_rows

__all__ = ["clock_seconds", "hydraulic_text", "time_seconds"]

#: Sections that only water quality reads.
_QUALITY_SECTIONS = frozenset({"[QUALITY]", "[REACTIONS]", "[SOURCES]", "[MIXING]"})
#: [OPTIONS] keywords that only water quality reads (``Tolerance`` is the quality tolerance;
#: the hydraulic ones are ``Accuracy``, ``HeadError`` and ``FlowChange``).
_QUALITY_OPTIONS = frozenset({"QUALITY", "DIFFUSIVITY", "TOLERANCE", "SEGMENTS"})
#: The report statistics WNTR reads (EPANET also takes a word's first letters, ``Average``).
_STATISTICS = frozenset({"AVERAGED", "MINIMUM", "MAXIMUM", "RANGE", "NONE"})
#: Seconds per unit, by the letters EPANET matches at the start of the unit word.
_UNITS = (("SEC", 1.0), ("MIN", 60.0), ("HOU", 3600.0), ("DAY", 86400.0))
_NUMBER = r"\d+(?:\.\d*)?|\.\d+"
_TIME = rf"(?:{_NUMBER})(?::\d+(?:\.\d*)?){{0,2}}"
#: A time with an optional unit or AM/PM in a rule clause or a control.
_RULE_TIME = re.compile(
    rf"(\bSYSTEM\s+(CLOCKTIME|TIME)\s+\S+\s+)({_TIME})(?:\s+([A-Za-z]+))?", re.IGNORECASE
)
_CONTROL_TIME = re.compile(rf"(\bAT\s+(CLOCKTIME|TIME)\s+)({_TIME})(?:\s+([A-Za-z]+))?", re.I)


def _hours(value: str) -> float:
    """Decimal hours of ``value`` (decimal hours, ``H:MM`` or ``H:MM:SS``)."""
    parts = [float(p) for p in value.split(":")]
    if len(parts) > 3 or any(not math.isfinite(p) or p < 0 for p in parts):
        raise ValueError(value)
    return sum(p / 60.0**i for i, p in enumerate(parts))


def time_seconds(value: str, unit: str | None = None) -> float:
    """Seconds of an EPANET time: ``value`` in decimal hours, ``H:MM`` or ``H:MM:SS``, scaled
    by ``unit`` (``SEC``, ``MIN``, ``HOURS``, ``DAYS``: only a decimal value takes one; EPANET
    matches the unit's first three letters); ``AM``/``PM`` make it a clock time
    (:func:`clock_seconds`).

    Raises:
        ValueError: not a time EPANET accepts.
    """
    if unit is not None and unit.upper() in ("AM", "PM"):
        return clock_seconds(value, unit)
    hours = _hours(value)
    if unit is None:
        return hours * 3600.0
    word = unit.upper()
    for prefix, seconds in _UNITS:
        if word.startswith(prefix):
            if ":" in value:
                raise ValueError(f"{value} {unit}")
            return hours * seconds
    raise ValueError(f"{value} {unit}")


def clock_seconds(value: str, am_pm: str | None) -> float:
    """Seconds after midnight of a clock time, as EPANET reads it: ``value`` as for
    :func:`time_seconds`; with ``AM`` 12 is midnight, with ``PM`` 12 is noon and 1-11 are
    afternoon hours; 13 or later with ``AM``/``PM`` is an error; without either, 24-hour.

    Raises:
        ValueError: not a clock time EPANET accepts.
    """
    hours = _hours(value)
    if am_pm is not None:
        word = am_pm.upper()
        if word not in ("AM", "PM") or hours >= 13.0:
            raise ValueError(f"{value} {am_pm}")
        if word == "AM" and hours >= 12.0:
            hours -= 12.0
        elif word == "PM" and hours < 12.0:
            hours += 12.0
    return hours * 3600.0


def _hours_or_none(value: str) -> float | None:
    """Decimal hours of a plain time value, None when it is not one."""
    try:
        return _hours(value)
    except ValueError:
        return None


def _hms(seconds: float) -> str:
    whole = round(seconds)
    return f"{whole // 3600}:{whole % 3600 // 60:02d}:{whole % 60:02d}"


def _clock(seconds: float) -> str:
    """12-hour ``H:MM:SS AM|PM`` (how WNTR reads a start clock time and a control's)."""
    whole = round(seconds) % 86400
    half = "PM" if whole >= 43200 else "AM"
    twelve = whole % 43200
    return f"{_hms(twelve if twelve >= 3600 else twelve + 43200)} {half}"


def _times_line(fields: list[str]) -> str | None:
    """A [TIMES] line rewritten with its time in ``H:MM:SS`` where WNTR would misread it (a
    unit, a decimal or 24-hour clock time), else None: the line is kept."""
    key = fields[0].upper()
    if key == "REPORT" and len(fields) > 2 and fields[1].upper() == "START":
        # reporting only; a later start leaves no result at time 0, where the transient begins
        return None if _hours_or_none(fields[2]) == 0 else ";" + " ".join(fields)
    if key == "STATISTIC":  # reporting only; a form WNTR does not know is left out
        return (
            None if len(fields) < 2 or fields[1].upper() in _STATISTICS else ";" + " ".join(fields)
        )
    clock = len(fields) > 1 and fields[1].upper() == "CLOCKTIME"
    at = 1 if key == "DURATION" else 2
    if len(fields) <= at:
        return None
    value, unit = fields[at], (fields[at + 1] if len(fields) > at + 1 else None)
    if clock:
        plain = ":" in value and "." not in value and unit is not None
        return None if plain else " ".join([*fields[:at], _clock(clock_seconds(value, unit))])
    if unit is None:
        return None
    return " ".join([*fields[:at], _hms(time_seconds(value, unit))])


def _sub_time(match: re.Match[str], *, twelve_hour: bool) -> str:
    """A rule's or control's time followed by a unit or AM/PM, written as WNTR reads it."""
    head, kind, value, word = match.group(1), match.group(2).upper(), match.group(3), match.group(4)
    if word is None or not (
        word.upper() in ("AM", "PM") or word.upper().startswith(tuple(u for u, _ in _UNITS))
    ):
        return match.group(0)
    if kind == "CLOCKTIME":
        seconds = clock_seconds(value, word)
        return f"{head}{_clock(seconds) if twelve_hour else _hms(seconds)}"
    return f"{head}{_hms(time_seconds(value, word))}"


def _undefined_pattern(fields: list[str], patterns: set[str]) -> bool:
    """An [OPTIONS] ``Pattern`` line naming no pattern of the file, with no pattern ``1``
    (EPANET's own default) to fall back on either: EPANET keeps demands constant; WNTR stops.

    Raises:
        ValueError: the pattern is undefined but a pattern ``1`` exists (which default EPANET
            would use is then ambiguous between its versions).
    """
    if fields[0].upper() != "PATTERN" or len(fields) < 2 or fields[1].upper() in patterns:
        return False
    if "1" in patterns:
        raise ValueError(f"the default pattern {fields[1]!r} is not defined")
    return True


def hydraulic_text(path: str | Path, text: str) -> str | None:
    """``text`` (the INP file ``path``) with its times in the forms WNTR reads as EPANET does
    and its water-quality lines made comments, every line keeping its number; ``None`` when
    nothing needs changing.

    Raises:
        NetworkError: a time EPANET would not accept either, naming the file and line.
    """
    lines = text.splitlines()
    original = list(lines)
    rows = list(_section_rows(lines, path))
    patterns = {row.fields[0].upper() for row in rows if row.section == "[PATTERNS]"}
    for row in rows:
        section, number, fields = row.section, row.line, row.fields
        raw, data = lines[number - 1], " ".join(fields)
        try:
            if section in _QUALITY_SECTIONS or (
                section == "[OPTIONS]" and fields[0].upper() in _QUALITY_OPTIONS
            ):
                lines[number - 1] = f";{raw}"
            elif section == "[OPTIONS]" and _undefined_pattern(fields, patterns):
                lines[number - 1] = f";{raw}"  # EPANET: no default pattern, constant demands
            elif section == "[TIMES]":
                new = _times_line(fields)
                lines[number - 1] = raw if new is None else new
            elif section in ("[RULES]", "[CONTROLS]"):
                rules = section == "[RULES]"
                new = (_RULE_TIME if rules else _CONTROL_TIME).sub(
                    partial(_sub_time, twelve_hour=not rules), data
                )
                lines[number - 1] = raw if new == data else new
        except ValueError as exc:
            raise NetworkError(f"{path}:{number}: not a value EPANET accepts: {exc}") from None
    if lines == original:
        return None
    return "\n".join(lines) + "\n"
