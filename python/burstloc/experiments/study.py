"""The robustness study (issue 6): localization accuracy over a one-factor-at-a-time grid.

Around the defaults (noise-free meters on every junction, bursts at the pipe mid-point with
coefficient 0.01, TSNet's default ``steady`` friction), one factor at a time is changed on the
first network of the study (paper15 by default): sensor noise sigma, the fraction of junctions that
carry meters, the burst position along the pipe, the burst coefficient (over a decade) and TSNet's
friction model. The other networks run at the defaults. Every grid point is scored for each
detector (calibrated CUSUM and Shewhart banks, :mod:`burstloc.experiments.calibrate`: no hand
tuning), each
localizer (``arrival``, ``signature``, ``fused``), each meter model (``instantaneous``,
``interval-averaged``; :func:`burstloc.sim.capture.capture`) and each capture interval, over
several phases of the capture clock, as top-1 / top-3 accuracy and the median time from the
burst to the decision.

Simulations go through :func:`burstloc.sim.tsnet.simulate_many` (the simulation cache and the
local/Dask executor of :mod:`burstloc.sim.sweep`); the grid points are then scored through the same
executor, one task per point. :func:`write_report` writes ``report.md``, ``results.json`` and
PNG plots (top-1 accuracy vs capture interval per detector and localizer).

Meter placement for a fraction ``f < 1`` (:func:`greedy_meters`): greedy coverage of the burst
signatures. Starting from no meter, add the junction that most increases the smallest distance
between any two pipes' unit-normalised signatures restricted to the chosen meters (ties: the
larger total signature); so every added meter separates the pair of pipes that is hardest to
tell apart so far. Deterministic, computed from the network model alone.

History: every captured stream is preceded by 2N + 1 readings of the initial steady state
(N = the calibrated localization interval), as a live meter's would be (TSNet starts from that
steady state); noise is added to them too.

Calibration: the noise model is the grid point's sigma, or the calibration default (0.01 m) when
the meters are noise-free (a threshold calibrated on exact readings would be zero).
"""

from __future__ import annotations

import json
import math
import os
import statistics
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc.constants import (
    CAPTURE_INTERVALS,
    DETECTORS,
    METER_MODELS,
    RANKING_LOCALIZERS,
    SCENARIO_DURATION,
)
from burstloc.exceptions import ConfigError, InputError, NetworkError

if TYPE_CHECKING:
    from burstloc.localize.evidence import MeterModel

__all__ = [
    "DEFAULT_LEVELS",
    "DEFAULT_NETWORKS",
    "Factors",
    "StudyPoint",
    "StudySettings",
    "greedy_meters",
    "run_study",
    "score_point",
    "study_grid",
    "study_time_step",
    "write_report",
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
            :func:`greedy_meters`).
        position: burst position along the pipe, fraction of its length.
        burst_coeff: the burst's emitter coefficient (TSNet's ``final_burst_coeff``).
        friction: TSNet's friction model (:data:`burstloc.sim.scenario.FRICTION_MODELS`).
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
        meter_models: any of :data:`burstloc.sim.capture.METER_MODELS`.
        phases: capture-clock phases per burst, spread evenly over one interval.
        duration: simulated seconds per burst (must cover the signature decision, 150 s after
            the burst).
        false_alarm_rate: calibration target, alarms per meter per hour.
        pipes: restrict every network to these pipes (``None`` = all; for tests).
        seed: noise seed.
        time_step: TSNet's requested time step, s (``None``: the rule of
            :func:`study_time_step`, TSNet's own step unless it is coarser than the finest
            capture interval).
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

    def __post_init__(self) -> None:
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


def greedy_meters(signatures: Any, count: int) -> tuple[str, ...]:
    """Choose ``count`` meters by greedy coverage of burst signatures (see the module doc).

    Args:
        signatures: a :class:`burstloc.localize.signature.SignatureSet` over the candidate
        junctions.
        count: how many meters, 1..number of candidates.

    Returns:
        The chosen junctions, in the signature set's meter order.

    Raises:
        ConfigError: ``count`` out of range.
    """
    meters = list(signatures.meters)
    if not (isinstance(count, int) and 1 <= count <= len(meters)):
        raise ConfigError(f"count must be between 1 and {len(meters)}, got {count!r}")
    matrix = np.abs(np.asarray(signatures.matrix, dtype=np.float64))
    strength = matrix.sum(axis=0)
    chosen: list[int] = []
    pairs = np.triu_indices(matrix.shape[0], k=1)
    for _ in range(count):
        keys = []
        for j in range(len(meters)):
            if j in chosen:
                continue
            sub = matrix[:, [*chosen, j]]
            norm = np.linalg.norm(sub, axis=1, keepdims=True)
            unit = np.divide(sub, norm, out=np.zeros_like(sub), where=norm > 0)
            gaps = np.linalg.norm(unit[pairs[0]] - unit[pairs[1]], axis=1)
            keys.append((float(gaps.min()) if gaps.size else 0.0, float(strength[j]), -j))
        chosen.append(-max(keys)[2])
    return tuple(meters[j] for j in sorted(chosen))


