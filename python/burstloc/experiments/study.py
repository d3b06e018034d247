"""The robustness study: localization accuracy over a one-factor-at-a-time grid.

Around the defaults (noise-free meters on every junction, bursts at the pipe mid-point with
coefficient 0.01, TSNet's default ``steady`` friction), one factor at a time is changed on the
first network of the study (paper15 by default): sensor noise sigma, the fraction of junctions
that carry meters, the burst position along the pipe, the burst coefficient (over a decade) and
TSNet's friction model. The other networks run at the defaults. Every grid point is scored for
each detector (calibrated CUSUM and Shewhart banks, :mod:`burstloc.experiments.calibrate`: no
hand tuning), each localizer (``arrival``, ``signature``, ``fused``), each meter model
(``instantaneous``, ``interval-averaged``; :func:`burstloc.sim.scenarios.capture.capture`) and each
capture interval, over several phases of the capture clock, as top-1 / top-3 accuracy and the
median time from the burst to the decision.

The grid (points, factors, settings) is :mod:`burstloc.experiments.grid`. Simulations go
through :func:`burstloc.sim.transient.tsnet.simulate_many` (the simulation cache and the
local/Dask executor of :mod:`burstloc.sim.scenarios.sweep`); the grid points are then scored through
the
same executor, one task per point, and through the same harness as ``burstloc evaluate``
(:mod:`burstloc.experiments.harness`: capture, detector bank, localizers, tally).
:func:`write_report` (:func:`burstloc.experiments.study_report.write_study_report`) writes
``report.md``, ``results.json`` and PNG plots (top-1 accuracy vs capture interval per detector
and localizer).

Meter placement for a fraction ``f < 1``: the greedy coverage of the burst signatures
(:func:`burstloc.sim.placement.methods.coverage_meters`), or the settings' placement method
(``StudySettings.placement``). A meter file (``StudySettings.meters``, ``burstloc study
--meters-file``) replaces every junction as the meters of its network's points at full
coverage.

Wave speeds per pipe (``StudySettings.wave_speeds``, ``burstloc study --wave-speeds``) apply
to every point alike: the bursts are simulated with them, the meters placed, the arrival
localizer built and the configuration calibrated with paths timed at each pipe's speed (as
``burstloc simulate``, ``place`` and ``calibrate`` take them).

History: every captured stream is preceded by 2N + 1 readings of the initial steady state
(N = the calibrated localization interval), as a live meter's would be (TSNet starts from that
steady state); noise is added to them too.

Calibration: the noise model is the grid point's sigma, or the calibration default (0.01 m) when
the meters are noise-free (a threshold calibrated on exact readings would be zero).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from burstloc.experiments.calibrate import DEFAULT_NOISE_SIGMA, calibrate
from burstloc.experiments.grid import (
    StudyPoint,
    StudySettings,
    point_scenarios,
)
from burstloc.experiments.harness import Clock, Tally, capture_readings
from burstloc.experiments.ranking import RankingSetup, rank_attempts

__all__ = [
    "run_study",
    "score_point",
]


def score_point(task: tuple[StudyPoint, StudySettings]) -> list[dict[str, Any]]:
    """Score one grid point (simulations must be cached or are simulated here).

    Every burst is captured, run through the calibrated bank and every localizer, and counted
    by :mod:`burstloc.experiments.harness` (the code ``burstloc evaluate`` scores with): at
    phase ``k`` the capture clock's first tick is ``k / phases`` of an interval after the
    simulation's start, preceded by ``2N + 1`` steady readings; the sensor noise (keyed by pipe,
    phase and interval) covers them too.

    Returns one row per detector x localizer x meter model x capture interval: ``top1``,
    ``top3`` (fractions of attempts), ``attempts``, ``not_located``, ``median_time_s`` (burst
    start to decision) and the point's description.
    """
    from burstloc.localize.decide import RankingLocalizers
    from burstloc.localize.fused import FusedLocalizer
    from burstloc.localize.signature import SignatureLocalizer
    from burstloc.network import read_network
    from burstloc.sim.model.prepare import arrival_localizer
    from burstloc.sim.placement.methods import place_meters
    from burstloc.sim.scenarios.sensors import SensorModel
    from burstloc.sim.signatures.compute import cached_signature_sets
    from burstloc.sim.transient.tsnet import simulate_burst

    point, settings = task
    f = point.factors
    network = read_network(point.network)  # once per worker process
    results = [simulate_burst(s) for s in point_scenarios(point, settings, network)]
    junctions = list(results[0].junctions)
    signature_sets = cached_signature_sets(network, junctions)
    count = max(1, round(f.meter_fraction * len(junctions)))
    if count < len(junctions):
        placed = place_meters(
            network, count, method=settings.placement, wave_speeds=settings.wave_speeds
        )
        meters = list(placed.meters)
    else:
        meters = list(settings.meters_for(network) or junctions)
    arrival = arrival_localizer(network, meters, wave_speeds=settings.wave_speeds)
    signature = SignatureLocalizer([s.for_meters(meters) for s in signature_sets])
    config = calibrate(
        network,
        capture_intervals=settings.capture_intervals,
        meters=meters,
        noise_sigma=f.noise_sigma if f.noise_sigma > 0 else DEFAULT_NOISE_SIGMA,
        false_alarm_rate=settings.false_alarm_rate,
        seed=settings.seed,
        wave_speeds=settings.wave_speeds,
    )
    localizers = RankingLocalizers(arrival, signature, FusedLocalizer(arrival, signature))
    setup = RankingSetup(meters, config, localizers, network)
    sensor = SensorModel(noise_sigma=f.noise_sigma, seed=settings.seed)
    rows: list[dict[str, Any]] = []
    for dt in settings.capture_intervals:
        history = 2 * config.for_interval(dt).localization_interval + 1
        clocks = [Clock(dt, k * dt / settings.phases, history) for k in range(settings.phases)]
        for detector in settings.detectors:
            for model in settings.meter_models:
                tally = {name: Tally() for name in settings.localizers}
                for k, clock in enumerate(clocks):
                    for res in results:
                        readings = capture_readings(
                            res,
                            clock,
                            model,
                            meters=meters,
                            sensor=sensor,
                            noise_key=f"{res.pipe}/{k}/{dt}",
                        )
                        ranked = rank_attempts(
                            res,
                            readings,
                            setup,
                            detector=detector,
                            capture_interval=dt,
                            localizers=settings.localizers,
                            meter_model=model,
                        )
                        for name, attempt in ranked.items():
                            tally[name].add(attempt)
                rows += [
                    _row(point, len(meters), detector, name, model, dt, t)
                    for name, t in tally.items()
                ]
    return rows


def _row(
    point: StudyPoint,
    meters: int,
    detector: str,
    localizer: str,
    model: str,
    dt: float,
    tally: Tally,
) -> dict[str, Any]:
    """One row of the study's results."""
    return {
        "network": Path(point.network).stem,
        "point": point.label,
        "factor": point.factor,
        "level": None if point.factor == "default" else getattr(point.factors, point.factor),
        "meters": meters,
        "detector": detector,
        "localizer": localizer,
        "meter_model": model,
        "capture_interval": dt,
        "top1": tally.top1_fraction,
        "top3": tally.top3_fraction,
        "attempts": tally.attempts,
        "not_located": tally.not_located,
        "median_time_s": tally.median_time(),
    }


