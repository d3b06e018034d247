"""The localization model: what the ranking localizers need of a network, stored, versioned.

The arrival and signature localizers need facts about the network that only a hydraulic model
gives: each pipe's end nodes in the steady-state flow direction and its length, the shortest path
lengths from those end nodes to the meters, the wave front a burst on each pipe sends to each
meter (relative: which silent meters should have heard it) and the burst signatures (steady-state
head drops at the meters, per pipe and position), and the network's other links (valves, pumps)
that join the pipes where a crew walks between them. ``burstloc calibrate`` computes them once,
offline (:func:`burstloc.sim.model.prepare.prepare_model`: WNTR and EPANET), and stores them in the
configuration it writes (:class:`burstloc.localize.config.Calibration`); the live monitor builds
its localizers from the stored model
(:meth:`burstloc.localize.decide.RankingLocalizers.from_model`) and never runs a hydraulic model.

A model is bound to one network file (its SHA-256, :func:`burstloc.inp.network_hash`) and one
ordered list of meters: :meth:`LocalizationModel.check` refuses, by name, a model for another
network or other meters. The JSON document carries the format tag :data:`MODEL_FORMAT`; a
distance to an unreachable meter is stored as ``null``; ``fronts`` and ``connectors`` may be
absent (a model written before they were stored). Numpy only; on the live path.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc._validate import FieldError, check_names, check_number
from burstloc.constants import (
    CLOCK_TOLERANCE,
    MAX_TIMING_FACTOR,
    WAVE_SPEED,
    WAVE_SPEED_TOLERANCE,
)
from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.pipes import PipeGeometry
from burstloc.localize.signature import SignatureSet

__all__ = ["MODEL_FORMAT", "LocalizationModel"]

MODEL_FORMAT = "burstloc-localization-model/1"
"""Format tag of a stored localization model."""

#: Limits a model is checked against: meters, candidate pipes, signature sets (positions).
MAX_METERS = 10_000
MAX_PIPES = 100_000
MAX_SIGNATURE_SETS = 64
#: Pressure waves in water pipes travel at most about 1500 m/s; this leaves room for any unit.
MAX_WAVE_SPEED = 10_000.0
#: A pipe's wave travel per metre (its stretch, the model's wave speed over its own) is at most.
MAX_STRETCH = 100.0
#: Pipe lengths and path lengths (m) are at most this.
MAX_LENGTH = 1e8


@dataclass(frozen=True, eq=False)
class LocalizationModel:
    """The network facts the ranking localizers need (module docstring).

    ``pipes``: every candidate pipe with its flow-direction end nodes, length (m) and stretch
    (its wave travel per metre: :class:`~burstloc.localize.pipes.PipeGeometry`).
    ``node_distances[node][j]``: shortest path length (m) along the pipes from ``node`` (an end
    node of a candidate pipe) to ``meters[j]`` (``inf`` when there is no path); where pipes have
    wave speeds of their own, in metres of wave travel at ``wave_speed`` (travel time times it).
    ``signature_sets``: the burst signatures at ``meters``, one set per position along the pipes.
    ``wave_speed``: the pressure-wave speed (m/s) the arrival localizer assumes;
    ``wave_speed_tolerance`` the relative uncertainty of a travel time along a path, and
    ``clock_tolerance`` (s) that of each meter's clock: the timing error the search regions
    allow (:mod:`burstloc.localize.region`).
    ``fronts[pipe][j]``: the wave front a burst on ``pipe`` sends to ``meters[j]``, relative to
    the others (:func:`burstloc.sim.model.prepare.wave_fronts`): which silent meters should have
    heard it (:class:`burstloc.localize.arrival.ArrivalLocalizer`). ``None`` (a model stored
    without them): every silent meter counts as not yet reached.
    ``clock_offsets[meter]``: how late (s) each meter hears a wave, its clock and its sensor
    together, as known events showed (:mod:`burstloc.localize.travel_fit`); ``None``: not known
    (every meter on time).
    ``connectors``: the network's links that are not candidate pipes (valves, pumps), as
    ``(start node, end node, length m)`` (0 for a valve or a pump): with the pipes, the paths a
    crew walks from a named point to the burst (:mod:`burstloc.localize.center`); ``None`` (a
    model stored without them): the pipes alone.
    ``timing_factor``: the search regions' timing error over the stated one at one capture
    interval; not stored with the model: set per interval by
    :meth:`~burstloc.localize.config.Calibration.model_at` from
    :attr:`~burstloc.localize.interval.IntervalCalibration.timing_factor`.

    Raises:
        ConfigError: the parts do not fit together (a pipe end without distances, signatures of
            other meters or another network, no pipe, a bad wave speed).
    """

    network_hash: str
    meters: tuple[str, ...]
    pipes: tuple[PipeGeometry, ...]
    node_distances: Mapping[str, NDArray[np.float64]]
    signature_sets: tuple[SignatureSet, ...]
    wave_speed: float = WAVE_SPEED
    fronts: Mapping[str, NDArray[np.float64]] | None = None
    wave_speed_tolerance: float = WAVE_SPEED_TOLERANCE
    clock_tolerance: float = CLOCK_TOLERANCE
    clock_offsets: Mapping[str, float] | None = None
    timing_factor: float = 1.0
    connectors: Sequence[tuple[str, str, float]] | None = None

    def __post_init__(self) -> None:
        meters = check_names(self.meters, "meters", high=MAX_METERS)
        if not 1 <= len(self.pipes) <= MAX_PIPES:
            raise FieldError("pipes", f"must hold 1 to {MAX_PIPES} pipes, got {len(self.pipes)}")
        for i, p in enumerate(self.pipes):
            check_number(p.length, f"pipes[{i}].length", low=0, low_open=True, high=MAX_LENGTH)
            check_number(p.stretch, f"pipes[{i}].stretch", low=0, low_open=True, high=MAX_STRETCH)
        check_number(self.wave_speed, "wave_speed", low=0, low_open=True, high=MAX_WAVE_SPEED)
        check_number(self.wave_speed_tolerance, "wave_speed_tolerance", low=0, high=1)
        check_number(self.clock_tolerance, "clock_tolerance_s", low=0, high=60)
        check_number(self.timing_factor, "timing_factor", low=1, high=MAX_TIMING_FACTOR)
        if len(self.signature_sets) > MAX_SIGNATURE_SETS:
            raise FieldError("signature_sets", f"must hold at most {MAX_SIGNATURE_SETS} sets")
        distances: dict[str, NDArray[np.float64]] = {}
        for node, row in self.node_distances.items():
            values = np.array(row, dtype=np.float64)
            if values.shape != (len(meters),) or np.any(np.isnan(values)) or np.any(values < 0):
                raise FieldError(
                    f"node_distances.{node}", f"must be {len(meters)} lengths >= 0 (m) or null"
                )
            values.setflags(write=False)
            distances[str(node)] = values
        for p in self.pipes:
            for node in (p.start, p.end):
                if node not in distances:
                    raise ConfigError(f"no distances from node {node!r} (pipe {p.pipe!r})")
        if not self.signature_sets:
            raise ConfigError("a localization model needs at least one signature set")
        for sig in self.signature_sets:
            if sig.network_hash != self.network_hash or sig.meters != meters:
                raise ConfigError(
                    f"signature set at position {sig.params.get('position')} is for another "
                    f"network or other meters than the model ({self.network_hash})"
                )
        object.__setattr__(self, "meters", meters)
        object.__setattr__(self, "pipes", tuple(self.pipes))
        object.__setattr__(self, "node_distances", distances)
        object.__setattr__(self, "signature_sets", tuple(self.signature_sets))
        object.__setattr__(self, "wave_speed", float(self.wave_speed))
        object.__setattr__(self, "wave_speed_tolerance", float(self.wave_speed_tolerance))
        object.__setattr__(self, "clock_tolerance", float(self.clock_tolerance))
        object.__setattr__(self, "timing_factor", float(self.timing_factor))
        if self.fronts is not None:
            object.__setattr__(self, "fronts", self._checked_fronts(self.fronts))
        if self.clock_offsets is not None:
            offsets = {}
            for meter, value in self.clock_offsets.items():
                if meter not in meters:
                    raise FieldError("clock_offsets_s", f"{meter!r} is not a meter of the model")
                offsets[meter] = check_number(value, f"clock_offsets_s.{meter}", low=-60, high=60)
            object.__setattr__(self, "clock_offsets", offsets)
        if self.connectors is not None:
            object.__setattr__(self, "connectors", self._checked_connectors(self.connectors))

    @staticmethod
    def _checked_connectors(
        connectors: Sequence[tuple[str, str, float]],
    ) -> tuple[tuple[str, str, float], ...]:
        """Each connector as ``(start, end, length)``: two node names, a length >= 0 (m)."""
        if len(connectors) > MAX_PIPES:
            raise FieldError("connectors", f"must hold at most {MAX_PIPES} links")
        out = []
        for i, item in enumerate(connectors):
            if (
                not isinstance(item, (tuple, list))
                or len(item) != 3
                or not all(isinstance(n, str) and n for n in item[:2])
            ):
                raise FieldError(f"connectors[{i}]", "must be [start node, end node, length]")
            length = check_number(item[2], f"connectors[{i}].length", low=0, high=MAX_LENGTH)
            out.append((item[0], item[1], float(length)))
        return tuple(out)

    def _checked_fronts(
        self, fronts: Mapping[str, NDArray[np.float64]]
    ) -> dict[str, NDArray[np.float64]]:
        """One row of ``len(meters)`` finite fronts >= 0 for every candidate pipe, read-only."""
        names = [p.pipe for p in self.pipes]
        if set(fronts) != set(names):
            missing = sorted(set(names) - set(fronts))[:5]
            extra = sorted(set(fronts) - set(names))[:5]
            raise FieldError(
                "fronts", f"must have one row per pipe (missing {missing}, extra {extra})"
            )
        rows: dict[str, NDArray[np.float64]] = {}
        for name in names:
            row = np.array(fronts[name], dtype=np.float64)
            if row.shape != (len(self.meters),) or not np.all(np.isfinite(row)) or np.any(row < 0):
                raise FieldError(f"fronts.{name}", f"must be {len(self.meters)} finite values >= 0")
            row.setflags(write=False)
            rows[name] = row
        return rows

    def __eq__(self, other: object) -> bool:
        """Equal when the stored documents are (arrays compared element by element)."""
        if not isinstance(other, LocalizationModel):
            return NotImplemented
        return self.to_json() == other.to_json()

    __hash__ = None  # type: ignore[assignment]

    def check(self, network_hash: str, meters: Sequence[str]) -> None:
        """Refuse (ConfigError, naming the difference) to serve another network or other meters."""
        if network_hash != self.network_hash:
            raise ConfigError(
                f"the localization model is for network {self.network_hash}, not {network_hash}; "
                "re-run `burstloc calibrate` for this network"
            )
        if tuple(meters) != self.meters:
            raise ConfigError(
                f"the localization model is for meters {list(self.meters)}, not {list(meters)}; "
                "re-run `burstloc calibrate` for these meters"
            )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary (see :data:`MODEL_FORMAT`)."""
        return {
            "format": MODEL_FORMAT,
            "network_hash": self.network_hash,
            "meters": list(self.meters),
            "wave_speed": self.wave_speed,
            "wave_speed_tolerance": self.wave_speed_tolerance,
            "clock_tolerance_s": self.clock_tolerance,
            **({} if self.clock_offsets is None else {"clock_offsets_s": dict(self.clock_offsets)}),
            "pipes": [
                {"pipe": p.pipe, "start": p.start, "end": p.end, "length": p.length}
                | ({} if p.stretch == 1.0 else {"stretch": p.stretch})
                for p in self.pipes
            ],
            "node_distances": {
                node: [float(d) if math.isfinite(d) else None for d in row]
                for node, row in self.node_distances.items()
            },
            "signature_sets": [s.to_json() for s in self.signature_sets],
            **(
                {}
                if self.fronts is None
                else {"fronts": {p: [float(f) for f in row] for p, row in self.fronts.items()}}
            ),
            **(
                {}
                if self.connectors is None
                else {"connectors": [[u, v, length] for u, v, length in self.connectors]}
            ),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> LocalizationModel:
        """Inverse of :meth:`to_json`; a malformed document or another format raises
        ConfigError."""
        if not isinstance(data, Mapping) or data.get("format") != MODEL_FORMAT:
            found = data.get("format") if isinstance(data, Mapping) else type(data).__name__
            raise ConfigError(
                f"not a burstloc localization model (format {found!r}, want {MODEL_FORMAT!r}); "
                "re-run `burstloc calibrate`"
            )
        try:
            return cls(
                network_hash=str(data["network_hash"]),
                meters=tuple(data["meters"]),
                wave_speed=float(data["wave_speed"]),
                # models stored before these were recorded: the defaults
                wave_speed_tolerance=float(data.get("wave_speed_tolerance", WAVE_SPEED_TOLERANCE)),
                clock_tolerance=float(data.get("clock_tolerance_s", CLOCK_TOLERANCE)),
                clock_offsets=data.get("clock_offsets_s"),
                pipes=tuple(
                    PipeGeometry(
                        str(p["pipe"]),
                        str(p["start"]),
                        str(p["end"]),
                        float(p["length"]),
                        float(p.get("stretch", 1.0)),
                    )
                    for p in data["pipes"]
                ),
                node_distances={
                    node: np.array([math.inf if d is None else float(d) for d in row])
                    for node, row in data["node_distances"].items()
                },
                signature_sets=tuple(SignatureSet.from_json(s) for s in data["signature_sets"]),
                fronts=(
                    None
                    if data.get("fronts") is None
                    else {
                        str(p): np.array(row, dtype=np.float64) for p, row in data["fronts"].items()
                    }
                ),
                connectors=(
                    None
                    if data.get("connectors") is None
                    else [tuple(c) for c in data["connectors"]]
                ),
            )
        except ConfigError:
            raise
        except InputError as exc:
            raise ConfigError(f"malformed localization model: {exc}") from exc
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise ConfigError(f"malformed localization model: {exc!r}") from exc
