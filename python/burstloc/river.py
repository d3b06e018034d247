"""burstloc's detectors as River drift detectors (optional: ``pip install burstloc[river]``).

:class:`Cusum` and :class:`Shewhart` follow River's drift-detector protocol
(``river.base.DriftDetector``): ``update(x)`` per sample, the ``drift_detected`` property,
``_reset()``, keyword parameters with defaults stored as attributes of the same name (so
``repr``, ``clone`` and ``_get_params`` work as for River's own detectors). The detection itself
is burstloc's Rust core, exactly as :class:`burstloc.Cusum` and :class:`burstloc.Shewhart`
compute it; ``last_alarm`` holds the core's alarm (start index, direction, amplitude).

Unlike River's ``PageHinkley``, a detector here is not reset after a drift: the CUSUM resets
its own sums when it alarms (TSNet's rule) and the Shewhart chart keeps its window, so the
alarms are those of the paper's detectors.

This module imports River; ``import burstloc`` never does. ``python -m burstloc.river`` prints
the comparison of :func:`compare_on_change_point_datasets`.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

try:
    from river.base import DriftDetector
except ImportError as err:  # pragma: no cover - exercised only without the extra
    raise ImportError("burstloc.river needs River: pip install 'burstloc[river]'") from err

from ._core import Alarm
from ._core import Cusum as _Cusum
from ._core import Shewhart as _Shewhart

__all__ = [
    "Cusum",
    "DatasetResult",
    "Shewhart",
    "compare_on_change_point_datasets",
    "score_detections",
]


class _CoreDetector(DriftDetector):
    """The River protocol around one of burstloc's core detectors (made by ``_make``)."""

    def _make(self) -> _Cusum | _Shewhart:
        raise NotImplementedError

    def _reset(self) -> None:
        super()._reset()
        self._detector = self._make()
        self.last_alarm: Alarm | None = None

    def update(self, x: int | float) -> None:
        """Feeds one sample; ``drift_detected`` tells whether it raised an alarm."""
        alarm = self._detector.update(float(x))
        self._drift_detected = alarm is not None
        if alarm is not None:
            self.last_alarm = alarm


class Cusum(_CoreDetector):
    """Two-sided CUSUM (TSNet's ``detect_cusum``, online; burstloc's Rust core) for River.

    Parameters
    ----------
    threshold
        Change (in the signal's units) that raises an alarm; finite and > 0.
    drift
        Subtracted from every step of the drift-corrected sums; finite and >= 0.

    Examples
    --------
    >>> from burstloc.river import Cusum
    >>> detector = Cusum(threshold=0.5, drift=0.01)
    >>> heads = [200.0, 200.01, 199.99] * 20 + [198.5] * 20
    >>> for i, x in enumerate(heads):
    ...     detector.update(x)
    ...     if detector.drift_detected:
    ...         print(f"change detected at index {i}: {detector.last_alarm.direction}")
    change detected at index 60: drop
    """

    def __init__(self, threshold: float = 0.5, drift: float = 0.0) -> None:
        super().__init__()
        self.threshold = threshold
        self.drift = drift
        self._reset()

    def _make(self) -> _Cusum:
        return _Cusum(self.threshold, self.drift)


class Shewhart(_CoreDetector):
    """Shewhart control chart over a sliding window (the paper's Algorithm 2) for River.

    Parameters
    ----------
    window
        Samples in the window, the current one included (>= 2).
    threshold
        Minimum distance to the window mean for an alarm (> 0).
    sigma
        Width of the control limits in window standard deviations (> 0); ``None`` takes the
        threshold (the paper's single parameter).

    Examples
    --------
    >>> from burstloc.river import Shewhart
    >>> detector = Shewhart(window=20, threshold=0.5, sigma=3.0)
    >>> heads = [200.0, 200.01, 199.99] * 20 + [198.5] * 20
    >>> detections = []
    >>> for i, x in enumerate(heads):
    ...     detector.update(x)
    ...     if detector.drift_detected:
    ...         detections.append(i)
    >>> detections[0]
    60
    """

    def __init__(self, window: int = 50, threshold: float = 0.5, sigma: float | None = None):
        super().__init__()
        self.window = window
        self.threshold = threshold
        self.sigma = sigma
        self._reset()

    def _make(self) -> _Shewhart:
        return _Shewhart(self.window, self.threshold, self.sigma)


