"""Bursts and other events together: how often is a non-burst reported as a burst?

Each simulated scenario (bursts on every pipe, and the non-burst events of
:func:`burstloc.experiments.event_set.default_events`: every valve and pump operated, demand
steps at the largest consumers; :mod:`burstloc.sim.events.operations`) is captured at each capture
interval
(instantaneous readings, clock phase 0, with the warm-up of ``burstloc evaluate``), run through
the calibrated CUSUM bank, and, when at least
:data:`~burstloc.localize.corroborate.CORROBORATE` meters alarm by the corroboration deadline
(the monitor's rule, :mod:`burstloc.localize.corroborate`), localized by the fused localizer
(its looks at the arrivals from the reading that corroborated them, as the monitor's) and
classified (:mod:`burstloc.localize.classify`) at the signature's decision time:
the answer is ``quiet`` (no corroborated alarm), ``burst``,
``other`` or ``unsure``. Only ``burst`` is a burst report. Every event is also classified
with its own operation declared (``asset, start, kind``). And a day of normal operation
(:func:`burstloc.sim.events.normal.normal_day`: diurnal demand, sensor noise) runs through the live
monitor with the classifier: its burst reports are false alarms.

**Calibrating the classifier** (:func:`calibrate_classifier`, never on the events): the bursts
of a calibration network (paper15: one per pipe, the paper's scenario) are classified without
thresholds; at each capture interval their largest relative residual, smallest scale and
largest lasting rise are measured, and that interval's thresholds are: ``max_residual`` =
1.5 x the largest residual; ``min_scale`` = 0.25 x the smallest scale (the smallest burst
reported with confidence is a quarter of the calibration bursts); ``rise_tolerance`` = 1.5 x
the largest rise a burst showed, at least 3 noise sigmas (the margins: :data:`RESIDUAL_MARGIN`,
:data:`SCALE_FRACTION`, :data:`RISE_MARGIN`). The top-level thresholds, for an interval not
calibrated, are the loosest of them. The asset nodes come from the evaluated network
(the junctions beside a valve or a pump).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from burstloc.exceptions import InputError, SimulationError, SimulatorMissingError
from burstloc.experiments.calibrate import DEFAULT_NOISE_SIGMA
from burstloc.experiments.event_set import asset_nodes, default_events
from burstloc.experiments.harness import Clock, capture_readings
from burstloc.experiments.ranking import RankingSetup
from burstloc.localize.classify import (
    CLASSES,
    ClassifierConfig,
    EventClassifier,
    Operation,
    classify_alarms,
)
from burstloc.localize.corroborate import CORROBORATE, corroborated_at, corroboration_deadline
from burstloc.localize.decide import decision_time, rank_alarms
from burstloc.localize.interval import calibrated_bank
from burstloc.localize.signature import SignatureLocalizer
from burstloc.network import NetworkSource, as_network
from burstloc.sim.events.operations import EventScenario
from burstloc.sim.scenarios.result import ScenarioResult

__all__ = [
    "ANSWERS",
    "Outcome",
    "Specificity",
    "calibrate_classifier",
    "classify_result",
    "evaluate_events",
]

#: What a scenario can end as.
ANSWERS = ("quiet", *CLASSES)
#: The calibration's margins (module docstring).
RESIDUAL_MARGIN = 1.5
SCALE_FRACTION = 0.25
RISE_MARGIN = 1.5


@dataclass(frozen=True)
class Outcome:
    """One scenario at one capture interval: the answer, the named pipe (if located), why."""

    answer: str
    pipe: str | None = None
    top3: tuple[str, ...] = ()
    reason: str = ""
    evidence: dict[str, Any] = field(default_factory=dict)


def classify_result(
    result: ScenarioResult,
    setup: RankingSetup,
    classifier: EventClassifier,
    capture_interval: float,
) -> Outcome:
    """Capture, detect, localize and classify one simulated scenario (module docstring)."""
    cal = setup.config.for_interval(capture_interval)
    clock = Clock.at_offset(capture_interval, 0.0, 2 * cal.localization_interval)
    times, values = capture_readings(result, clock, "instantaneous", meters=setup.meters)
    alarms = calibrated_bank("cusum", len(setup.meters), cal).run(np.ascontiguousarray(values))
    if not alarms:
        return Outcome("quiet")
    localizers = setup.localizers_at(capture_interval)
    by = corroboration_deadline("fused", localizers, alarms, times, cal)
    corroborated = corroborated_at(alarms, times, CORROBORATE, by)
    if corroborated is None:
        return Outcome("quiet")
    try:
        decision = rank_alarms(
            "fused",
            localizers,
            setup.meters,
            times,
            values,
            alarms,
            cal,
            "instantaneous",
            resume=corroborated,
        )
        settled = decision_time("signature", alarms, times, cal)
        kind = classify_alarms(
            classifier, setup.meters, times, values, alarms, cal, "instantaneous", settled
        )
    except InputError as exc:
        return Outcome("quiet", reason=str(exc))
    top = tuple(r.pipe for r in decision.ranking.top(3))
    return Outcome(kind.label, decision.pipe, top, kind.reason, dict(kind.evidence))


def calibrate_classifier(
    results: Sequence[ScenarioResult],
    setup: RankingSetup,
    capture_intervals: Sequence[float],
    assets: dict[str, str],
) -> ClassifierConfig:
    """Thresholds from bursts (module docstring): ``results`` are bursts of ``setup``'s network.

    Raises:
        InputError: no burst was detected, so nothing was measured.
    """
    loose = ClassifierConfig(max_residual=10.0, min_scale=0.0, rise_tolerance=1e3)
    signature = setup.localizers["signature"]
    assert isinstance(signature, SignatureLocalizer)
    probe = EventClassifier(loose, signature)
    measured: dict[str, dict[str, list[float]]] = {}
    for ci in capture_intervals:
        seen = measured.setdefault(f"{ci:g}", {"residual": [], "scale": [], "largest_rise_m": []})
        for result in results:
            outcome = classify_result(result, setup, probe, ci)
            if outcome.answer != "quiet":
                for name, values in seen.items():
                    values.append(outcome.evidence[name])
    if not any(seen["residual"] for seen in measured.values()):
        raise InputError("no calibration burst was detected: nothing to calibrate on")
    intervals = {ci: _thresholds(seen) for ci, seen in measured.items() if seen["residual"]}
    return ClassifierConfig(
        max_residual=max(t["max_residual"] for t in intervals.values()),
        min_scale=min(t["min_scale"] for t in intervals.values()),
        rise_tolerance=max(t["rise_tolerance"] for t in intervals.values()),
        asset_nodes=assets,
        intervals=intervals,
        provenance={
            "procedure": "burstloc.experiments.specificity.calibrate_classifier",
            "bursts": len(results),
            "measured": {
                ci: {"detected": len(seen["residual"]), **_extremes(seen)}
                for ci, seen in measured.items()
            },
        },
    )


def _extremes(seen: dict[str, list[float]]) -> dict[str, float]:
    """The largest residual, the smallest scale and the largest rise of the bursts seen."""
    return {
        "largest_residual": max(seen["residual"]),
        "smallest_scale": min(seen["scale"]),
        "largest_rise_m": max(seen["largest_rise_m"]),
    }


def _thresholds(seen: dict[str, list[float]]) -> dict[str, float]:
    """The thresholds from one capture interval's bursts (module docstring)."""
    worst = _extremes(seen)
    return {
        "max_residual": min(RESIDUAL_MARGIN * worst["largest_residual"], 10.0),
        "min_scale": SCALE_FRACTION * worst["smallest_scale"],
        "rise_tolerance": max(
            RISE_MARGIN * max(worst["largest_rise_m"], 0.0), 3 * DEFAULT_NOISE_SIGMA
        ),
    }


