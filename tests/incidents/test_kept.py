"""burstloc.incidents.kept: the readings around each alarm, held on the monitor's thread,
handed on once claimed and complete, written as a feed the monitor (and calibration) reads, in
pieces, every number as ``repr`` writes it (``burstloc._core.feed_lines``), steps that do not
fit their meters refused by type; and through the recorder, the readings of a real burst kept
on its incident, on SQLite and PostgreSQL."""

from __future__ import annotations

import io
import math
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from burstloc._core import feed_lines
from burstloc.exceptions import InputError
from burstloc.incidents import IncidentStore, kept
from burstloc.incidents.kept import AFTER, BEFORE, CAPTURES, Capture, ReadingsKeeper, write_feed
from burstloc.incidents.recorder import Recorder
from burstloc.live.monitor import BurstMonitor
from burstloc.live.parse import parse_lines
from burstloc.localize.config import Calibration
from burstloc.readings import Reading, Step

sys.path.insert(0, str(Path(__file__).parents[1] / "live"))  # live_feed: a real burst

METERS = ("M1", "M2")


def _steps(start: float, stop: float, dt: float = 0.5) -> list[Step]:
    return [Step(t, np.array([t, -t])) for t in np.round(np.arange(start, stop, dt), 6).tolist()]


def _keeper() -> tuple[ReadingsKeeper, list[Capture]]:
    handed: list[Capture] = []
    return ReadingsKeeper(handed.append), handed


def test_a_claimed_capture_holds_before_the_onset_to_after_the_newest_alarm() -> None:
    keeper, handed = _keeper()
    for step in _steps(0.0, 200.0):
        keeper.step(step)
        if step.timestamp == 100.0:
            keeper.alarm(100.0, 98.5)  # the first meter, its change after 98.5 s
        if step.timestamp == 103.0:
            keeper.alarm(103.0, 101.0)  # the second, later: the capture runs on
            keeper.claim("alarm:100.000000", 100.0)  # its record
            assert not handed  # not complete yet
    (capture,) = handed
    times = [s.timestamp for s in capture.steps]
    assert times[0] == 98.5 - BEFORE and times[-1] == 103.0 + AFTER
    assert np.allclose(np.diff(times), 0.5)  # none missing, none twice
    assert capture.onset == 98.5 and capture.key == "alarm:100.000000"
    keeper.flush()
    assert len(handed) == 1  # handed on once


def test_a_record_after_the_capture_is_complete_claims_it_then() -> None:
    keeper, handed = _keeper()
    for step in _steps(0.0, 60.0):
        keeper.step(step)
        if step.timestamp == 10.0:
            keeper.alarm(10.0, 9.0)
    assert not handed
    keeper.claim("alarm:10.000000", 10.0)
    (capture,) = handed
    assert capture.steps[0].timestamp == 0.0  # the feed began 9 s before the onset
    assert capture.steps[-1].timestamp == 10.0 + AFTER


def test_unclaimed_captures_are_let_go_and_a_record_of_none_changes_nothing() -> None:
    keeper, handed = _keeper()
    stamps = [10.0 + 100.0 * k for k in range(CAPTURES + 3)]
    for step in _steps(0.0, stamps[-1] + 50.0):
        keeper.step(step)
        if step.timestamp in stamps:
            keeper.alarm(step.timestamp, step.timestamp - 1.0)  # a lone meter, dismissed
    keeper.claim("alarm:10.000000", 10.0)  # the first capture was let go
    keeper.claim("alarm:55.000000", 55.0)  # no alarm at 55 s
    keeper.flush()
    assert not handed
    keeper.claim(f"alarm:{stamps[-1]:.6f}", stamps[-1])
    assert [c.first for c in handed] == [stamps[-1]]


def test_at_the_stop_a_claimed_capture_is_handed_with_what_it_holds() -> None:
    keeper, handed = _keeper()
    for step in _steps(0.0, 20.0):
        keeper.step(step)
        if step.timestamp == 15.0:
            keeper.alarm(15.0, 14.0)
            keeper.claim("alarm:15.000000", 15.0)
    assert not handed
    keeper.flush()
    (capture,) = handed
    assert capture.steps[-1].timestamp == 19.5


