"""burstloc.sim.transient.moc: the vectorized MOC solver gives TSNet's heads.

Every case runs both solvers on the same scenario (real TSNet runs, short): bursts on the shipped
paper15 network, on EPANET's Net1 (a pump, a tank) and Net2 (a supply junction made a fixed
inflow behind a valve leading nowhere), and every kind of event on paper15_assets (a valve
closing and opening, a pump tripping and starting, a demand step). Where this NumPy's ``np.dot``
adds a strided column as :func:`burstloc.sim.transient.moc_layout.dot_order` does (OpenBLAS with
NumPy
1.26 here), the heads are identical to the last bit; elsewhere (NumPy 2's OpenBLAS adds in
another order) they agree within :data:`BLAS_ATOL`: TSNet's junction equation is ill-conditioned
where a junction has no demand, so a last-place difference in a sum grows to micrometres, and
TSNet itself differs by as much between the two stacks (measured: 3.7 mm on Net1 over 20 s).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.sim.events.operations import EventScenario, simulate_event
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.moc_layout import dot_order
from burstloc.sim.transient.tsnet import simulate_burst

NETWORKS = Path(__file__).resolve().parents[2] / "networks"
#: Largest head difference (m) between the solvers where NumPy sums in another order.
BLAS_ATOL = 1e-2


def blas_sums_as_dot_order() -> bool:
    """Whether ``np.dot`` of a strided column (TSNet's junction sums) adds as ``dot_order``."""
    rng = np.random.default_rng(7)
    for length in range(1, 9):
        for _ in range(200):
            matrix = np.column_stack([rng.normal(size=length) * 100, rng.random(length)])
            weights = list(rng.random(length))
            column = matrix[:, 0]
            products = [float(column[i] * weights[i]) for i in range(length)]
            if np.dot(column, weights) != dot_order(products):
                return False
    return True


EXACT = blas_sums_as_dot_order()


def assert_same_heads(tsnet: ScenarioResult, vectorized: ScenarioResult) -> None:
    np.testing.assert_array_equal(tsnet.time, vectorized.time)
    assert tsnet.junctions == vectorized.junctions
    assert np.ptp(tsnet.heads) > 0.1  # a transient to compare, not a constant
    if EXACT:
        np.testing.assert_array_equal(vectorized.heads, tsnet.heads)
    else:
        np.testing.assert_allclose(vectorized.heads, tsnet.heads, rtol=0, atol=BLAS_ATOL)


BURSTS = {
    "paper15": (NETWORKS / "paper15.inp", "7", 3.0),
    "Net1 (pump, tank)": (NETWORKS / "public" / "Net1.inp", "110", 2.0),
    "Net2 (supply inflow)": (NETWORKS / "public" / "Net2.inp", "20", 2.0),
}


@pytest.mark.parametrize("name", list(BURSTS))
def test_a_burst_has_tsnets_heads(name: str) -> None:
    path, pipe, duration = BURSTS[name]
    if not path.is_file():
        pytest.fail(f"{path} is missing: run `make setup` (it fetches the public networks)")
    scenario = BurstScenario(path, pipe, burst_start=0.5, opening_time=0.3, duration=duration)
    tsnet = simulate_burst(replace(scenario, solver="tsnet"), cache=False)
    vectorized = simulate_burst(scenario, cache=False)
    assert vectorized.metadata["solver"] == "vectorized"
    assert tsnet.metadata["solver"] == "tsnet"
    assert_same_heads(tsnet, vectorized)


EVENTS = [
    ("valve-closure", "V16", {"setting": 0.2}),
    ("valve-opening", "V16", {"setting": 1.0}),
    ("pump-trip", "PU1", {}),
    ("pump-start", "PU1", {}),
    ("demand-step", "5", {"demand_change": 0.01}),
]


@pytest.mark.parametrize(("kind", "asset", "extra"), EVENTS, ids=[e[0] for e in EVENTS])
def test_an_event_has_tsnets_heads(kind: str, asset: str, extra: dict[str, float]) -> None:
    scenario = EventScenario(
        NETWORKS / "paper15_assets.inp", kind, asset, start=0.5, duration=3.0, **extra
    )
    tsnet = simulate_event(replace(scenario, solver="tsnet"), cache=False)
    vectorized = simulate_event(scenario, cache=False)
    assert_same_heads(tsnet, vectorized)


def test_net3_starts_steady_with_junction_10_below_atmospheric_pressure() -> None:
    """EPANET's Net3 on its transient-ready model (30 m pipes): junction 10, behind the closed
    Lake pump, starts at -0.45 m and the network simulates from a steady state."""
    path = NETWORKS / "public" / "Net3.inp"
    if not path.is_file():
        pytest.fail(f"{path} is missing: run `make setup` (it fetches the public networks)")
    scenario = BurstScenario(
        path,
        "20",
        burst_start=1.0,
        opening_time=0.3,
        burst_coeff=0.05,
        duration=3.0,
        min_pipe_length=30.0,
    )
    result = simulate_burst(scenario, cache=False)
    assert np.isfinite(result.heads).all()
    assert result.metadata["steady_start"]["max_movement_m"] < 0.01
    j10 = result.heads[:, result.junctions.index("10")]
    assert -0.5 < j10[0] < -0.4
    # said once, as where it starts, not as negative pressure caused by the burst
    assert "10" not in result.metadata["negative_pressure_nodes"]
    assert any(
        "Node 10 starts below atmospheric pressure" in w for w in result.metadata["warnings"]
    )
    assert np.abs(result.heads - result.heads[0]).max() > 0.1  # the burst arrived


def test_the_vectorized_solver_refuses_other_friction_models() -> None:
    with pytest.raises(ConfigError, match="steady friction only"):
        BurstScenario(NETWORKS / "paper15.inp", "7", friction="unsteady")
    with pytest.raises(ConfigError, match="solver must be one of"):
        BurstScenario(NETWORKS / "paper15.inp", "7", solver="fast")
    assert BurstScenario(NETWORKS / "paper15.inp", "7", friction="unsteady", solver="tsnet")


def test_the_solver_keys_the_cache_apart() -> None:
    """TSNet's results keep their cache keys; the vectorized solver's are its own."""
    scenario = BurstScenario(NETWORKS / "paper15.inp", "7")
    assert "solver" not in replace(scenario, solver="tsnet").parameters()
    assert scenario.parameters()["solver"] == "vectorized"
    assert scenario.cache_key() != replace(scenario, solver="tsnet").cache_key()
