"""``BurstScenario.min_pipe_length``: TSNet on the transient-ready model (burstloc.skeleton).

One burst on tests/connector_network.py's network (a 0.3 m and a 0.5 m connector), simulated
as it is (TSNet's step 0.125 ms, about 9 s of CPU) and with ``min_pipe_length=3`` (both
connectors lengthened to 3 m, every junction kept: a step of 1.25 ms, ten times longer). A
lengthened connector delays a wave crossing it by at most 3 m / 1200 m/s = 2.5 ms, and the
prepared heads are known every 1.25 ms; the burst opens over 20 ms, so around a wave front the
heads may differ by a quarter of the burst's head change (measured: 18 %), far less on average
(measured: 1.9 %), and the arrivals by a few milliseconds (measured: at most 3 ms).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.time_step import expected_time_step
from burstloc.sim.transient.tsnet import simulate_burst
from connector_network import CONNECTOR_INP

START = 0.02


def _scenario(path: Path, min_pipe_length: float | None) -> BurstScenario:
    return BurstScenario(
        path,
        "P3",
        burst_start=START,
        opening_time=0.02,
        burst_coeff=0.01,
        duration=0.2,
        min_pipe_length=min_pipe_length,
    )


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[ScenarioResult, ScenarioResult]:
    path = tmp_path_factory.mktemp("short") / "connectors.inp"
    path.write_text(CONNECTOR_INP)
    original = simulate_burst(_scenario(path, None), cache=False)
    prepared = simulate_burst(_scenario(path, 3.0), cache=False)
    return original, prepared


def _arrivals(result: ScenarioResult) -> np.ndarray:
    """Per meter, the first time its head moves 1 % of its largest change after the burst."""
    change = np.abs(result.heads - result.heads[0])
    moved = change > 0.01 * change.max(axis=0)
    return np.array([result.time[np.argmax(column)] for column in moved.T])


def test_the_step_follows_the_asked_length_not_the_connector(
    runs: tuple[ScenarioResult, ScenarioResult],
) -> None:
    original, prepared = runs
    assert original.time_step == pytest.approx(0.3 / 2400, rel=0.05)
    assert prepared.time_step == pytest.approx(3.0 / 2400, rel=0.05)
    assert prepared.junctions == original.junctions  # every junction kept
    summary = prepared.metadata["transient_model"]
    assert summary["lengthened"] == {"C1": pytest.approx(0.3), "C2": pytest.approx(0.5)}
    assert summary["merged"] == {}
    assert "transient_model" not in original.metadata


def test_heads_and_arrivals_stay_close(runs: tuple[ScenarioResult, ScenarioResult]) -> None:
    original, prepared = runs
    heads = np.column_stack(
        [np.interp(original.time, prepared.time, prepared.heads[:, m]) for m in range(6)]
    )
    swing = np.abs(original.heads - original.heads[0]).max()
    assert swing > 1.0  # the burst is seen
    assert np.abs(heads[0] - original.heads[0]).max() < 0.01  # the same steady state
    assert np.abs(heads - original.heads).max() < 0.25 * swing
    assert np.abs(heads - original.heads).mean() < 0.03 * swing
    assert np.abs(_arrivals(prepared) - _arrivals(original)).max() < 0.005


def test_expected_time_step_sees_the_prepared_model(tmp_path: Path) -> None:
    path = tmp_path / "connectors.inp"
    path.write_text(CONNECTOR_INP)
    assert expected_time_step(_scenario(path, None)) == pytest.approx(0.3 / 2400, rel=0.05)
    assert expected_time_step(_scenario(path, 3.0)) == pytest.approx(3.0 / 2400, rel=0.05)


def test_min_pipe_length_is_checked_and_keyed(tmp_path: Path) -> None:
    path = tmp_path / "connectors.inp"
    path.write_text(CONNECTOR_INP)
    with pytest.raises(ConfigError, match="min_pipe_length must be > 0 m"):
        _scenario(path, 0.0)
    assert "min_pipe_length" not in _scenario(path, None).parameters()
    assert _scenario(path, 3.0).cache_key() != _scenario(path, None).cache_key()
