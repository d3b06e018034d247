"""Where a meter's change starts, to a fraction of a reading, from the readings themselves.

A CUSUM places a change at its reset point: the last reading before its sum began to grow. With
a drift of a noise level per 0.2 s (:func:`burstloc.experiments.calibrate.cusum_threshold`) that
point is the last noise peak before the front, up to a tenth of a second early at a high-rate
logger's hundreds of readings a second, whatever the rate. A burst's front is not a step but a
ramp (the burst opens over a fraction of a second, the wave spreads it), so at a high rate it
spans many readings and its start can be fitted: the head is level, then departs along a line
(a *hinge*: ``y = b + g max(0, t - c)``), least squares over the readings from
:data:`LOOKBACK` s before the CUSUM's start to the reading that raised the alarm, ``c`` tried
every quarter reading. The fit is used where the front spans readings
(:data:`FITTED_INTERVAL`): at 0.2 s a front is one or two readings and the CUSUM's start is as
good. At 0.05 s a front spans a few readings; fitted there, on 200 L-TOWN pipes with
BattLeDIM's 33 sensors (each configuration calibrated with its own timing), the first record
came 1.3 s after the burst instead of 1.6 s, its 95 % region held the burst in 99 % instead of
96 %, and it landed 62 m from it on average instead of 72 m. :data:`FINEST_STEP_INTERVAL` (0.02
s) is where a front spans ten readings or more: the CUSUM's drift per 0.2 s and every alarm's
timing as stated (:mod:`burstloc.localize.timing_error`) hold there only.

Numpy only: on the live path.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "FINEST_STEP_INTERVAL",
    "FITS_KEPT",
    "FITTED_INTERVAL",
    "LOOKBACK",
    "SUBSTEPS",
    "change_start",
    "hinge_onset",
]

FINEST_STEP_INTERVAL = 0.02
"""Capture intervals (s) up to this one read a burst's front, a few tenths of a second, over ten
readings or more: an alarm is raised on the front's ramp (module docstring)."""

FITTED_INTERVAL = 0.05
"""Capture intervals (s) up to this one time a change by :func:`hinge_onset`: the front spans a
few readings at least."""

LOOKBACK = 0.5
"""Seconds of readings before the CUSUM's start that the fit reads (the level before the
change; the CUSUM's start is at most a few tenths of a second early)."""

SUBSTEPS = 4
"""Candidate change points per reading."""


def hinge_onset(
    times: NDArray[np.float64], values: NDArray[np.float64], start: int, index: int, sign: float
) -> float | None:
    """The time (s) one meter's change starts: the hinge (module docstring) fitted to
    ``values`` (its readings at ``times``) from :data:`LOOKBACK` s before reading ``start`` (the
    CUSUM's) to reading ``index`` (the alarm's), its slope of the alarm's ``sign``; ``None``
    where no such hinge fits (too few readings, or a departure the wrong way). A fit is kept
    (:data:`FITS_KEPT` of them, keyed by the readings it read), so the monitor's looks at the same
    alarm fit it once."""
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    if index - start < 1 or start < 0 or index >= t.size:
        return None
    first = int(np.searchsorted(t, t[start] - LOOKBACK, side="left"))
    tt, yy = t[first : index + 1], y[first : index + 1]
    if tt.size < 4 or sign == 0:
        return None
    return _fit(tt.tobytes(), yy.tobytes(), bool(sign > 0))


FITS_KEPT = 4096
"""Hinge fits :func:`hinge_onset` keeps: a few per meter of a few bursts."""


@functools.lru_cache(maxsize=FITS_KEPT)
def _fit(times: bytes, values: bytes, rising: bool) -> float | None:
    """The best hinge's change point over these readings (float64 bytes), its slope rising or
    falling; ``None`` where none fits."""
    tt, yy = np.frombuffer(times), np.frombuffer(values)
    step = (tt[-1] - tt[0]) / (tt.size - 1)
    cands = np.arange(tt[0] + step, tt[-1], step / SUBSTEPS)
    if cands.size == 0:
        return None
    x = np.maximum(tt[None, :] - cands[:, None], 0.0)  # (candidates, readings)
    n = float(tt.size)
    sx, sxx = x.sum(axis=1), (x * x).sum(axis=1)
    sy, sxy = float(yy.sum()), x @ yy
    det = n * sxx - sx * sx
    ok = det > 1e-12
    slope = np.where(ok, (n * sxy - sx * sy) / np.where(ok, det, 1.0), 0.0)
    level = (sy - slope * sx) / n
    rss = ((level[:, None] + slope[:, None] * x - yy[None, :]) ** 2).sum(axis=1)
    rss = np.where(ok & ((slope > 0) == rising) & (slope != 0), rss, np.inf)
    best = int(np.argmin(rss))
    if not np.isfinite(rss[best]):
        return None
    return float(cands[best])


def change_start(
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    start: int,
    index: int,
    amplitude: float,
    capture_interval: float,
) -> float:
    """Where one meter's change starts as the localizers read it: the time stamp of the reading
    before it (an alarm's window is ``[start, start + capture_interval]``). The detector's own
    start (reading ``start``; ``index`` raised the alarm, of ``amplitude``), or at capture
    intervals up to :data:`FITTED_INTERVAL` the fitted change point (:func:`hinge_onset`)
    less half an interval, so that the window is centred on it."""
    at = None
    if capture_interval <= FITTED_INTERVAL:
        at = hinge_onset(times, values, start, index, amplitude)
    return float(times[start]) if at is None else at - 0.5 * capture_interval
