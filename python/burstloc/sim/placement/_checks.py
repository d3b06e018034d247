"""Checks shared by the placement methods (:mod:`burstloc.sim.placement.methods`,
:mod:`burstloc.sim.placement.region`): the meter count, the wave speed and the capture
interval; the geometry of a meter set on a network file."""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError
from burstloc.localize.pipes import PipeGeometry
from burstloc.network import NetworkSource, as_network
from burstloc.wave_speeds import WaveSpeeds, stretch_of

__all__ = ["check_meter_count", "check_timing", "kept_indices", "meter_geometry"]


def check_meter_count(count: Any, available: int) -> int:
    """``count`` if it is an integer in ``[1, available]`` (ConfigError otherwise)."""
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= available:
        raise ConfigError(f"the meter count must be between 1 and {available}, got {count!r}")
    return count


def kept_indices(keep: Sequence[str], junctions: Sequence[str]) -> list[int]:
    """The positions in ``junctions`` of the meters ``keep`` (a set a network already has),
    in the order given (ConfigError: one is not among ``junctions``, or is listed twice)."""
    from burstloc._validate import some_names

    index = {name: i for i, name in enumerate(junctions)}
    unknown = [name for name in keep if name not in index]
    if unknown:
        raise ConfigError(f"kept meter(s) {some_names(unknown)} are not candidate junctions")
    if len(set(keep)) != len(keep):
        twice = sorted(name for name, n in Counter(keep).items() if n > 1)
        raise ConfigError(f"kept meter(s) {some_names(twice)} listed twice")
    return [index[name] for name in keep]


def check_timing(wave_speed: float, resolution: float) -> None:
    """ConfigError unless the wave speed (m/s) and the resolution (s) are finite and > 0."""
    if not (math.isfinite(wave_speed) and wave_speed > 0):
        raise ConfigError(f"wave_speed must be > 0 m/s, got {wave_speed}")
    if not (math.isfinite(resolution) and resolution > 0):
        raise ConfigError(f"resolution must be > 0 s, got {resolution}")


def meter_geometry(
    network: NetworkSource,
    meters: Sequence[str],
    wave_speed: float,
    wave_speeds: WaveSpeeds | None = None,
) -> tuple[list[PipeGeometry], dict[str, NDArray[np.float64]]]:
    """:func:`burstloc.sim.model.prepare.arrival_geometry` of ``meters`` (ConfigError for none);
    with ``wave_speeds`` (the others at ``wave_speed``) the paths are timed at each pipe's own
    speed (:func:`burstloc.wave_speeds.stretch_of`; NetworkError: a pipe ``network`` does not
    have)."""
    from burstloc.sim.model.prepare import arrival_geometry

    if not meters:
        raise ConfigError("no meters to separate bursts with")
    read = as_network(network)
    return arrival_geometry(read, list(meters), stretch_of(wave_speeds, read.model, wave_speed))
