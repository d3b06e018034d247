"""What pressure meters transmit: a simulated timeline sampled every capture interval.

A meter with capture interval Δ transmits, at each tick of its clock, the latest value of the
pressure it measures: sample-and-hold of the simulated timeline. The clock ticks at
``phase + k·Δ`` (k = 0, 1, ...), inside the simulated span. With a burst starting at time
``t_b``, the offset of the capture clock relative to the burst is ``(phase - t_b) mod Δ``:
sweeping ``phase`` over ``[0, Δ)`` moves the readings relative to the burst onset without
simulating again.

Pure NumPy: no simulator import (the live path may use it).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

# What a meter transmits at each tick: the pressure at that instant (the paper's model) or the
# mean pressure over the capture interval that ends at the tick (what most loggers report).
from burstloc.constants import METER_MODELS
from burstloc.exceptions import ConfigError, InputError

__all__ = [
    "capture",
    "interval_average",
    "resample",
    "time_step_of",
]


def time_step_of(time: ArrayLike) -> float:
    """Return the largest step of a strictly increasing timeline (the simulation's time step).

    Raises:
        InputError: fewer than two times, non-finite times, or times not strictly increasing.
    """
    t = np.asarray(time, dtype=np.float64)
    if t.ndim != 1 or t.size < 2:
        raise InputError(f"time must be 1-D with at least 2 entries, got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise InputError("time contains NaN or infinite values")
    steps = np.diff(t)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0)) + 1
        raise InputError(f"time must be strictly increasing; time[{bad}] = {t[bad]!r}")
    return float(steps.max())


def resample(
    time: ArrayLike, heads: ArrayLike, capture_interval: float, phase: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sample-and-hold a simulated timeline at a capture interval.

    Args:
        time: simulated times, shape ``(T,)``, strictly increasing (TSNet's grid).
        heads: values at those times, shape ``(T,)`` or ``(T, M)`` (one column per meter).
        capture_interval: Δ in seconds; must not be finer than the simulation's time step.
        phase: the capture clock's first tick, in ``[0, Δ)``; ticks are ``phase + k·Δ``.

    Returns:
        ``(sample_times, samples)``: the ticks inside ``[time[0], time[-1]]`` and, for each,
        the row of ``heads`` at the last simulated time at or before the tick.

    Raises:
        ConfigError: Δ is not a positive finite number or is finer than the time step; phase is
            outside ``[0, Δ)``.
        InputError: malformed ``time`` or ``heads``.
    """
    t = np.asarray(time, dtype=np.float64)
    dt = time_step_of(t)
    values = np.asarray(heads, dtype=np.float64)
    if values.ndim not in (1, 2) or values.shape[0] != t.size:
        raise InputError(
            f"heads must have shape ({t.size},) or ({t.size}, M) to match time, got {values.shape}"
        )
    delta = float(capture_interval)
    if not (math.isfinite(delta) and delta > 0):
        raise ConfigError(f"capture_interval must be a positive number, got {capture_interval!r}")
    if delta < dt * (1 - 1e-9):
        raise ConfigError(
            f"capture_interval {delta:g} s is finer than the simulation time step {dt:g} s; "
            "simulate with a smaller time_step or capture less often"
        )
    offset = float(phase)
    if not (math.isfinite(offset) and 0 <= offset < delta):
        raise ConfigError(f"phase must be in [0, {delta:g}), got {phase!r}")
    # Absorbs float error between k·Δ and the simulation's k·dt grid (far below any time step).
    tol = 1e-9 * max(1.0, abs(float(t[-1])))
    first = math.ceil((t[0] - offset - tol) / delta)
    last = math.floor((t[-1] - offset + tol) / delta)
    ticks = offset + delta * np.arange(first, last + 1, dtype=np.float64)
    index = np.searchsorted(t, ticks + tol, side="right") - 1
    return ticks, values[index].copy()


def interval_average(
    time: ArrayLike, heads: ArrayLike, capture_interval: float, phase: float = 0.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Interval-averaged readings: at each tick of :func:`resample`, the mean of the timeline
    over ``(tick - Δ, tick]``.

    The timeline is integrated with the trapezoid rule (linear between simulated points). Before
    ``time[0]`` the network is taken to be in its initial state (the first row of ``heads``), so
    an interval reaching back before the simulation averages that value there: exact for a
    simulation that starts from a steady state, as TSNet's do.

    Args and errors as :func:`resample`.
    """
    ticks, _ = resample(time, heads, capture_interval, phase)
    t = np.asarray(time, dtype=np.float64)
    values = np.asarray(heads, dtype=np.float64)
    flat = values.ndim == 1
    cols = values[:, None] if flat else values
    steps = np.diff(t)[:, None]
    cum = np.vstack(
        [np.zeros((1, cols.shape[1])), np.cumsum(0.5 * (cols[1:] + cols[:-1]) * steps, axis=0)]
    )

    def integral(x: NDArray[np.float64]) -> NDArray[np.float64]:
        inside = np.stack([np.interp(x, t, cum[:, j]) for j in range(cols.shape[1])], axis=1)
        before = np.minimum(x - t[0], 0.0)[:, None] * cols[0][None, :]
        return inside + before

    delta = float(capture_interval)
    means = (integral(ticks) - integral(ticks - delta)) / delta
    return ticks, means[:, 0] if flat else means


def capture(
    time: ArrayLike,
    heads: ArrayLike,
    capture_interval: float,
    phase: float = 0.0,
    meter_model: str = "instantaneous",
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Readings of a simulated timeline under a meter model (one of :data:`METER_MODELS`):
    :func:`resample` for ``"instantaneous"``, :func:`interval_average` for
    ``"interval-averaged"``.

    Raises:
        ConfigError: unknown meter model, or as :func:`resample`.
    """
    if meter_model == "instantaneous":
        return resample(time, heads, capture_interval, phase)
    if meter_model == "interval-averaged":
        return interval_average(time, heads, capture_interval, phase)
    raise ConfigError(f"meter_model must be one of {METER_MODELS}, got {meter_model!r}")
