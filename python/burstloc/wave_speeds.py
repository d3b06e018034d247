"""Pressure-wave speeds per pipe: what a utility knows of its mains' materials.

A wave runs at about 1 200-1 300 m/s in steel, cast and ductile iron and at 300-500 m/s in PE
and PVC. One speed for every pipe (:data:`burstloc.constants.WAVE_SPEED`, the ``--wave-speed``
option) is the default; a wave-speeds file gives some pipes, or classes of diameter, their own.
The simulation runs each pipe at its speed, and the localizers time each path at its pipes'
speeds (shortest paths weighted by travel time, :func:`burstloc.sim.model.prepare.length_graph`).

Two forms are read (:func:`read_wave_speeds`):

* **CSV**, one pipe per line, ``pipe,wave_speed`` (m/s), as a GIS export gives it (a header line
  naming the columns is allowed; ``#`` starts a comment)::

      pipe,wave_speed
      p12,420
      p13,1250

* **JSON**, pipes by name and classes by diameter (the first class whose ``up_to_mm`` is at
  least the pipe's diameter applies; a pipe named in ``pipes`` takes its own)::

      {"pipes": {"p12": 420},
       "diameters": [{"up_to_mm": 110, "wave_speed": 400}, {"up_to_mm": 300, "wave_speed": 1100}]}

A pipe neither names runs at the run's ``--wave-speed``. Network files have no material field,
so materials come in as the pipes (or diameter classes) that have them.

A base module (no simulator): the monitor reads a localization model built with these speeds,
never the file.
"""

from __future__ import annotations

import csv
import io
import itertools
import math
import os
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from burstloc._validate import FieldError, check_number, read_json, read_text
from burstloc.exceptions import ConfigError, NetworkError

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

__all__ = ["MAX_WAVE_SPEED", "MIN_WAVE_SPEED", "WaveSpeeds", "read_wave_speeds", "stretch_of"]

#: The slowest wave a pipe may be given (m/s): thin plastic mains run at about 200-300 m/s.
MIN_WAVE_SPEED = 50.0
#: The fastest (m/s): water itself carries a wave at about 1 480 m/s.
MAX_WAVE_SPEED = 2_000.0

_MAX_FILE_BYTES = 64 * 1024 * 1024