def _scenarios(point: StudyPoint, settings: StudySettings) -> list[Any]:
    """The point's bursts, one per pipe, with the time step rule of :func:`study_time_step`."""
    from burstloc.network import load_network, pipe_names
    from burstloc.sim.scenario import BurstScenario

    pipes = settings.pipes or tuple(pipe_names(load_network(point.network)))
    f = point.factors
    scenarios = [
        BurstScenario(
            point.network,
            pipe,
            position=f.position,
            burst_coeff=f.burst_coeff,
            friction=f.friction,
            duration=settings.duration,
            time_step=settings.time_step,
        )
        for pipe in pipes
    ]
    return [replace(s, time_step=study_time_step(s, settings)) for s in scenarios]


def study_time_step(scenario: Any, settings: StudySettings) -> float | None:
    """TSNet time step for a study burst: ``settings.time_step`` if given; else TSNet's own
    (``None``) when it is no coarser than the finest capture interval, and half that interval
    otherwise (a capture needs simulated samples at least as fine as its interval; half of it
    keeps TSNet's wave-speed adjustment, which can lengthen a requested step by up to 50 %,
    below the interval).
    """
    from burstloc.sim.tsnet import expected_time_step

    if settings.time_step is not None:
        return settings.time_step
    finest = min(settings.capture_intervals)
    try:
        expected = expected_time_step(replace(scenario, time_step=None))
    except NetworkError:
        return None  # an unknown pipe: its simulation fails and names it
    return None if expected <= finest else finest / 2


@dataclass
class _Tally:
    """Counts of one localizer at one detector x meter model x interval."""

    top1: int = 0
    top3: int = 0
    n: int = 0
    nodet: int = 0
    times: list[float] = field(default_factory=list)


def _with_history(
    ticks: np.ndarray, readings: np.ndarray, steady: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray]:
    """Prepend ``count`` readings of the initial steady state at the capture interval.

    TSNet starts from a steady state, so these are the readings a meter reported before the
    simulation began: a live detector has a history, and a Shewhart chart's reference window
    (2N readings) is full before the burst even at 10 s intervals.
    """
    dt = float(ticks[1] - ticks[0])
    before = ticks[0] - dt * np.arange(count, 0, -1, dtype=np.float64)
    history = np.repeat(steady[None, :], count, axis=0)
    return np.concatenate([before, ticks]), np.vstack([history, readings])


def _signature_first(names: Sequence[str]) -> list[str]:
    """``names`` with ``signature`` ahead of ``fused`` (whose decision can reuse its ranking)."""
    return sorted(names, key=lambda name: name != "signature")


