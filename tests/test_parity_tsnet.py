"""Parity of the batch references with their sources.

``burstloc.detect_cusum`` must return exactly what TSNet 0.3.1's own
``tsnet.postprocessing.detect_cusum(time, x, threshold, drift, show=False, ending=...)``
returns, post-processing quirks included (TSNet is the oracle here, imported only by tests);
``burstloc.detect_shewhart`` must agree exactly with the transcription of Algorithm 2 in
``reference.py`` (NumPy's mean and std, as in the paper's code).

Parity is checked over the parameter domain burstloc accepts (finite samples, threshold > 0,
drift >= 0). Outside it TSNet returns something rather than raising (a NaN simply never
alarms, a negative threshold alarms at every step); burstloc raises ``InputError`` /
``ConfigError`` instead, which ``test_outside_the_domain_we_raise_where_tsnet_answers`` pins.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from tsnet.postprocessing import detect_cusum as tsnet_detect_cusum

import burstloc
from reference import shewhart_batch
from signals import build_signal, cusum_parameters, pressure_signals


def tsnet(x: np.ndarray, threshold: float, drift: float, ending: bool):
    time = np.arange(x.size) * 0.01
    return tsnet_detect_cusum(time, x, threshold, drift, show=False, ending=ending)


def assert_same_changes(x: np.ndarray, threshold: float, drift: float, ending: bool) -> None:
    time = np.arange(x.size) * 0.01
    start, end, amplitude = burstloc.detect_cusum(time, x, threshold, drift, ending=ending)
    t_start, t_end, t_amplitude = tsnet(x, threshold, drift, ending)
    assert start.dtype == np.int64 and end.dtype == np.int64
    assert amplitude.dtype == np.float64
    np.testing.assert_array_equal(start, t_start)
    np.testing.assert_array_equal(end, t_end)
    assert amplitude.shape == t_amplitude.shape
    np.testing.assert_allclose(amplitude, t_amplitude, rtol=0.0, atol=1e-9)


@settings(
    max_examples=120,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(data=st.data(), ending=st.booleans())
def test_detect_cusum_matches_tsnet(data: st.DataObject, ending: bool) -> None:
    x = data.draw(pressure_signals())
    threshold, drift = data.draw(cusum_parameters(x))
    assert_same_changes(x, threshold, drift, ending)


@pytest.mark.parametrize("ending", [True, False])
@pytest.mark.parametrize(
    "x",
    [
        np.array([]),
        np.array([3.0]),
        np.array([1.0, 1.0]),
        np.array([0.0, 5.0]),
        np.array([5.0, 0.0]),
        np.zeros(10_000),
        np.r_[np.full(50, 80.0), np.full(50, 79.0), np.full(50, 80.0)],
        np.r_[np.full(10, 1e-6), np.full(10, 3e-6)],
        np.r_[np.full(10, 1e6), np.full(10, 1e6 + 3.0)],
        np.sin(np.linspace(0.0, 60.0, 3_000)) * 2.0 + 50.0,
    ],
    ids=["empty", "single", "flat2", "up2", "down2", "flat10k", "plateau", "tiny", "huge", "wave"],
)
def test_detect_cusum_matches_tsnet_on_hand_picked_signals(x: np.ndarray, ending: bool) -> None:
    scale = (float(np.ptp(x)) if x.size else 0.0) or 1.0
    for fraction in (0.05, 0.5, 0.99):
        for drift in (0.0, 0.01 * scale):
            assert_same_changes(x, fraction * scale, drift, ending)


def _size_mismatch(x: np.ndarray, threshold: float, drift: float) -> str:
    """Which of TSNet's start/end reconciliation branches ``x`` takes ("", "<" or ">")."""
    starts, _, _ = tsnet(x, threshold, drift, ending=False)
    if starts.size == 0:
        return ""
    reverse, _, _ = tsnet(x[::-1], threshold, drift, ending=False)
    unique = np.unique(starts).size
    return "<" if unique < reverse.size else ">" if unique > reverse.size else ""


