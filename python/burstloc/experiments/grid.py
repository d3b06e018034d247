"""The robustness study's grid: its networks, factors and levels, the one-factor-at-a-time
points, the settings every point is scored with, and each point's simulated bursts.

Scored by :mod:`burstloc.experiments.study`.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from burstloc.constants import (
    CAPTURE_INTERVALS,
    DETECTORS,
    METER_MODELS,
    RANKING_LOCALIZERS,
    SCENARIO_DURATION,
)
from burstloc.exceptions import ConfigError
from burstloc.network import Network, NetworkSource, as_network, identify
from burstloc.sim.placement.methods import PLACEMENT_METHODS, MeterSet
from burstloc.wave_speeds import WaveSpeeds

if TYPE_CHECKING:
    from burstloc.localize.evidence import MeterModel

__all__ = [
    "DEFAULT_LEVELS",
    "DEFAULT_NETWORKS",
    "Factors",
    "StudyPoint",
    "StudySettings",
    "point_scenarios",
    "study_grid",
    "study_time_step",
]

#: The study's networks, relative to the repository root (see networks/README.md).
DEFAULT_NETWORKS = ("networks/paper15.inp", "networks/todini6.inp", "networks/awumah11.inp")

#: Levels of each factor; the first network's grid varies one factor at a time around
#: :class:`Factors`' defaults.
DEFAULT_LEVELS: dict[str, tuple[Any, ...]] = {
    "noise_sigma": (0.0, 0.01, 0.05, 0.1),
    "meter_fraction": (1.0, 0.5, 0.25),
    "position": (0.1, 0.5, 0.9),
    "burst_coeff": (0.003, 0.01, 0.03),
    "friction": ("steady", "quasi-steady", "unsteady"),
}


@dataclass(frozen=True)
class Factors:
    """One setting of the study's factors (defaults: the study's centre point).

    Attributes:
        noise_sigma: additive Gaussian noise per reading, m.
        meter_fraction: fraction of junctions with meters, in (0, 1] (placed by
            :func:`burstloc.sim.placement.methods.place_meters`, ``StudySettings.placement``).
        position: burst position along the pipe, fraction of its length.
        burst_coeff: the burst's emitter coefficient (TSNet's ``final_burst_coeff``).
        friction: TSNet's friction model (:data:`burstloc.sim.scenarios.scenario.FRICTION_MODELS`).
    """

    noise_sigma: float = 0.0
    meter_fraction: float = 1.0
    position: float = 0.5
    burst_coeff: float = 0.01
    friction: str = "steady"

    def __post_init__(self) -> None:
        if not (math.isfinite(self.noise_sigma) and self.noise_sigma >= 0):
            raise ConfigError(f"noise_sigma must be >= 0 m, got {self.noise_sigma!r}")
        if not (0 < self.meter_fraction <= 1):
            raise ConfigError(f"meter_fraction must be in (0, 1], got {self.meter_fraction!r}")


@dataclass(frozen=True)
class StudyPoint:
    """A grid point: a network, the factor varied (``"default"`` for the centre) and the levels."""

    network: str
    factor: str
    factors: Factors = field(default_factory=Factors)

    @property
    def label(self) -> str:
        """``"paper15: noise_sigma=0.05"`` style name."""
        name = Path(self.network).stem
        if self.factor == "default":
            return f"{name}: default"
        return f"{name}: {self.factor}={getattr(self.factors, self.factor)}"


@dataclass(frozen=True)
class StudySettings:
    """What every grid point is scored with.

    Attributes:
        capture_intervals: seconds.
        detectors: ``"cusum"`` and/or ``"shewhart"``.
        localizers: any of :data:`burstloc.constants.RANKING_LOCALIZERS`.
        meter_models: any of :data:`burstloc.sim.scenarios.capture.METER_MODELS`.
        phases: capture-clock phases per burst, spread evenly over one interval.
        duration: simulated seconds per burst (must cover the signature decision, 150 s after
            the burst).
        false_alarm_rate: calibration target, alarms per meter per hour.
        pipes: restrict every network to these pipes (``None`` = all; for tests).
        seed: noise seed.
        time_step: TSNet's requested time step, s (``None``: the rule of
            :func:`study_time_step`, TSNet's own step unless it is coarser than the finest
            capture interval).
        placement: how meters are placed for a meter fraction below 1, one of
            :data:`burstloc.sim.placement.methods.PLACEMENT_METHODS` (default ``"coverage"``).
        meter_sets: meter files (:class:`burstloc.sim.placement.methods.MeterSet`); a network
            with one uses its meters instead of every junction at full coverage.
        wave_speeds: pipes (or diameter classes) of their own wave speed, on every network of
            the study (``None``: one speed): the bursts are simulated, the meters placed and
            the localizers calibrated with them.
    """

    capture_intervals: tuple[float, ...] = CAPTURE_INTERVALS
    detectors: tuple[str, ...] = DETECTORS
    localizers: tuple[str, ...] = RANKING_LOCALIZERS
    meter_models: tuple[MeterModel, ...] = METER_MODELS
    phases: int = 5
    duration: float = SCENARIO_DURATION
    false_alarm_rate: float = 0.1
    pipes: tuple[str, ...] | None = None
    seed: int = 0
    time_step: float | None = None
    placement: str = "coverage"
    meter_sets: tuple[MeterSet, ...] = ()
    wave_speeds: WaveSpeeds | None = None

    def meters_for(self, network: NetworkSource) -> tuple[str, ...] | None:
        """The meters of ``network``'s meter file among :attr:`meter_sets`, or ``None``."""
        fingerprint = identify(network)[1]
        for meter_set in self.meter_sets:
            if meter_set.network_hash == fingerprint:
                return meter_set.meters
        return None

    def __post_init__(self) -> None:
        if self.placement not in PLACEMENT_METHODS:
            raise ConfigError(
                f"placement must be one of {PLACEMENT_METHODS}, got {self.placement!r}"
            )
        for name, values, allowed in (
            ("detectors", self.detectors, DETECTORS),
            ("localizers", self.localizers, RANKING_LOCALIZERS),
            ("meter_models", self.meter_models, METER_MODELS),
        ):
            bad = [v for v in values if v not in allowed]
            if bad or not values:
                raise ConfigError(f"{name} must be a non-empty subset of {allowed}, got {values}")
        if not self.capture_intervals or not all(
            math.isfinite(dt) and dt > 0 for dt in self.capture_intervals
        ):
            raise ConfigError(f"capture_intervals must be > 0 s, got {self.capture_intervals}")
        if not (isinstance(self.phases, int) and self.phases >= 1):
            raise ConfigError(f"phases must be a positive integer, got {self.phases!r}")
        if self.wave_speeds is not None and not isinstance(self.wave_speeds, WaveSpeeds):
            raise ConfigError(f"wave_speeds must be WaveSpeeds, got {self.wave_speeds!r}")

    def to_json(self) -> dict[str, Any]:
        """The settings as the study's ``results.json`` records them: the meter files as
        written, ``wave_speeds`` only when given (in the wave-speeds file's JSON form)."""
        document = {f.name: getattr(self, f.name) for f in fields(self)}
        document["meter_sets"] = [m.to_json() for m in self.meter_sets]
        del document["wave_speeds"]
        if self.wave_speeds:
            document["wave_speeds"] = self.wave_speeds.to_json()
        return document


