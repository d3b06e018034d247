"""The search regions' timing error: how far a meter's alarm may miss the arrival model's time.

A meter's alarm start is known to one capture interval; beyond it the misfit is the detector's
placement of the change and the model's error (:func:`timing_scale`): half an interval
(:data:`TIMING_INTERVALS`), a floor for the model itself (:data:`TIMING_FLOOR`), each meter's
clock, and the wave speed known to a share of each travel time, added in quadrature. The error
is a Student-t (:data:`TAIL_DOF` degrees of freedom) mixed with a chance :data:`OUTLIER` that
the alarm says nothing of the first wave (:func:`timing_penalty`). The stated scale is a floor,
not a promise: the alarms' own misfits at the best-fitting point say how large the error is
(:func:`misfit_scale`), and :func:`widened_scale` pools the two.

A weak change is timed worse than a strong one. An alarm whose change is a few noise levels
high (its amplitude over the meter's noise, :func:`alarm_strengths`, the noise read from the
readings before the burst: :func:`baseline_noise`) starts where the CUSUM's sum began to grow
among noise of the same size, and is more often some later wave than the first. On L-TOWN's 33
BattLeDIM sensors (24 simulated bursts, alarm starts against the fronts' travel times, each
burst's time fitted) the alarms 7-10 noise levels high scattered 1.8 times as widely as those
over 15 at 0.2 s (0.24 against 0.13 s) and 2 times at 0.05 s, and at 0.2 s one in five was
more than half a second off, against one in fifty. So an alarm below :data:`STRONG_ALARM` noise
levels has its timing error widened by ``STRONG_ALARM / strength`` and its outlier chance
raised by the square of that (:func:`weak_alarms`, :func:`alarm_weakness`). Not at 0.02 s and
finer, where a front spans ten readings or more, its start is fitted to the readings
(:mod:`burstloc.localize.onset`) and an alarm's amplitude is the height of the front's ramp when
it was raised: there, on the same
L-TOWN pipes, it grew the median 95 % region from 467 to 663 m and held no more. Numpy only: on
the live path (:mod:`burstloc.localize.region` uses them).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from burstloc.localize.evidence import BurstEvidence
from burstloc.localize.onset import FINEST_STEP_INTERVAL
from burstloc.readings import robust_sigma

__all__ = [
    "BASELINE_READINGS",
    "FIT_PARAMETERS",
    "MAX_OUTLIER",
    "MIN_BASELINE",
    "MISFIT_TRIM",
    "OUTLIER",
    "STATED_DOF",
    "STRONG_ALARM",
    "TAIL_DOF",
    "TIMING_FLOOR",
    "TIMING_INTERVALS",
    "alarm_strengths",
    "alarm_weakness",
    "baseline_noise",
    "misfit_scale",
    "timing_penalty",
    "timing_scale",
    "weak_alarms",
    "widened_scale",
]

TIMING_INTERVALS = 0.5
"""Timing error beyond the capture interval, in capture intervals: where in its interval the
detector places a change it sees one reading late or early."""

TIMING_FLOOR = 0.02
"""Timing error (s) of the model itself: path lengths and wave speed (20 ms is 24 m of wave
travel at 1200 m/s)."""

TAIL_DOF = 3.0
"""Degrees of freedom of the Student-t timing error."""

OUTLIER = 0.05
"""Chance that a meter's alarm start says nothing of the burst's first wave."""

MISFIT_TRIM = 0.1
"""Share of the largest alarm misfits :func:`misfit_scale` leaves out (outliers)."""

FIT_PARAMETERS = 3
"""What the arrival fit chooses: the point (a pipe and a place along it) and the burst time."""

STATED_DOF = 4
"""How many alarms' worth of misfits the stated timing error counts for against the misfits
(:func:`widened_scale`): a few meters' misfits widen it little, a few tens decide it."""

STRONG_ALARM = 15.0
"""An alarm's change this many noise levels high, or more, is timed to the stated error; a
weaker one's is wider (module docstring)."""

MAX_OUTLIER = 0.5
"""The largest chance that a weak alarm says nothing of the first wave."""

MIN_BASELINE = 10
"""Readings before the burst needed to tell a meter's noise (fewer: its alarms count as
strong)."""

BASELINE_READINGS = 200
"""The most readings before the burst that :func:`baseline_noise` reads."""

_T_PEAK = math.gamma(0.5 * (TAIL_DOF + 1)) / (
    math.sqrt(TAIL_DOF * math.pi) * math.gamma(0.5 * TAIL_DOF)
)


def timing_scale(
    capture_interval: float,
    travel: NDArray[np.float64] | float = 0.0,
    wave_speed_tolerance: float = 0.0,
    clock_tolerance: float = 0.0,
) -> NDArray[np.float64] | float:
    """Scale (s) of the timing error beyond the capture interval (module docstring): the
    detector's placement of the change, the model's floor, each meter's clock and the wave's
    travel time ``travel`` (s, from the candidate point to the meter) known to
    ``wave_speed_tolerance`` of itself, added in quadrature."""
    base = math.hypot(TIMING_INTERVALS * capture_interval, TIMING_FLOOR, clock_tolerance)
    if wave_speed_tolerance == 0:
        return base
    spread = wave_speed_tolerance * np.where(np.isfinite(travel), travel, 0.0)
    return np.asarray(np.hypot(base, spread), dtype=np.float64)


def timing_penalty(
    gap: NDArray[np.float64],
    scale: NDArray[np.float64] | float,
    horizon: float,
    outlier: NDArray[np.float64] | float = OUTLIER,
) -> NDArray[np.float64]:
    """Minus the log-likelihood of timing misfits ``gap`` (s), 0 at no misfit: a Student-t
    error of ``scale`` s (a number, or one per misfit) mixed with a chance ``outlier`` (a
    number, or one per misfit; default :data:`OUTLIER`) of an error uniform over ``horizon``
    s."""
    z = gap / scale
    kernel = np.power(1.0 + z * z / TAIL_DOF, -0.5 * (TAIL_DOF + 1.0))
    flat = outlier * scale / (np.maximum(horizon, scale) * _T_PEAK)
    return np.asarray(
        np.log((1.0 - outlier) + flat) - np.log((1.0 - outlier) * kernel + flat),
        dtype=np.float64,
    )


def baseline_noise(
    times: NDArray[np.float64], values: NDArray[np.float64], onset: float
) -> NDArray[np.float64]:
    """Each column's noise level (m) in ``values`` (readings at ``times``) before ``onset``:
    :func:`~burstloc.readings.robust_sigma` of the last :data:`BASELINE_READINGS` readings at
    or before it (a slow trend cancels); ``nan``
    for every column with fewer than :data:`MIN_BASELINE` such readings."""
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    end = int(np.searchsorted(t, onset, side="right"))
    base = y[max(0, end - BASELINE_READINGS) : end]
    if base.shape[0] < MIN_BASELINE:
        return np.full(y.shape[1], np.nan)
    return robust_sigma(base)


def alarm_strengths(
    amplitudes: NDArray[np.float64], noise: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Each alarm's change in noise levels: ``|amplitudes|`` over ``noise`` (m, one per alarm);
    ``inf`` (a strong alarm) where the noise is unknown (``nan``) or zero."""
    a = np.abs(np.asarray(amplitudes, dtype=np.float64))
    n = np.asarray(noise, dtype=np.float64)
    known = np.isfinite(n) & (n > 0)
    return np.where(known, a / np.where(known, n, 1.0), np.inf)


def weak_alarms(
    strengths: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """For alarms ``strengths`` noise levels high, what weakness does to their timing (module
    docstring): ``(widening, outlier)``, the factor on each one's timing error (1 at
    :data:`STRONG_ALARM` and above) and its outlier chance (:data:`OUTLIER` there, at most
    :data:`MAX_OUTLIER`)."""
    s = np.asarray(strengths, dtype=np.float64)
    widening = np.maximum(1.0, STRONG_ALARM / np.maximum(s, 1e-9))
    outlier = np.minimum(MAX_OUTLIER, OUTLIER * widening**2)
    return widening, outlier


def misfit_scale(gap: NDArray[np.float64]) -> tuple[float, int]:
    """The timing error (s) that the alarms' own misfits ``gap`` (s, one per alarmed meter, at
    the best-fitting point) show, and its degrees of freedom: their RMS with the largest
    :data:`MISFIT_TRIM` of them left out (a late meter is the outlier term's), over the degrees
    of freedom the fit leaves (:data:`FIT_PARAMETERS` fitted); ``(0, 0)`` with too few alarms
    to tell."""
    g = np.sort(np.abs(np.asarray(gap, dtype=np.float64)))
    kept = g[: g.size - math.floor(MISFIT_TRIM * g.size)]
    dof = kept.size - FIT_PARAMETERS
    if dof < 1:
        return 0.0, 0
    return float(np.sqrt(np.sum(kept**2) / dof)), int(dof)


def widened_scale(stated: float, shown: float, dof: int) -> float:
    """The timing error (s) after the alarms' misfits: the stated one weighed as
    :data:`STATED_DOF` degrees of freedom against what the misfits show with their ``dof``
    (a variance's conjugate update), never below the stated one."""
    pooled = math.sqrt((STATED_DOF * stated**2 + dof * shown**2) / (STATED_DOF + dof))
    return max(stated, pooled)


def alarm_weakness(
    evidence: BurstEvidence, meters: Sequence[str]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:func:`weak_alarms` of the alarms of ``meters`` in ``evidence``, each one's strength its
    amplitude over its meter's noise before the burst (:func:`baseline_noise` of the evidence's
    readings before its onset); every alarm as strong at capture intervals up to
    :data:`~burstloc.localize.onset.FINEST_STEP_INTERVAL`, where an alarm is raised on the
    front's ramp: its amplitude is the ramp so far, not the change's size."""
    if evidence.capture_interval <= FINEST_STEP_INTERVAL:
        return weak_alarms(np.full(len(meters), np.inf))
    noise = baseline_noise(
        evidence.times, evidence.readings[:, evidence.columns(meters)], evidence.onset
    )
    amplitudes = np.array([evidence.alarms[m].amplitude for m in meters], dtype=np.float64)
    return weak_alarms(alarm_strengths(amplitudes, noise))
