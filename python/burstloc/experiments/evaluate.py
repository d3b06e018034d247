"""Burst every pipe, stream the meters' readings, localize, and score (paper section V).

For a network and one or more runs (detector x capture interval x parameters x mode):

1. one burst scenario per pipe is simulated (or loaded from the cache) with the
   :data:`burstloc.experiments.paper.SCENARIO` choices, long enough for every run to see ``2 x
   interval``
   readings after the burst;
2. each scenario is sampled at the run's capture interval at ``phases`` clock offsets and
   replayed through the real-time loop (:class:`burstloc.live.paper_locator.BurstLocator`): the
   first
   window whose changes make the rules name a pipe decides (the paper's single localization
   attempt); no decision means "not located", never a guess;
3. a prediction is correct when it names the burst pipe; accuracy = correct / pipes (eq. 4).

**Phases.** Phase ``k`` of ``N`` starts the capture clock, and with it the window grid, ``k / N``
of one capture interval (``phase_span="capture"``, the default) or of one localization window,
``interval x capture interval`` (``phase_span="window"``: every alignment of the windows to the
burst), earlier relative to the burst (:func:`readings_at_offset`). Accuracy is reported at
phase 0 (the per-pipe tables) and as mean, min and max over the phases. The time to localize
is the decision time (the timestamp of the newest reading of the deciding window) minus the
burst start; its median is taken over every located attempt, all phases.

**Localizers.** ``RunSpec.localizer`` is ``"paper"`` (the rules above, the default)
or one of the ranking localizers ``"arrival"``, ``"signature"``, ``"fused"``
(:mod:`burstloc.localize.arrival`, :mod:`burstloc.localize.signature`,
:mod:`burstloc.localize.fused`). These run the Rust
detector bank with a calibrated configuration (:mod:`burstloc.experiments.calibrate`; computed for
the
network when none is given: no hand tuning), build the evidence from its alarms at the
localizer's decision time (:func:`burstloc.localize.decide.rank_alarms`) and rank every pipe; the
prediction is the best-ranked pipe, and top-1 / top-3 accuracy are reported (for the paper's
rules, which name one pipe, top-3 equals top-1). ``RunSpec.meter_model`` chooses instantaneous
samples (the paper's) or interval-averaged readings (:func:`burstloc.sim.capture.capture`).
"""

from __future__ import annotations

import math
import os
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import (
    CAPTURE_INTERVALS,
    DETECTORS,
    LOCALIZERS,
    METER_MODELS,
    SIGNATURE_DECISION_DELAY,
    MeterModel,
)
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrated_bank
from burstloc.live.paper_locator import BurstLocator
from burstloc.live.stream import replay
from burstloc.localize.decide import decision_time, rank_alarms
from burstloc.localize.detection import DetectorConfig, Mode, make_detector
from burstloc.localize.evidence import Ranking
from burstloc.localize.paper_rules import Localization
from burstloc.sim.capture import capture
from burstloc.sim.prepare import ranking_localizers

if TYPE_CHECKING:
    import networkx as nx

    from burstloc.experiments.calibrate import Calibration
    from burstloc.localize.decide import RankingLocalizers
    from burstloc.sim.scenario import ScenarioResult

__all__ = [
    "DEFAULT_LOCALIZER",
    "PAPER_OPTIONS",
    "PHASE_SPANS",
    "RANKING_LOCALIZATION_INTERVAL",
    "Attempt",
    "Evaluation",
    "RankingSetup",
    "RunResult",
    "RunSpec",
    "calibrated_bank",
    "decision_time",
    "evaluate",
    "locate_burst",
    "locate_ranked",
    "paper_runs",
    "phase_offsets",
    "plan_runs",
    "ranking_runs",
    "readings_after",
    "readings_at_offset",
    "required_duration",
]

#: What the phases of an evaluation are spread over.
PHASE_SPANS: tuple[str, ...] = ("capture", "window")

#: ``burstloc evaluate``'s localizer: the fused one, ahead of the paper's rules at every capture
#: interval in ``burstloc study`` (docs/study/report.md).
DEFAULT_LOCALIZER = "fused"


