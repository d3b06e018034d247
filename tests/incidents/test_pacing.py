"""burstloc.incidents.alerts.pacing: a replayed file's alerts follow the file's clock, not the
machine's speed. The sender's threads are made to pass only when woken (their wall-clock poll
set to a day), as on a machine too busy to run them while the file is read: every alert still
reaches a real receiver when the readings' clock reaches it, on SQLite and PostgreSQL."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from receiver import receiver

from burstloc.incidents import IncidentStore
from burstloc.incidents.alerts import WebhookSettings, sender
from burstloc.incidents.alerts.outbox import Outbox
from burstloc.incidents.alerts.pacing import ReplayPacing
from burstloc.incidents.alerts.sender import WebhookSender
from burstloc.incidents.recorder import Recorder
from burstloc.readings import Step

STEP = 0.2  # s of reading time per step
BURST = 10.0  # the decision's reading time


def _decision() -> dict[str, object]:
    return {
        "type": "decision", "burst": True, "first_alarm": BURST, "time": BURST,
        "pipes": [{"pipe": "P", "score": 0.0}],
        "position": {"pipe": "P", "from": "N", "metres": 5.0},
        "region": {"length_m": 80.0, "confidence": 0.95, "stretches": [{"pipe": "P"}]},
    }  # fmt: skip


def test_a_replay_delivers_retries_and_escalations_when_its_clock_reaches_them(
    target: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(sender, "POLL", 86_400.0)  # no pass unless woken
    clock = {"now": None}  # the readings' time; None before the first reading
    faults: list[int | str] = [503, "close"]
    said: list[str] = []
    at: list[float] = []  # the readings' clock at each accepted alert

    def fault() -> int | str | None:
        if faults:
            return faults.pop(0)
        at.append(clock["now"])
        return None

    store = IncidentStore.open(target)
    with receiver(fault) as got:
        settings = WebhookSettings(
            (got.url,), dead_letter=tmp_path / "dead.jsonl", escalate_after=60.0
        )
        outbox = Outbox(store, settings, clock=lambda: clock["now"])
        outbox.attach()
        webhooks = WebhookSender(outbox, said.append, paced=True).start()
        recorder = Recorder(store, said.append, committed=lambda b, c: webhooks.wake())
        pacing = ReplayPacing(recorder, webhooks, lambda: clock["now"], said.append)
        try:
            for k in range(1000):  # 200 s of readings
                clock["now"] = k * STEP
                if k * STEP == BURST:
                    recorder.record(_decision())
                    pacing.record(_decision())
                pacing.step(Step(k * STEP, np.zeros(1)))
            passes = webhooks._lanes[0].begun
        finally:
            recorder.close()
            webhooks.close()
            store.close()
    assert got.events == [(1, "incident.new"), (1, "incident.escalated")]
    assert got.refused == [503, "close"]
    # failed at 10 s, again 2 s later, then 4 s later: delivered at 16 s; escalated at 70 s
    assert at == pytest.approx([BURST + 6.0, BURST + 60.0])
    # a pass per alert due (and the first), not one per step
    assert passes <= 8, passes
    assert not [s for s in said if "without waiting" in s], said


def test_without_pacing_the_busy_sender_misses_the_replay(
    target: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The same replay unpaced: the file is read before the sender passes, so the receiver
    gets nothing while it runs (what the pacing is for)."""
    monkeypatch.setattr(sender, "POLL", 86_400.0)
    clock = {"now": None}
    store = IncidentStore.open(target)
    with receiver(lambda: 503) as got:
        settings = WebhookSettings((got.url,), dead_letter=tmp_path / "dead.jsonl")
        outbox = Outbox(store, settings, clock=lambda: clock["now"])
        outbox.attach()
        webhooks = WebhookSender(outbox, lambda s: None).start()
        recorder = Recorder(store, lambda s: None)
        try:
            for k in range(1000):
                clock["now"] = k * STEP
                if k * STEP == BURST:
                    recorder.record(_decision())
            requests = got.requests
        finally:
            recorder.close()
            webhooks.close()
            store.close()
    assert requests == 0
