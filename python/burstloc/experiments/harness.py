"""The one experiment harness: a simulated burst in, scored attempts out.

``burstloc evaluate`` (:mod:`burstloc.experiments.evaluate`) and ``burstloc study``
(:mod:`burstloc.experiments.study`) both score through this module, so the two cannot drift
apart:

1. :func:`capture_readings` turns a simulated burst
(:class:`burstloc.sim.scenarios.result.ScenarioResult`)
   into what meters report: the chosen meters' columns, captured under a meter model on a
   :class:`Clock` (its phase, and the readings of the initial steady state that precede the
   simulated span, a live meter's history), with optional sensor noise;
2. :func:`locate_burst` streams them through the paper's rules
   (:class:`burstloc.live.paper_locator.BurstLocator`);
   :func:`burstloc.experiments.ranking.rank_attempts` feeds them, step by step, to the live
   monitor of each ranking localizer and takes its first decision (what runs live is what is
   scored);
3. each outcome is an :class:`Attempt`, and a :class:`Tally` counts attempts into top-1 / top-3
   accuracy, "not located" and the median time from the burst to the decision.

The two experiments differ only in their clocks, stated where they are made:
``evaluate`` moves the clock ``offset`` seconds earlier relative to the burst with ``2N``
steady readings of warm-up (:meth:`Clock.at_offset`); the study starts it ``k / phases`` of an
interval after the simulation's start with ``2N + 1`` steady readings (``N``: the localization
interval).

Calibration (thresholds, localization interval, decision delays) comes from
:mod:`burstloc.experiments.calibrate`, imported by :mod:`burstloc.experiments.ranking` only.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import MeterModel
from burstloc.exceptions import ConfigError, InputError
from burstloc.experiments.runs import RunSpec
from burstloc.inp import check_meters
from burstloc.live.paper_locator import BurstLocator
from burstloc.live.windows import replay
from burstloc.localize.decide import Decision
from burstloc.localize.detection import make_detector
from burstloc.localize.evidence import Ranking
from burstloc.localize.paper_rules import Localization
from burstloc.sim.scenarios.capture import capture

if TYPE_CHECKING:
    import networkx as nx

    from burstloc.sim.scenarios.result import ScenarioResult
    from burstloc.sim.scenarios.sensors import SensorModel

__all__ = [
    "Attempt",
    "Clock",
    "Tally",
    "capture_readings",
    "locate_burst",
    "readings_at_offset",
]

Readings = tuple[NDArray[np.float64], NDArray[np.float64]]


@dataclass(frozen=True)
class Clock:
    """The capture clock of one attempt.

    Attributes:
        capture_interval: seconds between readings.
        phase: the first tick after the simulation's start, seconds after it, in
            ``[0, capture_interval)``.
        history: readings of the initial steady state before that tick, one capture interval
            apart (TSNet starts from the steady state and it holds until the burst: these are
            the readings a meter reported before the simulated span; a streaming detector's
            reference window is full when the span begins).
    """

    capture_interval: float
    phase: float = 0.0
    history: int = 0

    def __post_init__(self) -> None:
        ci = self.capture_interval
        if not (math.isfinite(ci) and ci > 0):
            raise ConfigError(f"capture interval must be > 0 s, got {ci!r}")
        if not (math.isfinite(self.phase) and 0 <= self.phase < ci):
            raise ConfigError(f"clock phase must be in [0, {ci:g}) s, got {self.phase!r}")
        if isinstance(self.history, bool) or not isinstance(self.history, int) or self.history < 0:
            raise ConfigError(f"history must be a number of readings >= 0, got {self.history!r}")

    @classmethod
    def at_offset(cls, capture_interval: float, offset: float, warm_up: int) -> Clock:
        """The clock ticking at ``t0 - offset - warm_up x capture_interval + k x
        capture_interval`` (``t0``: the simulation's start): ``offset`` moves the clock, and
        with it the window grid, that many seconds earlier relative to the burst. The history is
        the ``ceil(offset / capture_interval)`` ticks in ``[t0 - offset, t0)`` and ``warm_up``
        more before them (a whole number of windows does not move the window grid)."""
        ci = float(capture_interval)
        k = math.ceil(offset / ci - 1e-9)  # ticks in [t0 - offset, t0)
        phase = k * ci - offset
        if phase < 1e-9 * ci:
            phase = 0.0
        return cls(ci, phase, k + warm_up)


def capture_readings(
    result: ScenarioResult,
    clock: Clock,
    meter_model: MeterModel | str = "instantaneous",
    *,
    meters: Sequence[str] | None = None,
    sensor: SensorModel | None = None,
    noise_key: int | str = 0,
) -> Readings:
    """What the meters report of one simulated burst: ``(times, values)``, (T,) and (T, M).

    ``meters`` (default: every junction of ``result``, in its order) are sampled on ``clock``
    under ``meter_model`` (:func:`burstloc.sim.scenarios.capture.capture`; sample-and-hold or
    interval
    means of the simulation from its start on), preceded by ``clock.history`` readings of the
    initial steady state. ``sensor`` adds its noise to every reading, history included, drawn
    under ``noise_key``.

    Raises:
        NetworkError: a meter that is not a junction of ``result``.
        ConfigError: the clock's interval is finer than the simulation's time step.
    """
    junctions = list(result.junctions)
    names = (
        junctions if meters is None else check_meters(meters, junctions, "the simulated network")
    )
    columns = [junctions.index(m) for m in names]
    heads = result.heads if meters is None else result.heads[:, columns]
    ci = clock.capture_interval
    t0 = float(result.time[0])
    times, values = capture(result.time - t0, heads, ci, clock.phase, meter_model)
    lead = clock.history
    pre = times[0] - ci * np.arange(lead, 0, -1, dtype=np.float64)
    times = np.concatenate([pre, times]) + t0
    values = np.concatenate([np.repeat(heads[:1], lead, axis=0), values])
    if sensor is not None:
        _, values = sensor.apply(names, values, key=noise_key)
    return times, values


def readings_at_offset(
    result: ScenarioResult,
    spec: RunSpec,
    offset: float,
    meters: Sequence[str] | None = None,
    *,
    sensor: SensorModel | None = None,
) -> Readings:
    """The readings of one run at a clock offset (s): ``meters`` (default every junction), on
    :meth:`Clock.at_offset` with ``2 x interval`` readings of warm-up; ``sensor`` adds its
    noise, drawn under the key ``"<pipe>/<offset>"`` (the same readings for every run at that
    offset and capture interval).

    The capture clock ticks at ``t0 - offset - 2 x interval x capture_interval + k x
    capture_interval`` (``t0``: the simulation's start). Ticks before ``t0`` carry the initial
    steady state, which is exact (TSNet starts from it and it holds until the burst); ticks from
    ``t0`` on sample the simulation (sample-and-hold).
    """
    clock = Clock.at_offset(spec.capture_interval, offset, 2 * spec.localization_interval)
    key = f"{result.pipe}/{offset!r}/{spec.capture_interval!r}"
    return capture_readings(
        result, clock, spec.meter_model, meters=meters, sensor=sensor, noise_key=key
    )


@dataclass(frozen=True)
class Attempt:
    """One burst streamed at one clock offset, and the answer: the paper's rules'
    :class:`~burstloc.localize.paper_rules.Localization` or a ranking localizer's
    :class:`~burstloc.localize.decide.Decision` (the monitor's result type), or neither (not
    located)."""

    pipe: str
    offset: float
    burst_start: float
    localization: Localization | None = None
    decision: Decision | None = None
    early: tuple[Decision, ...] = ()
    """The monitor's early (transient) records before ``decision``, in order: located from
    the arrivals, answered later (:class:`burstloc.live.decision.LiveDecision`)."""
    kept: int | None = None
    """How many best pipes each ranking kept (:meth:`compact`); ``None``: all."""

    @property
    def ranking(self) -> Ranking | None:
        """The ranking localizer's ranking, or ``None``."""
        return None if self.decision is None else self.decision.ranking

    @property
    def decided_at(self) -> float | None:
        """Reading time of the ranking localizer's decision, or ``None``."""
        return None if self.decision is None else self.decision.time

    @property
    def located(self) -> bool:
        """Whether the rules (or a ranking localizer) named a pipe."""
        return self.predicted_pipe is not None

    @property
    def predicted_pipe(self) -> str | None:
        """The named (best-ranked) pipe, or ``None``."""
        if self.ranking is not None:
            best = self.ranking.best
            return None if best is None else best.pipe
        return None if self.localization is None else self.localization.pipe

    @property
    def correct(self) -> bool:
        """Whether the named (best-ranked) pipe is the burst pipe."""
        return self.predicted_pipe == self.pipe

    def in_top(self, k: int) -> bool:
        """Whether the burst pipe is among the ``k`` best-ranked (the paper's rules name one).

        Raises:
            InputError: ``k`` beyond what a compacted attempt kept (:meth:`compact`).
        """
        if self.ranking is not None:
            if self.kept is not None and k > self.kept:
                raise InputError(f"this attempt kept its {self.kept} best pipes, not {k}")
            return self.ranking.in_top(self.pipe, k)
        return self.correct

    def compact(self, keep: int) -> Attempt:
        """The attempt with each decision's ranking cut to its ``keep`` best pipes (a ranking
        of every pipe is about 160 KB on a 900-pipe network; the tables read the first three):
        what a long evaluation holds per burst."""

        def cut(decision: Decision | None) -> Decision | None:
            if decision is None or len(decision.ranking) <= keep:
                return decision
            return replace(decision, ranking=decision.ranking.head(keep))

        return replace(
            self,
            decision=cut(self.decision),
            early=tuple(d for d in map(cut, self.early) if d is not None),
            kept=keep,
        )

    @property
    def predicted(self) -> tuple[str, str] | None:
        """The named pipe's ``(start, end)`` in flow direction, or ``None``."""
        if self.ranking is not None:
            best = self.ranking.best
            return None if best is None else (best.start, best.end)
        loc = self.localization
        return None if loc is None else (loc.start_node, loc.end_node)

    @property
    def time_to_localize(self) -> float | None:
        """Seconds from the burst start to the decision, or ``None``."""
        if self.ranking is not None:
            return None if self.decided_at is None else self.decided_at - self.burst_start
        loc = self.localization
        return None if loc is None else loc.decision_time - self.burst_start


def locate_burst(
    result: ScenarioResult,
    graph: nx.DiGraph,
    spec: RunSpec,
    offset: float = 0.0,
    *,
    sensor: SensorModel | None = None,
) -> Attempt:
    """Stream one simulated burst at a clock offset through the paper's real-time loop.

    The capture clock, and with it the window grid, starts ``offset`` seconds earlier relative
    to the burst than at offset 0 (see :func:`readings_at_offset`); ``sensor`` adds its noise.
    """
    times, values = readings_at_offset(result, spec, offset, sensor=sensor)
    meters = list(result.junctions)
    detector = make_detector(spec.detector, meters, spec.localization_interval, spec.mode)
    locator = BurstLocator(graph, meters, detector, spec.localization_interval)
    outcome = locator.first(replay(times, values))
    burst_start = float(result.metadata["burst_start"])
    return Attempt(result.pipe, offset, burst_start, outcome.localization if outcome else None)


@dataclass
class Tally:
    """Counts of attempts: top-1 / top-3 hits, not located, and the times to a decision.

    Both ``burstloc evaluate`` (:meth:`burstloc.experiments.evaluate.RunResult.tally`) and the
    study's rows count with it.
    """

    attempts: int = 0
    top1: int = 0
    top3: int = 0
    not_located: int = 0
    times: list[float] = field(default_factory=list)

    @classmethod
    def of(cls, attempts: Iterable[Attempt]) -> Tally:
        """The tally of ``attempts``."""
        tally = cls()
        for attempt in attempts:
            tally.add(attempt)
        return tally

    def add(self, attempt: Attempt) -> None:
        """Count one attempt (located: a decision was made, whatever it named)."""
        self.attempts += 1
        self.top1 += attempt.in_top(1)
        self.top3 += attempt.in_top(3)
        ttl = attempt.time_to_localize
        if ttl is None:
            self.not_located += 1
        else:
            self.times.append(ttl)

    @property
    def top1_fraction(self) -> float:
        """Top-1 hits / attempts (eq. 4 over every attempt counted)."""
        return self.top1 / self.attempts

    @property
    def top3_fraction(self) -> float:
        """Top-3 hits / attempts."""
        return self.top3 / self.attempts

    def median_time(self) -> float | None:
        """Median seconds from the burst to the decision over the located attempts, or
        ``None``."""
        return float(statistics.median(self.times)) if self.times else None
