"""The times a burst at a candidate point allows each meter, and the burst time that fits them.

For each candidate point of the arrival localizer (:mod:`burstloc.localize.arrival`) each meter
gives a *window* of burst times ``[lo, hi]``: an alarm puts the wave's arrival in its capture
interval, a silence after it (``hi`` infinite), and a meter that says nothing has ``lo`` not
finite. :func:`fit_windows` finds each point's least-squares burst time and each meter's misfit
to it; :func:`window_misfit` measures the misfits at a given time; :func:`silence_counts` says
which silences count at all. Numpy only: on the live path.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["fit_windows", "silence_counts", "window_misfit"]


def silence_counts(
    fronts: NDArray[np.float64], alarmed: Sequence[int], silent: Sequence[int]
) -> NDArray[np.bool_]:
    """Which silent meters would have heard each candidate's wave, had it reached them.

    ``fronts`` (candidates, meters): the wave front a burst on each candidate sends to each meter,
    relative to the others (:func:`burstloc.sim.model.prepare.wave_fronts`); ``alarmed`` and
    ``silent``: meter columns. Returns (candidates, len(silent)): ``True`` where the silent
    meter's silence counts against the candidate (its wave has not reached it yet).

    The detector bank runs one threshold at every meter (:func:`burstloc.localize.config.
    calibrated_bank`), and every alarmed meter saw a change of at least that threshold. So, for
    a burst on the candidate, a silent meter whose front is at least that of some alarmed meter
    would have alarmed too once the wave reached it: its silence says the wave has not. A silent
    meter with a weaker front than every alarmed one may have been reached and not moved enough
    to alarm: its silence says nothing about the candidate. The burst's size, unknown, cancels.
    Alarmed meters that the candidate sends no front to (beyond a tank) say nothing of its size;
    when none is left, every silence counts (the candidate explains no alarm by its front).
    """
    rows = np.asarray(fronts, dtype=np.float64)
    at_alarms = rows[:, list(alarmed)]
    weakest = np.where(at_alarms > 0, at_alarms, np.inf).min(axis=1, initial=np.inf)
    weakest = np.where(np.isfinite(weakest), weakest, 0.0)
    return np.asarray(rows[:, list(silent)] >= weakest[:, None], dtype=np.bool_)


def window_misfit(
    lo: NDArray[np.float64], hi: NDArray[np.float64], t0: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Each meter's distance (s) from the burst time ``t0`` (shape ``lo.shape[:-1] + (1,)``) to
    its window ``[lo, hi]`` (:meth:`ArrivalLocalizer.windows`); 0 where the window says
    nothing (``lo`` not finite)."""
    says = np.isfinite(lo)
    lo_f, hi_f = np.where(says, lo, -np.inf), np.where(says, hi, np.inf)
    gap = np.maximum(lo_f - t0, 0.0) + np.maximum(t0 - hi_f, 0.0)
    return np.asarray(np.where(np.isfinite(gap), gap, 0.0), dtype=np.float64)


def fit_windows(
    lo: NDArray[np.float64], hi: NDArray[np.float64], alarmed: int, capture_interval: float
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """The least-squares burst time of each point's windows (:meth:`ArrivalLocalizer.windows`,
    the first ``alarmed`` of them alarms) and each meter's misfit to it: ``(gap, placed)``,
    ``placed`` where some alarm's window is finite (the point explains an alarm).

    The squared misfit is convex and piecewise quadratic in ``t0``; its derivative is piecewise
    linear and non-decreasing. Each point's root is found by Newton's method, which lands on it
    once in its linear piece, safeguarded by bisection of a bracket that holds it (a step that
    leaves the bracket halves it instead), to a millionth of ``capture_interval``: a few
    iterations, each only over the points not yet settled."""
    dt = capture_interval
    says = np.isfinite(lo)
    lo_f, hi_f = np.where(says, lo, -np.inf), np.where(says, hi, np.inf)
    first = says[..., :alarmed]
    left = np.where(first, lo[..., :alarmed], np.inf).min(axis=-1) - dt
    right = (
        np.maximum(
            np.where(first, hi[..., :alarmed], -np.inf).max(axis=-1),
            np.where(says, lo, -np.inf).max(axis=-1),
        )
        + dt
    )
    shape, meters = left.shape, lo.shape[-1]
    a, b = left.reshape(-1).copy(), right.reshape(-1).copy()
    low, high = lo_f.reshape(-1, meters), hi_f.reshape(-1, meters)
    with np.errstate(invalid="ignore"):  # no alarm's window: no time, no misfit (below)
        t0 = 0.5 * (a + b)
    tol = 1e-6 * dt
    live = np.flatnonzero(np.isfinite(a) & np.isfinite(b) & (b - a > tol))
    for _ in range(64):
        if live.size == 0:
            break
        t, lo_t, hi_t = t0[live], a[live], b[live]
        late = t[:, None] - high[live]  # how far past each window's end
        np.maximum(late, 0.0, out=late)
        early = low[live] - t[:, None]  # how far before each window's start
        np.maximum(early, 0.0, out=early)
        grad = late.sum(axis=1) - early.sum(axis=1)
        slope = np.count_nonzero(late, axis=1) + np.count_nonzero(early, axis=1)
        up = grad > 0
        hi_t = np.where(up, t, hi_t)
        lo_t = np.where(up, lo_t, t)
        settled = np.abs(grad) <= tol * slope  # within tol of the root of its linear piece
        newton = t - grad / np.maximum(slope, 1)
        inside = (newton > lo_t) & (newton < hi_t)
        t0[live] = np.where(settled, t, np.where(inside, newton, 0.5 * (lo_t + hi_t)))
        a[live], b[live] = lo_t, hi_t
        live = live[~settled & (hi_t - lo_t > tol)]
    with np.errstate(invalid="ignore"):
        gap = window_misfit(lo, hi, t0.reshape(shape)[..., None])
    return gap, np.asarray(first.any(axis=-1), dtype=np.bool_)
