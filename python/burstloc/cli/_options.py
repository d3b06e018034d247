"""Options several subcommands share: the network, numbers, the burst and the sensor noise,
where simulations run and whether they are cached."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, Any

from burstloc.constants import BURST_FLOW, BURST_SHARE, WAVE_SPEED
from burstloc.exceptions import ConfigError, NetworkError

if TYPE_CHECKING:
    from burstloc.experiments.paper import ScenarioConfig
    from burstloc.network import NetworkSource
    from burstloc.sim.scenarios.cache import DiskCache
    from burstloc.sim.signatures.burst_size import BurstFlow
    from burstloc.wave_speeds import WaveSpeeds

__all__ = [
    "DefaultsFormatter",
    "add_burst_options",
    "add_meters_file_option",
    "add_meters_option",
    "add_min_pipe_length_option",
    "add_network_argument",
    "add_noise_option",
    "add_number",
    "add_run_options",
    "add_solver_option",
    "add_time_step_option",
    "add_wave_speed_option",
    "add_wave_speeds_option",
    "burst_size_of",
    "cache_of",
    "check_run_options",
    "meters_of",
    "run_of",
    "scenario_of",
    "time_step_of",
    "wave_speeds_of",
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


Options = argparse.ArgumentParser | argparse._ArgumentGroup
"""Where options are added: a parser or one of its groups."""


def add_network_argument(parser: argparse.ArgumentParser) -> None:
    """The ``NETWORK.inp`` argument: the EPANET INP file (read once, at the command's edge)."""
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")


def add_number(
    parser: Options,
    flag: str,
    default: Any,
    metavar: str,
    help: str | None = None,
    *,
    kind: type[float] | type[int] = float,
    many: bool = False,
) -> None:
    """A number option ``flag`` of type ``kind`` (one or more of them with ``many``)."""
    parser.add_argument(
        flag, type=kind, nargs="+" if many else None, default=default, metavar=metavar, help=help
    )


def add_noise_option(parser: Options, default: float | None, help: str) -> None:
    """``--noise SIGMA``: the meters' Gaussian noise, standard deviation in m (``help`` says
    what it is for in the command)."""
    add_number(parser, "--noise", default, "SIGMA", f"the meters' Gaussian noise, m: {help}")


def add_wave_speed_option(parser: Options, help: str = "pressure wave speed, m/s") -> None:
    """``--wave-speed A``: the pressure wave speed (:data:`burstloc.constants.WAVE_SPEED`)."""
    add_number(parser, "--wave-speed", WAVE_SPEED, "A", help)


def add_wave_speeds_option(parser: Options, help: str) -> None:
    """``--wave-speeds FILE``: pipes (or diameter classes) of their own wave speed
    (:mod:`burstloc.wave_speeds`; :func:`wave_speeds_of` reads it)."""
    parser.add_argument(
        "--wave-speeds",
        default=None,
        metavar="FILE",
        help="pipes of their own pressure wave speed: a CSV 'pipe,wave_speed' (m/s) or a JSON "
        "file of pipes and diameter classes; the other pipes run at --wave-speed. " + help,
    )


def wave_speeds_of(args: argparse.Namespace, *networks: NetworkSource) -> WaveSpeeds | None:
    """The ``--wave-speeds`` file read and checked against each of ``networks`` (``None``
    without it).

    Raises:
        ConfigError: the file cannot be read or is not a wave-speeds file (naming it).
        NetworkError: it names a pipe one of the networks does not have.
    """
    if getattr(args, "wave_speeds", None) is None:
        return None
    from burstloc.network import as_network
    from burstloc.wave_speeds import read_wave_speeds

    speeds = read_wave_speeds(args.wave_speeds)
    for network in networks:
        read = as_network(network)
        try:
            speeds.check(read.model)
        except NetworkError as exc:
            raise NetworkError(f"{exc} ({read.path})") from None
    return speeds


def add_burst_options(parser: Options, position: float | None) -> None:
    """``--position F``, ``--burst-flow L/S``, ``--burst-share PCT`` and ``--burst-coeff C``:
    where each burst opens and its size, as a flow, a share of the network's demand (the
    default: :data:`~burstloc.constants.BURST_SHARE`, at most
    :data:`~burstloc.constants.BURST_FLOW`) or an emitter coefficient (:func:`burst_size_of`
    reads them)."""
    where = (
        "where each burst opens, as a fraction of its pipe's length from the pipe's INP start "
        "node, strictly between 0 and 1"
    )
    if position is None:
        where += " (default 0.5, mid-pipe)"
    add_number(parser, "--position", position, "F", where)
    sizes = parser.add_mutually_exclusive_group()
    sizes.add_argument(
        "--burst-flow",
        type=float,
        default=None,
        metavar="L/S",
        help="size every burst by its flow: each pipe's emitter coefficient draws this many L/s "
        "at its burst point's pressure before it opens (the flow falls as the pressure does). "
        f"Default: {100 * BURST_SHARE:g} %% of the network's demand, at most "
        f"{1000 * BURST_FLOW:g} L/s (2 L/s on L-TOWN), a burst every committed network and "
        "L-TOWN feed with their pressures above zero; the paper's experiment, --localizer "
        "paper, keeps the paper's coefficient 0.02. Printed and recorded either way",
    )
    sizes.add_argument(
        "--burst-share",
        type=float,
        default=None,
        metavar="PCT",
        help="size every burst as this percentage of the network's demand (at the steady "
        "state it opens from) instead",
    )
    sizes.add_argument(
        "--burst-coeff",
        type=float,
        default=None,
        metavar="C",
        help="size every burst by its final emitter coefficient instead, m^3/s/m^0.5 (the "
        "paper's: 0.02, which draws 0.02 x sqrt(pressure head) m^3/s: more than some "
        "networks' whole demand)",
    )


def burst_size_of(
    args: argparse.Namespace, *, paper: bool = False
) -> tuple[float | None, BurstFlow | None]:
    """The bursts' size from ``--burst-coeff``/``--burst-flow``/``--burst-share``:
    ``(coefficient, flow)``, one of them ``None``. Neither given: the default flow
    (:data:`~burstloc.sim.signatures.burst_size.DEFAULT_BURST`), or with ``paper`` (the paper's
    experiment) ``(None, None)``: the scenario's own coefficient.

    Raises:
        ConfigError: a size that is not a positive finite number, a share above 100 %.
    """
    from burstloc.sim.signatures.burst_size import DEFAULT_BURST, BurstFlow

    if args.burst_coeff is not None:
        if not (math.isfinite(args.burst_coeff) and args.burst_coeff > 0):
            raise ConfigError(f"--burst-coeff must be a positive number, got {args.burst_coeff}")
        return args.burst_coeff, None
    if args.burst_flow is not None:
        if not (math.isfinite(args.burst_flow) and args.burst_flow > 0):
            raise ConfigError(
                f"--burst-flow must be a positive number of L/s, got {args.burst_flow}"
            )
        return None, BurstFlow(flow=args.burst_flow / 1000.0)
    share = getattr(args, "burst_share", None)
    if share is not None:
        if not (math.isfinite(share) and 0 < share <= 100):
            raise ConfigError(f"--burst-share must be a percentage in (0, 100], got {share}")
        return None, BurstFlow(share=share / 100.0)
    return (None, None) if paper else (None, DEFAULT_BURST)


def scenario_of(
    args: argparse.Namespace, *, paper: bool = False
) -> tuple[ScenarioConfig, BurstFlow | None]:
    """The bursts' scenario from ``--position``, ``--min-pipe-length``, ``--solver`` (where the
    command has them) and the burst size (:func:`burst_size_of`): ``(scenario, flow)``, the
    flow ``None`` where a coefficient sizes the bursts.

    Raises:
        ConfigError: a position outside (0, 1), a bad burst size.
    """
    from dataclasses import replace

    from burstloc.experiments.paper import SCENARIO

    scenario = SCENARIO
    if args.position is not None:
        if not 0.0 < args.position < 1.0:
            raise ConfigError(f"--position must be strictly between 0 and 1, got {args.position}")
        scenario = replace(scenario, position=args.position)
    if args.min_pipe_length is not None:
        scenario = replace(scenario, min_pipe_length=args.min_pipe_length)
    if getattr(args, "solver", None) is not None:
        scenario = replace(scenario, solver=args.solver)
    coeff, flow = burst_size_of(args, paper=paper)
    if coeff is not None:
        scenario = replace(scenario, burst_coeff=coeff)
    return scenario, flow


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


def add_meters_option(parser: Options, help: str) -> None:
    """``--meters IDS|FILE``: the metered junctions, as IDs or a file
    (:func:`burstloc.sim.placement.methods.meter_list`); ``help`` says what the default is."""
    parser.add_argument(
        "--meters",
        nargs="+",
        default=None,
        metavar="IDS|FILE",
        help="the metered junctions: IDs separated by spaces or commas, or a file (a meter file "
        "from `burstloc place`, or a text file of IDs, one or more a line, # comments); " + help,
    )


def meters_of(args: argparse.Namespace, network: NetworkSource) -> tuple[str, ...] | None:
    """The meters of ``--meters IDS|FILE`` or ``--meters-file`` for ``network`` (ConfigError:
    both given, another network, an unknown junction or a bad file), or ``None`` without
    either option."""
    listed = getattr(args, "meters", None)
    path = getattr(args, "meters_file", None)
    if listed is not None and path is not None:
        raise ConfigError("give the meters once: --meters or --meters-file, not both")
    if listed is not None:
        from burstloc.sim.placement.methods import meter_list

        return meter_list(listed, network)
    if path is None:
        return None
    from burstloc.sim.placement.methods import MeterSet

    return MeterSet.load(path).check(network)


def run_of(args: argparse.Namespace) -> dict[str, Any]:
    """The keywords of a sweep the run options ask for: ``workers``, ``scheduler`` and
    ``progress`` (not with ``--quiet``)."""
    return {"workers": args.workers, "scheduler": args.scheduler, "progress": not args.quiet}


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


def add_time_step_option(parser: argparse.ArgumentParser, *, capture_rule: bool = True) -> None:
    """``--time-step S``: TSNet's requested time step (default: TSNet's largest, or with
    ``capture_rule`` half the finest capture interval where TSNet's is coarser)."""
    rule = ", or half the finest capture interval where TSNet's is coarser" if capture_rule else ""
    text = f"TSNet's time step in seconds (default: TSNet's largest stable step{rule})"
    add_number(parser, "--time-step", None, "S", text)


def time_step_of(args: argparse.Namespace) -> float | None:
    """``--time-step``, checked: a positive, finite number of seconds (ConfigError otherwise),
    or ``None`` without the option."""
    step = args.time_step
    if step is not None and not (math.isfinite(step) and step > 0):
        raise ConfigError(f"--time-step must be a positive number of seconds, got {step:g}")
    return step
