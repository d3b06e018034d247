"""burstloc.sim.scenarios.capture: sample-and-hold of a simulated timeline at a capture interval."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from burstloc.constants import METER_MODELS
from burstloc.exceptions import ConfigError, InputError
from burstloc.sim.scenarios.capture import capture, interval_average, resample, time_step_of


def test_holds_the_last_simulated_value() -> None:
    time = np.arange(11) * 0.1  # 0.0 .. 1.0
    heads = np.arange(11, dtype=float)
    ticks, samples = resample(time, heads, 0.25)
    np.testing.assert_allclose(ticks, [0.0, 0.25, 0.5, 0.75, 1.0])
    # 0.25 s holds the 0.2 s value, 0.75 s the 0.7 s value.
    np.testing.assert_array_equal(samples, [0, 2, 5, 7, 10])


def test_ticks_on_grid_points_take_that_point_despite_float_error() -> None:
    dt = 0.07742923127880359  # a TSNet time step
    time = np.arange(3000) * dt
    heads = np.arange(3000, dtype=float)
    ticks, samples = resample(time, heads, 3 * dt)
    # 3*k*dt computed two ways differs in the last bits; the reading is still sample 3k.
    np.testing.assert_array_equal(samples, 3 * np.arange(ticks.size))


def test_phase_shifts_the_capture_clock() -> None:
    time = np.arange(101) * 0.1
    heads = np.column_stack([time, -time])
    ticks, samples = resample(time, heads, 2.0, phase=0.5)
    np.testing.assert_allclose(ticks, [0.5, 2.5, 4.5, 6.5, 8.5])
    np.testing.assert_allclose(samples[:, 0], ticks)
    np.testing.assert_allclose(samples[:, 1], -ticks)


def test_interval_equal_to_the_time_step_returns_the_timeline() -> None:
    time = np.arange(50) * 0.2
    heads = np.random.default_rng(1).normal(size=(50, 3))
    ticks, samples = resample(time, heads, 0.2)
    np.testing.assert_allclose(ticks, time)
    np.testing.assert_array_equal(samples, heads)


def test_interval_finer_than_the_time_step_is_an_error() -> None:
    time = np.arange(10) * 0.5
    with pytest.raises(ConfigError, match=r"0\.2 s is finer than the simulation time step 0\.5 s"):
        resample(time, np.zeros(10), 0.2)


@pytest.mark.parametrize("interval", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_interval(interval: float) -> None:
    with pytest.raises(ConfigError, match="capture_interval"):
        resample(np.arange(5.0), np.zeros(5), interval)


@pytest.mark.parametrize("phase", [-0.1, 2.0, 2.5, float("nan")])
def test_phase_outside_one_interval(phase: float) -> None:
    with pytest.raises(ConfigError, match="phase"):
        resample(np.arange(10.0), np.zeros(10), 2.0, phase)


def test_bad_timelines() -> None:
    with pytest.raises(InputError, match="strictly increasing"):
        resample([0.0, 1.0, 1.0, 2.0], np.zeros(4), 1.0)
    with pytest.raises(InputError, match="at least 2"):
        resample([0.0], np.zeros(1), 1.0)
    with pytest.raises(InputError, match="NaN"):
        resample([0.0, np.nan], np.zeros(2), 1.0)
    with pytest.raises(InputError, match="shape"):
        resample(np.arange(5.0), np.zeros((4, 2)), 1.0)


def test_time_step_of_is_the_largest_step() -> None:
    assert time_step_of([0.0, 0.1, 0.3, 0.4]) == pytest.approx(0.2)


@given(
    dt=st.floats(0.01, 0.5),
    steps=st.integers(2, 400),
    ratio=st.floats(1.0, 20.0),
    phase_fraction=st.floats(0.0, 0.999),
)
def test_every_sample_is_the_latest_value_at_its_tick(
    dt: float, steps: int, ratio: float, phase_fraction: float
) -> None:
    time = np.arange(steps) * dt
    heads = np.arange(steps, dtype=float)  # value = index, so the sample names its source
    interval = ratio * dt
    phase = phase_fraction * interval
    assume(phase < interval)
    ticks, samples = resample(time, heads, interval, phase)
    tol = 1e-9 * max(1.0, time[-1])  # resample's float tolerance
    assert np.all((ticks >= time[0] - tol) & (ticks <= time[-1] + tol))
    if ticks.size > 1:
        np.testing.assert_allclose(np.diff(ticks), interval, rtol=1e-9)
    source = samples.astype(int)
    assert np.all(time[source] <= ticks + tol)  # held value is not from the future
    later = source + 1 < steps
    assert np.all(time[source[later] + 1] > ticks[later] + tol)  # ... and is the latest one
    # No tick inside the span is missed.
    first_missing = phase + interval * (np.floor((time[-1] - phase) / interval) + 1)
    assert first_missing > time[-1] - tol


def test_interval_average_of_a_ramp_is_the_midpoint_value() -> None:
    time = np.arange(101) * 0.1  # 0 .. 10 s
    heads = np.column_stack([2.0 * time, np.full(time.size, 3.0)])
    ticks, means = interval_average(time, heads, 2.0, phase=0.5)
    np.testing.assert_allclose(ticks, [0.5, 2.5, 4.5, 6.5, 8.5])
    # Before t = 0 the network holds its initial value (0): the first interval (-1.5, 0.5]
    # averages 0 for 1.5 s and the ramp 0 -> 1 for 0.5 s.
    np.testing.assert_allclose(means[0, 0], (0.5 * 0.5 * 1.0) / 2.0)
    np.testing.assert_allclose(means[1:, 0], 2.0 * (ticks[1:] - 1.0))
    np.testing.assert_allclose(means[:, 1], 3.0)


def test_interval_average_smooths_what_sampling_aliases() -> None:
    # A 2 s oscillation sampled every 2 s aliases to a constant offset; averaging removes it.
    time = np.arange(0, 60.0001, 0.05)
    heads = 10.0 + np.sin(2 * np.pi * time / 2.0 + 1.0)
    _, held = resample(time, heads, 2.0, phase=0.0)
    ticks, means = interval_average(time, heads, 2.0, phase=0.0)
    assert means.shape == held.shape == ticks.shape
    assert abs(float(np.mean(held[1:])) - 10.0) > 0.5
    np.testing.assert_allclose(means[1:], 10.0, atol=2e-3)


def test_interval_average_at_the_time_step_is_the_trapezoid_mean() -> None:
    time = np.arange(6) * 0.5
    heads = np.array([0.0, 1.0, 0.0, 4.0, 2.0, 2.0])
    ticks, means = interval_average(time, heads, 0.5)
    np.testing.assert_allclose(ticks, time)
    np.testing.assert_allclose(means, [0.0, 0.5, 0.5, 2.0, 3.0, 2.0])


def test_capture_selects_the_meter_model() -> None:
    time = np.arange(41) * 0.25
    heads = np.sin(time)
    for model, func in (("instantaneous", resample), ("interval-averaged", interval_average)):
        ticks, values = capture(time, heads, 1.0, 0.5, meter_model=model)
        expected_ticks, expected = func(time, heads, 1.0, 0.5)
        np.testing.assert_array_equal(ticks, expected_ticks)
        np.testing.assert_array_equal(values, expected)
    assert set(METER_MODELS) == {"instantaneous", "interval-averaged"}
    with pytest.raises(ConfigError, match="meter_model"):
        capture(time, heads, 1.0, meter_model="peak")
    with pytest.raises(ConfigError, match="capture_interval"):
        interval_average(time, heads, 0.1)