def study_grid(
    networks: Sequence[str | os.PathLike[str]],
    levels: dict[str, Sequence[Any]] | None = None,
    vary: Sequence[str] | None = None,
) -> list[StudyPoint]:
    """The one-factor-at-a-time grid: every network at the defaults, then, on the networks in
    ``vary`` (default: the first one), every non-default level of every factor in ``levels``.

    Raises:
        ConfigError: an unknown factor, or no network.
    """
    if not networks:
        raise ConfigError("the study needs at least one network")
    chosen: dict[str, Sequence[Any]] = dict(DEFAULT_LEVELS if levels is None else levels)
    defaults = Factors()
    unknown = [f for f in chosen if not hasattr(defaults, f)]
    if unknown:
        raise ConfigError(f"unknown study factor(s) {unknown}; known: {list(asdict(defaults))}")
    paths = [os.fspath(n) for n in networks]
    varied = {os.fspath(n) for n in (paths[:1] if vary is None else vary)}
    points = [StudyPoint(path, "default") for path in paths]
    for path in paths:
        if path not in varied:
            continue
        for factor, values in chosen.items():
            for value in values:
                if value != getattr(defaults, factor):
                    points.append(StudyPoint(path, factor, replace(defaults, **{factor: value})))
    return points


def point_scenarios(
    point: StudyPoint, settings: StudySettings, network: Network | None = None
) -> list[Any]:
    """The point's bursts, one per pipe, with the time step rule of :func:`study_time_step`;
    the vectorized solver at steady friction, TSNet's for the other friction models.
    ``network``: the point's network, read already."""
    from burstloc.sim.scenarios.scenario import BurstScenario

    read = as_network(point.network) if network is None else network
    pipes = settings.pipes or read.pipes
    f = point.factors
    scenarios = [
        BurstScenario(
            point.network,
            pipe,
            position=f.position,
            burst_coeff=f.burst_coeff,
            friction=f.friction,
            solver="vectorized" if f.friction == "steady" else "tsnet",
            duration=settings.duration,
            time_step=settings.time_step,
            wave_speeds=settings.wave_speeds,
        )
        for pipe in pipes
    ]
    return [replace(s, time_step=study_time_step(s, settings)) for s in scenarios]


def study_time_step(scenario: Any, settings: StudySettings) -> float | None:
    """TSNet time step for a study burst: ``settings.time_step`` if given, else the rule of
    :func:`burstloc.sim.transient.time_step.capture_time_step` for the finest capture interval."""
    from burstloc.sim.transient.time_step import capture_time_step

    return capture_time_step(scenario, min(settings.capture_intervals), settings.time_step)
