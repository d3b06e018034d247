"""The runs of an evaluation: what to score, and over which clock phases.

A :class:`RunSpec` is one detector configuration at one capture interval, scored with one
localizer (the paper's rules, ``"paper"``, or a ranking localizer) under one meter model.
:func:`paper_runs` builds the paper's Tables I/II runs (or runs with given parameters),
:func:`ranking_runs` the ranking localizers' runs and :func:`plan_runs` both, as
``burstloc evaluate`` asks for them. :func:`phase_offsets` spreads a run's attempts over clock
offsets, and :func:`required_duration` says how long a burst must be simulated for a run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from burstloc._validate import check_count, check_number
from burstloc.constants import (
    CAPTURE_INTERVALS,
    DETECTORS,
    LOCALIZERS,
    METER_MODELS,
    SIGNATURE_DECISION_DELAY,
    MeterModel,
)
from burstloc.exceptions import ConfigError
from burstloc.experiments import paper
from burstloc.localize.detection import DetectorConfig, Mode
from burstloc.localize.interval import MAX_CAPTURE_INTERVAL, MAX_LOCALIZATION_INTERVAL

__all__ = [
    "PAPER_OPTIONS",
    "PHASE_SPANS",
    "RANKING_LOCALIZATION_INTERVAL",
    "RunSpec",
    "paper_runs",
    "phase_offsets",
    "plan_runs",
    "ranking_runs",
    "readings_after",
    "required_duration",
]

#: What the phases of an evaluation are spread over.
PHASE_SPANS: tuple[str, ...] = ("capture", "window")


@dataclass(frozen=True)
class RunSpec:
    """One run of the experiment: a detector configuration at a capture interval.

    ``label`` names the paper's scenario (``"S_C1"``...) when the run is one of Tables I/II.
    ``localizer`` is one of :data:`LOCALIZERS`; ``meter_model`` one of
    :data:`burstloc.sim.scenarios.capture.METER_MODELS`. A ranking localizer uses the detector's
    kind with the
    calibrated thresholds (the configuration given to :func:`evaluate`), not ``detector``'s.
    """

    detector: DetectorConfig
    capture_interval: float
    localization_interval: int
    mode: Mode = Mode.WINDOW
    label: str | None = None
    localizer: str = "paper"
    meter_model: str = "instantaneous"

    def __post_init__(self) -> None:
        ci = check_number(
            self.capture_interval,
            "capture interval (s)",
            low=0,
            low_open=True,
            high=MAX_CAPTURE_INTERVAL,
        )
        li = check_count(
            self.localization_interval, "localization_interval", high=MAX_LOCALIZATION_INTERVAL
        )
        object.__setattr__(self, "localization_interval", li)
        object.__setattr__(self, "capture_interval", ci)
        object.__setattr__(self, "mode", Mode(self.mode))
        if self.localizer not in LOCALIZERS:
            raise ConfigError(f"localizer must be one of {LOCALIZERS}, got {self.localizer!r}")
        if self.meter_model not in METER_MODELS:
            raise ConfigError(
                f"meter model must be one of {METER_MODELS}, got {self.meter_model!r}"
            )

    def params(self) -> dict[str, Any]:
        """The run's parameters (JSON ``params``)."""
        return {
            **self.detector.params(),
            "localization_interval": self.localization_interval,
            "mode": self.mode.value,
        }

    def paper_run(self) -> paper.PaperRun | None:
        """The paper's run with the same detector, capture interval, threshold and interval
        (``None`` for a ranking localizer: the paper's figures are for its rules)."""
        if self.localizer != "paper":
            return None
        for run in paper.PAPER_RUNS:
            if (
                run.detector == self.detector.kind
                and run.capture_interval == self.capture_interval
                and run.threshold == self.detector.threshold
                and run.localization_interval == self.localization_interval
            ):
                return run
        return None


