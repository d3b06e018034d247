"""A network's ringing after a burst, as a meter reports it: a level plus two damped modes
shared by every meter (shared by the steady-level and signature tests)."""

from __future__ import annotations

import numpy as np


def ringing(
    t: np.ndarray, level: np.ndarray, shapes: np.ndarray, dt: float, model: str
) -> np.ndarray:
    """Level plus two shared damped modes, sampled or averaged over (t - dt, t]."""

    def signal(x: np.ndarray) -> np.ndarray:
        m1 = np.exp(-0.03 * x) * np.cos(0.4 * x + 0.3)
        m2 = np.exp(-0.01 * x) * np.sin(1.3 * x)
        return level[None, :] + m1[:, None] * shapes[0] + m2[:, None] * shapes[1]

    if model == "instantaneous":
        return signal(t)
    sub = np.linspace(0, 1, 41)[1:]
    return np.mean([signal(t - dt + f * dt) for f in sub], axis=0)
