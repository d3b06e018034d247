"""Every run's attempts at a network's bursts: each pipe's simulated burst captured at each run's
interval and clock phases, and decided (:mod:`burstloc.experiments.harness`), the paper's rules
one attempt at a time, the ranking localizers that share a run's readings on one capture
(:func:`burstloc.experiments.ranking.rank_attempts`); and the check that the simulations can
give every run what it reads. :func:`burstloc.experiments.evaluate.evaluate` scores with them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from burstloc.exceptions import ConfigError
from burstloc.experiments.harness import Attempt, locate_burst, readings_at_offset
from burstloc.experiments.ranking import RankingSetup, rank_attempts
from burstloc.experiments.runs import RunSpec, phase_offsets, readings_after

if TYPE_CHECKING:
    from burstloc.sim.scenarios.result import ScenarioResult
    from burstloc.sim.scenarios.sensors import SensorModel

__all__ = ["check_results", "score_runs"]


def check_results(
    runs: Sequence[RunSpec], results: Sequence[ScenarioResult], phases: int, phase_span: str
) -> None:
    """Refuse results that cannot provide every run: a capture interval finer than their
    time step, too few readings after the burst.

    Raises:
        ConfigError: naming the run.
    """
    dt = max(r.time_step for r in results)
    for spec in runs:
        if spec.capture_interval < dt * (1 - 1e-9):
            raise ConfigError(
                f"capture interval {spec.capture_interval:g} s is finer than the simulation "
                f"time step {dt:.4g} s: the scenario cannot provide it"
            )
    shortest = min(results, key=lambda r: float(r.time[-1]))
    for spec in runs:
        for offset in phase_offsets(spec, phases, phase_span):
            # the ticks alone: one meter's column (every junction's is a copy of the heads)
            times, _ = readings_at_offset(shortest, spec, offset, list(shortest.junctions)[:1])
            n = readings_after(times, float(shortest.metadata["burst_start"]))
            if n < 2 * spec.localization_interval:
                raise ConfigError(
                    f"run {spec.detector.kind} at {spec.capture_interval:g} s gets only {n} "
                    f"readings after the burst at clock offset {offset:g} s (the simulation "
                    f"ends at {float(shortest.time[-1]):g} s); it needs "
                    f"2 x {spec.localization_interval}"
                )


def score_runs(
    runs: Sequence[RunSpec],
    results: dict[str, ScenarioResult],
    pipes: Sequence[str],
    graph: Any,
    setup: RankingSetup | None,
    phases: int,
    phase_span: str,
    sensors: dict[str, SensorModel | None],
) -> dict[RunSpec, dict[str, list[Attempt]]]:
    """Every run's attempts, ``[spec][pipe][k]``. Ranking runs that differ only in their
    localizer see the same readings, captured once per attempt and fed to each localizer's
    monitor (:func:`burstloc.experiments.ranking.rank_attempts`)."""
    scored: dict[RunSpec, dict[str, list[Attempt]]] = {}
    for spec in runs:
        if spec in scored:
            continue
        offsets = phase_offsets(spec, phases, phase_span)
        if setup is None or spec.localizer == "paper":
            sensor = sensors["paper"]
            scored[spec] = {
                p: [locate_burst(results[p], graph, spec, o, sensor=sensor) for o in offsets]
                for p in pipes
            }
            continue
        key = _readings_key(spec)
        group = [s for s in runs if s.localizer != "paper" and _readings_key(s) == key]
        names = [s.localizer for s in group]
        by_name: dict[str, dict[str, list[Attempt]]] = {n: {p: [] for p in pipes} for n in names}
        for p in pipes:
            for o in offsets:
                ranked = rank_attempts(
                    results[p],
                    readings_at_offset(
                        results[p], spec, o, setup.meters, sensor=sensors["ranking"]
                    ),
                    setup,
                    detector=spec.detector.kind,
                    capture_interval=spec.capture_interval,
                    localizers=names,
                    meter_model=spec.meter_model,
                    offset=o,
                )
                for name, attempt in ranked.items():
                    by_name[name][p].append(attempt)
        for s in group:
            scored[s] = by_name[s.localizer]
    return scored


def _readings_key(spec: RunSpec) -> tuple[Any, ...]:
    """What a ranking run's readings and bank depend on (all but its localizer)."""
    return (
        spec.detector.kind,
        spec.capture_interval,
        spec.localization_interval,
        spec.mode,
        spec.meter_model,
    )
