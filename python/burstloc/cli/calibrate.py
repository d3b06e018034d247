"""``burstloc calibrate``: thresholds and localization settings from a burst-free baseline."""

from __future__ import annotations

import argparse
import time
from typing import TYPE_CHECKING, Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_burst_options,
    add_meters_file_option,
    add_meters_option,
    add_min_pipe_length_option,
    add_network_argument,
    add_noise_option,
    add_number,
    add_wave_speed_option,
    add_wave_speeds_option,
    meters_of,
    scenario_of,
    wave_speeds_of,
)
from burstloc.constants import (
    CAPTURE_INTERVALS,
    CLOCK_TOLERANCE,
    EXACT_SIGNATURES_UP_TO,
    HYBRID_SIGNATURES_UP_TO,
    WAVE_SPEED_TOLERANCE,
)

if TYPE_CHECKING:
    from burstloc.localize.config import Calibration
    from burstloc.network import Network

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc calibrate``."""
    from burstloc.experiments import calibrate

    parser = subparsers.add_parser(
        "calibrate",
        help="derive detector thresholds from a burst-free baseline",
        description="Per meter and capture interval, thresholds that meet a target false-alarm "
        "rate on the network's steady state plus the sensor noise model, and the localization "
        "model (pipe flow directions and lengths, path lengths to the meters, burst "
        "signatures; computed here with WNTR/EPANET); written as a named configuration that "
        "`evaluate --config` and `monitor --config` accept.",
    )
    add_network_argument(parser)
    parser.add_argument(
        "--out",
        required=True,
        help="configuration file to write: JSON, or with a path ending in .npz the same "
        "document with its large matrices as binary arrays (a third of the size on a "
        "900-pipe network; both load anywhere a configuration is read)",
    )
    add_number(parser, "--capture-interval", list(CAPTURE_INTERVALS), "S", many=True)
    add_noise_option(parser, calibrate.DEFAULT_NOISE_SIGMA, "what the thresholds are set for")
    add_number(
        parser,
        "--false-alarm-rate",
        calibrate.DEFAULT_FALSE_ALARM_RATE,
        "R",
        "target false alarms per meter per hour",
    )
    meters = parser.add_mutually_exclusive_group()
    add_meters_option(meters, "default: every junction")  # type: ignore[arg-type]
    add_meters_file_option(meters)  # type: ignore[arg-type]
    add_number(
        parser,
        "--wave-speed-tolerance",
        WAVE_SPEED_TOLERANCE,
        "U",
        "how well the wave's travel times are known, as a share of each (the search regions "
        "widen with the path: U x path / wave speed)",
    )
    add_number(
        parser,
        "--clock-tolerance",
        CLOCK_TOLERANCE,
        "S",
        "how well each meter's clock is known, s (GPS loggers: 0.001, NTP: a few ms)",
    )
    add_wave_speed_option(
        parser, "the pressure wave speed the localizers assume, m/s (--known-events fits it)"
    )
    add_wave_speeds_option(
        parser,
        "The localizers time each path at its pipes' speeds (--known-events scales them all).",
    )
    parser.add_argument(
        "--known-events",
        default=None,
        metavar="FILE",
        help="learn the wave speed, each meter's clock offset and the travel times' tolerance "
        "from transients whose place and time are known (a JSON file listing each event's "
        "readings feed, time and junction or pipe and position; see docs/results.md)",
    )
    fronts = parser.add_argument_group(
        "the fronts' speed",
        "A weak front is heard once it has grown past a threshold, later the farther it has "
        "gone: at 0.05 s and coarser the meters hear bursts' fronts travel slower than the "
        "wave (about 1 020 m/s on L-TOWN where the wave runs at 1 200 m/s). --front-bursts "
        "measures that speed at each capture interval on bursts simulated here on the "
        "network's own transient model, and the arrival localizer times paths at it. On the "
        "same bursts it checks the search regions: where more bursts fall outside the 95 % "
        "regions than chance explains, their timing error is widened until they hold.",
    )
    add_number(
        fronts,  # type: ignore[arg-type]
        "--front-bursts",
        0,
        "N",
        "bursts to simulate (default 0: paths timed at the wave speed; 24 or more to fit)",
        kind=int,
    )
    add_number(fronts, "--front-seed", 0, "S", "draws the bursts' pipes", kind=int)  # type: ignore[arg-type]
    add_burst_options(fronts, None)
    add_min_pipe_length_option(fronts)  # type: ignore[arg-type]
    parser.add_argument("--name", default=None, help="the configuration's name")
    parser.add_argument(
        "--signatures",
        choices=("auto", "epanet", "hybrid", "linear"),
        default="auto",
        help="how the burst signatures are computed: 'epanet' one EPANET steady state per pipe "
        "and position (exact for the reference burst), 'hybrid' one per pipe at mid-pipe and the "
        "other positions from the linearized steady state, 'linear' one factorization of the "
        "linearized steady state (seconds on any network; a large burst's shape approximated); "
        f"'auto' (default): epanet up to {EXACT_SIGNATURES_UP_TO} pipes, hybrid up to "
        f"{HYBRID_SIGNATURES_UP_TO}, linear above",
    )
    add_number(
        parser,
        "--workers",
        None,
        "N",
        "local processes for the hybrid signatures' EPANET runs (default: one per CPU)",
        kind=int,
    )
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc calibrate``."""
    from burstloc.experiments.calibrate import calibrate
    from burstloc.network import read_network

    check_output(args.out)
    began = time.perf_counter()
    network = read_network(args.network)
    config = calibrate(
        network,
        capture_intervals=args.capture_interval,
        noise_sigma=args.noise,
        false_alarm_rate=args.false_alarm_rate,
        meters=meters_of(args, network),
        name=args.name,
        signatures=args.signatures,
        workers=args.workers,
        wave_speed_tolerance=args.wave_speed_tolerance,
        clock_tolerance=args.clock_tolerance,
        wave_speed=args.wave_speed,
        wave_speeds=wave_speeds_of(args, network),
    )
    if args.front_bursts:
        config = _fronts(args, network, config)
    if args.known_events:
        config = _learn(args, network, config)
    seconds = time.perf_counter() - began
    for line in config.summary():
        print(line)
    print(f"calibrated in {seconds:.1f} s; wrote {config.save(args.out)}")
    return 0


