"""The *arrival* localizer: which pipe explains when each meter saw the burst's pressure wave.

A burst sends a pressure wave through the network at the wave speed ``a``; it reaches meter ``m``
after ``dist(point, m) / a``, where ``dist`` is the shortest path length along the pipes (the
network as an undirected graph weighted by pipe length). The burst time is unknown, so each
candidate point is fitted with a free time offset ``t0``. The meters' alarm starts are only known
to a capture interval ``dt`` (a start stamp ``tau`` means the change arrived between ``tau`` and
``tau + dt``), so the misfit of meter ``m`` is the distance from ``t0 + dist / a`` to the interval
``[tau_m, tau_m + dt]``. Meters that read but stay silent until the decision time ``T`` add a
one-sided constraint: their wave must not have arrived before ``T - 2 dt`` (this is what tells a
pipe from its neighbours when only one end node has a meter), but only those that would have
heard the candidate's wave (:func:`burstloc.localize.windows.silence_counts`): a burst on a
large main moves far heads by less than the detectors' threshold, and their silence then says
nothing about when the wave came. ``t0`` minimises the sum of squared misfits (a convex
problem: :func:`burstloc.localize.windows.fit_windows`). A pipe's candidate points are
interior points along it (default ``0.1, 0.2, ..., 0.9`` of its length); the pipe keeps its best
point.

A burst's first front is a drop wherever it arrives. A far meter whose first front was too weak
to alarm on often alarms later, on a rise (a reflection): an alarm whose change has the sign
opposite to the first front's
(:func:`~burstloc.localize.evidence.against_front`) says only that the front came no later,
and its window is open towards earlier times (``lo`` an arrival horizon before ``hi``), at
capture intervals of :data:`RESOLVED_FRONT_INTERVAL` and finer: at coarser ones a reading holds
the front and the waves after it, and its change's sign says nothing of which came first. A burst
on L-TOWN's pipe p30 at 0.01 s (BattLeDIM's sensors, 2.04 L/s): six of the seven meters that
alarmed on a drop timed its first front within 13 ms; the five that alarmed on a rise did so
0.09-2.4 s after the front had reached them, and drew the answer to a pipe 455 m away.

Score (higher is better) = ``-(RMS misfit) / dt + amplitude_weight * A``, where ``A`` in [0, 1]
is the mean absolute alarm amplitude at the pipe's two end nodes relative to the largest alarm
amplitude: amplitudes only break (near) ties, e.g. at coarse capture intervals where many pipes
fit the arrival pattern equally well.

Position along the named pipe (:meth:`ArrivalLocalizer.position`): the same fit on points every
metre along that pipe gives the burst's distance from the pipe's start node (flow direction) with
an interval. One capture interval of timing error is ``wave_speed x dt`` metres of wave travel
(240 m at 0.2 s and 1200 m/s), so at best the interval is that long; where every meter lies beyond
one end of the pipe the arrivals cannot tell its points apart and the interval is the whole pipe.

The geometry (flow-direction end nodes and length of every pipe, shortest path lengths from the
pipes' end nodes to the meters) is computed offline
(:func:`burstloc.sim.model.prepare.arrival_geometry`)
and stored with the calibrated configuration (:class:`burstloc.localize.model.LocalizationModel`);
ranking is numpy only and on the live path.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import (
    CANDIDATE_POSITIONS,
    CLOCK_TOLERANCE,
    WAVE_SPEED,
    WAVE_SPEED_TOLERANCE,
)
from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.evidence import BurstEvidence, RankedPipe, Ranking, against_front
from burstloc.localize.pipes import PipeGeometry, PipePosition
from burstloc.localize.windows import fit_windows, silence_counts

__all__ = [
    "POSITION_STEP",
    "RESOLVED_FRONT_INTERVAL",
    "ArrivalLocalizer",
    "position_tolerance",
]

RESOLVED_FRONT_INTERVAL = 0.1
"""The coarsest capture interval (s) at which an alarm on a change of the sign opposite to the
first front's is taken as a later wave's (module docstring): a burst opening in 0.3 s spreads its
front over three such readings."""

DEFAULT_POSITIONS = CANDIDATE_POSITIONS
"""Candidate burst positions along each pipe
(:data:`burstloc.localize.evidence.CANDIDATE_POSITIONS`)."""


def position_tolerance(alarms: int) -> float:
    """Extra RMS misfit (capture intervals) a point inside the position interval may have over
    the best point, with ``alarms`` alarmed meters: the quantisation noise of an RMS over that
    many alarm starts, ``1 / sqrt(12 alarms)`` (each start is known to one capture interval,
    uniform noise of standard deviation ``1 / sqrt(12)``; the same noise sets the fused
    localizer's decisive margin, :func:`burstloc.localize.fused.quantisation_margin`)."""
    if alarms < 1:
        raise InputError(f"a position needs at least one alarm, got {alarms}")
    return 1.0 / math.sqrt(12.0 * alarms)


POSITION_STEP = 1.0
"""Spacing (m) of the points tried along the named pipe when estimating the burst position (at
least 50 and at most 2,000 points per pipe)."""


def _horizon(dist: NDArray[np.float64]) -> float:
    """The longest spread (m) of the path lengths from one candidate point to the meters it
    reaches (``dist``: (pipes, points, meters); unreachable meters are infinite)."""
    finite = np.isfinite(dist)
    if not finite.any():
        return 0.0
    near = np.where(finite, dist, np.inf).min(axis=2)
    far = np.where(finite, dist, -np.inf).max(axis=2)
    spread = np.where(finite.any(axis=2), far - near, 0.0)
    return float(spread.max())


class ArrivalLocalizer:
    """Rank pipes by how well wave travel from a point on them explains the meters' alarm starts.

    ``distances[i, j]`` is the shortest path length (m) from ``nodes[i]`` to ``meters[j]``;
    ``pipes`` the candidates. Build it from a stored model
    (:meth:`burstloc.localize.decide.RankingLocalizers.from_model`) or, offline, from a network
    (:func:`burstloc.sim.model.prepare.arrival_localizer`).
    """

    def __init__(
        self,
        pipes: Sequence[PipeGeometry],
        meters: Sequence[str],
        node_distances: Mapping[str, NDArray[np.float64]],
        *,
        wave_speed: float = WAVE_SPEED,
        positions: Iterable[float] = DEFAULT_POSITIONS,
        amplitude_weight: float = 0.05,
        decision_delay: float | None = None,
        silence: bool = True,
        fronts: Mapping[str, NDArray[np.float64]] | None = None,
        wave_speed_tolerance: float = WAVE_SPEED_TOLERANCE,
        clock_tolerance: float = CLOCK_TOLERANCE,
        clock_offsets: Mapping[str, float] | None = None,
        timing_factor: float = 1.0,
        connectors: Sequence[tuple[str, str, float]] = (),
    ) -> None:
        if not (math.isfinite(wave_speed) and wave_speed > 0):
            raise ConfigError(f"wave_speed must be > 0 m/s, got {wave_speed}")
        if not (math.isfinite(wave_speed_tolerance) and 0 <= wave_speed_tolerance <= 1):
            raise ConfigError(f"wave_speed_tolerance must be in [0, 1], got {wave_speed_tolerance}")
        if not (math.isfinite(clock_tolerance) and clock_tolerance >= 0):
            raise ConfigError(f"clock_tolerance must be >= 0 s, got {clock_tolerance}")
        self.wave_speed_tolerance = float(wave_speed_tolerance)
        """Relative uncertainty of a travel time along a path (the search regions' timing
        error grows with the path: :func:`burstloc.localize.timing_error.timing_scale`)."""
        self.clock_tolerance = float(clock_tolerance)
        """Uncertainty (s) of each meter's clock."""
        if not (math.isfinite(timing_factor) and timing_factor >= 1):
            raise ConfigError(f"timing_factor must be >= 1, got {timing_factor}")
        self.timing_factor = float(timing_factor)
        """The search regions' timing error over the stated one, as simulated bursts showed it
        at this capture interval (:mod:`burstloc.experiments.region_spread`)."""
        pos = np.array(sorted(set(float(x) for x in positions)), dtype=np.float64)
        if pos.size == 0 or np.any(pos < 0) or np.any(pos > 1):
            raise ConfigError("positions must be fractions in [0, 1] (at least one)")
        if not (math.isfinite(amplitude_weight) and amplitude_weight >= 0):
            raise ConfigError(f"amplitude_weight must be >= 0, got {amplitude_weight}")
        if not pipes:
            raise ConfigError("no candidate pipes")
        self.meters = tuple(meters)
        known = clock_offsets or {}
        self.clock_offsets = np.array([float(known.get(m, 0.0)) for m in self.meters])
        """How late (s) each meter hears a wave (known events' fit): taken off its alarm
        start."""
        if not np.all(np.isfinite(self.clock_offsets)):
            raise ConfigError("clock offsets must be finite numbers of seconds")
        self.pipes = tuple(pipes)
        self.connectors = tuple(connectors)
        """The network's other links joining the pipes, ``(start, end, length m)``: a crew's
        paths (:class:`~burstloc.localize.model.LocalizationModel`)."""
        self.wave_speed = float(wave_speed)
        self.positions = pos
        self.amplitude_weight = float(amplitude_weight)
        self.silence = bool(silence)
        for p in self.pipes:
            for node in (p.start, p.end):
                if node not in node_distances:
                    raise ConfigError(f"no distances from node {node!r} (pipe {p.pipe!r})")
                if np.shape(node_distances[node]) != (len(self.meters),):
                    raise ConfigError(f"distances from {node!r} must have one value per meter")
        # (pipes, positions, meters): path length from each candidate point to each meter
        d_start = np.array([node_distances[p.start] for p in self.pipes], dtype=np.float64)
        d_end = np.array([node_distances[p.end] for p in self.pipes], dtype=np.float64)
        length = np.array([p.travel for p in self.pipes], dtype=np.float64)
        self._ends = list(zip(d_start, d_end, strict=True))
        self.end_distances = (d_start, d_end)
        """Path lengths (m) from each pipe's start and end node to each meter, (pipes, meters)
        each (metres of wave travel at ``wave_speed`` where pipes have speeds of their own)."""
        self.stretch = np.array([p.stretch for p in self.pipes], dtype=np.float64)
        """Per pipe, metres of wave travel per metre of pipe (:class:`PipeGeometry`)."""
        self._fronts: NDArray[np.float64] | None = None
        if fronts is not None:
            missing = [p.pipe for p in self.pipes if p.pipe not in fronts]
            if missing:
                raise ConfigError(f"no wave fronts for pipe(s) {missing[:5]}")
            self._fronts = np.array([fronts[p.pipe] for p in self.pipes], dtype=np.float64)
            if self._fronts.shape != (len(self.pipes), len(self.meters)):
                raise ConfigError("wave fronts must have one value per meter")
        along = pos[None, :, None] * length[:, None, None]
        self._dist = np.minimum(
            along + d_start[:, None, :], (length[:, None, None] - along) + d_end[:, None, :]
        )
        self.pipe_travel = float(np.median(length)) / self.wave_speed
        """Median wave travel time (s) along one candidate pipe."""
        self.longest_travel = float(length.max()) / self.wave_speed
        """The longest wave travel time (s) along one candidate pipe."""
        nearest = self._dist[:, int(np.argmin(np.abs(pos - 0.5))), :].min(axis=1)
        nearest = nearest[np.isfinite(nearest)]  # a pipe no meter is reached from counts not
        self.meter_travel = (
            float(np.median(nearest)) / self.wave_speed if nearest.size else self.pipe_travel
        )
        """Median wave travel time (s) from a candidate pipe's middle to the meter nearest it:
        where meters are few, what the arrivals must time is a burst's place among them, not one
        pipe against its neighbour."""
        self.decision_delay = (
            float(decision_delay) if decision_delay is not None else self.pipe_travel
        )
        """How long after the first alarm the localizer first looks at the arrivals (default:
        ``pipe_travel``: by then the wave has reached both ends of the burst pipe)."""
        self.horizon = _horizon(self._dist) / self.wave_speed
        """Wave travel time (s) from the first meter a burst's wave reaches to the last one it
        reaches, the longest over the candidate points: the latest a look at the arrivals can
        learn from (:func:`burstloc.localize.decide.rank_alarms` looks until then)."""

    def misfit(self, evidence: BurstEvidence) -> NDArray[np.float64]:
        """RMS arrival misfit (s) of every pipe's best candidate point, shape (pipes,).

        Alarmed meters contribute their distance to ``[tau, tau + dt]``. With ``silence`` on, a
        meter that reads but has not alarmed by the decision time ``T`` says the wave has not
        reached it before ``T - 2 dt`` (one interval for the stamp, one for the detector): a
        candidate whose wave would have arrived earlier pays the difference. With wave fronts
        (``fronts``), only the silent meters that would have heard the candidate's wave do
        (:func:`silence_counts`); the others add no misfit (and still count in the mean, so
        that every candidate's RMS is over the same meters). Needs at least one alarm among the
        meters.
        """
        return np.asarray(self._rms(self._dist, evidence).min(axis=1), dtype=np.float64)

    def columns(self, evidence: BurstEvidence) -> tuple[list[int], list[int]]:
        """The meters :meth:`windows` gives a window to, as columns of :attr:`meters`: the
        alarmed ones, then (with ``silence`` on) the silent ones that read."""
        alarmed = [j for j, m in enumerate(self.meters) if m in evidence.alarms]
        silent: list[int] = []
        if self.silence:
            reading = set(evidence.meters)
            silent = [
                j for j, m in enumerate(self.meters) if m not in evidence.alarms and m in reading
            ]
        return alarmed, silent

    def windows(
        self,
        dist: NDArray[np.float64],
        evidence: BurstEvidence,
        rows: slice | list[int] = slice(None),
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_], int]:
        """The burst times ``t0`` each meter allows at candidate points: ``(lo, hi, reach,
        alarmed)``.

        ``dist`` (..., points, meters): path lengths from candidate points to the meters, of the
        pipes ``self.pipes[rows]`` along the first axis (for their wave fronts). ``lo`` / ``hi``
        (..., points, K): for each of the ``alarmed`` alarmed meters first, then each silent
        reading meter, the interval of ``t0`` that puts its wave in its capture interval (an
        alarm) or after the decision time less two intervals (a silence: ``hi`` infinite);
        ``-inf`` where the point's wave does not reach the meter, or a silence says nothing
        (:func:`silence_counts`); ``reach`` where the wave reaches the meter (a silence that
        says nothing still counts in an RMS, so that every point's is over the same meters).

        Raises:
            InputError: no meter of the model has alarmed.
        """
        alarmed, silent = self.columns(evidence)
        if not alarmed:
            raise InputError("no meter of the arrival model has alarmed: nothing to localize")
        dt = evidence.capture_interval
        tau = np.array([evidence.alarms[self.meters[j]].start for j in alarmed])
        tau = tau - self.clock_offsets[alarmed]
        lo_parts = [tau[None, None, :] - dist[:, :, alarmed] / self.wave_speed]
        hi_parts = [lo_parts[0] + dt]
        against = np.zeros(len(alarmed), dtype=np.bool_)
        if dt <= RESOLVED_FRONT_INTERVAL:
            against = against_front(evidence, [self.meters[j] for j in alarmed])
        if against.any():  # a later wave's alarm: the first front came no later than it
            lo_parts[0] = np.where(against, hi_parts[0] - max(self.horizon, 10 * dt), lo_parts[0])
        if silent:  # (empty with silence off)
            bound = evidence.decision_time - 2 * dt
            lo_parts.append(bound - dist[:, :, silent] / self.wave_speed)
            hi_parts.append(np.full_like(lo_parts[-1], np.inf))
        lo = np.concatenate(lo_parts, axis=2)  # t0 values that put each arrival in its window
        hi = np.concatenate(hi_parts, axis=2)
        reach = np.isfinite(lo)
        if self._fronts is not None and silent:
            heard = silence_counts(self._fronts[rows], alarmed, silent)
            lo[:, :, len(alarmed) :] = np.where(
                heard[:, None, :], lo[:, :, len(alarmed) :], -np.inf
            )
        return lo, hi, reach, len(alarmed)

    def gaps(
        self,
        dist: NDArray[np.float64],
        evidence: BurstEvidence,
        rows: slice | list[int] = slice(None),
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.bool_]]:
        """Each meter's timing misfit (s) at candidate points, with the burst time fitted.

        For each point of :meth:`windows` the burst time ``t0`` minimises the sum of squared
        misfits (:meth:`misfit`); returns ``(gap, counted, placed)``: ``gap`` (..., points, K)
        each meter's distance from ``t0`` to its window (0 where it says nothing),
        ``counted`` where a meter takes part (its wave reaches the point), and ``placed``
        (..., points) whether the point reaches some alarmed meter at all (``False``: it cannot
        explain the alarms).

        Raises:
            InputError: no meter of the model has alarmed.
        """
        lo, hi, finite, count = self.windows(dist, evidence, rows)
        gap, placed = fit_windows(lo, hi, count, evidence.capture_interval)
        return gap, finite, placed

    def _rms(
        self,
        dist: NDArray[np.float64],
        evidence: BurstEvidence,
        rows: slice | list[int] = slice(None),
    ) -> NDArray[np.float64]:
        """RMS misfit (s) of candidate points whose path lengths to the meters are ``dist``
        (shape ``(pipes, points, meters)``; the pipes are ``self.pipes[rows]``), shape
        ``(pipes, points)`` (see :meth:`misfit`)."""
        gap, finite, placed = self.gaps(dist, evidence, rows)
        count = np.maximum(finite.sum(axis=2), 1)
        rms = np.sqrt(np.sum(gap**2, axis=2) / count)
        rms = np.where(placed, rms, np.inf)
        return np.asarray(rms, dtype=np.float64)

    def position(self, evidence: BurstEvidence, pipe: str) -> PipePosition:
        """Where on ``pipe`` the burst is, from the arrival fit (module docstring).

        Points every :data:`POSITION_STEP` metres along the pipe, ends included, are fitted as in
        :meth:`misfit`. The estimate is the middle of the best-fitting stretch (the points whose
        misfit equals the smallest one: with alarm starts known to one capture interval ``dt``,
        a stretch about ``wave_speed x dt`` long where meters lie beyond both ends); the interval
        spans the points within :func:`position_tolerance` capture intervals of the best misfit
        (the whole pipe when the meters cannot tell its points apart).

        Raises:
            InputError: ``pipe`` is not a candidate, or no meter of the model has alarmed.
        """
        index = {p.pipe: i for i, p in enumerate(self.pipes)}
        if pipe not in index:
            raise InputError(f"pipe {pipe!r} is not a candidate of the arrival localizer")
        geo = self.pipes[index[pipe]]
        count = int(np.clip(math.ceil(geo.length / POSITION_STEP), 49, 1999)) + 1
        along = np.linspace(0.0, geo.length, count)
        d_start, d_end = self._ends[index[pipe]]
        wave = along * geo.stretch
        dist = np.minimum(wave[:, None] + d_start, (geo.travel - wave)[:, None] + d_end)
        rms = self._rms(dist[None], evidence, [index[pipe]])[0]
        best = float(rms.min())
        dt = evidence.capture_interval
        if not math.isfinite(best):
            return PipePosition(
                pipe, geo.start, geo.end, geo.length, geo.length / 2, 0.0, geo.length
            )
        flat = along[rms <= best + 1e-6 * dt]
        alarmed = sum(m in evidence.alarms for m in self.meters)
        near = along[rms <= best + position_tolerance(alarmed) * dt]
        return PipePosition(
            pipe,
            geo.start,
            geo.end,
            geo.length,
            float(0.5 * (flat.min() + flat.max())),
            float(near.min()),
            float(near.max()),
        )

    def amplitude_term(self, evidence: BurstEvidence) -> NDArray[np.float64]:
        """Per pipe, the mean absolute alarm amplitude at its end nodes over the largest one."""
        amps = {m: abs(a.amplitude) for m, a in evidence.alarms.items()}
        top = max(amps.values(), default=0.0)
        if top <= 0:
            return np.zeros(len(self.pipes))
        return np.array(
            [(amps.get(p.start, 0.0) + amps.get(p.end, 0.0)) / (2 * top) for p in self.pipes]
        )

    def rank(self, evidence: BurstEvidence) -> Ranking:
        """Every pipe, best first; see the module docstring for the score."""
        rms = self.misfit(evidence)
        score = -rms / evidence.capture_interval + self.amplitude_weight * self.amplitude_term(
            evidence
        )
        score = np.where(np.isfinite(score), score, -1e12)
        return Ranking(
            RankedPipe(p.pipe, p.start, p.end, float(s))
            for p, s in zip(self.pipes, score, strict=True)
        )