@dataclass(frozen=True)
class WaveSpeeds:
    """Wave speeds (m/s) of named pipes and of diameter classes; every other pipe runs at the
    run's wave speed.

    Attributes:
        pipes: ``(pipe, speed)`` pairs, sorted by pipe name.
        diameters: ``(up to this diameter in m, speed)`` classes, in increasing diameter.
        source: where they were read from (for messages and the records).

    Raises:
        ConfigError: a speed out of ``[MIN_WAVE_SPEED, MAX_WAVE_SPEED]``, a pipe listed twice or
            diameter classes out of order.
    """

    pipes: tuple[tuple[str, float], ...] = ()
    diameters: tuple[tuple[float, float], ...] = ()
    source: str = ""
    _by_pipe: dict[str, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        by_pipe = dict(self.pipes)
        if len(by_pipe) != len(self.pipes):
            counts = Counter(p for p, _ in self.pipes)
            twice = sorted(p for p, n in counts.items() if n > 1)
            raise ConfigError(f"wave speeds{self._where}: pipe(s) listed twice: {twice[:5]}")
        object.__setattr__(self, "_by_pipe", by_pipe)
        for name, speed in self.pipes:
            self._checked(speed, f"pipe {name!r}")
        bounds = [d for d, _ in self.diameters]
        if any(b <= a for a, b in itertools.pairwise(bounds)):
            raise ConfigError(f"wave speeds{self._where}: diameter classes must increase")
        for diameter, speed in self.diameters:
            self._checked(diameter, "a diameter class's bound", low=0.0, high=100.0)
            self._checked(speed, f"diameters up to {1000 * diameter:g} mm")
        object.__setattr__(self, "pipes", tuple(sorted(self.pipes)))

    @property
    def _where(self) -> str:
        return f" ({self.source})" if self.source else ""

    def _checked(
        self, value: float, what: str, low: float = MIN_WAVE_SPEED, high: float = MAX_WAVE_SPEED
    ) -> float:
        try:
            return check_number(value, what, low=low, high=high)
        except FieldError as exc:
            raise ConfigError(f"wave speeds{self._where}: {exc}") from None

    def __bool__(self) -> bool:
        """Whether any pipe or class has a speed of its own."""
        return bool(self.pipes or self.diameters)

    def speed(self, pipe: str, diameter: float, default: float) -> float:
        """The wave speed (m/s) of ``pipe`` of ``diameter`` (m); ``default`` when neither its
        name nor a diameter class gives one."""
        own = self._by_pipe.get(pipe)
        if own is not None:
            return own
        for bound, speed in self.diameters:
            if diameter <= bound:
                return speed
        return default

    def check(self, wn: WaterNetworkModel) -> None:
        """Refuse speeds for pipes ``wn`` does not have.

        Raises:
            NetworkError: the file names a pipe the network does not have.
        """
        pipes = set(wn.pipe_name_list)
        unknown = sorted(p for p in self._by_pipe if p not in pipes)
        if unknown:
            raise NetworkError(
                f"wave speeds{self._where} name {len(unknown)} pipe(s) the network does not "
                f"have: {unknown[:5]}"
            )

    def of(self, wn: WaterNetworkModel, default: float) -> dict[str, float]:
        """Every pipe's wave speed (m/s) in ``wn``, ``default`` where none is given
        (:meth:`check`'s errors)."""
        self.check(wn)
        return {
            p: self.speed(p, float(wn.get_link(p).diameter), default) for p in wn.pipe_name_list
        }

    def differing(self, wn: WaterNetworkModel, default: float) -> dict[str, float]:
        """The speeds (m/s) of the pipes of ``wn`` that do not run at ``default``
        (:meth:`check`'s errors)."""
        return {p: a for p, a in self.of(wn, default).items() if a != default}

    def describe(self, wn: WaterNetworkModel, default: float) -> str:
        """``"3 of 25 pipes at their own wave speed (400-600 m/s), the others at 1200 m/s"``:
        what :meth:`differing` finds on ``wn``, in words (:meth:`check`'s errors)."""
        own = self.differing(wn, default)
        low, high = min(own.values(), default=default), max(own.values(), default=default)
        speeds = "" if not own else f" ({low:g} m/s)" if low == high else f" ({low:g}-{high:g} m/s)"
        return (
            f"{len(own)} of {wn.num_pipes} pipes at their own wave speed{speeds}, the others "
            f"at {default:g} m/s"
        )

    def stretch(self, wn: WaterNetworkModel, wave_speed: float) -> dict[str, float]:
        """Per pipe of ``wn`` whose speed is not ``wave_speed``, the metres of wave travel at
        ``wave_speed`` that one metre of it takes (``wave_speed / its speed``): path lengths
        weighted so are travel times times ``wave_speed`` (:meth:`check`'s errors)."""
        return {p: wave_speed / a for p, a in self.differing(wn, wave_speed).items()}

    def to_json(self) -> dict[str, Any]:
        """``{"pipes": {name: m/s}, "diameters": [{"up_to_mm", "wave_speed"}]}``, the JSON form
        :func:`read_wave_speeds` reads."""
        return {
            "pipes": dict(self.pipes),
            "diameters": [
                {"up_to_mm": round(1000 * d, 6), "wave_speed": s} for d, s in self.diameters
            ],
        }

    @classmethod
    def from_json(cls, data: Any, source: str = "") -> WaveSpeeds:
        """Read the JSON form (module docstring).

        Raises:
            ConfigError: not that form, naming the field.
        """
        where = f"wave speeds {source}".rstrip()
        if not isinstance(data, Mapping):
            raise ConfigError(f"{where}: must be a JSON object with 'pipes' and/or 'diameters'")
        extra = sorted(set(data) - {"pipes", "diameters"})
        if extra:
            raise ConfigError(f"{where}: unknown key(s) {extra} (expected 'pipes', 'diameters')")
        pipes = data.get("pipes", {})
        if not isinstance(pipes, Mapping):
            raise ConfigError(f"{where}: 'pipes' must map pipe names to m/s")
        named = tuple((str(p), _checked_at(where, v, f"pipes.{p}")) for p, v in pipes.items())
        classes = data.get("diameters", [])
        if not isinstance(classes, list):
            raise ConfigError(f"{where}: 'diameters' must be a list of classes")
        bounds = []
        for i, entry in enumerate(classes):
            if not isinstance(entry, Mapping) or set(entry) != {"up_to_mm", "wave_speed"}:
                raise ConfigError(
                    f"{where}: diameters[{i}] must be {{'up_to_mm': mm, 'wave_speed': m/s}}"
                )
            mm = _checked_at(where, entry["up_to_mm"], f"diameters[{i}].up_to_mm", bound=True)
            speed = _checked_at(where, entry["wave_speed"], f"diameters[{i}].wave_speed")
            bounds.append((mm / 1000.0, speed))
        return cls(named, tuple(bounds), source)


def stretch_of(
    wave_speeds: WaveSpeeds | None, wn: WaterNetworkModel, wave_speed: float
) -> dict[str, float]:
    """:meth:`WaveSpeeds.stretch` of ``wave_speeds`` on ``wn`` at ``wave_speed``; ``{}`` (every
    pipe at ``wave_speed``) without them (:meth:`WaveSpeeds.check`'s errors)."""
    return wave_speeds.stretch(wn, wave_speed) if wave_speeds else {}


def _checked_at(where: str, value: Any, field: str, *, bound: bool = False) -> float:
    """A speed (or, with ``bound``, a diameter in mm), the error naming the file and field."""
    try:
        if bound:
            return check_number(value, field, low=0.0, high=100_000.0, low_open=True)
        return check_number(value, field, low=MIN_WAVE_SPEED, high=MAX_WAVE_SPEED)
    except FieldError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def _csv_rows(text: str, where: str) -> Iterable[tuple[str, float]]:
    first = True
    for number, row in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        cells = [c.strip() for c in row]
        if len(cells) != 2 or not cells[0]:
            raise ConfigError(f"{where} line {number}: expected 'pipe,wave_speed', got {row!r}")
        header, first = first, False
        try:
            value = float(cells[1])
        except ValueError:
            if header:
                continue  # column names
            raise ConfigError(
                f"{where} line {number}: the wave speed {cells[1]!r} is not a number"
            ) from None
        if not (math.isfinite(value) and MIN_WAVE_SPEED <= value <= MAX_WAVE_SPEED):
            raise ConfigError(
                f"{where} line {number}: the wave speed of pipe {cells[0]!r} must be in "
                f"[{MIN_WAVE_SPEED:g}, {MAX_WAVE_SPEED:g}] m/s, got {cells[1]}"
            )
        yield cells[0], value


def read_wave_speeds(path: str | os.PathLike[str]) -> WaveSpeeds:
    """Read a wave-speeds file: JSON (``.json``) or CSV (anything else); module docstring.

    Raises:
        ConfigError: the file cannot be read or is not one of the forms, naming the file and
            the line or field.
    """
    source = os.fspath(path)
    if source.lower().endswith(".json"):
        return WaveSpeeds.from_json(read_json(path, "wave speeds"), source)
    where = f"wave speeds {source}"
    text = read_text(path, "wave speeds", _MAX_FILE_BYTES, bom=True)
    rows = tuple(_csv_rows(text, where))
    if not rows:
        raise ConfigError(f"{where}: no 'pipe,wave_speed' line")
    return WaveSpeeds(rows, (), source)  # a pipe listed twice is refused there
