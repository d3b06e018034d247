"""Meter placements side by side: place K meters by every method, evaluate each placement.

:func:`compare_placements` places the meters (:mod:`burstloc.sim.placement.methods`), calibrates for
them
and scores every pipe's burst through ``burstloc evaluate``'s harness
(:func:`burstloc.experiments.evaluate.evaluate`): top-1 / top-3, the median time to a decision
and the position errors (:mod:`burstloc.experiments.position`). ``burstloc place --compare``
prints :func:`format_comparison` of its rows.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from burstloc.experiments import paper
from burstloc.experiments.evaluate import evaluate
from burstloc.experiments.runs import plan_runs
from burstloc.network import NetworkSource, as_network
from burstloc.sim.placement.methods import PLACEMENT_METHODS, place_meters

if TYPE_CHECKING:
    from burstloc.wave_speeds import WaveSpeeds

__all__ = ["compare_placements", "format_comparison"]


def compare_placements(
    network: NetworkSource,
    count: int,
    *,
    methods: Sequence[str] = PLACEMENT_METHODS,
    capture_interval: float = 0.2,
    detector: str = "cusum",
    localizers: Sequence[str] = ("arrival", "fused"),
    phases: int = 5,
    position: float = 0.5,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = False,
    wave_speeds: WaveSpeeds | None = None,
    wave_speed: float | None = None,
) -> list[dict[str, Any]]:
    """Place ``count`` meters by each of ``methods`` and evaluate each placement.

    Every pipe bursts at ``position`` of its length (the paper's scenario otherwise; simulated
    once and cached, shared by the methods); the meters are calibrated for each placement
    (no hand tuning) and scored by ``burstloc evaluate``'s harness at ``capture_interval``.
    ``wave_speeds``: pipes of their own wave speed, the others at the scenario's: the meters
    are placed, the bursts simulated and the localizers calibrated with them. ``wave_speed``
    (m/s, default the scenario's): the other pipes', for the placement, the bursts and the
    localizers alike.

    Returns:
        One row per method and localizer: ``method``, ``meters`` (the junctions), ``localizer``,
        ``top1``, ``top3``, ``median_time_s``, ``position_mean_m``, ``position_p90_m``.
    """
    runs = plan_runs(
        localizers=localizers, detectors=(detector,), capture_intervals=(capture_interval,)
    )
    scenario = replace(paper.SCENARIO, position=position)
    if wave_speed is not None:
        scenario = replace(scenario, wave_speed=wave_speed)
    read = as_network(network)
    rows: list[dict[str, Any]] = []
    for method in methods:
        placed = place_meters(
            read,
            count,
            method=method,
            wave_speed=scenario.wave_speed,
            resolution=capture_interval,
            wave_speeds=wave_speeds,
        )
        ev = evaluate(
            read,
            runs,
            phases=phases,
            scenario=scenario,
            meters=placed.meters,
            workers=workers,
            scheduler=scheduler,
            progress=progress,
            wave_speeds=wave_speeds,
        )
        for run in ev.runs:
            tally, errors = run.tally(), run.position_errors()
            rows.append(
                {
                    "method": method,
                    "meters": list(placed.meters),
                    "localizer": run.spec.localizer,
                    "top1": tally.top1_fraction,
                    "top3": tally.top3_fraction,
                    "median_time_s": tally.median_time(),
                    "position_mean_m": errors.mean,
                    "position_p90_m": errors.p90,
                }
            )
    return rows


def format_comparison(rows: Sequence[Mapping[str, Any]]) -> str:
    """The rows of :func:`compare_placements` as a Markdown table."""
    lines = [
        "| method | meters | localizer | top-1 / top-3 | median time | position error mean / p90 |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        time = "-" if r["median_time_s"] is None else f"{r['median_time_s']:.2f} s"
        where = (
            "-"
            if r["position_mean_m"] is None
            else f"{r['position_mean_m']:.0f} / {r['position_p90_m']:.0f} m"
        )
        lines.append(
            f"| {r['method']} | {' '.join(r['meters'])} | {r['localizer']} | "
            f"{100 * r['top1']:.0f} / {100 * r['top3']:.0f} % | {time} | {where} |"
        )
    return "\n".join(lines) + "\n"