def test_the_feed_file_is_what_the_monitor_reads_without_the_filled_values(
    tmp_path: Path,
) -> None:
    steps = [
        Step(1.0, np.array([50.0, 40.0])),
        Step(1.2, np.array([49.123456789, 40.5]), filled=("M2",)),
        Step(1.4, np.array([float("nan"), 39.0])),
    ]
    capture = Capture(1.2, 1.4, steps, [(1.2, 1.0)], complete=True, key="alarm:1.200000")
    capture.first_alarm = 1.2
    kept = write_feed(capture, METERS, tmp_path / "readings")
    assert kept.key == "alarm:1.200000" and kept.onset == 1.0
    path = Path(kept.path)
    assert path.is_absolute() and path.parent == (tmp_path / "readings").resolve()
    text = path.read_text(encoding="utf-8")
    assert text.splitlines()[0] == "timestamp,meter,value"
    read = [r for r in parse_lines(io.StringIO(text)) if isinstance(r, Reading)]
    assert [(r.timestamp, r.meter, r.value) for r in read] == [
        (1.0, "M1", 50.0), (1.0, "M2", 40.0), (1.2, "M1", 49.123456789), (1.4, "M2", 39.0),
    ]  # fmt: skip


def test_a_long_capture_is_written_in_chunks_every_value_read_back_exactly(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(kept, "CHUNK", 40)  # 13 steps of 3 meters a piece: 16 pieces
    rng = np.random.default_rng(11)
    meters = ("N2", "J-17", "meter 3")
    sent = np.round(40.0 + 30.0 * rng.random((200, 3)), 4)  # as meters send them
    sent[::7, 1] = 40.0 + rng.random(29)  # full doubles, every digit
    sent[5] = [-0.0, -12.5, 1e-9]
    sent[6] = [np.nan, np.inf, 2.0**60 + 2048.0]
    steps = [
        Step(round(1_800_000_000.0 + k / 250, 3), sent[k], ("N2",) if k % 50 == 3 else ())
        for k in range(200)
    ]
    capture = Capture(steps[40].timestamp, steps[-1].timestamp, steps, [], complete=True)
    capture.key = "alarm:long"
    path = Path(write_feed(capture, meters, tmp_path).path)
    lines = path.read_text(encoding="utf-8").splitlines()
    with path.open(encoding="utf-8") as text:  # each value to the bit (-0.0 keeps its sign)
        read = [(r.timestamp, r.meter, struct.pack("<d", r.value)) for r in parse_lines(text)]
    wanted = [
        (s.timestamp, m, struct.pack("<d", v))
        for s in steps
        for m, v in zip(meters, s.values.tolist(), strict=True)
        if m not in s.filled and np.isfinite(v)
    ]
    assert read == wanted and len(lines) == 1 + len(wanted)  # in order, none twice
    assert (steps[5].timestamp, "N2", struct.pack("<d", -0.0)) in read
    # a reading as sent is written as repr writes it (the file is the same as before)
    assert lines[1] == f"{float(steps[0].timestamp)!r},N2,{float(sent[0, 0])!r}"
    assert lines[3] == f"{float(steps[0].timestamp)!r},meter 3,{float(sent[0, 2])!r}"


def test_a_step_without_one_value_per_meter_is_refused_and_no_file_is_left(
    tmp_path: Path,
) -> None:
    steps = [Step(1.0, np.array([50.0, 40.0])), Step(1.2, np.array([49.0]))]
    capture = Capture(1.0, 1.2, steps, [(1.0, 0.8)], complete=True, key="alarm:1.000000")
    with pytest.raises(InputError, match="a step with 1 values for 2 meters"):
        write_feed(capture, METERS, tmp_path / "readings")
    assert list((tmp_path / "readings").iterdir()) == []


def test_every_number_is_written_as_repr_writes_it() -> None:
    rng = np.random.default_rng(5)
    drawn = rng.integers(0, 2**64 - 1, 60_000, dtype=np.uint64).view(np.float64)  # any bits
    sent = np.round(40.0 + 30.0 * rng.random(20_000), 4)  # as meters send them
    tens = [10.0**k for k in range(-20, 24)]
    edges = [0.0, 5e-324, 2.2250738585072014e-308, 1.7976931348623157e308, 0.1 + 0.2]
    edges += [2.0**53, 2.0**53 + 2, 1e-4, 1e-5, 1e16, 9999999999999998.0, 2.0**60 + 2048.0]
    edges += tens + [float(np.nextafter(t, 0.0)) for t in tens]
    edges += [float(np.nextafter(t, np.inf)) for t in tens]
    edges += [2.0**k for k in range(-1074, 1024, 7)]
    values = np.concatenate([drawn, sent, edges, -np.array(edges)])
    values = values[np.isfinite(values)].tolist()
    steps = [Step(v, np.array([v])) for v in values]  # each a timestamp too
    lines = feed_lines(steps, ["m"]).decode("ascii").splitlines()
    assert lines == [f"{v!r},m,{v!r}" for v in values]
    assert "-0.0,m,-0.0" in lines and "1e+16,m,1e+16" in lines and "1e-05,m,1e-05" in lines


def test_values_are_read_from_any_array_or_list_of_numbers() -> None:
    meters = ["a", "b", "c"]
    columns = np.array([[1.5, 0.0], [2.5, 0.0], [-3.25, 0.0]])
    forms = [
        np.array([1.5, 2.5, -3.25]),
        columns[:, 0],  # not contiguous
        np.array([1.5, 2.5, -3.25], dtype=np.float32),
        [1.5, 2.5, -3.25],
        (1.5, 2.5, -3.25),
    ]
    for values in forms:
        got = feed_lines([Step(0.2, values, ("b", "not a meter"))], meters)  # type: ignore[arg-type]
        assert got == b"0.2,a,1.5\n0.2,c,-3.25\n"
    assert feed_lines([Step(7.0, np.array([1, 2, 3]))], meters) == (
        b"7.0,a,1.0\n7.0,b,2.0\n7.0,c,3.0\n"
    )
    assert feed_lines([], meters) == b""


def test_steps_that_do_not_fit_their_meters_are_refused_by_type() -> None:
    two = np.array([1.0, 2.0])
    with pytest.raises(InputError, match="a step with 3 values for 2 meters"):
        feed_lines([Step(1.0, two), Step(1.2, np.zeros(3))], METERS)
    with pytest.raises(InputError, match=r"steps\[1\] has no timestamp"):
        feed_lines([Step(1.0, two), (1.2, two)], METERS)  # type: ignore[list-item]
    with pytest.raises(InputError, match="step 1 has a timestamp that is not a finite number"):
        feed_lines([Step(1.0, two), Step(math.inf, two)], METERS)
    with pytest.raises(InputError, match=r"steps\[0\]\.values must be numbers"):
        feed_lines([Step(1.0, "ab")], METERS)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        feed_lines([Step(1.0, two)], "M1")  # a str is not a list of meters


def test_a_real_bursts_readings_are_kept_on_its_incident(
    tiny: Path,
    tiny_config: Calibration,
    tiny_feed: list[Reading],
    target: str,
    tmp_path: Path,
) -> None:
    from live_feed import Collected

    store = IncidentStore.open(target)
    said: list[str] = []
    monitor = BurstMonitor(tiny, tiny_config, capture_interval=0.2)
    recorder = Recorder(store, said.append, meters=monitor.meters, readings=tmp_path / "readings")
    done = Collected(monitor, observer=recorder, health_every=0).run(tiny_feed)
    recorder.close()
    try:
        (decision,) = done.decisions
        (row,) = [r for r in store.incidents() if r["kind"] == "burst"]
        assert row["alarmed"] == decision["alarmed"] and len(row["alarmed"]) >= 2
        first = decision["first_alarm"]
        assert first - 5.0 < row["onset"] < first  # the change began before the first alarm
        path = Path(row["readings"])
        assert path.parent == (tmp_path / "readings").resolve()
        with path.open(encoding="utf-8") as lines:
            kept = [r for r in parse_lines(lines) if isinstance(r, Reading)]
        stamps = [round(r.timestamp, 6) for r in kept]
        # from BEFORE s before the onset to at least AFTER s after the first alarm
        assert stamps[0] == pytest.approx(row["onset"] - BEFORE, abs=0.2 + 1e-6)
        assert stamps[-1] >= first + AFTER - 1e-6
        wanted = [r for r in tiny_feed if stamps[0] - 1e-6 <= r.timestamp <= stamps[-1] + 1e-6]
        assert [(t, r.meter, r.value) for t, r in zip(stamps, kept, strict=True)] == [
            (round(r.timestamp, 6), r.meter, r.value) for r in wanted
        ]  # every reading of the span, exactly
        assert not said
    finally:
        store.close()