@dataclass(frozen=True)
class RunSpec:
    """One run of the experiment: a detector configuration at a capture interval.

    ``label`` names the paper's scenario (``"S_C1"``...) when the run is one of Tables I/II.
    ``localizer`` is one of :data:`LOCALIZERS`; ``meter_model`` one of
    :data:`burstloc.sim.capture.METER_MODELS`. A ranking localizer uses the detector's kind with the
    calibrated thresholds (the configuration given to :func:`evaluate`), not ``detector``'s.
    """

    detector: DetectorConfig
    capture_interval: float
    localization_interval: int
    mode: Mode = Mode.WINDOW
    label: str | None = None
    localizer: str = "paper"
    meter_model: str = "instantaneous"

    def __post_init__(self) -> None:
        ci = self.capture_interval
        if isinstance(ci, bool) or not isinstance(ci, (int, float)) or not math.isfinite(ci):
            raise ConfigError(f"capture interval must be a number of seconds, got {ci!r}")
        if ci <= 0:
            raise ConfigError(f"capture interval must be > 0 s, got {ci}")
        li = self.localization_interval
        if isinstance(li, bool) or not isinstance(li, int):
            raise ConfigError(f"localization interval must be an integer, got {li!r}")
        if li < 1:
            raise ConfigError(f"localization interval must be >= 1, got {li}")
        object.__setattr__(self, "capture_interval", float(ci))
        object.__setattr__(self, "mode", Mode(self.mode))
        if self.localizer not in LOCALIZERS:
            raise ConfigError(f"localizer must be one of {LOCALIZERS}, got {self.localizer!r}")
        if self.meter_model not in METER_MODELS:
            raise ConfigError(
                f"meter model must be one of {METER_MODELS}, got {self.meter_model!r}"
            )

    def params(self) -> dict[str, Any]:
        """The run's parameters (JSON ``params``)."""
        return {
            **self.detector.params(),
            "localization_interval": self.localization_interval,
            "mode": self.mode.value,
        }

    def paper_run(self) -> paper.PaperRun | None:
        """The paper's run with the same detector, capture interval, threshold and interval
        (``None`` for a ranking localizer: the paper's figures are for its rules)."""
        if self.localizer != "paper":
            return None
        for run in paper.PAPER_RUNS:
            if (
                run.detector == self.detector.kind
                and run.capture_interval == self.capture_interval
                and run.threshold == self.detector.threshold
                and run.localization_interval == self.localization_interval
            ):
                return run
        return None


def paper_runs(
    detectors: Sequence[str] = ("cusum", "shewhart"),
    capture_intervals: Sequence[float] | None = None,
    modes: Sequence[Mode | str] = (paper.DEFAULT_MODE,),
    *,
    threshold: float | None = None,
    drift: float | None = None,
    sigma: float | None = None,
    localization_interval: int | None = None,
) -> list[RunSpec]:
    """Runs for detectors x capture intervals x modes, with Tables I/II parameters by default.

    A capture interval the paper did not use needs ``threshold`` and ``localization_interval``.
    ``threshold``, ``drift`` (CUSUM), ``sigma`` (Shewhart) and ``localization_interval``
    override the paper's values for every run.
    """
    intervals = list(CAPTURE_INTERVALS if capture_intervals is None else capture_intervals)
    runs: list[RunSpec] = []
    for kind in detectors:
        table = {r.capture_interval: r for r in paper.PAPER_RUNS if r.detector == kind}
        if kind not in ("cusum", "shewhart"):
            raise ConfigError(f"unknown detector {kind!r}; choose cusum, shewhart or both")
        for ci in intervals:
            ci = float(ci)
            if not (math.isfinite(ci) and ci > 0):
                raise ConfigError(f"capture interval must be > 0 s, got {ci:g}")
            base = table.get(ci)
            thr = threshold if threshold is not None else (base.threshold if base else None)
            li = (
                localization_interval
                if localization_interval is not None
                else (base.localization_interval if base else None)
            )
            if thr is None or li is None:
                raise ConfigError(
                    f"capture interval {ci:g} s is not one of the paper's "
                    f"({', '.join(f'{c:g}' for c in CAPTURE_INTERVALS)}); give "
                    "--threshold and --localization-interval for it"
                )
            if kind == "cusum":
                if sigma is not None:
                    raise ConfigError("--sigma applies to the Shewhart chart only")
                cfg = DetectorConfig("cusum", thr, drift=drift or 0.0)
            else:
                if drift is not None:
                    raise ConfigError("--drift applies to the CUSUM only")
                cfg = DetectorConfig("shewhart", thr, sigma=sigma)
            for mode in modes:
                spec = RunSpec(cfg, ci, li, Mode(mode))
                label = spec.paper_run()
                runs.append(RunSpec(cfg, ci, li, Mode(mode), label.scenario if label else None))
    return runs


