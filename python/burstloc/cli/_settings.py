"""``--settings FILE``: every option of a command in one TOML file; the command line overrides it.

A settings file is flat: ``key = value`` lines, a key for each option of the command, named as
the option without its dashes (``capture-interval = 0.2`` for ``--capture-interval 0.2``;
``network`` for the ``NETWORK.inp`` argument). Each value has the option's TOML type: a string,
a number (an integer where the option takes one), ``true``/``false`` for a flag, an array for an
option given several times (``plausible = ["N4=0:80", "N7=0:90"]``). Paths are read as on the
command line (relative to the working directory). An unknown key, a value of the wrong type or
a bad value stops the command with a message naming the file and the key.

The file is applied by :class:`SettingsParser`, the class of every subcommand's parser: before
argparse reads the command line, the file's values become the options' defaults (and the
options they provide are no longer required), so an option given on the command line wins and
an option given nowhere keeps its own default. The parsed namespace carries a
:class:`SettingsSource` (``settings_source``) that reads the file again
(:meth:`SettingsSource.read`) and knows which options the command line gave.

TOML is read with the standard library's :mod:`tomllib` (Python 3.11+) or ``tomli`` (3.10).
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import math
import sys
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from burstloc.exceptions import ConfigError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - exercised on Python 3.10
    import tomli as tomllib

__all__ = ["OPTION", "SettingsParser", "SettingsSource", "SettingsSpec"]

#: The option that names the settings file (its ``dest`` is ``settings``).
OPTION = "--settings"

_FLAGS = (argparse._StoreTrueAction, argparse._StoreFalseAction)
_NOT_SETTINGS = ("help", "settings", "version")


class SettingsSpec:
    """The keys a settings file may hold for one parser, and how each value is read."""

    def __init__(self, parser: argparse.ArgumentParser) -> None:
        self.actions: dict[str, argparse.Action] = {}
        for action in parser._actions:
            if action.dest in _NOT_SETTINGS or action.dest == argparse.SUPPRESS:
                continue
            longs = [s for s in action.option_strings if s.startswith("--")]
            if action.option_strings and not longs:
                continue
            self.actions[longs[0][2:] if longs else action.dest] = action
        #: Each option's default, as the parser has it (before any file is applied).
        self.defaults = {a.dest: a.default for a in self.actions.values()}

    def key(self, dest: str) -> str:
        """The settings key of the option ``dest``."""
        return next(k for k, a in self.actions.items() if a.dest == dest)

    def load(self, path: str | Path) -> dict[str, Any]:
        """The options of the settings file ``path`` (``dest`` → value), checked.

        Raises:
            ConfigError: the file cannot be read or is not TOML, or a key is unknown or its
                value of the wrong type or bad (naming the file and the key).
        """
        try:
            with open(path, "rb") as handle:
                document = tomllib.load(handle)
        except OSError as exc:
            raise ConfigError(f"cannot read settings file {str(path)!r}: {exc.strerror}") from exc
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            raise ConfigError(f"settings file {str(path)!r} is not TOML: {exc}") from None
        return self.check(document, str(path))

    def check(self, document: Mapping[str, Any], source: str) -> dict[str, Any]:
        """``document`` (the file's table) as options (``dest`` → value), checked."""
        values: dict[str, Any] = {}
        for key, value in document.items():
            action = self.actions.get(key)
            if action is None:
                raise ConfigError(f"{source}: {self._unknown(key, value)}")
            try:
                values[action.dest] = _value(action, value)
            except (argparse.ArgumentTypeError, ValueError, TypeError) as exc:
                raise ConfigError(f"{source}: key {key!r}: {exc}") from None
        return values

    def _unknown(self, key: str, value: Any) -> str:
        if isinstance(value, dict):
            return f"[{key}] is a table; a settings file is flat: one 'key = value' per option"
        near = difflib.get_close_matches(key.replace("_", "-"), list(self.actions), n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        return f"unknown key {key!r}{hint}: the keys are the options of the command, " + (
            "without their dashes"
        )


def _kind(value: Any) -> str:
    names = {bool: "a boolean", str: "a string", int: "an integer", float: "a number",
             list: "an array", dict: "a table"}  # fmt: skip
    return names.get(type(value), type(value).__name__)


def _value(action: argparse.Action, value: Any) -> Any:
    """One key's TOML ``value`` as the option ``action`` would hold it."""
    if isinstance(action, _FLAGS):
        if not isinstance(value, bool):
            raise TypeError(f"want true or false, got {_kind(value)}")
        return value if isinstance(action, argparse._StoreTrueAction) else not value
    many = isinstance(action, argparse._AppendAction) or action.nargs in ("+", "*")
    if many:
        if not isinstance(value, list):
            raise TypeError(f"want an array, got {_kind(value)}")
        if action.nargs == "+" and not value:
            raise ValueError("want at least one value, got an empty array")
        return [_one(action, v) for v in value]
    return _one(action, value)


def _one(action: argparse.Action, value: Any) -> Any:
    kind: Any = action.type
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"want a number, got {_kind(value)}")
        if not math.isfinite(value):
            raise ValueError(f"want a finite number, got {value}")
        result: Any = float(value)
    elif kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"want an integer, got {_kind(value)}")
        result = value
    else:
        if not isinstance(value, str):
            raise TypeError(f"want a string, got {_kind(value)}")
        result = value if kind is None else kind(value)
    if action.choices is not None and result not in action.choices:
        choices = ", ".join(repr(c) for c in action.choices)
        raise ValueError(f"want one of {choices}, got {result!r}")
    return result


