"""burstloc.live.loop: bad data never stops the live loop; silent meters, clocks, health."""

from __future__ import annotations

from pathlib import Path

import pytest
from live_feed import Collected

from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading, parse_line
from burstloc.live.reporter import Reporter
from burstloc.live.state import StateFile, identity
from burstloc.localize.config import Calibration
from burstloc.readings import Reading

PIPE = "C"  # the burst pipe of the tiny_feed fixture


@pytest.fixture(scope="module")
def config(tiny_config: Calibration) -> Calibration:
    return tiny_config


@pytest.fixture(scope="module")
def feed(tiny_feed: list[Reading]) -> list[Reading]:
    return tiny_feed


def _run(tiny: Path, config: Calibration, items, **options) -> Collected:
    monitor = BurstMonitor(tiny, config, capture_interval=0.2)
    return Collected(monitor, **options).run(items)


def test_a_clean_feed_gives_one_decision_that_tells_the_truth(tiny, config, feed) -> None:
    done = _run(tiny, config, feed)
    (decision,) = done.decisions
    assert decision["pipes"][0]["pipe"] == PIPE
    assert decision["meters"] == list(config.meters) and decision["excluded"] == []
    assert set(decision["alarmed"]) <= set(config.meters) and len(decision["alarmed"]) >= 2
    delay = decision["time"] - decision["first_alarm"]
    assert decision["decision_delay_s"] == pytest.approx(delay)
    cal = config.for_interval(0.2)
    assert decision["waited"] == (delay > cal.arrival_decision_delay + 0.2 + 1e-9)
    assert decision["health"]["meters"]["J1"]["readings"] > 0
    assert done.health_records and not done.messages
    # where on C (250 m, burst at its middle): within half a capture step of wave travel
    where = decision["position"]
    assert where["pipe"] == PIPE and where["from"] == decision["pipes"][0]["start"]
    assert abs(where["metres"] - 125.0) <= 0.5 * 0.2 * 1200.0
    assert where["low"] <= where["metres"] <= where["high"] <= where["length"] == 250.0


def test_bad_data_is_reported_and_skipped_and_the_decision_is_unchanged(tiny, config, feed) -> None:
    clean = _run(tiny, config, feed).decisions
    burst_at = clean[0]["first_alarm"]
    k = next(i for i, r in enumerate(feed) if r.timestamp >= burst_at - 30.0)
    garbage: list[Reading | BadReading] = [
        BadReading("line 7", "value is not a finite number: '1,J1,abc'", "J1"),
        Reading(feed[k].timestamp, "nowhere", 50.0),
        Reading(feed[k].timestamp, "J2", 1e6),  # implausible: would alarm and hide the burst
        Reading(feed[k].timestamp, "J3", -500.0),
    ]
    dirty = _run(tiny, config, [*feed[:k], *garbage, *feed[k:]])
    assert [d["pipes"] for d in dirty.decisions] == [d["pipes"] for d in clean]
    assert dirty.decisions[0]["time"] == clean[0]["time"]
    text = "\n".join(dirty.messages)
    assert "line 7: value is not a finite number" in text
    assert "unknown meter 'nowhere'" in text
    assert "implausible value 1e+06 m from meter 'J2'" in text
    assert "implausible value -500 m from meter 'J3'" in text
    meters = dirty.health.record()["meters"]
    assert meters["J1"]["bad"] == 1 and meters["J2"]["implausible"] == 1
    assert dirty.health.bad_unknown == 1


def test_a_silent_meter_is_excluded_and_included_again(tiny, config, feed) -> None:
    gone = "J4"
    burst_at = _run(tiny, config, feed).decisions[0]["first_alarm"]
    back_at = burst_at + 200.0
    items = [r for r in feed if r.meter != gone or r.timestamp >= back_at]
    done = _run(tiny, config, items, silent_after=5.0)
    (decision,) = done.decisions
    assert decision["excluded"] == [gone] and gone not in decision["meters"]
    assert decision["health"]["meters"][gone]["silent"] is True
    assert decision["pipes"], "the other meters still localize"
    text = "\n".join(done.messages)
    assert f"meter {gone!r} never heard from: excluded from localization" in text
    assert f"meter {gone!r} reports again: included" in text
    assert done.health.meter[gone].silent is False


