"""burstloc.sim.transient.moc_rust: the Rust time loop gives the NumPy loop's heads to the last bit.

The default solver (``"vectorized"``) runs the MOC time loop in Rust (crate ``moc-core``); the
``"numpy"`` solver runs the same loop as NumPy array operations. Every expression keeps the same
order of operations, squares are the C library's ``pow`` in both and a junction's sum adds in
``np.dot``'s order in both, so the heads are equal, not merely close, on real networks: bursts
on paper15, EPANET's Net1 (a pump and a tank), Net2 (a valve leading nowhere), Anytown (a pump
station) and Net3 (two pumps, a closed one, transient-ready pipes), a network with an active
PRV and a pump given by its power, and every kind of event (a valve operated, a pump tripping
and starting: per-step pump curves and valve losses, a demand step).

That holds where NumPy promotes a float32 scalar times a Python float to float64 (NumPy 1.x).
NumPy 2 keeps it float32 (NEP 50), and on that stack WNTR hands TSNet float32 pump curves and
valve coefficients: TSNet's pump and valve functions, which the NumPy loop calls, then compute
parts in float32 where the Rust port computes in float64. There the heads agree within
:data:`ELEMENT_ATOL` (measured: 7.7e-6 m on Net3, 6.4e-7 m on Net1; networks without pumps or
valves stay identical).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_moc import EVENTS  # the same events the NumPy loop is checked on against TSNet

from burstloc import InputError
from burstloc._core import moc_run
from burstloc.sim.events.operations import EventScenario, simulate_event
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst

NETWORKS = Path(__file__).resolve().parents[2] / "networks"
#: Whether TSNet's pump and valve functions compute in float64 here (see the module docstring).
EXACT = type(np.float32(1.0) * 1.0) is np.float64
#: Largest head difference (m) between the loops where they do not.
ELEMENT_ATOL = 1e-3

#: A reservoir, a pump given by its power, an active PRV between two pipes, a loop.
PUMP_AND_PRV = """\
[JUNCTIONS]
 J0   0     0
 J9   0     0
 J1   10    2
 J2   10    3
 J2a  10    0
 J2b  10    0
 J3   5     3
 J4   0     2
 J5   0     4

[RESERVOIRS]
 R1   50

[PIPES]
 A    R1     J0     150     300       100        0          Open
 A2   J9     J1     150     300       100        0          Open
 B    J1     J2     200     250       100        0          Open
 C    J2     J2a    120     250       100        0          Open
 C2   J2b    J3     130     200       100        0          Open
 D    J3     J4     150     200       100        0          Open
 E    J4     J5     180     150       100        0          Open
 F    J5     J2b    220     150       100        0          Open

[PUMPS]
 P1   J0     J9     POWER 7

[VALVES]
 V1   J2a    J2b    250   PRV   25   0

[OPTIONS]
 Units              LPS
 Headloss           H-W
 Required Pressure  0.1