def paper_runs(
    detectors: Sequence[str] = ("cusum", "shewhart"),
    capture_intervals: Sequence[float] | None = None,
    modes: Sequence[Mode | str] = (paper.DEFAULT_MODE,),
    *,
    threshold: float | None = None,
    drift: float | None = None,
    sigma: float | None = None,
    localization_interval: int | None = None,
) -> list[RunSpec]:
    """Runs for detectors x capture intervals x modes, with Tables I/II parameters by default.

    A capture interval the paper did not use needs ``threshold`` and ``localization_interval``.
    ``threshold``, ``drift`` (CUSUM), ``sigma`` (Shewhart) and ``localization_interval``
    override the paper's values for every run.
    """
    intervals = list(CAPTURE_INTERVALS if capture_intervals is None else capture_intervals)
    runs: list[RunSpec] = []
    for kind in detectors:
        table = {r.capture_interval: r for r in paper.PAPER_RUNS if r.detector == kind}
        if kind not in ("cusum", "shewhart"):
            raise ConfigError(f"unknown detector {kind!r}; choose cusum, shewhart or both")
        for ci in intervals:
            ci = float(ci)
            if not (math.isfinite(ci) and ci > 0):
                raise ConfigError(f"capture interval must be > 0 s, got {ci:g}")
            base = table.get(ci)
            thr = threshold if threshold is not None else (base.threshold if base else None)
            li = (
                localization_interval
                if localization_interval is not None
                else (base.localization_interval if base else None)
            )
            if thr is None or li is None:
                raise ConfigError(
                    f"capture interval {ci:g} s is not one of the paper's "
                    f"({', '.join(f'{c:g}' for c in CAPTURE_INTERVALS)}); give "
                    "--threshold and --localization-interval for it"
                )
            if kind == "cusum":
                if sigma is not None:
                    raise ConfigError("--sigma applies to the Shewhart chart only")
                cfg = DetectorConfig("cusum", thr, drift=drift or 0.0)
            else:
                if drift is not None:
                    raise ConfigError("--drift applies to the CUSUM only")
                cfg = DetectorConfig("shewhart", thr, sigma=sigma)
            for mode in modes:
                spec = RunSpec(cfg, ci, li, Mode(mode))
                label = spec.paper_run()
                runs.append(RunSpec(cfg, ci, li, Mode(mode), label.scenario if label else None))
    return runs


#: Localization interval of a ranking run at a capture interval the paper did not use (the
#: paper's value at every coarse interval): it only sets the warm-up history and the simulated
#: span; the calibrated bank and the localizer's decision delay do the rest.
RANKING_LOCALIZATION_INTERVAL = 10


def ranking_runs(
    detectors: Sequence[str],
    capture_intervals: Sequence[float] | None,
    localizers: Sequence[str],
    meter_models: Sequence[str] = ("instantaneous",),
) -> list[RunSpec]:
    """Runs of ranking localizers (not ``"paper"``) for detectors x intervals x meter models.

    A ranking run detects with the calibrated bank of its detector kind, so only the kind
    matters; its ``detector`` carries the paper's Tables I/II threshold where the paper used
    the interval (for the JSON record) and 1 m otherwise, and its localization interval the
    paper's, else :data:`RANKING_LOCALIZATION_INTERVAL`. Any capture interval > 0 is accepted.
    Its mode is ``stream``: the bank is fed once per reading and never reset.

    Raises:
        ConfigError: an unknown detector or localizer, ``"paper"`` among ``localizers``, or a
            capture interval that is not > 0.
    """
    if "paper" in localizers:
        raise ConfigError("ranking_runs builds ranking localizers only; use paper_runs for 'paper'")
    intervals = list(CAPTURE_INTERVALS if capture_intervals is None else capture_intervals)
    runs: list[RunSpec] = []
    for kind in detectors:
        table = {r.capture_interval: r for r in paper.PAPER_RUNS if r.detector == kind}
        for ci in intervals:
            ci = float(ci)
            if not (math.isfinite(ci) and ci > 0):
                raise ConfigError(f"capture interval must be > 0 s, got {ci:g}")
            base = table.get(ci)
            cfg = DetectorConfig(kind, base.threshold if base else 1.0)
            li = base.localization_interval if base else RANKING_LOCALIZATION_INTERVAL
            runs += [
                RunSpec(cfg, ci, li, Mode.STREAM, localizer=name, meter_model=model)
                for name in localizers
                for model in meter_models
            ]
    return runs


