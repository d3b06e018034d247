"""``burstloc monitor``: the live loop over a feed of readings."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from burstloc.constants import DETECTORS, METER_MODELS, RANKING_LOCALIZERS
from burstloc.exceptions import InputError

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc monitor``."""
    parser = subparsers.add_parser(
        "monitor",
        help="the live loop: readings in (CSV), one JSON line per located burst out",
        description=(
            "Read pressure readings 'timestamp,meter,value' (a file, or - for stdin) in "
            "arrival order, assemble complete time steps, run the calibrated detector bank of "
            "--config and a ranking localizer built from the localization model stored in it "
            "(no hydraulic model runs), and print one JSON line per located burst: the "
            "decision time, the first alarm and the three best pipes. NETWORK.inp is only "
            "checked against the configuration's SHA-256."
        ),
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument(
        "--config",
        required=True,
        metavar="PATH",
        help="`burstloc calibrate` output (with its localization model)",
    )
    parser.add_argument(
        "--capture-interval",
        type=float,
        required=True,
        metavar="S",
        help="seconds between readings",
    )
    parser.add_argument("--readings", default="-", metavar="FILE", help="CSV file (default: stdin)")
    parser.add_argument("--detector", choices=DETECTORS, default="cusum")
    parser.add_argument("--localizer", choices=RANKING_LOCALIZERS, default="fused")
    parser.add_argument("--meter-model", choices=METER_MODELS, default="instantaneous")
    parser.add_argument(
        "--timeout", type=int, default=3, metavar="N", help="steps to wait for a late reading"
    )
    parser.add_argument(
        "--missing", choices=("skip", "hold"), default="hold", help="policy for incomplete steps"
    )
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc monitor``."""
    import json

    from burstloc.live.monitor import BurstMonitor, monitor_readings, parse_readings
    from burstloc.localize.config import Calibration

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
