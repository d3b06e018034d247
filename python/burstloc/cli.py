"""The ``burstloc`` command line: subcommands that wire library calls together.

Each subcommand has an ``add_<name>_parser`` function (its arguments) and a ``run_<name>``
function (its handler); :func:`build_parser` registers them. The CLI holds no logic of its own.

Exit status: 0 success, 1 some scenarios failed (reported on stderr), 2 bad input.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Sequence
from typing import Any

from burstloc.exceptions import ConfigError, InputError, NetworkError, SimulationError

__all__ = [
    "add_calibrate_parser",
    "add_evaluate_parser",
    "add_monitor_parser",
    "add_simulate_parser",
    "add_study_parser",
    "build_parser",
    "main",
    "run_calibrate",
    "run_evaluate",
    "run_monitor",
    "run_simulate",
    "run_study",
]


# --- simulate ------------------------------------------------------------------------------


def add_simulate_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc simulate``."""
    from burstloc import simulate as sim

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
    parser.add_argument("--position", type=float, default=0.5, help="fraction along the pipe")
    parser.add_argument("--burst-start", type=float, default=sim.DEFAULT_BURST_START, metavar="S")
    parser.add_argument("--duration", type=float, default=sim.DEFAULT_DURATION, metavar="S")
    parser.add_argument(
        "--burst-coeff",
        type=float,
        default=sim.DEFAULT_BURST_COEFF,
        metavar="C",
        help="final emitter coefficient, m^3/s/m^0.5",
    )
    parser.add_argument("--opening-time", type=float, default=sim.DEFAULT_OPENING_TIME, metavar="S")
    parser.add_argument("--wave-speed", type=float, default=sim.DEFAULT_WAVE_SPEED, metavar="M/S")
    parser.add_argument(
        "--time-step", type=float, default=None, metavar="S", help="default: TSNet's largest"
    )
    parser.add_argument(
        "--capture-interval",
        type=float,
        default=None,
        metavar="S",
        help="write the readings meters send every S seconds instead of TSNet's grid",
    )
    parser.add_argument("--capture-phase", type=float, default=0.0, metavar="S")
    parser.add_argument("--out", default="out/simulations", metavar="DIR")
    parser.add_argument("--workers", type=int, default=None, metavar="N")
    parser.add_argument("--scheduler", default=None, metavar="ADDR", help="Dask scheduler")
    parser.add_argument("--cache-dir", default=None, metavar="DIR")
    parser.add_argument("--no-cache", action="store_true", help="simulate; store nothing")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run_simulate)
    return parser


