"""Fixtures of the live tests: the tiny network calibrated at 0.2 s, and a noisy feed of a
real TSNet burst on its pipe :data:`PIPE`, as per-meter readings."""

from __future__ import annotations

from pathlib import Path

import pytest
from live_feed import burst_steps, readings

from burstloc.experiments.calibrate import calibrate
from burstloc.localize.config import Calibration
from burstloc.readings import Reading

#: The burst pipe of :func:`tiny_feed`.
PIPE = "C"


@pytest.fixture(scope="module")
def tiny_config(tiny: Path) -> Calibration:
    """The tiny network calibrated at 0.2 s for noise sigma = 0.01 m."""
    return calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)


@pytest.fixture(scope="module")
def tiny_feed(tiny: Path, tiny_config: Calibration) -> list[Reading]:
    """A burst on :data:`PIPE` with noise sigma = 0.002 m, as readings."""
    steps = burst_steps(tiny, tiny_config.meters, PIPE, sigma=0.002)
    return readings(steps, tiny_config.meters)
