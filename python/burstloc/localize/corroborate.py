"""How many meters make a burst: the corroboration rule of the live monitor and of the events
evaluation (``burstloc evaluate --events``), in one place.

A burst's wave reaches every meter near it; a noise excursion, a glitch or the tail of the
ringing after a decision reaches one. An alarm is *corroborated* once ``needed`` meters have
alarmed (each meter's first alarm counts, at its reading time), and it may be corroborated until
its *deadline* (:func:`corroboration_deadline`): the localizer's first decision time
(:func:`burstloc.localize.decide.decision_time`) or the arrival horizon after the first alarm
(:func:`burstloc.localize.decide.arrival_horizon`: by then a burst's wave has reached every
meter it will reach), whichever is later. Waiting for the horizon matters on large networks: a
burst on a large main moves far heads by less than the detectors' threshold, and on EPANET's
Net3 (every junction metered, 0.2 s) one meter alone had alarmed by the first look at pipe 20's
burst, more within the horizon. Alarms not corroborated by their deadline are dismissed.

Numpy only; on the live path.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.localize.decide import decision_time, fused_of, horizon_of
from burstloc.localize.evidence import Localizer

if TYPE_CHECKING:
    from burstloc.localize.interval import IntervalCalibration

__all__ = ["CORROBORATE", "corroborated_at", "corroboration_deadline"]

#: Meters that must have alarmed for a decision, by default (fewer when fewer report).
CORROBORATE = 2


def corroboration_deadline(
    localizer: str,
    localizers: Mapping[str, Localizer],
    alarms: Sequence[Any],
    times: np.ndarray,
    calibration: IntervalCalibration,
) -> float:
    """The reading time until which ``alarms`` may be corroborated (module docstring): the
    later of ``localizer``'s decision time and the arrival horizon after the first alarm (the
    ``"arrival"`` localizer's, :func:`~burstloc.localize.decide.horizon_of`).

    Raises:
        InputError: no alarm.
    """
    due = decision_time(localizer, alarms, times, calibration, fused_of(localizers))
    first = min(float(times[a.index]) for a in alarms)
    return max(due, first + horizon_of(localizers, calibration))


def corroborated_at(
    alarms: Sequence[Any], times: np.ndarray, needed: int, by: float
) -> float | None:
    """The reading time at which ``needed`` meters (at least one) had alarmed, if that is by
    the reading time ``by`` (:func:`corroboration_deadline`); ``None`` otherwise: fewer meters'
    first alarms came by ``by``, or by the last reading when that is earlier (the caller who
    has not reached ``by`` yet may wait for more)."""
    firsts: dict[int, float] = {}
    for a in alarms:
        at = float(times[a.index])
        if at <= by + 1e-9 and at < firsts.get(int(a.channel), math.inf):
            firsts[int(a.channel)] = at
    wanted = max(needed, 1)
    if len(firsts) < wanted:
        return None
    return sorted(firsts.values())[wanted - 1]
