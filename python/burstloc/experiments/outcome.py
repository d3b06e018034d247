"""What ``burstloc evaluate`` measured: each run's attempts and scores (:class:`RunResult`), and
the whole evaluation (:class:`Evaluation`), with the CLI's JSON contract
(``tests/evaluate_schema.json``)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from burstloc.constants import CAPTURE_INTERVALS
from burstloc.experiments import paper
from burstloc.experiments.harness import Attempt, Tally
from burstloc.experiments.position import PipePoint, PositionErrors, PositionOutcome
from burstloc.experiments.ranking import RankingSetup
from burstloc.experiments.region_score import RegionOutcome, RegionScores
from burstloc.experiments.runs import RunSpec

if TYPE_CHECKING:
    from burstloc.sim.scenarios.result import ScenarioResult

__all__ = ["Evaluation", "RunResult"]


@dataclass
class RunResult:
    """All attempts of one run: ``attempts[pipe][k]`` is the burst on ``pipe`` at offset ``k``."""

    spec: RunSpec
    pipes: list[str]
    truth: dict[str, tuple[str, str]]
    offsets: list[float]
    attempts: dict[str, list[Attempt]]
    points: dict[str, PipePoint] = field(default_factory=dict)
    positions: dict[str, list[PositionOutcome]] = field(default_factory=dict)
    """Per pipe and offset: the position error (m) and whether the interval held the true point
    (:func:`burstloc.experiments.position.score_position`)."""
    regions: dict[str, list[RegionOutcome]] = field(default_factory=dict)
    """Per pipe and offset: the search regions against the true point
    (:func:`burstloc.experiments.region_score.score_region`)."""

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

    def tally(self) -> Tally:
        """Every attempt of the run (all pipes, all phases) counted by the harness."""
        return Tally.of(a for p in self.pipes for a in self.attempts[p])

    def position_errors(self) -> PositionErrors:
        """Position errors (m) over every attempt of the run (all pipes, all phases)."""
        return PositionErrors.of(o for p in self.pipes for o in self.positions.get(p, []))

    def region_scores(self) -> RegionScores:
        """Search-region coverage, lengths and distances over every attempt of the run."""
        return RegionScores.of(o for p in self.pipes for o in self.regions.get(p, []))

    def median_time_to_localize(self) -> float | None:
        """Median seconds from burst to decision over every located attempt (all phases)."""
        return self.tally().median_time()

    def to_json(self) -> dict[str, Any]:
        """The run as the CLI's JSON contract (tests/evaluate_schema.json)."""
        acc = self.phase_accuracies()
        tally = self.tally()
        pipes = []
        for p in self.pipes:
            a = self.attempts[p][0]
            loc = a.localization
            at = None if a.decision is None else a.decision.position
            region = None if a.decision is None else a.decision.region
            truth = self.points.get(p)
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
                    "position": None if at is None else at.to_json(),
                    "true_position": None
                    if truth is None
                    else {"pipe": p, "from": truth.node, "metres": truth.metres},
                    "position_error_m": (self.positions.get(p) or [PositionOutcome()])[0].error,
                    "region": None if region is None else region.to_json(),
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
            "accuracy_phase_mean": tally.top1_fraction,
            "accuracy_phase_min": float(min(acc)),
            "accuracy_phase_max": float(max(acc)),
            "top1": tally.top1_fraction,
            "top3": tally.top3_fraction,
            "accuracy_per_phase": acc,
            "phase_offsets_s": list(self.offsets),
            "median_time_to_localize_s": tally.median_time(),
            "position_error_m": self.position_errors().to_json(),
            "region": self.region_scores().to_json() if self.spec.localizer != "paper" else None,
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
    meters: list[str] = field(default_factory=list)
    """The junctions the ranking localizers read (empty: only the paper's rules ran)."""
    specificity: dict[str, Any] | None = None
    setup: RankingSetup | None = field(default=None, repr=False)

    def to_json(self) -> dict[str, Any]:
        """The CLI's JSON document (see tests/evaluate_schema.json)."""
        doc = {
            "network": self.network,
            "scenario": dict(self.scenario),
            "phase_span": self.phase_span,
            "warnings": list(self.warnings),
            "meters": list(self.meters),
            "runs": [r.to_json() for r in self.runs],
        }
        if self.specificity is not None:
            doc["specificity"] = self.specificity
        return doc
