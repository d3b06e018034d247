"""Shelving, as SCADA alarm practice has it (ISA-18.2, EEMUA 191): an operator takes an alarm
out of the way for a while, with a reason, and it comes back by itself.

An open incident is *shelved* until a time (at most :data:`MOST_SHELVED` ahead) by an operator
with a reason; its life-cycle state does not change (it may still be acknowledged, dispatched,
closed: closing ends the shelving). While shelved it is listed apart and never escalated by the
webhook alerts. It returns when an operator *unshelves* it or when its time is up (a history row
``unshelved`` by :data:`EXPIRY_BY` through :data:`EXPIRY_VIA`: "unshelved (expired)"), on the
store's wall clock. Expiry needs no timer: the store applies it lazily, before every read and
every action, and the alerts' check applies it before it escalates
(:mod:`burstloc.incidents.shelves`); a returned incident still unacknowledged is escalated
again only after the full escalation time from its return.

A *meter* is shelved the same way (its faults are under maintenance): a meter-fault incident the
monitor opens for it meanwhile arrives already shelved, until the meter's shelving ends, and no
webhook alert is sent for it. A shelved meter still takes part in localization: shelving hides
alarms, it does not take a meter out of service. Pure logic, no database.
"""

from __future__ import annotations

import math
import re

from burstloc.exceptions import InputError

__all__ = [
    "EXPIRY_BY",
    "EXPIRY_VIA",
    "MOST_SHELVED",
    "REASON_CHARS",
    "SHELVED",
    "UNSHELVED",
    "action_label",
    "check_shelving",
    "parse_duration",
]

#: The longest a shelving may last, in seconds (24 h).
MOST_SHELVED = 24 * 3600.0
#: The longest reason.
REASON_CHARS = 2000
#: The history rows' actions.
SHELVED, UNSHELVED = "shelved", "unshelved"
#: Who and through what a shelving that ran out is ended (its history row).
EXPIRY_BY, EXPIRY_VIA = "burstloc", "expiry"

_UNITS = {"s": 1.0, "m": 60.0, "min": 60.0, "h": 3600.0, "d": 86_400.0}
_PART = re.compile(r"(\d+(?:\.\d+)?)\s*(min|s|m|h|d)")


def parse_duration(text: str) -> float:
    """``"30m"``, ``"2h"``, ``"1h30m"``, ``"90s"`` → seconds, checked by :func:`check_shelving`'s
    bounds (more than 0, at most :data:`MOST_SHELVED`).

    Raises:
        InputError: not a duration (a number with a unit s, m or min, h, d, possibly several), or
            one out of bounds.
    """
    if not isinstance(text, str):
        raise InputError(f"a shelving time is text such as 30m or 2h, got {text!r}")
    squeezed = text.strip().lower()
    parts = _PART.findall(squeezed)
    if not squeezed or _PART.sub("", squeezed).strip():
        raise InputError(
            f"a shelving time is a number with a unit (s, m, h, d), such as 30m, 2h or 1h30m; "
            f"got {text!r}"
        )
    seconds = sum(float(number) * _UNITS[unit] for number, unit in parts)
    _bounded(seconds, text)
    return seconds


def _bounded(seconds: float, given: object) -> None:
    if not (math.isfinite(seconds) and 0 < seconds <= MOST_SHELVED):
        raise InputError(
            f"a shelving time must be more than 0 and at most {MOST_SHELVED / 3600:g} h, "
            f"got {given!r}"
        )


def check_shelving(seconds: float, reason: str | None) -> str:
    """The reason, stripped, once ``seconds`` and ``reason`` are acceptable.

    Raises:
        InputError: a time out of bounds, no reason or an overlong one.
    """
    _bounded(seconds, f"{seconds:g} s")
    if reason is None or not str(reason).strip():
        raise InputError("shelving needs a reason (it is recorded, with who and until when)")
    if len(reason) > REASON_CHARS:
        raise InputError(f"the reason is longer than {REASON_CHARS} characters")
    return reason.strip()


def action_label(action: str, via: str) -> str:
    """A history row's action as an operator reads it: ``unshelved (expired)`` for a shelving
    that ran out, else ``action``."""
    return f"{UNSHELVED} (expired)" if action == UNSHELVED and via == EXPIRY_VIA else action
