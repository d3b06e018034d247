"""The ``burstloc`` command line: one module per subcommand, wiring only.

Each subcommand module (:mod:`~burstloc.cli.simulate`, :mod:`~burstloc.cli.evaluate`,
:mod:`~burstloc.cli.calibrate`, :mod:`~burstloc.cli.monitor`, :mod:`~burstloc.cli.study`) has an
``add_parser(subparsers)`` function (its arguments) and a ``run(args)`` handler that calls the
library and prints; :func:`build_parser` registers them. Nothing in the library imports this
package.

Exit status: 0 success, 1 some scenarios failed (reported on stderr), 2 bad input.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from burstloc.cli import calibrate, evaluate, monitor, simulate, study
from burstloc.exceptions import ConfigError, InputError, NetworkError, SimulationError

__all__ = ["build_parser", "main"]

#: The subcommands, in the order ``burstloc --help`` lists them.
SUBCOMMANDS = (simulate, evaluate, calibrate, monitor, study)


def build_parser() -> argparse.ArgumentParser:
    """Return the ``burstloc`` parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="burstloc", description="Real-time pipe-burst localization from pressure transients."
    )
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in SUBCOMMANDS:
        command.add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    args = build_parser().parse_args(argv)
    try:
        return int(args.handler(args))
    except (ConfigError, InputError, NetworkError, SimulationError) as exc:
        print(f"burstloc: error: {exc}", file=sys.stderr)
        return 2
