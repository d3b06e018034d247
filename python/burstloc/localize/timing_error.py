"""The search regions' timing error: how far a meter's alarm may miss the arrival model's time.

A meter's alarm start is known to one capture interval; beyond it the misfit is the detector's
placement of the change and the model's error (:func:`timing_scale`): half an interval
(:data:`TIMING_INTERVALS`), a floor for the model itself (:data:`TIMING_FLOOR`), each meter's
clock, and the wave speed known to a share of each travel time, added in quadrature. The error
is a Student-t (:data:`TAIL_DOF` degrees of freedom) mixed with a chance :data:`OUTLIER` that
the alarm says nothing of the first wave (:func:`timing_penalty`). The stated scale is a floor,
not a promise: the alarms' own misfits at the best-fitting point say how large the error is
(:func:`misfit_scale`), and :func:`widened_scale` pools the two. Numpy only: on the live path
(:mod:`burstloc.localize.region` uses them).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "FIT_PARAMETERS",
    "MISFIT_TRIM",
    "OUTLIER",
    "STATED_DOF",
    "TAIL_DOF",
    "TIMING_FLOOR",
    "TIMING_INTERVALS",
    "misfit_scale",
    "timing_penalty",
    "timing_scale",
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
    gap: NDArray[np.float64], scale: NDArray[np.float64] | float, horizon: float
) -> NDArray[np.float64]:
    """Minus the log-likelihood of timing misfits ``gap`` (s), 0 at no misfit: a Student-t
    error of ``scale`` s (a number, or one per misfit) mixed with an :data:`OUTLIER` uniform
    over ``horizon`` s."""
    z = gap / scale
    kernel = np.power(1.0 + z * z / TAIL_DOF, -0.5 * (TAIL_DOF + 1.0))
    flat = OUTLIER * scale / (np.maximum(horizon, scale) * _T_PEAK)
    return np.asarray(
        np.log((1.0 - OUTLIER) + flat) - np.log((1.0 - OUTLIER) * kernel + flat),
        dtype=np.float64,
    )


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
