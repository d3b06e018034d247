"""burstloc.localize.steady_level: the new steady level through the network's ringing."""

from __future__ import annotations

import numpy as np
import pytest

from burstloc.exceptions import InputError
from burstloc.localize.steady_level import (
    baseline_levels,
    block_average,
    estimate_levels,
    fit_damped_modes,
)
from ringing import ringing


def test_projected_mode_search_matches_a_direct_least_squares() -> None:
    from burstloc.localize.steady_level import _basis, _pair_rss

    rng = np.random.default_rng(3)
    t = np.arange(0.0, 90.0, 2.0)
    y = rng.normal(size=(t.size, 5))
    y -= y.mean(axis=0)
    fixed = [(0.4, 0.03)]
    omegas, decays = np.array([0.2, 0.9, 1.4]), np.array([0.0, 0.02, 0.05])
    for span in (0.0, 2.0):
        fast = _pair_rss(t, span, y, fixed, omegas, decays)
        for g in range(omegas.size):
            basis = _basis(t, span, [*fixed, (float(omegas[g]), float(decays[g]))])
            coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
            assert fast[g] == pytest.approx(float(np.sum((y - basis @ coef) ** 2)), rel=1e-9)


@pytest.mark.parametrize("model", ["instantaneous", "interval-averaged"])
@pytest.mark.parametrize("dt", [2.0, 5.0])
def test_damped_fit_sees_throughringing(model: str, dt: float) -> None:
    rng = np.random.default_rng(3)
    level = rng.uniform(40, 60, size=5)
    shapes = rng.uniform(-0.8, 0.8, size=(2, 5))
    t = np.arange(60.0, 160.0 + 1e-9, dt)
    y = ringing(t, level, shapes, dt, model)
    fitted = estimate_levels(t, y, capture_interval=dt, meter_model=model)  # type: ignore[arg-type]
    naive = y.mean(axis=0)
    assert np.max(np.abs(fitted - level)) < 0.01
    assert np.max(np.abs(fitted - level)) < 0.2 * np.max(np.abs(naive - level))


def test_damped_fit_of_a_quiet_window_is_the_mean() -> None:
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 100.0, 5.0)
    y = 30.0 + 0.001 * rng.standard_normal((t.size, 3))
    fit = fit_damped_modes(t, y, capture_interval=5.0)
    assert fit.omegas == ()  # no mode pays for its parameters
    np.testing.assert_allclose(fit.levels, y.mean(axis=0))


def test_estimators_reject_bad_input() -> None:
    with pytest.raises(InputError, match="no reading after"):
        estimate_levels(np.zeros(0), np.zeros((0, 2)), capture_interval=1.0)
    with pytest.raises(InputError, match="before the burst"):
        baseline_levels(np.zeros((0, 2)))
    with pytest.raises(InputError):
        estimate_levels(np.arange(3.0), np.ones((3, 2)), capture_interval=1.0, method="mode")  # type: ignore[arg-type]


def test_block_average_keeps_full_blocks() -> None:
    t = np.arange(1, 12) * 0.2
    y = np.arange(11.0)[:, None]
    tb, yb, width = block_average(t, y, 0.2, 1.0)
    assert width == pytest.approx(1.0)
    np.testing.assert_allclose(tb, [1.0, 2.0])
    np.testing.assert_allclose(yb[:, 0], [2.0, 7.0])
