"""``burstloc simulate``: simulate pipe bursts (one NPZ file per pipe) or another event with
TSNet (a valve or pump operation, a demand step)."""

from __future__ import annotations

import argparse
import math
import sys
from datetime import datetime
from typing import Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_burst_options,
    add_meters_option,
    add_min_pipe_length_option,
    add_network_argument,
    add_noise_option,
    add_number,
    add_run_options,
    add_solver_option,
    add_time_step_option,
    add_wave_speed_option,
    add_wave_speeds_option,
    burst_size_of,
    cache_of,
    check_run_options,
    meters_of,
    run_of,
    wave_speeds_of,
)
from burstloc.cli._truth import add_truth_options, truth_of
from burstloc.constants import SCENARIO_DURATION
from burstloc.exceptions import ConfigError

__all__ = ["add_parser", "run"]

# : The kinds of ``--event`` (:data:`burstloc.sim.events.operations.EVENT_KINDS`, without importing
# the
#: simulator to build the parser).
EVENT_KINDS = ("valve-closure", "valve-opening", "pump-trip", "pump-start", "demand-step")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc simulate``."""
    from burstloc.experiments.paper import SCENARIO

    parser = subparsers.add_parser(
        "simulate",
        help="simulate pipe bursts with TSNet and write one NPZ file per scenario, or a feed",
        description=(
            "Simulate a burst on each chosen pipe (split at --position) and write the pressure "
            "head of every junction over time, one NPZ file per pipe: arrays time (T,), heads "
            "(T, M), junctions (M,) and metadata (a JSON string). Results are cached. The burst "
            "is the one `burstloc evaluate` simulates (5 %% of the network's demand, at most "
            "5 L/s, opened in 0.3 s, at 10 s; "
            "--burst-coeff 0.02 is the paper's). With --feed FILE (one pipe or --event, and "
            "--capture-interval): "
            "also the readings the meters would send, in the CSV form `burstloc monitor "
            "--readings` reads: a header line 'timestamp,meter,value', then one line per "
            "reading, every meter's reading of a capture tick before the next tick's; "
            "timestamp: seconds from the simulation's start, or with --start an ISO 8601 time; "
            "meter: the junction; value: pressure head, m (0.1 mm), with --noise."
        ),
    )
    add_network_argument(parser)
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--pipe", nargs="+", metavar="ID", help="pipe(s) to burst")
    which.add_argument("--all", action="store_true", help="burst every pipe, one at a time")
    which.add_argument(
        "--event",
        choices=list(EVENT_KINDS),
        default=None,
        help="simulate this non-burst event on --asset instead of a burst",
    )
    parser.add_argument(
        "--asset", default=None, metavar="ID", help="--event: the valve, pump or junction"
    )
    event = parser.add_argument_group("event (with --event)")
    add_number(
        event, "--operation-time", 1.0, "S", "how long the operation or demand ramp takes, s"
    )
    add_number(
        event,
        "--setting",
        None,
        "F",
        "valve-*: final fraction open (default: 0 for a closure, 1 for an opening)",
    )
    add_number(event, "--demand-change", None, "M3/S", "demand-step: the junction's demand change")
    add_burst_options(parser, 0.5)
    for flag, default, metavar, text in (
        ("--burst-start", SCENARIO.burst_start, "S", "when the burst (or --event) starts, s"),
        ("--duration", SCENARIO_DURATION, "S", "simulated, s"),
        ("--opening-time", SCENARIO.opening_time, "S", "how long the burst takes to open, s"),
    ):
        add_number(parser, flag, default, metavar, text)
    add_wave_speed_option(parser)
    add_wave_speeds_option(parser, "A merged pipe of --min-pipe-length keeps its travel time.")
    add_time_step_option(parser)
    add_min_pipe_length_option(parser)
    add_solver_option(parser)
    add_number(
        parser,
        "--capture-interval",
        None,
        "S",
        "write the readings meters send every S seconds instead of TSNet's grid",
    )
    add_number(parser, "--capture-phase", 0.0, "S", "first capture tick, s")
    parser.add_argument(
        "--out", default="out/simulations", metavar="DIR", help="directory of the NPZ files"
    )
    feed = parser.add_argument_group("feed (the readings a monitor would receive)")
    feed.add_argument(
        "--feed",
        default=None,
        metavar="FILE",
        help="write the captured readings as a `burstloc monitor --readings` feed (CSV)",
    )
    add_noise_option(feed, 0.0, "--feed: added to the readings")
    add_number(feed, "--seed", 0, "N", "--feed: the noise's seed", kind=int)
    add_meters_option(
        feed,
        "--feed writes these meters' readings only (default: the configuration's with "
        "--config, else every junction)",
    )
    feed.add_argument(
        "--config",
        default=None,
        metavar="PATH",
        help="--feed: the configuration the monitor will run (from `burstloc calibrate`): the "
        "feed carries its meters' readings; refused if made for another network",
    )
    feed.add_argument(
        "--start",
        default=None,
        metavar="ISO-TIME",
        help="--feed: the wall-clock time of the simulation's start, ISO 8601 with a UTC offset "
        "or Z (e.g. 2026-11-26T10:00:00Z); the feed's timestamps are then ISO times "
        "(default: seconds from the simulation's start)",
    )
    add_run_options(parser)
    parser.set_defaults(handler=run)
    add_truth_options(
        parser,
        "simulate the burst on a perturbed copy of the network; the clock offsets and the "
        "silent meter act on the --feed, the meters' readings (all off by default)",
    )
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc simulate``."""
    from burstloc.experiments.paper import SCENARIO
    from burstloc.network import as_network
    from burstloc.sim.scenarios import scenario
    from burstloc.sim.scenarios.result import output_path
    from burstloc.sim.transient.time_step import with_capture_time_step
    from burstloc.sim.transient.tsnet import simulate_many

    check_output(args.out, directory=True)
    check_run_options(args)
    start = _check_feed(args)
    args.feed_meters = _feed_meters(args)
    if args.event is not None:
        return _event(args, start)
    truth = truth_of(args)
    if truth is not None and args.feed is None:
        meters_only = [
            option
            for option, on in (
                ("--truth-clock-offset", truth.clock_offset > 0),
                ("--truth-silent-meter", truth.silent_meter is not None),
            )
            if on
        ]
        if meters_only:
            raise ConfigError(
                f"{' and '.join(meters_only)} act on the meters' readings: give --feed FILE "
                "(the scenario files hold the simulation itself)"
            )
    coeff, flow = burst_size_of(args)
    network = as_network(args.network)  # read once, here at the edge
    scenarios = scenario.burst_scenarios(
        network,
        None if args.all else args.pipe,
        position=args.position,
        burst_start=args.burst_start,
        opening_time=args.opening_time,
        burst_coeff=SCENARIO.burst_coeff if coeff is None else coeff,
        wave_speed=args.wave_speed,
        duration=args.duration,
        time_step=args.time_step,
        min_pipe_length=args.min_pipe_length,
        solver=args.solver,
        wave_speeds=wave_speeds_of(args, network),
    )
    if args.capture_interval is not None:  # a step fine enough for the readings asked for
        scenarios = with_capture_time_step(scenarios, args.capture_interval)
    hearing = None
    if truth is not None:
        from dataclasses import replace

        from burstloc.experiments.truth import Hearing

        print(f"truth perturbed: {truth.describe()}", flush=True)
        scenarios = [replace(s, truth=truth) for s in scenarios]
        hearing = Hearing(truth, network.model, args.feed_meters)
    from burstloc.sim.signatures.burst_size import describe_sizes, sized_scenarios, with_size

    scenarios, sizes = sized_scenarios(scenarios, flow, network)
    print(describe_sizes(sizes, flow))
    size_of = {s.pipe: size for s, size in zip(scenarios, sizes, strict=True)}
    cache = cache_of(args)
    report = simulate_many(
        scenarios,
        cache=cache,
        **run_of(args),
    )
    written = 0
    said: set[str] = set()
    for _, result in report.succeeded():
        for text in result.metadata.get("warnings", []):  # a fallback the user must hear of
            if text.startswith("DemandDrivenWarning: ") and text not in said:
                said.add(text)
                print(f"burstloc: warning: {text.split(': ', 1)[1]}", file=sys.stderr)
        negative = result.negative_pressure(shown=5)  # more than the network can feed there
        if negative is not None:
            print(f"burstloc: warning: {negative}", file=sys.stderr)
        result = with_size(result, size_of[result.pipe], flow)
        heard = result if hearing is None or args.feed is None else hearing(result)
        if args.capture_interval is not None:
            result = result.resample(args.capture_interval, args.capture_phase)
            if heard is not result:
                heard = heard.resample(args.capture_interval, args.capture_phase)
        result.save(output_path(args.out, result))
        written += 1
        _write_feed(args, heard, start)
    print(f"wrote {written} scenario file(s) to {args.out}")
    for line in report.failure_lines():
        print(f"burstloc: failed: {line}", file=sys.stderr)
    return 0 if report.ok else 1