#: Localization interval of a ranking run at a capture interval the paper did not use (the
#: paper's value at every coarse interval): it only sets the warm-up history and the simulated
#: span; the calibrated bank and the localizer's decision delay do the rest.
RANKING_LOCALIZATION_INTERVAL = 10


def ranking_runs(
    detectors: Sequence[str],
    capture_intervals: Sequence[float] | None,
    localizers: Sequence[str],
    meter_models: Sequence[str] = ("instantaneous",),
) -> list[RunSpec]:
    """Runs of ranking localizers (not ``"paper"``) for detectors x intervals x meter models.

    A ranking run detects with the calibrated bank of its detector kind, so only the kind
    matters; its ``detector`` carries the paper's Tables I/II threshold where the paper used
    the interval (for the JSON record) and 1 m otherwise, and its localization interval the
    paper's, else :data:`RANKING_LOCALIZATION_INTERVAL`. Any capture interval > 0 is accepted.
    Its mode is ``stream``: the bank is fed once per reading and never reset.

    Raises:
        ConfigError: an unknown detector or localizer, ``"paper"`` among ``localizers``, or a
            capture interval that is not > 0.
    """
    if "paper" in localizers:
        raise ConfigError("ranking_runs builds ranking localizers only; use paper_runs for 'paper'")
    intervals = list(CAPTURE_INTERVALS if capture_intervals is None else capture_intervals)
    runs: list[RunSpec] = []
    for kind in detectors:
        table = {r.capture_interval: r for r in paper.PAPER_RUNS if r.detector == kind}
        for ci in intervals:
            ci = float(ci)
            if not (math.isfinite(ci) and ci > 0):
                raise ConfigError(f"capture interval must be > 0 s, got {ci:g}")
            base = table.get(ci)
            cfg = DetectorConfig(kind, base.threshold if base else 1.0)
            li = base.localization_interval if base else RANKING_LOCALIZATION_INTERVAL
            runs += [
                RunSpec(cfg, ci, li, Mode.STREAM, localizer=name, meter_model=model)
                for name in localizers
                for model in meter_models
            ]
    return runs


#: Options that configure the paper's rules only (:func:`plan_runs` refuses them otherwise).
PAPER_OPTIONS: tuple[str, ...] = ("threshold", "drift", "sigma", "localization_interval", "mode")


def plan_runs(
    *,
    localizers: Sequence[str],
    detectors: Sequence[str] = DETECTORS,
    capture_intervals: Sequence[float] | None = None,
    meter_models: Sequence[MeterModel] = ("instantaneous",),
    mode: str | None = None,
    threshold: float | None = None,
    drift: float | None = None,
    sigma: float | None = None,
    localization_interval: int | None = None,
) -> list[RunSpec]:
    """The runs of one evaluation: the paper's rules (Tables I/II parameters, or the given ones)
    and the ranking localizers, for every detector, capture interval and meter model.

    ``mode`` is the paper's detection mode (``"window"``, ``"stream"`` or ``"both"``; default
    :data:`burstloc.experiments.paper.DEFAULT_MODE`).

    Raises:
        ConfigError: a paper-only option (:data:`PAPER_OPTIONS`) without the paper's rules.
    """
    chosen = list(dict.fromkeys(localizers))
    ranking = [name for name in chosen if name != "paper"]
    paper_options = {
        "threshold": threshold,
        "drift": drift,
        "sigma": sigma,
        "localization_interval": localization_interval,
        "mode": mode,
    }
    if "paper" not in chosen:
        given = [f"--{k.replace('_', '-')}" for k, v in paper_options.items() if v is not None]
        if given:
            raise ConfigError(
                f"{', '.join(given)} apply to the paper's rules only (add --localizer paper); "
                f"{', '.join(ranking)} use the calibrated configuration (--config)"
            )
    runs: list[RunSpec] = []
    if "paper" in chosen:
        chosen_mode = mode or paper.DEFAULT_MODE
        runs += [
            replace(spec, meter_model=model)
            for spec in paper_runs(
                detectors,
                capture_intervals,
                ("window", "stream") if chosen_mode == "both" else (chosen_mode,),
                threshold=threshold,
                drift=drift,
                sigma=sigma,
                localization_interval=localization_interval,
            )
            for model in meter_models
        ]
    if ranking:
        runs += ranking_runs(detectors, capture_intervals, ranking, meter_models)
    return runs