[END]
"""


def public(name: str) -> Path:
    path = NETWORKS / "public" / name
    if not path.is_file():
        pytest.fail(f"{path} is missing: run `make setup` (it fetches the public networks)")
    return path


def assert_equal_heads(numpy_loop: ScenarioResult, rust_loop: ScenarioResult) -> None:
    assert numpy_loop.metadata["solver"] == "numpy"
    assert rust_loop.metadata["solver"] == "vectorized"
    np.testing.assert_array_equal(rust_loop.time, numpy_loop.time)
    assert rust_loop.junctions == numpy_loop.junctions
    assert np.ptp(rust_loop.heads) > 0.1  # a transient to compare, not a constant
    if EXACT:
        np.testing.assert_array_equal(rust_loop.heads, numpy_loop.heads)
        negative = numpy_loop.metadata["negative_pressure_nodes"]
        assert rust_loop.metadata["negative_pressure_nodes"] == negative
    else:
        np.testing.assert_allclose(rust_loop.heads, numpy_loop.heads, rtol=0, atol=ELEMENT_ATOL)


BURSTS = {
    "paper15": (lambda: NETWORKS / "paper15.inp", "7", 3.0, None),
    "Net1 (pump, tank)": (lambda: public("Net1.inp"), "110", 2.0, None),
    "Net2 (valve leading nowhere)": (lambda: public("Net2.inp"), "20", 2.0, None),
    "Anytown (pump station)": (lambda: public("Anytown.inp"), "4", 2.0, None),
    "Net3 (pumps, transient-ready)": (lambda: public("Net3.inp"), "20", 1.5, 30.0),
}


@pytest.mark.parametrize("name", list(BURSTS))
def test_a_burst_has_the_numpy_loops_heads(name: str) -> None:
    path, pipe, duration, min_length = BURSTS[name]
    scenario = BurstScenario(
        path(),
        pipe,
        burst_start=0.5,
        opening_time=0.3,
        duration=duration,
        min_pipe_length=min_length,
    )
    numpy_loop = simulate_burst(replace(scenario, solver="numpy"), cache=False)
    assert_equal_heads(numpy_loop, simulate_burst(scenario, cache=False))


def test_a_power_pump_and_an_active_prv_have_the_numpy_loops_heads(tmp_path: Path) -> None:
    path = tmp_path / "pump_prv.inp"
    path.write_text(PUMP_AND_PRV, encoding="utf-8")
    scenario = BurstScenario(path, "D", burst_start=1.0, opening_time=0.3, duration=2.0)
    numpy_loop = simulate_burst(replace(scenario, solver="numpy"), cache=False)
    rust_loop = simulate_burst(scenario, cache=False)
    assert_equal_heads(numpy_loop, rust_loop)
    j3 = rust_loop.junctions.index("J3")
    assert rust_loop.heads[0, j3] - rust_loop.heads[-1, j3] > 0.5  # the burst arrived


@pytest.mark.parametrize(("kind", "asset", "extra"), EVENTS, ids=[e[0] for e in EVENTS])
def test_an_event_has_the_numpy_loops_heads(kind: str, asset: str, extra: dict[str, float]) -> None:
    scenario = EventScenario(
        NETWORKS / "paper15_assets.inp", kind, asset, start=0.5, duration=3.0, **extra
    )
    numpy_loop = simulate_event(replace(scenario, solver="numpy"), cache=False)
    assert_equal_heads(numpy_loop, simulate_event(scenario, cache=False))


def arrays(**changes: object) -> dict[str, object]:
    """A two-pipe network laid out for ``moc_run``: R -> pipe 0 -> junction -> pipe 1 -> dead
    end, two reaches per pipe."""
    base: dict[str, object] = {
        "steps": 4,
        "pipe_points": np.array([[0, 2], [3, 2]], dtype=np.int64),
        "pipes": np.tile([0.01, 100.0, 1e-4, 0.0, 1e-5, 1e-5, 0.03, 0.03], (2, 1)),
        "h0": np.full(6, 50.0),
        "v0": np.zeros(6),
        "nodes": np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 10.0], [0.0, 0.001, 10.0]]),
        "junctions": np.array([[2, 1, 0, 1], [3, 4, 1, 1]], dtype=np.int64),
        "junction_values": np.array([[1.0, 6e-4], [-1.0, 6e-4]]),
        "contributions": np.array([[0, 4, 1, 0], [1, 1, 0, 0]], dtype=np.int64),
        "contribution_signs": np.array([-1.0, 1.0]),
        "dead_ends": np.array([[5, 4, 1, 2, 0]], dtype=np.int64),
        "dead_floors": np.array([10.0]),
        "reservoirs": np.array([[0, 1, 0]], dtype=np.int64),
        "reservoir_values": np.array([[50.0, 1.0]]),
        "valve_ends": np.zeros((0, 3), dtype=np.int64),
        "valve_sides": np.zeros(0),
        "valve_series": np.zeros((4, 0)),
        "elements": np.zeros((0, 8), dtype=np.int64),
        "element_values": np.zeros((0, 3)),
        "element_series": np.zeros((4, 0)),
        "bursts": np.zeros(0, dtype=np.int64),
        "burst_series": np.zeros((4, 0)),
        "pulses": np.zeros(0, dtype=np.int64),
        "pulse_series": np.zeros((4, 0)),
        "record": np.array([0, 2, 5], dtype=np.int64),
    }
    return {**base, **changes}


def test_moc_run_steps_a_small_network() -> None:
    heads, junction_failed, dead_failed, element_warnings = moc_run(**arrays())  # type: ignore[arg-type]
    assert heads.shape == (4, 3)
    assert np.isfinite(heads).all()
    assert heads[0].tolist() == [50.0, 50.0, 50.0]
    assert (heads[:, 0] == 50.0).all()  # the reservoir holds its head
    assert heads[-1, 2] < 50.0  # the dead end's demand draws its head down
    assert junction_failed.tolist() == [0, 0] and dead_failed.tolist() == [0]
    assert element_warnings.shape == (0, 3)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"h0": np.full(6, 50, dtype=np.int64)}, "h0 must be a 1-D numpy array of f64"),
        ({"pipes": np.zeros((2, 7))}, "pipes must be a 2-D numpy array of f64 with 8 columns"),
        ({"record": np.array([0, 9], dtype=np.int64)}, "record 1: index 9 out of range"),
        ({"record": np.array([-1], dtype=np.int64)}, "record holds a negative index -1"),
        ({"burst_series": np.zeros((3, 0))}, None),
        (
            {"bursts": np.array([1], dtype=np.int64), "burst_series": np.zeros((3, 1))},
            "burst_series must hold 4 steps x 1 values",
        ),
        (
            {"elements": np.array([[7, 0, 0, 0, 0, 0, 0, 0]]), "element_values": np.zeros((1, 3))},
            "elements: kind 7 is none of",
        ),
    ],
)
def test_moc_run_refuses_arrays_that_do_not_fit(
    changes: dict[str, object], message: str | None
) -> None:
    if message is None:  # an empty series of any length fits: no column is read
        moc_run(**arrays(**changes))  # type: ignore[arg-type]
        return
    with pytest.raises(InputError, match=message):
        moc_run(**arrays(**changes))  # type: ignore[arg-type]