def run_study(
    points: Sequence[StudyPoint],
    settings: StudySettings,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> tuple[list[dict[str, Any]], list[str]]:
    """Simulate (cached) every burst of every point, then score the points.

    Returns:
        ``(rows, problems)``: the rows of every point that could be scored, and one message per
        point left out (a simulation or the scoring failed; the message names it and why).
    """
    from burstloc.sim.scenarios.sweep import sweep
    from burstloc.sim.transient.tsnet import simulate_many

    needs = {p: point_scenarios(p, settings) for p in points}
    scenarios = list(dict.fromkeys(s for group in needs.values() for s in group))
    report = simulate_many(scenarios, workers=workers, scheduler=scheduler, progress=progress)
    failed = {f.item: str(f) for f in report.failures}
    problems = []
    runnable = []
    for point, group in needs.items():
        bad = [failed[s] for s in group if s in failed]
        if bad:
            problems.append(f"{point.label}: left out, {len(bad)} simulation(s) failed: {bad[0]}")
        else:
            runnable.append(point)
    scored = sweep(
        score_point,
        [(p, settings) for p in runnable],
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="study",
        label=lambda task: task[0].label,
    )
    problems += [f"{f.item[0].label}: left out, scoring failed: {f}" for f in scored.failures]
    return [row for _, rows in scored.succeeded() for row in rows], problems