def phase_offsets(spec: RunSpec, phases: int, span: str = "capture") -> list[float]:
    """The clock offsets (s) of the ``phases`` attempts of a run, evenly spread."""
    if isinstance(phases, bool) or not isinstance(phases, int) or phases < 1:
        raise ConfigError(f"phases must be an integer >= 1, got {phases!r}")
    if span not in PHASE_SPANS:
        raise ConfigError(f"phase span must be one of {PHASE_SPANS}, got {span!r}")
    period = spec.capture_interval
    if span == "window":
        period *= spec.localization_interval
    return [k * period / phases for k in range(phases)]


def required_duration(spec: RunSpec, burst_start: float) -> float:
    """Simulated time a run needs: ``2 x interval`` readings after the burst at any phase.

    ``burst_start + (2 x interval + 1) x capture_interval``: one capture interval of margin for
    the clock phase and for TSNet's grid, which ends up to one time step short of the duration.
    """
    need = burst_start + (2 * spec.localization_interval + 1) * spec.capture_interval
    if spec.localizer in ("signature", "fused"):
        need = max(need, burst_start + SIGNATURE_DECISION_DELAY + 2 * spec.capture_interval)
    return need


def readings_after(times: np.ndarray, burst_start: float) -> int:
    """How many capture ticks fall strictly after the burst start."""
    return int(np.count_nonzero(times > burst_start + 1e-9))


@dataclass(frozen=True)
class Attempt:
    """One burst streamed at one clock offset: what was decided, when, and by which rule."""

    pipe: str
    offset: float
    burst_start: float
    localization: Localization | None
    ranking: Ranking | None = None
    decided_at: float | None = None

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
        """Whether the burst pipe is among the ``k`` best-ranked (the paper's rules name one)."""
        if self.ranking is not None:
            return self.ranking.in_top(self.pipe, k)
        return self.correct

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


def readings_at_offset(result: ScenarioResult, spec: RunSpec, offset: float) -> tuple[Any, Any]:
    """The readings of one run at a clock offset (s).

    The capture clock ticks at ``t0 - offset - 2 x interval x capture_interval + k x
    capture_interval`` (``t0``: the simulation's start): the offset moves the clock, and with
    it the window grid, ``offset`` seconds earlier relative to the burst. Ticks before ``t0``
    carry the initial steady state, which is exact (TSNet starts from it and it holds until the
    burst): ``2 x interval`` of them are a warm-up, so that a streaming detector's reference
    window is full when the simulated span begins, as it would be for meters that have been
    reporting long before a burst. Being a whole number of windows, the warm-up does not move
    the window grid. Ticks from ``t0`` on sample the simulation (sample-and-hold).
    """
    ci = spec.capture_interval
    t0 = float(result.time[0])
    k = math.ceil(offset / ci - 1e-9)  # ticks in [t0 - offset, t0)
    phase = k * ci - offset
    if phase < 1e-9 * ci:
        phase = 0.0
    times, values = capture(result.time - t0, result.heads, ci, phase, spec.meter_model)
    lead = k + 2 * spec.localization_interval
    pre = times[0] - ci * np.arange(lead, 0, -1, dtype=np.float64)
    times = np.concatenate([pre, times]) + t0
    values = np.concatenate([np.repeat(result.heads[:1], lead, axis=0), values])
    return times, values