def score_point(task: tuple[StudyPoint, StudySettings]) -> list[dict[str, Any]]:
    """Score one grid point (simulations must be cached or are simulated here).

    Returns one row per detector x localizer x meter model x capture interval: ``top1``,
    ``top3`` (fractions of attempts), ``attempts``, ``not_located``, ``median_time_s`` (burst
    start to decision) and the point's description.
    """
    from burstloc.experiments.calibrate import DEFAULT_NOISE_SIGMA, calibrate
    from burstloc.experiments.evaluate import calibrated_bank
    from burstloc.localize.decide import rank_alarms
    from burstloc.localize.fused import FusedLocalizer
    from burstloc.localize.signature import SignatureLocalizer
    from burstloc.network import load_network
    from burstloc.sim.capture import capture
    from burstloc.sim.prepare import arrival_localizer
    from burstloc.sim.sensors import SensorModel
    from burstloc.sim.signatures import cached_signature_sets, cached_signatures
    from burstloc.sim.tsnet import simulate_burst

    point, settings = task
    f = point.factors
    results = [simulate_burst(s) for s in _scenarios(point, settings)]
    junctions = list(results[0].junctions)
    all_signatures = cached_signatures(point.network, junctions)
    signature_sets = cached_signature_sets(point.network, junctions)
    count = max(1, round(f.meter_fraction * len(junctions)))
    meters = list(greedy_meters(all_signatures, count)) if count < len(junctions) else junctions
    columns = [junctions.index(m) for m in meters]
    wn = load_network(point.network)
    arrival = arrival_localizer(wn, meters)
    signature = SignatureLocalizer([s.for_meters(meters) for s in signature_sets])
    fused = FusedLocalizer(arrival, signature)
    localizers: dict[str, Any] = {"arrival": arrival, "signature": signature, "fused": fused}
    config = calibrate(
        point.network,
        capture_intervals=settings.capture_intervals,
        meters=meters,
        noise_sigma=f.noise_sigma if f.noise_sigma > 0 else DEFAULT_NOISE_SIGMA,
        false_alarm_rate=settings.false_alarm_rate,
        seed=settings.seed,
    )
    sensor = SensorModel(noise_sigma=f.noise_sigma, seed=settings.seed)
    rows: list[dict[str, Any]] = []
    for dt in settings.capture_intervals:
        cal = config.for_interval(dt)
        for detector in settings.detectors:
            pad = 2 * cal.localization_interval + 1
            for model in settings.meter_models:
                tally = {n: _Tally() for n in settings.localizers}
                for k in range(settings.phases):
                    phase = k * dt / settings.phases
                    for res in results:
                        ticks, readings = capture(res.time, res.heads[:, columns], dt, phase, model)
                        ticks, readings = _with_history(ticks, readings, res.heads[0, columns], pad)
                        _, readings = sensor.apply(meters, readings, key=f"{res.pipe}/{k}/{dt}")
                        bank = calibrated_bank(detector, len(meters), cal)
                        alarms = bank.run(np.ascontiguousarray(readings))
                        burst = float(res.metadata["burst_start"])
                        signature_ranking = None  # shared with fused (same evidence, same time)
                        for name in _signature_first(settings.localizers):
                            entry = tally[name]
                            entry.n += 1
                            try:
                                decision = rank_alarms(
                                    name,
                                    localizers,
                                    meters,
                                    ticks,
                                    readings,
                                    alarms,
                                    cal,
                                    model,
                                    signature_ranking=signature_ranking,
                                )
                            except InputError:
                                entry.nodet += 1
                                continue
                            if name == "signature":
                                signature_ranking = decision.ranking
                            entry.top1 += decision.ranking.in_top(res.pipe, 1)
                            entry.top3 += decision.ranking.in_top(res.pipe, 3)
                            entry.times.append(decision.time - burst)
                for name, e in tally.items():
                    rows.append(
                        {
                            "network": Path(point.network).stem,
                            "point": point.label,
                            "factor": point.factor,
                            "level": None
                            if point.factor == "default"
                            else getattr(f, point.factor),
                            "meters": len(meters),
                            "detector": detector,
                            "localizer": name,
                            "meter_model": model,
                            "capture_interval": dt,
                            "top1": e.top1 / e.n,
                            "top3": e.top3 / e.n,
                            "attempts": e.n,
                            "not_located": e.nodet,
                            "median_time_s": statistics.median(e.times) if e.times else None,
                        }
                    )
    return rows


def run_study(
    points: Sequence[StudyPoint],
    settings: StudySettings,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> tuple[list[dict[str, Any]], list[str]]:
    """Simulate (cached) every burst of every point, then score the points.

    Returns:
        ``(rows, problems)``: the rows of every point that could be scored, and one message per
        point left out (a simulation or the scoring failed; the message names it and why).
    """
    from burstloc.sim.sweep import sweep
    from burstloc.sim.tsnet import simulate_many

    needs = {p: _scenarios(p, settings) for p in points}
    scenarios = list(dict.fromkeys(s for group in needs.values() for s in group))
    report = simulate_many(scenarios, workers=workers, scheduler=scheduler, progress=progress)
    failed = {f.item: str(f) for f in report.failures}
    problems = []
    runnable = []
    for point, group in needs.items():
        bad = [failed[s] for s in group if s in failed]
        if bad:
            problems.append(f"{point.label}: left out, {len(bad)} simulation(s) failed: {bad[0]}")
        else:
            runnable.append(point)
    scored = sweep(
        score_point,
        [(p, settings) for p in runnable],
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="study",
        label=lambda task: task[0].label,
    )
    problems += [f"{f.item[0].label}: left out, scoring failed: {f}" for f in scored.failures]
    return [row for _, rows in scored.succeeded() for row in rows], problems


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f}"


