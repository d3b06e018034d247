"""Hypothesis strategies for pressure-like signals (shared by the detector tests).

A signal is a chain of segments (flat runs, steps up or down, ramps, noisy stretches,
plateaus that come back) around a base level, optionally with sensor noise, scaled by a power
of ten from 1e-6 to 1e6 so that tiny and huge amplitudes are both covered.
"""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

KINDS = ("flat", "step", "ramp", "noise", "plateau")
SEGMENT = st.tuples(
    st.sampled_from(KINDS),
    st.integers(min_value=1, max_value=3000),
    st.floats(min_value=-5.0, max_value=5.0, allow_nan=False, allow_infinity=False),
)


def build_signal(
    n: int,
    base: float,
    scale: float,
    segments: list[tuple[str, int, float]],
    noise: float,
    seed: int,
) -> np.ndarray:
    """Assemble ``n`` samples from ``segments`` (repeated flat at the end if they run short)."""
    rng = np.random.default_rng(seed)
    level = base * scale
    parts = []
    for kind, length, amplitude in segments:
        size = amplitude * scale
        if kind == "flat":
            part = np.full(length, level)
        elif kind == "step":
            level += size
            part = np.full(length, level)
        elif kind == "ramp":
            part = level + np.linspace(0.0, size, length)
            level = float(part[-1])
        elif kind == "noise":
            part = level + rng.normal(0.0, abs(size) * 0.1 + 1e-300, length)
        else:  # plateau: up (or down) for a while, then back
            part = np.full(length, level + size)
        parts.append(part)
    x = np.concatenate(parts) if parts else np.empty(0)
    if x.size < n:
        x = np.concatenate([x, np.full(n - x.size, level)])
    x = x[:n].copy()
    if noise > 0.0:
        x += rng.normal(0.0, noise * scale, n)
    return x


@st.composite
def pressure_signals(draw: st.DrawFn, min_size: int = 2, max_size: int = 10_000) -> np.ndarray:
    """A float64 pressure-like trace of ``min_size`` to ``max_size`` samples."""
    # Half of the draws are long (hypothesis otherwise favours short signals).
    long = st.integers(min_value=max(min_size, max_size // 2), max_value=max_size)
    n = draw(st.integers(min_value=min_size, max_value=max_size) | long)
    exponent = draw(st.integers(min_value=-6, max_value=6))
    base = draw(st.floats(min_value=-100.0, max_value=100.0, allow_nan=False))
    segments = draw(st.lists(SEGMENT, min_size=1, max_size=8))
    noise = draw(st.sampled_from([0.0, 0.0, 1e-4, 1e-2, 0.1]))
    seed = draw(st.integers(min_value=0, max_value=2**32 - 1))
    return build_signal(n, base, 10.0**exponent, segments, noise, seed)


def signal_scale(x: np.ndarray) -> float:
    """A typical step size of ``x`` (for choosing thresholds in proportion), never zero."""
    if x.size < 2:
        return 1.0
    spread = float(np.max(x) - np.min(x))
    return spread if spread > 0.0 else max(abs(float(x[0])), 1.0)


@st.composite
def cusum_parameters(draw: st.DrawFn, x: np.ndarray) -> tuple[float, float]:
    """``(threshold, drift)`` in proportion to the signal's range: from hair-trigger to deaf."""
    scale = signal_scale(x)
    threshold = scale * draw(st.floats(min_value=1e-3, max_value=2.0))
    drift = scale * draw(st.sampled_from([0.0, 0.0, 1e-4, 1e-3, 1e-2, 0.1]))
    return threshold, drift
