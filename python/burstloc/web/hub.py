"""The hand-off from the monitor to the web page: a bounded inbox the monitor only appends to.

:class:`Hub` is the :class:`~burstloc.live.observe.LiveObserver` that ``burstloc monitor --web``
gives the live loop. On the monitor's thread each call appends one item to a bounded ``deque``
(an atomic operation: no lock, no wait; when the page side falls behind, the oldest items are
dropped, never the monitor slowed) and, for the rare items that must show at once (a decision,
transient or event record, a message), wakes the page side through a callback that only
schedules work on its event loop. Alarms and readings wait for the page side's next poll
(:data:`burstloc.web.server.POLL`): waking it at an alarm would put its work (it shares the
monitor's interpreter) in the middle of the decision the alarm starts. Health records are built
at most every ``health_every`` seconds of wall-clock time. The page side
(:class:`burstloc.web.view.View`) drains the inbox.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from typing import Any

from burstloc.live.observe import LiveObserver
from burstloc.readings import Step

__all__ = ["INBOX", "Hub"]

#: Items the inbox holds before the oldest are dropped.
INBOX = 50_000


class Hub(LiveObserver):
    """The monitor's side of the web view (module docstring)."""

    def __init__(self, *, health_every: float = 0.5, inbox: int = INBOX) -> None:
        #: Steps as they are (the item per step is the step itself: no allocation), the rest as
        #: (kind, payload).
        self.inbox: deque[Step | tuple[str, Any]] = deque(maxlen=inbox)
        self.step = self.inbox.append  # type: ignore[method-assign, assignment]
        self.health_every = health_every
        #: Called (on the monitor's thread) after an item that must show at once; it must only
        #: schedule work elsewhere (``loop.call_soon_threadsafe``).
        self.wake: Callable[[], None] | None = None
        self._next_health = 0.0

    def _urgent(self, item: tuple[str, Any]) -> None:
        self.inbox.append(item)
        wake = self.wake
        if wake is not None:
            try:
                wake()
            except RuntimeError:  # the page side's loop has closed: nobody to tell
                self.wake = None

    def step(self, step: Step) -> None:
        """Keep the step for the meters' recent readings (replaced, per hub, by the inbox's
        own ``append``: the cheapest call the monitor can make)."""
        self.inbox.append(step)

    def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
        """An alarm, shown at the next poll."""
        self.inbox.append(("alarm", (meter, time, onset, amplitude)))

    def record(self, record: dict[str, Any]) -> None:
        """A decision, transient or event record, shown at once (a health record at the next
        poll)."""
        if record.get("type") == "health":
            self.inbox.append(("record", record))
        else:
            self._urgent(("record", record))

    def message(self, text: str) -> None:
        """A message for the log, shown at once."""
        self._urgent(("message", text))

    def tick(self, health: Callable[[], dict[str, Any]]) -> None:
        """Take the current health record every ``health_every`` seconds (wall clock)."""
        now = time.monotonic()
        if now >= self._next_health:
            self._next_health = now + self.health_every
            self.inbox.append(("health", health()))

    def drain(self, limit: int = 100_000) -> list[Step | tuple[str, Any]]:
        """Take up to ``limit`` items, oldest first (the page side's only read)."""
        items = []
        pop = self.inbox.popleft
        try:
            for _ in range(limit):
                items.append(pop())
        except IndexError:
            pass
        return items