@dataclass
class Specificity:
    """Counts of answers per (scenario type, capture interval), burst localization, failures."""

    counts: dict[str, dict[float, dict[str, int]]] = field(default_factory=dict)
    burst_top1: dict[float, int] = field(default_factory=dict)
    burst_top3: dict[float, int] = field(default_factory=dict)
    events: list[dict[str, Any]] = field(default_factory=list)
    declared: dict[float, dict[str, int]] = field(default_factory=dict)
    classifier: dict[str, Any] = field(default_factory=dict)
    normal: list[dict[str, Any]] = field(default_factory=list)
    missed: list[dict[str, Any]] = field(default_factory=list)
    skipped: list[dict[str, str]] = field(default_factory=list)

    def add(
        self,
        kind: str,
        ci: float,
        outcome: Outcome,
        label: str,
        truth: str | None,
        declared: Outcome | None = None,
    ) -> None:
        """Count one outcome: a burst's (``truth``: its pipe) or an event's (``truth`` None),
        with ``declared`` the event's outcome when its operation was declared. Every event is
        listed with its answer, reason and evidence; a burst only when it is not reported as
        one."""
        row = self.counts.setdefault(kind, {}).setdefault(ci, dict.fromkeys(ANSWERS, 0))
        row[outcome.answer] += 1
        if truth is not None:
            self.burst_top1[ci] = self.burst_top1.get(ci, 0) + (outcome.pipe == truth)
            self.burst_top3[ci] = self.burst_top3.get(ci, 0) + (truth in outcome.top3)
            if outcome.answer != "burst":
                self.missed.append(
                    {"pipe": truth, "capture_interval": ci, "class": outcome.answer,
                     "reason": outcome.reason}
                )  # fmt: skip
            return
        record = {
            "event": label,
            "type": kind,
            "capture_interval": ci,
            "class": outcome.answer,
            "pipe": outcome.pipe,
            "reason": outcome.reason,
            "evidence": dict(outcome.evidence),
            "class_declared": None if declared is None else declared.answer,
        }
        self.events.append(record)
        if declared is not None:
            counted = self.declared.setdefault(ci, {})
            counted[kind] = counted.get(kind, 0) + (declared.answer == "burst")

    @property
    def reported(self) -> list[dict[str, Any]]:
        """The events reported as bursts: event, capture interval, named pipe and evidence."""
        return [
            {"event": e["event"], "capture_interval": e["capture_interval"], "pipe": e["pipe"],
             **e["evidence"]}
            for e in self.events
            if e["class"] == "burst"
        ]  # fmt: skip

    def to_json(self) -> dict[str, Any]:
        """The ``specificity`` block of ``burstloc evaluate --events`` (evaluate_schema.json)."""
        table = []
        for kind, by_ci in self.counts.items():
            for ci, row in sorted(by_ci.items()):
                n = sum(row.values())
                declared = self.declared.get(ci, {}).get(kind) if kind != "burst" else None
                table.append(
                    {
                        "type": kind,
                        "capture_interval": ci,
                        "scenarios": n,
                        **row,
                        "reported_as_burst": row["burst"] / n,
                        "reported_as_burst_declared": None if declared is None else declared / n,
                    }
                )
        bursts = self.counts.get("burst", {})
        return {
            "table": table,
            "burst_top1": {
                str(ci): self.burst_top1[ci] / sum(bursts[ci].values()) for ci in bursts
            },
            "burst_top3": {
                str(ci): self.burst_top3[ci] / sum(bursts[ci].values()) for ci in bursts
            },
            "false_burst_reports": self.reported,
            "events": list(self.events),
            "classifier": dict(self.classifier),
            "normal_operation": list(self.normal),
            "bursts_not_reported": list(self.missed),
            "events_not_simulated": list(self.skipped),
        }

    def format_table(self) -> str:
        """The confusion table as text: one row per type and capture interval."""
        lines = [
            "type            CI s  n   quiet burst other unsure  as burst  declared",
        ]
        for row in self.to_json()["table"]:
            declared = row["reported_as_burst_declared"]
            lines.append(
                f"{row['type']:<14} {row['capture_interval']:>5g} {row['scenarios']:>3} "
                f"{row['quiet']:>6} {row['burst']:>5} {row['other']:>5} {row['unsure']:>6} "
                f"{100 * row['reported_as_burst']:>8.1f}% "
                + ("      -" if declared is None else f"{100 * declared:>7.1f}%")
            )
        for ci in sorted(self.burst_top1):
            n = sum(self.counts["burst"][ci].values())
            lines.append(
                f"bursts at {ci:g} s: top-1 {100 * self.burst_top1[ci] / n:.1f} %, "
                f"top-3 {100 * self.burst_top3[ci] / n:.1f} %"
            )
        for r in self.reported:
            lines.append(f"reported as a burst: {r['event']} at {r['capture_interval']:g} s")
        for skipped in self.skipped:
            lines.append(f"left out, not simulated: {skipped['event']}: {skipped['error']}")
        for m in self.missed:
            lines.append(
                f"burst on {m['pipe']} at {m['capture_interval']:g} s: {m['class']}, {m['reason']}"
            )
        for day in self.normal:
            lines.append(
                f"normal operation at {day['capture_interval']:g} s: {day['hours']:g} h, "
                f"{day['decisions']} decision(s), {day['burst_reports']} burst report(s) "
                f"(sigma {day['noise_sigma']:g} m)"
            )
        return "\n".join(lines) + "\n"


