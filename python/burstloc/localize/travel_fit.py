"""Travel times learnt from known events: the wave speed and each meter's clock offset.

A transient whose place and time are known (a valve operated, a hydrant opened, a confirmed
burst) is heard by each meter at ``t_e + c_k + d_ek / a``: ``t_e`` the event's time, ``d_ek``
the shortest path (m) from its place to meter ``k``, ``a`` the wave speed and ``c_k`` the
meter's clock offset (s, its clock and its sensor's response together). A meter's detector
places the change between two readings: its onset (the last reading before it) plus half a
capture interval is the observed arrival. :func:`fit_travel_times` fits ``1 / a`` and the
``c_k`` to every observed arrival of every event by weighted least squares, each arrival
weighted by its timing error (a capture interval's rounding, ``dt^2 / 12``, and the stated
relative error of its travel time), the offsets held near zero by the stated clock tolerance
(with a tolerance of 0 they are not fitted). One pass more drops the arrivals more than
:data:`OUTLIER_SIGMAS` robust standard deviations off (a meter that alarmed on a reflection).

The fitted speed is an *effective* one: a detector hears a weak front when it has grown past
its threshold, later the farther (the more junctions) it has travelled, so it is slower than
the pipes' acoustic speed, and it is the one the arrival localizer needs. What the fit leaves
unexplained, as a share of each travel time (a robust spread: the regions' timing kernel has
heavy tails for the rare large miss), becomes the model's ``wave_speed_tolerance`` (the
search regions' timing error: :func:`burstloc.localize.timing_error.timing_scale`), at least
:data:`MIN_TOLERANCE`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np

from burstloc.exceptions import ConfigError
from burstloc.localize.model import LocalizationModel

__all__ = [
    "MAX_FITTED_SPEED",
    "MIN_FITTED_SPEED",
    "MIN_TOLERANCE",
    "OUTLIER_SIGMAS",
    "EventArrivals",
    "TravelFit",
    "fit_travel_times",
]

#: Arrivals further than this many robust standard deviations from the first fit are dropped.
OUTLIER_SIGMAS = 4.0
#: The smallest relative travel-time error the fit states (a few events cannot show less).
MIN_TOLERANCE = 0.02
#: Fitted wave speeds outside [MIN_FITTED_SPEED, MAX_FITTED_SPEED] m/s are refused: no main
#: carries a pressure wave that slowly or that fast, so the events or their places are wrong.
MIN_FITTED_SPEED = 100.0
MAX_FITTED_SPEED = 2000.0


@dataclass(frozen=True)
class EventArrivals:
    """One known event as the meters heard it.

    ``name`` names it in messages; ``time`` (s, the readings' clock) is when it happened;
    ``distances[meter]`` the shortest path (m) from its place to each meter (``inf``: no path);
    ``onsets[meter]`` the reading time (s) before each alarmed meter's change;
    ``capture_interval`` (s) the readings' period.
    """

    name: str
    time: float
    distances: Mapping[str, float]
    onsets: Mapping[str, float]
    capture_interval: float


@dataclass(frozen=True)
class TravelFit:
    """What the known events say: the effective ``wave_speed`` (m/s), each meter's
    ``clock_offsets`` (s, only meters some event was heard at), the relative travel-time error
    left (``wave_speed_tolerance``), the residuals' RMS (s) and how many arrivals were used
    (``arrivals``) and dropped as outliers (``dropped``)."""

    wave_speed: float
    clock_offsets: dict[str, float]
    wave_speed_tolerance: float
    rms: float
    arrivals: int
    dropped: int

    def apply(self, model: LocalizationModel) -> LocalizationModel:
        """``model`` with this fit's wave speed, tolerance and clock offsets."""
        offsets = {m: float(self.clock_offsets.get(m, 0.0)) for m in model.meters}
        return replace(
            model,
            wave_speed=self.wave_speed,
            wave_speed_tolerance=self.wave_speed_tolerance,
            clock_offsets=offsets,
        )


def _rows(
    events: Sequence[EventArrivals], meters: Sequence[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per arrival: the observed travel time (s), the distance (m), the meter's column and the
    capture interval."""
    column = {m: k for k, m in enumerate(meters)}
    y, x, k, dt = [], [], [], []
    for event in events:
        if not (math.isfinite(event.time) and event.capture_interval > 0):
            raise ConfigError(f"known event {event.name!r}: a time and a capture interval > 0")
        for meter, onset in event.onsets.items():
            if meter not in column:
                raise ConfigError(f"known event {event.name!r}: {meter!r} is not a meter")
            distance = float(event.distances.get(meter, math.inf))
            if not (math.isfinite(distance) and math.isfinite(onset)):
                continue  # no path: the meter heard something else
            y.append(onset + event.capture_interval / 2 - event.time)
            x.append(distance)
            k.append(column[meter])
            dt.append(event.capture_interval)
    return np.array(y), np.array(x), np.array(k, dtype=np.intp), np.array(dt)


def _solve(
    y: np.ndarray,
    x: np.ndarray,
    k: np.ndarray,
    weight: np.ndarray,
    meters: int,
    clock_tolerance: float,
) -> tuple[float, np.ndarray]:
    """Weighted least squares for ``(slowness, offsets)``; offsets held near 0 by
    ``clock_tolerance`` (none fitted when it is 0)."""
    fit_offsets = clock_tolerance > 0
    columns = 1 + (meters if fit_offsets else 0)
    a = np.zeros((y.size, columns))
    a[:, 0] = x
    if fit_offsets:
        a[np.arange(y.size), 1 + k] = 1.0
    sw = np.sqrt(weight)
    lhs, rhs = a * sw[:, None], y * sw
    if fit_offsets:  # the prior: each offset ~ N(0, clock_tolerance^2)
        prior = np.zeros((meters, columns))
        prior[np.arange(meters), 1 + np.arange(meters)] = 1.0 / clock_tolerance
        lhs, rhs = np.vstack([lhs, prior]), np.concatenate([rhs, np.zeros(meters)])
    theta, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    offsets = theta[1:] if fit_offsets else np.zeros(meters)
    return float(theta[0]), offsets


def _relative(residual: np.ndarray, travel: np.ndarray, dt: np.ndarray) -> float:
    """The relative travel-time error ``residual`` shows, once a capture interval's rounding is
    taken out: a robust standard deviation (1.4826 x the median absolute share of each travel
    time), as the search regions' heavy-tailed timing kernel takes the rare large misses."""
    if residual.size == 0:
        return 1.0
    excess = np.sqrt(np.maximum(residual**2 - dt**2 / 12, 0.0)) / np.maximum(travel, dt)
    return 1.4826 * float(np.median(excess))


def fit_travel_times(
    events: Sequence[EventArrivals],
    meters: Sequence[str],
    *,
    wave_speed: float,
    wave_speed_tolerance: float,
    clock_tolerance: float,
) -> TravelFit:
    """Fit the effective wave speed and the meters' clock offsets to ``events`` (module
    docstring); ``wave_speed`` and ``wave_speed_tolerance`` are what was assumed before (they
    weight the arrivals), ``clock_tolerance`` (s) how far a clock may be off.

    Raises:
        ConfigError: no event, fewer than three arrivals or arrivals all at one distance (they
            cannot tell a speed), or a fitted speed no main has.
    """
    if not events:
        raise ConfigError("no known event to learn the travel times from")
    y, x, k, dt = _rows(events, meters)
    if y.size < 3 or np.ptp(x) <= 0:
        raise ConfigError(
            f"the known events give {y.size} arrival(s) at {np.unique(x).size} distance(s): at "
            "least three arrivals at different distances are needed to fit a wave speed"
        )
    tolerance, slowness = wave_speed_tolerance, 1 / wave_speed
    keep = np.ones(y.size, dtype=bool)
    for _ in range(3):  # fit; weigh by what the fit leaves, drop the outliers; fit again
        variance = dt**2 / 12 + (tolerance * slowness * x) ** 2 + 1e-12
        slowness, offsets = _solve(
            y[keep], x[keep], k[keep], 1 / variance[keep], len(meters), clock_tolerance
        )
        residual = y - slowness * x - offsets[k]
        spread = np.maximum(1.4826 * float(np.median(np.abs(residual[keep]))), np.sqrt(variance))
        keep = np.abs(residual) <= OUTLIER_SIGMAS * spread
        if keep.sum() < 3:
            raise ConfigError("the known events' arrivals disagree: fewer than three fit together")
        tolerance = max(_relative(residual[keep], slowness * x[keep], dt[keep]), 1e-3)
    if not (1 / MAX_FITTED_SPEED <= slowness <= 1 / MIN_FITTED_SPEED):
        found = "no finite" if slowness <= 0 else f"{1 / slowness:.0f} m/s"
        raise ConfigError(
            f"the known events fit a wave speed of {found}, outside {MIN_FITTED_SPEED:g}-"
            f"{MAX_FITTED_SPEED:g} m/s: check their places and times"
        )
    residual = residual[keep]
    tolerance = float(np.clip(_relative(residual, slowness * x[keep], dt[keep]), MIN_TOLERANCE, 1))
    heard = sorted(set(k[keep].tolist()))
    return TravelFit(
        wave_speed=1 / slowness,
        clock_offsets={meters[j]: float(offsets[j]) for j in heard},
        wave_speed_tolerance=tolerance,
        rms=float(np.sqrt(np.mean(residual**2))),
        arrivals=int(keep.sum()),
        dropped=int((~keep).sum()),
    )
