"""How many meters make a burst, and until when (burstloc.localize.corroborate), on the line
network."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from burstloc.exceptions import InputError
from burstloc.localize.corroborate import corroborated_at, corroboration_deadline
from burstloc.localize.decide import RankingLocalizers, arrival_horizon, decision_time
from burstloc.localize.evidence import IndexedAlarm
from burstloc.localize.fused import FusedLocalizer
from burstloc.localize.looks import ALARM_LAG, ALARM_LAG_SECONDS
from line_network import line_arrival, line_calibration, line_signature

TIMES = np.round(np.arange(0.0, 30.0, 0.5), 9)


def _at(t: float, channel: int) -> IndexedAlarm:
    index = int(np.searchsorted(TIMES, t))
    return IndexedAlarm(channel, index, index - 1, -1.0)


def test_each_meter_counts_once_at_its_first_alarm_up_to_the_deadline() -> None:
    # meter 0 alarms twice, meter 2 at 12 s, meter 1 at 13 s
    alarms = [_at(10.0, 0), _at(10.5, 0), _at(13.0, 1), _at(12.0, 2)]
    assert corroborated_at(alarms, TIMES, 2, by=20.0) == 12.0
    assert corroborated_at(alarms, TIMES, 3, by=20.0) == 13.0
    assert corroborated_at(alarms, TIMES, 1, by=20.0) == 10.0
    assert corroborated_at(alarms, TIMES, 0, by=20.0) == 10.0  # at least one meter
    # a meter's alarm after the deadline does not count; one meter alone, however often, not
    assert corroborated_at(alarms, TIMES, 2, by=11.5) is None
    assert corroborated_at(alarms, TIMES, 3, by=12.5) is None
    assert corroborated_at(alarms[:2], TIMES, 2, by=29.0) is None


def test_the_deadline_is_the_later_of_the_decision_time_and_the_arrival_horizon() -> None:
    arrival, signature = line_arrival(), line_signature(np.eye(3, 4))
    localizers = RankingLocalizers(arrival, signature, FusedLocalizer(arrival, signature))
    alarms = [_at(10.0, 1), _at(10.5, 0)]
    early = line_calibration(0.5, arrival_decision_delay=0.5)
    assert arrival.horizon == pytest.approx(1.4)  # the wave's travel to the farthest meter
    # the arrival localizer's first look comes before the horizon: the horizon
    due = decision_time("arrival", alarms, TIMES, early)
    assert due == pytest.approx(10.5)
    by = corroboration_deadline("arrival", localizers, alarms, TIMES, early)
    assert by == pytest.approx(10.0 + arrival_horizon(arrival, early)) and by > due
    # a first look after the horizon, or the signature's decision time: the decision time
    late = line_calibration(0.5, arrival_decision_delay=4.0)
    assert corroboration_deadline("arrival", localizers, alarms, TIMES, late) == 14.0
    signature_due = decision_time("signature", alarms, TIMES, early)
    assert corroboration_deadline("signature", localizers, alarms, TIMES, early) == signature_due
    # without an arrival localizer, the calibrated first look stands for the horizon
    alone = {"signature": signature}
    assert corroboration_deadline("signature", alone, alarms, TIMES, early) == signature_due
    assert corroboration_deadline(
        "signature", alone, alarms, TIMES, replace(early, arrival_decision_delay=90.0)
    ) == pytest.approx(100.0)
    with pytest.raises(InputError, match="no alarm"):
        corroboration_deadline("arrival", localizers, [], TIMES, early)


def test_the_horizon_allows_for_the_slowest_stated_wave_and_the_alarms_lag() -> None:
    arrival = line_arrival()
    assert arrival.horizon == pytest.approx(1.4)  # the farthest meters' spread at the wave speed
    tolerance = arrival.wave_speed_tolerance
    assert tolerance > 0
    spread = 1.4 / (1.0 - tolerance)
    # two readings up to the lag's bound in seconds; one reading at coarse intervals
    assert pytest.approx(0.2 * ALARM_LAG) == ALARM_LAG_SECONDS
    for dt, lag in ((0.01, 0.02), (0.2, 0.4), (0.3, 0.4), (0.5, 0.5), (2.0, 2.0)):
        calibration = line_calibration(dt, arrival_decision_delay=dt)
        assert arrival_horizon(arrival, calibration) == pytest.approx(spread + lag), dt
    # the second meter's alarm raised two readings after the bare spread still corroborates
    signature = line_signature(np.eye(3, 4))
    localizers = RankingLocalizers(arrival, signature, FusedLocalizer(arrival, signature))
    calibration = line_calibration(0.2, arrival_decision_delay=0.2)
    times = np.round(np.arange(0.0, 30.0, 0.2), 9)
    first, second = 50, 59  # 10.0 s and 11.8 s: more than 1.47 s apart, within 1.47 + 2 x 0.2
    alarms = [IndexedAlarm(0, first, first - 1, -1.0), IndexedAlarm(2, second, second - 1, -1.0)]
    by = corroboration_deadline("arrival", localizers, alarms, times, calibration)
    assert 10.0 + spread < 11.8 <= by
    assert corroborated_at(alarms, times, 2, by) == pytest.approx(11.8)
    assert corroborated_at(alarms, times, 2, 10.0 + spread) is None  # the bare spread
