"""The monitor's corroboration (burstloc.live.monitor, burstloc.localize.corroborate): alarms
of one meter wait for a second meter until the arrival horizon, then are dismissed.

paper15 with three meters far apart (N3, 8, 6) and a real TSNet burst on pipe 2: meter 8
alarms first, and the wave reaches meter 6 more than the calibrated first look later.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from live_feed import burst_steps

from burstloc.experiments.calibrate import calibrate
from burstloc.live.monitor import BurstMonitor
from burstloc.live.monitor_state import monitor_state, restore_monitor
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.config import Calibration
from burstloc.localize.decide import arrival_horizon
from burstloc.localize.interval import calibrated_bank
from burstloc.readings import Step

METERS = ("N3", "8", "6")
PIPE = "2"


@pytest.fixture(scope="module")
def config(paper15: Path) -> Calibration:
    return calibrate(paper15, capture_intervals=(0.2,), noise_sigma=0.01, meters=METERS)


@pytest.fixture(scope="module")
def steps(paper15: Path, config: Calibration) -> list[Step]:
    return burst_steps(paper15, config.meters, PIPE, before=60.0, after=150.0)


def _first_alarms(config: Calibration, steps: list[Step]) -> list[float]:
    """Each meter's first alarm (reading time), earliest first."""
    values = np.array([s.values for s in steps])
    alarms = calibrated_bank("cusum", len(config.meters), config.for_interval(0.2)).run(values)
    firsts: dict[int, float] = {}
    for a in alarms:
        firsts.setdefault(int(a.channel or 0), steps[a.index].timestamp)
    return sorted(firsts.values())


def _horizon(monitor: BurstMonitor) -> float:
    """Seconds after the first alarm by which a burst's wave has reached every meter (at the
    slowest stated wave speed) and its alarms have been raised."""
    arrival = monitor.localizers["arrival"]
    assert isinstance(arrival, ArrivalLocalizer)
    horizon = arrival_horizon(arrival, monitor.calibration)
    assert horizon > arrival.horizon + 2 * monitor.calibration.capture_interval
    return horizon


def test_a_second_meter_after_the_first_look_corroborates_the_burst(
    paper15: Path, config: Calibration, steps: list[Step]
) -> None:
    first, second = _first_alarms(config, steps)[:2]
    cal = config.for_interval(0.2)
    assert second > first + cal.arrival_decision_delay + 0.2  # heard alone at the first look
    monitor = BurstMonitor(paper15, config, capture_interval=0.2)
    decisions = list(monitor.run(steps))
    assert [d.pipe for d in decisions] == [PIPE] and monitor.dismissed == 0
    decided = decisions[0]
    assert decided.first_alarm == pytest.approx(first)
    assert second <= decided.time < first + _horizon(monitor)
    assert len(decided.alarmed) >= 2


def test_one_meter_alone_is_dismissed_and_counted_at_the_arrival_horizon(
    paper15: Path, config: Calibration, steps: list[Step]
) -> None:
    quiet = [Step(s.timestamp, steps[0].values) for s in steps[:600]]
    glitch = 300
    for k in range(glitch, glitch + 3):  # meter 8 reads 0.5 m low for three readings
        values = quiet[k].values.copy()
        values[1] -= 0.5
        quiet[k] = Step(quiet[k].timestamp, values)
    monitor = BurstMonitor(paper15, config, capture_interval=0.2)
    cal = config.for_interval(0.2)
    horizon = _horizon(monitor)
    assert horizon > cal.arrival_decision_delay + 0.4
    alarm = quiet[glitch].timestamp
    waiting = []
    for step in quiet:
        assert monitor.push(step) is None
        waiting.append((step.timestamp, monitor.pending, monitor.dismissed))
    after_look = [w for w in waiting if alarm + cal.arrival_decision_delay < w[0] < alarm + horizon]
    assert after_look and all(pending and dismissed == 0 for _, pending, dismissed in after_look)
    assert monitor.dismissed == 1 and not monitor.pending
    dismissed_at = next(t for t, _, dismissed in waiting if dismissed)
    assert alarm + horizon - 1e-9 <= dismissed_at <= alarm + horizon + 0.2 + 1e-9


def test_a_state_saved_while_waiting_gives_the_same_decision(
    paper15: Path, config: Calibration, steps: list[Step]
) -> None:
    first, second = _first_alarms(config, steps)[:2]
    whole = list(BurstMonitor(paper15, config, capture_interval=0.2).run(steps))
    cut = next(k for k, s in enumerate(steps) if s.timestamp > (first + second) / 2)
    before = BurstMonitor(paper15, config, capture_interval=0.2)
    assert list(before.run(steps[:cut])) == []
    state = json.loads(json.dumps(monitor_state(before)))
    assert len(state["alarms"]) == 1  # one meter so far, past the first look: waiting
    assert state["due"] < steps[cut - 1].timestamp < state["corroborate_by"]
    again = BurstMonitor(paper15, config, capture_interval=0.2)
    restore_monitor(again, state)
    after = list(again.run(steps[cut:]))
    assert [d.to_json() for d in after] == [d.to_json() for d in whole]
    assert again.dismissed == 0
    # a state saved before the wait: the event was corroborated by its first look or dismissed
    older = BurstMonitor(paper15, config, capture_interval=0.2)
    restore_monitor(older, {k: v for k, v in state.items() if k != "corroborate_by"})
    older.push(steps[cut])
    assert older.dismissed == 1 and not older.pending
