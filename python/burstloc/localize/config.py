"""The stored configuration: calibrated detector settings and the localization model.

``burstloc calibrate`` (:func:`burstloc.experiments.calibrate.calibrate`, the threshold search)
writes a :class:`Calibration` as a named JSON document (format :data:`CALIBRATION_FORMAT`):

* the network file's SHA-256 (:func:`burstloc.inp.network_hash`) and the ordered meters;
* per capture interval, an :class:`IntervalCalibration`: CUSUM and Shewhart thresholds per meter,
  the localization interval and the decision delays;
* the noise model and false-alarm target it was calibrated for, and its provenance;
* ``model``: the :class:`burstloc.localize.model.LocalizationModel` (flow-direction end nodes and
  lengths of the pipes, path lengths to the meters, wave fronts, burst signatures), computed
  offline with the hydraulic model, so that whoever loads the configuration (``burstloc
  monitor`` on a gateway) builds its localizers without WNTR, EPANET or TSNet.

:meth:`Calibration.check` refuses, by name, a configuration for another network or other meters;
the stored model must match the configuration's network and meters. A configuration written by an
earlier version (format ``burstloc-calibration/1``) holds no model: loading it raises a
:class:`~burstloc.exceptions.ConfigError` that says to re-run ``burstloc calibrate`` (it is not
upgraded in place, which would need the hydraulic model). Numpy and the Rust detectors only; on
the live path.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from burstloc._atomic import write_json, write_json_npz
from burstloc._validate import (
    FieldError,
    Fields,
    attributes,
    check_names,
    check_number,
    check_string,
    read_json,
    read_json_npz,
    some_names,
)
from burstloc.exceptions import ConfigError
from burstloc.inp import check_meters, junction_names_in_file
from burstloc.localize.interval import (
    IntervalCalibration,
    levels,
)
from burstloc.localize.model import LocalizationModel
from burstloc.network import Network, NetworkSource, identify

__all__ = ["CALIBRATION_FORMAT", "Calibration"]

CALIBRATION_FORMAT = "burstloc-calibration/2"
"""Format tag of a configuration file (2: with the localization model)."""

_EARLIER_FORMATS = frozenset({"burstloc-calibration/1"})

#: Limits every configuration is checked against on load and at construction.
MAX_METERS = 10_000
MAX_INTERVALS = 64
MAX_FALSE_ALARM_RATE = 1e6
_HASH = re.compile(r"sha256:[0-9a-f]{64}")


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
        """Check every field (a FieldError names it by its JSON name) and the model's fit."""
        check_string(self.name, "name", max_length=256)
        check_string(self.network, "network")
        if not isinstance(self.network_hash, str) or not _HASH.fullmatch(self.network_hash):
            raise FieldError(
                "network_hash", f"must be 'sha256:' and 64 hex digits, got {self.network_hash!r}"
            )
        meters = check_names(self.meters, "meters", high=MAX_METERS)
        object.__setattr__(self, "meters", meters)
        self.model.check(self.network_hash, meters)
        object.__setattr__(
            self, "noise_sigma", levels(self.noise_sigma, "noise_sigma", meters, positive=False)
        )
        object.__setattr__(
            self,
            "false_alarm_rate",
            check_number(
                self.false_alarm_rate,
                "false_alarm_rate_per_hour",
                low=0,
                low_open=True,
                high=MAX_FALSE_ALARM_RATE,
            ),
        )
        intervals = tuple(self.intervals)
        if not 1 <= len(intervals) <= MAX_INTERVALS:
            raise FieldError("intervals", f"must hold 1 to {MAX_INTERVALS}, got {len(intervals)}")
        seen: list[float] = []
        for i, item in enumerate(intervals):
            if set(item.cusum_threshold) != set(meters):
                raise FieldError(
                    f"intervals[{i}].cusum.threshold",
                    f"must have one value per meter {list(meters)}",
                )
            if any(math.isclose(item.capture_interval, c, rel_tol=1e-9) for c in seen):
                raise FieldError(
                    f"intervals[{i}].capture_interval",
                    f"lists {item.capture_interval:g} s a second time",
                )
            seen.append(item.capture_interval)
        object.__setattr__(self, "intervals", intervals)
        if not isinstance(self.provenance, Mapping):
            raise FieldError("provenance", f"must be an object, got {self.provenance!r}")

    def with_fitted(
        self, changes: Mapping[float, Mapping[str, Any]], provenance: Mapping[str, Any]
    ) -> Calibration:
        """This configuration with each capture interval of ``changes`` given those fields (a
        fit's results) and ``provenance`` added to its own."""
        intervals = tuple(
            replace(item, **changes[item.capture_interval])
            if item.capture_interval in changes
            else item
            for item in self.intervals
        )
        return replace(self, intervals=intervals, provenance={**self.provenance, **provenance})

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

    def model_at(self, capture_interval: float) -> LocalizationModel:
        """The localization model as the arrival localizer reads it at ``capture_interval``:
        its paths timed at the fronts' speed there (:attr:`IntervalCalibration.front_factor`
        times the model's wave speed), its regions' timing error that interval's
        (:attr:`IntervalCalibration.timing_factor`)."""
        item = self.for_interval(capture_interval)
        if item.front_factor == 1.0 and item.timing_factor == self.model.timing_factor:
            return self.model
        return replace(
            self.model,
            wave_speed=self.model.wave_speed * item.front_factor,
            timing_factor=item.timing_factor,
        )

    def check(self, network: NetworkSource, meters: Sequence[str] | None = None) -> None:
        """Refuse (ConfigError) to be used with another network or another set of meters, or
        with meters that are not junctions of ``network`` (a configuration edited by hand).
        An INP file is hashed and its junctions read from its text (no model is built)."""
        junctions = (  # an INP file's junctions first: the file is read once, then hashed
            network.junctions if isinstance(network, Network) else junction_names_in_file(network)
        )
        path, digest = identify(network)
        if digest != self.network_hash:
            raise ConfigError(
                f"configuration {self.name!r} was calibrated for network {self.network!r} "
                f"({self.network_hash}), not for {path!r} ({digest})"
            )
        where = f"{path} (in configuration {self.name!r})"
        check_meters(self.meters, junctions, where, ConfigError)
        if meters is not None and tuple(meters) != self.meters:
            missing = sorted(set(self.meters) - set(meters))
            extra = sorted(set(meters) - set(self.meters))
            parts = [
                f"{len(names)} {what} {some_names(names)}"
                for what, names in (("missing", missing), ("extra", extra))
                if names
            ]
            detail = ", ".join(parts) if parts else "the same meters in another order"
            raise ConfigError(
                f"configuration {self.name!r} was calibrated for {len(self.meters)} other "
                f"meters ({detail}); give its meters (--meters, default: the configuration's) "
                "or calibrate for these"
            )

    def summary(self) -> list[str]:
        """What an engineer checks before deploying the configuration, one line each: its
        meters and noise, per capture interval the range of the per-meter thresholds, the
        false alarms to expect and how the burst signatures were computed."""
        sigmas = sorted(self.noise_sigma.values())
        noise = f"{sigmas[0]:g} m" if sigmas[0] == sigmas[-1] else f"{sigmas[0]:g}-{sigmas[-1]:g} m"
        meters = len(self.meters)
        lines = [
            f"configuration {self.name!r}: {meters} meters of {self.network} ("
            f"{some_names(list(self.meters))}), sensor noise {noise}, signatures "
            f"{self.provenance.get('signatures', 'unknown')}"
        ]

        def span(values: Mapping[str, float]) -> str:
            low, high = min(values.values()), max(values.values())
            return f"{low:.3g} m" if math.isclose(low, high) else f"{low:.3g}-{high:.3g} m"

        for item in self.intervals:
            lines.append(
                f"  capture {item.capture_interval:g} s: CUSUM threshold "
                f"{span(item.cusum_threshold)} (drift {span(item.cusum_drift)}), Shewhart "
                f"threshold {span(item.shewhart_threshold)}; localization every "
                f"{item.localization_interval} readings"
                + (
                    f"; fronts heard at {item.front_factor * self.model.wave_speed:.0f} m/s"
                    if item.front_factor != 1.0
                    else ""
                )
                + (
                    f"; regions' timing error x{item.timing_factor:.2f}"
                    if item.timing_factor != 1.0
                    else ""
                )
            )
        per_day = self.false_alarm_rate * 24 * meters
        lines.append(
            f"expected false alarms: {self.false_alarm_rate:g} per meter per hour, "
            f"{per_day:.3g} a day over the {meters} meters (single-meter alarms: the monitor "
            "reports a burst only when two meters alarm)"
        )
        return lines

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary (see :data:`CALIBRATION_FORMAT`)."""
        return {
            "format": CALIBRATION_FORMAT,
            **attributes(self, "name", "network", "network_hash"),
            "meters": list(self.meters),
            "noise_sigma": dict(self.noise_sigma),
            "false_alarm_rate_per_hour": self.false_alarm_rate,
            "intervals": [i.to_json() for i in self.intervals],
            "provenance": dict(self.provenance),
            "model": self.model.to_json(),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any], source: str = "configuration") -> Calibration:
        """Inverse of :meth:`to_json`: every field type- and range-checked; a malformed document
        raises ConfigError naming ``source`` and the field, and so does one written by an
        earlier version (no localization model: re-run ``burstloc calibrate``)."""
        if not isinstance(data, Mapping):
            Fields(data, source)  # raises: not a JSON object
        found = data.get("format")
        if found in _EARLIER_FORMATS:
            raise ConfigError(
                f"{source}: configuration {data.get('name')!r} was written by an earlier "
                f"burstloc (format {found!r}) and holds no localization model; re-run "
                f"`burstloc calibrate {data.get('network', 'NETWORK.inp')} --out PATH` to write "
                "a new one"
            )
        if found != CALIBRATION_FORMAT:
            raise ConfigError(
                f"{source}: not a burstloc configuration (format {found!r}, want "
                f"{CALIBRATION_FORMAT!r})"
            )
        fields = Fields(data, source)
        intervals = []
        for item in fields.objects("intervals", high=MAX_INTERVALS):
            intervals.append(IntervalCalibration.from_json(item))
        model = fields.obj("model")
        with model.checking():
            stored_model = LocalizationModel.from_json(model.data)
        return fields.build(
            cls,
            ("name", "network", "network_hash", "meters", "noise_sigma"),
            {"false_alarm_rate": "false_alarm_rate_per_hour"},
            intervals=tuple(intervals),
            model=stored_model,
            provenance=fields.optional_object("provenance"),
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the configuration (atomically); returns the path. A path ending in ``.npz``
        gets the same document with its large float matrices (the signatures, the wave fronts)
        stored as binary arrays (:func:`burstloc._atomic.write_json_npz`): a fraction of the
        JSON's size and reading time on a large network; any other path gets JSON."""
        if os.fspath(path).endswith(".npz"):
            return write_json_npz(path, self.to_json())
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
        if os.fspath(path).endswith(".npz"):
            data = read_json_npz(path, "configuration")
        else:
            data = read_json(path, "configuration")
        config = cls.from_json(data, f"configuration {os.fspath(path)}")
        if network is not None:
            config.check(network, meters)
        return config
