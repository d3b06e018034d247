"""burstloc.live.health across a restart: what the feed sends again is replayed, not a clock
offset and not a flood of late readings."""

from __future__ import annotations

from pathlib import Path

import pytest
from live_feed import Collected, burst_steps, readings

from burstloc.live.health import CLOCK_JUMP, Health
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import BadReading
from burstloc.live.plausible import PlausibleRange
from burstloc.live.state import StateFile, identity
from burstloc.localize.config import Calibration
from burstloc.readings import Reading

RESTART = 695.0  # s; the burst starts at 702 s


@pytest.fixture(scope="module")
def long_feed(tiny: Path, tiny_config: Calibration) -> list[Reading]:
    """Eleven minutes of steady readings, then a burst on pipe C."""
    steps = burst_steps(tiny, tiny_config.meters, "C", before=700.0, after=200.0, sigma=0.002)
    return readings(steps, tiny_config.meters)


def _identity(config: Calibration) -> dict[str, object]:
    return identity(
        config,
        capture_interval=0.2,
        detector="cusum",
        localizer="fused",
        meter_model="instantaneous",
    )


def _loop(tiny: Path, config: Calibration, state: StateFile) -> Collected:
    return Collected(BurstMonitor(tiny, config, capture_interval=0.2), state=state)


@pytest.mark.parametrize("replay", [10.0, 60.0, 600.0])
def test_readings_sent_again_after_a_restart_are_replayed_not_off_the_clock(
    tiny, tiny_config, long_feed, tmp_path: Path, replay: float
) -> None:
    config, feed = tiny_config, long_feed
    ident = _identity(config)
    clean = _loop(tiny, config, StateFile(tmp_path / "clean.json", ident)).run(feed)
    state = StateFile(tmp_path / "state.json", ident)
    before = _loop(tiny, config, state)
    for r in feed:
        if r.timestamp < RESTART:
            before.loop.feed(r)
    before.loop.save()  # the last save before the monitor stopped (kill -9)

    after = _loop(tiny, config, state)
    saved = state.load()
    assert saved is not None
    after.loop.restore(saved)
    again = [r for r in feed if r.timestamp >= RESTART - replay]  # the feed goes back
    after.run(again)

    strip = [{k: v for k, v in d.items() if k != "health"} for d in after.decisions]
    assert strip == [{k: v for k, v in d.items() if k != "health"} for d in clean.decisions]
    assert clean.decisions[0]["pipes"][0]["pipe"] == "C"
    text = "\n".join(after.messages)
    assert "off the clock" not in text and "clock offset" not in text and "late" not in text
    meters = after.health.record()["meters"]
    assert all(after.health.meter[m].clock_offset == 0.0 for m in config.meters)
    assert sum(meters[m]["late"] for m in config.meters) == 0
    assert sum(meters[m]["off_clock"] for m in config.meters) == 0
    replayed = sum(r.timestamp < RESTART for r in again)
    assert sum(meters[m]["replayed"] for m in config.meters) == replayed
    per_meter = replayed // len(config.meters)
    for m in config.meters:
        assert (
            f"meter {m!r}: {per_meter} readings sent again after the restart (seen before it) "
            "skipped" in text
        )
    # Counted as readings once, as without the restart.
    assert {m: meters[m]["readings"] for m in meters} == {
        m: clean.health.record()["meters"][m]["readings"] for m in meters
    }


def test_a_feed_that_is_all_replay_is_said(tiny, tiny_config, long_feed, tmp_path: Path) -> None:
    # Before, a feed sent again in full after a restart was skipped without a word.
    config, feed = tiny_config, long_feed
    state = StateFile(tmp_path / "state.json", _identity(config))
    before = _loop(tiny, config, state)
    for r in feed[:2000]:
        before.loop.feed(r)
    before.loop.save()
    after = _loop(tiny, config, state)
    saved = state.load()
    assert saved is not None
    after.loop.restore(saved)
    after.run(feed[1000:2000])  # every reading seen before the restart
    assert after.loop.readings == 1000 and after.decisions == []
    meters = len(config.meters)
    said = (
        f"the feed ended in its replay: 1000 readings of {meters} meter(s) sent again after the "
        "restart (seen before it) skipped, none newer"
    )
    assert [m for m in after.messages if said in m], after.messages


