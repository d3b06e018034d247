"""``burstloc evaluate``'s and ``simulate``'s options for a perturbed truth
(:mod:`burstloc.sim.scenarios.perturb`)."""

from __future__ import annotations

import argparse
from typing import Any

from burstloc.sim.scenarios.perturb import TruthPerturbation

__all__ = ["add_truth_options", "truth_of"]


def add_truth_options(parser: argparse.ArgumentParser, description: str | None = None) -> None:
    """Add the ``--truth-*`` options: the truth the meters hear simulated on a perturbed copy
    of the network, while the localizers keep the model (``description``: the group's, for a
    command other than ``evaluate``)."""
    group = parser.add_argument_group(
        "perturbed truth",
        description
        or "simulate what the meters hear on a perturbed copy of the network while the "
        "localizers keep the model (all off by default): does the 95 % search region keep its "
        "coverage?",
    )
    group.add_argument(
        "--truth-wave-speed-spread",
        type=float,
        default=0.0,
        metavar="F",
        help="each pipe's wave speed in the truth uniform in a(1 ± F), a the model's (e.g. 0.15)",
    )
    group.add_argument(
        "--truth-roughness-spread",
        type=float,
        default=0.0,
        metavar="F",
        help="each pipe's roughness in the truth multiplied by U(1 - F, 1 + F) (e.g. 0.3)",
    )
    group.add_argument(
        "--truth-clock-offset",
        type=float,
        default=0.0,
        metavar="S",
        help="each meter's clock off by a draw of N(0, S²) seconds (e.g. 0.005)",
    )
    group.add_argument(
        "--truth-silent-meter",
        type=float,
        default=None,
        metavar="S",
        help="the metered junction nearest each burst sends nothing from S s after the burst "
        "starts (ranking localizers)",
    )
    group.add_argument(
        "--truth-seed",
        type=int,
        default=0,
        metavar="N",
        help="seed of every draw of the truth (default 0): the same seed gives the same truth",
    )


def truth_of(args: Any) -> TruthPerturbation | None:
    """The perturbation the options ask for, or ``None`` when they ask for none.

    Raises:
        ConfigError: a bad value, naming its option.
    """
    truth = TruthPerturbation(
        wave_speed_spread=args.truth_wave_speed_spread,
        roughness_spread=args.truth_roughness_spread,
        clock_offset=args.truth_clock_offset,
        silent_meter=args.truth_silent_meter,
        seed=args.truth_seed,
    )
    return truth if truth.active else None
