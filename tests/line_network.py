"""A line of four meters 600 m apart (m0 - m1 - m2 - m3; pipes p01, p12, p23) and localizers on it,
shared by the fused-localizer and decision tests."""

from __future__ import annotations

import numpy as np

from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.interval import IntervalCalibration
from burstloc.localize.pipes import PipeGeometry
from burstloc.localize.signature import SignatureLocalizer, SignatureSet

METERS = ("m0", "m1", "m2", "m3")
PIPES = ("p01", "p12", "p23")
WAVE = 1200.0


def line_arrival() -> ArrivalLocalizer:
    pos = {m: 600.0 * i for i, m in enumerate(METERS)}
    distances = {n: np.array([abs(pos[n] - pos[m]) for m in METERS]) for n in METERS}
    pipes = [PipeGeometry(f"p{i}{i + 1}", f"m{i}", f"m{i + 1}", 600.0) for i in range(3)]
    return ArrivalLocalizer(pipes, METERS, distances, wave_speed=WAVE)


def line_calibration(dt: float = 0.05, arrival_decision_delay: float = 1.0) -> IntervalCalibration:
    """A calibration of capture interval ``dt`` (decision delay 60 s; no thresholds)."""
    return IntervalCalibration(
        capture_interval=dt,
        localization_interval=10,
        cusum_threshold={},
        cusum_drift={},
        shewhart_threshold={},
        shewhart_sigma=3.0,
        decision_delay=60.0,
        arrival_decision_delay=arrival_decision_delay,
    )


def line_signature(matrix: np.ndarray) -> SignatureLocalizer:
    sig = SignatureSet(
        network_hash="sha256:test",
        meters=METERS,
        pipes=PIPES,
        endpoints={f"p{i}{i + 1}": (f"m{i}", f"m{i + 1}") for i in range(3)},
        matrix=matrix,
        baseline=np.full(4, 50.0),
        params={},
    )
    return SignatureLocalizer(sig, settle=20.0, decision_delay=60.0, estimator="mean")
