"""No phantom bursts after the hold-off: seeded noise (sigma = 0.01 m) on paper15, many seeds.

Mirrors the hold-off, re-arm and corroboration rules of :mod:`burstloc.live.monitor` on a real
TSNet burst whose network rings for minutes.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from live_feed import burst_steps

from burstloc.experiments.calibrate import calibrate
from burstloc.live.monitor import BurstMonitor
from burstloc.localize.config import Calibration

PIPE = "3"
SEEDS = range(20)


@pytest.fixture(scope="module")
def config(paper15: Path) -> Calibration:
    return calibrate(paper15, capture_intervals=(0.2,), noise_sigma=0.01)


def _decisions(
    paper15: Path, config: Calibration, seed: int, **options: int | bool
) -> list[str | None]:
    steps = burst_steps(
        paper15,
        config.meters,
        PIPE,
        before=300.0,
        after=400.0,
        sigma=0.01,
        seed=seed,
        duration=220.0,
    )
    monitor = BurstMonitor(paper15, config, capture_interval=0.2, **options)
    return [d.pipe for d in monitor.run(steps)]


def test_one_burst_one_decision_over_many_seeds(paper15: Path, config: Calibration) -> None:
    runs = [_decisions(paper15, config, seed) for seed in SEEDS]
    assert all(len(found) == 1 for found in runs), runs
    assert sum(found == [PIPE] for found in runs) >= 0.9 * len(SEEDS), runs


def test_without_the_rules_the_ringing_gives_phantoms(paper15: Path, config: Calibration) -> None:
    runs = [
        _decisions(paper15, config, seed, rearm=0, settle=False, corroborate=1)
        for seed in SEEDS[:5]
    ]
    assert any(len(found) > 1 for found in runs), runs
