"""Ranked answers of the localizers beyond the paper's rules, and the evidence they read.

Every localizer of :mod:`burstloc.localize.signature`, :mod:`burstloc.localize.arrival` and
:mod:`burstloc.localize.fused`
returns a :class:`Ranking`: every candidate pipe with a score, best first (higher is better), so
that ``evaluate`` can report top-1 and top-3 accuracy. They all read the same input, a
:class:`BurstEvidence`: the readings of the meters around a detected burst plus the first alarm
of each meter. A ranking localizer is anything with ``rank(evidence) -> Ranking``: the
:class:`Localizer` protocol.

The paper's rules (:mod:`burstloc.localize.paper_rules`) and the window detectors
(:mod:`burstloc.localize.detection`) share one record of a detected change, :class:`Change`.

This module imports neither the simulator nor WNTR: it is on the live path.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, overload

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import METER_MODELS, MeterModel
from burstloc.exceptions import InputError
from burstloc.localize.onset import change_start

__all__ = [
    "BurstEvidence",
    "Change",
    "IndexedAlarm",
    "Localizer",
    "MeterAlarm",
    "RankedPipe",
    "Ranking",
    "against_front",
    "evidence_at",
    "evidence_from_alarms",
]


@dataclass(frozen=True)
class RankedPipe:
    """One candidate pipe of a ranking.

    ``start`` and ``end`` are the pipe's end nodes in the steady-state flow direction; ``score`` is
    the localizer's score, higher is better (scores of different localizers are not comparable).
    """

    pipe: str
    start: str
    end: str
    score: float


class Ranking(Sequence[RankedPipe]):
    """Candidate pipes ordered best first (highest score first; equal scores by pipe name).

    ``first``: a pipe placed first whatever its score: the pipe of the answer's named point
    (:mod:`burstloc.localize.center`), which the scores of one localizer need not put first.

    >>> r = Ranking([RankedPipe("a", "n1", "n2", -0.5), RankedPipe("b", "n2", "n3", -0.1)])
    >>> [p.pipe for p in r.top(2)], r.rank_of("a")
    (['b', 'a'], 2)
    >>> [p.pipe for p in Ranking(r, first="a")]
    ['a', 'b']
    """

    def __init__(self, items: Iterable[RankedPipe], *, first: str | None = None) -> None:
        entries = list(items)
        seen: set[str] = set()
        for item in entries:
            if not isinstance(item, RankedPipe):
                raise InputError(f"a Ranking holds RankedPipe items, got {type(item).__name__}")
            if math.isnan(item.score):
                raise InputError(f"pipe {item.pipe!r} has a NaN score")
            if item.pipe in seen:
                raise InputError(f"pipe {item.pipe!r} appears twice in a ranking")
            seen.add(item.pipe)
        if first is not None and first not in seen:
            raise InputError(f"pipe {first!r} to place first is not in the ranking")
        self.first = first
        """The pipe placed first whatever its score (``None``: the best score leads)."""
        self._items: tuple[RankedPipe, ...] = tuple(
            sorted(entries, key=lambda p: (p.pipe != first, -p.score, p.pipe))
        )
        self._rank = {p.pipe: i + 1 for i, p in enumerate(self._items)}

    @overload
    def __getitem__(self, index: int) -> RankedPipe: ...

    @overload
    def __getitem__(self, index: slice) -> Sequence[RankedPipe]: ...

    def __getitem__(self, index: int | slice) -> RankedPipe | Sequence[RankedPipe]:
        """The candidate at ``index`` (0 is the best) or a slice of candidates."""
        return self._items[index]

    def __len__(self) -> int:
        """Number of candidate pipes."""
        return len(self._items)

    def __iter__(self) -> Iterator[RankedPipe]:
        """Candidates, best first."""
        return iter(self._items)

    def __repr__(self) -> str:
        head = ", ".join(f"{p.pipe}:{p.score:.4g}" for p in self._items[:3])
        more = ", ..." if len(self._items) > 3 else ""
        return f"Ranking([{head}{more}])"

    @property
    def best(self) -> RankedPipe | None:
        """The top candidate, or ``None`` for an empty ranking."""
        return self._items[0] if self._items else None

    def head(self, k: int) -> Ranking:
        """The ranking of the ``k`` first candidates, in the same order."""
        kept = self.top(k)
        first = self.first if any(p.pipe == self.first for p in kept) else None
        return Ranking(kept, first=first)

    def top(self, k: int) -> list[RankedPipe]:
        """The ``k`` best candidates (fewer if the ranking is shorter)."""
        if k < 1:
            raise InputError(f"top-k needs k >= 1, got {k}")
        return list(self._items[:k])

    def rank_of(self, pipe: str) -> int | None:
        """1-based rank of ``pipe``, or ``None`` if it is not a candidate."""
        return self._rank.get(pipe)

    def in_top(self, pipe: str, k: int) -> bool:
        """True when ``pipe`` is among the ``k`` best candidates."""
        rank = self.rank_of(pipe)
        return rank is not None and rank <= k

    def scores(self) -> dict[str, float]:
        """Pipe -> score."""
        return {p.pipe: p.score for p in self._items}

    def to_records(self, k: int | None = None) -> list[dict[str, object]]:
        """JSON-ready records ``{"pipe", "start", "end", "score", "rank"}`` of the ``k`` best."""
        items = self._items if k is None else self._items[:k]
        return [
            {"pipe": p.pipe, "start": p.start, "end": p.end, "score": p.score, "rank": i + 1}
            for i, p in enumerate(items)
        ]


@dataclass(frozen=True)
class MeterAlarm:
    """The first alarm a meter raised for the burst: when its change started and how big it was.

    ``start`` is the time stamp (s) of the last reading before the change, as the detector places
    it (the CUSUM's reset point before the alarm); ``amplitude`` is the signed change in metres
    (negative for a drop).
    """

    meter: str
    start: float
    amplitude: float


@dataclass(frozen=True)
class BurstEvidence:
    """What a localizer sees of one burst: the meters' readings and their first alarms.

    ``times`` (T,) are the reading time stamps in seconds, increasing; ``readings`` (T, M) the
    pressure heads in metres, column ``j`` from ``meters[j]``. ``onset`` is the time stamp of the
    last reading before the burst's change, as the detectors place it (the earliest alarm start):
    readings at or before it are the burst-free baseline; readings after it, up to the decision
    time (the last time stamp), show the burst. ``capture_interval`` is the meters' reporting
    period and ``meter_model`` says whether a reading is an instantaneous sample or the mean over
    the interval ending at its time stamp.
    """

    meters: tuple[str, ...]
    times: NDArray[np.float64]
    readings: NDArray[np.float64]
    onset: float
    capture_interval: float
    meter_model: MeterModel = "instantaneous"
    alarms: Mapping[str, MeterAlarm] = field(default_factory=dict)

    def __post_init__(self) -> None:
        times = np.asarray(self.times, dtype=np.float64)
        readings = np.asarray(self.readings, dtype=np.float64)
        meters = tuple(self.meters)
        if len(set(meters)) != len(meters):
            raise InputError("evidence lists a meter twice")
        if times.ndim != 1 or readings.ndim != 2 or readings.shape != (times.size, len(meters)):
            raise InputError(
                f"evidence needs times (T,) and readings (T, {len(meters)}), got "
                f"{times.shape} and {readings.shape}"
            )
        if times.size and not np.all(np.isfinite(times)):
            raise InputError("evidence time stamps must be finite")
        if times.size > 1 and np.any(np.diff(times) <= 0):
            raise InputError("evidence time stamps must increase")
        if not np.all(np.isfinite(readings)):
            raise InputError("evidence readings must be finite (NaN or infinite reading)")
        if not (math.isfinite(self.capture_interval) and self.capture_interval > 0):
            raise InputError(f"capture_interval must be > 0, got {self.capture_interval}")
        if not math.isfinite(self.onset):
            raise InputError(f"onset must be finite, got {self.onset}")
        if self.meter_model not in METER_MODELS:
            raise InputError(f"unknown meter model {self.meter_model!r}; use one of {METER_MODELS}")
        alarms = dict(self.alarms)
        for name, alarm in alarms.items():
            if name not in meters:
                raise InputError(f"alarm for {name!r}, which is not one of the evidence's meters")
            if alarm.meter != name or not (
                math.isfinite(alarm.start) and math.isfinite(alarm.amplitude)
            ):
                raise InputError(f"malformed alarm for meter {name!r}: {alarm}")
        times.setflags(write=False)
        readings.setflags(write=False)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "readings", readings)
        object.__setattr__(self, "meters", meters)
        object.__setattr__(self, "alarms", alarms)

    @property
    def decision_time(self) -> float:
        """Time stamp of the last reading (when the localizer answers)."""
        return float(self.times[-1]) if self.times.size else self.onset

    def columns(self, meters: Sequence[str]) -> NDArray[np.intp]:
        """Column indices of ``meters`` in ``readings`` (an InputError names a missing meter)."""
        index = {m: j for j, m in enumerate(self.meters)}
        missing = [m for m in meters if m not in index]
        if missing:
            raise InputError(f"evidence has no readings for meter(s) {missing}")
        return np.array([index[m] for m in meters], dtype=np.intp)


class Localizer(Protocol):
    """A ranking localizer: every candidate pipe, scored, from one burst's evidence."""

    def rank(self, evidence: BurstEvidence) -> Ranking:
        """Every candidate pipe, best first."""
        ...


@dataclass(frozen=True, slots=True)
class Change:
    """One change a detector found at one meter in a window.

    ``amplitude`` is signed where the detector gives a sign (CUSUM ``x[end] - x[start]``,
    streaming alarms) and absolute for the paper's batch Shewhart (``|x - mean|``).
    Times are timestamps of the stream (s); ``end_time`` is set when the detector estimates
    the end of the change (TSNet-style CUSUM).
    """

    node: str
    start_time: float
    amplitude: float
    alarm_time: float | None = None
    end_time: float | None = None


@dataclass(frozen=True)
class IndexedAlarm:
    """An alarm by reading index, shaped like :class:`burstloc.Alarm` for
    :func:`evidence_from_alarms`: meter column ``channel``, the reading that raised it
    (``index``), the last reading before the change (``start``) and ``amplitude`` (m)."""

    channel: int
    index: int
    start: int
    amplitude: float


def evidence_from_alarms(
    meters: Sequence[str],
    times: NDArray[np.float64],
    readings: NDArray[np.float64],
    alarms: Iterable[Any],
    *,
    capture_interval: float,
    meter_model: MeterModel = "instantaneous",
    decision_time: float | None = None,
    alarm_window: float | None = None,
) -> BurstEvidence:
    """Build the evidence of one burst from a detector bank's alarms.

    ``alarms`` are objects with ``channel`` (meter column), ``index`` (reading that raised the
    alarm), ``start`` (reading where the change started) and ``amplitude``, such as the
    :class:`burstloc.Alarm` items of ``DetectorBank.run``. A start is taken as the last reading
    before the change: the CUSUM's reset point is that already; an alarm whose start is its own
    reading (a Shewhart chart) starts at the reading before. The earliest alarm is the detection;
    each meter keeps its first alarm raised within ``alarm_window`` seconds of it (default: up to
    the decision time); ``onset`` is the earliest start among them. Readings and alarms after
    ``decision_time`` are ignored (default: all readings). At capture intervals up to
    :data:`~burstloc.localize.onset.FITTED_INTERVAL` a start is the change point fitted
    to the readings less half an interval (:func:`~burstloc.localize.onset.change_start`), so
    that the interval an alarm's start allows is centred on it.
    """
    t = np.asarray(times, dtype=np.float64)
    values = np.asarray(readings, dtype=np.float64)
    end = float(t[-1]) if decision_time is None else float(decision_time)
    usable = []
    for alarm in alarms:
        channel = alarm.channel
        index, start = int(alarm.index), int(alarm.start)
        if channel is None or not 0 <= int(channel) < len(meters):
            raise InputError(f"alarm channel {channel!r} is not a meter column")
        if not (0 <= start <= index < t.size):
            raise InputError(f"alarm indices start={start}, index={index} outside the readings")
        if start == index and index > 0:
            start = index - 1  # a chart that flags the changed reading itself (Shewhart)
        if t[index] <= end:
            usable.append((index, start, int(channel), float(alarm.amplitude)))
    if not usable:
        raise InputError("no alarm before the decision time: no burst to localize")
    usable.sort()
    first = t[usable[0][0]]
    limit = end if alarm_window is None else min(end, first + alarm_window)
    per_meter: dict[str, MeterAlarm] = {}
    for index, start, channel, amplitude in usable:
        meter = meters[channel]
        if t[index] <= limit and meter not in per_meter:
            began = change_start(t, values[:, channel], start, index, amplitude, capture_interval)
            per_meter[meter] = MeterAlarm(meter, began, amplitude)
    onset = min(a.start for a in per_meter.values())
    keep = t <= end
    return BurstEvidence(
        meters=tuple(meters),
        times=t[keep],
        readings=values[keep],
        onset=onset,
        capture_interval=capture_interval,
        meter_model=meter_model,
        alarms=per_meter,
    )


def evidence_at(
    decided: float,
    meters: Sequence[str],
    times: NDArray[np.float64],
    readings: NDArray[np.float64],
    alarms: Iterable[Any],
    calibration: Any,
    meter_model: MeterModel,
    *,
    alarm_window: float | None = None,
) -> BurstEvidence:
    """:func:`evidence_from_alarms` at reading time ``decided`` with a calibration's capture
    interval and alarm window (``alarm_window`` s, default its ``arrival_decision_delay``): the
    evidence every ranking localizer and the classifier read."""
    return evidence_from_alarms(
        meters,
        times,
        readings,
        alarms,
        capture_interval=calibration.capture_interval,
        meter_model=meter_model,
        decision_time=decided,
        alarm_window=calibration.arrival_decision_delay if alarm_window is None else alarm_window,
    )


def against_front(evidence: BurstEvidence, meters: Sequence[str]) -> NDArray[np.bool_]:
    """Per meter of ``meters`` (all alarmed), whether its alarm's change has the sign opposite
    to the first front's (the earliest alarm's; among alarms at one start, the largest's). A
    burst's first front is a drop everywhere it arrives; a meter that alarmed on a rise heard
    some later wave (a reflection) after a first front too weak to alarm on, so its alarm says
    only that the first front came no later."""
    alarms = [evidence.alarms[m] for m in meters]
    if not alarms:
        return np.zeros(0, dtype=np.bool_)
    first = min(alarms, key=lambda a: (a.start, -abs(a.amplitude)))
    sign = math.copysign(1.0, first.amplitude) if first.amplitude != 0 else 0.0
    return np.array([a.amplitude * sign < 0 for a in alarms], dtype=np.bool_)