def run_simulate(args: argparse.Namespace) -> int:
    """Handle ``burstloc simulate``."""
    from burstloc import simulate as sim
    from burstloc.cache import DiskCache

    scenarios = sim.burst_scenarios(
        args.network,
        None if args.all else args.pipe,
        position=args.position,
        burst_start=args.burst_start,
        opening_time=args.opening_time,
        burst_coeff=args.burst_coeff,
        wave_speed=args.wave_speed,
        duration=args.duration,
        time_step=args.time_step,
    )
    cache: DiskCache | bool = False if args.no_cache else DiskCache(args.cache_dir)
    report = sim.simulate_many(
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
        result.save(sim.output_path(args.out, result))
        written += 1
    print(f"wrote {written} scenario file(s) to {args.out}")
    for failure in report.failures:
        print(f"burstloc: failed: {failure}", file=sys.stderr)
    return 0 if report.ok else 1


# --- evaluate ------------------------------------------------------------------------------


#: ``evaluate`` options that configure the paper's rules only.
_PAPER_OPTIONS = ("threshold", "drift", "sigma", "localization_interval", "mode")


def add_evaluate_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc evaluate``."""
    from burstloc.evaluate import DEFAULT_LOCALIZER, LOCALIZERS

    parser = subparsers.add_parser(
        "evaluate",
        help="burst every pipe, localize in real time, score (top-1 / top-3 accuracy)",
        description=(
            "Burst each pipe (simulated once, cached), stream the meters' readings at each "
            "capture interval through the detectors and a localizer, and report accuracy. With "
            "no options: the fused localizer, both detectors x capture intervals 0.2, 2, 5, "
            "10 s. With --localizer paper: the paper's experiment (Tables I/II parameters), "
            "printed beside the paper's Tables III-V; `--localizer paper fused` shows both."
        ),
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument(
        "--detector", choices=("cusum", "shewhart", "both"), default="both", help="default: both"
    )
    parser.add_argument(
        "--capture-interval",
        type=float,
        nargs="+",
        default=None,
        metavar="S",
        help="capture interval(s) in seconds (default: the paper's 0.2 2 5 10)",
    )
    parser.add_argument(
        "--threshold", type=float, default=None, metavar="M", help="paper: default Tables I/II"
    )
    parser.add_argument(
        "--drift", type=float, default=None, metavar="M", help="paper: CUSUM drift (default 0)"
    )
    parser.add_argument(
        "--sigma",
        type=float,
        default=None,
        metavar="K",
        help="paper: Shewhart control-limit multiplier s (default: equal to --threshold)",
    )
    parser.add_argument(
        "--localization-interval",
        type=int,
        default=None,
        metavar="N",
        help="paper: new complete readings per window (default: Tables I/II)",
    )
    parser.add_argument(
        "--mode",
        choices=("window", "stream", "both"),
        default=None,
        help="paper: detection mode, the paper's per-window call ('window') or the streaming "
        "bank ('stream'); default: burstloc.paper.DEFAULT_MODE",
    )
    parser.add_argument(
        "--localizer",
        nargs="+",
        choices=LOCALIZERS,
        default=[DEFAULT_LOCALIZER],
        metavar="NAME",
        help=f"one or more of {', '.join(LOCALIZERS)} (default: {DEFAULT_LOCALIZER}, the most "
        "accurate in `burstloc study`). 'paper' is the paper's rules with Tables I/II "
        "parameters (the options marked 'paper' apply to it only); the ranking localizers use "
        "the calibrated detector bank (--config, or a calibration computed for the network)",
    )
    parser.add_argument(
        "--meter-model",
        choices=("instantaneous", "interval-averaged", "both"),
        default="instantaneous",
        help="what a meter reports each capture interval (default: instantaneous, the paper's)",
    )
    parser.add_argument(
        "--config",
        default=None,
        metavar="PATH",
        help="calibration from `burstloc calibrate` (ranking localizers); refused if it was "
        "made for another network or other meters",
    )
    parser.add_argument("--pipes", nargs="+", default=None, metavar="ID", help="default: all")
    parser.add_argument(
        "--phases", type=int, default=5, metavar="N", help="clock phases per burst (default 5)"
    )
    parser.add_argument(
        "--phase-span",
        choices=("capture", "window"),
        default="capture",
        help="spread the phases over one capture interval (default) or one localization window",
    )
    parser.add_argument("--json", default=None, metavar="PATH", help="write the JSON results")
    parser.add_argument("--csv", default=None, metavar="PATH", help="write the CSV results")
    parser.add_argument(
        "--plot",
        default=None,
        metavar="DIR",
        help="write PNGs: per run, a map of every burst's true and named pipe, and the meters' "
        "traces with their alarms for the first pipe of --pipes",
    )
    parser.add_argument("--workers", type=int, default=None, metavar="N")
    parser.add_argument("--scheduler", default=None, metavar="ADDR", help="Dask scheduler")
    parser.add_argument("--cache-dir", default=None, metavar="DIR")
    parser.add_argument("--no-cache", action="store_true", help="simulate; store nothing")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run_evaluate)
    return parser


def run_evaluate(args: argparse.Namespace) -> int:
    """Handle ``burstloc evaluate``."""
    from burstloc import paper, report
    from burstloc.cache import DiskCache
    from burstloc.evaluate import evaluate, paper_runs, ranking_runs

    detectors = ("cusum", "shewhart") if args.detector == "both" else (args.detector,)
    localizers = list(dict.fromkeys(args.localizer))
    ranking = [name for name in localizers if name != "paper"]
    if "paper" not in localizers:
        given = [f"--{o.replace('_', '-')}" for o in _PAPER_OPTIONS if getattr(args, o) is not None]
        if given:
            raise ConfigError(
                f"{', '.join(given)} apply to the paper's rules only (add --localizer paper); "
                f"{', '.join(ranking)} use the calibrated configuration (--config)"
            )
    meter_models = (
        ("instantaneous", "interval-averaged")
        if args.meter_model == "both"
        else (args.meter_model,)
    )
    runs = []
    if "paper" in localizers:
        mode = args.mode or paper.DEFAULT_MODE
        runs += [
            dataclasses.replace(spec, meter_model=model)
            for spec in paper_runs(
                detectors,
                args.capture_interval,
                ("window", "stream") if mode == "both" else (mode,),
                threshold=args.threshold,
                drift=args.drift,
                sigma=args.sigma,
                localization_interval=args.localization_interval,
            )
            for model in meter_models
        ]
    if ranking:
        runs += ranking_runs(detectors, args.capture_interval, ranking, meter_models)
    config = None
    if args.config:
        from burstloc.calibrate import Calibration

        config = Calibration.load(args.config)
    cache: DiskCache | bool = False if args.no_cache else DiskCache(args.cache_dir)
    ev = evaluate(
        args.network,
        runs,
        pipes=args.pipes,
        phases=args.phases,
        phase_span=args.phase_span,
        cache=cache,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=not args.quiet,
        config=config,
    )
    print(report.format_tables(ev), end="")
    if args.json:
        print(f"wrote {report.write_json(ev, args.json)}")
    if args.csv:
        print(f"wrote {report.write_csv(ev, args.csv)}")
    if args.plot:
        from burstloc import plot

        for path in plot.write_plots(ev, args.plot):
            print(f"wrote {path}")
    return 0


# --- calibrate -----------------------------------------------------------------------------


def add_calibrate_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc calibrate``."""
    from burstloc import calibrate

    parser = subparsers.add_parser(
        "calibrate",
        help="derive detector thresholds from a burst-free baseline (issue 6)",
        description="Per meter and capture interval, thresholds that meet a target false-alarm "
        "rate on the network's steady state plus the sensor noise model; written as a named "
        "configuration that `evaluate --config` accepts.",
    )
    parser.add_argument("network", help="EPANET INP file")
    parser.add_argument("--out", required=True, help="configuration file to write (JSON)")
    parser.add_argument(
        "--capture-interval",
        type=float,
        nargs="+",
        default=list(calibrate.DEFAULT_CAPTURE_INTERVALS),
        metavar="S",
    )
    parser.add_argument(
        "--noise",
        type=float,
        default=calibrate.DEFAULT_NOISE_SIGMA,
        metavar="SIGMA",
        help="sensor noise standard deviation, m",
    )
    parser.add_argument(
        "--false-alarm-rate",
        type=float,
        default=calibrate.DEFAULT_FALSE_ALARM_RATE,
        metavar="R",
        help="target false alarms per meter per hour",
    )
    parser.add_argument("--meters", nargs="+", default=None, help="metered junctions (default all)")
    parser.add_argument("--name", default=None, help="the configuration's name")
    parser.set_defaults(handler=run_calibrate)
    return parser


def run_calibrate(args: argparse.Namespace) -> int:
    """Handle ``burstloc calibrate``."""
    from burstloc.calibrate import calibrate

    config = calibrate(
        args.network,
        capture_intervals=args.capture_interval,
        noise_sigma=args.noise,
        false_alarm_rate=args.false_alarm_rate,
        meters=args.meters,
        name=args.name,
    )
    print(f"wrote {config.save(args.out)}")
    return 0


# --- monitor -------------------------------------------------------------------------------


def add_monitor_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc monitor``."""
    from burstloc.decide import RANKING_LOCALIZERS
    from burstloc.ranking import METER_MODELS

    parser = subparsers.add_parser(
        "monitor",
        help="the live loop: readings in (CSV), one JSON line per located burst out",
        description=(
            "Read pressure readings 'timestamp,meter,value' (a file, or - for stdin) in "
            "arrival order, assemble complete time steps, run the calibrated detector bank of "
            "--config and a ranking localizer, and print one JSON line per located burst: the "
            "decision time, the first alarm and the three best pipes."
        ),
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument(
        "--config", required=True, metavar="PATH", help="`burstloc calibrate` output"
    )
    parser.add_argument(
        "--capture-interval",
        type=float,
        required=True,
        metavar="S",
        help="seconds between readings",
    )
    parser.add_argument("--readings", default="-", metavar="FILE", help="CSV file (default: stdin)")
    parser.add_argument("--detector", choices=("cusum", "shewhart"), default="cusum")
    parser.add_argument("--localizer", choices=RANKING_LOCALIZERS, default="fused")
    parser.add_argument("--meter-model", choices=METER_MODELS, default="instantaneous")
    parser.add_argument(
        "--timeout", type=int, default=3, metavar="N", help="steps to wait for a late reading"
    )
    parser.add_argument(
        "--missing", choices=("skip", "hold"), default="hold", help="policy for incomplete steps"
    )
    parser.set_defaults(handler=run_monitor)
    return parser


def run_monitor(args: argparse.Namespace) -> int:
    """Handle ``burstloc monitor``."""
    import json

    from burstloc.calibrate import Calibration
    from burstloc.monitor import BurstMonitor, monitor_readings, parse_readings

    config = Calibration.load(args.config)
    monitor = BurstMonitor(
        args.network,
        config,
        capture_interval=args.capture_interval,
        detector=args.detector,
        localizer=args.localizer,
        meter_model=args.meter_model,
    )
    try:
        source = sys.stdin if args.readings == "-" else open(args.readings)  # noqa: SIM115
    except OSError as exc:
        raise InputError(f"cannot read readings {args.readings!r}: {exc.strerror}") from exc
    try:
        readings = parse_readings(source)
        options = {
            "period": args.capture_interval,
            "timeout": args.timeout,
            "missing": args.missing,
        }
        for decided in monitor_readings(monitor, readings, **options):
            print(json.dumps(decided.to_json()), flush=True)
    finally:
        if source is not sys.stdin:
            source.close()
    return 0


# --- study ---------------------------------------------------------------------------------


def add_study_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc study``."""
    from burstloc.study import add_study_arguments

    parser = subparsers.add_parser(
        "study",
        help="robustness study: accuracy over a one-factor-at-a-time grid (issue 6)",
        description="Simulate (cached) and score a grid of noise, meter coverage, burst size and "
        "friction around the defaults; write report.md, results.json and PNG plots.",
    )
    add_study_arguments(parser)
    parser.set_defaults(handler=run_study)
    return parser


def run_study(args: argparse.Namespace) -> int:
    """Handle ``burstloc study``."""
    from burstloc.study import run_study_command

    return run_study_command(args)


# --- wiring --------------------------------------------------------------------------------


def build_parser() -> argparse.ArgumentParser:
    """Return the ``burstloc`` parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="burstloc", description="Real-time pipe-burst localization from pressure transients."
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    add_simulate_parser(subparsers)
    add_evaluate_parser(subparsers)
    add_calibrate_parser(subparsers)
    add_monitor_parser(subparsers)
    add_study_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except (ConfigError, InputError, NetworkError, SimulationError) as exc:
        print(f"burstloc: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
