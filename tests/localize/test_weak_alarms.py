"""Weak alarms are timed worse (burstloc.localize.timing_error): the meters' noise read before
the burst, each alarm's strength in noise levels, and what weakness does to a search region."""

from __future__ import annotations

import math

import numpy as np
import pytest

from burstloc.localize.evidence import BurstEvidence, MeterAlarm
from burstloc.localize.onset import FINEST_STEP_INTERVAL
from burstloc.localize.region import posterior
from burstloc.localize.timing_error import (
    MAX_OUTLIER,
    MIN_BASELINE,
    OUTLIER,
    STRONG_ALARM,
    alarm_strengths,
    alarm_weakness,
    baseline_noise,
    timing_penalty,
    weak_alarms,
)
from line_network import METERS, WAVE, line_arrival


def test_the_noise_before_the_burst_is_read_through_a_slow_trend() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 30.0, 0.1)
    sigma = np.array([0.01, 0.05])
    values = rng.standard_normal((t.size, 2)) * sigma + 0.2 * t[:, None]  # a rising demand
    values[t > 20.0] -= 3.0  # the burst's drop, after the onset: not noise
    noise = baseline_noise(t, values, onset=20.0)
    assert noise == pytest.approx(sigma, rel=0.15)
    # too few readings before the onset to tell: unknown
    assert np.isnan(baseline_noise(t, values, onset=t[MIN_BASELINE - 2])).all()


def test_strength_is_amplitude_over_noise_and_unknown_noise_counts_as_strong() -> None:
    strengths = alarm_strengths(np.array([-0.1, 0.3, -0.2]), np.array([0.01, np.nan, 0.0]))
    assert strengths[0] == pytest.approx(10.0)
    assert np.isinf(strengths[1:]).all()


def test_weak_alarms_are_widened_and_more_often_outliers_strong_ones_are_not() -> None:
    widening, outlier = weak_alarms(np.array([np.inf, STRONG_ALARM, STRONG_ALARM / 2, 0.5]))
    assert widening[:2].tolist() == [1.0, 1.0] and outlier[:2].tolist() == [OUTLIER, OUTLIER]
    assert widening[2] == pytest.approx(2.0) and outlier[2] == pytest.approx(4 * OUTLIER)
    assert widening[3] == pytest.approx(STRONG_ALARM / 0.5) and outlier[3] == MAX_OUTLIER
    # a larger outlier chance costs a large misfit less and a small one more
    far, near = np.array([2.0]), np.array([0.0])
    assert timing_penalty(far, 0.1, 10.0, 0.2) < timing_penalty(far, 0.1, 10.0, OUTLIER)
    assert timing_penalty(near, 0.1, 10.0, 0.2) == pytest.approx(0.0)


def _evidence(late: float, far_amplitude: float, dt: float = 0.2) -> BurstEvidence:
    """A burst 900 m along the line at t = 1 s, read with 0.01 m of noise; every meter's change
    0.5 m but the farthest one's (``far_amplitude``), whose alarm starts ``late`` s late."""
    rng = np.random.default_rng(1)
    alarms = {}
    for i, m in enumerate(METERS):
        arrive = 1.0 + abs(900.0 - 600.0 * i) / WAVE + (late if i == 3 else 0.0)
        amplitude = far_amplitude if i == 3 else -0.5
        alarms[m] = MeterAlarm(m, math.floor(arrive / dt - 1e-9) * dt, amplitude)
    t = np.arange(-10.0, 4.0, dt)
    return BurstEvidence(
        meters=METERS,
        times=t,
        readings=0.01 * rng.standard_normal((t.size, len(METERS))),
        onset=min(a.start for a in alarms.values()),
        capture_interval=dt,
        alarms=alarms,
    )


def test_the_evidence_s_alarms_are_weighed_by_their_strength() -> None:
    widening, outlier = alarm_weakness(_evidence(0.0, -0.07), list(METERS))
    assert widening[:3] == pytest.approx(1.0) and outlier[:3] == pytest.approx(OUTLIER)
    assert widening[3] == pytest.approx(STRONG_ALARM / 7.0, rel=0.2) and outlier[3] > OUTLIER
    # at 0.02 s and finer a change's start is fitted to the readings: every alarm as stated
    widening, outlier = alarm_weakness(_evidence(0.0, -0.07, dt=FINEST_STEP_INTERVAL), METERS)
    assert widening.tolist() == [1.0] * 4 and outlier.tolist() == [OUTLIER] * 4


def _near(late: float, far_amplitude: float) -> tuple[float, float]:
    """(probability within 100 m of the burst, distance from it of the densest point)."""
    post = posterior(line_arrival(), _evidence(late, far_amplitude))
    grid = post.grid
    x = 600.0 * grid.pipe + 0.5 * (grid.low + grid.high)
    best = x[int(np.argmax(post.probability / grid.length))]
    return float(post.probability[np.abs(x - 900.0) < 100.0].sum()), abs(best - 900.0)


def test_a_weak_alarm_late_by_a_second_pulls_the_region_less_than_a_strong_one() -> None:
    weak_mass, weak_miss = _near(1.0, -0.07)  # 7 noise levels: often not the first wave
    strong_mass, strong_miss = _near(1.0, -0.5)
    assert weak_mass > 1.3 * strong_mass and weak_miss < strong_miss - 100.0
    # on time, a weak alarm costs the region little of what it holds near the burst
    assert _near(0.0, -0.07)[0] > 0.85 * _near(0.0, -0.5)[0]
