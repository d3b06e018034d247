"""burstloc.incidents.alerts: webhook alerts through a real HTTP receiver that fails on purpose
(503s, dropped connections, no answer), on SQLite and PostgreSQL: every incident delivered once,
in order, after the receiver was down for the first 10 minutes of a replay (its clock moved by
the test: reading time, not wall time); a restarted sender delivers what the last one left;
alerts given up to the dead-letter file; escalations fire once, and not for an acknowledged
incident."""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest
from receiver import receiver

from burstloc.exceptions import ConfigError
from burstloc.incidents import IncidentStore
from burstloc.incidents.alerts import WebhookSettings
from burstloc.incidents.alerts.outbox import Outbox
from burstloc.incidents.alerts.sender import WebhookSender
from burstloc.incidents.intake import Observed, from_record

NEW, ESCALATED = "incident.new", "incident.escalated"


class Replay:
    """The alerts' clock, moved by the test (a replay's reading time)."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _news(k: int) -> Observed:
    record = {
        "type": "decision", "burst": True, "first_alarm": 100.0 * k, "time": 100.0 * k + 3,
        "pipes": [{"pipe": f"P{k}", "score": 0.0}, {"pipe": "Q", "score": -1.0}],
        "position": {"pipe": f"P{k}", "from": "N1", "metres": 12.5},
        "region": {"length_m": 80.0, "confidence": 0.95, "stretches": [{"pipe": f"P{k}"}]},
    }  # fmt: skip
    item = from_record(record, 1.8e9 + k)
    assert item is not None
    return item


@contextmanager
def alerting(
    target: str, url: str, folder: Path, clock: Replay, said: list[str], **limits: Any
) -> Iterator[tuple[IncidentStore, Outbox, WebhookSender]]:
    """A store with its outbox and a started sender; closed after."""
    store = IncidentStore.open(target)
    settings = WebhookSettings((url,), dead_letter=folder / "dead.jsonl", **limits)
    outbox = Outbox(store, settings, clock=clock, link=lambda i: f"http://page:8080/#incident={i}")
    outbox.attach()
    sender = WebhookSender(outbox, said.append).start()
    try:
        yield store, outbox, sender
    finally:
        sender.close()
        store.close()


def test_a_receiver_down_for_the_first_ten_minutes_gets_every_incident_once_in_order(
    target: str, tmp_path: Path
) -> None:
    clock, said = Replay(), []
    failures = itertools.cycle([503, "close", 500])
    hung: list[bool] = []

    def fault() -> int | str | None:
        if clock.now >= 600.0:
            return None
        if not hung:  # the first attempt gets no answer: the sender's timeout
            hung.append(True)
            return "hang"
        return next(failures)

    with (
        receiver(fault) as got,
        alerting(target, got.url, tmp_path, clock, said, timeout=2.0) as (store, outbox, sender),
    ):
        opened = []
        for minute in range(30):  # an incident a minute, the clock moved by the replay
            clock.now = 60.0 * minute
            (incident,) = store.take([_news(minute)])
            opened.append(incident)
            assert sender.settle()
        for minute in range(30, 40):
            clock.now = 60.0 * minute
            assert sender.settle()
        assert got.events == [(i, NEW) for i in opened]  # every one, in order
        keys = [key for key, _ in got.accepted]
        assert len(set(keys)) == len(keys) == 30  # once each
        assert {"hang", "close", 503, 500} <= set(got.refused)
        assert sender.delivered == 30 and sender.dead_lettered == 0
        assert sender.failed_attempts == len(got.refused) >= 6
        counts = outbox.counts()
        assert counts["delivered"] == 30 and counts["pending"] == 0
        first = got.accepted[0][1]
        assert first["incident"]["pipe"] == "P0" and first["incident"]["state"] == "detected"
        assert first["incident"]["point"] == {"pipe": "P0", "from": "N1", "metres": 12.5}
        assert first["incident"]["region"]["pipes"] == ["P0", "Q"]
        assert first["link"] == f"http://page:8080/#incident={opened[0]}"
        assert first["at"] == 0.0 and first["alert"] == got.accepted[0][0]
    assert any("no answer within 2 s" in s for s in said)
    assert any("delivering again" in s for s in said)


def test_a_restarted_sender_delivers_what_the_last_one_left(target: str, tmp_path: Path) -> None:
    clock, said = Replay(), []
    down = [True]
    with receiver(lambda: 503 if down[0] else None) as got:
        with alerting(target, got.url, tmp_path, clock, said) as (store, _, sender):
            opened = [store.take([_news(k)])[0] for k in range(3)]
            assert sender.settle()
        assert got.accepted == [] and got.requests == 1  # the head only, in order
        assert any("3 webhook alerts not delivered yet: kept in the outbox" in s for s in said)
        down[0] = False
        clock.now = 10.0
        with alerting(target, got.url, tmp_path, clock, said) as (_, outbox, sender):
            assert sender.settle()
            assert got.events == [(i, NEW) for i in opened]
            assert outbox.counts()["pending"] == 0


@pytest.mark.parametrize(
    ("why", "limits", "faults", "times"),
    [
        ("attempts", {"max_attempts": 3}, [503, 503, 503], [0.0, 10.0, 20.0]),
        ("age", {"max_age": 30.0}, [503, 503], [0.0, 40.0]),
        ("refused", {}, [400], [0.0]),
    ],
)
def test_an_alert_is_given_up_to_the_dead_letter_file_and_the_queue_moves_on(
    tmp_path: Path, why: str, limits: dict[str, Any], faults: list[int], times: list[float]
) -> None:
    clock, said = Replay(), []
    left = list(faults)
    target = str(tmp_path / "incidents.sqlite")
    with (
        receiver(lambda: left.pop(0) if left else None) as got,
        alerting(target, got.url, tmp_path, clock, said, **limits) as (store, outbox, sender),
    ):
        first, second = (store.take([_news(k)])[0] for k in range(2))
        for t in times:
            clock.now = t
            assert sender.settle()
        assert got.events == [(second, NEW)]
        assert sender.dead_lettered == 1 and sender.delivered == 1
        assert outbox.counts()["dead"] == 1
    (line,) = (tmp_path / "dead.jsonl").read_text().splitlines()
    dead = json.loads(line)
    assert dead["incident"] == first and dead["event"] == NEW and dead["url"] == got.url
    assert dead["attempts"] == len(faults) and dead["payload"]["incident"]["id"] == first
    assert f"HTTP {faults[-1]}" in dead["reason"]
    (message,) = [s for s in said if "given up" in s]
    assert f"incident {first}" in message and str(tmp_path / "dead.jsonl") in message


def test_an_escalation_fires_once_and_not_for_an_acknowledged_incident(
    target: str, tmp_path: Path
) -> None:
    clock, said = Replay(), []
    with (
        receiver() as got,
        alerting(target, got.url, tmp_path, clock, said, escalate_after=900.0) as (
            store,
            outbox,
            sender,
        ),
    ):
        seen = store.take([_news(1)])[0]
        clock.now = 60.0
        unseen = store.take([_news(2)])[0]
        clock.now = 300.0
        store.acknowledge(seen, "ann", "cli")
        assert sender.settle()
        clock.now = 959.0  # the acknowledged one's time has come, not the other's
        assert sender.settle()
        assert got.events == [(seen, NEW), (unseen, NEW)]
        clock.now = 960.0
        assert sender.settle()
        clock.now = 5000.0
        assert sender.settle()
        assert got.events == [(seen, NEW), (unseen, NEW), (unseen, ESCALATED)]
        escalated = got.accepted[-1][1]
        assert escalated["unacknowledged_minutes"] == 15.0 and escalated["at"] == 960.0
        assert escalated["incident"]["state"] == "detected"
        assert escalated["link"] == f"http://page:8080/#incident={unseen}"
        counts = outbox.counts()
        assert counts["cancelled"] == 1 and counts["waiting"] == 0
        assert counts["delivered"] == 3


def test_alerts_to_a_url_no_longer_configured_are_given_up_and_said(tmp_path: Path) -> None:
    clock, said = Replay(), []
    target = str(tmp_path / "incidents.sqlite")
    with (
        receiver(lambda: 503) as old,
        alerting(target, old.url, tmp_path, clock, said) as (store, _, sender),
    ):
        store.take([_news(1)])
        assert sender.settle()
    with receiver() as new, alerting(target, new.url, tmp_path, clock, said) as (_, outbox, _s):
        assert outbox.counts()["dead"] == 1
    assert any("its URL is no longer configured" in s for s in said)
    assert json.loads((tmp_path / "dead.jsonl").read_text())["url"] == old.url


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"urls": ()}, "webhook: give at least one URL"),
        ({"urls": ("ftp://host/x",)}, "webhook: want an http:// or https:// URL"),
        ({"urls": ("http:///x",)}, "names no host"),
        ({"urls": ("http://host:99999/",)}, "is not a URL"),
        ({"escalate_after": -60.0}, "webhook-escalate-minutes must be a finite number > 0"),
        ({"max_attempts": 0}, "max-attempts must be >= 1"),
    ],
)
def test_bad_settings_are_refused_by_name(
    tmp_path: Path, settings: dict[str, Any], message: str
) -> None:
    values = {"urls": ("http://127.0.0.1:9/hook",), "dead_letter": tmp_path / "d.jsonl"}
    with pytest.raises(ConfigError, match=message):
        WebhookSettings(**{**values, **settings})


def test_the_metrics_count_the_alerts(tmp_path: Path) -> None:
    from prometheus_client import CollectorRegistry, generate_latest

    from burstloc.web.metrics import _webhooks

    clock, said = Replay(), []
    faults = [503]
    target = str(tmp_path / "incidents.sqlite")
    with (
        receiver(lambda: faults.pop() if faults else None) as got,
        alerting(target, got.url, tmp_path, clock, said, escalate_after=60.0) as (store, _, sender),
    ):
        store.take([_news(1)])
        assert sender.settle()

        class Collector:
            def collect(self) -> Iterator[Any]:
                return _webhooks(sender)

        registry = CollectorRegistry()
        registry.register(Collector())  # type: ignore[arg-type]
        text = generate_latest(registry).decode()
        for line in (
            "burstloc_webhook_pending 1.0",
            "burstloc_webhook_waiting 1.0",
            "burstloc_webhook_delivered_total 0.0",
            "burstloc_webhook_failed_attempts_total 1.0",
            "burstloc_webhook_dead_lettered_total 0.0",
        ):
            assert line in text
        clock.now = 10.0
        assert sender.settle()
        assert "burstloc_webhook_delivered_total 1.0" in generate_latest(registry).decode()