def with_operation(classifier: EventClassifier, event: EventScenario) -> EventClassifier:
    """The classifier with ``event``'s own operation declared."""
    op = Operation(event.asset, event.start, event.kind)
    return EventClassifier(replace(classifier.config), classifier.signature, [op])


def evaluate_events(
    network: NetworkSource,
    bursts: dict[str, ScenarioResult],
    capture_intervals: Sequence[float],
    *,
    calibration_network: NetworkSource,
    calibration_bursts: dict[str, ScenarioResult],
    duration: float,
    setup: RankingSetup | None = None,
    normal_hours: float = 24.0,
    cache: Any = True,
    progress: bool = True,
    solver: str = "vectorized",
) -> tuple[Specificity, ClassifierConfig]:
    """Classify ``bursts`` (pipe -> its burst on ``network``) and :func:`default_events` at each
    capture interval, with a classifier calibrated on ``calibration_bursts`` (of
    ``calibration_network``); every event also with its operation declared; and
    ``normal_hours`` of normal operation
    (:func:`burstloc.experiments.normal_day.normal_operation`; 0: none). ``setup``: the
    localizers and calibration of ``network`` (default: calibrated here); ``solver`` simulates
    the events. An event that cannot be simulated (one that does not start steady, say) is left
    out, said on stderr and listed (``Specificity.skipped``, ``events_not_simulated``)."""
    import sys

    from burstloc.experiments.normal_day import normal_operation
    from burstloc.sim.events.operations import simulate_event

    read, cal_read = as_network(network), as_network(calibration_network)
    meters = list(next(iter(bursts.values())).junctions)
    if setup is None:
        setup = RankingSetup.build(read, meters, capture_intervals)
    cal_setup = setup
    if os.path.abspath(cal_read.path) != os.path.abspath(read.path):
        cal_meters = list(next(iter(calibration_bursts.values())).junctions)
        cal_setup = RankingSetup.build(cal_read, cal_meters, capture_intervals)
    config = calibrate_classifier(
        list(calibration_bursts.values()), cal_setup, capture_intervals, asset_nodes(read)
    )
    signature = setup.localizers["signature"]
    assert isinstance(signature, SignatureLocalizer)
    classifier = EventClassifier(config, signature)
    events = []
    out = Specificity(classifier=config.to_json())
    for scenario in default_events(read, duration, solver):
        if progress:
            print(f"simulating {scenario.label}", file=sys.stderr)
        try:
            events.append((scenario, simulate_event(scenario, cache=cache)))
        except SimulatorMissingError:
            raise
        except SimulationError as exc:  # e.g. it does not start steady: counted and said
            print(f"burstloc: {scenario.label} left out: {exc}", file=sys.stderr)
            out.skipped.append({"event": scenario.label, "error": str(exc)})
    for ci in capture_intervals:
        for pipe, result in bursts.items():
            out.add("burst", ci, classify_result(result, setup, classifier, ci), pipe, pipe)
        for scenario, result in events:
            outcome = classify_result(result, setup, classifier, ci)
            known = classify_result(result, setup, with_operation(classifier, scenario), ci)
            out.add(scenario.kind, ci, outcome, scenario.label, None, declared=known)
        if normal_hours > 0:
            out.normal.append(normal_operation(read, setup, config, ci, hours=normal_hours))
    return out, config
