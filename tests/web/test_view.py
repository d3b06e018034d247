"""The hand-off from the monitor to the page (burstloc.web.hub, burstloc.web.view), the live
loop's observer (burstloc.live.observe) and the drawing read from an INP file (burstloc.layout)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from web_browser import ROOT

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.layout import read_layout
from burstloc.live.observe import LiveObserver
from burstloc.readings import Step
from burstloc.web import View, check_access, parse_bind
from burstloc.web.hub import Hub
from burstloc.web.view import ROWS_PER_PUSH


def test_the_inbox_is_bounded_and_the_oldest_are_dropped() -> None:
    hub = Hub(inbox=3)
    for k in range(10):
        hub.step(Step(float(k), [1.0]))
    assert [s.timestamp for s in hub.drain()] == [7.0, 8.0, 9.0]  # type: ignore[union-attr]
    assert hub.drain() == []


def test_urgent_news_wakes_the_page_side_and_a_closed_loop_is_forgotten() -> None:
    hub = Hub()
    woken: list[int] = []
    hub.wake = lambda: woken.append(1)
    hub.step(Step(0.0, [1.0]))
    assert woken == []  # readings wait for the next poll
    hub.alarm("N3", 1.0, 0.8, -0.5)
    hub.record({"type": "health"})
    assert woken == []  # alarms and health wait for the poll too: not amid the decision
    hub.record({"type": "decision"})
    hub.message("meter 'N8' silent")
    assert len(woken) == 2

    def closed() -> None:
        raise RuntimeError("Event loop is closed")

    hub.wake = closed
    hub.record({"type": "event"})  # never raises into the monitor
    assert hub.wake is None
    kinds = [item[0] if isinstance(item, tuple) else "step" for item in hub.drain()]
    assert kinds == ["step", "alarm", "record", "record", "message", "record"]


def test_health_is_built_only_when_due() -> None:
    hub = Hub(health_every=3600.0)
    built: list[int] = []

    def health() -> dict[str, Any]:
        built.append(1)
        return {"type": "health", "meters": {}}

    for _ in range(100):
        hub.tick(health)
    assert built == [1]


def _decision(pipe: str, time: float, kind: str = "decision") -> dict[str, Any]:
    return {
        "type": kind,
        "time": time,
        "pipes": [{"pipe": pipe, "start": "a", "end": "b", "score": 0.0}],
        "position": {"pipe": pipe, "from": "a", "metres": 5.0, "low": 1.0, "high": 9.0,
                     "length": 10.0},
        "decision_delay_s": 0.5,
    }  # fmt: skip


def test_the_view_keeps_the_incident_and_a_new_alarm_after_the_answer_starts_another() -> None:
    view = View(["N3", "N5"], 0.2, {"network": "x.inp"})
    news = view.take(
        [
            Step(1.0, [50.0, float("nan")]),
            Step(1.2, [50.5, 49.0], filled=("N5",)),
            ("alarm", ("N3", 1.2, 1.0, -0.5)),
            ("alarm", ("N5", 1.4, 1.2, -0.4)),
            ("record", _decision("9", 1.5, "transient")),
            ("record", _decision("9", 2.0)),
        ]
    )
    assert [n["kind"] for n in news] == ["rows", "alarm", "alarm", "record", "record"]
    # strict JSON: NaN as null; a filled value is not a reading
    assert news[0]["rows"] == [(1.0, [50.0, None]), (1.2, [50.5, None])]
    json.dumps(news, allow_nan=False)
    snap = view.snapshot()
    assert [a["meter"] for a in snap["alarms"]] == ["N3", "N5"]
    assert snap["transient"]["time"] == 1.5 and snap["answer"]["time"] == 2.0
    assert "burst located on pipe 9, 5 m from node a" in snap["log"][-1]["text"]
    news = view.take([("alarm", ("N5", 300.0, 299.8, -0.4))])
    assert [n["kind"] for n in news] == ["incident", "alarm"]
    snap = view.snapshot()
    assert [a["meter"] for a in snap["alarms"]] == ["N5"] and snap["answer"] is None
    json.dumps(snap, allow_nan=False)


def test_a_backlog_of_readings_is_thinned_for_the_push_but_kept_for_a_new_page() -> None:
    view = View(["N3"], 0.2, {}, window=600.0)
    news = view.take([Step(0.2 * k, [float(k)]) for k in range(500)])
    rows = news[0]["rows"]
    assert len(rows) == ROWS_PER_PUSH and rows[-1] == (pytest.approx(99.8), [499.0])
    assert len(view.snapshot()["rows"]) == 500


def test_an_implausible_count_that_rises_is_dated() -> None:
    view = View(["N3"], 0.2, {})
    meters = {"N3": {"implausible": 0, "silent": False}}
    view.take([("health", {"type": "health", "time": 10.0, "meters": meters})])
    assert view.implausible_at == {}
    meters = {"N3": {"implausible": 1, "silent": False}}
    news = view.take([("record", {"type": "health", "time": 12.0, "meters": meters})])
    assert view.implausible_at == {"N3": 12.0}
    assert news[-1]["kind"] == "health" and news[-1]["implausible_at"] == {"N3": 12.0}


def test_the_live_loop_tells_its_observer_every_step_alarm_and_record(
    tiny: Path, tiny_config: Any, tiny_feed: Any
) -> None:
    from live_feed import Collected

    from burstloc.live.monitor import BurstMonitor

    class Seen(LiveObserver):
        def __init__(self) -> None:
            self.steps: list[float] = []
            self.alarms: list[tuple[str, float, float]] = []
            self.records: list[dict[str, Any]] = []

        def step(self, step: Step) -> None:
            self.steps.append(step.timestamp)

        def alarm(self, meter: str, time: float, onset: float, amplitude: float) -> None:
            self.alarms.append((meter, time, onset))

        def record(self, record: dict[str, Any]) -> None:
            self.records.append(record)

    seen = Seen()
    monitor = BurstMonitor(tiny, tiny_config, capture_interval=0.2)
    run = Collected(monitor, observer=seen).run(tiny_feed)
    assert seen.records == run.records  # every record emitted, in order
    decision = run.decisions[0]
    assert {m for m, _, _ in seen.alarms} == set(decision["alarmed"])
    assert min(t for _, t, _ in seen.alarms) == pytest.approx(decision["first_alarm"])
    assert all(onset <= t for _, t, onset in seen.alarms)
    assert len(seen.steps) == len({r.timestamp for r in tiny_feed})
    assert seen.steps == sorted(seen.steps)


def test_the_drawing_has_every_node_and_link_with_vertices(tmp_path: Path) -> None:
    layout = read_layout(ROOT / "networks" / "paper15_assets.inp")
    kinds = {k for k, *_ in layout.links.values()}
    assert kinds == {"pipe", "pump", "valve"}
    doc = layout.to_json()
    assert len(doc["links"]["names"]) == len(layout.links) == 29
    assert all(len(v) % 2 == 0 for v in doc["links"]["vertices"])
    inp = tmp_path / "v.inp"
    inp.write_text(
        "[JUNCTIONS]\n J1 0 1\n J2 0 1\n J3 0 1\n[RESERVOIRS]\n R 50\n[PIPES]\n"
        " P1 R J1 100 300 100 0 OPEN\n P2 J1 J2 100 300 100 0 OPEN\n"
        " P3 J2 J3 100 300 100 0 OPEN\n"
        "[COORDINATES]\n R 0 0\n J1 10 0\n J3 30 10\n[VERTICES]\n P2 15 5\n P2 18 6\n[END]\n"
    )
    layout = read_layout(inp)
    assert layout.links["P2"][3] == [(15.0, 5.0), (18.0, 6.0)]
    assert layout.nodes["J2"] == ("junction", 20.0, 5.0)  # no coordinates: between J1 and J3
    assert layout.lengths["P1"] == 100.0
    inp.write_text("[JUNCTIONS]\n J1 0 1\n[PIPES]\n P1 J1 X 100 300 100 0 OPEN\n[END]\n")
    with pytest.raises(NetworkError, match="unknown node"):
        read_layout(inp)


def test_addresses_and_tokens() -> None:
    assert parse_bind("8080") == ("127.0.0.1", 8080)
    assert parse_bind("0.0.0.0:80") == ("0.0.0.0", 80)
    assert parse_bind("[::1]:9000") == ("::1", 9000)
    for bad in ("http", "host:", "70000", ":12"):
        with pytest.raises(ConfigError, match=r"\[HOST:\]PORT"):
            parse_bind(bad)
    check_access("127.0.0.1", None)
    check_access("::1", None)
    check_access("localhost", None)
    check_access("0.0.0.0", "token")
    for host in ("0.0.0.0", "192.168.1.5", "example.org", "::"):
        with pytest.raises(ConfigError, match="needs a token"):
            check_access(host, None)
        with pytest.raises(ConfigError, match="needs a token"):
            check_access(host, "")
