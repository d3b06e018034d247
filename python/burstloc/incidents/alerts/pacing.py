"""A replayed file's alerts on the file's clock, whatever the machine's speed.

A replay (``burstloc monitor --readings FILE --webhook URL``) runs the readings as fast as they
are read, and its alerts' clock is the readings' time. The sender's threads pass every
:data:`~burstloc.incidents.alerts.sender.POLL` s of wall-clock time, so without pacing what a
receiver gets from a replay would depend on how fast the machine read the file: a retry due 2 s
of reading time later, or an escalation due a minute later, could be passed by the whole file
between two passes. :class:`ReplayPacing`, the last of the loop's observers, makes the replay
wait where the live monitor would have: once an incident record is queued, until the store has
it and a pass has alerted it; and whenever the readings' clock reaches the next alert due
(:attr:`~burstloc.incidents.alerts.sender.WebhookSender.next_due`), until a pass has sent it.
Between those moments a step costs one comparison. This is the one observer that makes the
loop wait (:mod:`burstloc.live.observe`), and only a replayed file's: a live feed's alerts run
on the wall clock and never hold the monitor.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from burstloc.incidents.alerts.sender import WebhookSender
from burstloc.incidents.recorder import Recorder
from burstloc.live.observe import LiveObserver
from burstloc.readings import Step

__all__ = ["ReplayPacing"]


class ReplayPacing(LiveObserver):
    """Holds a replay's loop until ``recorder`` has stored what it was given and ``sender``
    has passed over what is due on ``clock`` (module docstring); ``say`` reports a store or
    receiver that made it wait in vain."""

    def __init__(
        self,
        recorder: Recorder,
        sender: WebhookSender,
        clock: Callable[[], float | None],
        say: Callable[[str], None],
    ) -> None:
        self.recorder, self.sender, self.clock, self.say = recorder, sender, clock, say
        self._seen = 0  # the recorder's items already waited for
        self._said = False

    def step(self, step: Step) -> None:
        """A step whose time reaches the next alert due, or after new incident records: wait."""
        if self.recorder.queued != self._seen:
            self._catch_up()
            return
        now = self.clock()
        if now is not None and now >= self.sender.next_due:
            self._catch_up()

    def record(self, record: dict[str, Any]) -> None:
        """A record that opened an incident is alerted at its own time, not a step later."""
        if self.recorder.queued != self._seen:
            self._catch_up()

    def _catch_up(self) -> None:
        self._seen = self.recorder.queued
        stored = self.recorder.flush()
        passed = self.sender.settle()
        if not (stored and passed) and not self._said:
            self._said = True
            what = "the incident store" if not stored else "a webhook receiver"
            self.say(f"the replay went on without waiting for {what} (slow to answer)")
