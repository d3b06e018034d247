"""A :class:`~burstloc.live.monitor.BurstMonitor`'s state across a restart: the detector bank
snapshot, the history ring, the pending decision and its corroboration deadline, the hold-off
and re-arming, the dismissed count and the meters excluded or in their grace period, as
JSON-ready data (the live loop writes it in its state file, :mod:`burstloc.live.state`)."""

from __future__ import annotations

import base64
from collections import deque
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc import _core
from burstloc.exceptions import ConfigError
from burstloc.live.history import RowHistory
from burstloc.localize.evidence import IndexedAlarm

if TYPE_CHECKING:
    from burstloc.live.monitor import BurstMonitor

__all__ = ["monitor_state", "restore_monitor"]


def monitor_state(monitor: BurstMonitor) -> dict[str, Any]:
    """The whole state of ``monitor``, JSON-ready."""
    m = monitor
    return {
        "bank": base64.b64encode(m.bank.snapshot()).decode("ascii"),
        "times": list(m._times),
        "values": m._values.tolist(),
        "fill": m._fill.tolist(),
        "seen": m._seen,
        "steps": m._steps,
        "alarms": [[a.channel, a.index, a.start, a.amplitude] for a in m._alarms],
        "due": m._due,
        "corroborate_by": m._by,
        "resume": m._resume,
        "early": m._early,
        "announced": m._announced,
        "quiet_until": m._arm.quiet_until,
        "arming": m._arm.steps_left,
        "arm_by": m._arm.arm_by,
        "dismissed": m.dismissed,
        "grace": dict(m._grace),
        "excluded": sorted(m.excluded),
    }


def restore_monitor(monitor: BurstMonitor, state: Mapping[str, Any]) -> None:
    """Carry ``monitor`` on from :func:`monitor_state` of a monitor of the same configuration
    and options.

    Raises:
        ConfigError: the saved bank is not this monitor's kind and size.
    """
    m = monitor
    bank = _core.DetectorBank.restore(base64.b64decode(state["bank"]))
    if bank.kind != m.bank.kind or bank.channels != m.bank.channels:
        raise ConfigError(
            f"saved detector bank is {bank.kind} x {bank.channels}, "
            f"not {m.bank.kind} x {m.bank.channels}"
        )
    m.bank = bank
    m._times = deque((float(t) for t in state["times"]), maxlen=m._times.maxlen)
    values = RowHistory(m._values.capacity, m._values.width)
    values.extend(state["values"])
    m._values = values
    m._fill = np.array(state["fill"], dtype=np.float64)
    m._seen, m._steps = int(state["seen"]), int(state["steps"])
    m._alarms = [IndexedAlarm(int(c), int(i), int(s), float(a)) for c, i, s, a in state["alarms"]]
    m._due = state["due"]
    # states saved before: corroborated by the decision time, as the monitor then wanted
    m._by = state.get("corroborate_by", m._due)
    m._resume = state.get("resume")  # states saved before: the looks are taken from the start
    m._announced = bool(state.get("announced", False))  # states saved before: False
    m._early = state.get("early")  # states saved before: no early answer pending
    m._arm.quiet_until = state["quiet_until"]
    m._arm.steps_left = int(state["arming"])
    m._arm.arm_by = state["arm_by"]
    m.dismissed = int(state["dismissed"])
    m._grace = {str(k): int(v) for k, v in state["grace"].items()}
    m.excluded = set(state["excluded"])
