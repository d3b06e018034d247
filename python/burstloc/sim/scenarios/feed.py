"""A monitor's feed from a simulation: the readings meters would send, in the monitor's CSV form.

``burstloc simulate ... --feed FILE`` writes one: a header line ``timestamp,meter,value``
(:data:`burstloc.readings.CSV_HEADER`), then one line per reading, every meter's reading of a
capture tick before the next tick's, meters in the network's junction order (or the order of
the meters given: a utility's own meters only). ``timestamp`` is
seconds from the simulation's start, or with a start time the ISO 8601 time (its UTC offset
kept; ``Z`` for UTC); ``value`` is the pressure head in metres (0.1 mm), with seeded Gaussian
noise when asked (:class:`burstloc.sim.scenarios.sensors.SensorModel`: the same seed and pipe, the
same noise). A reading that is NaN (a meter silent under a perturbed truth,
:func:`burstloc.sim.scenarios.perturb.silence`) is not written: the meter sent nothing.
``burstloc monitor --readings FILE`` reads it as it is.

Pure NumPy: no simulator import.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from datetime import datetime
from pathlib import Path

from burstloc._atomic import write_text
from burstloc.exceptions import ConfigError
from burstloc.readings import CSV_HEADER, format_timestamp
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.sensors import SensorModel

__all__ = ["feed_text", "write_feed"]


def feed_text(
    result: ScenarioResult,
    *,
    noise: float = 0.0,
    seed: int = 0,
    start: datetime | None = None,
    meters: Sequence[str] | None = None,
) -> str:
    """The feed of ``result``, captured readings (module docstring), as CSV text.

    Args:
        result: a result resampled at a capture interval (:meth:`ScenarioResult.resample`).
        noise: standard deviation of the meters' Gaussian noise, m (0: exact readings).
        seed: the noise's seed (drawn per pipe or event, as in the study).
        start: the wall-clock time of the simulation's start (ISO timestamps), or ``None``
            (seconds from the simulation's start).
        meters: the junctions that carry meters, in the feed's order (default: every
            junction of ``result``, in the network's order).

    Raises:
        ConfigError: ``result`` is on the simulation's grid, not a capture interval's; a bad
            ``noise`` or ``seed``; no meter or one listed twice.
        NetworkError: a meter that is not a junction of ``result``.
    """
    if result.metadata.get("capture_interval") is None:
        raise ConfigError("a feed needs readings at a capture interval (--capture-interval S)")
    key = str(result.metadata.get("pipe") or result.metadata.get("label") or "")
    chosen = None if meters is None else tuple(meters)
    meters, values = SensorModel(noise_sigma=noise, seed=seed, meters=chosen).apply(
        result.junctions, result.heads, key=key
    )
    lines = [",".join(CSV_HEADER)]
    for t, row in zip(result.time.tolist(), values.tolist(), strict=True):
        stamp = format_timestamp(t, start)
        lines.extend(
            f"{stamp},{m},{value:.4f}"
            for m, value in zip(meters, row, strict=True)
            if math.isfinite(value)  # NaN: a silent meter sends nothing
        )
    return "\n".join(lines) + "\n"


def write_feed(
    path: str | os.PathLike[str],
    result: ScenarioResult,
    *,
    noise: float = 0.0,
    seed: int = 0,
    start: datetime | None = None,
    meters: Sequence[str] | None = None,
) -> tuple[Path, int]:
    """Write :func:`feed_text` to ``path`` (atomically); return the path and the number of
    readings written."""
    text = feed_text(result, noise=noise, seed=seed, start=start, meters=meters)
    return write_text(path, text), text.count("\n") - 1
