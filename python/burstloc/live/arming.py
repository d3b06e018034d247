"""After a decision: the monitor's hold-off, then its re-arming.

A burst rings through the network for minutes. After a decision the monitor holds off for
``holdoff`` seconds (default: the calibrated signature delay, 150 s): the readings still fill
its history, alarms are ignored. Then the bank starts afresh from the current level and
*re-arms*: it must run ``rearm`` steps in a row without an alarm (any alarm restarts the bank
and the count) and the ringing must have died down (the step-to-step changes of the last
:data:`QUIET_WINDOW` seconds back within :data:`QUIET_FACTOR` of the calibrated noise's,
:func:`rang_out`; or one more hold-off gone by) before an alarm may start a new decision, so the
tail of the ringing never becomes a phantom second burst. A second burst within the hold-off is
not reported separately.

:class:`Arming` holds that state for :class:`burstloc.live.monitor.BurstMonitor`; numpy only.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError
from burstloc.live.history import RowHistory

__all__ = ["QUIET_FACTOR", "QUIET_WINDOW", "Arming", "rang_out"]

#: Re-arming waits until the step-to-step changes of the last QUIET_WINDOW seconds are back to
#: within QUIET_FACTOR of the calibrated noise's (the ringing has died down), at most one more
#: hold-off.
QUIET_WINDOW = 30.0
QUIET_FACTOR = 1.3


def rang_out(history: RowHistory, steps: int, noise: NDArray[np.float64]) -> NDArray[np.bool_]:
    """Per meter, whether the ringing has died down: over the last ``steps`` steps of
    ``history``, the step-to-step RMS change is within :data:`QUIET_FACTOR` of that of the
    meter's ``noise`` (its standard deviation, m). All false while the history holds ``steps``
    steps or fewer."""
    if len(history) <= steps:
        return np.zeros(history.width, dtype=bool)
    recent = history.last(steps + 1)
    rms = np.sqrt(np.mean(np.diff(recent, axis=0) ** 2, axis=0))
    quiet: NDArray[np.bool_] = rms <= QUIET_FACTOR * math.sqrt(2.0) * noise
    return quiet


class Arming:
    """The hold-off after a decision and the re-arming after it (module docstring).

    ``holdoff``: seconds of reading time alarms are ignored after a decision; ``rearm``:
    alarm-free steps needed after it; ``settle``: whether re-arming also waits for the ringing
    to die down (or one more hold-off).

    Raises:
        ConfigError: a ``holdoff`` that is not a finite number of seconds >= 0, a ``rearm`` that
            is not a whole number of steps >= 0.
    """

    def __init__(self, holdoff: float, rearm: int, settle: bool) -> None:
        seconds = float(holdoff)
        if not (math.isfinite(seconds) and seconds >= 0):
            raise ConfigError(f"holdoff must be a finite number of seconds >= 0, got {holdoff}")
        if isinstance(rearm, bool) or not isinstance(rearm, int) or rearm < 0:
            raise ConfigError(f"rearm must be a whole number of steps >= 0, got {rearm!r}")
        self.holdoff = seconds
        self.rearm = rearm
        self.settle = settle
        #: End of the hold-off after a decision (reading time), ``None`` outside one.
        self.quiet_until: float | None = None
        #: Alarm-free steps still needed while re-arming.
        self.steps_left = 0
        #: Re-arming: re-armed by then (reading time) even if still ringing; ``None`` when armed.
        self.arm_by: float | None = None

    @property
    def holding_off(self) -> bool:
        """Whether alarms are ignored after a decision."""
        return self.quiet_until is not None

    @property
    def arming(self) -> bool:
        """Whether the hold-off is over and the bank is re-arming."""
        return self.arm_by is not None

    def hold(self, t: float) -> None:
        """A decision at reading time ``t``: the hold-off starts."""
        self.quiet_until = t + self.holdoff

    def hold_over(self, t: float) -> bool:
        """Whether the hold-off ends at the step at ``t`` (re-arming starts; the caller starts
        the bank afresh from the current level)."""
        if self.quiet_until is None or t + 1e-9 < self.quiet_until:
            return False
        self.quiet_until = None
        self.steps_left = self.rearm
        self.arm_by = t + self.holdoff
        return True

    def armed(self, t: float, alarmed: bool, rang_out: Callable[[], bool]) -> tuple[bool, bool]:
        """After the bank's step at ``t`` (``alarmed``: it raised alarms): whether alarms count,
        and whether the bank must start afresh (an alarm while re-arming). ``rang_out`` tells
        whether the ringing has died down (asked only when it decides)."""
        if self.quiet_until is not None:
            return False, False
        if self.arm_by is None:
            return True, False
        if alarmed:
            self.steps_left = self.rearm
        elif self.steps_left > 0:
            self.steps_left -= 1
        settled = not self.settle or t + 1e-9 >= self.arm_by or rang_out()
        if self.steps_left == 0 and settled:
            self.arm_by = None
        return False, alarmed