def _table(
    rows: list[dict[str, Any]], intervals: Sequence[float], label_keys: Sequence[str]
) -> str:
    head = "| " + " | ".join(label_keys) + " | "
    head += " | ".join(f"{dt:g} s" for dt in intervals) + " |"
    lines = [head, "|" + "---|" * (len(label_keys) + len(intervals))]
    groups: dict[tuple[Any, ...], dict[float, dict[str, Any]]] = {}
    for row in rows:
        groups.setdefault(tuple(row[k] for k in label_keys), {})[row["capture_interval"]] = row
    for key, by_dt in groups.items():
        cells = []
        for dt in intervals:
            r = by_dt.get(dt)
            cells.append("-" if r is None else f"{_pct(r['top1'])} / {_pct(r['top3'])}")
        lines.append("| " + " | ".join(str(k) for k in key) + " | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _plot(rows: list[dict[str, Any]], path: Path, title: str, series_keys: Sequence[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    models = sorted({r["meter_model"] for r in rows})
    fig, axes = plt.subplots(1, len(models), figsize=(5 * len(models), 3.6), squeeze=False)
    for ax, model in zip(axes[0], models, strict=True):
        series: dict[tuple[Any, ...], list[tuple[float, float]]] = {}
        for r in rows:
            if r["meter_model"] == model:
                key = tuple(r[k] for k in series_keys)
                series.setdefault(key, []).append((r["capture_interval"], 100 * r["top1"]))
        for key, pts in sorted(series.items(), key=lambda kv: str(kv[0])):
            pts.sort()
            ax.plot(
                [p[0] for p in pts], [p[1] for p in pts], marker="o", label=" ".join(map(str, key))
            )
        ax.set_xscale("log")
        ax.set_xlabel("capture interval (s)")
        ax.set_ylabel("top-1 accuracy (%)")
        ax.set_ylim(-2, 102)
        ax.set_title(f"{title} - {model}", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_report(
    rows: list[dict[str, Any]],
    settings: StudySettings,
    out_dir: str | os.PathLike[str],
    problems: Sequence[str] = (),
) -> Path:
    """Write ``report.md``, ``results.json`` and the PNG plots to ``out_dir``; return the report.

    The report's first table is the summary (fused localizer, CUSUM detector, both meter
    models: top-1 / top-3 % per capture interval for every grid point); then the defaults of
    every network per detector and localizer; then every row.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(
        json.dumps(
            {"settings": asdict(settings), "rows": rows, "problems": list(problems)},
            indent=2,
            default=str,
        )
    )
    dts = list(settings.capture_intervals)
    parts = [
        "# burstloc robustness study",
        "",
        f"Top-1 / top-3 accuracy (%) over {settings.phases} phases of the capture clock; "
        "calibrated detectors (no hand tuning); one factor varied at a time around the "
        "defaults (noise-free meters on every junction, burst at mid-pipe, coefficient 0.01, "
        "TSNet steady friction). See `burstloc.experiments.study` for the rules.",
        "",
    ]
    if problems:
        parts += ["**Left out:**", "", *[f"- {p}" for p in problems], ""]
    best = settings.localizers[-1] if "fused" not in settings.localizers else "fused"
    det = settings.detectors[0]
    summary = [r for r in rows if r["localizer"] == best and r["detector"] == det]
    parts += [f"## Summary ({best} localizer, {det})", ""]
    parts += [_table(summary, dts, ["point", "meters", "meter_model"]), ""]
    parts += ["## Every network at the defaults", ""]
    defaults = [r for r in rows if r["factor"] == "default"]
    parts += [_table(defaults, dts, ["network", "detector", "localizer", "meter_model"]), ""]
    times = [
        r for r in defaults if r["capture_interval"] == min(dts) and r["median_time_s"] is not None
    ]
    if times:
        parts += [f"Median time from burst to decision at {min(dts):g} s:", ""]
        parts += [
            f"- {r['network']} {r['detector']} {r['localizer']} {r['meter_model']}: "
            f"{r['median_time_s']:.2f} s"
            for r in times
        ]
        parts.append("")
    parts += ["## All rows", ""]
    parts += [_table(rows, dts, ["point", "detector", "localizer", "meter_model"]), ""]
    for network in dict.fromkeys(r["network"] for r in rows):
        sub = [r for r in defaults if r["network"] == network]
        name = f"{network}_defaults.png"
        _plot(sub, out / name, f"{network} defaults", ["detector", "localizer"])
        parts.append(f"![{network}]({name})")
    for factor in dict.fromkeys(r["factor"] for r in rows if r["factor"] != "default"):
        sub = [
            r
            for r in rows
            if r["localizer"] == best
            and r["detector"] == det
            and (
                r["factor"] == factor
                or (r["factor"] == "default" and r["network"] == rows[0]["network"])
            )
        ]
        name = f"factor_{factor}.png"
        _plot(sub, out / name, f"{factor} ({best}, {det})", ["point"])
        parts.append(f"![{factor}]({name})")
    report = out / "report.md"
    report.write_text("\n".join(parts) + "\n")
    return report
