"""Travel times learnt from known events: the wave speed and each meter's clock offset.

A transient whose place and time are known (a valve operated, a hydrant opened, a confirmed
burst) is heard by each meter at ``t_e + c_k + d_ek / a``: ``t_e`` the event's time, ``d_ek``
the shortest path (m) from its place to meter ``k``, ``a`` the wave speed and ``c_k`` the
meter's clock offset (s, its clock and its sensor's response together). A meter's detector
places the change between two readings: its onset (the last reading before it) plus half a
capture interval is the observed arrival. :func:`fit_travel_times` fits ``1 / a`` and the
``c_k`` to every observed arrival of every event by weighted least squares (an event whose time
is not known, a burst found later, gets its own time fitted: only the differences between its
arrivals count), each arrival
weighted by its timing error (a capture interval's rounding, ``dt^2 / 12``, and the stated
relative error of its travel time), the offsets held near zero by the stated clock tolerance
(with a tolerance of 0 they are not fitted). Each pass drops the arrivals more than
:data:`OUTLIER_SIGMAS` robust standard deviations off (a meter that alarmed on a reflection).

A least-squares fit follows its outliers, so the first pass starts from a speed they cannot
move (:func:`robust_slowness`): the median of the slopes between every two arrivals of one
event (and, for an event whose time is known, from the event to each arrival), each weighed
as the least-squares fit weighs it, and its first trimming is made there. A whole event can
be heard late: a burst whose fronts reach most meters too weak to alarm, heard seconds later
by a larger wave (L-TOWN's p8, 10 L/s at 0.05 s: 20 of its 28 arrivals 0.4-7 s late); pooled
with two events heard on time, it pulled a least-squares start from 1 132 to 962 m/s and the
tolerance from 3.6 % to 24 %.

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
    "robust_slowness",
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
    ``capture_interval`` (s) the readings' period. ``time_known=False``: when it happened is
    not known (a burst found later): the fit takes its time from the arrivals, and only the
    differences between its meters' arrivals count.
    """

    name: str
    time: float
    distances: Mapping[str, float]
    onsets: Mapping[str, float]
    capture_interval: float
    time_known: bool = True


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
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per arrival: the observed travel time (s; from its event's ``time``), the distance (m),
    the meter's column, the capture interval, its event's column among the events whose time
    is fitted (-1: a known time) and its event's index. An event of unknown time heard at
    fewer than two distances says nothing and is left out."""
    column = {m: k for k, m in enumerate(meters)}
    y, x, k, dt, e, g = [], [], [], [], [], []
    unknown = 0
    for index, event in enumerate(events):
        if not (math.isfinite(event.time) and event.capture_interval > 0):
            raise ConfigError(f"known event {event.name!r}: a time and a capture interval > 0")
        rows = []
        for meter, onset in event.onsets.items():
            if meter not in column:
                raise ConfigError(f"known event {event.name!r}: {meter!r} is not a meter")
            distance = float(event.distances.get(meter, math.inf))
            if not (math.isfinite(distance) and math.isfinite(onset)):
                continue  # no path: the meter heard something else
            rows.append((onset + event.capture_interval / 2 - event.time, distance, column[meter]))
        if not event.time_known:
            if len({r[1] for r in rows}) < 2:
                continue
            unknown += 1
        for travel, distance, meter_column in rows:
            y.append(travel)
            x.append(distance)
            k.append(meter_column)
            dt.append(event.capture_interval)
            e.append(-1 if event.time_known else unknown - 1)
            g.append(index)
    return (
        np.array(y),
        np.array(x),
        np.array(k, dtype=np.intp),
        np.array(dt),
        np.array(e, dtype=np.intp),
        np.array(g, dtype=np.intp),
    )


def _weighted_median(values: np.ndarray, weights: np.ndarray) -> float:
    """The value below which half the ``weights`` lie."""
    order = np.argsort(values, kind="stable")
    cumulative = np.cumsum(weights[order])
    return float(values[order][np.searchsorted(cumulative, 0.5 * cumulative[-1])])


def robust_slowness(
    travel: np.ndarray,
    distance: np.ndarray,
    event: np.ndarray,
    known: np.ndarray,
    variance: np.ndarray,
) -> float:
    """A slowness (s/m) that a minority of late arrivals cannot move (module docstring): the
    weighted median of the slopes between every two arrivals of one event and, for an event
    whose time is ``known`` (one flag per arrival), from the event to each arrival. Each slope
    weighs as least squares would weigh it, its distance squared over its travel time's
    ``variance`` (s², per arrival; a pair's the sum of its two). ``travel`` (s) and
    ``distance`` (m) per arrival, ``event`` its event's index; ``nan`` where no two arrivals
    are at different distances."""
    slopes, weights = [], []
    for g in np.unique(event):
        mine = np.flatnonzero(event == g)
        i, j = np.triu_indices(mine.size, k=1)
        a, b = mine[i], mine[j]
        apart = distance[a] - distance[b]
        wide = apart != 0
        slopes.append((travel[a] - travel[b])[wide] / apart[wide])
        weights.append(apart[wide] ** 2 / (variance[a] + variance[b])[wide])
        if known[mine[0]]:
            far = mine[distance[mine] > 0]
            slopes.append(travel[far] / distance[far])
            weights.append(distance[far] ** 2 / variance[far])
    slope, weight = np.concatenate(slopes), np.concatenate(weights)
    return math.nan if slope.size == 0 else _weighted_median(slope, weight)


def _robust_residual(
    travel: np.ndarray, distance: np.ndarray, event: np.ndarray, known: np.ndarray, slowness: float
) -> np.ndarray:
    """Each arrival's misfit at ``slowness``: an event of unknown time placed at the median of
    its arrivals' misfits."""
    residual = travel - slowness * distance
    for g in np.unique(event[~known]):
        mine = event == g
        residual[mine] -= np.median(residual[mine])
    return residual


def _solve(
    y: np.ndarray,
    x: np.ndarray,
    k: np.ndarray,
    e: np.ndarray,
    weight: np.ndarray,
    meters: int,
    clock_tolerance: float,
    times: int,
) -> tuple[float, np.ndarray, np.ndarray]:
    """Weighted least squares for ``(slowness, offsets, times)``: offsets held near 0 by
    ``clock_tolerance`` (none fitted when it is 0), a time for each of the ``times`` events of
    unknown time (``e`` its column, -1 for none; one whose arrivals were all dropped: 0)."""
    fit_offsets = clock_tolerance > 0
    clocks = meters if fit_offsets else 0
    columns = 1 + clocks + times
    a = np.zeros((y.size, columns))
    a[:, 0] = x
    if fit_offsets:
        a[np.arange(y.size), 1 + k] = 1.0
    timed = e >= 0
    a[np.flatnonzero(timed), 1 + clocks + e[timed]] = 1.0
    sw = np.sqrt(weight)
    lhs, rhs = a * sw[:, None], y * sw
    if fit_offsets:  # the prior: each offset ~ N(0, clock_tolerance^2)
        prior = np.zeros((meters, columns))
        prior[np.arange(meters), 1 + np.arange(meters)] = 1.0 / clock_tolerance
        lhs, rhs = np.vstack([lhs, prior]), np.concatenate([rhs, np.zeros(meters)])
    theta, *_ = np.linalg.lstsq(lhs, rhs, rcond=None)
    offsets = theta[1 : 1 + clocks] if fit_offsets else np.zeros(meters)
    shifts = theta[1 + clocks :]
    return float(theta[0]), offsets, shifts


def _relative(residual: np.ndarray, travel: np.ndarray, dt: np.ndarray) -> float:
    """The relative travel-time error ``residual`` shows, once a capture interval's rounding is
    taken out: a robust standard deviation (1.4826 x the median absolute share of each travel
    time), as the search regions' heavy-tailed timing kernel takes the rare large misses."""
    if residual.size == 0:
        return 1.0
    excess = np.sqrt(np.maximum(residual**2 - dt**2 / 12, 0.0)) / np.maximum(travel, dt)
    return 1.4826 * float(np.median(excess))


def _within(residual: np.ndarray, kept: np.ndarray, variance: np.ndarray) -> np.ndarray:
    """The arrivals within :data:`OUTLIER_SIGMAS` spreads of the fit: the spread is the
    median absolute residual of the ``kept`` ones (scaled to a normal's sigma), never below an
    arrival's own timing error (``variance``, s²)."""
    spread = np.maximum(1.4826 * float(np.median(np.abs(residual[kept]))), np.sqrt(variance))
    return np.abs(residual) <= OUTLIER_SIGMAS * spread


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
    y, x, k, dt, e, g = _rows(events, meters)
    if y.size < 3 or np.ptp(x) <= 0:
        raise ConfigError(
            f"the known events give {y.size} arrival(s) at {np.unique(x).size} distance(s): at "
            "least three arrivals at different distances are needed to fit a wave speed"
        )
    tolerance, slowness = wave_speed_tolerance, 1 / wave_speed
    keep = np.ones(y.size, dtype=bool)
    variance = dt**2 / 12 + (tolerance * slowness * x) ** 2 + 1e-12
    start = robust_slowness(y, x, g, e < 0, variance)
    if math.isfinite(start) and start > 0:  # the first pass weighs and trims from there
        slowness = start
        residual = _robust_residual(y, x, g, e < 0, start)
        trimmed = _within(residual, np.ones(y.size, dtype=bool), variance)
        if trimmed.sum() >= 3:
            keep = trimmed
    for _ in range(3):  # fit; weigh by what the fit leaves, drop the outliers; fit again
        variance = dt**2 / 12 + (tolerance * slowness * x) ** 2 + 1e-12
        slowness, offsets, shifts = _solve(
            y[keep],
            x[keep],
            k[keep],
            e[keep],
            1 / variance[keep],
            len(meters),
            clock_tolerance,
            int(e.max(initial=-1)) + 1,
        )
        shift = np.zeros(y.size)
        shift[e >= 0] = shifts[e[e >= 0]]
        residual = y - slowness * x - offsets[k] - shift
        keep = _within(residual, keep, variance)
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