def locate_burst(
    result: ScenarioResult,
    graph: nx.DiGraph,
    spec: RunSpec,
    offset: float = 0.0,
) -> Attempt:
    """Stream one simulated burst at a clock offset through the real-time loop.

    The capture clock, and with it the window grid, starts ``offset`` seconds earlier relative
    to the burst than at offset 0 (see :func:`readings_at_offset`).
    """
    times, values = readings_at_offset(result, spec, offset)
    meters = list(result.junctions)
    detector = make_detector(spec.detector, meters, spec.localization_interval, spec.mode)
    locator = BurstLocator(graph, meters, detector, spec.localization_interval)
    outcome = locator.first(replay(times, values))
    burst_start = float(result.metadata["burst_start"])
    return Attempt(result.pipe, offset, burst_start, outcome.localization if outcome else None)


@dataclass
class RankingSetup:
    """What the ranking localizers of one network need, built once per evaluation."""

    meters: list[str]
    config: Calibration
    localizers: RankingLocalizers

    @classmethod
    def build(
        cls,
        network: str,
        meters: Sequence[str],
        capture_intervals: Sequence[float],
        config: Calibration | None = None,
    ) -> RankingSetup:
        """Localizers for ``meters`` of ``network`` and a calibration covering the intervals.

        Without ``config`` the network is calibrated here
        (:func:`burstloc.experiments.calibrate.calibrate`
        with its defaults). A ``config`` for another network or other meters is refused by
        name (:meth:`burstloc.experiments.calibrate.Calibration.check`), as is one without an
        interval.
        """
        from burstloc.experiments.calibrate import calibrate

        if config is None:
            config = calibrate(network, capture_intervals=capture_intervals, meters=meters)
        else:
            config.check(network, meters)
            for ci in capture_intervals:
                config.for_interval(ci)
        return cls(list(meters), config, ranking_localizers(network, meters))


def locate_ranked(
    result: ScenarioResult, spec: RunSpec, setup: RankingSetup, offset: float = 0.0
) -> Attempt:
    """One burst at a clock offset through the calibrated bank and a ranking localizer."""
    from burstloc.exceptions import InputError

    times, values = readings_at_offset(result, spec, offset)
    burst_start = float(result.metadata["burst_start"])
    cal = setup.config.for_interval(spec.capture_interval)
    bank = calibrated_bank(spec.detector.kind, len(setup.meters), cal)
    alarms = bank.run(np.ascontiguousarray(values))
    if not alarms:
        return Attempt(result.pipe, offset, burst_start, None)
    try:
        decision = rank_alarms(
            spec.localizer,
            setup.localizers,
            setup.meters,
            times,
            values,
            alarms,
            cal,
            spec.meter_model,  # type: ignore[arg-type]
        )
    except InputError:
        return Attempt(result.pipe, offset, burst_start, None)
    return Attempt(result.pipe, offset, burst_start, None, decision.ranking, decision.time)


