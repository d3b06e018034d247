"""The live loop of the ranking localizers: complete time steps in, decisions out.

A :class:`BurstMonitor` holds, for one network and one calibrated configuration
(:class:`burstloc.localize.config.Calibration`, e.g. ``burstloc calibrate --out CONFIG``), the
calibrated Rust detector bank of one capture interval, the ranking localizers built from the
configuration's stored localization model (:class:`burstloc.localize.model.LocalizationModel`)
and a bounded history of readings. Each :meth:`BurstMonitor.push` feeds one complete time step (a
:class:`burstloc.readings.Step`: one reading per meter, in the configuration's meter order) to
the bank; once a meter alarms, the monitor answers at the localizer's decision time with the same
rule as ``burstloc evaluate`` (:func:`burstloc.localize.decide.rank_alarms`), ranking again at
the next look while the arrivals seen so far are not decisive (``Decision.look_again``).

After a decision the monitor holds off for ``holdoff`` seconds (default: the calibrated signature
delay, 150 s), then re-arms (:mod:`burstloc.live.arming`: ``rearm`` alarm-free steps and the ringing
died down), so that the tail of a burst's ringing never becomes a phantom second burst; a second
burst within the hold-off is not reported separately. A decision needs alarms from at least
``corroborate`` meters (default 2; :mod:`burstloc.localize.corroborate`): alarms not corroborated by
the first decision time are kept, with the first alarms of meters that alarm later (a burst on a
large main reaches far meters late or below the threshold), until enough meters have alarmed (the
monitor then decides, looking at the arrivals from the reading that corroborated them) or the
arrival horizon after the first alarm has passed. A single meter's alarm (the calibrated false
alarms of a noisy meter, the tail of the ringing after the hold-off) is dismissed and counted at
that horizon, later than the first decision time (on EPANET's Net3, 19.8 s after the alarm).

**Meters that do not report.** :attr:`BurstMonitor.excluded` (kept by the live loop from
:mod:`burstloc.live.health`: silent meters) take no part: their alarms are ignored and the
localizers run on the other meters (:class:`burstloc.live.subset.SubsetLocalizers`). A value
filled for a meter (named in :attr:`Step.filled`; NaN when the stream had nothing to fill with)
is replaced by the meter's last value (at first its steady head from the model) and cannot
alarm. A meter that comes back is ignored for ``rearm`` steps while its detector settles.

Bad input (a step with the wrong number of values, a non-finite value of a meter that reported,
a timestamp that does not advance) raises :class:`~burstloc.exceptions.InputError` naming it
and leaves the monitor exactly as it was. A configuration for another network or other meters
is refused by name; the network file is only hashed (:func:`burstloc.inp.network_hash`). Each
decision is a :class:`~burstloc.live.decision.LiveDecision`.
:mod:`burstloc.live.monitor_state` carries the whole state (bank snapshot, history, pending
decision and its corroboration deadline, hold-off) across a restart.

Nothing here runs a hydraulic model: this module imports neither WNTR, EPANET, TSNet nor
:mod:`burstloc.sim` or :mod:`burstloc.experiments`.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import replace

import numpy as np

from burstloc.constants import MAX_SAMPLE, METER_MODELS, RANKING_LOCALIZERS, MeterModel
from burstloc.exceptions import ConfigError, InputError
from burstloc.live.arming import QUIET_WINDOW, Arming, rang_out
from burstloc.live.decision import LiveDecision
from burstloc.live.history import RowHistory
from burstloc.live.observe import LiveObserver
from burstloc.live.subset import SubsetLocalizers, taking_part
from burstloc.localize.classify import ClassifierConfig, EventClassifier, Operation, classify_alarms
from burstloc.localize.config import Calibration
from burstloc.localize.corroborate import CORROBORATE, corroborated_at, corroboration_deadline
from burstloc.localize.decide import (
    Decision,
    RankingLocalizers,
    decision_time,
    early_answer,
    early_time,
    fused_of,
    horizon_of,
    rank_alarms,
)
from burstloc.localize.evidence import IndexedAlarm, Localizer
from burstloc.localize.interval import calibrated_bank
from burstloc.network import NetworkSource
from burstloc.readings import Step, step_values

_Part = tuple[np.ndarray, np.ndarray, list[IndexedAlarm], tuple[str, ...], Mapping[str, Localizer]]

__all__ = ["HISTORY_BEFORE_ONSET", "BurstMonitor"]

#: Seconds of readings kept before a burst's onset (the baseline of the signature localizer).
HISTORY_BEFORE_ONSET = 60.0


class BurstMonitor:
    """Calibrated detector bank + ranking localizers over a live feed of complete time steps.

    Parameters
    ----------
    network:
        The EPANET INP file the configuration was calibrated for (checked by its SHA-256), or
        the :class:`~burstloc.network.Network` read from it.
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
        Prebuilt localizers by name (default: built from the configuration's model). With
        prebuilt localizers, excluded meters cannot be left out of the localization.
    holdoff:
        Seconds after a decision during which alarms are ignored (default: the calibrated
        ``decision_delay``).
    rearm:
        Alarm-free steps needed after the hold-off before an alarm counts again (default: two
        localization intervals).
    settle:
        Whether re-arming also waits for the ringing to die down (default: yes; module
        docstring).
    corroborate:
        Meters that must have alarmed (default 2; fewer when fewer meters report) by the later
        of the decision time and the arrival horizon after the first alarm
        (:func:`burstloc.localize.corroborate.corroboration_deadline`). Alarms of fewer meters
        are dismissed then (counted in :attr:`dismissed`): a burst reaches every meter near it,
        a noise excursion or a glitch one.

    Raises:
        ConfigError: a configuration for another network or other meters, no calibration for
            the capture interval, an unknown detector, localizer or meter model, a bad
            ``holdoff`` or ``rearm``.
        NetworkError: the network file cannot be read.
    """

    def __init__(
        self,
        network: NetworkSource,
        config: Calibration,
        *,
        capture_interval: float,
        detector: str = "cusum",
        localizer: str = "fused",
        meter_model: MeterModel = "instantaneous",
        localizers: Mapping[str, Localizer] | None = None,
        holdoff: float | None = None,
        rearm: int | None = None,
        corroborate: int = CORROBORATE,
        settle: bool = True,
        classify: ClassifierConfig | None = None,
        operations: Sequence[Operation] = (),
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
        model = config.model_at(capture_interval)  # paths timed at the fronts' speed there
        self._subsets = SubsetLocalizers(model) if localizers is None else None
        self.localizers: Mapping[str, Localizer] = (
            RankingLocalizers.from_model(model) if localizers is None else dict(localizers)
        )
        self._fused = fused_of(self.localizers)
        if localizer not in self.localizers:
            raise ConfigError(f"no {localizer!r} localizer among {sorted(self.localizers)}")
        cal = self.calibration
        self._arm = Arming(
            cal.decision_delay if holdoff is None else holdoff,
            2 * cal.localization_interval if rearm is None else rearm,
            bool(settle),
        )
        if isinstance(corroborate, bool) or not isinstance(corroborate, int) or corroborate < 1:
            raise ConfigError(f"corroborate must be a whole number >= 1, got {corroborate!r}")
        self.corroborate = corroborate
        self.dismissed = 0  # alarms not corroborated by enough meters
        self.steady = np.asarray(config.model.signature_sets[0].baseline, dtype=np.float64)
        span = HISTORY_BEFORE_ONSET + cal.decision_delay + cal.arrival_decision_delay
        steps = math.ceil(span / cal.capture_interval) + 2 * cal.localization_interval + 2
        self._times: deque[float] = deque(maxlen=steps)
        self._values = RowHistory(steps, len(self.meters))
        self._fill = self.steady.copy()  # last value of each meter (filled values replace NaN)
        self._seen = 0  # steps fed to the bank since it last started afresh
        self._steps = 0  # steps fed in all
        self._alarms: list[IndexedAlarm] = []  # by bank index
        self._due: float | None = None
        self._by: float | None = None  # corroborated by then, or dismissed (the deadline)
        self._resume: float | None = None  # the next look at the arrivals (Decision.look_again)
        self._announced = False  # the pending decision's transient record has been given
        self._early: float | None = None  # the fused localizer's early answer is due then
        self._noise = np.array([max(config.noise_sigma.get(m, 0.0), 1e-3) for m in self.meters])
        self._quiet_steps = max(math.ceil(QUIET_WINDOW / cal.capture_interval), 5)
        self._grace: dict[str, int] = {}  # meter back from silence -> step it counts again
        self.excluded: set[str] = set()
        self.classifier = (
            None if classify is None else EventClassifier.of(classify, self.localizers)
        )
        self.operations = list(operations)
        #: Told of every alarm that counts (:meth:`LiveObserver.alarm`); set by the live loop.
        self.observer: LiveObserver | None = None

    @property
    def pending(self) -> bool:
        """Whether a burst has been detected and awaits its decision."""
        return self._due is not None

    @property
    def holdoff(self) -> float:
        """Seconds after a decision during which alarms are ignored."""
        return self._arm.holdoff

    @property
    def rearm(self) -> int:
        """Alarm-free steps needed after the hold-off before an alarm counts again."""
        return self._arm.rearm

    @property
    def holding_off(self) -> bool:
        """Whether the monitor is ignoring alarms after a decision (see ``holdoff``)."""
        return self._arm.holding_off

    @property
    def arming(self) -> bool:
        """Whether the monitor is re-arming after a hold-off (see ``rearm``)."""
        return self._arm.arming

    def exclude(self, meter: str) -> None:
        """Leave ``meter`` out (silent) until :meth:`include`."""
        self.excluded.add(meter)

    def include(self, meter: str) -> None:
        """Take ``meter`` back; its alarms count again after ``rearm`` steps."""
        if meter in self.excluded:
            self.excluded.discard(meter)
            self._grace[meter] = self._steps + self.rearm

    def push(self, step: Step) -> LiveDecision | None:
        """Feed one complete time step; return the decision it completes, if any.

        Raises:
            InputError: not a :class:`Step`, wrong number of values, a non-finite or
                out-of-range value (beyond :data:`~burstloc.constants.MAX_SAMPLE`) of a meter
                that is neither excluded nor filled, a timestamp not after the previous one, or
                a burst that the localizer cannot place (the pending decision is then dropped);
                the monitor is otherwise unchanged.
        """
        if not isinstance(step, Step):  # e.g. a ReadingStream's Window: name the fix
            raise InputError(
                f"push takes a complete time step (burstloc.Step, from a burstloc.StepFeed), "
                f"got {type(step).__name__}"
            )
        t = float(step.timestamp)
        values = step_values(step)
        if values.shape != (len(self.meters),):
            raise InputError(
                f"step at t = {t:g} s has {values.size} values for {len(self.meters)} meters"
            )
        if not math.isfinite(t):
            raise InputError(f"step timestamp {t!r} is not finite")
        absent = set(step.filled) | self.excluded if step.filled or self.excluded else set()
        if not np.abs(values).max() <= MAX_SAMPLE:  # False for NaN too: the detectors' rule
            bad = np.flatnonzero(~(np.abs(values) <= MAX_SAMPLE))
            for j in bad:
                if self.meters[j] not in absent:
                    kind = "non-finite" if not math.isfinite(values[j]) else "out-of-range"
                    raise InputError(
                        f"{kind} reading {values[j]} from meter {self.meters[j]!r} at t = {t:g} s"
                    )
            values = values.copy()  # the step's own array is never written
            values[bad] = self._fill[bad]
        if self._times and t <= self._times[-1]:
            raise InputError(
                f"step at t = {t:g} s is not after the previous one (t = {self._times[-1]:g} s)"
            )
        self._fill = values
        if self._arm.hold_over(t):
            self._restart_bank()  # the hold-off is over: start afresh from the current level
        alarms = self.bank.step(values)
        self._times.append(t)
        self._values.append(values)
        self._seen += 1
        self._steps += 1
        arm = self._arm
        if arm.quiet_until is not None or arm.arm_by is not None:  # after a decision
            counts, restart = arm.armed(t, bool(alarms), self._settled)
            if restart:
                self._restart_bank()
            if not counts:
                return None
        if alarms:  # each meter's first alarm only: the localizers use first arrivals
            alarmed = {a.channel for a in self._alarms}
            for a in alarms:
                channel = int(a.channel or 0)
                if channel not in alarmed and self._counts(self.meters[channel], absent):
                    self._alarms.append(IndexedAlarm(channel, a.index, a.start, a.amplitude))
                    alarmed.add(channel)
                    if self.observer is not None:
                        onset = self._times[max(a.start - self._seen + len(self._times), 0)]
                        self.observer.alarm(self.meters[channel], t, onset, a.amplitude)
        if self._alarms and self._due is None:
            times = np.fromiter(self._times, dtype=np.float64)
            shifted, cal = self._shifted(times.size), self.calibration
            self._due = decision_time(self.localizer, shifted, times, cal, self._fused)
            self._by = corroboration_deadline(self.localizer, self.localizers, shifted, times, cal)
            self._early = early_time(self.localizer, shifted, times, cal, self._fused)
        if self._early is not None and t + 1e-9 >= self._early and not self._announced:
            early = self._early_answer()
            if early is not None:
                return early
        if self._due is None or t + 1e-9 < self._due:
            return None
        times = np.fromiter(self._times, dtype=np.float64)
        needed = min(self.corroborate, len(self.meters) - len(self.excluded))
        by = self._due if self._by is None else self._by
        corroborated = corroborated_at(self._shifted(times.size), times, needed, by)
        if corroborated is None:
            if t + 1e-9 < by:
                return None  # more meters may still alarm: the wave is still on its way
            self.dismissed += 1  # one meter alone: noise or a glitch, not a burst
            self._forget()
            return None
        # no look at the arrivals before the reading that corroborated them
        if self._resume is None or self._resume < corroborated:
            self._resume = corroborated
        return self._decide()

    def run(self, steps: Iterable[Step]) -> Iterator[LiveDecision]:
        """Yield the decisions of a feed of steps."""
        for step in steps:
            decided = self.push(step)
            if decided is not None:
                yield decided

    def _counts(self, meter: str, absent: set[str]) -> bool:
        return meter not in absent and self._grace.get(meter, -1) <= self._steps

    def _settled(self) -> bool:
        """Whether the ringing has died down at every reporting meter
        (:func:`burstloc.live.arming.rang_out`)."""
        if len(self._values) <= self._quiet_steps:
            return False
        quiet = rang_out(self._values, self._quiet_steps, self._noise)
        return all(q or m in self.excluded for q, m in zip(quiet, self.meters, strict=True))

    def _forget(self) -> None:
        """Drop the pending alarms and their decision."""
        self._alarms, self._announced = [], False
        self._due = self._by = self._resume = self._early = None

    def _restart_bank(self) -> None:
        self.bank.reset()
        self._seen = 0

    def _shifted(self, size: int) -> list[IndexedAlarm]:
        """The bank's alarms with indices into the history (starts clipped to its oldest)."""
        first = self._seen - size  # bank index of the oldest step kept (< 0 after a reset)
        return [
            IndexedAlarm(a.channel, a.index - first, max(a.start - first, 0), a.amplitude)
            for a in self._alarms
            if a.index >= first
        ]

    def _taking_part(self) -> _Part:
        """``(times, readings, alarms, meters, localizers)`` of the meters taking part
        (:func:`burstloc.live.subset.taking_part`)."""
        times = np.fromiter(self._times, dtype=np.float64)
        readings, alarms, meters, localizers = taking_part(
            self.meters, self.excluded, self.localizers, self._subsets,
            self._values.array(), self._shifted(times.size),
        )  # fmt: skip
        return times, readings, alarms, meters, localizers

    def _early_answer(self) -> LiveDecision | None:
        """The fused localizer's early answer, as a transient record, once enough meters have
        corroborated the alarms (``None`` before; while its looks at the arrivals wait for
        more readings, when the next is due; or when the arrivals place the burst nowhere)."""
        times, readings, alarms, meters, localizers = self._taking_part()
        needed = min(self.corroborate, len(self.meters) - len(self.excluded))
        if not alarms or corroborated_at(alarms, times, needed, float(times[-1])) is None:
            return None
        fused = fused_of(localizers)
        if fused is None:
            self._early = None
            return None
        cal = self.calibration
        decision = early_answer(
            fused, meters, times, readings, alarms, cal, self.meter_model, resume=self._early
        )
        if decision is not None and decision.look_again is not None:
            self._early = decision.look_again  # not decisive yet: the next look is due then
            return None
        self._early = None
        if decision is None:
            return None
        self._announced = True
        settled = decision_time("signature", alarms, times, cal)
        return self._record(decision, meters, alarms, localizers, settled)

    def _record(
        self,
        decision: Decision,
        meters: Sequence[str],
        alarms: Sequence[IndexedAlarm],
        localizers: Mapping[str, Localizer],
        answer_at: float | None = None,
    ) -> LiveDecision:
        """``decision`` as the monitor reports it, over the meters taking part; with
        ``answer_at``, the early (transient) record of an answer due then."""
        alarmed = tuple(sorted({meters[a.channel] for a in alarms}, key=self.meters.index))
        excluded = tuple(m for m in self.meters if m in self.excluded)
        if answer_at is not None:
            classifying = self.classifier is not None
            # answer_at is decision_time("signature", ...): the onset plus the decision delay
            wait = self.calibration.decision_delay
            return LiveDecision(
                decision, self.localizer, tuple(meters), excluded, alarmed, False, answer_at,
                classifying=classifying, wait=wait,
            )  # fmt: skip
        looked = horizon_of(localizers, self.calibration)
        waited = decision.waited or (
            decision.time - decision.first_alarm > looked + self.calibration.capture_interval + 1e-9
        )
        return LiveDecision(decision, self.localizer, tuple(meters), excluded, alarmed, waited)

    def _decide(self) -> LiveDecision | None:
        times, readings, alarms, meters, localizers = self._taking_part()
        cal = self.calibration
        try:
            if not alarms:
                raise InputError("every meter that alarmed has gone silent")
            decision = rank_alarms(
                self.localizer,
                localizers,
                meters,
                times,
                readings,
                alarms,
                cal,
                self.meter_model,
                resume=self._resume,
                provisional=False,  # a look not decisive yet is discarded: looked at again
            )
        except InputError as exc:
            self._forget()
            raise InputError(
                f"burst detected but not located at t = {times[-1]:g} s: {exc}"
            ) from exc
        if decision.look_again is not None:
            self._due = decision.look_again  # the arrivals are not decisive yet: more are due
            self._resume = decision.look_again
            return None
        settled = decision_time("signature", alarms, times, cal)
        if (decision.waited or self.classifier) and times[-1] + 1e-9 < settled:
            self._due = settled  # the fused localizer or the classifier waits for the signatures
            if self._announced:
                return None
            # Located now, answered when the lasting change has settled: say where at once.
            self._announced = True
            return self._record(decision, meters, alarms, localizers, settled)
        if self.classifier is not None:  # over the meters that take part
            classifier = EventClassifier.of(self.classifier.config, localizers, self.operations)
            kind = classify_alarms(
                classifier, meters, times, readings, alarms, cal, self.meter_model, settled
            )
            # answered now, whatever time the ranking itself could have been given
            decision = replace(decision, time=float(times[-1]), classification=kind)
        self._forget()
        self._arm.hold(float(times[-1]))
        return self._record(decision, meters, alarms, localizers)
