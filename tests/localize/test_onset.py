"""The change point fitted to a meter's readings (burstloc.localize.onset)."""

from __future__ import annotations

import numpy as np
import pytest

from burstloc.localize.evidence import IndexedAlarm, evidence_from_alarms
from burstloc.localize.onset import FITTED_INTERVAL, _fit, hinge_onset


def _front(dt: float, onset: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Level 50 m, then a 0.4 m drop over 0.3 s from ``onset``; 1 cm of noise; 0 to 3 s."""
    t = np.arange(0.0, 3.0, dt)
    y = 50.0 - 0.4 * np.clip((t - onset) / 0.3, 0.0, 1.0)
    return t, y + np.random.default_rng(seed).normal(0.0, 0.01, t.size)


@pytest.mark.parametrize("dt", [0.004, 0.01])
def test_the_hinge_finds_where_the_front_starts_to_a_fraction_of_a_reading(dt: float) -> None:
    errors = []
    for seed in range(20):
        onset = 1.0 + 0.37 * dt  # between two readings
        t, y = _front(dt, onset, seed)
        index = int(np.searchsorted(t, onset + 0.25))  # the alarm, late in the front
        start = int(np.searchsorted(t, onset - 0.15))  # a CUSUM's start, 0.15 s early
        found = hinge_onset(t, y, start, index, -1.0)
        assert found is not None
        errors.append(found - onset)
    assert np.sqrt(np.mean(np.square(errors))) < 0.02  # against 0.15 s from the CUSUM's start
    assert abs(np.mean(errors)) < 0.01


def test_no_hinge_the_wrong_way_or_from_too_few_readings() -> None:
    t, y = _front(0.004, 1.0, 0)
    index, start = int(np.searchsorted(t, 1.25)), int(np.searchsorted(t, 0.9))
    assert hinge_onset(t, y, start, index, +1.0) is None  # a rise asked, the readings drop
    assert hinge_onset(t[:3], y[:3], 0, 2, -1.0) is None
    assert hinge_onset(t, y, index, index, -1.0) is None


def test_evidence_centres_a_fine_alarms_window_on_the_fitted_change() -> None:
    for dt, fitted in ((0.004, True), (0.05, True), (0.2, False)):
        assert (dt <= FITTED_INTERVAL) is fitted
        t, y = _front(dt, 1.0, 1)
        index, start = int(np.searchsorted(t, 1.25)), int(np.searchsorted(t, 0.85))
        alarm = IndexedAlarm(channel=0, index=index, start=start, amplitude=-0.3)
        evidence = evidence_from_alarms(("m",), t, y[:, None], [alarm], capture_interval=dt)
        began = evidence.alarms["m"].start
        if fitted:  # the window [start, start + dt] holds the fitted change, mid-window
            assert began + 0.5 * dt == pytest.approx(1.0, abs=0.02 if dt < 0.02 else 0.05)
        else:  # the detector's own start
            assert began == t[start]


def test_a_fit_is_kept_for_the_same_readings_and_redone_for_others() -> None:
    t, y = _front(0.004, 1.0, 2)
    index, start = int(np.searchsorted(t, 1.25)), int(np.searchsorted(t, 0.9))
    first = hinge_onset(t, y, start, index, -1.0)
    hits = _fit.cache_info().hits
    longer = np.concatenate([y, [49.0]])  # the same readings, one more after: the same fit
    assert hinge_onset(np.append(t, t[-1] + 0.004), longer, start, index, -1.0) == first
    assert _fit.cache_info().hits == hits + 1
    other = y.copy()
    other[index - 40 :] -= 0.2  # other readings at the same times: fitted anew, elsewhere
    moved = hinge_onset(t, other, start, index, -1.0)
    assert _fit.cache_info().hits == hits + 1
    assert moved is not None and moved != first
