"""The believable readings of each meter: a value outside its range is a bad reading.

:class:`PlausibleRange` holds, per meter, the lowest and highest believable reading (m of head):
by default below -10 m or above twice the highest steady head at the meters, with overrides per
meter or for every meter (``burstloc monitor --plausible``). :class:`burstloc.live.health.Health`
counts, reports and skips a reading outside it, so it never reaches the detectors.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from burstloc.exceptions import ConfigError

__all__ = ["PlausibleRange"]


@dataclass(frozen=True)
class PlausibleRange:
    """Per meter, the lowest and highest believable reading (m of head)."""

    low: Mapping[str, float]
    high: Mapping[str, float]

    @classmethod
    def default(cls, meters: Sequence[str], steady_heads: Sequence[float]) -> PlausibleRange:
        """Below -10 m or above twice the highest steady head at the meters is implausible."""
        top = 2.0 * max(max(float(h) for h in steady_heads), 10.0)
        return cls({m: -10.0 for m in meters}, {m: top for m in meters})

    def with_overrides(self, overrides: Mapping[str | None, tuple[float, float]]) -> PlausibleRange:
        """This range with ``overrides`` (meter, or ``None`` for every meter, → (low, high)).

        Raises:
            ConfigError: an unknown meter or an empty or non-finite range.
        """
        low, high = dict(self.low), dict(self.high)
        for meter, (lo, hi) in overrides.items():
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ConfigError(f"plausible range must be finite LOW < HIGH, got {lo}:{hi}")
            if meter is not None and meter not in low:
                raise ConfigError(f"plausible range for unknown meter {meter!r}")
            for m in low if meter is None else (meter,):
                low[m], high[m] = float(lo), float(hi)
        return PlausibleRange(low, high)
