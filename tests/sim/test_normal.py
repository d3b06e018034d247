"""burstloc.sim.events.normal: a day of background pressure (EPANET extended period + noise)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from burstloc._diagnostics import capture_diagnostics
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.sim.events.normal import DIURNAL, normal_day


def test_pressure_follows_the_demand_pattern(tiny: Path) -> None:
    times, heads = normal_day(tiny, capture_interval=10.0, noise_sigma=0.0)
    assert times[0] == 0 and np.allclose(np.diff(times), 10.0) and times[-1] < 24 * 3600
    assert heads.shape == (times.size, 4)
    hourly = heads[::360]  # on the hour
    # the most demand (the evening or morning peak) is the lowest pressure, the night the highest
    peak, night = int(np.argmax(DIURNAL)), int(np.argmin(DIURNAL))
    assert np.all(hourly[peak] < hourly[night])
    # slow: consecutive readings differ by far less than a burst's metres
    assert np.abs(np.diff(heads, axis=0)).max() < 0.05


def test_noise_has_the_asked_spread_and_is_seeded(tiny: Path) -> None:
    _, exact = normal_day(tiny, capture_interval=10.0, noise_sigma=0.0, hours=2)
    _, noisy = normal_day(tiny, capture_interval=10.0, noise_sigma=0.01, hours=2, seed=3)
    _, again = normal_day(tiny, capture_interval=10.0, noise_sigma=0.01, hours=2, seed=3)
    assert np.std(noisy - exact) == pytest.approx(0.01, rel=0.1)
    np.testing.assert_array_equal(noisy, again)


def test_bad_arguments(tiny: Path) -> None:
    with pytest.raises(ConfigError, match="capture_interval"):
        normal_day(tiny, capture_interval=0.0)
    with pytest.raises(ConfigError, match="hours"):
        normal_day(tiny, capture_interval=1.0, hours=-1)
    with pytest.raises(NetworkError, match="nowhere"):
        normal_day(tiny, capture_interval=1.0, meters=["nowhere"])


def test_what_epanet_warns_is_recorded_not_printed(tiny: Path, tmp_path: Path) -> None:
    # EPANET's Net1 sets no required pressure: WNTR's default (0.07 m) is below EPANET's lower
    # limit (0.1 psi there, 0.1 m here), and WNTR warns that it raised it
    low = tmp_path / "low_required_pressure.inp"
    text = tiny.read_text()
    assert "Required Pressure  0.1" in text
    low.write_text(text.replace("Required Pressure  0.1", "Required Pressure  0.05"))
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        _, heads = normal_day(low, capture_interval=60.0, noise_sigma=0.0, hours=1)
    assert not [w for w in shown if "REQUIRED PRESSURE" in str(w.message)]
    with capture_diagnostics() as diagnostics:
        normal_day(low, capture_interval=60.0, noise_sigma=0.0, hours=1)
    assert any("REQUIRED PRESSURE" in w for w in diagnostics.warnings)
    # EPANET ran with its 0.1 m, as the tiny network itself asks: the same heads
    _, same = normal_day(tiny, capture_interval=60.0, noise_sigma=0.0, hours=1)
    np.testing.assert_allclose(heads, same)
