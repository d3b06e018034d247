"""Every element of EPANET's hydraulic model simulated from a steady start, on small real INP
files: parallel mains, a pump given by its power, an active PRV (also with its downstream pipe
reversed and a demand at its node), clock times and units, a water-quality option. Each runs a
short burst (vectorized solver, the default); ``simulate_burst`` refuses a run whose heads move
more than 5 cm before the onset (``burstloc.sim.transient.steady``), so a result is a steady
start."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc import network
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.steady import STEADY_TOLERANCE
from burstloc.sim.transient.tsnet import simulate_burst

#: Two zones: R1 feeds J1; J2 -> J3 (over the element under test) -> J4 -> J5, a loop J5-J2.
BASE = """\
[TITLE]
elements test network

[JUNCTIONS]
;ID  Elev  Demand
 J0   0     0
 J1   10    2
 J2   10    3
 J2b  10    {j2b}
 J3   5     3
 J4   0     2
 J5   0     4

[RESERVOIRS]
 R1   {head}

[PIPES]
;ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status
{first}
 B    J1     J2     200     250       100        0          Open
{middle}
 D    J3     J4     150     200       100        0          Open
 E    J4     J5     180     150       100        0          Open
 F    J5     J2b    220     150       100        0          Open
{extra}

[PUMPS]
{pumps}

[VALVES]
{valves}

[OPTIONS]
 Units              LPS
 Headloss           H-W
 Required Pressure  0.1
{options}

{sections}
[END]
"""

PLAIN = {
    "head": 60,
    "j2b": 0,
    "first": " A    R1     J0     150     300       100        0          Open\n"
    " A2   J0     J1     150     300       100        0          Open",
    "middle": " C    J2     J2b    120     250       100        0          Open\n"
    " C2   J2b    J3     130     200       100        0          Open",
    "extra": "",
    "pumps": "",
    "valves": "",
    "options": "",
    "sections": "",
}


def write(tmp_path: Path, name: str, **changes: str | float) -> Path:
    path = tmp_path / f"{name}.inp"
    path.write_text(BASE.format(**{**PLAIN, **changes}), encoding="utf-8")
    return path


def burst(path: Path, pipe: str) -> ScenarioResult:
    """A 2 s burst at 1 s, no cache; raises UnsteadyStartError if anything moves before it."""
    return simulate_burst(BurstScenario(path, pipe, burst_start=1.0, duration=2.0), cache=False)


def drop(result: ScenarioResult, junction: str) -> float:
    """How far the junction's pressure head fell after the burst (m)."""
    j = result.junctions.index(junction)
    return float(result.heads[0, j] - result.heads[-1, j])


def steady(result: ScenarioResult) -> float:
    moved = float(result.metadata["steady_start"]["max_movement_m"])
    assert moved <= STEADY_TOLERANCE
    return moved


def test_parallel_mains_each_burst_from_a_steady_start(tmp_path: Path) -> None:
    # B2 runs beside B: before, "parallel links are not supported by the flow-direction graph"
    path = write(tmp_path, "parallel", extra=" B2   J1     J2     210     200       100   0  Open")
    for pipe in ("B", "B2"):
        result = burst(path, pipe)
        steady(result)
        assert result.true_endpoints == ("J1", "J2")
        assert drop(result, "J2") > 0.5


def test_a_pump_given_by_its_power_runs_at_its_operating_point(tmp_path: Path) -> None:
    # before: "'PowerPump' object has no attribute 'get_pump_curve'"
    pumped = {
        "head": 20,
        "first": " A    R1     J0     150     300       100        0          Open\n"
        " A2   J9     J1     150     300       100        0          Open",
        "pumps": " P1   J0     J9     POWER 7",
        "sections": "",
    }
    text = BASE.format(**{**PLAIN, **pumped}).replace(" J1   10    2\n", " J1   10    2\n J9 0 0\n")
    path = tmp_path / "power.inp"
    path.write_text(text, encoding="utf-8")
    state = network.steady_state(network.load_network(path))
    lift = state.heads["J9"] - state.heads["J0"]
    assert lift == pytest.approx(7000 / (1000 * 9.81 * state.flows["P1"]), rel=1e-3)  # P/(rho g Q)
    result = burst(path, "B")
    steady(result)
    [curve] = result.metadata["power_pumps"]
    assert curve["pump"] == "P1" and curve["head"] == pytest.approx(lift, rel=1e-3)
    assert drop(result, "J2") > 0.5


