"""The candidate pipes and the points on them that the localizers name.

:class:`PipeGeometry` is a candidate pipe as the stored model keeps it
(:class:`burstloc.localize.model.LocalizationModel`): its flow-direction end nodes, length and
wave travel per metre. :class:`PipePosition` is a named point: metres along a pipe from its
flow-direction start node, within an interval. Plain data; on the live path.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["PipeGeometry", "PipePosition"]


@dataclass(frozen=True)
class PipeGeometry:
    """A candidate pipe: its end nodes (``start``, ``end``, flow direction) and length (m);
    ``stretch``: the metres of wave travel at the localizer's wave speed that one metre of it
    takes (that speed over the pipe's own, :mod:`burstloc.wave_speeds`; 1 for a pipe at it)."""

    pipe: str
    start: str
    end: str
    length: float
    stretch: float = 1.0

    @property
    def travel(self) -> float:
        """The pipe's length in metres of wave travel at the localizer's wave speed."""
        return self.length * self.stretch


@dataclass(frozen=True)
class PipePosition:
    """Where on a pipe the burst is: ``metres`` from its ``start`` node (the flow-direction start
    node, as in the ranking), within ``[low, high]``; ``length`` is the pipe's length (m)."""

    pipe: str
    start: str
    end: str
    length: float
    metres: float
    low: float
    high: float

    def to_json(self) -> dict[str, Any]:
        """JSON-ready record: ``pipe``, ``from`` (the start node), ``metres``, ``low``,
        ``high``, ``length``."""
        return {
            "pipe": self.pipe,
            "from": self.start,
            "metres": self.metres,
            "low": self.low,
            "high": self.high,
            "length": self.length,
        }
