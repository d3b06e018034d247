"""The reading types every layer shares: a meter's reading, a complete time step, a window.

:class:`Reading` is what a meter sends, :class:`Step` a complete time step (one value per
meter), :class:`Window` what one localization attempt of the paper's rules sees.
:mod:`burstloc.live.feeds` assembles them from a feed; the localizers read them.

The feed's CSV form (``timestamp,meter,value``, :data:`CSV_HEADER`) and its timestamps
(:func:`timestamp_seconds`: seconds, or ISO 8601 with a UTC offset) are defined here, for the
monitor that reads feeds (:mod:`burstloc.live.parse`) and the simulator that writes them
(:mod:`burstloc.sim.scenarios.feed`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from datetime import datetime, timedelta

import numpy as np
import numpy.typing as npt

from burstloc.exceptions import StreamError

__all__ = [
    "CSV_HEADER",
    "FloatArray",
    "Item",
    "Reading",
    "Step",
    "Window",
    "format_timestamp",
    "parse_start_time",
    "robust_sigma",
    "step_values",
    "timestamp_seconds",
]

#: The columns of the feed's CSV form, one reading a line; a first line naming them is a header.
CSV_HEADER = ("timestamp", "meter", "value")

FloatArray = npt.NDArray[np.float64]
"""A float64 NumPy array."""


@dataclass(frozen=True, slots=True)
class Reading:
    """One pressure reading: ``value`` (m) from ``meter`` for the step at ``timestamp`` (s)."""

    timestamp: float
    meter: str
    value: float


@dataclass(frozen=True, slots=True, eq=False)
class Step:
    """A complete time step: one value per meter, in the stream's meter order.

    ``filled`` names the meters whose value was filled by the ``"hold"`` missing policy (empty
    for a step every meter reported). A monitor keeps ``values`` (a float64 array) as it is,
    without a copy: the array is not written after the step is made.
    """

    timestamp: float
    values: FloatArray
    filled: tuple[str, ...] = ()


def step_values(step: Step) -> FloatArray:
    """``step``'s values as a float64 vector: the step's own array when it is one, not copied
    (the reader must not write it). NumPy 1.x lets go of the GIL for every array copy, however
    small: a copy at every step of a live loop hands the GIL over at every step, and a thread
    beside the loop that waits for it (the incident store's writer) then wakes at each
    hand-over and rarely gets it, at a cost to the loop's own CPU time of about a tenth
    (``benches/bench_incidents.py``, section 3)."""
    values = step.values
    if type(values) is np.ndarray and values.dtype == np.float64:
        return values
    return np.array(values, dtype=np.float64)


@dataclass(frozen=True, slots=True, eq=False)
class Window:
    """The data one localization attempt sees (paper IV.B, "Fetching data").

    ``times`` (S,) and ``values`` (S, M) hold the previous ``interval`` steps followed by the
    ``new`` current ones (S = ``new`` for the first window). Columns follow ``meters``. Arrays
    are read-only.
    """

    index: int
    meters: tuple[str, ...]
    times: FloatArray
    values: FloatArray
    new: int
    first_step: int
    filled: tuple[tuple[str, ...], ...] = field(default=())

    @property
    def decision_time(self) -> float:
        """Timestamp of the newest step: when this window became available."""
        return float(self.times[-1])

    @property
    def steps(self) -> int:
        """Number of steps in the (concatenated) window."""
        return int(self.times.shape[0])

    def column(self, meter: str) -> FloatArray:
        """The readings of one meter over the window."""
        try:
            j = self.meters.index(meter)
        except ValueError:
            raise StreamError(f"meter {meter!r} is not in this stream") from None
        return self.values[:, j]

    def means(self) -> dict[str, float]:
        """Mean reading of every meter over the concatenated window."""
        means = self.values.mean(axis=0)
        return {m: float(v) for m, v in zip(self.meters, means, strict=True)}


Item = Reading | Step


def timestamp_seconds(text: str) -> float:
    """A reading's timestamp as seconds.

    Either a finite number of seconds (from any origin: the simulation's start, or the Unix epoch)
    or an ISO 8601 date and time with a UTC offset or ``Z`` (``2026-11-26T10:00:00.2Z``,
    ``2026-11-26T12:00:00.2+02:00``), given as seconds since the Unix epoch.

    Raises:
        ValueError: neither; the message says why (an ISO time without an offset is refused: its
            time zone is unknown).
    """
    try:
        x = float(text)
    except (TypeError, ValueError, OverflowError):
        return parse_start_time(text).timestamp()
    if not math.isfinite(x):
        raise ValueError("timestamp is not a finite number of seconds")
    return x


def parse_start_time(text: str) -> datetime:
    """An ISO 8601 date and time with a UTC offset or ``Z``.

    Raises:
        ValueError: not one, or one without an offset; the message says which.
    """
    stamp = str(text).strip()
    if stamp[-1:] in ("Z", "z"):  # Python 3.10's fromisoformat does not read "Z"
        stamp = stamp[:-1] + "+00:00"
    try:
        when = datetime.fromisoformat(stamp)
    except ValueError:
        raise ValueError(
            "timestamp is neither seconds nor an ISO 8601 date and time "
            "(e.g. 2026-11-26T10:00:00.2Z)"
        ) from None
    if when.utcoffset() is None:
        raise ValueError("ISO 8601 timestamp without a UTC offset (add Z or +HH:MM)")
    return when


def format_timestamp(seconds: float, start: datetime | None = None) -> str:
    """A feed's timestamp: ``seconds`` (to the microsecond, no float noise), or with ``start``
    the ISO 8601 time ``seconds`` after it, in ``start``'s offset (``Z`` for UTC), to the
    millisecond (to the microsecond where a reading falls between milliseconds)."""
    micros = round(seconds * 1e6)
    if start is None:
        whole, part = divmod(abs(micros), 1_000_000)
        sign = "-" if micros < 0 else ""
        return f"{sign}{whole}" + (f".{part:06d}".rstrip("0") if part else "")
    when = start + timedelta(microseconds=micros)
    spec = "microseconds" if when.microsecond % 1000 else "milliseconds"
    text = when.isoformat(timespec=spec)
    return text[:-6] + "Z" if when.utcoffset() == timedelta(0) else text


def robust_sigma(readings: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Each column's noise level in ``readings`` (rows in time): the median absolute deviation
    of its first differences over ``0.6745 sqrt(2)``, so a slow drift of the level cancels."""
    diffs = np.diff(np.asarray(readings, dtype=np.float64), axis=0)
    mad = np.median(np.abs(diffs - np.median(diffs, axis=0)), axis=0)
    return np.asarray(mad / (0.6745 * math.sqrt(2.0)), dtype=np.float64)
