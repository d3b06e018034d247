"""What the live loop tells an observer (a view of the running monitor, e.g. the web page).

A :class:`LiveObserver` given to :class:`~burstloc.live.loop.LiveLoop` is told, on the
monitor's own thread, every time step fed to the monitor, every alarm that counts toward a
decision, every record the loop emits (decision, transient, event, health) and, at each
periodic check, offered the current health record (:meth:`LiveObserver.tick`, a callable it
calls only when it wants one: building the record costs more than a step). The methods must
return at once: an observer hands the news on (a bounded queue, a latest-state snapshot) and
never makes the monitor wait (the one exception: a replayed file's webhook alerts,
:mod:`burstloc.incidents.alerts.pacing`, hold the replay to the file's clock). The base class
ignores everything.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from burstloc.readings import Step

__all__ = ["LiveObserver", "fan_out"]


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


def fan_out(*observers: LiveObserver | None) -> LiveObserver | None:
    """One observer that tells each of ``observers`` (``None`` ones left out) in turn: the
    single one itself when there is one, ``None`` when there is none. A method an observer
    does not override (the base class's, which ignores the news) is not called."""
    present = [o for o in observers if o is not None]
    if len(present) <= 1:
        return present[0] if present else None
    return _FanOut(present)


class _FanOut(LiveObserver):
    """The observers of :func:`fan_out`: per method, only those that override it."""

    def __init__(self, observers: list[LiveObserver]) -> None:
        def told(name: str) -> list[Callable[..., None]]:
            base = getattr(LiveObserver, name)
            return [
                getattr(o, name)
                for o in observers
                if getattr(type(o), name, base) is not base or name in vars(o)
            ]

        self._step, self._alarm = told("step"), told("alarm")
        self._record, self._message, self._tick = told("record"), told("message"), told("tick")
        if len(self._step) == 1:  # the step of every reading: the cheapest call there is
            self.step = self._step[0]  # type: ignore[method-assign]

    def step(self, step: Step) -> None:
        """Each observer's :meth:`LiveObserver.step`."""
        for call in self._step:
            call(step)

    def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
        """Each observer's :meth:`LiveObserver.alarm`."""
        for call in self._alarm:
            call(meter, time, onset, amplitude)

    def record(self, record: dict[str, Any]) -> None:
        """Each observer's :meth:`LiveObserver.record`."""
        for call in self._record:
            call(record)

    def message(self, text: str) -> None:
        """Each observer's :meth:`LiveObserver.message`."""
        for call in self._message:
            call(text)

    def tick(self, health: Callable[[], dict[str, Any]]) -> None:
        """Each observer's :meth:`LiveObserver.tick`."""
        for call in self._tick:
            call(health)