def test_after_the_replay_a_meter_reading_out_of_order_is_late_again(
    tiny, tiny_config, long_feed, tmp_path: Path
) -> None:
    state = StateFile(tmp_path / "state.json", _identity(tiny_config))
    before = _loop(tiny, tiny_config, state)
    before.run([r for r in long_feed if r.timestamp < 100.0])
    after = _loop(tiny, tiny_config, state)
    saved = state.load()
    assert saved is not None
    after.loop.restore(saved)
    fresh = [r for r in long_feed if 100.0 <= r.timestamp < 110.0]
    old = Reading(109.0, "J1", fresh[0].value)  # after J1's replay ended: a late reading
    after.run([*fresh, old])
    assert after.health.meter["J1"].counts["replayed"] == 0
    assert after.health.meter["J1"].counts["late"] == 1, after.messages


def _health() -> Health:
    meters = ("J1", "J2", "J3", "J4")
    return Health(meters, PlausibleRange.default(meters, [60.0] * 4), capture_interval=0.2)


def _tick(health: Health, t: float, meters: tuple[str, ...] = ("J1", "J2", "J3", "J4")) -> list:
    return [health.admit(Reading(t, m, 50.0), f"t {t:g} {m}") for m in meters]


def test_a_reading_a_day_off_the_clock_is_bad_and_moves_nothing_until_the_feed_moves() -> None:
    health = _health()
    for k in range(100):
        _tick(health, 0.2 * k)
    stray = health.admit(Reading(CLOCK_JUMP + 20.0, "J2", 50.0), "line 9")
    assert isinstance(stray, BadReading) and stray.meter == "J2"
    assert str(stray).startswith("line 9: timestamp 86420 s from meter 'J2' is 1 days from")
    assert health.meter["J2"].counts["bad"] == 1 and health.meter["J2"].last == pytest.approx(19.8)
    # strays of different meters between readings on the clock never add up to a move
    for k, meter in enumerate(("J1", "J3", "J4")):
        assert isinstance(health.admit(Reading(2e5 + k, meter, 50.0), "x"), BadReading)
        assert all(isinstance(r, Reading) for r in _tick(health, 20.0 + 0.2 * k))
    assert health.reference == pytest.approx(20.4)
    # the whole feed two days later: the readings of more than half of the meters move it
    later = 2 * 86_400.0
    first = _tick(health, later)
    assert [type(r).__name__ for r in first] == ["BadReading", "BadReading", "Reading", "Reading"]
    assert health.reference == pytest.approx(later)
    assert all(isinstance(r, Reading) for r in _tick(health, later + 0.2))
    assert health.update_silence() == ([], [])
    row = health.admit_row([later + 0.4], [0], [50.0], "m")
    assert row.times == [later + 0.4] and not row.moved


def test_a_restart_after_an_outage_of_days_resumes_on_the_new_clock(
    tiny: Path, tiny_config: Calibration, long_feed: list[Reading], tmp_path: Path
) -> None:
    state = StateFile(tmp_path / "state.json", _identity(tiny_config))
    _loop(tiny, tiny_config, state).run([r for r in long_feed if r.timestamp < RESTART])
    outage = 3 * 86_400.0  # the monitor and the feed down for a long weekend
    done = _loop(tiny, tiny_config, state)
    saved = state.load()
    assert saved is not None
    done.loop.restore(saved)
    resumed = [Reading(r.timestamp + outage, r.meter, r.value) for r in long_feed]
    done.run([r for r in resumed if r.timestamp >= RESTART + 0.2 + outage])
    text = "\n".join(done.messages)
    assert text.count("days from the feed's clock (t = 694.8 s;") == 2, text
    assert "the feed's clock moved by +3 days (t = 694.8 s to 259895.2 s)" in text, text
    (decision,) = done.decisions
    assert decision["pipes"][0]["pipe"] == "C"
    assert decision["first_alarm"] > outage


def test_one_reading_an_hour_off_is_held_back_not_a_clock_offset_of_zero() -> None:
    health = _health()
    for k in range(100):
        _tick(health, 0.2 * k)
    row = health.admit_row([19.8 + 3600.0], [1], [50.0], "line 9")
    assert row.refused == [(0, 1, None)] and not row.offsets and not row.times
    assert health.meter["J2"].counts["off_clock"] == 1 and health.meter["J2"].clock_offset == 0.0
