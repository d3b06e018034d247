"""burstloc.sim.steady: a simulation whose heads move before the event is refused, by name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import SimulationError, UnsteadyStartError
from burstloc.sim.scenario import BurstScenario
from burstloc.sim.steady import STEADY_TOLERANCE, check_steady_start, steady_start
from burstloc.sim.tsnet import simulate_burst

#: Three junctions behind a pipe far rougher (Hazen-Williams C = 10, a Darcy-Weisbach factor of
#: about 3) than TSNet's friction cap of 0.08, which it replaces by 0.03: TSNet's transient does
#: not start from EPANET's steady state. (An active throttle valve, TSNet's shut valve, was the
#: example before burstloc held valves at their steady loss: burstloc.sim.tsnet_elements.)
ROUGH_PIPE_INP = """\
[TITLE]
tiny network with a pipe rougher than TSNet's friction cap

[JUNCTIONS]
;ID   Elev   Demand
 J1   0      5
 J2   0      5
 J3   0      5

[RESERVOIRS]
 R1   60

[PIPES]
;ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status
 A    R1     J1     300     300       100        0          Open
 V1   J1     J2     250     200       10         0          Open
 B    J2     J3     250     200       100        0          Open

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


def test_an_unsteady_network_is_refused_naming_the_junction(tmp_path: Path) -> None:
    inp = tmp_path / "rough_pipe.inp"
    inp.write_text(ROUGH_PIPE_INP, encoding="utf-8")
    with pytest.raises(UnsteadyStartError) as caught:
        simulate_burst(BurstScenario(inp, "B", burst_start=1.0, duration=1.5), cache=False)
    error = caught.value
    assert isinstance(error, SimulationError)
    assert error.junction == "J2" and error.movement > 10.0 and error.time < 1.0
    assert error.network == str(inp)
    assert "junction 'J2' moved" in str(error) and str(inp) in str(error)