@dataclass
class RunResult:
    """All attempts of one run: ``attempts[pipe][k]`` is the burst on ``pipe`` at offset ``k``."""

    spec: RunSpec
    pipes: list[str]
    truth: dict[str, tuple[str, str]]
    offsets: list[float]
    attempts: dict[str, list[Attempt]]

    def phase_accuracies(self, k: int = 1) -> list[float]:
        """Top-``k`` accuracy (fraction) at each clock offset (``k = 1``: eq. 4)."""
        n = len(self.pipes)
        return [
            sum(self.attempts[p][i].in_top(k) for p in self.pipes) / n
            for i in range(len(self.offsets))
        ]

    @property
    def correct(self) -> int:
        """Pipes located correctly at phase 0."""
        return sum(self.attempts[p][0].correct for p in self.pipes)

    @property
    def total(self) -> int:
        """Pipes burst."""
        return len(self.pipes)

    @property
    def accuracy(self) -> float:
        """Correct / pipes at phase 0 (eq. 4, as a fraction)."""
        return self.correct / self.total

    def median_time_to_localize(self) -> float | None:
        """Median seconds from burst to decision over every located attempt (all phases)."""
        times = [
            a.time_to_localize
            for p in self.pipes
            for a in self.attempts[p]
            if a.time_to_localize is not None
        ]
        return float(statistics.median(times)) if times else None

    def to_json(self) -> dict[str, Any]:
        """The run as the CLI's JSON contract (tests/evaluate_schema.json)."""
        acc = self.phase_accuracies()
        pipes = []
        for p in self.pipes:
            a = self.attempts[p][0]
            loc = a.localization
            pipes.append(
                {
                    "pipe": p,
                    "true": list(self.truth[p]),
                    "predicted": list(a.predicted) if a.predicted else None,
                    "predicted_pipe": a.predicted_pipe,
                    "correct": a.correct,
                    "top3": a.in_top(3),
                    "time_to_localize_s": a.time_to_localize,
                    "rule": loc.rule.value if loc else (self.spec.localizer if a.located else None),
                    "trigger_node": loc.trigger_node if loc else None,
                    "phases_correct": sum(x.correct for x in self.attempts[p]),
                }
            )
        run = self.spec.paper_run()
        published = None
        if run is not None:
            k = CAPTURE_INTERVALS.index(run.capture_interval)
            published = {
                "scenario": run.scenario,
                "correct_in_table": paper.published_correct(run.detector)[k],
                "correct_printed": paper.PRINTED_TOTALS[run.detector][k],
                "accuracy_table_v": paper.TABLE_V[run.detector][k] / 100.0,
            }
        return {
            "detector": self.spec.detector.kind,
            "capture_interval": self.spec.capture_interval,
            "params": self.spec.params(),
            "mode": self.spec.mode.value,
            "localizer": self.spec.localizer,
            "meter_model": self.spec.meter_model,
            "correct": self.correct,
            "total": self.total,
            "accuracy": self.accuracy,
            "accuracy_phase_mean": float(np.mean(acc)),
            "accuracy_phase_min": float(min(acc)),
            "accuracy_phase_max": float(max(acc)),
            "top1": float(np.mean(acc)),
            "top3": float(np.mean(self.phase_accuracies(3))),
            "accuracy_per_phase": acc,
            "phase_offsets_s": list(self.offsets),
            "median_time_to_localize_s": self.median_time_to_localize(),
            "paper": published,
            "pipes": pipes,
        }


@dataclass
class Evaluation:
    """The outcome of :func:`evaluate`: every run, plus what was simulated."""

    network: str
    runs: list[RunResult]
    scenario: dict[str, Any]
    phase_span: str
    warnings: list[str] = field(default_factory=list)
    results: dict[str, ScenarioResult] = field(default_factory=dict, repr=False)
    graph: Any = field(default=None, repr=False)

    def to_json(self) -> dict[str, Any]:
        """The CLI's JSON document (see tests/evaluate_schema.json)."""
        return {
            "network": self.network,
            "scenario": dict(self.scenario),
            "phase_span": self.phase_span,
            "warnings": list(self.warnings),
            "runs": [r.to_json() for r in self.runs],
        }


