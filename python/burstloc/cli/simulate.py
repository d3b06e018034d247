"""``burstloc simulate``: simulate pipe bursts (one NPZ file per pipe) or another event with
TSNet (a valve or pump operation, a demand step)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_min_pipe_length_option,
    add_run_options,
    add_solver_option,
    cache_of,
    check_run_options,
)
from burstloc.constants import SCENARIO_DURATION, WAVE_SPEED
from burstloc.exceptions import ConfigError

__all__ = ["add_parser", "run"]

#: The kinds of ``--event`` (:data:`burstloc.sim.events.EVENT_KINDS`, without importing the
#: simulator to build the parser).
EVENT_KINDS = ("valve-closure", "valve-opening", "pump-trip", "pump-start", "demand-step")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc simulate``."""
    from burstloc.sim import scenario as sim

    parser = subparsers.add_parser(
        "simulate",
        help="simulate pipe bursts with TSNet and write one NPZ file per scenario",
        description=(
            "Simulate a burst on each chosen pipe (split at --position) and write the pressure "
            "head of every junction over time, one NPZ file per pipe: arrays time (T,), heads "
            "(T, M), junctions (M,) and metadata (a JSON string). Results are cached."
        ),
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
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
    parser.add_argument(
        "--operation-time",
        type=float,
        default=1.0,
        metavar="S",
        help="--event: how long the operation or the demand ramp takes (default 1 s)",
    )
    parser.add_argument(
        "--setting",
        type=float,
        default=None,
        metavar="F",
        help="--event valve-*: final fraction open (default: 0 for a closure, 1 for an opening)",
    )
    parser.add_argument(
        "--demand-change",
        type=float,
        default=None,
        metavar="M3/S",
        help="--event demand-step: the change of the junction's demand, m^3/s",
    )
    parser.add_argument("--position", type=float, default=0.5, help="fraction along the pipe")
    parser.add_argument(
        "--burst-start",
        "--start",
        type=float,
        default=sim.DEFAULT_BURST_START,
        metavar="S",
        help="when the burst (or --event) starts, s",
    )
    parser.add_argument("--duration", type=float, default=SCENARIO_DURATION, metavar="S")
    parser.add_argument(
        "--burst-coeff",
        type=float,
        default=sim.DEFAULT_BURST_COEFF,
        metavar="C",
        help="final emitter coefficient, m^3/s/m^0.5",
    )
    parser.add_argument("--opening-time", type=float, default=sim.DEFAULT_OPENING_TIME, metavar="S")
    parser.add_argument("--wave-speed", type=float, default=WAVE_SPEED, metavar="M/S")
    parser.add_argument(
        "--time-step", type=float, default=None, metavar="S", help="default: TSNet's largest"
    )
    add_min_pipe_length_option(parser)
    add_solver_option(parser)
    parser.add_argument(
        "--capture-interval",
        type=float,
        default=None,
        metavar="S",
        help="write the readings meters send every S seconds instead of TSNet's grid",
    )
    parser.add_argument("--capture-phase", type=float, default=0.0, metavar="S")
    parser.add_argument("--out", default="out/simulations", metavar="DIR")
    add_run_options(parser)
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc simulate``."""
    from burstloc.sim import scenario
    from burstloc.sim.tsnet import simulate_many

    check_output(args.out, directory=True)
    check_run_options(args)
    if args.event is not None:
        return _event(args)
    scenarios = scenario.burst_scenarios(
        args.network,
        None if args.all else args.pipe,
        position=args.position,
        burst_start=args.burst_start,
        opening_time=args.opening_time,
        burst_coeff=args.burst_coeff,
        wave_speed=args.wave_speed,
        duration=args.duration,
        time_step=args.time_step,
        min_pipe_length=args.min_pipe_length,
        solver=args.solver,
    )
    cache = cache_of(args)
    report = simulate_many(
        scenarios,
        cache=cache,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.quiet,
    )
    written = 0
    for _, result in report.succeeded():
        if args.capture_interval is not None:
            result = result.resample(args.capture_interval, args.capture_phase)
        result.save(scenario.output_path(args.out, result))
        written += 1
    print(f"wrote {written} scenario file(s) to {args.out}")
    for failure in report.failures:
        print(f"burstloc: failed: {failure}", file=sys.stderr)
    return 0 if report.ok else 1


def _event(args: argparse.Namespace) -> int:
    """``burstloc simulate --event KIND --asset ID``: one event, one NPZ file."""
    from burstloc.sim.events import EventScenario, event_output_path, simulate_event

    if args.asset is None:
        raise ConfigError(f"--event {args.event} needs --asset (the valve, pump or junction)")
    if args.min_pipe_length is not None:
        raise ConfigError("--min-pipe-length applies to bursts only, not to --event")
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
    )
    result = simulate_event(scenario, cache=cache_of(args))
    if args.capture_interval is not None:
        result = result.resample(args.capture_interval, args.capture_phase)
    path = result.save(event_output_path(args.out, scenario))
    print(f"wrote {path} ({scenario.label})")
    return 0
