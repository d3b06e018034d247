"""Change detection per localization window, on the Rust detectors (paper IV.B, step 3).

The paper runs its detector once per window, per meter, on the *concatenated* window (previous
``interval`` steps + current ``interval`` steps). Two named modes map that call onto the Rust
core; both take a :class:`~burstloc.live.windows.Window` and return the changes per meter
(:class:`~burstloc.localize.evidence.Change`):

``"window"`` (:class:`BatchDetector`, the paper's semantics)
    Every window is analysed from scratch; nothing carries over between windows.

    * CUSUM: ``burstloc.detect_cusum(times, x, threshold, drift, ending=True)`` on each meter's
      column of the concatenated window, exactly TSNet 0.3.1's ``detect_cusum`` (Algorithm 1).
      A meter alarms when it returns at least one change; each change has its start
      ``x``-index, its TSNet end-of-change index and amplitude ``x[end] - x[start]``.
    * Shewhart: ``burstloc.detect_shewhart(x, sigma, threshold)``, Algorithm 2 with the mean
      and (population) standard deviation of the whole concatenated window; each flagged
      sample is a change starting there, amplitude ``|x - mean|``.

``"stream"`` (:class:`StreamingDetector`, the real-time semantics)
    One :class:`burstloc.DetectorBank` channel per meter is fed every complete step exactly
    once, as the window that brings it as *new* arrives (the previous half of a window was fed
    with the window before). Nothing is reset between windows: a CUSUM keeps its sums and start
    indices, a Shewhart chart its trailing reference window. A window's changes are the alarms
    raised by its ``interval`` new steps.

    * CUSUM: the online pass of Algorithm 1 (sample 0 of the stream primes it); a change starts
      at the alarm's ``start`` (TSNet's ``tap``/``tan``), its amplitude is the alarm amplitude
      ``x[alarm] - x[start]`` (no end-of-change estimate: it would need future samples).
    * Shewhart: the reference window is the trailing ``2 * interval`` samples including the
      current one (the length of the paper's concatenated window); no alarm before the stream
      has brought that many; amplitude ``x - mean`` (signed).

:func:`make_detector` builds either from a :class:`DetectorConfig`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Any

import numpy as np

from burstloc import _core
from burstloc.constants import DETECTORS
from burstloc.exceptions import ConfigError, StreamError
from burstloc.localize.evidence import Change
from burstloc.readings import Window

__all__ = [
    "HISTORY",
    "BatchDetector",
    "DetectorConfig",
    "Mode",
    "StreamingDetector",
    "make_detector",
]

#: Steps of timestamps a :class:`StreamingDetector` keeps to date its alarms; a CUSUM change
#: that started longer ago is dated at the oldest kept step.
HISTORY = 65_536

#: The detector kinds of paper section III.


class Mode(str, Enum):
    """How the paper's per-window detector call maps onto detector state (module docstring)."""

    WINDOW = "window"
    STREAM = "stream"


