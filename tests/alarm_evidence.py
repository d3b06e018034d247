"""Burst evidence from known arrival times, as a detector would report them (shared by the
arrival localizer's tests)."""

from __future__ import annotations

import math

import numpy as np

from burstloc.localize.evidence import BurstEvidence, MeterAlarm


def arrival_evidence(
    arrivals: dict[str, float],
    dt: float,
    amplitudes: dict[str, float] | None = None,
    span: float = 5.0,
) -> BurstEvidence:
    """Alarm starts as a detector reports them: the last capture tick before each meter's
    wave (``arrivals``, s); readings every ``dt`` s over ``span`` s."""
    meters = tuple(sorted(arrivals))
    alarms = {
        m: MeterAlarm(
            m,
            math.floor(arrivals[m] / dt - 1e-9) * dt,
            (amplitudes or {}).get(m, -1.0),
        )
        for m in meters
    }
    t = np.arange(0.0, span, dt)
    return BurstEvidence(
        meters=meters,
        times=t,
        readings=np.zeros((t.size, len(meters))),
        onset=min(a.start for a in alarms.values()),
        capture_interval=dt,
        alarms=alarms,
    )
