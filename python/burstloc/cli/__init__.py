"""The ``burstloc`` command line: one module per subcommand, wiring only.

Each subcommand module (:mod:`~burstloc.cli.simulate`, :mod:`~burstloc.cli.evaluate`,
:mod:`~burstloc.cli.calibrate`, :mod:`~burstloc.cli.monitor`, :mod:`~burstloc.cli.study`) has an
``add_parser(subparsers)`` function (its arguments) and a ``run(args)`` handler that calls the
library and prints; :func:`build_parser` registers them. A subcommand's module is imported only
when its parser is built, and ``burstloc COMMAND ...`` builds only that command's parser, so
``burstloc monitor`` imports neither the simulator nor the experiments. Nothing in the library
imports this package.

Exit status: 0 success, 1 some scenarios failed (reported on stderr), 2 bad input.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from burstloc.exceptions import ConfigError, InputError, NetworkError, SimulationError

__all__ = ["build_parser", "main"]

#: The subcommands (modules of this package), in the order ``burstloc --help`` lists them.
SUBCOMMANDS = ("simulate", "evaluate", "calibrate", "monitor", "study")


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """Return the ``burstloc`` parser with every subcommand (or only the one named ``only``)."""
    parser = argparse.ArgumentParser(
        prog="burstloc", description="Real-time pipe-burst localization from pressure transients."
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in SUBCOMMANDS:
        if only is None or name == only:
            importlib.import_module(f"burstloc.cli.{name}").add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    args_list = list(sys.argv[1:] if argv is None else argv)
    command = args_list[0] if args_list and args_list[0] in SUBCOMMANDS else None
    args = build_parser(command).parse_args(args_list)
    try:
        return int(args.handler(args))
    except (ConfigError, InputError, NetworkError, SimulationError) as exc:
        print(f"burstloc: error: {exc}", file=sys.stderr)
        return 2
