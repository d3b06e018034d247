"""The webhook alerts' delivery, off the monitor's path: one thread per URL
(:class:`WebhookSender`), each delivering its URL's queue in the outbox
(:mod:`burstloc.incidents.alerts.outbox`) **in order, once each**.

A thread's pass, on the alerts' clock ``now``: the URL's escalations due become pending
(:meth:`~burstloc.incidents.alerts.outbox.Outbox.promote`); then its queue's head is POSTed
(``Content-Type: application/json``, ``Idempotency-Key``: the alert's key, a timeout), when its
next attempt is due, and so on down the queue while the receiver answers:

* a **2xx** answer: delivered, marked so in the outbox (committed before the next is sent);
* any other answer, no answer within the timeout, a refused or dropped connection: a failed
  attempt, said on stderr and counted; tried again after 2 s, doubling to 5 minutes
  (:data:`~burstloc.incidents.alerts.config.RETRY`), and nothing after it in the URL's queue
  is sent before it;
* a **4xx** answer other than 408, 425 and 429 (the receiver refuses this alert: sending it
  again would not change that), :data:`~burstloc.incidents.alerts.config.MAX_ATTEMPTS`
  attempts, or an alert :data:`~burstloc.incidents.alerts.config.MAX_AGE` old on the alerts'
  clock once tried: **given up**: a JSON line appended to the dead-letter file (fsync'ed), said
  on stderr, counted, marked ``dead``; the queue moves on.

So a receiver down for an hour gets every alert, in order, when it is back; a monitor
restarted meanwhile finds them in the outbox. The one resend: an alert the receiver took but
whose 2xx did not reach the outbox (the answer lost, or the monitor killed between the answer
and its commit) is sent again with the same ``Idempotency-Key``; a receiver that must never see
one twice drops a key it has seen.

A thread wakes every :data:`POLL` s (wall clock) and at :meth:`WebhookSender.wake`; the alerts'
clock is the monitor's (the wall clock, or a replay's reading time). Undelivered alerts to a URL
no longer configured are given up at the start, said.
"""

from __future__ import annotations

import http.client
import json
import math
import os
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from burstloc.incidents.alerts.config import shown
from burstloc.incidents.alerts.outbox import Outbox
from burstloc.incidents.errors import IncidentStoreError

__all__ = ["POLL", "RETRIED_4XX", "WebhookSender"]

#: Seconds (wall clock) between a thread's passes when nothing wakes it.
POLL = 0.5
#: The 4xx answers worth another attempt (timeout, too early, too many requests).
RETRIED_4XX = (408, 425, 429)
#: Bytes of an answer read (and of an error's body quoted).
_READ = 65_536


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    """A redirect is an answer, not followed (a POST is not re-sent elsewhere)."""

    def redirect_request(self, *args: Any, **kwargs: Any) -> None:
        return None