def detections(detector: DriftDetector, values: Iterable[float]) -> list[int]:
    """Indices where ``detector`` reports a drift (River's ``perform_test`` loop)."""
    found = []
    for i, x in enumerate(values):
        detector.update(x)
        if detector.drift_detected:
            found.append(i)
    return found


@dataclass(frozen=True)
class DatasetResult:
    """One detector on one annotated series."""

    dataset: str
    detector: str
    samples: int
    change_points: int
    detections: int
    detected: int  # change points followed by a detection within the margin
    mean_delay: float  # samples from a change point to its first detection (nan if none)
    false_alarms: int  # detections within the margin of no change point


def score_detections(
    found: list[int], change_points: list[int], margin: int
) -> tuple[int, float, int]:
    """(change points detected, mean delay, false alarms) of detections ``found``.

    A change point ``c`` is detected by the first detection in ``[c, c + margin]``; the delay
    is that detection's index minus ``c``. A detection in no such interval is a false alarm.
    """
    delays = []
    for c in change_points:
        first = next((d for d in found if c <= d <= c + margin), None)
        if first is not None:
            delays.append(first - c)
    false_alarms = sum(not any(c <= d <= c + margin for c in change_points) for d in found)
    mean = sum(delays) / len(delays) if delays else math.nan
    return len(delays), mean, false_alarms


#: River's annotated change-point datasets that ship in the package (no download), with the
#: variable monitored. ``BrentSpotPrice`` is left out: River's CSV (8,195 days) is not the
#: series its annotations index (the Turing change-point benchmark's 500 points).
DATASETS: dict[str, str | None] = {
    "AirlinePassengers": None,
    "Apple": "Close",
    "Bitcoin": None,
    "Occupancy": "V1",
    "RunLog": "Pace",
    "UKCoalEmploy": None,
}


def _series(name: str) -> tuple[list[float], list[int]]:
    """The values (scaled, see below) and the union of the annotators' change points."""
    from river.drift import datasets

    dataset = getattr(datasets, name)()
    column = DATASETS[name]
    values = [float(y if column is None else y[column]) for _, y in dataset]
    points = sorted({c for marks in dataset.annotations.values() for c in marks})
    # One scale for every detector: the median absolute first difference over the first
    # fifth of the series (a calibration period), so thresholds are in units of its noise.
    head = values[: max(len(values) // 5, 3)]
    steps = sorted(abs(b - a) for a, b in itertools.pairwise(head))
    scale = steps[len(steps) // 2] or 1.0
    return [v / scale for v in values], points


def _detectors() -> Iterator[tuple[str, DriftDetector]]:
    from river.drift import PageHinkley

    yield "burstloc Cusum(threshold=8, drift=1)", Cusum(threshold=8.0, drift=1.0)
    yield "burstloc Shewhart(window=20, threshold=4, sigma=3)", Shewhart(20, 4.0, 3.0)
    yield "River PageHinkley() (defaults)", PageHinkley()


def compare_on_change_point_datasets(margin_fraction: float = 0.05) -> list[DatasetResult]:
    """Every detector of :func:`_detectors` on every series of :data:`DATASETS`.

    Series are divided by their calibration scale (see ``_series``); the margin is
    ``max(5, margin_fraction * samples)`` samples.
    """
    rows = []
    for name in DATASETS:
        values, points = _series(name)
        margin = max(5, int(margin_fraction * len(values)))
        for label, detector in _detectors():
            found = detections(detector, values)
            detected, delay, false_alarms = score_detections(found, points, margin)
            rows.append(
                DatasetResult(
                    name, label, len(values), len(points), len(found), detected, delay, false_alarms
                )
            )
    return rows


def format_table(rows: list[DatasetResult]) -> str:
    """A Markdown table of ``rows``."""
    lines = [
        "| dataset | detector | samples | change points | detections | detected | mean delay"
        " | false alarms |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        delay = "-" if math.isnan(r.mean_delay) else f"{r.mean_delay:.1f}"
        lines.append(
            f"| {r.dataset} | {r.detector} | {r.samples} | {r.change_points} | {r.detections}"
            f" | {r.detected} | {delay} | {r.false_alarms} |"
        )
    return "\n".join(lines)


if __name__ == "__main__":
    print(format_table(compare_on_change_point_datasets()))