def _check_feed(args: argparse.Namespace) -> datetime | None:
    """The feed options checked before any work; the feed's start time, if any."""
    from burstloc.readings import parse_start_time

    if args.feed is None:
        for option, value, unset in [
            ("--noise", args.noise, 0.0),
            ("--start", args.start, None),
            ("--meters", args.meters, None),
            ("--config", args.config, None),
        ]:
            if value != unset:
                raise ConfigError(f"{option} applies to --feed FILE only")
        return None
    check_output(args.feed)
    if args.capture_interval is None:
        raise ConfigError(
            "--feed needs --capture-interval S: the interval the meters send readings at "
            "(the monitor's --capture-interval)"
        )
    if args.all or (args.pipe is not None and len(args.pipe) != 1):
        raise ConfigError("--feed writes one burst's readings: give one --pipe (or --event)")
    if not (math.isfinite(args.noise) and args.noise >= 0):
        raise ConfigError(f"--noise must be a finite number >= 0 (m), got {args.noise}")
    if args.seed < 0:
        raise ConfigError(f"--seed must be >= 0, got {args.seed}")
    if args.start is None:
        return None
    try:
        return parse_start_time(args.start)
    except ValueError as exc:
        raise ConfigError(f"--start: {exc}, got {args.start!r}") from None