def test_a_meter_that_starts_late_within_the_silence_time_is_not_excluded(
    tiny, config, feed
) -> None:
    clean = _run(tiny, config, feed).decisions
    items = [r for r in feed if r.meter != "J4" or r.timestamp >= feed[0].timestamp + 2.0]
    done = _run(tiny, config, items, silent_after=5.0)
    assert not [m for m in done.messages if "J4" in m and "excluded" in m], done.messages
    assert done.health.meter["J4"].counts["late"] == 0
    assert [d["pipes"][0]["pipe"] for d in done.decisions] == [clean[0]["pipes"][0]["pipe"]]


@pytest.mark.parametrize("offset", [2.0, -3600.0, 3600.0])
def test_a_meter_clock_offset_is_found_and_corrected(tiny, config, feed, offset: float) -> None:
    clean = _run(tiny, config, feed).decisions
    shifted = [
        Reading(r.timestamp + offset, r.meter, r.value) if r.meter == "J2" else r for r in feed
    ]
    done = _run(tiny, config, shifted)
    assert done.health.meter["J2"].clock_offset == pytest.approx(offset)
    assert [d["pipes"][0]["pipe"] for d in done.decisions] == [clean[0]["pipes"][0]["pipe"]]
    assert f"meter 'J2': clock offset {offset:+g} s found" in "\n".join(done.messages)
    assert done.health.record()["clock_corrected"] == {"J2": pytest.approx(offset)}


def test_reports_are_rate_limited_per_kind_and_nothing_is_silent() -> None:
    said: list[str] = []
    report = Reporter(said.append, burst=2, every=1000.0)
    for k in range(5):
        report("late", f"late {k}")
    report("clock-offset", "offset found")
    assert said == [
        "burstloc monitor: late 0",
        "burstloc monitor: late 1",
        "burstloc monitor: offset found",
    ]
    report.close()
    assert said[-1] == "burstloc monitor: 3 more late messages not shown"
    assert report.counts == {"late": 5, "clock-offset": 1}


def test_a_gap_in_the_whole_feed_is_not_a_clock_offset(tiny, config, feed) -> None:
    clean = _run(tiny, config, feed).decisions
    burst_at = clean[0]["first_alarm"]
    gap = 600.0  # ten minutes of readings lost (a broker that dropped them, a network outage)
    items = [r for r in feed if not burst_at - 620.0 <= r.timestamp < burst_at - 20.0]
    shifted = [
        Reading(r.timestamp + (gap if r.timestamp >= burst_at - 20.0 else 0.0), r.meter, r.value)
        for r in items
    ]
    done = _run(tiny, config, shifted)
    assert all(h.clock_offset == 0.0 for h in done.health.meter.values())
    assert [d["pipes"][0]["pipe"] for d in done.decisions] == [clean[0]["pipes"][0]["pipe"]]
    assert done.decisions[0]["first_alarm"] == pytest.approx(burst_at + gap)


def test_a_state_file_that_cannot_be_written_is_reported_and_the_loop_goes_on(
    tiny, config, feed, tmp_path: Path
) -> None:
    clean = _run(tiny, config, feed).decisions
    # A file where the state's directory should be: every save fails.
    blocker = tmp_path / "blocker"
    blocker.write_text("not a directory")
    ident = identity(
        config,
        capture_interval=0.2,
        detector="cusum",
        localizer="fused",
        meter_model="instantaneous",
    )
    done = _run(tiny, config, feed, state=StateFile(blocker / "state.json", ident), save_every=0.0)
    assert [d["pipes"] for d in done.decisions] == [d["pipes"] for d in clean]
    assert done.loop.failed_saves > 0
    assert any("state not saved" in m for m in done.messages)
    assert blocker.read_text() == "not a directory"


