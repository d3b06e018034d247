"""One capture interval's stored settings: the calibrated detector thresholds per meter, the
localization interval, the decision delays and the speed the fronts are heard at
(:class:`IntervalCalibration`, part of a :class:`burstloc.localize.config.Calibration`), and the
detector bank they make (:func:`calibrated_bank`). Numpy and the Rust detectors only; on the
live path.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from burstloc import _core
from burstloc._validate import (
    FieldError,
    Fields,
    attributes,
    check_count,
    check_number,
)
from burstloc.constants import MAX_TIMING_FACTOR
from burstloc.exceptions import ConfigError

__all__ = [
    "MAX_CAPTURE_INTERVAL",
    "MAX_DELAY",
    "MAX_LEVEL",
    "MAX_LOCALIZATION_INTERVAL",
    "IntervalCalibration",
    "calibrated_bank",
    "levels",
]

#: Capture intervals (s) in ``(0, MAX_CAPTURE_INTERVAL]``: a transient needs readings this often.
MAX_CAPTURE_INTERVAL = 3600.0
#: New readings per localization window (the Shewhart reference window is twice this).
MAX_LOCALIZATION_INTERVAL = 100_000
#: Thresholds, drifts, noise levels (m) and the Shewhart multiplier are at most this.
MAX_LEVEL = 1e6
#: Decision delays (s) are at most a day.
MAX_DELAY = 86_400.0


def levels(values: Any, field: str, meters: Sequence[str], *, positive: bool) -> dict[str, float]:
    """One finite level (m) per meter: exactly the keys ``meters``, each in range."""
    if not isinstance(values, Mapping):
        raise FieldError(field, f"must be an object of one value per meter, got {values!r}")
    if set(values) != set(meters):
        missing = sorted(set(meters) - set(values))
        extra = sorted(set(values) - set(meters))
        raise FieldError(field, f"must have one value per meter (missing {missing}, extra {extra})")
    return {
        m: check_number(values[m], f"{field}.{m}", low=0, low_open=positive, high=MAX_LEVEL)
        for m in meters
    }


@dataclass(frozen=True)
class IntervalCalibration:
    """Settings for one capture interval (thresholds per meter, in metres).

    ``front_factor``: the speed at which the detectors hear a burst's front travel at this
    interval, over the model's wave speed (1: the wave speed itself). A weak front is heard
    only once it has grown past a threshold, later the farther it has gone, so at coarse
    intervals it seems slower than the wave (:mod:`burstloc.experiments.front_speed` fits it
    from simulated bursts); the arrival localizer times paths at that speed
    (:meth:`~burstloc.localize.config.Calibration.model_at`). ``timing_factor``: the search
    regions' timing error over the stated one at this interval (at least 1), so that their
    stated probability holds on bursts simulated on the network
    (:mod:`burstloc.experiments.region_spread`)."""

    capture_interval: float
    localization_interval: int
    cusum_threshold: Mapping[str, float]
    cusum_drift: Mapping[str, float]
    shewhart_threshold: Mapping[str, float]
    shewhart_sigma: float
    decision_delay: float
    arrival_decision_delay: float
    front_factor: float = 1.0
    timing_factor: float = 1.0

    def __post_init__(self) -> None:
        """Check every field (a FieldError names it by its JSON name)."""
        meters = tuple(self.cusum_threshold) if isinstance(self.cusum_threshold, Mapping) else ()
        checked = {
            "capture_interval": check_number(
                self.capture_interval,
                "capture_interval",
                low=0,
                low_open=True,
                high=MAX_CAPTURE_INTERVAL,
            ),
            "localization_interval": check_count(
                self.localization_interval, "localization_interval", high=MAX_LOCALIZATION_INTERVAL
            ),
            "cusum_threshold": levels(
                self.cusum_threshold, "cusum.threshold", meters, positive=True
            ),
            "cusum_drift": levels(self.cusum_drift, "cusum.drift", meters, positive=False),
            "shewhart_threshold": levels(
                self.shewhart_threshold, "shewhart.threshold", meters, positive=True
            ),
            "shewhart_sigma": check_number(
                self.shewhart_sigma, "shewhart.sigma", low=0, low_open=True, high=MAX_LEVEL
            ),
            "decision_delay": check_number(
                self.decision_delay, "decision_delay_s", low=0, high=MAX_DELAY
            ),
            "arrival_decision_delay": check_number(
                self.arrival_decision_delay, "arrival_decision_delay_s", low=0, high=MAX_DELAY
            ),
            "front_factor": check_number(
                self.front_factor, "front_speed_factor", low=0.05, high=2.0
            ),
            "timing_factor": check_number(
                self.timing_factor, "region_timing_factor", low=1.0, high=MAX_TIMING_FACTOR
            ),
        }
        for name, value in checked.items():
            object.__setattr__(self, name, value)

    def uniform(self, detector: str) -> dict[str, float]:
        """One parameter set for a whole detector bank (the largest per-meter thresholds)."""
        if detector == "cusum":
            return {
                "threshold": max(self.cusum_threshold.values()),
                "drift": max(self.cusum_drift.values()),
            }
        if detector == "shewhart":
            return {
                "threshold": max(self.shewhart_threshold.values()),
                "sigma": self.shewhart_sigma,
            }
        raise ConfigError(f"unknown detector {detector!r}; use 'cusum' or 'shewhart'")

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            **attributes(self, "capture_interval", "localization_interval"),
            "cusum": {"threshold": dict(self.cusum_threshold), "drift": dict(self.cusum_drift)},
            "shewhart": {"threshold": dict(self.shewhart_threshold), "sigma": self.shewhart_sigma},
            "decision_delay_s": self.decision_delay,
            "arrival_decision_delay_s": self.arrival_decision_delay,
            "front_speed_factor": self.front_factor,
            "region_timing_factor": self.timing_factor,
        }

    @classmethod
    def from_json(
        cls, data: Mapping[str, Any] | Fields, source: str = "configuration"
    ) -> IntervalCalibration:
        """Inverse of :meth:`to_json`; every field is checked (ConfigError naming ``source``
        and the field)."""
        fields = data if isinstance(data, Fields) else Fields(data, source)
        cusum, shewhart = fields.obj("cusum"), fields.obj("shewhart")
        return fields.build(
            cls,
            ("capture_interval", "localization_interval"),
            {
                "decision_delay": "decision_delay_s",
                "arrival_decision_delay": "arrival_decision_delay_s",
            },
            cusum_threshold=cusum.get("threshold"),
            cusum_drift=cusum.get("drift"),
            shewhart_threshold=shewhart.get("threshold"),
            shewhart_sigma=shewhart.get("sigma"),
            front_factor=fields.data.get("front_speed_factor", 1.0),
            timing_factor=fields.data.get("region_timing_factor", 1.0),
        )


def calibrated_bank(
    kind: str, channels: int, calibration: IntervalCalibration
) -> _core.DetectorBank:
    """A :class:`burstloc.DetectorBank` of ``kind`` with one interval's calibrated settings
    (:meth:`IntervalCalibration.uniform`; Shewhart reference window 2N).

    Raises:
        ConfigError: unknown detector kind.
    """
    params = calibration.uniform(kind)
    if kind == "cusum":
        return _core.DetectorBank(
            "cusum", channels, threshold=params["threshold"], drift=params["drift"]
        )
    return _core.DetectorBank(
        "shewhart",
        channels,
        threshold=params["threshold"],
        sigma=params["sigma"],
        window=2 * calibration.localization_interval,
    )
