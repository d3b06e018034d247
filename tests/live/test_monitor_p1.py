"""Why the live monitor misses paper15's pipe P1 at 0.01 m of noise: a real simulation of the
burst on P1 (reservoir R1 to N3), the paper's burst at its middle, 0.2 s capture, the fused
localizer calibrated for that noise (docs/results.md, "Pipe P1").

Every point of P1 reaches the meters through N3 (R1 is a reservoir: no meter beyond it), so in
arrival times a burst anywhere on P1 is a burst at N3, and the N3 ends of P2, P3 and 4 fit as
well: without noise the arrivals are never decisive and the monitor waits for the lasting drop,
which names P1. Noise moves a neighbour meter's alarm start (the CUSUM's change point) a reading
or two before the wave can have come; the pipe towards that meter then fits the arrivals better
by more than the quantisation margin, and the monitor answers at once with it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.harness import Clock, capture_readings
from burstloc.experiments.ranking import monitor_answer
from burstloc.live.monitor import BurstMonitor
from burstloc.localize.interval import calibrated_bank
from burstloc.sim.scenarios.scenario import burst_scenarios
from burstloc.sim.scenarios.sensors import SensorModel
from burstloc.sim.transient.tsnet import simulate_burst

NOISE = 0.01


@pytest.fixture(scope="module")
def p1(paper15: Path) -> dict[str, Any]:
    params = paper.SCENARIO.parameters()
    params["duration"] = 170.0
    (scenario,) = burst_scenarios(str(paper15), ["P1"], **params)
    config = calibrate(paper15, capture_intervals=(0.2,), noise_sigma=NOISE)
    return {"result": simulate_burst(scenario), "config": config, "network": paper15}


def _readings(p1: dict[str, Any], sigma: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    return capture_readings(
        p1["result"],
        Clock(0.2, 0.0, history=450),  # 90 s of a monitor that has been running
        meters=list(p1["config"].meters),
        sensor=SensorModel(noise_sigma=sigma, seed=seed),
        noise_key="P1",
    )


def _answer(p1: dict[str, Any], times: np.ndarray, values: np.ndarray) -> Any:
    monitor = BurstMonitor(p1["network"], p1["config"], capture_interval=0.2)
    return monitor_answer(monitor, times, values)[1]


def _starts(p1: dict[str, Any], times: np.ndarray, values: np.ndarray) -> dict[str, float]:
    """Each meter's first alarm start (s), from the calibrated bank over the readings."""
    config = p1["config"]
    bank = calibrated_bank("cusum", len(config.meters), config.for_interval(0.2))
    starts: dict[str, float] = {}
    for alarm in bank.run(np.ascontiguousarray(values)):
        starts.setdefault(config.meters[int(alarm.channel or 0)], float(times[alarm.start]))
    return starts


def test_without_noise_the_arrivals_cannot_tell_p1_and_the_lasting_drop_names_it(p1) -> None:
    times, values = _readings(p1, 0.0)
    decision = _answer(p1, times, values)
    assert decision.waited and decision.pipe == "P1"
    assert decision.time - decision.first_alarm > 100.0  # the signature's time, not the arrivals'
    # the wave leaves P1 at N3: N3 alarms first, its neighbours (N2 610 m, 1 650 m, N4 914 m
    # away) within a reading of each other, 0.8 s later
    starts = _starts(p1, times, values)
    assert min(starts, key=starts.__getitem__) == "N3"
    assert [round(starts[m] - starts["N3"], 1) for m in ("N2", "1", "N4")] == [0.8, 0.8, 0.8]


def test_with_noise_an_early_alarm_start_next_to_n3_names_that_neighbour_at_once(p1) -> None:
    clean = _starts(p1, *_readings(p1, 0.0))
    times, values = _readings(p1, NOISE, seed=0)
    noisy = _starts(p1, times, values)
    # N4's alarm starts 0.4 s (two readings) before the wave from N3 can have reached it
    assert noisy["N3"] == clean["N3"]
    assert noisy["N4"] == pytest.approx(clean["N4"] - 0.4)
    assert noisy["N4"] - noisy["N3"] < 914.0 / 1200.0 - 0.2
    decision = _answer(p1, times, values)
    # P2 (N3 to N4) explains that early start; it leads P1 by more than the decisive margin at
    # the first look, so the monitor answers with it at once and never sees the lasting drop
    assert decision.pipe == "P2" and not decision.waited
    assert decision.time - decision.first_alarm < 1.5
    ranked = [p.pipe for p in decision.ranking.top(4)]
    assert ranked[0] == "P2" and set(ranked) == {"P1", "P2", "P3", "4"}
