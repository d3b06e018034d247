"""The meter file: the meters chosen for one network, as ``burstloc place`` writes them.

:func:`burstloc.sim.placement.methods.place_meters` returns a :class:`MeterSet`, which saves
as the documented JSON meter file (:data:`METERS_FORMAT`, read by ``burstloc evaluate``,
``calibrate``, ``simulate`` and ``study`` with ``--meters-file`` or ``--meters FILE``)::

    {
      "format": "burstloc-meters/1",
      "network": "networks/paper15.inp",      # informative
      "network_hash": "sha256:...",           # the INP file's SHA-256: checked on use
      "method": "arrival",                    # "coverage", "arrival", "region" or "manual"
      "meters": ["2", "7", "11", "14"],       # junction IDs
      "junctions": 15,                        # junctions the network has
      "wave_speeds": {"pipes": {"P7": 400}, "diameters": []}   # only when given: informative
    }

``method`` says how the meters were chosen: by one of :data:`PLACEMENT_METHODS`, or ``"manual"``
for a set written by hand (a utility's own meters). ``wave_speeds``, only in a file placed with
pipes of their own wave speed (``burstloc place --wave-speeds``), records them in the form
:func:`burstloc.wave_speeds.read_wave_speeds` reads (the other pipes ran at the placement's
``--wave-speed``); the commands that read the file take the meters only. A hand-made set needs
no JSON at all: wherever a command takes ``--meters IDS|FILE`` (and ``place --keep`` /
``--score``) it takes the IDs themselves (``--meters n1,n4,n31``) or a text file of them
(:func:`meter_list`)::

    # BattLeDIM's pressure sensors on L-TOWN
    n1, n4, n31
    n54 n105   # any mix of commas, spaces and lines
"""

from __future__ import annotations

import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from burstloc._atomic import write_json
from burstloc._validate import (
    Fields,
    attributes,
    check_count,
    check_names,
    check_string,
    read_json,
    some_names,
)
from burstloc.exceptions import ConfigError
from burstloc.network import NetworkSource, as_network, identify
from burstloc.wave_speeds import WaveSpeeds

__all__ = [
    "MAX_JUNCTIONS",
    "MAX_METERS",
    "METERS_FORMAT",
    "PLACEMENT_METHODS",
    "MeterSet",
    "meter_list",
]

METERS_FORMAT = "burstloc-meters/1"
"""Format tag of a meter file."""

PLACEMENT_METHODS: tuple[str, ...] = ("coverage", "arrival", "region")
"""The placement methods of :func:`burstloc.sim.placement.methods.place_meters`."""

#: Limit on the meters of a meter file (the localization model's).
MAX_METERS = 10_000

#: Limit on the junctions of the network a meter file is for (BWSN_Network_2 has 12 523).
MAX_JUNCTIONS = 1_000_000


@dataclass(frozen=True)
class MeterSet:
    """Meters chosen for one network: the junction IDs, how they were chosen, and the network's
    fingerprint (:data:`METERS_FORMAT`); ``wave_speeds``, the pipes of their own wave speed the
    placement timed paths with (``None``: one speed; informative, kept by their speeds alone).

    Raises:
        ConfigError: a bad field (named).
    """

    network: str
    network_hash: str
    method: str
    meters: tuple[str, ...]
    junctions: int
    wave_speeds: WaveSpeeds | None = None

    def __post_init__(self) -> None:
        check_string(self.network, "network")
        check_string(self.network_hash, "network_hash", max_length=128)
        if self.method not in (*PLACEMENT_METHODS, "manual"):
            raise ConfigError(
                f"method must be one of {[*PLACEMENT_METHODS, 'manual']}, got {self.method!r}"
            )
        object.__setattr__(self, "meters", check_names(self.meters, "meters", high=MAX_METERS))
        check_count(self.junctions, "junctions", high=MAX_JUNCTIONS)
        if self.wave_speeds is not None:
            if not isinstance(self.wave_speeds, WaveSpeeds):
                raise ConfigError(f"wave_speeds must be WaveSpeeds, got {self.wave_speeds!r}")
            speeds = WaveSpeeds(self.wave_speeds.pipes, self.wave_speeds.diameters)
            object.__setattr__(self, "wave_speeds", speeds or None)  # not where they were read

    def check(self, network: NetworkSource) -> tuple[str, ...]:
        """The meters, once the file is known to be for ``network`` (ConfigError otherwise)."""
        where, found = identify(network)
        if found != self.network_hash:
            raise ConfigError(
                f"the meter file was made for network {self.network} ({self.network_hash}), "
                f"not for {where} ({found}); run `burstloc place` for it"
            )
        return self.meters

    def to_json(self) -> dict[str, Any]:
        """The meter file's document."""
        return {
            "format": METERS_FORMAT,
            **attributes(self, "network", "network_hash", "method"),
            "meters": list(self.meters),
            "junctions": self.junctions,
            **({"wave_speeds": self.wave_speeds.to_json()} if self.wave_speeds else {}),
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the meter file (atomically)."""
        return write_json(path, self.to_json())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> MeterSet:
        """Read a meter file; every field is checked (ConfigError naming the file and field)."""
        source = f"meter file {os.fspath(path)}"
        fields = Fields(read_json(path, "meter file"), source)
        if fields.data.get("format") != METERS_FORMAT:
            raise ConfigError(
                f"{source}: not a burstloc meter file (format {fields.data.get('format')!r}, "
                f"want {METERS_FORMAT!r}); write one with `burstloc place`"
            )
        speeds = fields.data.get("wave_speeds")
        return fields.build(
            cls,
            ("network", "network_hash", "method", "meters", "junctions"),
            wave_speeds=None if speeds is None else WaveSpeeds.from_json(speeds, source),
        )


def meter_list(values: Sequence[str], network: NetworkSource) -> tuple[str, ...]:
    """The meters ``values`` name on ``network``, in the order given.

    ``values`` are junction IDs (each may hold several, separated by commas), or one file: a
    meter file (:data:`METERS_FORMAT`, refused if made for another network) or a text file of
    junction IDs separated by spaces, commas or new lines (``#`` starts a comment). What a
    utility's list of its own meters looks like, e.g. ``n1,n4,n31`` or ``owned.txt``.

    Raises:
        ConfigError: no ID, an ID that is not a junction of ``network`` (the first
            :data:`~burstloc._validate.LISTED` named, the rest counted) or listed twice, an
            unreadable or malformed file.
        NetworkError: missing or malformed network.
    """
    from burstloc.inp import check_meters

    read = as_network(network)
    if len(values) == 1 and os.path.isfile(values[0]):
        names = _meters_in_file(values[0], read)
        source = f"meter list {values[0]}"
    else:
        names = [n for value in values for n in value.split(",") if n]
        source = "the meter list"
    if not names:
        raise ConfigError(f"{source} names no meter")
    check_meters(names, read.junctions, read.path, ConfigError)
    twice = sorted(n for n, c in Counter(names).items() if c > 1)
    if twice:
        raise ConfigError(f"{source} lists {some_names(twice)} more than once")
    return tuple(names)


def _meters_in_file(path: str, network: NetworkSource) -> list[str]:
    """The junction IDs of a meter file or of a text file of IDs (:func:`meter_list`)."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read meter list {path}: {exc}") from None
    if text.lstrip().startswith("{"):
        return list(MeterSet.load(path).check(network))
    words = (line.split("#", 1)[0].replace(",", " ").split() for line in text.splitlines())
    return [w for line in words for w in line]