class WebhookSender:
    """Delivers ``outbox``'s alerts (module docstring); ``say`` tells the operator (stderr).
    :meth:`start` starts the threads, :meth:`close` stops them."""

    def __init__(self, outbox: Outbox, say: Callable[[str], None], *, paced: bool = False) -> None:
        self.outbox = outbox
        #: Whether each pass notes when the next alert is due (:attr:`next_due`: a replay
        #: paced by :mod:`~burstloc.incidents.alerts.pacing`; nothing else reads it).
        self.paced = paced
        self.settings = outbox.settings
        self.say = say
        #: Counters since the start (read by /metrics): 2xx answers, failed attempts, given up.
        self.delivered = self.failed_attempts = self.dead_lettered = 0
        self._count = threading.Lock()
        self._opener = urllib.request.build_opener(_NoRedirect)
        self._stop = threading.Event()
        self._lanes = [_Lane(self, url) for url in self.settings.urls]

    def start(self) -> WebhookSender:
        """Give up the strays (module docstring), then start one thread per URL."""
        for row in self.outbox.strays():
            self._give_up(row, row.attempts, "its URL is no longer configured")
        for lane in self._lanes:
            lane.thread.start()
        return self

    def wake(self) -> None:
        """Make every thread pass now (the clock moved, an alert was written)."""
        for lane in self._lanes:
            lane.wake.set()

    @property
    def next_due(self) -> float:
        """When the next alert is due on the alerts' clock, as the threads' last passes found
        it (``paced`` senders only): ``-inf`` before a URL's first pass with a time, ``inf`` when
        nothing is due."""
        return min(lane.next_due for lane in self._lanes)

    def settle(self, timeout: float = 60.0) -> bool:
        """Wait until every thread has finished a pass begun after this call (tests: after
        moving the clock); ``False`` if one did not within ``timeout`` s."""
        targets = [(lane, lane.begun + 1) for lane in self._lanes]
        self.wake()
        deadline = time.monotonic() + timeout
        for lane, target in targets:
            with lane.passed:
                while lane.done < target and lane.thread.is_alive():
                    left = deadline - time.monotonic()
                    if left <= 0 or not lane.passed.wait(left):
                        return False
        return True

    def close(self, timeout: float = 30.0) -> None:
        """One last pass, then stop the threads (waiting up to ``timeout`` s); say how many
        alerts stay in the outbox for the next start."""
        self._stop.set()
        self.wake()
        for lane in self._lanes:
            lane.thread.join(timeout)
            if lane.thread.is_alive():
                self.say(f"webhook {shown(lane.url)}: still sending after {timeout:g} s; left")
        try:
            left = self.outbox.counts()["pending"]
        except IncidentStoreError as exc:
            self.say(f"webhook alerts: the outbox cannot be read: {exc}")
            return
        if left:
            self.say(
                f"{left} webhook alerts not delivered yet: kept in the outbox "
                f"({self.outbox.store.where}), sent at the next start"
            )

    # ------------------------------------------------------------------ on a thread
    def post(self, url: str, key: str, event: str, body: str) -> tuple[bool, bool, str]:
        """POST one alert: (delivered, worth another attempt, what happened)."""
        request = urllib.request.Request(
            url,
            data=body.encode(),
            method="POST",
            headers={
                "Content-Type": "application/json; charset=utf-8",
                "Idempotency-Key": key,
                "User-Agent": self.outbox.source.replace(" ", "/"),
                "X-Burstloc-Event": f"incident.{event}",
            },
        )
        try:
            with self._opener.open(request, timeout=self.settings.timeout) as answer:
                answer.read(_READ)
                status = int(answer.status)
        except urllib.error.HTTPError as exc:
            status = int(exc.code)
            text = f"HTTP {status} {exc.reason}"
            return False, not (400 <= status < 500) or status in RETRIED_4XX, text
        except (urllib.error.URLError, http.client.HTTPException, OSError) as exc:
            reason = getattr(exc, "reason", None) or exc
            if isinstance(reason, TimeoutError) or "timed out" in str(reason):
                return False, True, f"no answer within {self.settings.timeout:g} s"
            return False, True, f"{type(reason).__name__}: {reason}"
        if 200 <= status < 300:
            return True, False, f"HTTP {status}"
        return False, not (400 <= status < 500), f"HTTP {status} (not followed)"

    def _give_up(self, row: Any, attempts: int, why: str) -> None:
        """``row`` to the dead-letter file, said, counted, marked dead."""
        path = Path(self.settings.dead_letter)
        line = {
            "alert": row.key, "url": row.url, "incident": row.incident_id,
            "event": f"incident.{row.event}",
            "attempts": attempts, "due_at": row.due_at, "reason": why,
            "given_up_at": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "payload": None if row.payload is None else json.loads(row.payload),
        }  # fmt: skip
        with open(path, "a", encoding="utf-8") as out:
            out.write(json.dumps(line) + "\n")
            out.flush()
            os.fsync(out.fileno())
        self.outbox.dead(row.id, attempts, why)
        with self._count:
            self.dead_lettered += 1
        self.say(
            f"webhook {shown(row.url)}: alert {row.key} (incident {row.incident_id}, "
            f"{row.event}) given up after {attempts} attempts: {why}; written to {path}"
        )


class _Lane:
    """One URL's thread."""

    def __init__(self, sender: WebhookSender, url: str) -> None:
        self.sender, self.url = sender, url
        self.wake = threading.Event()
        self.passed = threading.Condition()
        self.begun = self.done = 0
        self.failing = False
        #: The URL's next alert on the alerts' clock after the last pass (see ``next_due``).
        self.next_due = -math.inf
        self.thread = threading.Thread(target=self.run, name="burstloc-webhook", daemon=True)

    def run(self) -> None:
        stop = self.sender._stop
        while True:
            last = stop.is_set()
            with self.passed:
                self.begun += 1
            try:
                self.one_pass()
            except IncidentStoreError as exc:  # the store is down: the next pass tries again
                self.sender.say(f"webhook {shown(self.url)}: the outbox cannot be used: {exc}")
            except OSError as exc:  # the dead-letter file cannot be written
                self.sender.say(f"webhook {shown(self.url)}: {exc}; tried again")
            with self.passed:
                self.done += 1
                self.passed.notify_all()
            if last:
                return
            self.wake.wait(POLL)
            self.wake.clear()

    def one_pass(self) -> None:
        """Promote what is due, then deliver the queue's head while it goes through; then note
        when the next alert is due."""
        now = self.sender.outbox.clock()
        if now is None:
            return  # a replay before its first reading: no time yet
        self.deliver(now)
        if self.sender.paced:
            due = self.sender.outbox.next_due(self.url)
            self.next_due = math.inf if due is None else due

    def deliver(self, now: float) -> None:
        """Promote what is due by ``now``, then deliver the queue's head while it goes
        through."""
        sender, outbox, settings = self.sender, self.sender.outbox, self.sender.settings
        outbox.promote(self.url, now)
        while (row := outbox.head(self.url)) is not None and row.next_at <= now:
            attempts = row.attempts + 1
            ok, again, what = sender.post(self.url, row.key, row.event, row.payload)
            if ok:
                outbox.delivered(row.id, attempts)
                with sender._count:
                    sender.delivered += 1
                if self.failing:
                    self.failing = False
                    sender.say(f"webhook {shown(self.url)}: delivering again ({what})")
                continue
            with sender._count:
                sender.failed_attempts += 1
            self.failing = True
            too_old = now - row.due_at >= settings.max_age
            if not again or attempts >= settings.max_attempts or too_old:
                why = what if not again else f"{what} (the last of {attempts} attempts)"
                sender._give_up(row, attempts, why)
                continue
            wait = settings.backoff(attempts)
            outbox.failed(row.id, attempts, now + wait, what)
            sender.say(
                f"webhook {shown(self.url)}: alert for incident {row.incident_id} "
                f"({row.event}) not delivered: {what}; attempt {attempts}, again in {wait:g} s"
            )
            return
