"""The reading types every layer shares: a meter's reading, a complete time step, a window.

:class:`Reading` is what a meter sends, :class:`Step` a complete time step (one value per
meter), :class:`Window` what one localization attempt of the paper's rules sees.
:mod:`burstloc.live.feeds` assembles them from a feed; the localizers read them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from burstloc.exceptions import StreamError

__all__ = ["FloatArray", "Item", "Reading", "Step", "Window"]

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
    for a step every meter reported).
    """

    timestamp: float
    values: FloatArray
    filled: tuple[str, ...] = ()


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
