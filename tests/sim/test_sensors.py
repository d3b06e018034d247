"""burstloc.sim.scenarios.sensors: meter subsets and seeded Gaussian noise, off by default."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from burstloc.exceptions import ConfigError, InputError, NetworkError
from burstloc.sim.scenarios.sensors import SensorModel, choose_meters

JUNCTIONS = ["1", "2", "3", "N2"]
READINGS = np.arange(40, dtype=float).reshape(10, 4) + 100.0


def test_default_model_changes_nothing() -> None:
    model = SensorModel()
    assert not model.enabled
    names, values = model.apply(JUNCTIONS, READINGS)
    assert names == JUNCTIONS
    np.testing.assert_array_equal(values, READINGS)
    assert values is not READINGS  # a copy: the caller's array stays theirs


def test_meter_subset_in_the_given_order() -> None:
    model = SensorModel(meters=("N2", "1"))
    assert model.enabled
    names, values = model.apply(JUNCTIONS, READINGS)
    assert names == ["N2", "1"]
    np.testing.assert_array_equal(values, READINGS[:, [3, 0]])


def test_noise_is_seeded_per_key() -> None:
    model = SensorModel(noise_sigma=0.5, seed=7)
    _, a = model.apply(JUNCTIONS, READINGS, key="pipe 7")
    _, again = SensorModel(noise_sigma=0.5, seed=7).apply(JUNCTIONS, READINGS, key="pipe 7")
    _, other_key = model.apply(JUNCTIONS, READINGS, key="pipe 8")
    _, other_seed = SensorModel(noise_sigma=0.5, seed=8).apply(JUNCTIONS, READINGS, key="pipe 7")
    np.testing.assert_array_equal(a, again)
    assert not np.array_equal(a, other_key) and not np.array_equal(a, other_seed)
    assert not np.array_equal(a, READINGS)


def test_noise_has_the_requested_spread() -> None:
    flat = np.full((20_000, 3), 50.0)
    _, noisy = SensorModel(noise_sigma=0.25, seed=1).apply(["a", "b", "c"], flat)
    errors = noisy - flat
    assert abs(errors.mean()) < 0.01
    assert errors.std() == pytest.approx(0.25, rel=0.02)
    # Independent across meters.
    assert abs(np.corrcoef(errors.T)[0, 1]) < 0.03


@given(sigma=st.floats(0.0, 5.0), seed=st.integers(0, 2**32), key=st.text(max_size=8))
def test_noise_only_adds_to_the_selected_columns(sigma: float, seed: int, key: str) -> None:
    model = SensorModel(noise_sigma=sigma, meters=("3", "1"), seed=seed)
    names, values = model.apply(JUNCTIONS, READINGS, key=key)
    assert names == ["3", "1"] and values.shape == (10, 2)
    assert np.all(np.abs(values - READINGS[:, [2, 0]]) <= 10 * sigma + 1e-12)


@pytest.mark.parametrize("sigma", [-0.1, float("nan"), float("inf")])
def test_bad_sigma(sigma: float) -> None:
    with pytest.raises(ConfigError, match="noise_sigma"):
        SensorModel(noise_sigma=sigma)


def test_bad_meters() -> None:
    with pytest.raises(ConfigError, match="at least one"):
        SensorModel(meters=())
    with pytest.raises(ConfigError, match=r"\['1'\]"):
        SensorModel(meters=("1", "2", "1"))
    with pytest.raises(NetworkError, match="'R1'"):
        SensorModel(meters=("1", "R1")).apply(JUNCTIONS, READINGS)
    with pytest.raises(ConfigError, match="seed"):
        SensorModel(seed=-1)


def test_readings_must_match_the_junctions() -> None:
    with pytest.raises(InputError, match=r"\(T, 3\)"):
        SensorModel().apply(JUNCTIONS[:3], READINGS)


def test_choose_meters() -> None:
    picked = choose_meters(JUNCTIONS, 2, seed=3)
    assert len(set(picked)) == 2 and set(picked) <= set(JUNCTIONS)
    assert list(picked) == [j for j in JUNCTIONS if j in picked]  # network order
    assert choose_meters(JUNCTIONS, 2, seed=3) == picked
    assert {choose_meters(JUNCTIONS, 2, seed=s) for s in range(20)} != {picked}
    assert choose_meters(JUNCTIONS, 4) == tuple(JUNCTIONS)
    for count in (0, 5):
        with pytest.raises(ConfigError, match="count"):
            choose_meters(JUNCTIONS, count)
