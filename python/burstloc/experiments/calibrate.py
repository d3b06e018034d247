"""Automatic calibration: detector thresholds and localization settings from a burst-free baseline.

No hand tuning: for each capture interval, the detector thresholds are the smallest that keep the
false-alarm rate of every meter at or below a target (alarms per meter per hour) on burst-free
readings, and the localization settings follow from the network's geometry.

**Noise model.** A burst-free meter reads its steady level plus independent Gaussian noise of
standard deviation ``sigma`` per reading (the sensor model). ``sigma`` comes either from the
caller (``noise_sigma``: the meters' specification) or from recorded normal readings (a robust
estimate per meter: the median absolute first difference / (0.6745 * sqrt(2))). Both detectors
only see changes (CUSUM: successive differences; Shewhart: deviations from a trailing mean), so
the steady level itself does not matter.

**Thresholds.** A seeded noise stream (``numpy.random.default_rng(seed)``) is run through the
real Rust detectors (:class:`burstloc.Cusum`, :class:`burstloc.Shewhart`) and the threshold is
found by bisection on the number of false alarms per simulated hour. When the target is too rare
to be counted on a stream of ``max_samples`` readings, the tail is extrapolated: alarm rates
fall exponentially with the threshold, so the thresholds that give 100 and 10 alarms per stream
fix the slope. Floors keep a noise-free model usable: the CUSUM drift is ``max(sigma,
resolution)`` per reading (per 0.2 s at 0.02 s and finer: :func:`cusum_threshold`) and
every threshold at least ``10 * resolution`` (``resolution`` = 1 mm, a
meter's display step). The Shewhart multiplier ``s`` is 3 (the classic control limits) and its
reference window is ``2 * localization_interval`` readings, as in the streaming detector.

**Localization interval** (readings per half-window): enough readings for the wave to reach
every meter within one half-window, ``ceil(travel_spread / dt)``, at least 10 and at most 50.
The floor comes from the Shewhart chart: with a trailing reference window of ``W = 2 * N``
readings that includes the current one, ``|x - mean| / std`` can never exceed ``sqrt(W - 1)``,
so a multiplier of 3 needs ``W >= 11``; with ``N = 10`` a step's first reading scores 4.4.
``travel_spread`` is the longest wave travel time between two meters. The signature localizer
decides ``decision_delay`` = 150 s after the onset (the time budget for a decision on the
lasting drop); the arrival localizer first looks ``max(median pipe length / wave speed, 2 * dt)``
after the first alarm: by then the wave has reached both end nodes of the burst pipe, the meters
that matter most (with few meters it looks again until its answer is decisive or the wave has
reached every meter: :func:`burstloc.localize.decide.rank_alarms`).

**Configuration file.** The result is a :class:`burstloc.localize.config.Calibration` (the stored
configuration lives in the localize layer, which the live monitor reads without this module):
:meth:`~burstloc.localize.config.Calibration.save` writes a named JSON document with the network's
SHA-256, the meter list and the localization model
(:func:`burstloc.sim.model.prepare.prepare_model`:
pipe geometry and burst signatures, computed here once with WNTR/EPANET);
:meth:`~burstloc.localize.config.Calibration.check` refuses, by name, a configuration for another
network or other meters.

**Bad baselines.** A baseline shorter than ``MIN_BASELINE_READINGS`` readings or
``MIN_BASELINE_SECONDS`` is refused, and so is one that contains a burst: a lasting step (the
largest two-sample shift statistic of any meter above ``STEP_Z`` noise units and above 10 mm) or
a transient excursion (a reading more than ``SPIKE_Z`` noise units and 50 mm from the meter's
median).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from burstloc import _core
from burstloc._validate import check_names, check_number
from burstloc.constants import (
    CAPTURE_INTERVALS,
    CLOCK_TOLERANCE,
    SIGNATURE_DECISION_DELAY,
    WAVE_SPEED,
    WAVE_SPEED_TOLERANCE,
)
from burstloc.exceptions import ConfigError, InputError
from burstloc.inp import check_meters
from burstloc.localize.config import MAX_METERS, Calibration
from burstloc.localize.interval import MAX_CAPTURE_INTERVAL, IntervalCalibration
from burstloc.localize.onset import FINEST_STEP_INTERVAL
from burstloc.readings import robust_sigma
from burstloc.wave_speeds import WaveSpeeds, stretch_of

if TYPE_CHECKING:
    from burstloc.network import NetworkSource
    from burstloc.sim.signatures.compute import SignatureMethod

__all__ = [
    "Baseline",
    "BaselineError",
    "calibrate",
    "check_baseline",
    "cusum_threshold",
    "localization_interval",
    "shewhart_threshold",
]

DEFAULT_FALSE_ALARM_RATE = 0.1
"""Default target: false alarms per meter per hour (one per meter every 10 hours)."""
DEFAULT_NOISE_SIGMA = 0.01
"""Default sensor noise (m) when neither a sigma nor recorded readings are given."""
RESOLUTION = 0.001
"""Display step of a meter (m): the floor of the CUSUM drift; thresholds are at least 10x it."""
DRIFT_INTERVAL = 0.2
"""At capture intervals where a change's start is fitted to the readings
(:data:`~burstloc.localize.onset.FINEST_STEP_INTERVAL` and finer) the CUSUM drift is one noise
level per this many seconds, not per reading (:func:`cusum_threshold`)."""
SHEWHART_SIGMA = 3.0
"""Shewhart control-limit multiplier ``s``."""
SIGNATURE_SETTLE = 20.0
MIN_BASELINE_READINGS = 100
MIN_BASELINE_SECONDS = 60.0
STEP_Z = 12.0
SPIKE_Z = 12.0
_MAX_SAMPLES = 2_000_000


class BaselineError(InputError):
    """A calibration baseline is unusable: too short, or it contains a burst."""


@dataclass(frozen=True)
class Baseline:
    """Recorded burst-free readings: ``times`` (T,), ``readings`` (T, M) of ``meters``."""

    meters: tuple[str, ...]
    times: NDArray[np.float64]
    readings: NDArray[np.float64]

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=np.float64)
        r = np.asarray(self.readings, dtype=np.float64)
        if t.ndim != 1 or r.shape != (t.size, len(self.meters)):
            raise InputError(
                f"baseline needs times (T,) and readings (T, {len(self.meters)}), got "
                f"{t.shape} and {r.shape}"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(r))):
            raise InputError("baseline readings and times must be finite")
        if t.size > 1 and np.any(np.diff(t) <= 0):
            raise InputError("baseline time stamps must increase")
        object.__setattr__(self, "meters", tuple(self.meters))
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "readings", r)


def check_baseline(baseline: Baseline) -> NDArray[np.float64]:
    """Refuse a baseline that is too short or contains a burst; return its noise per meter."""
    n = baseline.times.size
    span = float(baseline.times[-1] - baseline.times[0]) if n > 1 else 0.0
    if n < MIN_BASELINE_READINGS or span < MIN_BASELINE_SECONDS:
        raise BaselineError(
            f"baseline too short: {n} readings over {span:g} s; calibration needs at least "
            f"{MIN_BASELINE_READINGS} readings and {MIN_BASELINE_SECONDS:g} s of burst-free data"
        )
    r = baseline.readings
    sigma = robust_sigma(r)
    floor = np.maximum(sigma, RESOLUTION)
    # lasting step: the largest two-sample shift statistic along the record, per meter
    csum = np.cumsum(r - r.mean(axis=0), axis=0)[:-1]
    k = np.arange(1, n)[:, None]
    shift = np.abs(csum) * np.sqrt(n / (k * (n - k)))  # = |mean_left - mean_right| * sqrt(...)
    z = shift.max(axis=0) / floor
    left_n = np.argmax(shift, axis=0) + 1
    size = np.array(
        [abs(r[: left_n[j], j].mean() - r[left_n[j] :, j].mean()) for j in range(r.shape[1])]
    )
    for j in np.argsort(-z):
        if z[j] > STEP_Z and size[j] > 0.01:
            raise BaselineError(
                f"baseline contains a burst: meter {baseline.meters[j]!r} shifts by "
                f"{size[j]:.3f} m at t = {baseline.times[left_n[j]]:g} s "
                f"({z[j]:.0f} noise units); calibrate on burst-free readings"
            )
    dev = np.abs(r - np.median(r, axis=0))
    spike = dev.max(axis=0)
    for j in np.argsort(-spike):
        if spike[j] > max(SPIKE_Z * floor[j], 0.05):
            i = int(np.argmax(dev[:, j]))
            raise BaselineError(
                f"baseline contains a burst: meter {baseline.meters[j]!r} departs "
                f"{spike[j]:.3f} m from its level at t = {baseline.times[i]:g} s; calibrate "
                "on burst-free readings"
            )
    return sigma


def _alarms_per_hour(make: Any, noise: NDArray[np.float64], dt: float) -> float:
    return len(make().update_many(noise)) / (noise.size * dt / 3600.0)


def _bisect_threshold(
    rate_at: Any, lo: float, hi: float, target: float, iterations: int = 40
) -> float:
    """Smallest threshold in [lo, hi] with ``rate_at(threshold) <= target`` (rate decreasing)."""
    if rate_at(lo) <= target:
        return lo
    while rate_at(hi) > target:
        lo, hi = hi, hi * 2
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if rate_at(mid) <= target:
            hi = mid
        else:
            lo = mid
        if hi - lo < 1e-5:
            break
    return hi


#: The lowest threshold calibrated (m): ten times the meters' resolution.
_FLOOR = 10 * RESOLUTION


def _threshold(make: Any, sigma: float, dt: float, rate: float, sampling: tuple[int, int]) -> float:
    """Threshold meeting ``rate`` alarms/hour for detectors built by ``make(threshold)`` on
    noise drawn with ``sampling`` (seed, most samples); at least :data:`_FLOOR`."""
    seed, max_samples = sampling
    if sigma <= 0:
        return _FLOOR
    samples = int(min(max_samples, max(10_000, math.ceil(50 * 3600.0 / (rate * dt)))))
    noise = np.random.default_rng(seed).normal(0.0, sigma, samples)
    hours = samples * dt / 3600.0

    def rate_at(thr: float) -> float:
        return _alarms_per_hour(lambda: make(thr), noise, dt)

    countable = 10.0 / hours  # the smallest rate with ten alarms in the stream
    if rate >= countable:
        return max(_FLOOR, _bisect_threshold(rate_at, _FLOOR, 10 * sigma, rate))
    # extrapolate the exponential tail from the thresholds giving 100 and 10 alarms
    r1, r2 = 100.0 / hours, countable
    h1 = _bisect_threshold(rate_at, _FLOOR, 10 * sigma, r1)
    h2 = _bisect_threshold(rate_at, _FLOOR, 10 * sigma, r2)
    slope = (h2 - h1) / math.log(r1 / r2) if h2 > h1 else sigma
    return max(_FLOOR, h2 + slope * math.log(r2 / rate))


def cusum_threshold(
    sigma: float,
    capture_interval: float,
    false_alarm_rate: float = DEFAULT_FALSE_ALARM_RATE,
    *,
    seed: int = 0,
    max_samples: int = _MAX_SAMPLES,
) -> tuple[float, float]:
    """``(threshold, drift)`` of a CUSUM meeting ``false_alarm_rate`` (alarms per hour) on
    Gaussian noise of standard deviation ``sigma`` (m) read every ``capture_interval`` s.

    The CUSUM sums successive differences less the drift, so a front that changes the head by
    less than the drift per reading is summed late or never. The paper's drift, one noise
    level per reading, hides every front slower than ``sigma / dt``: 2.5 m/s at 250 Hz and
    1 cm of noise, where a 0.5 m front over the 0.3 s a burst takes to open is never seen. At
    the capture intervals whose changes are timed from the readings themselves
    (:data:`~burstloc.localize.onset.FINEST_STEP_INTERVAL` and finer: the CUSUM has only to
    fire) the drift is one noise level per :data:`DRIFT_INTERVAL` s,
    ``sigma * dt / DRIFT_INTERVAL`` per reading, and the threshold rises to keep the
    false-alarm rate. Coarser, the CUSUM's start times the change, and the paper's drift
    places it better (measured on L-TOWN at 0.05 s: a mean distance of 45 m with it, 122 m with
    the smaller drift)."""
    drift = max(sigma, RESOLUTION)
    if capture_interval <= FINEST_STEP_INTERVAL:
        drift *= capture_interval / DRIFT_INTERVAL
    cusum = partial(_core.Cusum, drift=drift)
    threshold = _threshold(cusum, sigma, capture_interval, false_alarm_rate, (seed, max_samples))
    return threshold, drift


def shewhart_threshold(
    sigma: float,
    capture_interval: float,
    window: int,
    false_alarm_rate: float = DEFAULT_FALSE_ALARM_RATE,
    *,
    seed: int = 0,
    max_samples: int = _MAX_SAMPLES,
) -> float:
    """Absolute threshold of a Shewhart chart (multiplier 3, ``window`` readings) meeting the
    false-alarm rate on noise ``sigma``."""
    shewhart = partial(_core.Shewhart, window, sigma=SHEWHART_SIGMA)
    return _threshold(shewhart, sigma, capture_interval, false_alarm_rate, (seed, max_samples))


def localization_interval(capture_interval: float, travel_spread: float) -> int:
    """Readings per half-window: the wave crosses the network within one half-window; at
    least 10 (see the module docstring), at most 50."""
    return int(min(50, max(10, math.ceil(travel_spread / capture_interval - 1e-9))))


def calibrate(
    network: NetworkSource,
    *,
    capture_intervals: Sequence[float] = CAPTURE_INTERVALS,
    noise_sigma: float | None = None,
    baseline: Baseline | None = None,
    false_alarm_rate: float = DEFAULT_FALSE_ALARM_RATE,
    meters: Sequence[str] | None = None,
    name: str | None = None,
    wave_speed: float = WAVE_SPEED,
    seed: int = 0,
    max_samples: int = _MAX_SAMPLES,
    signatures: SignatureMethod = "auto",
    workers: int | None = None,
    wave_speed_tolerance: float = WAVE_SPEED_TOLERANCE,
    clock_tolerance: float = CLOCK_TOLERANCE,
    wave_speeds: WaveSpeeds | None = None,
) -> Calibration:
    """Calibrate every capture interval for ``network`` (see the module docstring).

    ``wave_speeds``: pipes (or diameter classes) of their own wave speed; the others run at
    ``wave_speed``. The localization model then times each path at its pipes' speeds.

    ``wave_speed_tolerance`` (a share of each travel time) and ``clock_tolerance`` (s): how well
    the wave speed and the meters' clocks are known, stored in the localization model for its
    search regions (:func:`burstloc.localize.timing_error.timing_scale`).

    The noise comes from ``baseline`` (recorded burst-free readings, checked by
    :func:`check_baseline`; their meters are the meters) or from ``noise_sigma`` (default
    :data:`DEFAULT_NOISE_SIGMA`); ``meters`` default to every junction. The localization model
    (:func:`burstloc.sim.model.prepare.prepare_model`, signatures cached on disk) is computed here,
    its burst signatures by ``signatures`` (:data:`burstloc.sim.signatures.compute.SignatureMethod`;
    the hybrid method's EPANET runs over ``workers`` local processes, default one per CPU).
    """
    from burstloc.network import as_network
    from burstloc.sim.model.prepare import length_graph, prepare_model, travel_time_spread
    from burstloc.sim.signatures.compute import signature_method

    signature_method(signatures, 0)  # an unknown method is refused before any work
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ConfigError(f"workers must be a positive integer, got {workers!r}")

    if not (math.isfinite(false_alarm_rate) and false_alarm_rate > 0):
        raise ConfigError(f"false_alarm_rate must be > 0 per hour, got {false_alarm_rate}")
    check_number(wave_speed_tolerance, "wave_speed_tolerance", low=0, high=1)
    check_number(clock_tolerance, "clock_tolerance", low=0, high=60)
    intervals = [
        check_number(c, "capture interval", low=0, low_open=True, high=MAX_CAPTURE_INTERVAL)
        for c in capture_intervals
    ]
    if not intervals:
        raise ConfigError("at least one capture interval is needed")
    if baseline is not None and noise_sigma is not None:
        raise ConfigError("give either a recorded baseline or noise_sigma, not both")
    read = as_network(network)
    wn, junctions = read.model, list(read.junctions)
    if baseline is not None:
        meter_list = list(baseline.meters)
        if meters is not None and tuple(meters) != baseline.meters:
            raise ConfigError("meters differ from the baseline's meters")
    else:
        meter_list = list(
            junctions if meters is None else check_names(meters, "meters", high=MAX_METERS)
        )
    check_meters(meter_list, junctions, read.path, ConfigError)
    if baseline is not None:
        sigmas = check_baseline(baseline)
        kind = "recorded"
        extra: dict[str, Any] = {
            "baseline_readings": int(baseline.times.size),
            "baseline_seconds": float(baseline.times[-1] - baseline.times[0]),
        }
    else:
        sigma = DEFAULT_NOISE_SIGMA if noise_sigma is None else float(noise_sigma)
        if not (math.isfinite(sigma) and sigma >= 0):
            raise ConfigError(f"noise_sigma must be >= 0 m, got {noise_sigma}")
        sigmas = np.full(len(meter_list), sigma)
        kind = "noise-model"
        extra = {}
    stretch = stretch_of(wave_speeds, wn, wave_speed)
    spread = travel_time_spread(length_graph(wn, stretch), meter_list, wave_speed)
    travel = [wn.get_link(p).length * stretch.get(p, 1.0) for p in wn.pipe_name_list]
    pipe_travel = float(np.median(travel)) / wave_speed
    items = []
    for dt in intervals:
        n = localization_interval(dt, spread)
        cache: dict[float, tuple[float, float, float]] = {}
        cus: dict[str, float] = {}
        drift: dict[str, float] = {}
        she: dict[str, float] = {}
        for meter, s in zip(meter_list, sigmas, strict=True):
            key = round(float(s), 6)
            if key not in cache:
                c_thr, c_drift = cusum_threshold(
                    key, dt, false_alarm_rate, seed=seed, max_samples=max_samples
                )
                s_thr = shewhart_threshold(
                    key, dt, 2 * n, false_alarm_rate, seed=seed, max_samples=max_samples
                )
                cache[key] = (c_thr, c_drift, s_thr)
            cus[meter], drift[meter], she[meter] = cache[key]
        items.append(
            IntervalCalibration(
                capture_interval=dt,
                localization_interval=n,
                cusum_threshold=cus,
                cusum_drift=drift,
                shewhart_threshold=she,
                shewhart_sigma=SHEWHART_SIGMA,
                decision_delay=SIGNATURE_DECISION_DELAY,
                arrival_decision_delay=max(pipe_travel, 2 * dt),
            )
        )
    return Calibration(
        name=name or f"{Path(read.path).stem}-calibrated",
        network=read.path,
        network_hash=read.hash,
        meters=tuple(meter_list),
        noise_sigma={m: float(s) for m, s in zip(meter_list, sigmas, strict=True)},
        false_alarm_rate=float(false_alarm_rate),
        intervals=tuple(items),
        model=replace(
            prepare_model(
                read,
                meter_list,
                wave_speed=wave_speed,
                wave_speeds=wave_speeds,
                signatures=signatures,
                workers=workers,
            ),
            wave_speed_tolerance=wave_speed_tolerance,
            clock_tolerance=clock_tolerance,
        ),
        provenance={
            "baseline": kind,
            "seed": seed,
            "wave_speed": wave_speed,
            **({"wave_speeds": wave_speeds.to_json()} if wave_speeds else {}),
            "travel_spread_s": spread,
            "resolution_m": RESOLUTION,
            "signatures": signature_method(signatures, wn.num_pipes),
            **extra,
        },
    )
