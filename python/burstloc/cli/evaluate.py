"""``burstloc evaluate``: burst every pipe, localize, score."""

from __future__ import annotations

import argparse
import math
from dataclasses import fields
from typing import TYPE_CHECKING, Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_burst_options,
    add_meters_file_option,
    add_meters_option,
    add_min_pipe_length_option,
    add_noise_option,
    add_run_options,
    add_solver_option,
    add_time_step_option,
    add_wave_speeds_option,
    cache_of,
    check_run_options,
    meters_of,
    run_of,
    scenario_of,
    time_step_of,
    wave_speeds_of,
)
from burstloc.cli._truth import add_truth_options, truth_of
from burstloc.constants import DETECTORS, LOCALIZERS, METER_MODELS
from burstloc.exceptions import ConfigError
from burstloc.experiments.evaluate import DEFAULT_LOCALIZER

if TYPE_CHECKING:
    from burstloc.localize.config import Calibration
    from burstloc.network import Network
    from burstloc.wave_speeds import WaveSpeeds

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc evaluate``."""
    parser = subparsers.add_parser(
        "evaluate",
        help="burst every pipe, localize in real time, score (top-1 / top-3 accuracy)",
        description=(
            "Burst each pipe (simulated once, cached), stream the meters' readings at each "
            "capture interval through the detectors and a localizer, and report accuracy. With "
            "no options: a burst of 5 %% of the network's demand (at most 5 L/s) mid-pipe, the "
            "fused localizer, both detectors x capture "
            "intervals 0.2, 2, 5, 10 s. With --localizer paper: the paper's experiment (its "
            "burst, coefficient 0.02, and Tables I/II parameters), printed beside the paper's "
            "Tables III-V; `--localizer paper fused` shows both on the paper's burst."
        ),
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument(
        "--detector", choices=(*DETECTORS, "both"), default="both", help="default: both"
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
        "bank ('stream'); default: burstloc.experiments.paper.DEFAULT_MODE",
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
        choices=(*METER_MODELS, "both"),
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
    add_burst_options(parser, None)
    add_noise_option(
        parser,
        None,
        "added to every reading of every run; default: the noise the configuration was "
        "calibrated for (each meter's, what the monitor expects) on the ranking localizers' "
        "readings and none on the paper's rules (its experiment is noiseless); 0: noiseless "
        "readings",
    )
    parser.add_argument(
        "--noise-seed",
        type=int,
        default=0,
        metavar="N",
        help="seed of the noise (default 0): the same seed gives the same readings",
    )
    add_min_pipe_length_option(parser)
    add_solver_option(parser)
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
        "--paper-tables",
        action="store_true",
        help="frame the tables as the paper's Tables III-V, with its figures beside ours, on any "
        "network (default: on the paper's network, networks/paper15.inp, only)",
    )
    parser.add_argument(
        "--plot",
        default=None,
        metavar="DIR",
        help="write PNGs: per run, a map of every burst's true and named pipe, and the meters' "
        "traces with their alarms for the first pipe of --pipes",
    )
    add_meters_option(
        parser,
        "default: the configuration's with --config, else every junction (the ranking "
        "localizers; the paper's rules read every junction)",
    )
    add_meters_file_option(parser)
    add_time_step_option(parser)
    parser.add_argument(
        "--events",
        action="store_true",
        help="also simulate non-burst events (every valve closed and opened, every pump "
        "tripped and started, demand steps at the largest consumers) and classify every "
        "alarm as burst, other event or unsure: a confusion table per type and capture interval",
    )
    parser.add_argument(
        "--classifier-network",
        default=None,
        metavar="NETWORK.inp",
        help="--events: calibrate the classifier on this network's bursts (default: NETWORK)",
    )
    parser.add_argument(
        "--normal-hours",
        type=float,
        default=24.0,
        metavar="H",
        help="--events: hours of normal operation (diurnal demand, noise 0.01 m) through the "
        "monitor per capture interval, to count false burst reports (default 24; 0: none)",
    )
    parser.add_argument(
        "--classifier-out",
        default=None,
        metavar="PATH",
        help="--events: write the calibrated classifier (for burstloc monitor --classify)",
    )
    add_wave_speeds_option(
        parser,
        "The bursts are simulated so, and a calibration made here times paths so; a --config "
        "keeps the speeds it was calibrated with.",
    )
    add_truth_options(parser)
    add_run_options(parser)
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc evaluate``."""
    from burstloc.experiments import report
    from burstloc.experiments.evaluate import evaluate
    from burstloc.experiments.runs import plan_runs
    from burstloc.network import read_network

    for path in (args.json, args.csv, args.classifier_out):
        if path:
            check_output(path)
    if args.plot:
        check_output(args.plot, directory=True)
    check_run_options(args)
    time_step = time_step_of(args)
    runs = plan_runs(
        localizers=args.localizer,
        detectors=DETECTORS if args.detector == "both" else (args.detector,),
        capture_intervals=args.capture_interval,
        meter_models=METER_MODELS if args.meter_model == "both" else (args.meter_model,),
        mode=args.mode,
        threshold=args.threshold,
        drift=args.drift,
        sigma=args.sigma,
        localization_interval=args.localization_interval,
    )
    network = read_network(args.network)
    meters = meters_of(args, network)
    config = None
    if args.config:
        from burstloc.localize.config import Calibration

        config = Calibration.load(args.config)
        if meters is None or set(meters) == set(config.meters):
            meters = config.meters  # the meters it was calibrated for, in its order
    cache = cache_of(args)
    # the paper's experiment keeps the paper's burst; every other run a utility's (a share of
    # the demand)
    scenario, flow = scenario_of(args, paper="paper" in args.localizer)
    if args.noise is not None and not (math.isfinite(args.noise) and args.noise >= 0):
        raise ConfigError(f"--noise must be a number of metres >= 0, got {args.noise}")
    if args.noise_seed < 0:
        raise ConfigError(f"--noise-seed must be >= 0, got {args.noise_seed}")
    truth = truth_of(args)
    if truth is not None:
        print(f"truth perturbed: {truth.describe()}; the localizers keep the model", flush=True)
    wave_speeds = wave_speeds_of(args, network)
    _say_wave_speeds(wave_speeds, config)
    ev = evaluate(
        network,
        runs,
        pipes=args.pipes,
        phases=args.phases,
        phase_span=args.phase_span,
        scenario=scenario,
        cache=cache,
        **run_of(args),
        config=config,
        meters=meters,
        time_step=time_step,
        noise=args.noise,
        noise_seed=args.noise_seed,
        # each burst scored as it arrives unless the plots or the classifier read its heads
        keep_heads=bool(args.plot or args.events),
        burst_flow=flow,
        truth=truth,
        wave_speeds=wave_speeds,
    )
    print(_flows_line(ev.scenario))
    print(report.format_tables(ev, True if args.paper_tables else None), end="")
    if args.events:
        _events(args, network, ev, cache)
    if args.json:
        print(f"wrote {report.write_json(ev, args.json)}")
    if args.csv:
        print(f"wrote {report.write_csv(ev, args.csv)}")
    if args.plot:
        from burstloc.experiments import plot

        for path in plot.write_plots(ev, args.plot):
            print(f"wrote {path}")
    return 0