def _positive(name: str, value: float, *, allow_zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ConfigError(f"{name} must be finite and {bound}, got {value!r}")
    return v


@dataclass(frozen=True)
class DetectorConfig:
    """A detector and its parameters.

    ``threshold`` (m): CUSUM's alarm level on the real cumulative sums; Shewhart's absolute
    limit on ``|x - mean|``. ``drift`` (m per sample): CUSUM only. ``sigma``: Shewhart's
    control-limit multiplier ``s`` (eq. 3); ``None`` means equal to ``threshold``, the paper's
    Algorithm 2, which uses its single ``threshold`` for both.
    """

    kind: str
    threshold: float
    drift: float = 0.0
    sigma: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in DETECTORS:
            raise ConfigError(
                f"unknown detector {self.kind!r}; choose one of {', '.join(DETECTORS)}"
            )
        _positive("threshold", self.threshold)
        _positive("drift", self.drift, allow_zero=True)
        if self.sigma is not None:
            _positive("sigma", self.sigma)
        if self.kind == "shewhart" and self.drift != 0.0:
            raise ConfigError("drift applies to the CUSUM only")
        if self.kind == "cusum" and self.sigma is not None:
            raise ConfigError("sigma applies to the Shewhart chart only")

    @property
    def effective_sigma(self) -> float:
        """The Shewhart multiplier in use (``threshold`` when ``sigma`` is ``None``)."""
        return self.threshold if self.sigma is None else float(self.sigma)

    def params(self) -> dict[str, float]:
        """The parameters as a JSON-ready dict (Shewhart's ``sigma`` resolved)."""
        if self.kind == "cusum":
            return {"threshold": float(self.threshold), "drift": float(self.drift)}
        return {"threshold": float(self.threshold), "sigma": self.effective_sigma}


class BatchDetector:
    """The paper's per-window call: each window analysed from scratch (mode ``"window"``)."""

    mode = Mode.WINDOW

    def __init__(self, config: DetectorConfig, meters: Sequence[str]) -> None:
        self.config = config
        self.meters: tuple[str, ...] = tuple(meters)

    def reset(self) -> None:
        """Nothing to forget: batch detection keeps no state between windows."""

    def detect(self, window: Window) -> dict[str, list[Change]]:
        """The changes of every meter in ``window`` (empty lists for meters that did not alarm)."""
        _check_meters(window, self.meters)
        times = np.ascontiguousarray(window.times)
        out: dict[str, list[Change]] = {}
        cfg = self.config
        for j, meter in enumerate(self.meters):
            x = np.ascontiguousarray(window.values[:, j])
            changes: list[Change] = []
            if cfg.kind == "cusum":
                start, end, amp = _core.detect_cusum(times, x, cfg.threshold, cfg.drift, True)
                for s, e, a in zip(start.tolist(), end.tolist(), amp.tolist(), strict=True):
                    changes.append(
                        Change(meter, float(times[s]), float(a), end_time=float(times[e]))
                    )
            else:
                index, amp = _core.detect_shewhart(x, cfg.effective_sigma, cfg.threshold)
                for i, a in zip(index.tolist(), amp.tolist(), strict=True):
                    t = float(times[i])
                    changes.append(Change(meter, t, float(a), alarm_time=t))
            out[meter] = changes
        return out


class StreamingDetector:
    """One Rust bank channel per meter, fed each step once, never reset (mode ``"stream"``)."""

    mode = Mode.STREAM

    def __init__(self, config: DetectorConfig, meters: Sequence[str], interval: int) -> None:
        if isinstance(interval, bool) or not isinstance(interval, (int, np.integer)):
            raise ConfigError(f"localization interval must be an integer, got {interval!r}")
        if interval < 1:
            raise ConfigError(f"localization interval must be >= 1, got {interval}")
        self.config = config
        self.meters: tuple[str, ...] = tuple(meters)
        self.interval = int(interval)
        self._bank = self._new_bank()
        # Timestamps of the most recent steps fed, to date alarm indices: _times[k] is the
        # timestamp of step _offset + k. Bounded to HISTORY steps.
        self._times: list[float] = []
        self._offset = 0

    def _new_bank(self) -> Any:
        cfg = self.config
        n = len(self.meters)
        if cfg.kind == "cusum":
            return _core.DetectorBank("cusum", n, threshold=cfg.threshold, drift=cfg.drift)
        return _core.DetectorBank(
            "shewhart",
            n,
            window=2 * self.interval,
            threshold=cfg.threshold,
            sigma=cfg.effective_sigma,
        )

    def reset(self) -> None:
        """Forget everything (a fresh bank)."""
        self._bank.reset()
        self._times = []
        self._offset = 0

    def _time(self, index: int) -> float:
        return self._times[max(index - self._offset, 0)]

    def detect(self, window: Window) -> dict[str, list[Change]]:
        """Feed the window's new steps to the bank; return the alarms they raised, per meter."""
        _check_meters(window, self.meters)
        new = window.values[window.steps - window.new :]
        new_times = window.times[window.steps - window.new :]
        alarms = self._bank.run(np.ascontiguousarray(new))
        self._times.extend(float(t) for t in new_times)
        out: dict[str, list[Change]] = {m: [] for m in self.meters}
        for a in alarms:
            meter = self.meters[a.channel]
            change = Change(
                meter, self._time(a.start), float(a.amplitude), alarm_time=self._time(a.index)
            )
            out[meter].append(change)
        if len(self._times) > 2 * HISTORY:
            drop = len(self._times) - HISTORY
            del self._times[:drop]
            self._offset += drop
        return out


def _check_meters(window: Window, meters: tuple[str, ...]) -> None:
    if window.meters != meters:
        raise StreamError(
            f"window meters {list(window.meters)} differ from the detector's {list(meters)}"
        )


def make_detector(
    config: DetectorConfig, meters: Sequence[str], interval: int, mode: Mode | str = Mode.WINDOW
) -> BatchDetector | StreamingDetector:
    """Build the detector of ``mode`` (``"window"``: the paper's; ``"stream"``: the bank's)."""
    try:
        m = Mode(mode)
    except ValueError:
        raise ConfigError(f"unknown detection mode {mode!r}; choose 'window' or 'stream'") from None
    if m is Mode.WINDOW:
        return BatchDetector(config, meters)
    return StreamingDetector(config, meters, interval)
