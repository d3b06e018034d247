"""Options several subcommands share: where simulations run and whether they are cached."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from burstloc.exceptions import ConfigError

if TYPE_CHECKING:
    from burstloc.network import NetworkSource
    from burstloc.sim.scenarios.cache import DiskCache

__all__ = [
    "DefaultsFormatter",
    "add_meters_file_option",
    "add_min_pipe_length_option",
    "add_run_options",
    "add_solver_option",
    "add_time_step_option",
    "cache_of",
    "check_run_options",
    "meters_of",
    "time_step_of",
]


class DefaultsFormatter(argparse.HelpFormatter):
    """``--help`` with every option's default: ``(default: X)`` after its help, unless the help
    already says it, or the default is ``None`` or ``False`` (none, or a flag)."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default = action.default
        if (
            not action.option_strings
            or default is None
            or default is False
            or default == []
            or default is argparse.SUPPRESS
            or "default" in text
        ):
            return action.help
        return f"{text} (default: %(default)s)" if text else "default: %(default)s"


def add_run_options(parser: argparse.ArgumentParser, *, cache: bool = True) -> None:
    """``--workers``, ``--scheduler``, ``--quiet`` and (with ``cache``) ``--cache-dir`` and
    ``--no-cache``."""
    parser.add_argument("--workers", type=int, default=None, metavar="N", help="local processes")
    parser.add_argument("--scheduler", default=None, metavar="ADDR", help="Dask scheduler")
    if cache:
        parser.add_argument("--cache-dir", default=None, metavar="DIR")
        parser.add_argument("--no-cache", action="store_true", help="simulate; store nothing")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def add_meters_file_option(parser: argparse.ArgumentParser) -> None:
    """``--meters-file FILE``: the meters a ``burstloc place`` meter file names."""
    parser.add_argument(
        "--meters-file",
        default=None,
        metavar="FILE",
        help="meters from a meter file written by `burstloc place` (format burstloc-meters/1); "
        "refused if it was made for another network",
    )


def add_min_pipe_length_option(parser: argparse.ArgumentParser) -> None:
    """``--min-pipe-length M``: simulate the transient-ready model (:mod:`burstloc.skeleton`)."""
    parser.add_argument(
        "--min-pipe-length",
        type=float,
        default=None,
        metavar="M",
        help="simulate the network's transient-ready model: pipes shorter than M metres are "
        "lengthened to M (diameter widened to keep their head loss), so TSNet's time step is "
        "at least M / (2 x wave speed) instead of being set by the shortest connector pipe "
        "(default: the network as it is)",
    )


def add_solver_option(parser: argparse.ArgumentParser) -> None:
    """``--solver {vectorized,numpy,tsnet}``: which MOC solver runs the transients."""
    from burstloc.sim.scenarios.scenario import SOLVERS

    parser.add_argument(
        "--solver",
        choices=SOLVERS,
        default=SOLVERS[0],
        help="transient solver: 'vectorized' (default) solves TSNet's model over the whole "
        "network at once in compiled code, the same heads as TSNet's own solver, its time loop "
        "hundreds of times faster; 'numpy' runs the same solver's time loop as NumPy array "
        "operations (the same heads, slower); 'tsnet' runs TSNet's MOCSimulator",
    )


def meters_of(args: argparse.Namespace, network: NetworkSource) -> tuple[str, ...] | None:
    """The meters of ``--meters-file`` for ``network`` (ConfigError: another network or a bad
    file), or ``None`` without the option."""
    if args.meters_file is None:
        return None
    from burstloc.sim.placement.methods import MeterSet

    return MeterSet.load(args.meters_file).check(network)


def cache_of(args: argparse.Namespace) -> DiskCache | bool:
    """The simulation cache the options ask for (``False``: none)."""
    from burstloc.sim.scenarios.cache import DiskCache

    return False if args.no_cache else DiskCache(args.cache_dir)


def check_run_options(args: argparse.Namespace) -> None:
    """Check before any work that ``--scheduler`` is reachable (ConfigError otherwise), even
    when every result will come from the cache."""
    if args.scheduler is not None:
        from burstloc.sim.scenarios.sweep import check_scheduler

        check_scheduler(args.scheduler)


def add_time_step_option(parser: argparse.ArgumentParser) -> None:
    """``--time-step S``: TSNet's requested time step (default: the capture rule)."""
    parser.add_argument(
        "--time-step",
        type=float,
        default=None,
        metavar="S",
        help="TSNet's time step in seconds (default: TSNet's largest stable step, or half the "
        "finest capture interval where TSNet's is coarser)",
    )


def time_step_of(args: argparse.Namespace) -> float | None:
    """``--time-step``, checked: a positive, finite number of seconds (ConfigError otherwise),
    or ``None`` without the option."""
    step = args.time_step
    if step is not None and not (math.isfinite(step) and step > 0):
        raise ConfigError(f"--time-step must be a positive number of seconds, got {step:g}")
    return step
