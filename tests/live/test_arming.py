"""burstloc.live.arming: the hold-off after a decision and the re-arming after it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.live.arming import Arming, rang_out
from burstloc.live.history import RowHistory


def never() -> bool:
    return False


def test_alarms_count_only_once_the_hold_off_and_the_re_arming_are_over() -> None:
    arm = Arming(holdoff=10.0, rearm=3, settle=False)
    assert arm.armed(0.0, True, never) == (True, False)  # armed: an alarm counts
    arm.hold(1.0)
    assert arm.holding_off and not arm.arming
    assert not arm.hold_over(10.9)
    assert arm.armed(10.9, True, never) == (False, False)  # ignored, the bank left alone
    assert arm.hold_over(11.0)  # the bank starts afresh here
    assert arm.arming and not arm.holding_off
    assert arm.armed(11.0, False, never) == (False, False)
    assert arm.armed(11.1, True, never) == (False, True)  # an alarm: bank afresh, count anew
    for t in (11.2, 11.3):
        assert arm.armed(t, False, never) == (False, False)
        assert arm.arming
    assert arm.armed(11.4, False, never) == (False, False)  # the third alarm-free step
    assert not arm.arming
    assert arm.armed(11.5, True, never) == (True, False)


def test_re_arming_waits_for_the_ringing_or_one_more_hold_off() -> None:
    arm = Arming(holdoff=10.0, rearm=0, settle=True)
    arm.hold(0.0)
    assert arm.hold_over(10.0)
    asked: list[float] = []

    def ringing() -> bool:
        asked.append(1.0)
        return False

    assert arm.armed(10.0, False, ringing) == (False, False)
    assert arm.armed(19.9, False, ringing) == (False, False) and arm.arming
    assert len(asked) == 2  # asked while it decides
    arm.armed(20.0, False, ringing)  # one more hold-off: re-armed though still ringing
    assert not arm.arming and len(asked) == 2
    arm.hold(30.0)
    assert arm.hold_over(40.0)
    arm.armed(40.0, False, lambda: True)  # the ringing has died down
    assert not arm.arming


def test_the_ringing_has_died_down_where_the_step_changes_are_back_to_the_noise() -> None:
    rng = np.random.default_rng(4)
    noise = np.full(4, 0.01)  # as calibrated
    actual = np.array([0.01, 0.01, 0.016, 0.011])  # the last two: 1.6 and 1.1 times that
    history = RowHistory(400, 4)
    assert not rang_out(history, 150, noise).any()  # nothing to judge yet
    for k in range(400):
        ringing = 0.5 * np.sin(k) * np.exp(-k / 800)  # meter 0 still rings
        history.append(np.array([10.0 + ringing, 20.0, 30.0, 40.0]) + rng.normal(0.0, actual))
    # quiet within QUIET_FACTOR (1.3) of the calibrated noise's step-to-step change
    assert rang_out(history, 150, noise).tolist() == [False, True, False, True]


@pytest.mark.parametrize(
    ("holdoff", "rearm", "named"),
    [(-1.0, 2, "holdoff"), (math.inf, 2, "holdoff"), (math.nan, 2, "holdoff"),
     (10.0, -1, "rearm"), (10.0, 2.5, "rearm"), (10.0, True, "rearm")],
)  # fmt: skip
def test_a_bad_hold_off_or_re_arming_is_refused_by_name(
    holdoff: float, rearm: int, named: str
) -> None:
    with pytest.raises(ConfigError, match=named):
        Arming(holdoff, rearm, settle=True)
