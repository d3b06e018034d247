"""burstloc.incidents.recorder: the live loop's records become incidents on a writer thread,
on SQLite and PostgreSQL; a full queue is said and counted, never a wait."""

from __future__ import annotations

import sys
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from burstloc.incidents import IncidentStore
from burstloc.incidents.recorder import Recorder
from burstloc.live.monitor import BurstMonitor
from burstloc.localize.config import Calibration
from burstloc.readings import Reading

sys.path.insert(0, str(Path(__file__).parents[1] / "live"))  # live_feed: a real burst

PIPE = "C"  # the burst pipe of the tiny_feed fixture


def test_a_burst_and_a_silent_meter_become_incidents(
    tiny: Path, tiny_config: Calibration, tiny_feed: list[Reading], target: str
) -> None:
    from live_feed import Collected

    store = IncidentStore.open(target)
    said: list[str] = []
    recorder = Recorder(store, said.append)
    gone, back = "J4", tiny_feed[-1].timestamp - 60.0
    feed = [
        r for r in tiny_feed if not (r.meter == gone and 20.0 < r.timestamp < back)
    ]  # J4 silent from 20 s until a minute before the end
    monitor = BurstMonitor(tiny, tiny_config, capture_interval=0.2)
    done = Collected(monitor, observer=recorder, silent_after=5.0, health_every=1.0).run(feed)
    recorder.close()
    try:
        (decision,) = done.decisions
        rows = store.incidents()
        bursts = [r for r in rows if r["kind"] == "burst"]
        faults = [r for r in rows if r["kind"] == "meter"]
        assert len(bursts) == 1 and bursts[0]["pipe"] == decision["pipes"][0]["pipe"] == PIPE
        burst = store.get(bursts[0]["id"])
        assert burst["record"]["time"] == decision["time"]
        assert burst["reading_time"] == decision["first_alarm"]
        assert burst["history"][0]["action"] == "detected"
        (fault,) = faults
        assert fault["meter"] == gone and fault["active"] is False  # it reports again
        history = [h["action"] for h in store.get(fault["id"])["history"]]
        assert history == ["detected", "cleared"]
        assert recorder.dropped == 0 and not said
    finally:
        store.close()


def test_a_full_queue_drops_says_and_counts_and_never_waits(tmp_path: Path) -> None:
    store = IncidentStore.open(str(tmp_path / "incidents.sqlite"))
    gate = threading.Event()
    take = store.take

    def held(news: Any) -> list[int]:
        gate.wait()  # the writer is stuck (a slow disk, a server far away)
        return take(news)

    store.take = held  # type: ignore[method-assign]
    said: list[str] = []
    recorder = Recorder(store, said.append, size=3)
    records = [
        {"type": "decision", "first_alarm": 10.0 * k, "time": 10.0 * k + 1,
         "pipes": [{"pipe": "C", "score": 0.0}]}
        for k in range(1, 11)
    ]  # fmt: skip
    recorder.record(records[0])
    while recorder.queue.qsize():  # until the writer holds it (and is stuck)
        time.sleep(0.01)
    for record in records[1:]:
        recorder.record(record)  # returns at once although the writer is stuck
    # the writer holds one, the queue three: the other six were dropped, said and counted
    assert recorder.dropped == 6
    assert said and "was not stored" in said[0] and "so far" in said[0]
    gate.set()
    recorder.close()
    try:
        assert recorder.stored == 10 - recorder.dropped
        assert len(store.incidents()) == recorder.stored
        assert any(f"{recorder.dropped} incident records were not stored" in s for s in said)
    finally:
        store.close()


@pytest.mark.parametrize("fault", ["silent", "implausible"])
def test_health_records_open_and_clear_meter_faults(tmp_path: Path, fault: str) -> None:
    store = IncidentStore.open(str(tmp_path / "incidents.sqlite"))
    recorder = Recorder(store, print)

    def health(t: float, silent: bool, implausible: int) -> dict[str, Any]:
        return {
            "type": "health", "time": t, "silent": ["J2"] if silent else [],
            "meters": {"J1": {"implausible": 0}, "J2": {"implausible": implausible}},
        }  # fmt: skip

    if fault == "silent":
        sequence = [(0.0, False, 0), (10.0, True, 0), (20.0, True, 0), (30.0, False, 0)]
    else:
        sequence = [(0.0, False, 0), (10.0, False, 1), (20.0, False, 2), (90.0, False, 2)]
    for t, silent, implausible in sequence:
        recorder.record(health(t, silent, implausible))
    recorder.close()
    try:
        (row,) = store.incidents()
        assert row["meter"] == "J2" and fault in row["summary"] and row["active"] is False
        assert [h["action"] for h in store.get(row["id"])["history"]] == ["detected", "cleared"]
    finally:
        store.close()
