"""The live loop of the ranking localizers: complete time steps in, decisions out.

A :class:`BurstMonitor` holds, for one network and one calibrated configuration
(:class:`burstloc.localize.config.Calibration`, e.g. ``burstloc calibrate --out CONFIG``), the
calibrated Rust detector bank of one capture interval, one ranking localizer built from the
configuration's stored localization model (:class:`burstloc.localize.model.LocalizationModel`)
and a bounded history of readings. Each :meth:`BurstMonitor.push` feeds one complete time step (a
:class:`burstloc.live.stream.Step`: one reading per meter, in the configuration's meter order) to
the
bank; once a meter alarms, the monitor answers at the localizer's decision time with the same
rule as ``burstloc evaluate`` (:func:`burstloc.localize.decide.rank_alarms`: about one wave travel
time
after the first alarm for the arrival localizer and a decisive fused one, 150 s after the onset
for the signature localizer and an undecided fused one). A burst rings through the network for
minutes, so after a decision the monitor holds off for ``holdoff`` seconds (default: the
calibrated signature delay, 150 s): the readings still fill the history, alarms are ignored,
and then the bank starts afresh, ready for the next burst. A second burst within the hold-off is
not reported separately.

Raw ``(timestamp, meter, value)`` readings become steps through
:class:`burstloc.live.stream.ReadingStream` (its rules for late, duplicate and missing readings);
:func:`monitor_readings` wires the two. Bad input (a step with the wrong number of values, a
non-finite value, a timestamp that does not advance) raises
:class:`~burstloc.exceptions.InputError` naming it (and the meter) and leaves the monitor exactly
as it was. A configuration for another network or other meters is refused by name; the network
file is only hashed (:func:`burstloc.inp.network_hash`), never loaded. Each decision is a
:class:`burstloc.localize.decide.Decision` (its ``to_json`` is what ``burstloc monitor`` prints).

Nothing here runs a hydraulic model: this module imports neither WNTR, EPANET, TSNet nor
:mod:`burstloc.sim` or :mod:`burstloc.experiments`.
"""

from __future__ import annotations

import math
import os
from collections import deque
from collections.abc import Iterable, Iterator, Mapping
from typing import Any

import numpy as np

from burstloc.constants import METER_MODELS, RANKING_LOCALIZERS, MeterModel
from burstloc.exceptions import ConfigError, InputError
from burstloc.live.stream import ReadingStream
from burstloc.localize.config import Calibration, calibrated_bank
from burstloc.localize.decide import (
    Decision,
    RankingLocalizers,
    decision_time,
    fused_of,
    rank_alarms,
)
from burstloc.localize.evidence import IndexedAlarm, Localizer
from burstloc.readings import Item, Reading, Step

__all__ = [
    "HISTORY_BEFORE_ONSET",
    "BurstMonitor",
    "monitor_readings",
    "parse_readings",
]

#: Seconds of readings kept before a burst's onset (the baseline of the signature localizer).
HISTORY_BEFORE_ONSET = 60.0


