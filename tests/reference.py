"""Pure-Python oracle of the paper's change-point detectors (section III).

Plain transcriptions, written for readability rather than speed, that the Rust detectors are
checked against:

* :func:`cusum_online` is the online pass of Algorithm 1 (TSNet's ``detect_cusum`` loop, with
  its ``gp_real``/``gn_real`` amplitude sums), one alarm per threshold crossing;
* :func:`shewhart_batch` is Algorithm 2 over a whole array (mean and population standard
  deviation of the array, alarm when the deviation exceeds both ``sigma * std`` and
  ``threshold``);
* :func:`shewhart_streaming` applies Algorithm 2's test to each trailing window of ``window``
  samples (the current sample included), the definition the streaming ``Shewhart`` follows.

The arithmetic is done in the same order as TSNet (``gp + s - drift``), so the oracle's CUSUM
sums are bit-identical to TSNet's; Algorithm 2 is NumPy code (``mean(x)``, ``std(x)``), so the
oracle takes the window statistics from NumPy and its decisions are exactly the paper's.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RefAlarm:
    """An alarm raised by an oracle detector (same fields as ``burstloc.Alarm``)."""

    index: int
    start: int
    direction: str
    amplitude: float


def cusum_online(x: Sequence[float], threshold: float, drift: float) -> list[RefAlarm]:
    """Run the online CUSUM pass of Algorithm 1 over ``x`` and return every alarm.

    Sample 0 only primes the previous value. For ``i >= 1`` the four sums move by
    ``s = x[i] - x[i-1]``; a drift-corrected sum that goes negative resets itself, its real
    twin and its start index; an alarm fires when a real sum exceeds ``threshold``, and then all
    four sums reset (the start indices do not).
    """
    gp = gn = gp_real = gn_real = 0.0
    tap = tan = 0
    alarms: list[RefAlarm] = []
    for i in range(1, len(x)):
        s = x[i] - x[i - 1]
        gp = gp + s - drift
        gp_real = gp_real + s
        gn = gn - s - drift
        gn_real = gn_real - s
        if gp < 0:
            gp, gp_real, tap = 0.0, 0.0, i
        if gn < 0:
            gn, gn_real, tan = 0.0, 0.0, i
        if gp_real > threshold or gn_real > threshold:
            rise = gp_real > threshold
            start = tap if rise else tan
            alarms.append(
                RefAlarm(
                    index=i,
                    start=start,
                    direction="rise" if rise else "drop",
                    amplitude=x[i] - x[start],
                )
            )
            gp = gn = gp_real = gn_real = 0.0
    return alarms


@dataclass(frozen=True)
class ShewhartDecision:
    """Algorithm 2's test on one sample: the decision, ``x - mean`` and the margin.

    ``margin`` is ``|x - mean| - max(sigma * std, threshold)`` (positive means an alarm): it
    tells how close to a tie at the control limit the decision was, for diagnostics.
    """

    index: int
    alarm: bool
    deviation: float
    margin: float


def _mean_std(values: np.ndarray) -> tuple[float, float]:
    # Algorithm 2 is NumPy code: mean(x) and std(x) (population), NumPy's summation order.
    return float(np.mean(values)), float(np.std(values))


def _decide(
    index: int, value: float, mean: float, std: float, sigma: float, threshold: float
) -> ShewhartDecision:
    deviation = value - mean
    distance = abs(deviation)
    return ShewhartDecision(
        index=index,
        alarm=distance > sigma * std and distance > threshold,
        deviation=deviation,
        margin=distance - max(sigma * std, threshold),
    )


def shewhart_batch(x: np.ndarray, sigma: float, threshold: float) -> list[ShewhartDecision]:
    """Algorithm 2 over the whole of ``x``: one decision per sample, against its mean/std."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    mean, std = _mean_std(x)
    return [_decide(i, v, mean, std, sigma, threshold) for i, v in enumerate(x.tolist())]


def shewhart_streaming(
    x: np.ndarray, window: int, sigma: float, threshold: float
) -> list[ShewhartDecision]:
    """Algorithm 2's test applied at each sample to the trailing window of ``window`` samples.

    The window ``x[i - window + 1 : i + 1]`` includes the current sample; there is no decision
    (and so no alarm) before ``window`` samples have been seen.
    """
    x = np.ascontiguousarray(x, dtype=np.float64)
    values = x.tolist()
    decisions = []
    for i in range(window - 1, len(values)):
        mean, std = _mean_std(x[i - window + 1 : i + 1])
        decisions.append(_decide(i, values[i], mean, std, sigma, threshold))
    return decisions


def amplitude_tolerance(x: np.ndarray) -> float:
    """Rounding slack for a streaming Shewhart amplitude (``x - mean`` from running sums).

    The running sums carry a relative error of order 1e-12 of the signal's magnitude; this
    allows 1e-9 of it.
    """
    return 1e-9 * max(float(np.max(np.abs(x))), 1e-300)
