"""The ``burstloc`` command line: one module per subcommand, wiring only.

Each subcommand module (:mod:`~burstloc.cli.simulate`, :mod:`~burstloc.cli.evaluate`,
:mod:`~burstloc.cli.calibrate`, :mod:`~burstloc.cli.monitor`, :mod:`~burstloc.cli.incidents`,
:mod:`~burstloc.cli.study`, :mod:`~burstloc.cli.place`) has an
``add_parser(subparsers)`` function (its arguments) and a ``run(args)`` handler that calls the
library and prints; :func:`build_parser` registers them. A subcommand's module is imported only
when its parser is built, and ``burstloc COMMAND ...`` builds only that command's parser, so
``burstloc monitor`` imports neither the simulator nor the experiments. Nothing in the library
imports this package.

Every output path is checked before any work (:func:`burstloc._atomic.check_output`) and every
file is written atomically, so a failed or interrupted run never replaces a good file.

Exit status, the same for every subcommand: 0 success; 1 simulations failed (every failure on
stderr: ``burstloc: failed: ...``; what succeeded is written); 2 bad input, a bad option or
configuration, an output that cannot be written, or a missing simulator (one
``burstloc: error: ...`` line); 130 interrupted (Ctrl-C:
one ``burstloc: interrupted`` line), 141 stdout closed by the reader (``burstloc ... | head``:
nothing more is printed).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from burstloc.exceptions import (
    ConfigError,
    InputError,
    NetworkError,
    OutputError,
    SimulationError,
    SimulatorMissingError,
)

__all__ = ["build_parser", "main", "run"]

#: The subcommands (modules of this package), in the order ``burstloc --help`` lists them.
SUBCOMMANDS = (
    "simulate",
    "evaluate",
    "calibrate",
    "monitor",
    "incidents",
    "study",
    "place",
    "geojson",
)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """Return the ``burstloc`` parser with every subcommand (or only the one named ``only``)."""
    from burstloc import __version__

    parser = argparse.ArgumentParser(
        prog="burstloc",
        description="Real-time pipe-burst localization from pressure transients. Exit status: "
        "0 done, 1 simulations failed, 2 bad input or options, 130 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"burstloc {__version__}")
    from burstloc.cli._options import DefaultsFormatter
    from burstloc.cli._settings import SettingsParser  # a command's --settings FILE

    subparsers = parser.add_subparsers(
        dest="command", required=True, metavar="COMMAND", parser_class=SettingsParser
    )

    for name in SUBCOMMANDS:
        if only is None or name == only:
            sub = importlib.import_module(f"burstloc.cli.{name}").add_parser(subparsers)
            sub.formatter_class = DefaultsFormatter  # every option's default in --help
            for action in sub._actions:  # an option without help: a line for its default
                if action.help is None and action.option_strings and action.default is not None:
                    action.help = "default: %(default)s"
    return parser


#: Exit status after Ctrl-C (128 + SIGINT) and after the reader closed stdout (128 + SIGPIPE).
INTERRUPTED, CLOSED_STDOUT = 130, 141

#: Exit status when simulations failed (each failure reported on stderr).
FAILED = 1


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status (module docstring)."""
    try:
        args_list = list(sys.argv[1:] if argv is None else argv)
        command = args_list[0] if args_list and args_list[0] in SUBCOMMANDS else None
        args = build_parser(command).parse_args(args_list)
        with warnings.catch_warnings():
            _each_warning_once()
            status = int(args.handler(args))
        sys.stdout.flush()  # a closed stdout is found here, not at interpreter exit
        return status
    except KeyboardInterrupt:
        print("burstloc: interrupted", file=sys.stderr)
        return INTERRUPTED
    except BrokenPipeError:
        _silence_stdout()
        return CLOSED_STDOUT
    except (ConfigError, InputError, NetworkError, SimulatorMissingError, OutputError) as exc:
        print(f"burstloc: error: {exc}", file=sys.stderr)
        return 2
    except SimulationError as exc:  # simulations that ran and failed: as `simulate` reports them
        print(f"burstloc: failed: {exc}", file=sys.stderr)
        return FAILED
    except OSError as exc:  # a file the library did not name: name it here
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"burstloc: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2


def _each_warning_once() -> None:
    """Say each distinct warning (category and text) once per run. WNTR warns each time it reads
    a network (once per candidate position, per split pipe), and Python's "once per place" goes
    blind whenever anything changes the warning filters (every ``catch_warnings`` block empties
    the registries, even for the ``once`` action); so repeats are dropped where warnings are
    shown. Call inside ``catch_warnings``, which puts the previous ``showwarning`` back."""
    said: set[tuple[type[Warning], str]] = set()
    show = warnings.showwarning

    def once(message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
        key = (category, str(message))
        if key not in said:
            said.add(key)
            show(message, category, filename, lineno, file, line)

    warnings.showwarning = once


def run() -> NoReturn:
    """The ``burstloc`` command and ``python -m burstloc``: :func:`main`, then exit with its
    status. After Ctrl-C the process ends at once (``os._exit``) once its streams are flushed:
    the interpreter's exit hooks would still wake the stopped worker pool's manager thread, and
    on Python 3.13 that can print a traceback (a closed wake-up pipe) after
    ``burstloc: interrupted``. Outputs are already safe: files are written atomically."""
    status = main()
    if status == INTERRUPTED:
        for stream in (sys.stdout, sys.stderr):
            with contextlib.suppress(OSError, ValueError):
                stream.flush()
        os._exit(status)
    raise SystemExit(status)


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's last flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass
