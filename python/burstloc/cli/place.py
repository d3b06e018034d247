"""``burstloc place``: choose the junctions that carry meters; write a meter file."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING, Any

from burstloc._atomic import check_output
from burstloc.cli._options import (
    add_run_options,
    add_wave_speed_option,
    add_wave_speeds_option,
    check_run_options,
    run_of,
    wave_speeds_of,
)
from burstloc.constants import SEARCHABLE
from burstloc.exceptions import ConfigError

if TYPE_CHECKING:
    from collections.abc import Sequence

    from burstloc.network import Network
    from burstloc.sim.placement.methods import MeterScores
    from burstloc.wave_speeds import WaveSpeeds

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc place``."""
    from burstloc.sim.placement.methods import PLACEMENT_METHODS
    from burstloc.sim.placement.scaled import DEFAULT_SCALING, SCALE_JUNCTIONS

    parser = subparsers.add_parser(
        "place",
        help="place K meters on a network's junctions (or add K to the meters it has, or "
        "score a set); write a meter file",
        description="Choose K junctions for pressure meters from the network model alone (no "
        "burst is simulated). 'arrival' (default): greedy separation of the wave arrival-time "
        "patterns of bursts on different pipes, for the arrival and fused localizers; "
        "'region' (default with --keep): the shortest expected search region, the meters "
        "that leave the least main whose arrival pattern is within a capture interval of the "
        "burst point's; 'coverage': greedy separation of the steady-state burst signatures. "
        "With --keep the meters a network has stay and K more are added to them. On a network "
        f"of more than {SCALE_JUNCTIONS} junctions, 'arrival' and 'region' choose among "
        f"{DEFAULT_SCALING.candidates} junctions spread over the network (the kept meters among "
        "them) and score a seeded sample of burst points (an approximation, deterministic; "
        "smaller networks get the exact greedy). Prints the meters and their expected "
        "ambiguous main (the metres of main a search region cannot rule out from arrival "
        "times, over burst points weighted by pipe length: what 'region' minimises), its "
        "median over the bursts and the share of bursts it leaves at most 1 km to search. "
        "--score rates a given set on the same measures and ranks its meters by what each "
        "adds. Arrival times are path lengths over --wave-speed, or with --wave-speeds each "
        "pipe's travel at its own speed. The meter file (JSON, format burstloc-meters/1) is "
        "accepted by `evaluate`, `calibrate`, `simulate` and `study` (--meters-file, or "
        "--meters FILE).",
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument(
        "--meters",
        type=int,
        default=None,
        metavar="K",
        help="how many meters to place (with --keep: how many to add)",
    )
    parser.add_argument(
        "--keep",
        nargs="+",
        default=None,
        metavar="IDS|FILE",
        help="the meters the network has (junction IDs, separated by spaces or commas, or a "
        "file: a meter file or a text file of IDs): kept, and --meters K more added",
    )
    parser.add_argument(
        "--score",
        nargs="+",
        default=None,
        metavar="IDS|FILE",
        help="rate this meter set (IDs or a file, as --keep) instead of placing: its expected "
        "ambiguous main, and each meter's contribution (how much longer the search is "
        "without it), least first",
    )
    parser.add_argument(
        "--method",
        choices=PLACEMENT_METHODS,
        default=None,
        help="default: arrival; with --keep: region",
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
    add_wave_speeds_option(
        parser,
        "The arrival and region methods and the scores time each path at its pipes' speeds (a "
        "pipe at 400 m/s takes three times as long as at 1200); the meter file records them; "
        "--compare also simulates the bursts and calibrates with them.",
    )
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
    from burstloc.sim.placement.methods import meter_list, place_meters

    if args.score is not None:
        for option, value in [("--meters", args.meters), ("--keep", args.keep)]:
            if value is not None:
                raise ConfigError(f"--score rates a given set: {option} does not apply")
        if args.out or args.compare:
            raise ConfigError("--score rates a given set: --out and --compare do not apply")
        network = read_network(args.network)
        wave_speeds = _wave_speeds(args, network)
        return _score(args, network, meter_list(args.score, network), wave_speeds)
    if args.meters is None:
        raise ConfigError("place needs --meters K (how many meters to place or add), or --score")
    if args.out:
        check_output(args.out)
    if args.compare:
        if args.keep is not None:
            raise ConfigError("--compare places from scratch: it does not take --keep")
        check_run_options(args)
    network = read_network(args.network)
    wave_speeds = _wave_speeds(args, network)
    keep = () if args.keep is None else meter_list(args.keep, network)
    method = args.method or ("region" if keep else "arrival")
    placed = place_meters(
        network,
        args.meters,
        method=method,
        wave_speed=args.wave_speed,
        resolution=args.capture_interval,
        keep=keep,
        wave_speeds=wave_speeds,
    )
    if keep:
        added = [m for m in placed.meters if m not in set(keep)]
        print(
            f"{len(placed.meters)} of {placed.junctions} junctions ({placed.method}): the "
            f"{len(keep)} kept and {len(added)} added: " + " ".join(added)
        )
        before = _scores(args, network, keep, wave_speeds)
        after = _scores(args, network, placed.meters, wave_speeds)
        print(_scores_line(f"the {len(keep)} kept", before))
        print(_scores_line(f"with the {len(added)} added", after))
        gain = before.ambiguous - after.ambiguous
        share = 100 * gain / before.ambiguous if before.ambiguous > 0 else 0.0
        print(
            f"the {len(added)} added rule out {gain:.0f} m ({share:.0f} %) of the expected "
            "ambiguous main (a model measure; `evaluate --meters` measures the search regions)"
        )
    else:
        print(
            f"{len(placed.meters)} of {placed.junctions} junctions ({placed.method}): "
            + " ".join(placed.meters)
        )
        print(_scores_line("the meters", _scores(args, network, placed.meters, wave_speeds)))
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
            wave_speeds=wave_speeds,
            wave_speed=args.wave_speed,
        )
        print(format_comparison(rows), end="")
    return 0


def _wave_speeds(args: argparse.Namespace, network: Network) -> WaveSpeeds | None:
    """The ``--wave-speeds`` file checked against ``network`` (:func:`wave_speeds_of`), said
    in one line when given."""
    wave_speeds = wave_speeds_of(args, network)
    if wave_speeds is not None:
        print(
            f"travel times from {args.wave_speeds}: "
            + wave_speeds.describe(network.model, args.wave_speed)
        )
    return wave_speeds


def _scores(
    args: argparse.Namespace,
    network: Network,
    meters: Sequence[str],
    wave_speeds: WaveSpeeds | None,
    *,
    each: bool = False,
) -> MeterScores:
    """:func:`~burstloc.sim.placement.methods.score_meters` of ``meters`` at the options'
    timing (``--wave-speed``, ``--capture-interval``, the ``--wave-speeds`` file)."""
    from burstloc.sim.placement.methods import score_meters

    return score_meters(
        network,
        meters,
        wave_speed=args.wave_speed,
        resolution=args.capture_interval,
        each=each,
        wave_speeds=wave_speeds,
    )


def _scores_line(what: str, scores: MeterScores) -> str:
    """One line of a meter set's scores."""
    return (
        f"{what}: expected ambiguous main at {scores.resolution:g} s {scores.ambiguous:.0f} m, "
        f"median burst {scores.ambiguity.median:.0f} m, {100 * scores.searchable:.0f} % of "
        f"bursts within {SEARCHABLE / 1000:g} km (the main a search region cannot rule out "
        "from arrival times)"
    )


def _score(
    args: argparse.Namespace,
    network: Network,
    meters: tuple[str, ...],
    wave_speeds: WaveSpeeds | None,
) -> int:
    """``place --score``: the set's scores and its meters ranked by what each adds."""
    scores = _scores(args, network, meters, wave_speeds, each=True)
    print(_scores_line(f"{len(meters)} meters", scores))
    print("each meter's contribution: the expected ambiguous main without it, minus with it")
    ranked = scores.contributions()
    width = max(len(m) for m in meters)
    for rank, (meter, gain) in enumerate(ranked, 1):
        print(f"  {rank:>3}. {meter:<{width}}  +{max(gain, 0.0):.0f} m")
    meter, gain = ranked[0]
    print(f"adds least: {meter} (+{max(gain, 0.0):.0f} m of expected ambiguous main without it)")
    return 0
