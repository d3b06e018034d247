"""``burstloc study``: the robustness grid of :mod:`burstloc.experiments.study`."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_run_options,
    add_time_step_option,
    add_wave_speeds_option,
    check_run_options,
    run_of,
    time_step_of,
    wave_speeds_of,
)
from burstloc.constants import (
    CAPTURE_INTERVALS,
    DETECTORS,
    RANKING_LOCALIZERS,
    SCENARIO_DURATION,
    WAVE_SPEED,
)
from burstloc.exceptions import ConfigError
from burstloc.experiments.grid import DEFAULT_LEVELS, DEFAULT_NETWORKS, StudySettings, study_grid
from burstloc.experiments.study import run_study
from burstloc.experiments.study_report import write_study_report as write_report
from burstloc.inp import network_hash
from burstloc.sim.placement.methods import PLACEMENT_METHODS, MeterSet

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc study``."""
    parser = subparsers.add_parser(
        "study",
        help="robustness study: accuracy over a one-factor-at-a-time grid",
        description="Simulate (cached) and score a grid of noise, meter coverage, burst size and "
        "friction around the defaults; write report.md, results.json and PNG plots.",
    )
    parser.add_argument(
        "networks", nargs="*", default=list(DEFAULT_NETWORKS), help="INP files (first: varied)"
    )
    parser.add_argument("--out", type=Path, default=Path("study"), help="report directory")
    parser.add_argument(
        "--capture-interval", type=float, nargs="+", default=list(CAPTURE_INTERVALS), metavar="S"
    )
    parser.add_argument("--detector", nargs="+", default=list(DETECTORS), choices=DETECTORS)
    parser.add_argument(
        "--localizer", nargs="+", default=list(RANKING_LOCALIZERS), choices=RANKING_LOCALIZERS
    )
    parser.add_argument("--phases", type=int, default=5, help="capture-clock phases per burst")
    parser.add_argument(
        "--duration", type=float, default=SCENARIO_DURATION, help="simulated seconds"
    )
    parser.add_argument(
        "--factors",
        nargs="*",
        default=list(DEFAULT_LEVELS),
        help=f"factors varied on the first network (default: all of {list(DEFAULT_LEVELS)})",
    )
    parser.add_argument("--pipes", nargs="+", default=None, help="only these pipes")
    add_time_step_option(parser)
    parser.add_argument(
        "--placement",
        choices=PLACEMENT_METHODS,
        default="coverage",
        help="how meters are placed for a meter fraction below 1 (default: coverage)",
    )
    parser.add_argument(
        "--meters-file",
        nargs="+",
        default=[],
        metavar="FILE",
        help="meter files from `burstloc place`: a network with one uses its meters instead of "
        "every junction at full coverage; a file for none of the networks is refused",
    )
    add_wave_speeds_option(
        parser,
        f"The study runs the other pipes at {WAVE_SPEED:g} m/s. On every network of the study "
        "(a pipe one of them does not have is refused): the bursts are simulated, the meters "
        "placed and the localizers calibrated with them; results.json records them.",
    )
    add_run_options(parser, cache=False)
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc study``: run the grid; print and write the report.

    Raises:
        ConfigError: an unknown factor or bad settings.
    """
    check_output(args.out, directory=True)
    check_run_options(args)
    unknown = [f for f in args.factors if f not in DEFAULT_LEVELS]
    if unknown:
        raise ConfigError(f"unknown factor(s) {unknown}; known: {list(DEFAULT_LEVELS)}")
    meter_sets = tuple(MeterSet.load(path) for path in args.meters_file)
    for path, meter_set in zip(args.meters_file, meter_sets, strict=True):
        if not any(network_hash(n) == meter_set.network_hash for n in args.networks):
            raise ConfigError(f"meter file {path} is for none of the study's networks")
    settings = StudySettings(
        capture_intervals=tuple(args.capture_interval),
        detectors=tuple(args.detector),
        localizers=tuple(args.localizer),
        phases=args.phases,
        duration=args.duration,
        pipes=tuple(args.pipes) if args.pipes else None,
        time_step=time_step_of(args),
        placement=args.placement,
        meter_sets=meter_sets,
        wave_speeds=wave_speeds_of(args, *args.networks),
    )
    points = study_grid(args.networks, {f: DEFAULT_LEVELS[f] for f in args.factors})
    rows, problems = run_study(points, settings, **run_of(args))
    report = write_report(rows, settings, args.out, problems)
    print(report.read_text())
    print(f"wrote {report}")
    return 1 if problems else 0
