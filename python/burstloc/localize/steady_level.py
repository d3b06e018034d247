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
  For interval-averaged readings the model is averaged (in closed form) over each capture
  interval, so the fit sees exactly what the meter reports. A mode is kept only if it lowers a
  BIC-style criterion, so a quiet window falls back to the mean. The level is the fitted constant.

Pure numpy (plus scipy's optimiser): on the live path.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from burstloc.constants import METER_MODELS, MeterModel
from burstloc.exceptions import InputError

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

_DECAY_GRID = (0.0, 0.01, 0.02, 0.04, 0.08)  # 1/s: undamped to a ~12 s time constant
_MAX_DECAY = 1.0  # 1/s
_MAX_GRID = 240  # candidate frequencies per decay rate in the grid search
_ZOOM_ROUNDS = 4  # refinement grids around the best grid point
_DEFAULT_MODES = 3
_BLOCK = 2.0  # s: dense readings are block-averaged to about this before the fit


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
    ``coefficients`` (2 * modes, M) the cosine and sine coefficients of each mode (their rows
    span the meters' oscillation shapes); ``rms`` the residual RMS over all readings (m).
    """

    levels: NDArray[np.float64]
    omegas: tuple[float, ...]
    decays: tuple[float, ...]
    amplitudes: NDArray[np.float64]
    coefficients: NDArray[np.float64]
    rms: float


def _averaging(capture_interval: float, meter_model: MeterModel) -> float:
    """Length (s) of the interval each reading averages the signal over: 0 = instantaneous."""
    return capture_interval if meter_model == "interval-averaged" else 0.0


def _mode_columns(
    t: NDArray[np.float64],
    span: float,
    omegas: NDArray[np.float64],
    decays: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``exp(-l t) cos(w t)`` and ``... sin(w t)`` columns for candidate pairs (g, n).

    With ``span > 0`` each reading is the mode's exact mean over ``[t - span, t]``: with
    ``z = -l + i w`` that mean is ``exp(z t) (1 - exp(-z span)) / (z span)``.
    """
    z = -decays + 1j * omegas
    cols = np.exp(z[:, None] * t[None, :])
    if span > 0:
        zs = z * span
        small = np.abs(zs) < 1e-8
        factor = np.where(small, 1.0 + 0j, (1.0 - np.exp(-zs)) / np.where(small, 1.0, zs))
        cols = cols * factor[:, None]
    return cols.real, cols.imag


def _basis(
    t: NDArray[np.float64], span: float, params: list[tuple[float, float]]
) -> NDArray[np.float64]:
    """Design matrix (n, 1 + 2 modes): a constant, then each mode's cosine and sine columns."""
    cols = [np.ones(t.shape[0])]
    for omega, decay in params:
        c, s = _mode_columns(t, span, np.array([omega]), np.array([decay]))
        cols += [c[0], s[0]]
    return np.column_stack(cols)


def _pair_rss(
    t: NDArray[np.float64],
    span: float,
    y: NDArray[np.float64],
    fixed: list[tuple[float, float]],
    omegas: NDArray[np.float64],
    decays: NDArray[np.float64],
) -> NDArray[np.float64]:
    """Residual sum of squares of the joint fit with the ``fixed`` modes plus one candidate mode
    ``(omegas[i], decays[i])``, for every candidate at once (``y`` is centred per meter)."""
    # Variable projection with the fixed modes projected out once: every candidate then needs
    # only a 2 x 2 solve (closed form), not a (1 + 2 modes)-square one.
    q, _ = np.linalg.qr(_basis(t, span, fixed))
    yp = y - q @ (q.T @ y)
    cos_col, sin_col = _mode_columns(t, span, omegas, decays)
    c = cos_col - (cos_col @ q) @ q.T
    s = sin_col - (sin_col @ q) @ q.T
    cc = np.einsum("gn,gn->g", c, c)
    ss = np.einsum("gn,gn->g", s, s)
    cs = np.einsum("gn,gn->g", c, s)
    rc = c @ yp  # (g, m)
    rs = s @ yp
    ridge = 1e-12 * (cc + ss) + 1e-300
    cc, ss = cc + ridge, ss + ridge
    det = cc * ss - cs * cs
    explained = (ss[:, None] * rc * rc - 2 * cs[:, None] * rc * rs + cc[:, None] * rs * rs) / det[
        :, None
    ]
    return np.asarray(float(np.sum(yp * yp)) - explained.sum(axis=1))


def _best_mode(
    t: NDArray[np.float64],
    span: float,
    y: NDArray[np.float64],
    fixed: list[tuple[float, float]],
    w_min: float,
    w_max: float,
    start: tuple[float, float] | None = None,
) -> tuple[float, float, float]:
    """Best additional mode ``(rss, omega, decay)``: a coarse grid (unless ``start`` is given),
    then zooming grids around the best pair."""
    if start is None:
        count = int(min(_MAX_GRID, max(40, 4 * t.shape[0])))
        om, de = np.meshgrid(np.linspace(w_min, w_max, count), np.array(_DECAY_GRID))
        om, de = om.ravel(), de.ravel()
        rss = _pair_rss(t, span, y, fixed, om, de)
        i = int(np.argmin(rss))
        best = (float(rss[i]), float(om[i]), float(de[i]))
        step_w = (w_max - w_min) / max(count - 1, 1)
    else:
        rss0 = _pair_rss(t, span, y, fixed, np.array([start[0]]), np.array([start[1]]))
        best = (float(rss0[0]), start[0], start[1])
        step_w = 0.02 * max(start[0], 0.05)
    step_d = 0.01
    for _ in range(_ZOOM_ROUNDS):
        om, de = np.meshgrid(
            best[1] + step_w * np.linspace(-2, 2, 9), best[2] + step_d * np.linspace(-2, 2, 9)
        )
        ok = (om > 0) & (de >= 0) & (de <= _MAX_DECAY)
        om, de = om[ok], de[ok]
        rss = _pair_rss(t, span, y, fixed, om, de)
        i = int(np.argmin(rss))
        if rss[i] < best[0]:
            best = (float(rss[i]), float(om[i]), float(de[i]))
        step_w, step_d = step_w / 3, step_d / 3
    return best


def fit_damped_modes(
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    *,
    capture_interval: float,
    meter_model: MeterModel = "instantaneous",
    modes: int = _DEFAULT_MODES,
) -> DampedFit:
    """Fit ``values[:, m] ~ L_m + sum_k exp(-l_k t) (a_mk cos w_k t + b_mk sin w_k t)``.

    ``w_k`` and ``l_k`` are shared by every meter. Frequencies are searched between the
    slowest one that the window can tell from a drift of the level and the Nyquist frequency of
    the capture interval (a faster mode aliases onto one of those); modes are added one at a time
    (grid search, then zooming grids) and kept only while the BIC of the joint fit improves;
    every kept mode is then refined once with the others fixed.
    """
    t = np.asarray(times, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    n, m = y.shape
    if modes < 0:
        raise InputError(f"modes must be >= 0, got {modes}")
    t = t - t[0]
    # centre each meter (the constant column absorbs it) so the residual sums keep their digits
    offset = y.mean(axis=0)
    y = y - offset
    averaging = _averaging(capture_interval, meter_model)
    span = float(t[-1]) if n > 1 else 0.0
    w_max = math.pi / capture_interval
    w_min = math.pi / max(span, capture_interval)
    count = n * m

    def bic(rss_value: float, k: int) -> float:
        params = m * (1 + 2 * k) + 2 * k
        return count * math.log(max(rss_value, 1e-300) / count) + params * math.log(count)

    chosen: list[tuple[float, float]] = []
    best_bic = bic(float(np.sum(y * y)), 0)
    for _ in range(modes):
        # every mode costs 2 readings per meter plus 2 shared parameters
        if n < 1 + 2 * (len(chosen) + 1) + 2 or w_max <= w_min:
            break
        rss, omega, decay = _best_mode(t, averaging, y, chosen, w_min, w_max)
        cand_bic = bic(rss, len(chosen) + 1)
        if cand_bic >= best_bic:
            break
        chosen.append((omega, decay))
        best_bic = cand_bic
    for i in range(len(chosen) if len(chosen) > 1 else 0):
        others = chosen[:i] + chosen[i + 1 :]
        _, omega, decay = _best_mode(t, averaging, y, others, w_min, w_max, start=chosen[i])
        chosen[i] = (omega, decay)
    basis = _basis(t, averaging, chosen)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    amps = np.hypot(coef[1::2], coef[2::2]) if chosen else np.zeros((0, m))
    resid = y - basis @ coef
    return DampedFit(
        levels=coef[0] + offset,
        omegas=tuple(w for w, _ in chosen),
        decays=tuple(d for _, d in chosen),
        amplitudes=np.asarray(amps, dtype=np.float64).reshape(len(chosen), m),
        coefficients=np.asarray(coef[1:], dtype=np.float64).reshape(2 * len(chosen), m),
        rms=float(np.sqrt(np.mean(resid * resid))),
    )


def block_average(
    times: NDArray[np.float64], values: NDArray[np.float64], capture_interval: float, block: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """Average consecutive readings in blocks of about ``block`` seconds.

    Dense instantaneous readings averaged over a block are (up to quadrature) the block's
    interval average; the fit then needs far fewer rows. Returns the block end stamps, the block
    means and the block length. Readings that do not fill a last block are dropped.
    """
    size = max(1, round(block / capture_interval))
    usable = (times.size // size) * size
    if size == 1 or usable == 0:
        return times, values, capture_interval
    t = times[:usable].reshape(-1, size)[:, -1]
    v = values[:usable].reshape(-1, size, values.shape[1]).mean(axis=1)
    return t, v, size * capture_interval


def estimate_levels(
    times: NDArray[np.float64],
    values: NDArray[np.float64],
    *,
    capture_interval: float,
    meter_model: MeterModel = "instantaneous",
    method: EstimatorName = "damped-fit",
    modes: int = _DEFAULT_MODES,
) -> NDArray[np.float64]:
    """New steady level per meter from post-burst readings ``values`` (T, M) at ``times`` (T,).

    ``modes`` is the most damped sinusoids the ``"damped-fit"`` may use. Readings closer than
    2 s apart are first block-averaged to about 2 s (:func:`block_average`).
    """
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
        model = meter_model
        interval = capture_interval
        if capture_interval < _BLOCK:
            t, y, interval = block_average(t, y, capture_interval, _BLOCK)
            if interval > capture_interval:
                model = "interval-averaged"
        return fit_damped_modes(
            t, y, capture_interval=interval, meter_model=model, modes=modes
        ).levels
    raise InputError(f"unknown estimator {method!r}; use one of {sorted(ESTIMATORS)}")
