"""The speed at which the detectors hear a burst's front, per capture interval, from simulated
bursts.

A burst's front loses height at every junction it passes. A meter's detector hears it once
the change has grown past its threshold: near the burst at once, far from it a few readings
late, the later the coarser the readings and the weaker the front. The arrival localizer,
timing paths at the pipes' wave speed, then reads the far meters' lateness as distance and
places bursts towards the near meters. Regressed within each burst (its time unknown), the
alarm starts of L-TOWN's 33 BattLeDIM sensors at 0.05 s lag by about 0.15 s per km: a front
heard at about 1 020 m/s where the wave runs at 1 200 m/s.

:func:`simulate_front_bursts` and :func:`speeds_of` measure that speed on the network itself,
without data: the first simulates bursts on ``bursts`` pipes drawn with ``seed`` (the
calibrated meters, their calibrated noise, the network's own transient model) and runs the
calibrated detector bank of each capture interval over the readings as the monitor does; the
second fits the travel times of every burst's arrivals
(:func:`burstloc.localize.travel_fit.fit_travel_times`, each burst's time fitted, no clock
offsets). The fitted speed over the model's wave speed (at most 1: a fit faster than the wave,
as two meters far apart can give, leaves the wave's speed) is that interval's
:attr:`~burstloc.localize.interval.IntervalCalibration.front_factor`, the arrivals' scatter
around it (a share of each travel time) is recorded in its provenance but not used: the
search regions already widen to the misfits each burst shows, and on L-TOWN's 200 pipes at
0.01 s the scatter (8.6 % then; 4.8 % since the fit's robust start) as the regions' tolerance
grew them by 45 % and held no more.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError, SimulationError
from burstloc.experiments.harness import Clock, capture_readings
from burstloc.experiments.known_events import onsets_after
from burstloc.experiments.paper import SCENARIO, ScenarioConfig
from burstloc.experiments.position import NetworkDistance, PipePoint, true_point, wave_travel
from burstloc.localize.config import Calibration
from burstloc.localize.interval import calibrated_bank
from burstloc.localize.travel_fit import EventArrivals, TravelFit, fit_travel_times
from burstloc.network import Network, closed_pipes, pipe_names

__all__ = [
    "DEFAULT_FRONT_BURSTS",
    "FrontBurst",
    "FrontFit",
    "simulate_front_bursts",
    "speeds_of",
    "with_front_speeds",
]

#: Bursts simulated by default: enough arrivals (bursts x meters) for a slope good to a few %.
DEFAULT_FRONT_BURSTS = 24


@dataclass(frozen=True)
class FrontBurst:
    """One simulated burst as the meters read it at one capture interval: its ``truth`` (the
    burst point, on a pipe of ``length`` m), the noisy readings ``(times, values)`` of the
    calibrated meters, the calibrated bank's ``alarms`` from the burst on, and its
    ``arrivals`` (each meter's first alarm start, with its distance from the burst)."""

    truth: PipePoint
    length: float
    times: NDArray[np.float64]
    values: NDArray[np.float64]
    alarms: tuple[Any, ...]
    arrivals: EventArrivals


@dataclass(frozen=True)
class FrontFit:
    """What the simulated bursts showed at one capture interval: the ``fit`` of their arrivals
    and how many of the ``bursts`` the meters heard (at least two meters each)."""

    capture_interval: float
    fit: TravelFit
    bursts: int
    heard: int

    def factor(self, wave_speed: float) -> float:
        """The front's speed over ``wave_speed`` (the model's), at most 1: no detector hears a
        front before the wave brings it, so a fit faster than the wave (two meters a burst, whose
        one difference the paths' shapes decide) leaves the wave's speed."""
        return min(1.0, self.fit.wave_speed / wave_speed)


def _pipes(network: Network, count: int, seed: int) -> list[str]:
    """``count`` open pipes drawn with ``seed`` (all of them where there are fewer)."""
    closed = set(closed_pipes(network.model))
    open_pipes = sorted(p for p in pipe_names(network.model) if p not in closed)
    if not open_pipes:
        raise ConfigError(f"{network.path}: no open pipe to simulate a burst on")
    rng = np.random.default_rng(seed)
    chosen = rng.choice(len(open_pipes), size=min(count, len(open_pipes)), replace=False)
    return [open_pipes[i] for i in sorted(chosen)]


def _heard(
    result: Any,
    config: Calibration,
    capture_interval: float,
    truth: tuple[PipePoint, float],
    distances: dict[str, float],
    detector: str,
    seed: int,
) -> FrontBurst:
    """One burst at ``capture_interval``: the calibrated bank run over noisy readings as the
    monitor runs it, its alarms from the burst on, each meter's first alarm start."""
    from burstloc.sim.scenarios.sensors import SensorModel

    cal = config.for_interval(capture_interval)
    meters = list(config.meters)
    clock = Clock.at_offset(capture_interval, 0.0, 2 * cal.localization_interval)
    sensor = SensorModel(meters=tuple(meters), seed=seed, meter_sigma=dict(config.noise_sigma))
    times, values = capture_readings(
        result, clock, meters=meters, sensor=sensor, noise_key=f"front/{result.pipe}"
    )
    burst = float(result.metadata["burst_start"])
    alarms = calibrated_bank(detector, len(meters), cal).run(np.ascontiguousarray(values))
    onsets = onsets_after(meters, (times, values), alarms, burst, capture_interval)
    arrivals = EventArrivals(
        name=f"burst on {result.pipe}",
        time=burst,
        distances=distances,
        onsets=onsets,
        capture_interval=capture_interval,
        time_known=False,
    )
    after = tuple(a for a in alarms if times[int(a.index)] >= burst)  # noise before: dismissed
    return FrontBurst(truth[0], truth[1], times, values, after, arrivals)


def simulate_front_bursts(
    network: Network,
    config: Calibration,
    *,
    bursts: int = DEFAULT_FRONT_BURSTS,
    seed: int = 0,
    scenario: ScenarioConfig = SCENARIO,
    burst_flow: Any = None,
    detector: str = "cusum",
    workers: int | None = None,
    cache: Any = False,
    progress: bool = False,
) -> dict[float, list[FrontBurst]]:
    """What the calibrated meters hear of simulated bursts, per capture interval of ``config``.

    ``bursts`` pipes drawn with ``seed`` burst as ``scenario`` says (its ``min_pipe_length``:
    the transient-ready model), sized by ``burst_flow`` (m³/s or a
    :class:`~burstloc.sim.signatures.burst_size.BurstFlow`; ``None``: the scenario's
    coefficient); simulated over ``workers`` processes, through ``cache`` (default none).

    Raises:
        ConfigError: ``bursts`` < 2 (a speed needs two bursts' arrivals at least).
        SimulationError: a burst could not be simulated.
    """
    from burstloc.sim.scenarios.scenario import burst_scenarios
    from burstloc.sim.signatures.burst_size import sized_scenarios
    from burstloc.sim.transient import tsnet as simulate
    from burstloc.sim.transient.time_step import with_capture_time_step

    if not isinstance(bursts, int) or bursts < 2:
        raise ConfigError(f"the front's speed needs at least 2 simulated bursts, got {bursts!r}")
    config.check(network)
    model = config.model
    intervals = [item.capture_interval for item in config.intervals]
    longest = max(
        2 * item.localization_interval * item.capture_interval for item in config.intervals
    )
    params: dict[str, Any] = scenario.parameters()
    travel = wave_travel(network.model, float(params["wave_speed"]))
    params["duration"] = float(math.ceil(scenario.burst_start + travel + longest + 1.0))
    scenarios = burst_scenarios(network, _pipes(network, bursts, seed), **params)
    scenarios = with_capture_time_step(scenarios, min(intervals))
    scenarios, _ = sized_scenarios(scenarios, burst_flow, network)
    stretch = {p.pipe: p.stretch for p in model.pipes if p.stretch != 1.0}
    distance = NetworkDistance(network.model, stretch)
    events: dict[float, list[FrontBurst]] = {dt: [] for dt in intervals}

    def arrivals(_: Any, result: Any) -> Any:
        point = true_point(result, network.model)
        truth = (point, float(network.model.get_link(result.pipe).length))
        distances = {m: distance.to_node(point, m) for m in config.meters}
        for dt in intervals:
            events[dt].append(_heard(result, config, dt, truth, distances, detector, seed))
        return replace(result, time=result.time[:1].copy(), heads=result.heads[:1].copy())

    report = simulate.simulate_many(
        scenarios, cache=cache, workers=workers, progress=progress, shrink=arrivals
    )
    if report.failures:
        raise SimulationError("; ".join(report.failure_lines()))
    return events


def speeds_of(config: Calibration, bursts: Mapping[float, Sequence[FrontBurst]]) -> list[FrontFit]:
    """The front's speed fitted on each capture interval's simulated ``bursts``.

    Raises:
        ConfigError: the bursts' arrivals cannot tell a speed at some interval (fewer than three
            arrivals at different distances: the meters heard nothing, or the network is too
            small).
    """
    model = config.model
    fits = []
    for dt, heard_at in bursts.items():
        events = [b.arrivals for b in heard_at]
        heard = sum(len(e.onsets) >= 2 for e in events)
        try:
            fit = fit_travel_times(
                events,
                config.meters,
                wave_speed=model.wave_speed,
                wave_speed_tolerance=model.wave_speed_tolerance,
                clock_tolerance=0.0,
            )
        except ConfigError as exc:
            raise ConfigError(
                f"the front's speed at {dt:g} s cannot be fitted from {len(events)} "
                f"simulated bursts ({heard} heard by two meters or more): {exc}"
            ) from None
        fits.append(FrontFit(dt, fit, len(events), heard))
    return fits


def with_front_speeds(config: Calibration, fits: Sequence[FrontFit]) -> Calibration:
    """``config`` with each fitted interval's front factor, recorded in its provenance."""
    model_speed = config.model.wave_speed
    changes = {f.capture_interval: {"front_factor": f.factor(model_speed)} for f in fits}
    provenance = {
        "front_speeds": {
            f"{f.capture_interval:g}": {
                "speed": round(f.fit.wave_speed, 1),
                "bursts": f.bursts,
                "heard": f.heard,
                "arrivals": f.fit.arrivals,
                "scatter": round(f.fit.wave_speed_tolerance, 4),
            }
            for f in fits
        },
    }
    return config.with_fitted(changes, provenance)
