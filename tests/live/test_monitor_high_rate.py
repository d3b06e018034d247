"""A logger reading 250 times a second: paper15's pipe P7 burst at its middle (5 L/s, opened in
0.3 s), four meters (N4, 8, N7, 1), 1 cm of noise, a real simulation read every 0.004 s.

The paper's CUSUM sums successive differences less a drift of one noise level per reading: at
250 Hz that hides every front slower than 2.5 m/s, so a monitor calibrated with it never saw this
burst (its fronts are 0.5 m over 0.3 s). The calibrated drift is a rate below 0.2 s
(:func:`burstloc.experiments.calibrate.cusum_threshold`): the monitor answers within seconds and
places the burst within metres.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.harness import Clock, capture_readings
from burstloc.experiments.ranking import monitor_answer
from burstloc.live.monitor import BurstMonitor
from burstloc.sim.scenarios.scenario import burst_scenarios
from burstloc.sim.scenarios.sensors import SensorModel
from burstloc.sim.signatures.burst_size import DEFAULT_BURST, sized_scenarios
from burstloc.sim.transient.time_step import with_capture_time_step
from burstloc.sim.transient.tsnet import simulate_burst

METERS = ("N4", "8", "N7", "1")
DT = 0.004


def test_a_250_hz_monitor_answers_at_once_and_within_metres(paper15: Path) -> None:
    scenarios = burst_scenarios(str(paper15), ["P7"], duration=13.0)
    (scenario,), (size,) = sized_scenarios(with_capture_time_step(scenarios, DT), DEFAULT_BURST)
    assert size.flow_lps == pytest.approx(5.0)
    result = simulate_burst(scenario)
    config = calibrate(
        paper15, capture_intervals=(DT,), noise_sigma=0.01, meters=METERS, max_samples=300_000
    )
    times, values = capture_readings(
        result,
        Clock(DT, 0.0, history=2500),  # 10 s of a monitor that has been running
        meters=list(config.meters),
        sensor=SensorModel(noise_sigma=0.01, seed=3),
        noise_key="P7",
    )
    monitor = BurstMonitor(paper15, config, capture_interval=DT)
    _, decision = monitor_answer(monitor, times, values)
    assert decision is not None and decision.pipe == "P7"
    assert decision.time - scenario.burst_start < 3.0  # seconds, not the lasting drop's 150 s
    assert decision.position is not None
    assert abs(decision.position.metres - 500.0) < 30.0  # mid-pipe of a 1 000 m pipe
