"""``burstloc place``: choose the junctions that carry meters; write a meter file."""

from __future__ import annotations

import argparse
from typing import Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_run_options,
    add_wave_speed_option,
    check_run_options,
    run_of,
)

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc place``."""
    from burstloc.sim.placement.methods import PLACEMENT_METHODS
    from burstloc.sim.placement.scaled import DEFAULT_SCALING, SCALE_JUNCTIONS

    parser = subparsers.add_parser(
        "place",
        help="place K meters on a network's junctions; write a meter file",
        description="Choose K junctions for pressure meters from the network model alone (no "
        "burst is simulated). 'arrival' (default): greedy separation of the wave arrival-time "
        "patterns of bursts on different pipes, for the arrival and fused localizers; "
        "'region': the shortest expected search region, the meters that leave the least main "
        "whose arrival pattern is within a capture interval of the burst point's; "
        "'coverage': greedy separation of the steady-state burst signatures. On a network of "
        f"more than {SCALE_JUNCTIONS} junctions, 'arrival' and 'region' choose among "
        f"{DEFAULT_SCALING.candidates} junctions spread over the network and score a seeded "
        "sample of burst points (an approximation, deterministic; smaller networks get the "
        "exact greedy). Prints the meters, "
        "their arrival separation (the share of candidate burst points whose arrival pattern "
        "is at least one capture interval from every other pipe's) and their expected "
        "ambiguous main (the metres of main a search region cannot rule out from arrival "
        "times, averaged over burst points: what 'region' minimises). The meter file "
        "(JSON, format burstloc-meters/1) is accepted by `evaluate`, `calibrate` and `study` "
        "with --meters-file.",
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument("--meters", type=int, required=True, metavar="K", help="how many meters")
    parser.add_argument(
        "--method", choices=PLACEMENT_METHODS, default="arrival", help="default: arrival"
    )
    parser.add_argument(
        "--capture-interval",
        type=float,
        default=0.2,
        metavar="S",
        help="arrival, region: the capture interval the meters will report at (default 0.2 s); "
        "arrival times closer than that count as alike",
    )
    add_wave_speed_option(parser, "arrival, region: the pressure wave speed, m/s")
    parser.add_argument("--out", default=None, metavar="FILE", help="write the meter file")
    parser.add_argument(
        "--compare",
        action="store_true",
        help="also place K meters by every method and evaluate each placement (every pipe "
        "bursts, simulated once and cached; calibrated; arrival and fused localizers at "
        "--capture-interval): top-1 / top-3 and position errors side by side",
    )
    parser.add_argument(
        "--position",
        type=float,
        default=0.5,
        metavar="F",
        help="--compare: where each burst opens along its pipe (fraction, default 0.5)",
    )
    parser.add_argument(
        "--phases", type=int, default=5, metavar="N", help="--compare: clock phases per burst"
    )
    add_run_options(parser, cache=False)
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc place``: print the meters; write the file with ``--out``."""
    from burstloc.network import read_network
    from burstloc.sim.placement.methods import meter_scores, place_meters

    if args.out:
        check_output(args.out)
    if args.compare:
        check_run_options(args)
    network = read_network(args.network)
    timing = {"wave_speed": args.wave_speed, "resolution": args.capture_interval}
    placed = place_meters(network, args.meters, method=args.method, **timing)
    print(
        f"{len(placed.meters)} of {placed.junctions} junctions ({placed.method}): "
        + " ".join(placed.meters)
    )
    told, ambiguous = meter_scores(network, placed.meters, **timing)
    print(
        f"arrival separation at {args.capture_interval:g} s: {100 * told:.0f} % of the candidate "
        "burst points are at least one capture interval from every point of every other pipe"
    )
    print(
        f"expected ambiguous main at {args.capture_interval:g} s: {ambiguous:.0f} m (the main a "
        "search region cannot rule out from arrival times, averaged over burst points)"
    )
    if args.out:
        print(f"wrote {placed.save(args.out)}")
    if args.compare:
        from burstloc.experiments.placements import compare_placements, format_comparison

        rows = compare_placements(
            network,
            args.meters,
            capture_interval=args.capture_interval,
            phases=args.phases,
            position=args.position,
            **run_of(args),
        )
        print(format_comparison(rows), end="")
    return 0