def evaluate(
    network: str | os.PathLike[str],
    runs: Sequence[RunSpec],
    *,
    pipes: Sequence[str] | None = None,
    phases: int = 5,
    phase_span: str = "capture",
    scenario: paper.ScenarioConfig = paper.SCENARIO,
    cache: Any = True,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    config: Calibration | None = None,
) -> Evaluation:
    """Run the experiment: simulate (cached), stream, localize and score every run.

    ``config`` is the calibration the ranking localizers' detector bank uses (runs with
    ``localizer != "paper"``); without one the network is calibrated here.

    Raises:
        NetworkError: missing or malformed network, unknown pipe.
        ConfigError: no runs, bad phases, or a capture interval finer than the simulation's
            time step.
        SimulationError: a burst could not be simulated.
    """
    from burstloc import network as netmod
    from burstloc.sim import tsnet as simulate
    from burstloc.sim.scenario import burst_scenarios

    if not runs:
        raise ConfigError("no runs to evaluate")
    for spec in runs:
        phase_offsets(spec, phases, phase_span)  # validates phases and span
    path = os.fspath(network)
    if not Path(path).is_file():
        raise NetworkError(f"network file not found: {path}")
    wn = netmod.load_network(path)
    graph = netmod.flow_direction_graph(wn)
    all_pipes = netmod.pipe_names(wn)
    chosen = list(all_pipes if pipes is None else pipes)
    unknown = [p for p in chosen if p not in all_pipes]
    if unknown:
        raise NetworkError(f"unknown pipe(s) {unknown} in {path}; pipes: {', '.join(all_pipes)}")
    if not chosen:
        raise NetworkError(f"no pipes to burst in {path}")
    if len(set(chosen)) != len(chosen):
        raise ConfigError(f"pipes listed more than once: {chosen}")

    warnings: list[str] = []
    params: dict[str, Any] = scenario.parameters()
    needed = max(required_duration(s, scenario.burst_start) for s in runs)
    if params["duration"] is None:
        params["duration"] = float(math.ceil(needed - 1e-9))
    elif params["duration"] + 1e-9 < needed:
        worst = max(runs, key=lambda s: required_duration(s, scenario.burst_start))
        raise ConfigError(
            f"the scenario simulates {params['duration']:g} s but the run "
            f"{worst.detector.kind} at {worst.capture_interval:g} s with localization interval "
            f"{worst.localization_interval} needs {needed:g} s (2 x interval readings after "
            f"the burst at {scenario.burst_start:g} s, whatever the phase)"
        )
    scenarios = burst_scenarios(path, chosen, **params)
    report = simulate.simulate_many(
        scenarios, cache=cache, workers=workers, scheduler=scheduler, progress=progress
    )
    if report.failures:
        from burstloc.exceptions import SimulationError

        raise SimulationError("; ".join(str(f) for f in report.failures))
    results = {s.pipe: r for s, r in zip(scenarios, report.results, strict=True) if r is not None}

    dt = max(r.time_step for r in results.values())
    for spec in runs:
        if spec.capture_interval < dt * (1 - 1e-9):
            raise ConfigError(
                f"capture interval {spec.capture_interval:g} s is finer than the simulation "
                f"time step {dt:.4g} s: the scenario cannot provide it"
            )
    shortest = min(results.values(), key=lambda r: float(r.time[-1]))
    for spec in runs:
        for offset in phase_offsets(spec, phases, phase_span):
            times, _ = readings_at_offset(shortest, spec, offset)
            n = readings_after(times, float(shortest.metadata["burst_start"]))
            if n < 2 * spec.localization_interval:
                raise ConfigError(
                    f"run {spec.detector.kind} at {spec.capture_interval:g} s gets only {n} "
                    f"readings after the burst at clock offset {offset:g} s (the simulation "
                    f"ends at {float(shortest.time[-1]):g} s); it needs "
                    f"2 x {spec.localization_interval}"
                )

    for p, r in results.items():
        negative = r.metadata.get("negative_pressure_nodes") or []
        if negative:
            warnings.append(f"burst on pipe {p}: negative pressure at {', '.join(negative)}")
    truth = {p: r.true_endpoints for p, r in results.items()}
    ranked = [spec for spec in runs if spec.localizer != "paper"]
    setup = None
    if ranked:
        meters = list(next(iter(results.values())).junctions)
        intervals = sorted({spec.capture_interval for spec in ranked})
        setup = RankingSetup.build(path, meters, intervals, config)
    out: list[RunResult] = []
    for spec in runs:
        offsets = phase_offsets(spec, phases, phase_span)
        if setup is not None and spec.localizer != "paper":
            attempts = {
                p: [locate_ranked(results[p], spec, setup, o) for o in offsets] for p in chosen
            }
        else:
            attempts = {
                p: [locate_burst(results[p], graph, spec, o) for o in offsets] for p in chosen
            }
        out.append(RunResult(spec, chosen, truth, offsets, attempts))
    return Evaluation(path, out, params, phase_span, warnings, results, graph)