def _csv(feed: list[Reading]) -> list[str]:
    """The feed as the monitor's CSV lines (header first: line k + 1 is reading k)."""
    return ["timestamp,meter,value", *(f"{r.timestamp!r},{r.meter},{r.value:.4f}" for r in feed)]


def _parsed(done: Collected, lines: list[str]):
    """The lines through the real parser, sharing the loop's timestamp form, as the CLI does."""
    for number, line in enumerate(lines, start=1):
        item = parse_line(line, f"line {number}", done.loop.timestamps)
        if item is not None:
            yield f"line {number}", item


@pytest.mark.parametrize(
    ("stamp", "reason"),
    [
        # the same instant in ISO 8601 (1970 epoch): only its form tells it apart
        ("1970-01-01T00:00:40Z", "timestamp in ISO 8601 in a feed of seconds (since line 2)"),
        ("2026-11-26T10:00:40Z", "timestamp in ISO 8601 in a feed of seconds (since line 2)"),
        # seconds, but from another origin: years from the feed's clock
        ("1795687240", "timestamp 1795687240 s from meter 'J2' is 2.078e+04 days from the feed's"),
    ],
)
def test_a_line_off_the_feed_s_time_form_or_clock_is_a_bad_reading_and_nothing_else_is_lost(
    tiny, config, feed, stamp: str, reason: str
) -> None:
    lines = _csv(feed)
    clean = Collected(BurstMonitor(tiny, config, capture_interval=0.2))
    clean.run(_parsed(clean, lines))
    odd = next(k for k, line in enumerate(lines) if line.startswith("40.0,J2,"))
    lines[odd] = stamp + lines[odd].removeprefix("40.0")
    done = Collected(BurstMonitor(tiny, config, capture_interval=0.2))
    done.run(_parsed(done, lines))
    assert f"burstloc monitor: bad reading skipped: line {odd + 1}: {reason}" in "\n".join(
        done.messages
    ), done.messages
    assert len(done.messages) == len(clean.messages) + 1
    meters, before = done.health.record()["meters"], clean.health.record()["meters"]
    assert meters["J2"]["bad"] == before["J2"]["bad"] + 1
    assert meters["J2"]["readings"] == before["J2"]["readings"] - 1
    assert all(meters[m] == before[m] for m in ("J1", "J3", "J4"))
    assert done.loop.readings == clean.loop.readings - ("days from" not in reason)  # parsed or not
    # the burst is located as from the clean feed, at the same time (the skipped reading is
    # filled with J2's previous one: the scores move in their fifth digit)
    ranked = [[p["pipe"] for p in d["pipes"]] for d in done.decisions]
    assert ranked == [[p["pipe"] for p in d["pipes"]] for d in clean.decisions]
    assert [d["time"] for d in done.decisions] == [d["time"] for d in clean.decisions]
    assert done.decisions[0]["pipes"][0]["pipe"] == PIPE


def test_the_whole_feed_moved_by_days_is_followed_not_refused(tiny, config, feed) -> None:
    clean = _run(tiny, config, feed).decisions
    burst_at = clean[0]["first_alarm"]
    outage = 2 * 86_400.0  # readings resume two days later (a plant network down for a weekend)
    resume = burst_at - 20.0
    moved = [
        Reading(r.timestamp + (outage if r.timestamp >= resume else 0.0), r.meter, r.value)
        for r in feed
    ]
    done = _run(tiny, config, moved)
    text = "\n".join(done.messages)
    # the first resumed readings are far from the clock, until those of most meters agree
    assert text.count("days from the feed's clock") == 2, text
    assert "the feed's clock moved by +2 days" in text
    assert [d["pipes"][0]["pipe"] for d in done.decisions] == [PIPE]
    assert done.decisions[0]["first_alarm"] == pytest.approx(burst_at + outage)
    assert done.health.reference is not None and done.health.reference > outage