#: Options that configure the paper's rules only (:func:`plan_runs` refuses them otherwise).
PAPER_OPTIONS: tuple[str, ...] = ("threshold", "drift", "sigma", "localization_interval", "mode")


def plan_runs(
    *,
    localizers: Sequence[str],
    detectors: Sequence[str] = DETECTORS,
    capture_intervals: Sequence[float] | None = None,
    meter_models: Sequence[MeterModel] = ("instantaneous",),
    mode: str | None = None,
    threshold: float | None = None,
    drift: float | None = None,
    sigma: float | None = None,
    localization_interval: int | None = None,
) -> list[RunSpec]:
    """The runs of one evaluation: the paper's rules (Tables I/II parameters, or the given ones)
    and the ranking localizers, for every detector, capture interval and meter model.

    ``mode`` is the paper's detection mode (``"window"``, ``"stream"`` or ``"both"``; default
    :data:`burstloc.experiments.paper.DEFAULT_MODE`).

    Raises:
        ConfigError: a paper-only option (:data:`PAPER_OPTIONS`) without the paper's rules.
    """
    chosen = list(dict.fromkeys(localizers))
    ranking = [name for name in chosen if name != "paper"]
    paper_options = {
        "threshold": threshold,
        "drift": drift,
        "sigma": sigma,
        "localization_interval": localization_interval,
        "mode": mode,
    }
    if "paper" not in chosen:
        given = [f"--{k.replace('_', '-')}" for k, v in paper_options.items() if v is not None]
        if given:
            raise ConfigError(
                f"{', '.join(given)} apply to the paper's rules only (add --localizer paper); "
                f"{', '.join(ranking)} use the calibrated configuration (--config)"
            )
    runs: list[RunSpec] = []
    if "paper" in chosen:
        chosen_mode = mode or paper.DEFAULT_MODE
        runs += [
            replace(spec, meter_model=model)
            for spec in paper_runs(
                detectors,
                capture_intervals,
                ("window", "stream") if chosen_mode == "both" else (chosen_mode,),
                threshold=threshold,
                drift=drift,
                sigma=sigma,
                localization_interval=localization_interval,
            )
            for model in meter_models
        ]
    if ranking:
        runs += ranking_runs(detectors, capture_intervals, ranking, meter_models)
    return runs


#: Clock phases per burst are at most this.
MAX_PHASES = 1000


def phase_offsets(spec: RunSpec, phases: int, span: str = "capture") -> list[float]:
    """The clock offsets (s) of the ``phases`` attempts of a run, evenly spread."""
    check_count(phases, "phases", high=MAX_PHASES)
    if span not in PHASE_SPANS:
        raise ConfigError(f"phase span must be one of {PHASE_SPANS}, got {span!r}")
    period = spec.capture_interval
    if span == "window":
        period *= spec.localization_interval
    return [k * period / phases for k in range(phases)]


def required_duration(spec: RunSpec, burst_start: float, travel: float = 0.0) -> float:
    """Simulated time a run needs: ``2 x interval`` readings after the burst at any phase.

    ``burst_start + (2 x interval + 1) x capture_interval``: one capture interval of margin for
    the clock phase and for TSNet's grid, which ends up to one time step short of the duration.
    The signature and fused localizers answer ``SIGNATURE_DECISION_DELAY`` after the onset the
    meters see, which is up to ``travel`` seconds (the wave's longest travel to a meter) after
    the burst. The arrival localizer looks at the arrivals until its horizon after the first
    alarm (the wave's travel from the first meter it reaches to the last): the first alarm up
    to ``travel`` after the burst, the horizon up to ``travel`` after it (fronts heard slower
    than the wave included: ``travel`` bounds twice any path), so ``2 x travel``.
    """
    need = burst_start + (2 * spec.localization_interval + 1) * spec.capture_interval
    if spec.localizer == "arrival":
        need = max(need, burst_start + 2 * travel + 2 * spec.capture_interval)
    if spec.localizer in ("signature", "fused"):
        need = max(
            need, burst_start + travel + SIGNATURE_DECISION_DELAY + 2 * spec.capture_interval
        )
    return need


def readings_after(times: np.ndarray, burst_start: float) -> int:
    """How many capture ticks fall strictly after the burst start."""
    return int(np.count_nonzero(times > burst_start + 1e-9))