@pytest.mark.parametrize("layout", ["pipe -> PRV -> pipe", "reversed pipe, demand at the PRV"])
def test_an_active_prv_is_held_at_its_steady_loss(tmp_path: Path, layout: str) -> None:
    # before: TSNet took the active PRV as closed and the zone below it fell by metres at once;
    # L-TOWN's PRVs: 114 m; a reversed pipe or a demand at its node then still 0.3-0.5 m
    middle = " C    J2     J2a    120     250       100        0          Open\n"
    middle += (
        " C2   J2b    J3     130     200       100        0          Open"
        if layout == "pipe -> PRV -> pipe"
        else " C2   J3     J2b    130     200       100        0          Open"
    )
    path = write(
        tmp_path,
        "prv",
        middle=middle,
        j2b=0 if layout == "pipe -> PRV -> pipe" else 1.5,
        valves=" V1   J2a    J2b    250   PRV   25   0",
    )
    path.write_text(
        path.read_text(encoding="utf-8").replace(" J2b  10", " J2a  10    0\n J2b  10"),
        encoding="utf-8",
    )
    state = network.steady_state(network.load_network(path))
    assert state.heads["J2b"] - 10 == pytest.approx(25, abs=0.01)  # EPANET holds the setting
    assert state.heads["J2a"] - 10 > 35  # well above it: the PRV is active
    result = burst(path, "D")
    assert steady(result) < 0.02
    assert drop(result, "J3") > 0.5


def test_clock_times_units_and_a_quality_option_simulate(tmp_path: Path) -> None:
    # before: WNTR stopped at the rule's '6 AM' ("could not convert string to float") and at
    # the 'Chemical TIME' quality option
    sections = (
        "[TIMES]\n Duration 24 HOURS\n Hydraulic Timestep 30 MIN\n Pattern Timestep 1:00\n"
        " Start ClockTime 6 AM\n\n[RULES]\nRULE 1\nIF SYSTEM CLOCKTIME >= 6 AM\n"
        "AND SYSTEM CLOCKTIME < 8 PM\nTHEN PIPE E STATUS IS OPEN\n\n"
        "[QUALITY]\n J1 0.5\n\n[REACTIONS]\n Global Bulk -0.5\n"
    )
    path = write(tmp_path, "clock", options=" Quality  Chemical TIME", sections=sections)
    wn = network.load_network(path)
    assert wn.options.time.start_clocktime == 6 * 3600
    assert wn.options.time.hydraulic_timestep == 1800
    result = burst(path, "C")
    steady(result)
    assert np.all(np.isfinite(result.heads)) and drop(result, "J2b") > 0.5


def test_a_pipe_with_a_large_minor_loss_keeps_its_steady_loss(tmp_path: Path) -> None:
    # before: TSNet capped the friction factor the loss folds into at 0.08 (taking 0.03), the
    # pipe lost a fraction of EPANET's head and the network moved by metres (BWSN_Network_1)
    path = write(tmp_path, "minor")
    text = path.read_text(encoding="utf-8")
    old = " B    J1     J2     200     250       100        0 "
    path.write_text(text.replace(old, old.replace(" 0 ", " 500 ")), encoding="utf-8")
    state = network.steady_state(network.load_network(path))
    assert state.heads["J1"] - state.heads["J2"] > 1.5  # mostly the minor loss
    result = burst(path, "D")
    assert steady(result) < 0.01
    assert drop(result, "J3") > 0.5
