"""Detection per window: the paper's batch call and the streaming bank, against the oracles."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from burstloc.exceptions import ConfigError, StreamError
from burstloc.live.windows import ReadingStream
from burstloc.localize.detection import (
    BatchDetector,
    DetectorConfig,
    Mode,
    StreamingDetector,
    make_detector,
)
from burstloc.readings import Step
from reference import cusum_online, shewhart_batch, shewhart_streaming

METERS = ("a", "b", "c")
DT = 0.2


def burst_like(n: int = 40, at: int = 17, seed: int = 0) -> np.ndarray:
    """Three meters: a sharp drop at ``at`` (a: -6 m, b: -3 m one step later, c: none)."""
    rng = np.random.default_rng(seed)
    x = np.full((n, 3), 190.0) + rng.normal(0.0, 0.01, (n, 3))
    x[at:, 0] -= 6.0
    x[at + 1 :, 1] -= 3.0
    return x


def windows_of(values: np.ndarray, interval: int) -> list:
    steps = [Step(round(k * DT, 10), values[k]) for k in range(values.shape[0])]
    return list(ReadingStream(METERS, interval).windows(steps))


def test_config_validation() -> None:
    with pytest.raises(ConfigError, match="unknown detector 'ewma'"):
        DetectorConfig("ewma", 1.0)
    with pytest.raises(ConfigError, match="threshold"):
        DetectorConfig("cusum", -1.0)
    with pytest.raises(ConfigError, match="threshold"):
        DetectorConfig("cusum", float("nan"))
    with pytest.raises(ConfigError, match="drift"):
        DetectorConfig("cusum", 1.0, drift=-0.1)
    with pytest.raises(ConfigError, match="sigma"):
        DetectorConfig("shewhart", 1.0, sigma=0.0)
    with pytest.raises(ConfigError, match="CUSUM only"):
        DetectorConfig("shewhart", 1.0, drift=0.5)
    with pytest.raises(ConfigError, match="Shewhart chart only"):
        DetectorConfig("cusum", 1.0, sigma=2.0)
    sh = DetectorConfig("shewhart", 1.5)
    assert sh.effective_sigma == 1.5 and sh.params() == {"threshold": 1.5, "sigma": 1.5}
    assert DetectorConfig("shewhart", 1.5, sigma=3.0).effective_sigma == 3.0
    assert DetectorConfig("cusum", 0.3).params() == {"threshold": 0.3, "drift": 0.0}


def test_make_detector_modes() -> None:
    cfg = DetectorConfig("cusum", 0.3)
    assert isinstance(make_detector(cfg, METERS, 5), BatchDetector)
    assert isinstance(make_detector(cfg, METERS, 5, "stream"), StreamingDetector)
    assert make_detector(cfg, METERS, 5, Mode.STREAM).mode is Mode.STREAM
    with pytest.raises(ConfigError, match="unknown detection mode 'online'"):
        make_detector(cfg, METERS, 5, "online")
    with pytest.raises(ConfigError, match=">= 1"):
        make_detector(cfg, METERS, 0, "stream")


def test_batch_cusum_is_tsnet_detect_cusum_on_the_concatenated_window() -> None:
    from tsnet.postprocessing.detect_cusum import detect_cusum as tsnet_cusum

    values = burst_like()
    det = BatchDetector(DetectorConfig("cusum", 0.3, drift=0.01), METERS)
    windows = windows_of(values, 5)
    alarmed = 0
    for w in windows:
        got = det.detect(w)
        for j, m in enumerate(METERS):
            s, e, amp = tsnet_cusum(w.times, w.values[:, j], 0.3, 0.01, False, ending=True)
            want = [(w.times[a], w.times[b], x) for a, b, x in zip(s, e, amp, strict=True)]
            have = [(c.start_time, c.end_time, c.amplitude) for c in got[m]]
            assert have == want
            alarmed += bool(have)
    assert alarmed >= 2  # the drop at a and b is found (in two overlapping windows each)


def test_batch_shewhart_is_algorithm_2_on_the_concatenated_window() -> None:
    values = burst_like()
    det = BatchDetector(DetectorConfig("shewhart", 1.5), METERS)
    found = 0
    for w in windows_of(values, 5):
        got = det.detect(w)
        for j, m in enumerate(METERS):
            ref = [d for d in shewhart_batch(list(w.values[:, j]), 1.5, 1.5) if d.alarm]
            assert [c.start_time for c in got[m]] == [w.times[d.index] for d in ref]
            np.testing.assert_allclose(
                [c.amplitude for c in got[m]], [abs(d.deviation) for d in ref], rtol=1e-12
            )
            found += len(ref)
    assert found > 0


def test_batch_detection_forgets_between_windows() -> None:
    w = windows_of(burst_like(), 5)[3]
    det = BatchDetector(DetectorConfig("cusum", 0.3), METERS)
    first = det.detect(w)
    assert det.detect(w) == first


def _stream_alarms(det: StreamingDetector, values: np.ndarray, interval: int):
    out = []
    for w in windows_of(values, interval):
        for m, cs in det.detect(w).items():
            out += [(m, c.alarm_time, c.start_time, c.amplitude) for c in cs]
    return sorted(out, key=lambda t: (t[1], METERS.index(t[0])))


def _reference_stream(values: np.ndarray, n: int, fn) -> list:
    out = []
    for j, m in enumerate(METERS):
        for a in fn(list(values[:n, j])):
            out.append((m, round(a[0] * DT, 10), round(a[1] * DT, 10), a[2]))
    return sorted(out, key=lambda t: (t[1], METERS.index(t[0])))


@given(interval=st.integers(1, 7), seed=st.integers(0, 1000), at=st.integers(1, 35))
def test_streaming_cusum_is_the_online_cusum_over_the_whole_stream(interval, seed, at) -> None:
    """Whatever the window length, stream mode reports the online pass's alarms, each once."""
    values = burst_like(at=at, seed=seed)
    det = StreamingDetector(DetectorConfig("cusum", 0.3, drift=0.005), METERS, interval)
    got = _stream_alarms(det, values, interval)
    n = (values.shape[0] // interval) * interval  # the steps that made it into windows

    def online(x):
        return [(a.index, a.start, a.amplitude) for a in cusum_online(x, 0.3, 0.005)]

    want = _reference_stream(values, n, online)
    assert [g[:3] for g in got] == [w[:3] for w in want]
    np.testing.assert_allclose([g[3] for g in got], [w[3] for w in want], rtol=1e-12)
    if at < n:  # a burst in the trailing steps that fill no window is never seen
        assert any(g[0] == "a" for g in got)


def test_streaming_shewhart_uses_a_trailing_window_of_two_intervals() -> None:
    values = burst_like()
    interval = 4
    det = StreamingDetector(DetectorConfig("shewhart", 1.5), METERS, interval)
    got = _stream_alarms(det, values, interval)

    def trailing(x):
        return [
            (d.index, d.index, d.deviation)
            for d in shewhart_streaming(x, 2 * interval, 1.5, 1.5)
            if d.alarm
        ]

    want = _reference_stream(values, values.shape[0], trailing)
    assert [g[:3] for g in got] == [w[:3] for w in want]
    np.testing.assert_allclose([g[3] for g in got], [w[3] for w in want], rtol=1e-9)
    assert got and got[0][0] == "a"


def test_streaming_reset_forgets_state() -> None:
    values = burst_like()
    det = StreamingDetector(DetectorConfig("cusum", 0.3), METERS, 5)
    first = _stream_alarms(det, values, 5)
    det.reset()
    assert _stream_alarms(det, values, 5) == first


def test_window_with_other_meters_is_rejected() -> None:
    w = windows_of(burst_like(), 5)[0]
    for det in (
        BatchDetector(DetectorConfig("cusum", 0.3), ("a", "b", "x")),
        StreamingDetector(DetectorConfig("cusum", 0.3), ("a", "b", "x"), 5),
    ):
        with pytest.raises(StreamError, match="differ"):
            det.detect(w)