class SettingsSource:
    """The settings file a command was started with: read again by :meth:`read`."""

    def __init__(self, path: str, spec: SettingsSpec, command_line: frozenset[str]) -> None:
        self.path = path
        self.spec = spec
        #: The options (``dest``) the command line gave: they win over the file, always.
        self.command_line = command_line

    def read(self) -> dict[str, Any]:
        """Every option as the file sets it now (``dest`` → value; an option the file leaves out
        at its default), command-line options left out.

        Raises:
            ConfigError: as :meth:`SettingsSpec.load`.
        """
        values = {**self.spec.defaults, **self.spec.load(self.path)}
        return {k: v for k, v in values.items() if k not in self.command_line}


def _settings_path(argv: Sequence[str]) -> str | None:
    """The value of ``--settings`` in ``argv`` (the last one given), ``None`` without it."""
    found = None
    for k, arg in enumerate(argv):
        if arg == "--":
            break
        if arg == OPTION and k + 1 < len(argv):
            found = argv[k + 1]
        elif arg.startswith(OPTION + "="):
            found = arg[len(OPTION) + 1 :]
    return found


@contextlib.contextmanager
def _provided(actions: Sequence[argparse.Action], values: Mapping[str, Any]) -> Iterator[None]:
    """The parser's ``actions`` with ``values`` (``dest`` → value) as their defaults, none of
    them required (a positional made optional); as they were afterwards."""
    saved = [(a, a.default, a.required, a.nargs) for a in actions if a.dest in values]
    try:
        for action, *_ in saved:
            action.default = values[action.dest]
            action.required = False
            if not action.option_strings and action.nargs is None:
                action.nargs = "?"
        yield
    finally:
        for action, default, required, nargs in saved:
            action.default, action.required, action.nargs = default, required, nargs


class SettingsParser(argparse.ArgumentParser):
    """An :class:`argparse.ArgumentParser` that applies ``--settings FILE`` (module docstring)
    when it has that option; otherwise an ordinary parser."""

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        """Parse ``args`` over the settings file's values (module docstring)."""
        argv = list(sys.argv[1:] if args is None else args)
        path = _settings_path(argv)
        if path is None or not any(a.dest == "settings" for a in self._actions):
            return super().parse_known_args(argv, namespace)
        spec = SettingsSpec(self)
        values = spec.load(path)
        actions = list(spec.actions.values())
        with _provided(actions, dict.fromkeys(spec.defaults)):  # what the command line gives
            given, _ = super().parse_known_args(list(argv), None)
        typed = {a.dest for a in actions if getattr(given, a.dest, None) is not None}
        with _provided(actions, values):
            parsed, extras = super().parse_known_args(argv, namespace)
        for action in actions:  # an option given several times replaces the file's list
            if isinstance(action, argparse._AppendAction) and action.dest in typed:
                setattr(parsed, action.dest, getattr(given, action.dest))
        parsed.settings_source = SettingsSource(path, spec, frozenset(typed))
        return parsed, extras
