"""burstloc.sim.transient.steady: a simulation whose heads move before the event is refused, by
name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import SimulationError, UnsteadyStartError
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient import tsnet_run
from burstloc.sim.transient.steady import STEADY_TOLERANCE, check_steady_start, steady_start
from burstloc.sim.transient.tsnet import simulate_burst

#: A pressure-reducing valve between two pipes, active in EPANET's steady state (it holds J2 at
#: 20 m): TSNet's own valve model takes an active valve as shut, so without burstloc holding it
# : at its steady loss (``burstloc.sim.transient.tsnet_elements.hold_valves``) the transient does
# not start
#: from EPANET's steady state. (A pipe rougher than TSNet's friction cap was the example before
#: burstloc kept every pipe's steady friction factor: burstloc.sim.transient._tsnet_compat.)
ACTIVE_VALVE_INP = """\
[TITLE]
tiny network with an active pressure-reducing valve

[JUNCTIONS]
;ID   Elev   Demand
 J1   0      5
 J1a  0      0
 J2a  0      0
 J2   0      5
 J3   0      5

[RESERVOIRS]
 R1   60

[PIPES]
;ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status
 A    R1     J1     300     300       100        0          Open
 A2   J1     J1a    250     200       100        0          Open
 B2   J2a    J2     250     200       100        0          Open
 B    J2     J3     250     200       100        0          Open

[VALVES]
;ID  Node1  Node2  Diameter  Type  Setting  MinorLoss
 V1   J1a    J2a    200       PRV   20       0

[OPTIONS]
 Units  LPS
 Headloss  H-W

[END]
"""


def test_the_largest_movement_before_the_onset_is_found() -> None:
    times = np.arange(10) * 0.5
    heads = np.full((10, 3), 40.0)
    heads[3, 1] += 0.2  # junction "b" at 1.5 s, before the onset
    heads[8, 2] -= 9.0  # the event itself (4.0 s): not part of the start
    found = steady_start(times, heads, ["a", "b", "c"], onset=4.0)
    assert (found.junction, found.movement, found.time) == ("b", pytest.approx(0.2), 1.5)
    with pytest.raises(UnsteadyStartError, match=r"net\.inp .* junction 'b' moved 0\.2 m"):
        check_steady_start(times, heads, ["a", "b", "c"], 4.0, "net.inp")
    heads[3, 1] = 40.0 + STEADY_TOLERANCE / 2
    assert check_steady_start(times, heads, ["a", "b", "c"], 4.0, "net.inp").junction == "b"


def test_no_step_before_the_onset_is_a_steady_start() -> None:
    found = steady_start(np.array([0.0, 1.0]), np.array([[1.0], [5.0]]), ["a"], onset=0.0)
    assert found.movement == 0.0 and found.junction is None


def test_a_steady_network_passes_and_records_its_movement(tiny_network: Path) -> None:
    result = simulate_burst(BurstScenario(tiny_network, "B", burst_start=0.5, duration=1.5))
    record = result.metadata["steady_start"]
    assert 0.0 <= record["max_movement_m"] < STEADY_TOLERANCE
    assert record["onset"] == 0.5 and record["tolerance_m"] == STEADY_TOLERANCE


def test_an_unsteady_network_is_refused_naming_the_junction(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    inp = tmp_path / "active_valve.inp"
    inp.write_text(ACTIVE_VALVE_INP, encoding="utf-8")
    scenario = BurstScenario(inp, "B", burst_start=1.0, duration=1.5)
    assert simulate_burst(scenario, cache=False).metadata["steady_start"]["max_movement_m"] < 0.01
    monkeypatch.setattr(tsnet_run, "hold_valves", lambda tm: [])  # TSNet's own model of the valve
    with pytest.raises(UnsteadyStartError) as caught:
        simulate_burst(scenario, cache=False)
    error = caught.value
    assert isinstance(error, SimulationError)
    assert error.junction == "J1a" and error.movement > 10.0 and error.time < 1.0  # the shut valve
    assert error.network == str(inp)
    assert "junction 'J1a' moved" in str(error) and str(inp) in str(error)