class BurstMonitor:
    """Calibrated detector bank + ranking localizer over a live feed of complete time steps.

    Parameters
    ----------
    network:
        The EPANET INP file the configuration was calibrated for (checked by its SHA-256).
    config:
        The configuration (``Calibration.load(path)``); its meters are the step's columns and
        its localization model makes the localizers.
    capture_interval:
        Seconds between steps; the configuration must have been calibrated for it.
    detector:
        ``"cusum"`` or ``"shewhart"``.
    localizer:
        ``"arrival"``, ``"signature"`` or ``"fused"`` (default).
    meter_model:
        What a reading is: ``"instantaneous"`` or ``"interval-averaged"``.
    localizers:
        Prebuilt localizers by name (default: built from the configuration's model,
        :meth:`burstloc.localize.decide.RankingLocalizers.from_model`).
    holdoff:
        Seconds after a decision during which alarms are ignored (default: the calibrated
        ``decision_delay``).

    Raises:
        ConfigError: a configuration for another network or other meters, no calibration for
            the capture interval, or an unknown detector, localizer or meter model.
        NetworkError: the network file cannot be read.
    """

    def __init__(
        self,
        network: str | os.PathLike[str],
        config: Calibration,
        *,
        capture_interval: float,
        detector: str = "cusum",
        localizer: str = "fused",
        meter_model: MeterModel = "instantaneous",
        localizers: Mapping[str, Localizer] | None = None,
        holdoff: float | None = None,
    ) -> None:
        if localizer not in RANKING_LOCALIZERS:
            raise ConfigError(f"localizer must be one of {RANKING_LOCALIZERS}, got {localizer!r}")
        if meter_model not in METER_MODELS:
            raise ConfigError(f"meter model must be one of {METER_MODELS}, got {meter_model!r}")
        config.check(network)
        self.meters: tuple[str, ...] = tuple(config.meters)
        self.calibration = config.for_interval(capture_interval)
        self.detector = detector
        self.localizer = localizer
        self.meter_model: MeterModel = meter_model
        self.bank = calibrated_bank(detector, len(self.meters), self.calibration)
        self.localizers: Mapping[str, Localizer] = (
            RankingLocalizers.from_model(config.model) if localizers is None else dict(localizers)
        )
        self._fused = fused_of(self.localizers)
        if localizer not in self.localizers:
            raise ConfigError(f"no {localizer!r} localizer among {sorted(self.localizers)}")
        cal = self.calibration
        self.holdoff = cal.decision_delay if holdoff is None else float(holdoff)
        if not (math.isfinite(self.holdoff) and self.holdoff >= 0):
            raise ConfigError(f"holdoff must be a finite number of seconds >= 0, got {holdoff}")
        span = HISTORY_BEFORE_ONSET + cal.decision_delay + cal.arrival_decision_delay
        steps = math.ceil(span / cal.capture_interval) + 2 * cal.localization_interval + 2
        self._times: deque[float] = deque(maxlen=steps)
        self._values: deque[np.ndarray] = deque(maxlen=steps)
        self._seen = 0  # steps fed to the bank since it last started afresh
        self._alarms: list[Any] = []
        self._due: float | None = None
        self._quiet_until: float | None = None  # end of the hold-off after a decision

    @property
    def pending(self) -> bool:
        """Whether a burst has been detected and awaits its decision."""
        return self._due is not None

    @property
    def holding_off(self) -> bool:
        """Whether the monitor is ignoring alarms after a decision (see ``holdoff``)."""
        return self._quiet_until is not None

    def push(self, step: Step) -> Decision | None:
        """Feed one complete time step; return the decision it completes, if any.

        Raises:
            InputError: wrong number of values, a non-finite value (the bank names the meter
                column) or a timestamp not after the previous one; the monitor is unchanged.
        """
        t = float(step.timestamp)
        values = np.ascontiguousarray(step.values, dtype=np.float64)
        if values.shape != (len(self.meters),):
            raise InputError(
                f"step at t = {t:g} s has {values.size} values for {len(self.meters)} meters"
            )
        if not math.isfinite(t):
            raise InputError(f"step timestamp {t!r} is not finite")
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            j = int(bad[0])
            raise InputError(
                f"non-finite reading {values[j]} from meter {self.meters[j]!r} at t = {t:g} s"
            )
        if self._times and t <= self._times[-1]:
            raise InputError(
                f"step at t = {t:g} s is not after the previous one (t = {self._times[-1]:g} s)"
            )
        if self._quiet_until is not None and t + 1e-9 >= self._quiet_until:
            self.bank.reset()  # the hold-off is over: start afresh for the next burst
            self._seen = 0
            self._quiet_until = None
        alarms = self.bank.step(values)
        self._times.append(t)
        self._values.append(values.copy())
        self._seen += 1
        if self._quiet_until is not None:
            return None
        self._alarms += alarms
        if self._alarms and self._due is None:
            times, _ = self._history()
            self._due = decision_time(
                self.localizer,
                self._shifted(times.size),
                times,
                self.calibration,
                self._fused,
            )
        if self._due is None or t + 1e-9 < self._due:
            return None
        return self._decide()

    def run(self, steps: Iterable[Step]) -> Iterator[Decision]:
        """Yield the decisions of a feed of steps."""
        for step in steps:
            decided = self.push(step)
            if decided is not None:
                yield decided

    def _history(self) -> tuple[np.ndarray, np.ndarray]:
        return np.fromiter(self._times, dtype=np.float64), np.array(self._values)

    def _shifted(self, size: int) -> list[IndexedAlarm]:
        """The bank's alarms with indices into the history (starts clipped to its oldest)."""
        first = self._seen - size  # bank index of the oldest step kept (< 0 after a reset)
        return [
            IndexedAlarm(a.channel, a.index - first, max(a.start - first, 0), a.amplitude)
            for a in self._alarms
            if a.index >= first
        ]

    def _decide(self) -> Decision | None:
        times, readings = self._history()
        alarms = self._shifted(times.size)
        cal = self.calibration
        decision = rank_alarms(
            self.localizer,
            self.localizers,
            self.meters,
            times,
            readings,
            alarms,
            cal,
            self.meter_model,
        )
        if decision.waited:
            settled = decision_time("signature", alarms, times, cal)
            if times[-1] + 1e-9 < settled:  # the fused localizer waits for the signatures
                self._due = settled
                return None
        self._alarms = []
        self._due = None
        self._quiet_until = float(times[-1]) + self.holdoff
        return decision


def monitor_readings(
    monitor: BurstMonitor, readings: Iterable[Item], **stream_options: Any
) -> Iterator[Decision]:
    """Assemble raw readings into steps (:class:`burstloc.live.stream.ReadingStream` over the
    monitor's meters, one step per window; ``stream_options`` such as ``period``, ``timeout``,
    ``missing``) and yield the monitor's decisions."""
    stream = ReadingStream(monitor.meters, 1, **stream_options)
    for window in stream.windows(readings):
        decided = monitor.push(Step(float(window.times[-1]), window.values[-1]))
        if decided is not None:
            yield decided


def parse_readings(lines: Iterable[str]) -> Iterator[Reading]:
    """Readings from CSV lines ``timestamp,meter,value`` (seconds, junction name, metres of head).

    A first line ``timestamp,meter,value`` is a header; blank lines and lines starting with
    ``#`` are skipped.

    Raises:
        InputError: a line without three fields or with a timestamp or value that is not a
            finite number, naming the line.
    """
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = [f.strip() for f in text.split(",")]
        if number == 1 and fields == ["timestamp", "meter", "value"]:
            continue
        if len(fields) != 3:
            raise InputError(f"line {number}: want 'timestamp,meter,value', got {text!r}")
        try:
            timestamp, value = float(fields[0]), float(fields[2])
        except ValueError:
            raise InputError(
                f"line {number}: timestamp and value must be numbers: {text!r}"
            ) from None
        if not (math.isfinite(timestamp) and math.isfinite(value)):
            raise InputError(f"line {number}: non-finite timestamp or value: {text!r}")
        yield Reading(timestamp, fields[1], value)
