"""What the live loop tells an observer (a view of the running monitor, e.g. the web page).

A :class:`LiveObserver` given to :class:`~burstloc.live.loop.LiveLoop` is told, on the
monitor's own thread, every time step fed to the monitor, every alarm that counts toward a
decision, every record the loop emits (decision, transient, event, health) and, at each
periodic check, offered the current health record (:meth:`LiveObserver.tick`, a callable it
calls only when it wants one: building the record costs more than a step). The methods must
return at once: an observer hands the news on (a bounded queue, a latest-state snapshot) and
never makes the monitor wait. The base class ignores everything.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from burstloc.readings import Step

__all__ = ["LiveObserver"]


class LiveObserver:
    """Receives the live loop's news; every method returns at once (module docstring)."""

    def step(self, step: Step) -> None:
        """A complete time step, as fed to the monitor (values in the configuration's meter
        order; ``step.filled`` names the meters whose value was filled)."""

    def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
        """A meter's first alarm toward a decision: raised at reading time ``time``, its
        change starting at ``onset`` (s), of ``amplitude`` (m)."""

    def record(self, record: dict[str, Any]) -> None:
        """A record the loop emits (``"type"``: decision, transient, event or health)."""

    def message(self, text: str) -> None:
        """A message the monitor reports (a meter gone silent, a clock offset, bad input)."""

    def tick(self, health: Callable[[], dict[str, Any]]) -> None:
        """The periodic check: ``health()`` builds the current health record, if wanted."""