def _say_wave_speeds(wave_speeds: WaveSpeeds | None, config: Calibration | None) -> None:
    """Say when the simulated pipes' wave speeds are not those the configuration's localizers
    time paths with."""
    if config is None:
        return
    calibrated = config.provenance.get("wave_speeds")
    given = wave_speeds.to_json() if wave_speeds else None
    if calibrated != given:
        print(
            "the bursts are simulated with "
            + ("the --wave-speeds file's" if given else "one wave speed")
            + "; the localizers keep the configuration's "
            + ("own wave speeds per pipe" if calibrated else "one wave speed"),
            flush=True,
        )


def _flows_line(scenario: dict[str, Any]) -> str:
    """The bursts' nominal flows (L/s) and how they were chosen, in one line."""
    ordered = sorted(scenario["burst_flows_lps"].values())
    sizing = scenario.get("burst_sizing")
    chosen = f"; sized as {sizing}" if sizing and "%" in sizing else ""
    return (
        f"the bursts drew {ordered[0]:.3g}-{ordered[-1]:.3g} L/s (median "
        f"{ordered[len(ordered) // 2]:.3g}) at their burst points' pressure before they "
        f"opened{chosen}"
    )


def _events(args: argparse.Namespace, network: Network, ev: Any, cache: Any) -> None:
    """Classify the evaluation's bursts and the default events; add the table to ``ev``."""
    from burstloc.experiments.specificity import evaluate_events
    from burstloc.localize.classify import ClassifierConfig
    from burstloc.network import read_network
    from burstloc.sim.scenarios.scenario import BurstScenario, burst_scenarios
    from burstloc.sim.transient.time_step import with_capture_time_step
    from burstloc.sim.transient.tsnet import simulate_many

    intervals = sorted({r.spec.capture_interval for r in ev.runs})
    duration = float(ev.scenario["duration"])
    calibration = network
    if args.classifier_network and args.classifier_network != args.network:
        calibration = read_network(args.classifier_network)
        # how the bursts were simulated, less what belongs to this network's pipes
        shared = {f.name for f in fields(BurstScenario)} - {
            "network",
            "pipe",
            "truth",
            "wave_speeds",
        }
        how = {k: v for k, v in ev.scenario.items() if k in shared}
        scenarios = with_capture_time_step(
            burst_scenarios(calibration, None, **how), min(intervals)
        )
        report = simulate_many(scenarios, cache=cache, workers=args.workers, progress=False)
        cal_bursts = {s.pipe: r for s, r in report.succeeded()}
    else:
        cal_bursts = dict(ev.results)
    spec, config = evaluate_events(
        network,
        dict(ev.results),
        intervals,
        calibration_network=calibration,
        calibration_bursts=cal_bursts,
        duration=duration,
        setup=ev.setup,
        normal_hours=args.normal_hours,
        cache=cache,
        progress=not args.quiet,
        solver=args.solver,
    )
    ev.specificity = spec.to_json()
    print(spec.format_table(), end="")
    if args.classifier_out:
        print(f"wrote {ClassifierConfig.save(config, args.classifier_out)}")