def _feed_meters(args: argparse.Namespace) -> tuple[str, ...] | None:
    """The feed's meters: ``--meters``, else the ``--config``'s, else ``None`` (every
    junction); checked against the network before any simulation."""
    meters = meters_of(args, args.network)
    if meters is None and args.config is not None:
        from burstloc.localize.config import Calibration

        config = Calibration.load(args.config)
        config.check(args.network)
        meters = config.meters
    return meters


def _write_feed(args: argparse.Namespace, result: Any, start: datetime | None) -> None:
    from burstloc.sim.scenarios.feed import write_feed

    if args.feed is not None:
        meters = args.feed_meters
        path, count = write_feed(
            args.feed, result, noise=args.noise, seed=args.seed, start=start, meters=meters
        )
        which = "every junction" if meters is None else f"{len(meters)} meters"
        print(f"wrote {count} readings of {which} to {path} (a `burstloc monitor --readings` feed)")


def _event(args: argparse.Namespace, start: datetime | None) -> int:
    """``burstloc simulate --event KIND --asset ID``: one event, one NPZ file."""
    from burstloc.sim.events.operations import EventScenario, event_output_path, simulate_event

    if args.asset is None:
        raise ConfigError(f"--event {args.event} needs --asset (the valve, pump or junction)")
    if truth_of(args) is not None:
        raise ConfigError("--truth-* options apply to bursts only, not to --event")
    for option, value in (
        ("--min-pipe-length", args.min_pipe_length),
        ("--burst-flow", args.burst_flow),
        ("--burst-coeff", args.burst_coeff),
    ):
        if value is not None:
            raise ConfigError(f"{option} applies to bursts only, not to --event")
    setting = args.setting
    if setting is None:
        setting = 1.0 if args.event == "valve-opening" else 0.0
    scenario = EventScenario(
        args.network,
        args.event,
        args.asset,
        start=args.burst_start,
        operation_time=args.operation_time,
        setting=setting,
        demand_change=0.0 if args.demand_change is None else args.demand_change,
        wave_speed=args.wave_speed,
        duration=args.duration,
        time_step=args.time_step,
        solver=args.solver,
        wave_speeds=wave_speeds_of(args, args.network),
    )
    result = simulate_event(scenario, cache=cache_of(args))
    if args.capture_interval is not None:
        result = result.resample(args.capture_interval, args.capture_phase)
    path = result.save(event_output_path(args.out, scenario))
    print(f"wrote {path} ({scenario.label})")
    _write_feed(args, result, start)
    return 0
