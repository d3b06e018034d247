"""The stored configuration: calibrated detector settings and the localization model.

``burstloc calibrate`` (:func:`burstloc.experiments.calibrate.calibrate`, the threshold search)
writes a :class:`Calibration` as a named JSON document (format :data:`CALIBRATION_FORMAT`):

* the network file's SHA-256 (:func:`burstloc.inp.network_hash`) and the ordered meters;
* per capture interval, an :class:`IntervalCalibration`: CUSUM and Shewhart thresholds per meter,
  the localization interval and the decision delays;
* the noise model and false-alarm target it was calibrated for, and its provenance;
* ``model``: the :class:`burstloc.localize.model.LocalizationModel` (flow-direction end nodes and
  lengths of the pipes, path lengths to the meters, burst signatures), computed offline with the
  hydraulic model, so that whoever loads the configuration (``burstloc monitor`` on a gateway)
  builds its localizers without WNTR, EPANET or TSNet.

:meth:`Calibration.check` refuses, by name, a configuration for another network or other meters;
the stored model must match the configuration's network and meters. A configuration written by an
earlier version (format ``burstloc-calibration/1``) holds no model: loading it raises a
:class:`~burstloc.exceptions.ConfigError` that says to re-run ``burstloc calibrate`` (it is not
upgraded in place, which would need the hydraulic model). Numpy and the Rust detectors only; on
the live path.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from burstloc import _core
from burstloc._atomic import write_json
from burstloc.exceptions import ConfigError
from burstloc.inp import network_hash
from burstloc.localize.model import LocalizationModel

__all__ = ["CALIBRATION_FORMAT", "Calibration", "IntervalCalibration", "calibrated_bank"]

CALIBRATION_FORMAT = "burstloc-calibration/2"
"""Format tag of a configuration file (2: with the localization model)."""

_EARLIER_FORMATS = frozenset({"burstloc-calibration/1"})


@dataclass(frozen=True)
class IntervalCalibration:
    """Settings for one capture interval (thresholds per meter, in metres)."""

    capture_interval: float
    localization_interval: int
    cusum_threshold: Mapping[str, float]
    cusum_drift: Mapping[str, float]
    shewhart_threshold: Mapping[str, float]
    shewhart_sigma: float
    decision_delay: float
    arrival_decision_delay: float

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
            "capture_interval": self.capture_interval,
            "localization_interval": self.localization_interval,
            "cusum": {"threshold": dict(self.cusum_threshold), "drift": dict(self.cusum_drift)},
            "shewhart": {"threshold": dict(self.shewhart_threshold), "sigma": self.shewhart_sigma},
            "decision_delay_s": self.decision_delay,
            "arrival_decision_delay_s": self.arrival_decision_delay,
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> IntervalCalibration:
        """Inverse of :meth:`to_json`."""
        return cls(
            capture_interval=float(data["capture_interval"]),
            localization_interval=int(data["localization_interval"]),
            cusum_threshold={k: float(v) for k, v in data["cusum"]["threshold"].items()},
            cusum_drift={k: float(v) for k, v in data["cusum"]["drift"].items()},
            shewhart_threshold={k: float(v) for k, v in data["shewhart"]["threshold"].items()},
            shewhart_sigma=float(data["shewhart"]["sigma"]),
            decision_delay=float(data["decision_delay_s"]),
            arrival_decision_delay=float(data["arrival_decision_delay_s"]),
        )


@dataclass(frozen=True)
class Calibration:
    """A named configuration: per capture interval settings for one network and meter set, and
    the localization model the ranking localizers are built from (module docstring).

    Raises:
        ConfigError: a model for another network or other meters.
    """

    name: str
    network: str
    network_hash: str
    meters: tuple[str, ...]
    noise_sigma: Mapping[str, float]
    false_alarm_rate: float
    intervals: tuple[IntervalCalibration, ...]
    model: LocalizationModel
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "meters", tuple(self.meters))
        self.model.check(self.network_hash, self.meters)

    def for_interval(self, capture_interval: float) -> IntervalCalibration:
        """The settings calibrated for ``capture_interval`` (ConfigError if there are none)."""
        for item in self.intervals:
            if math.isclose(item.capture_interval, capture_interval, rel_tol=1e-9):
                return item
        have = ", ".join(f"{i.capture_interval:g}" for i in self.intervals)
        raise ConfigError(
            f"configuration {self.name!r} has no calibration for a {capture_interval:g} s "
            f"capture interval (it has {have} s); run `burstloc calibrate` for it"
        )

    def check(self, network: str | os.PathLike[str], meters: Sequence[str] | None = None) -> None:
        """Refuse (ConfigError) to be used with another network or another set of meters."""
        digest = network_hash(network)
        if digest != self.network_hash:
            raise ConfigError(
                f"configuration {self.name!r} was calibrated for network {self.network!r} "
                f"({self.network_hash}), not for {os.fspath(network)!r} ({digest})"
            )
        if meters is not None and tuple(meters) != self.meters:
            missing = sorted(set(self.meters) - set(meters))
            extra = sorted(set(meters) - set(self.meters))
            detail = f"missing {missing}, extra {extra}" if missing or extra else "other order"
            raise ConfigError(
                f"configuration {self.name!r} was calibrated for other meters ({detail})"
            )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary (see :data:`CALIBRATION_FORMAT`)."""
        return {
            "format": CALIBRATION_FORMAT,
            "name": self.name,
            "network": self.network,
            "network_hash": self.network_hash,
            "meters": list(self.meters),
            "noise_sigma": dict(self.noise_sigma),
            "false_alarm_rate_per_hour": self.false_alarm_rate,
            "intervals": [i.to_json() for i in self.intervals],
            "provenance": dict(self.provenance),
            "model": self.model.to_json(),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Calibration:
        """Inverse of :meth:`to_json`; a malformed document raises ConfigError, and so does one
        written by an earlier version (no localization model: re-run ``burstloc calibrate``)."""
        found = data.get("format") if isinstance(data, Mapping) else None
        if found in _EARLIER_FORMATS:
            raise ConfigError(
                f"configuration {data.get('name')!r} was written by an earlier burstloc (format "
                f"{found!r}) and holds no localization model; re-run `burstloc calibrate "
                f"{data.get('network', 'NETWORK.inp')} --out PATH` to write a new one"
            )
        if found != CALIBRATION_FORMAT:
            raise ConfigError(
                f"not a burstloc configuration (format {found!r}, want {CALIBRATION_FORMAT!r})"
            )
        try:
            return cls(
                name=str(data["name"]),
                network=str(data["network"]),
                network_hash=str(data["network_hash"]),
                meters=tuple(data["meters"]),
                noise_sigma={k: float(v) for k, v in data["noise_sigma"].items()},
                false_alarm_rate=float(data["false_alarm_rate_per_hour"]),
                intervals=tuple(IntervalCalibration.from_json(i) for i in data["intervals"]),
                model=LocalizationModel.from_json(data["model"]),
                provenance=dict(data.get("provenance", {})),
            )
        except ConfigError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError) as exc:
            raise ConfigError(f"malformed configuration: {exc!r}") from exc

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the configuration as JSON (atomically); returns the path."""
        return write_json(path, self.to_json())

    @classmethod
    def load(
        cls,
        path: str | os.PathLike[str],
        *,
        network: str | os.PathLike[str] | None = None,
        meters: Sequence[str] | None = None,
    ) -> Calibration:
        """Read a configuration; with ``network`` (and ``meters``) it is also :meth:`check` ed."""
        try:
            with open(path) as fh:
                data = json.load(fh)
        except (OSError, json.JSONDecodeError) as exc:
            raise ConfigError(f"cannot read configuration {os.fspath(path)!r}: {exc}") from exc
        config = cls.from_json(data)
        if network is not None:
            config.check(network, meters)
        return config


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
