"""burstloc.sim.events.operations: valve, pump and demand events on paper15_assets, real TSNet runs
(4 s)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from burstloc.cli import main
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.sim.events.operations import EventScenario, event_output_path, simulate_event
from burstloc.sim.scenarios.cache import DiskCache
from burstloc.sim.scenarios.result import ScenarioResult

ASSETS = Path(__file__).resolve().parents[2] / "networks" / "paper15_assets.inp"
SHORT = {"start": 0.5, "duration": 4.0}


def run(kind: str, asset: str, **kwargs: float) -> ScenarioResult:
    return simulate_event(EventScenario(ASSETS, kind, asset, **SHORT, **kwargs), cache=False)  # type: ignore[arg-type]


def change(result: ScenarioResult, node: str) -> float:
    """Mean head over the last second minus the head before the event (m)."""
    col = result.junctions.index(node)
    before = result.heads[result.time < 0.5, col]
    assert np.ptp(before) < 2e-3  # TSNet starts from EPANET's steady state
    return float(np.mean(result.heads[result.time > 3.0, col]) - before[0])


def test_a_valve_closure_raises_the_head_upstream_and_lowers_it_downstream() -> None:
    result = run("valve-closure", "V16")
    assert change(result, "V1") > 5 and change(result, "V2") < -5  # a water hammer at the valve
    assert result.metadata["event"] == "valve-closure"
    assert result.metadata["asset_nodes"] == ["V1", "V2"]
    assert "pipe" not in result.metadata


def test_a_valve_opening_from_shut_lowers_the_head_upstream() -> None:
    result = run("valve-opening", "V16", setting=1.0)
    assert change(result, "V1") < -0.05 and change(result, "V2") > 0.05


def swing(result: ScenarioResult) -> np.ndarray:
    """Each meter's head minus its initial head (m), (T, M)."""
    return result.heads - result.heads[0]


def first_to_move(result: ScenarioResult, by: float = 0.3) -> str:
    """The meter whose head first moves by more than ``by`` metres."""
    moved = np.abs(swing(result)) > by
    first = np.where(moved.any(axis=0), np.argmax(moved, axis=0), result.time.size)
    return result.junctions[int(np.argmin(first))]


def test_a_pump_trip_drops_the_head_at_its_outlet_first() -> None:
    result = run("pump-trip", "PU1")
    assert first_to_move(result) == "PS"
    assert swing(result)[:, result.junctions.index("PS")].min() == swing(result).min() < -10


def test_a_pump_start_raises_the_head_at_its_outlet_first() -> None:
    result = run("pump-start", "PU1", operation_time=2.0)
    assert first_to_move(result) == "PS"
    assert swing(result)[:, result.junctions.index("PS")].max() == swing(result).max() > 5
    assert swing(result).min() > -0.01  # nothing drops


def test_a_demand_step_lowers_the_head_at_the_junction_first() -> None:
    up = run("demand-step", "8", demand_change=0.01)
    assert first_to_move(up) == "8" and change(up, "8") < -0.5
    down = run("demand-step", "8", demand_change=-0.01)
    assert first_to_move(down) == "8" and change(down, "8") > 0.5


def test_events_are_cached(tmp_path: Path) -> None:
    store = DiskCache(tmp_path)
    scenario = EventScenario(ASSETS, "pump-trip", "PU1", **SHORT)  # type: ignore[arg-type]
    first = simulate_event(scenario, cache=store)
    again = simulate_event(scenario, cache=store)
    assert first.metadata["cache"] == "miss" and again.metadata["cache"] == "hit"
    np.testing.assert_array_equal(first.heads, again.heads)


@pytest.mark.parametrize(
    ("kind", "asset", "kwargs", "match"),
    [
        ("valve-closure", "PU1", {}, "no valve 'PU1'"),
        ("pump-trip", "V16", {}, "no pump 'V16'"),
        ("demand-step", "V1", {"demand_change": 0.01}, "no base demand"),
        ("demand-step", "nowhere", {"demand_change": 0.01}, "no junction 'nowhere'"),
    ],
)
def test_an_asset_of_the_wrong_kind_is_a_network_error(
    kind: str, asset: str, kwargs: dict[str, float], match: str
) -> None:
    with pytest.raises(NetworkError, match=match):
        run(kind, asset, **kwargs)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"kind": "flood", "asset": "V16"}, "event kind"),
        ({"kind": "pump-trip", "asset": "PU1", "operation_time": 0.0}, "operation_time"),
        ({"kind": "valve-closure", "asset": "V16", "setting": 1.0}, "setting"),
        ({"kind": "valve-opening", "asset": "V16", "setting": 0.0}, "setting"),
        ({"kind": "demand-step", "asset": "8"}, "demand_change"),
        ({"kind": "pump-trip", "asset": "PU1", "start": float("nan")}, "start"),
    ],
)
def test_bad_parameters_are_config_errors(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        EventScenario(ASSETS, **kwargs)  # type: ignore[arg-type]


def test_simulate_event_writes_one_file(tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = ["simulate", str(ASSETS), "--event", "demand-step", "--asset", "N8"]
    args += ["--demand-change", "0.02", "--burst-start", "0.5", "--duration", "2"]
    args += ["--out", str(out)]
    args += ["--capture-interval", "0.2", "--cache-dir", str(tmp_path / "c"), "--quiet"]
    assert main(args) == 0
    scenario = EventScenario(ASSETS, "demand-step", "N8", demand_change=0.02)
    with np.load(event_output_path(out, scenario), allow_pickle=False) as data:
        meta = json.loads(str(data["metadata"]))
        assert data["heads"].shape[1] == 18
    assert meta["event"] == "demand-step" and meta["demand_change"] == 0.02
    assert meta["capture_interval"] == 0.2


def test_simulate_event_needs_an_asset(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["simulate", str(ASSETS), "--event", "pump-trip", "--out", str(tmp_path / "o")])
    assert code != 0
    assert "--asset" in capsys.readouterr().err
