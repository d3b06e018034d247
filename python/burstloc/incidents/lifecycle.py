"""An incident's life cycle (after ISA-18.2's alarm states): the states, the operator's
actions that move an incident between them, and the outcome a closed incident records.

::

    detected --acknowledge--> acknowledged --dispatch--> dispatched --close--> closed
                                   \\--------------------close---------------------^

An incident is *detected* when the monitor reports it (a located burst, the early record of an
alarm still being answered, an event, a meter fault). An operator *acknowledges* it (it has been
seen), may *dispatch* a crew, and *closes* it with an outcome: the burst was found at a point
(network coordinates) or it was a false alarm. Closing needs an acknowledgement first (an alarm
is never closed unseen); a note may be added in any state. The monitor's own updates (the
answer after the early record, a meter fault that clears) change no state: they are history
rows. Pure logic, no database: :mod:`burstloc.incidents.store` applies it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from burstloc.exceptions import InputError
from burstloc.incidents.errors import IncidentStateError

__all__ = [
    "ACTIONS",
    "CLOSED",
    "OPEN_STATES",
    "STATES",
    "Outcome",
    "next_state",
    "parse_point",
]

DETECTED, ACKNOWLEDGED, DISPATCHED, CLOSED = "detected", "acknowledged", "dispatched", "closed"
#: Every state, in life-cycle order.
STATES = (DETECTED, ACKNOWLEDGED, DISPATCHED, CLOSED)
#: The states of an incident still open.
OPEN_STATES = (DETECTED, ACKNOWLEDGED, DISPATCHED)

#: The operator's actions: the states each is allowed from, and the state it leads to (``None``:
#: the state does not change).
ACTIONS: dict[str, tuple[tuple[str, ...], str | None]] = {
    "acknowledge": ((DETECTED,), ACKNOWLEDGED),
    "dispatch": ((ACKNOWLEDGED,), DISPATCHED),
    "close": ((ACKNOWLEDGED, DISPATCHED), CLOSED),
    "note": (STATES, None),
}

#: The history row each action appends (its ``action`` column).
DONE = {"acknowledge": "acknowledged", "dispatch": "dispatched", "close": "closed", "note": "note"}

#: The outcomes of a closed incident.
FOUND, FALSE_ALARM = "found", "false-alarm"


def next_state(incident: int, state: str, action: str) -> str:
    """The state after ``action`` on incident ``incident`` in ``state``.

    Raises:
        IncidentStateError: ``action`` is not allowed from ``state``.
        InputError: an unknown action.
    """
    if action not in ACTIONS:
        raise InputError(f"unknown action {action!r}: one of {', '.join(ACTIONS)}")
    allowed, after = ACTIONS[action]
    if state not in allowed:
        raise IncidentStateError(incident, state, action, allowed)
    return state if after is None else after


@dataclass(frozen=True)
class Outcome:
    """How a closed incident ended: ``found`` at ``(x, y)`` (the network's coordinates, as its
    INP file gives them) or a ``false-alarm``.

    Raises:
        InputError: another kind, a found outcome without a finite point, a false alarm with one.
    """

    kind: str
    x: float | None = None
    y: float | None = None

    def __post_init__(self) -> None:
        if self.kind == FOUND:
            if (
                self.x is None
                or self.y is None
                or not (math.isfinite(self.x) and math.isfinite(self.y))
            ):
                raise InputError(
                    f"a found outcome needs a finite point x,y, got {self.x}, {self.y}"
                )
        elif self.kind == FALSE_ALARM:
            if self.x is not None or self.y is not None:
                raise InputError("a false alarm has no point where it was found")
        else:
            raise InputError(f"outcome must be {FOUND!r} or {FALSE_ALARM!r}, got {self.kind!r}")

    @classmethod
    def found(cls, x: float, y: float) -> Outcome:
        """Found at ``(x, y)``."""
        return cls(FOUND, float(x), float(y))

    @classmethod
    def false_alarm(cls) -> Outcome:
        """A false alarm."""
        return cls(FALSE_ALARM)

    def to_json(self) -> dict[str, object]:
        """``{"outcome": kind}``, with ``"found_at": [x, y]`` when found."""
        doc: dict[str, object] = {"outcome": self.kind}
        if self.kind == FOUND:
            doc["found_at"] = [self.x, self.y]
        return doc


def parse_point(text: str) -> tuple[float, float]:
    """``"X,Y"`` → ``(x, y)``.

    Raises:
        InputError: not two finite numbers separated by a comma.
    """
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        x, y = float(parts[0]), float(parts[1])
    except ValueError:
        raise InputError(f"a point is X,Y (two numbers), got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise InputError(f"a point needs finite coordinates, got {text!r}")
    return x, y