def test_detect_cusum_matches_tsnet_in_both_reconciliation_branches() -> None:
    """TSNet reconciles unequal numbers of starts and ends with ``argmax`` look-ups.

    Those branches (``tai.size < taf.size`` and ``>``) are where its quirks live, so this test
    makes sure both are taken, on seeded noisy random walks, and that we still agree.
    """
    seen = {"<": 0, ">": 0, "": 0}
    for seed in range(300):
        rng = np.random.default_rng(seed)
        x = np.cumsum(rng.normal(0.0, 1.0, 200)) + rng.choice([0.0, 5.0], 200)
        threshold = float(rng.uniform(0.5, 6.0))
        drift = float(rng.choice([0.0, 0.2, 0.5]))
        seen[_size_mismatch(x, threshold, drift)] += 1
        for ending in (True, False):
            assert_same_changes(x, threshold, drift, ending)
    assert seen["<"] > 0 and seen[">"] > 0, seen


@given(
    x=pressure_signals(max_size=2_000),
    sigma=st.floats(min_value=0.5, max_value=4.0),
    threshold_fraction=st.floats(min_value=0.0, max_value=0.5),
)
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@example(x=np.r_[np.full(100, 50.0), np.full(100, 45.0)], sigma=1.0, threshold_fraction=0.1)
def test_detect_shewhart_matches_algorithm_2(
    x: np.ndarray, sigma: float, threshold_fraction: float
) -> None:
    threshold = threshold_fraction * float(np.ptp(x)) + 1e-12
    index, amplitude = burstloc.detect_shewhart(x, sigma, threshold)
    assert index.dtype == np.int64 and amplitude.dtype == np.float64
    decisions = shewhart_batch(x, sigma, threshold)
    expected = [d for d in decisions if d.alarm]
    np.testing.assert_array_equal(index, [d.index for d in expected])
    np.testing.assert_array_equal(amplitude, [abs(d.deviation) for d in expected])


def test_detect_shewhart_flags_the_burst_samples() -> None:
    x = np.r_[np.full(100, 50.0), np.full(10, 40.0)]
    index, amplitude = burstloc.detect_shewhart(x, 2.0, 1.0)
    mean = x.mean()
    np.testing.assert_array_equal(index, np.arange(100, 110))
    np.testing.assert_allclose(amplitude, np.abs(x[100:] - mean))


def test_outside_the_domain_we_raise_where_tsnet_answers() -> None:
    x = build_signal(200, 50.0, 1.0, [("step", 100, -3.0)], 0.01, 0)
    time = np.arange(x.size, dtype=float)
    bad = x.copy()
    bad[120] = np.nan
    # TSNet silently returns a result for a NaN sample...
    tsnet(bad, 1.0, 0.0, ending=True)
    # ... we name it instead.
    with pytest.raises(burstloc.InputError, match="120"):
        burstloc.detect_cusum(time, bad, 1.0, 0.0)
    with pytest.raises(burstloc.InputError, match="inf at index 200"):
        burstloc.detect_cusum(np.r_[time, 200.0], np.r_[x, np.inf], 1.0, 0.0)
    tsnet(x, -1.0, 0.0, ending=True)
    with pytest.raises(burstloc.ConfigError, match="threshold"):
        burstloc.detect_cusum(time, x, -1.0, 0.0)
    with pytest.raises(burstloc.ConfigError, match="drift"):
        burstloc.detect_cusum(time, x, 1.0, -0.5)
    with pytest.raises(burstloc.InputError, match="same length"):
        burstloc.detect_cusum(time[:-1], x, 1.0, 0.0)
    with pytest.raises(burstloc.InputError, match="float64"):
        burstloc.detect_cusum(time, x.astype(np.float32), 1.0, 0.0)
    with pytest.raises(burstloc.InputError, match="shape"):
        burstloc.detect_shewhart(x.reshape(20, 10), 1.0, 1.0)
    with pytest.raises(burstloc.InputError, match="list"):
        burstloc.detect_shewhart(x.tolist(), 1.0, 1.0)