def _fronts(args: argparse.Namespace, network: Network, config: Calibration) -> Calibration:
    """``config`` with the speed its meters hear bursts' fronts at, per capture interval, fitted
    on ``--front-bursts`` simulated bursts, and the timing error its search regions need there
    to hold what they state on those bursts; what was fitted printed."""
    from burstloc.experiments.front_speed import simulate_front_bursts, speeds_of, with_front_speeds
    from burstloc.experiments.region_spread import fit_timing_factors, with_timing_factors

    scenario, flow = scenario_of(args)
    bursts = simulate_front_bursts(
        network,
        config,
        bursts=args.front_bursts,
        seed=args.front_seed,
        scenario=scenario,
        burst_flow=flow,
        workers=args.workers,
    )
    fits = speeds_of(config, bursts)
    speed = config.model.wave_speed
    for f in fits:
        print(
            f"fronts at {f.capture_interval:g} s: heard at {f.fit.wave_speed:.0f} m/s "
            f"({f.fit.wave_speed / speed:.3f} x {speed:.0f} m/s"
            + (
                "; no faster than the wave: the paths keep its speed"
                if f.factor(speed) == 1
                else ""
            )
            + f") over {f.fit.arrivals} arrivals of "
            f"{f.heard}/{f.bursts} bursts ({f.fit.dropped} dropped), scatter "
            f"{f.fit.wave_speed_tolerance:.1%}"
        )
    config = with_front_speeds(config, fits)
    spreads = fit_timing_factors(config, bursts)
    for g in spreads:
        print(
            f"regions at {g.capture_interval:g} s: timing error x{g.factor:g}, the "
            f"{g.confidence:.0%} regions holding {g.held(g.factor)}/{g.placed} of the bursts the "
            f"arrivals placed ({g.held(1.0)} at x1; {g.bursts} simulated)"
        )
    return with_timing_factors(config, spreads)


def _learn(args: argparse.Namespace, network: Network, config: Calibration) -> Calibration:
    """``config`` with the travel times the known events show (wave speed, clock offsets,
    tolerance); what was fitted printed."""
    from dataclasses import replace

    from burstloc.experiments.known_events import event_arrivals, read_known_events
    from burstloc.localize.travel_fit import fit_travel_times

    events = read_known_events(args.known_events, network)
    arrivals = event_arrivals(events, network, config)
    model = config.model
    fit = fit_travel_times(
        arrivals,
        config.meters,
        wave_speed=model.wave_speed,
        wave_speed_tolerance=model.wave_speed_tolerance,
        clock_tolerance=model.clock_tolerance,
    )
    offsets = sorted(fit.clock_offsets.values())
    print(
        f"known events: {len(events)}, {fit.arrivals} arrivals ({fit.dropped} dropped as "
        f"outliers); wave speed {model.wave_speed:.0f} -> {fit.wave_speed:.0f} m/s"
        + (
            f" (each pipe's own speed x {fit.wave_speed / model.wave_speed:.3f})"
            if any(p.stretch != 1.0 for p in model.pipes)
            else ""
        )
        + ", "
        f"travel-time tolerance {model.wave_speed_tolerance:.1%} -> "
        f"{fit.wave_speed_tolerance:.1%}, residual RMS {1000 * fit.rms:.1f} ms"
        + (
            f"; clock offsets {1000 * offsets[0]:+.1f} to {1000 * offsets[-1]:+.1f} ms"
            if offsets and model.clock_tolerance > 0
            else ""
        )
    )
    provenance = {**config.provenance, "known_events": len(events), "wave_speed": fit.wave_speed}
    return replace(config, model=fit.apply(model), provenance=provenance)
