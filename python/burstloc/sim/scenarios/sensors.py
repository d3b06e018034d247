"""Sensor models for robustness studies: meter subsets and additive Gaussian noise.

Off by default: :class:`SensorModel()` keeps every junction's reading exactly. Apply a model
to captured readings (after :func:`burstloc.sim.scenarios.capture.resample`), not to the simulated
timeline, so that the noise is drawn once per transmitted reading.

Pure NumPy: no simulator import.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from burstloc._validate import some_names
from burstloc.exceptions import ConfigError, InputError, NetworkError

__all__ = ["SensorModel", "choose_meters"]


def _stream_id(key: int | str) -> int:
    if isinstance(key, int) and key >= 0:
        return key
    return int.from_bytes(hashlib.sha256(str(key).encode("utf-8")).digest()[:8], "little")


@dataclass(frozen=True)
class SensorModel:
    """Which junctions carry meters and how noisy the meters are.

    Attributes:
        noise_sigma: standard deviation of additive Gaussian noise, in metres (0 = exact).
        meters: the junctions with meters, in output column order; ``None`` = all junctions.
        seed: seed of the noise; with the ``key`` given to :meth:`apply`, it fixes the draw.
        meter_sigma: standard deviations (m) of the named meters, in place of ``noise_sigma``
            (e.g. a calibrated configuration's ``noise_sigma``, which is per meter).
    """

    noise_sigma: float = 0.0
    meters: tuple[str, ...] | None = None
    seed: int = 0
    meter_sigma: Mapping[str, float] | None = None

    def __post_init__(self) -> None:
        sigma = self.noise_sigma
        if not (isinstance(sigma, (int, float)) and math.isfinite(sigma) and sigma >= 0):
            raise ConfigError(f"noise_sigma must be a finite number >= 0 (m), got {sigma!r}")
        if self.meters is not None:
            meters = tuple(self.meters)
            if not meters:
                raise ConfigError("meters must name at least one junction (or be None for all)")
            duplicates = sorted({m for m in meters if meters.count(m) > 1})
            if duplicates:
                raise ConfigError(f"meters lists junctions more than once: {duplicates}")
            object.__setattr__(self, "meters", meters)
        if not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"seed must be a non-negative integer, got {self.seed!r}")
        if self.meter_sigma is not None:
            for name, value in self.meter_sigma.items():
                if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                    raise ConfigError(
                        f"noise sigma of meter {name!r} must be a finite number >= 0 (m), "
                        f"got {value!r}"
                    )
            object.__setattr__(self, "meter_sigma", dict(self.meter_sigma))

    @property
    def enabled(self) -> bool:
        """True when the model changes anything (noise or a subset of meters)."""
        return self.noise_sigma > 0 or self.meters is not None or bool(self.meter_sigma)

    def apply(
        self, junctions: Sequence[str], readings: ArrayLike, key: int | str = 0
    ) -> tuple[list[str], NDArray[np.float64]]:
        """Return the metered junctions and their (noisy) readings.

        Args:
            junctions: the column names of ``readings``.
            readings: shape ``(T, len(junctions))``, in metres.
            key: distinguishes independent draws under one seed (e.g. the burst pipe), so two
                scenarios do not share a noise sequence; the same ``(seed, key)`` always gives
                the same noise.

        Raises:
            NetworkError: a meter is not one of ``junctions``.
            InputError: ``readings`` does not have one column per junction.
        """
        names = list(junctions)
        values = np.asarray(readings, dtype=np.float64)
        if values.ndim != 2 or values.shape[1] != len(names):
            raise InputError(
                f"readings must have shape (T, {len(names)}) for {len(names)} junctions, "
                f"got {values.shape}"
            )
        if self.meters is not None:
            column = {name: i for i, name in enumerate(names)}
            unknown = [m for m in self.meters if m not in column]
            if unknown:
                raise NetworkError(
                    f"{len(unknown)} unknown meter junction(s) {some_names(unknown)}; known: "
                    f"{some_names(names)}"
                )
            names = list(self.meters)
            values = values[:, [column[m] for m in names]]
        else:
            values = values.copy()
        if self.meter_sigma:
            sigma = np.array([self.meter_sigma.get(n, self.noise_sigma) for n in names])
            rng = np.random.default_rng([self.seed, _stream_id(key)])
            values += rng.standard_normal(size=values.shape) * sigma
        elif self.noise_sigma > 0:
            rng = np.random.default_rng([self.seed, _stream_id(key)])
            values += rng.normal(0.0, self.noise_sigma, size=values.shape)
        return names, values


def choose_meters(junctions: Sequence[str], count: int, seed: int = 0) -> tuple[str, ...]:
    """Pick ``count`` distinct junctions at random (seeded), in the order of ``junctions``.

    Raises:
        ConfigError: ``count`` is not between 1 and the number of junctions.
    """
    names = list(junctions)
    if not (isinstance(count, int) and 1 <= count <= len(names)):
        raise ConfigError(f"count must be between 1 and {len(names)}, got {count!r}")
    picked = np.random.default_rng(seed).choice(len(names), size=count, replace=False)
    return tuple(names[i] for i in sorted(picked))
