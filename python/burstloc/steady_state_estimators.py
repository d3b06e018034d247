"""Estimators of the new steady pressure level after a burst, from a short window of readings.

After a burst TSNet's network rings: slowly decaying oscillations of a few tenths of a metre, with
periods of seconds to tens of seconds and shared by all meters (the network's hydraulic modes),
sit on top of a lasting drop of a few centimetres to a few metres. Readings every 2-10 s alias
these oscillations, so a plain mean of the post-burst readings is off by centimetres to
decimetres, while the signature localizer needs the lasting drop to millimetres.

Estimators (``method``), each returning one level per meter:

* ``"mean"`` and ``"median"`` of the readings;
* ``"damped-fit"``: every meter's readings are fitted jointly with a level per meter plus up to
  ``modes`` damped sinusoids whose frequency and decay rate are shared by all meters
  (each meter gets its own amplitude and phase), by variable projection: the shared nonlinear
  parameters are searched on a grid then refined, the per-meter linear ones solved in closed form.
  For interval-averaged readings the model is averaged over each capture interval, so the fit sees
  exactly what the meter reports. A mode is kept only if it lowers a BIC-style criterion, so a
  quiet window falls back to the mean. The level is the fitted constant.

Pure numpy (plus scipy's optimiser): on the live path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize

from burstloc.exceptions import InputError
from burstloc.ranking import METER_MODELS, MeterModel

__all__ = [
    "ESTIMATORS",
    "DampedFit",
    "EstimatorName",
    "baseline_levels",
    "estimate_levels",
    "fit_damped_modes",
]

EstimatorName = Literal["mean", "median", "damped-fit"]
ESTIMATORS: frozenset[str] = frozenset({"mean", "median", "damped-fit"})

_DECAY_GRID = (0.0, 0.005, 0.01, 0.02, 0.04, 0.08)  # 1/s: from undamped to a ~12 s time constant
_MAX_GRID = 300  # candidate frequencies per decay rate in the grid search
_AVERAGING_NODES = 8  # Gauss-Legendre nodes per capture interval for interval-averaged readings


def baseline_levels(values: NDArray[np.float64]) -> NDArray[np.float64]:
    """Pre-burst level per meter: the mean of the burst-free readings ``values`` (T, M)."""
    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 2 or v.shape[0] == 0:
        raise InputError("no reading before the burst onset: the baseline level is unknown")
    return v.mean(axis=0)


@dataclass(frozen=True)
class DampedFit:
    """Result of :func:`fit_damped_modes`.

    ``levels`` (M,) are the fitted constants; ``omegas`` and ``decays`` (rad/s, 1/s) the shared
    mode parameters; ``amplitudes`` (modes, M) each meter's amplitude of each mode;
    ``rms`` the residual RMS over all readings (m).
    """

    levels: NDArray[np.float64]
    omegas: tuple[float, ...]
    decays: tuple[float, ...]
    amplitudes: NDArray[np.float64]
    rms: float


def _basis(
    t: NDArray[np.float64],
    params: list[tuple[float, float]],
    capture_interval: float,
    meter_model: MeterModel,
) -> NDArray[np.float64]:
    """Design matrix (n, 1 + 2 modes): constant, then ``exp(-l t) cos(w t)``, ``... sin(w t)``."""
    if meter_model == "interval-averaged":
        nodes, weights = np.polynomial.legendre.leggauss(_AVERAGING_NODES)
        # a reading at t averages (t - dt, t]: map [-1, 1] onto it
        offs = (nodes - 1.0) * 0.5 * capture_interval
        tt = t[:, None] + offs[None, :]
        w = weights * 0.5
    else:
        tt = t[:, None]
        w = np.ones(1)
    cols = [np.ones(t.size)]
    for omega, decay in params:
        env = np.exp(-decay * tt)
        cols.append((env * np.cos(omega * tt)) @ w)
        cols.append((env * np.sin(omega * tt)) @ w)
    return np.column_stack(cols)


def _grid_rss(
    t: NDArray[np.float64],
    y: NDArray[np.float64],
    fixed: list[tuple[float, float]],
    omegas: NDArray[np.float64],
    decay: float,
    capture_interval: float,
    meter_model: MeterModel,
) -> NDArray[np.float64]:
    """Residual sum of squares of the joint fit for each candidate frequency (batched)."""
    fixed_basis = _basis(t, fixed, capture_interval, meter_model)  # (n, 1 + 2 * fixed)
    if meter_model == "interval-averaged":
        nodes, weights = np.polynomial.legendre.leggauss(_AVERAGING_NODES)
        tt = t[:, None] + ((nodes - 1.0) * 0.5 * capture_interval)[None, :]
        w = weights * 0.5
    else:
        tt = t[:, None]
        w = np.ones(1)
    env = np.exp(-decay * tt)  # (n, q)
    phase = omegas[:, None, None] * tt[None, :, :]  # (g, n, q)
    cos_col = (env[None] * np.cos(phase)) @ w  # (g, n)
    sin_col = (env[None] * np.sin(phase)) @ w
    g = omegas.size
    basis = np.concatenate(
        [
            np.broadcast_to(fixed_basis, (g, *fixed_basis.shape)),
            cos_col[:, :, None],
            sin_col[:, :, None],
        ],
        axis=2,
    )  # (g, n, k)
    gram = np.einsum("gnk,gnl->gkl", basis, basis)
    rhs = np.einsum("gnk,nm->gkm", basis, y)
    k = gram.shape[1]
    gram = gram + np.eye(k)[None] * (1e-12 * np.trace(gram, axis1=1, axis2=2)[:, None, None])
    coef = np.linalg.solve(gram, rhs)
    return float(np.sum(y * y)) - np.einsum("gkm,gkm->g", rhs, coef)


def _rss(basis: NDArray[np.float64], y: NDArray[np.float64]) -> float:
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    r = y - basis @ coef
    return float(np.sum(r * r))


def fit_damped_modes(
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    *,
    capture_interval: float,
    meter_model: MeterModel = "instantaneous",
    modes: int = 2,
    max_frequency: float | None = None,
) -> DampedFit:
    """Fit ``values[:, m] ~ L_m + sum_k exp(-l_k t) (a_mk cos w_k t + b_mk sin w_k t)``.

    ``w_k`` and ``l_k`` are shared by every meter. Frequencies are searched up to the Nyquist
    frequency of the capture interval (or ``max_frequency`` Hz if lower); modes are added one at a
    time and kept only while the BIC of the joint fit improves.
    """
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    n, m = y.shape
    t = t - t[0]
    span = float(t[-1]) if n > 1 else 0.0
    nyquist = math.pi / capture_interval
    w_max = nyquist if max_frequency is None else min(nyquist, 2 * math.pi * max_frequency)
    # frequencies whose period exceeds twice the window are indistinguishable from a level drift
    w_min = math.pi / max(span, capture_interval)
    base = _basis(t, [], capture_interval, meter_model)
    rss = _rss(base, y)
    chosen: list[tuple[float, float]] = []

    def bic(rss_value: float, k: int) -> float:
        count = n * m
        params = m * (1 + 2 * k) + 2 * k
        return count * math.log(max(rss_value, 1e-300) / count) + params * math.log(count)

    best_bic = bic(rss, 0)
    for _ in range(modes):
        # every mode costs 2 readings per meter plus 2 shared parameters
        if n < 1 + 2 * (len(chosen) + 1) + 2 or w_max <= w_min:
            break
        omegas = np.linspace(w_min, w_max, int(min(_MAX_GRID, max(40, 4 * n))))
        best_rss, best_omega, best_decay = math.inf, 0.0, 0.0
        for decay in _DECAY_GRID:
            rss_grid = _grid_rss(t, y, chosen, omegas, decay, capture_interval, meter_model)
            i = int(np.argmin(rss_grid))
            if rss_grid[i] < best_rss:
                best_rss, best_omega, best_decay = float(rss_grid[i]), float(omegas[i]), decay
        start = np.array([v for p in chosen for v in p] + [best_omega, best_decay])

        def objective(theta: NDArray[np.float64]) -> float:
            pars = [(float(theta[2 * i]), float(theta[2 * i + 1])) for i in range(len(theta) // 2)]
            if any(d < 0 or d > 1.0 or w < 0 for w, d in pars):
                return math.inf
            return _rss(_basis(t, pars, capture_interval, meter_model), y)

        res = minimize(
            objective, start, method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-10}
        )
        theta = res.x if res.fun <= best_rss else start
        cand = [(float(theta[2 * i]), float(theta[2 * i + 1])) for i in range(len(theta) // 2)]
        cand_rss = min(float(res.fun), best_rss)
        cand_bic = bic(cand_rss, len(cand))
        if cand_bic >= best_bic:
            break
        chosen, rss, best_bic = cand, cand_rss, cand_bic
    basis = _basis(t, chosen, capture_interval, meter_model)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    amps = np.hypot(coef[1::2], coef[2::2]) if chosen else np.zeros((0, m))
    resid = y - basis @ coef
    return DampedFit(
        levels=coef[0].copy(),
        omegas=tuple(w for w, _ in chosen),
        decays=tuple(d for _, d in chosen),
        amplitudes=np.asarray(amps, dtype=np.float64).reshape(len(chosen), m),
        rms=float(np.sqrt(np.mean(resid * resid))),
    )


def estimate_levels(
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    *,
    capture_interval: float,
    meter_model: MeterModel = "instantaneous",
    method: EstimatorName = "damped-fit",
) -> NDArray[np.float64]:
    """New steady level per meter from post-burst readings ``values`` (T, M) at ``times`` (T,)."""
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    if y.ndim != 2 or t.shape != (y.shape[0],):
        raise InputError(f"times (T,) and values (T, M) do not match: {t.shape}, {y.shape}")
    if y.shape[0] == 0:
        raise InputError("no reading after the burst has settled: the new level is unknown")
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(t))):
        raise InputError("readings must be finite")
    if meter_model not in METER_MODELS:
        raise InputError(f"unknown meter model {meter_model!r}")
    if method == "mean":
        return y.mean(axis=0)
    if method == "median":
        return np.median(y, axis=0)
    if method == "damped-fit":
        return fit_damped_modes(
            t, y, capture_interval=capture_interval, meter_model=meter_model
        ).levels
    raise InputError(f"unknown estimator {method!r}; use one of {sorted(ESTIMATORS)}")
