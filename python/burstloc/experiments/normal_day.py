"""False burst reports in normal operation: a day of background pressure through the monitor.

:func:`normal_operation` feeds :func:`burstloc.sim.events.normal.normal_day` (diurnal demand by an
EPANET extended-period run, sensor noise) to the live monitor with the classifier, and counts
its decisions and how many were reported as bursts (``burstloc evaluate --events``).
"""

from __future__ import annotations

from typing import Any

from burstloc.experiments.calibrate import DEFAULT_NOISE_SIGMA
from burstloc.experiments.ranking import RankingSetup
from burstloc.localize.classify import ClassifierConfig
from burstloc.network import NetworkSource

__all__ = ["normal_operation"]


def normal_operation(
    network: NetworkSource,
    setup: RankingSetup,
    config: ClassifierConfig,
    capture_interval: float,
    *,
    hours: float = 24.0,
    noise_sigma: float = DEFAULT_NOISE_SIGMA,
    seed: int = 0,
) -> dict[str, Any]:
    """A day of normal operation (:func:`burstloc.sim.events.normal.normal_day`) through the live
    monitor with the classifier: how many decisions, how many reported as bursts, and what
    the simulator warned (``simulator_warnings``)."""
    from burstloc._diagnostics import capture_diagnostics
    from burstloc.live.monitor import BurstMonitor
    from burstloc.readings import Step
    from burstloc.sim.events.normal import normal_day

    with capture_diagnostics() as diagnostics:
        times, values = normal_day(
            network,
            capture_interval=capture_interval,
            noise_sigma=noise_sigma,
            hours=hours,
            meters=setup.meters,
            seed=seed,
        )
    monitor = BurstMonitor(
        network,
        setup.config,
        capture_interval=capture_interval,
        localizers=setup.localizers_at(capture_interval),
        classify=config,
    )
    steps = (Step(float(t), v) for t, v in zip(times, values, strict=True))
    decisions = [d for d in monitor.run(steps) if not d.transient]  # the classified answers
    return {
        "capture_interval": capture_interval,
        "hours": hours,
        "noise_sigma": noise_sigma,
        "decisions": len(decisions),
        "burst_reports": sum(d.is_burst for d in decisions),
        "dismissed": monitor.dismissed,
        "events": [d.to_json()["classification"] for d in decisions],
        "simulator_warnings": list(diagnostics.warnings),
    }
