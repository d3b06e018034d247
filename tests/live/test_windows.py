"""The real-time feed: complete steps, windows, and the rules for imperfect readings."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from burstloc.exceptions import ConfigError, InputError, StreamError
from burstloc.live.windows import MissingPolicy, ReadingStream, readings_of, replay
from burstloc.readings import Reading, Step

METERS = ("a", "b", "c")


def _steps(n: int, m: int = 3, dt: float = 0.2) -> list[Step]:
    rng = np.random.default_rng(n * 7 + m)
    return [Step(round(k * dt, 10), rng.normal(50.0, 1.0, m)) for k in range(n)]


def _collect(stream: ReadingStream, items) -> list:
    return list(stream.windows(items))


def test_windows_concatenate_previous_and_current_interval() -> None:
    steps = _steps(7)
    windows = _collect(ReadingStream(METERS, 2), steps)
    # 7 steps, interval 2 -> 3 windows; the 7th step waits for a partner that never comes.
    assert [w.index for w in windows] == [0, 1, 2]
    assert [w.steps for w in windows] == [2, 4, 4]
    assert [w.new for w in windows] == [2, 2, 2]
    assert [w.first_step for w in windows] == [0, 0, 2]
    np.testing.assert_array_equal(windows[1].times, [s.timestamp for s in steps[0:4]])
    np.testing.assert_array_equal(windows[2].values, np.vstack([s.values for s in steps[2:6]]))
    assert windows[2].decision_time == steps[5].timestamp
    np.testing.assert_array_equal(windows[2].column("b"), [s.values[1] for s in steps[2:6]])
    means = windows[2].means()
    assert means["c"] == pytest.approx(np.mean([s.values[2] for s in steps[2:6]]))
    assert not windows[0].values.flags.writeable


def test_step_completes_only_when_every_meter_reported() -> None:
    s = ReadingStream(METERS, 1)
    assert s.push(Reading(0.0, "c", 3.0)) == []
    assert s.push(Reading(0.0, "a", 1.0)) == []
    (w,) = s.push(Reading(0.0, "b", 2.0))
    assert w.values.tolist() == [[1.0, 2.0, 3.0]]
    assert s.stats.steps == 1 and s.stats.readings == 3


def test_readings_and_steps_give_the_same_windows() -> None:
    steps = _steps(12)
    by_steps = _collect(ReadingStream(METERS, 3), steps)
    by_readings = _collect(ReadingStream(METERS, 3), readings_of(steps, METERS))
    assert len(by_steps) == len(by_readings) == 4
    for x, y in zip(by_steps, by_readings, strict=True):
        np.testing.assert_array_equal(x.times, y.times)
        np.testing.assert_array_equal(x.values, y.values)


def test_out_of_order_readings_of_pending_steps_are_assembled() -> None:
    s = ReadingStream(METERS, 1, timeout=5)
    # step 0.2 fully arrives before step 0.0 completes: nothing is emitted until 0.0 is.
    s.push(Reading(0.0, "a", 1.0))
    for m, v in zip(METERS, (4.0, 5.0, 6.0), strict=True):
        assert s.push(Reading(0.2, m, v)) == []
    s.push(Reading(0.0, "b", 2.0))
    out = s.push(Reading(0.0, "c", 3.0))
    assert [w.times.tolist() for w in out] == [[0.0], [0.0, 0.2]]
    assert out[1].values.tolist() == [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
    assert s.stats.late == 0 and s.stats.skipped_steps == 0


def test_late_reading_is_dropped_and_counted() -> None:
    s = ReadingStream(METERS, 1)
    for st_ in _steps(2):
        s.push(st_)
    assert s.push(Reading(0.0, "a", 99.0)) == []  # step 0.0 was emitted long ago
    assert s.push(Step(0.2, np.ones(3))) == []  # so was 0.2
    assert s.stats.late == 1 + 3
    (w,) = s.push(Step(0.4, np.full(3, 7.0)))
    assert 99.0 not in w.values


def test_duplicate_reading_is_dropped_first_value_wins() -> None:
    s = ReadingStream(METERS, 1)
    s.push(Reading(0.0, "a", 1.0))
    s.push(Reading(0.0, "a", 100.0))
    s.push(Reading(0.0, "b", 2.0))
    (w,) = s.push(Reading(0.0, "c", 3.0))
    assert w.values.tolist() == [[1.0, 2.0, 3.0]]
    assert s.stats.duplicates == 1


def _missing_b_at_second_step(policy: str, timeout: int) -> tuple[ReadingStream, list]:
    s = ReadingStream(METERS, 1, timeout=timeout, missing=policy)
    windows = []
    for k in range(5):
        for j, m in enumerate(METERS):
            if k == 1 and m == "b":
                continue
            windows += s.push(Reading(k * 1.0, m, 10.0 * k + j))
    return s, windows


def test_incomplete_step_is_skipped_after_timeout() -> None:
    s, windows = _missing_b_at_second_step("skip", timeout=2)
    # step 1 blocks while 2 newer steps (2, 3) arrive; the first reading of 4 gives up on it.
    assert s.stats.skipped_steps == 1
    assert [w.decision_time for w in windows] == [0.0, 2.0, 3.0, 4.0]
    assert windows[1].times.tolist() == [0.0, 2.0]  # the gap is visible
    assert all(f == () for w in windows for f in w.filled)


def test_incomplete_step_waits_within_timeout() -> None:
    s = ReadingStream(METERS, 1, timeout=2)
    s.push(Reading(0.0, "a", 1.0))
    s.push(Step(1.0, np.ones(3)))
    s.push(Step(2.0, np.ones(3)))  # two newer steps: step 0.0 still waits
    assert s.stats.steps == 0 and s.stats.skipped_steps == 0
    s.push(Reading(0.0, "b", 1.0))
    out = s.push(Reading(0.0, "c", 1.0))  # completes 0.0, releasing 1.0 and 2.0 too
    assert [w.decision_time for w in out] == [0.0, 1.0, 2.0]
    s.push(Reading(3.0, "a", 1.0))
    s.push(Step(4.0, np.ones(3)))
    s.push(Step(5.0, np.ones(3)))
    assert s.stats.skipped_steps == 0
    s.push(Reading(6.0, "a", 1.0))  # the third newer step gives up on 3.0
    assert s.stats.skipped_steps == 1 and s.stats.steps == 5


def test_hold_policy_fills_with_last_value_and_says_so() -> None:
    s, windows = _missing_b_at_second_step("hold", timeout=0)
    assert s.stats.filled_readings == 1 and s.stats.skipped_steps == 0
    w = windows[1]
    assert w.times.tolist() == [0.0, 1.0]
    assert w.values[1].tolist() == [10.0, 1.0, 12.0]  # b held from step 0
    assert w.filled == ((), ("b",))


def test_hold_without_a_previous_value_skips() -> None:
    s = ReadingStream(METERS, 1, timeout=0, missing=MissingPolicy.HOLD)
    s.push(Reading(0.0, "a", 1.0))
    s.push(Reading(1.0, "a", 1.0))  # times out step 0.0, which cannot be held
    assert s.stats.skipped_steps == 1 and s.stats.filled_readings == 0


def test_flush_resolves_pending_steps_by_policy() -> None:
    s = ReadingStream(METERS, 1, timeout=10, missing="hold")
    s.push(Step(0.0, np.array([1.0, 2.0, 3.0])))
    s.push(Reading(1.0, "a", 5.0))
    (w,) = s.flush()
    assert w.values[-1].tolist() == [5.0, 2.0, 3.0] and w.filled[-1] == ("b", "c")


def test_unreported_step_on_a_clock_waits_then_is_skipped() -> None:
    steps = _steps(6)
    s = ReadingStream(METERS, 1, timeout=1, period=0.2)
    s.push(steps[0])
    s.push(steps[2])  # nobody reported 0.2 (yet)
    assert s.stats.steps == 1
    for r in readings_of([steps[1]], METERS):  # it arrives within the timeout
        s.push(r)
    assert s.stats.steps == 3 and s.stats.skipped_steps == 0
    s.push(steps[5])  # 0.6 and 0.8 missing; one newer step: they wait
    assert s.stats.steps == 3
    s.push(Reading(1.2, "a", 1.0))  # two newer steps: both give up
    assert s.stats.skipped_steps == 2 and s.stats.steps == 4


def test_without_a_clock_an_unheard_of_step_cannot_be_waited_for() -> None:
    steps = _steps(3)
    s = ReadingStream(METERS, 1, timeout=3)
    s.push(steps[0])
    s.push(steps[2])  # 0.2 never heard of: 0.4 goes through
    assert s.stats.steps == 2
    s.push(steps[1])
    assert s.stats.late == 3


def test_period_snaps_jittery_timestamps_to_one_step() -> None:
    s = ReadingStream(METERS, 1, period=0.2)
    s.push(Reading(0.399, "a", 1.0))
    s.push(Reading(0.4004, "b", 2.0))
    (w,) = s.push(Reading(0.41, "c", 3.0))
    assert w.decision_time == pytest.approx(0.4)


def test_unknown_meter_is_an_error_and_leaves_state_unchanged() -> None:
    s = ReadingStream(METERS, 1)
    s.push(Reading(0.0, "a", 1.0))
    before = (s.stats.readings, dict(s.feed._pending[0.0].values))
    with pytest.raises(StreamError, match="unknown meter 'zz'"):
        s.push(Reading(0.0, "zz", 1.0))
    assert (s.stats.readings, dict(s.feed._pending[0.0].values)) == before
    assert issubclass(StreamError, InputError) and issubclass(StreamError, ValueError)


@pytest.mark.parametrize(
    ("item", "match"),
    [
        (Reading(0.0, "a", float("nan")), "not finite"),
        (Reading(float("inf"), "a", 1.0), "not finite"),
        (Reading(0.0, "a", "x"), "not a number"),  # type: ignore[arg-type]
        (Step(0.0, np.array([1.0, np.inf, 2.0])), "'b'.*not finite"),
        (Step(0.0, np.ones(2)), "expected 3"),
    ],
)
def test_bad_readings_raise_stream_error(item, match: str) -> None:
    s = ReadingStream(METERS, 1)
    with pytest.raises(StreamError, match=match):
        s.push(item)
    assert s.stats.readings == 0 and not s.feed._pending


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"interval": 0}, "interval must be >= 1"),
        ({"interval": 1.5}, "must be an integer"),
        ({"interval": 1, "timeout": -1}, "timeout"),
        ({"interval": 1, "missing": "guess"}, "missing policy"),
        ({"interval": 1, "period": 0.0}, "period"),
    ],
)
def test_bad_configuration_raises_config_error(kwargs, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        ReadingStream(METERS, **kwargs)


def test_meters_must_be_distinct_and_non_empty() -> None:
    with pytest.raises(ConfigError, match="more than once"):
        ReadingStream(["a", "a"], 1)
    with pytest.raises(ConfigError, match="at least one meter"):
        ReadingStream([], 1)


def test_readings_of_a_step_before_the_first_one_heard_are_counted_late() -> None:
    steps = _steps(2)
    readings = list(readings_of(steps, METERS))
    s = ReadingStream(METERS, 1, timeout=2, period=0.2)
    got = _collect(s, readings[3:] + readings[:3])  # step 1 complete before step 0 arrives
    assert [w.times.tolist() for w in got] == [[steps[1].timestamp]]
    assert s.stats.late == 3 and s.stats.readings == 6


@given(
    n=st.integers(min_value=1, max_value=25),
    interval=st.integers(min_value=1, max_value=4),
    timeout=st.integers(min_value=0, max_value=3),
    data=st.data(),
)
def test_delays_within_the_timeout_lose_nothing(n, interval, timeout, data) -> None:
    """On a known clock, readings delayed by <= ``timeout`` steps give the in-order windows.

    The clock starts at the first reading the stream hears, so that one is of the first step
    (readings of a step before the first one heard are late: see the test below).
    """
    steps = _steps(n)
    readings = list(readings_of(steps, METERS))
    delays = data.draw(
        st.lists(st.integers(0, timeout), min_size=len(readings), max_size=len(readings))
    )
    delays[0] = 0
    order = sorted(range(len(readings)), key=lambda i: (i // 3 + delays[i], i))
    shuffled = [readings[i] for i in order]
    s = ReadingStream(METERS, interval, timeout=timeout, period=0.2)
    got = _collect(s, shuffled)
    want = _collect(ReadingStream(METERS, interval), steps)
    assert s.stats.skipped_steps == 0 and s.stats.late == 0
    assert len(got) == len(want)
    for x, y in zip(got, want, strict=True):
        np.testing.assert_array_equal(x.values, y.values)
        np.testing.assert_allclose(x.times, y.times, rtol=0, atol=1e-12)


def test_async_source_gives_the_same_windows() -> None:
    steps = _steps(9)

    async def feed():
        for r in readings_of(steps, METERS):
            await asyncio.sleep(0)
            yield r

    async def collect():
        return [w async for w in ReadingStream(METERS, 2).awindows(feed())]

    got = asyncio.run(collect())
    want = _collect(ReadingStream(METERS, 2), steps)
    assert [w.times.tolist() for w in got] == [w.times.tolist() for w in want]


def test_replay_of_captured_arrays() -> None:
    times = np.arange(5) * 0.5
    values = np.arange(15, dtype=float).reshape(5, 3)
    steps = list(replay(times, values))
    assert [s.timestamp for s in steps] == times.tolist()
    np.testing.assert_array_equal(np.vstack([s.values for s in steps]), values)
    with pytest.raises(StreamError, match="shapes"):
        list(replay(times, values[:4]))


def test_live_path_does_not_import_the_simulator() -> None:
    code = textwrap.dedent(
        """
        import sys
        import burstloc.live.windows, burstloc.localize.paper_rules, burstloc.localize.detection
        forbidden = ("burstloc.sim", "burstloc.experiments", "wntr", "tsnet")
        bad = sorted(m for m in sys.modules
                     if any(m == f or m.startswith(f + ".") for f in forbidden))
        print(",".join(bad))
        """
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == ""
