"""The ranking localizers scored as they run live: a simulated burst's readings fed step by
step to the live monitor (:class:`burstloc.live.monitor.BurstMonitor`) of each ranking
localizer, its first decision the attempt's answer.

:class:`RankingSetup` holds what the monitors need (the meters, the calibration, the localizers
built from its model, per capture interval where the fronts are heard slower than the wave:
:meth:`RankingSetup.localizers_at`); :func:`rank_attempts` scores one burst with each
localizer; :func:`locate_ranked` one burst at a clock offset for one run. The readings and the
:class:`~burstloc.experiments.harness.Attempt` come from :mod:`burstloc.experiments.harness`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import WAVE_SPEED, MeterModel
from burstloc.exceptions import InputError
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.harness import Attempt, Readings, readings_at_offset
from burstloc.experiments.runs import RunSpec
from burstloc.live.monitor import BurstMonitor
from burstloc.localize.config import Calibration
from burstloc.localize.decide import Decision, RankingLocalizers
from burstloc.network import Network, NetworkSource, as_network
from burstloc.readings import Step

if TYPE_CHECKING:
    from burstloc.sim.scenarios.result import ScenarioResult
    from burstloc.wave_speeds import WaveSpeeds

__all__ = [
    "RankingSetup",
    "first_decision",
    "locate_ranked",
    "monitor_answer",
    "rank_attempts",
]


@dataclass
class RankingSetup:
    """What the ranking localizers need: the meters (the columns of the readings), the
    calibration of their detector bank, the localizers by name and the network (the monitor
    checks the calibration against it)."""

    meters: list[str]
    config: Calibration
    localizers: RankingLocalizers
    network: Network
    _at: dict[float, RankingLocalizers] = field(default_factory=dict, repr=False)

    def localizers_at(self, capture_interval: float) -> RankingLocalizers:
        """The localizers as the monitor builds them at ``capture_interval``: the model's paths
        timed at the fronts' speed there (:meth:`Calibration.model_at`); :attr:`localizers`
        where that is the wave speed itself."""
        model = self.config.model_at(capture_interval)
        if model is self.config.model:
            return self.localizers
        if capture_interval not in self._at:
            self._at[capture_interval] = RankingLocalizers.from_model(model)
        return self._at[capture_interval]

    @classmethod
    def build(
        cls,
        network: NetworkSource,
        meters: Sequence[str],
        capture_intervals: Sequence[float],
        config: Calibration | None = None,
        wave_speeds: WaveSpeeds | None = None,
        wave_speed: float = WAVE_SPEED,
    ) -> RankingSetup:
        """Localizers for ``meters`` of ``network`` and a calibration covering the intervals.

        The localizers are the calibration's own localization model (``config.model``, what the
        monitor reads: its signatures as ``calibrate`` computed them). Without ``config`` the
        network is calibrated here
        (:func:`burstloc.experiments.calibrate.calibrate` with its defaults, ``wave_speed``
        (m/s, the pipes' without one of their own in ``wave_speeds``) and ``wave_speeds``: the
        simulated bursts' own). A ``config`` for
        another network or other meters is refused by name
        (:meth:`burstloc.experiments.calibrate.Calibration.check`), as is one without an
        interval.
        """
        read = as_network(network)
        if config is None:
            config = calibrate(
                read,
                capture_intervals=capture_intervals,
                meters=meters,
                wave_speed=wave_speed,
                wave_speeds=wave_speeds,
            )
        else:
            config.check(read, meters)
            for ci in capture_intervals:
                config.for_interval(ci)
        # the configuration's own localization model, as the monitor reads it
        return cls(list(meters), config, RankingLocalizers.from_model(config.model), read)


def rank_attempts(
    result: ScenarioResult,
    readings: Readings,
    setup: RankingSetup,
    *,
    detector: str,
    capture_interval: float,
    localizers: Sequence[str],
    meter_model: MeterModel | str = "instantaneous",
    offset: float = 0.0,
) -> dict[str, Attempt]:
    """One burst's readings (of ``setup.meters``, captured every ``capture_interval`` s) fed
    step by step to the live monitor (:class:`burstloc.live.monitor.BurstMonitor`: the
    calibrated ``detector`` bank, the corroboration of its alarms, the looks at the arrivals),
    once for each of ``localizers``; its first decision is the attempt's answer.

    Scoring the monitor itself makes what is scored what runs live: an alarm of one meter
    alone (a noise excursion before the burst) is dismissed as the monitor dismisses it. A
    burst the monitor detects but cannot place (an ``InputError`` it reports and skips) leaves
    it watching for the next alarm, as live. An attempt without a decision is not located.
    ``offset`` is recorded in the attempts.

    Returns:
        The attempt of each localizer, by name.

    Raises:
        InputError: ``readings`` do not have one column per meter of ``setup``.
    """
    times, values = readings
    if values.shape[1] != len(setup.meters):
        raise InputError(f"readings have {values.shape[1]} columns for {len(setup.meters)} meters")
    burst_start = float(result.metadata["burst_start"])
    out: dict[str, Attempt] = {}
    for name in dict.fromkeys(localizers):
        monitor = BurstMonitor(
            setup.network,
            setup.config,
            capture_interval=capture_interval,
            detector=detector,
            localizer=name,
            meter_model=meter_model,  # type: ignore[arg-type]
            localizers=setup.localizers_at(capture_interval),
        )
        early, decision = monitor_answer(monitor, times, values)
        out[name] = Attempt(result.pipe, offset, burst_start, decision=decision, early=early)
    return {name: out[name] for name in localizers}


def monitor_answer(
    monitor: BurstMonitor, times: NDArray[np.float64], values: NDArray[np.float64]
) -> tuple[tuple[Decision, ...], Decision | None]:
    """``(early, answer)``: the first answer of ``monitor`` fed the readings ``(times,
    values)`` step by step (a decision or event, ``None`` without one) and the early
    (transient) records before it. A burst it detects but cannot place is skipped, as the live
    loop skips it. A NaN is a meter that sent nothing: named in the step's ``filled``, as the
    live feed names it."""
    early: list[Decision] = []
    gaps = np.isnan(values)
    for t, row, gap in zip(times.tolist(), values, gaps, strict=True):
        filled = tuple(monitor.meters[j] for j in np.flatnonzero(gap)) if gap.any() else ()
        try:
            decided = monitor.push(Step(t, row, filled))
        except InputError:
            continue
        if decided is not None and decided.transient:
            early.append(decided.decision)
        elif decided is not None:
            return tuple(early), decided.decision
    return tuple(early), None


def first_decision(
    monitor: BurstMonitor, times: NDArray[np.float64], values: NDArray[np.float64]
) -> Decision | None:
    """The first answer of ``monitor`` fed the readings step by step, or ``None``
    (:func:`monitor_answer`)."""
    return monitor_answer(monitor, times, values)[1]


def locate_ranked(
    result: ScenarioResult, spec: RunSpec, setup: RankingSetup, offset: float = 0.0
) -> Attempt:
    """One burst at a clock offset through the calibrated bank and ``spec``'s ranking
    localizer (:func:`readings_at_offset`, :func:`rank_attempts`)."""
    readings = readings_at_offset(result, spec, offset)
    ranked = rank_attempts(
        result,
        readings,
        setup,
        detector=spec.detector.kind,
        capture_interval=spec.capture_interval,
        localizers=[spec.localizer],
        meter_model=spec.meter_model,
        offset=offset,
    )
    return ranked[spec.localizer]
