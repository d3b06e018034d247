"""What kept models of the published library from a steady transient start, each on a small real
INP file: a pipe rougher than TSNet's friction cap (KY13, KY14), a pipe EPANET closes at a full
tank (KY11), EPANET's steady state left unconverged by loose options (KY15, exnet-3), a junction
below atmospheric pressure that EPANET delivers nothing (KY15, exnet-3), a pump near shut-off
(MICROPOLIS's well pumps), a pipe from a dead end to a tank (Richmond_skeleton), a closed valve
a control sets at the start (BWSN_Network_2); and the models
refused as faults of the model (below absolute vacuum, no demand delivered: anytown-exeter,
hanoi-exeter). Each burst runs on the vectorized solver, and ``simulate_burst`` refuses a run
whose heads move more than 5 cm before the onset (``burstloc.sim.transient.steady``)."""

from __future__ import annotations

from pathlib import Path

import pytest
from test_elements import burst, drop  # a 2 s burst at 1 s; a junction's fall
from test_elements import steady as moved  # the movement before it, within the tolerance

from burstloc import network
from burstloc.exceptions import NetworkError
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst

#: R1 -> J1 -> J2 -> J3 -> J4 with {extra} lines added per test.
CHAIN = """\
[TITLE]
transient start test network

[JUNCTIONS]
;ID  Elev  Demand
 J1   0     2
 J2   0     3
 J3   {j3}     {d3}
 J4   0     2
{junctions}

[RESERVOIRS]
 R1   {head}
{reservoirs}

[TANKS]
{tanks}

[PIPES]
;ID  Node1  Node2  Length  Diameter  Roughness  MinorLoss  Status
 A    R1     J1     300     300       100        0          Open
 B    J1     J2     250     {bd}       {br}        0          Open
 C    J2     J3     250     200       100        0          Open
 D    J3     J4     200     150       100        0          Open
{pipes}

[PUMPS]
{pumps}

[CURVES]
{curves}

[OPTIONS]
 Units  LPS
 Headloss  H-W
{options}

[END]
"""

PLAIN = {
    "head": 60,
    "j3": 0,
    "d3": 3,
    "bd": 250,
    "br": 100,
    "junctions": "",
    "reservoirs": "",
    "tanks": "",
    "pipes": "",
    "pumps": "",
    "curves": "",
    "options": "",
}


def write(tmp_path: Path, name: str, **changes: str | float) -> Path:
    """The chain with ``changes``, as ``tmp_path/name.inp``."""
    (path := tmp_path / f"{name}.inp").write_text(CHAIN.format(**{**PLAIN, **changes}), "utf-8")
    return path


def test_a_pipe_rougher_than_tsnets_friction_cap_keeps_its_steady_friction(
    tmp_path: Path,
) -> None:
    # before: TSNet replaced the Darcy-Weisbach factor (about 3 for C = 10) by 0.03 and J2-J4
    # moved by metres (KY13, KY14: Hazen-Williams pipes at low velocity, over half of KY14's)
    path = write(tmp_path, "rough", br=10, bd=200)
    assert moved(burst(path, "C")) < 0.01
    assert drop(burst(path, "C"), "J3") > 0.5


def test_a_pipe_epanet_closes_at_a_full_tank_stays_shut(tmp_path: Path) -> None:
    # T1 is full (level at its maximum) and J2 is above it: EPANET closes E rather than fill it.
    # Before: TSNet held T1's head and opened E, J2 moved by metres (KY11's T-24 and T-4)
    path = write(
        tmp_path,
        "full_tank",
        tanks=" T1   0    30   0   30   10   0",
        pipes=" E    J2     T1     100     150       100        0          Open",
    )
    state = network.steady_state(network.load_network(path))
    assert "E" in state.closed and state.flows["E"] == 0.0
    assert state.heads["J2"] > 40  # well above the tank's 30 m: E would fill it
    result = burst(path, "C")
    assert moved(result) < 0.01
    assert result.metadata["closed_at_rest"] == ["E"]
    assert drop(result, "J3") > 0.5


def test_a_steady_state_left_unconverged_by_the_models_options_is_converged(
    tmp_path: Path,
) -> None:
    # Trials 1, Accuracy 0.1: EPANET stops before the flows balance (exnet-3's Accuracy 0.1,
    # KY15's pumps and valves switching past its 100 trials); TSNet started from that state
    # and moved. The transient's steady state is solved to 1000 trials and accuracy 0.001.
    path = write(
        tmp_path,
        "loose",
        pipes=" E    J1     J4     400     100       100        0          Open",
        options=" Trials  1\n Accuracy  0.1\n Unbalanced  Continue",
    )
    result = burst(path, "C")
    assert moved(result) < 0.01
    assert drop(result, "J3") > 0.5


def test_a_junction_below_zero_pressure_that_epanet_delivers_nothing(tmp_path: Path) -> None:
    # J3 is 65 m up, 5.5 m below atmospheric pressure: EPANET's pressure-driven state delivers
    # none of its demand. Before: TSNet's demand coefficient 1e-8 / sqrt(-5.5), NaN, and every
    # head non-finite (KY15, exnet-3)
    path = write(tmp_path, "uphill", j3=65, d3=1)
    state = network.steady_state(network.load_network(path))
    assert state.heads["J3"] - 65 < -1 and abs(state.demands["J3"]) < 1e-6
    result = burst(path, "B")
    assert moved(result) < 0.01
    assert drop(result, "J2") > 0.5


#: Pumps near shut-off: four in parallel (as MICROPOLIS's four well pumps), each on a design
#: curve (0, 44.2 m), (23.7 L/s, 39.6 m), (34.7 L/s, 27.4 m), lifting from R2 into J1 against R1
#: (44 m above R2).
NEAR_SHUT_OFF = {
    "head": 44,
    "reservoirs": " R2   0",
    "pumps": "\n".join(f" P{i}   R2    J5    HEAD  1" for i in range(1, 5)),
    "junctions": " J5   0     0",
    "pipes": " E    J5     J1     30      300       100        0          Open",
    "curves": " 1   0   44.2\n 1   23.66   39.6\n 1   34.7   27.4",
}


def test_a_pump_near_shut_off_keeps_a_falling_curve(tmp_path: Path) -> None:
    # TSNet refits each curve through the operating point, replacing the design point nearest
    # to it: the shut-off point, and the new parabola rises there (slope > 0), so the pumps
    # feed waves back amplified. Before: J5 moved 0.12 m by 8 s; MICROPOLIS's heads 5 m by 3 s
    path = write(tmp_path, "shut_off", **NEAR_SHUT_OFF)
    state = network.steady_state(network.load_network(path))
    assert 0 < state.flows["P1"] < 0.01  # a few L/s of the curve's 35
    result = simulate_burst(BurstScenario(path, "C", burst_start=8.0, duration=9.0), cache=False)
    assert moved(result) < 0.01
    assert drop(result, "J3") > 0.5


def test_a_pipe_from_a_dead_end_to_a_tank_is_turned_around(tmp_path: Path) -> None:
    # J5 is a dead end fed by the tank T1 only (Richmond_skeleton's junction 753 below its
    # closed pump). Before: "the vectorized solver cannot simulate pipe 'E': a Tank at its end
    # with nothing at its start"
    path = write(
        tmp_path,
        "dead_end_tank",
        junctions=" J5   0     1",
        tanks=" T1   0    30   0   40   10   0",
        pipes=" E    J5     T1     300     100       100        0          Open",
    )
    result = burst(path, "C")
    assert moved(result) < 0.01
    assert result.metadata["turned_pipes"] == ["E"]
    assert drop(result, "J3") > 0.5


def test_a_closed_valve_a_control_sets_at_the_start_is_held_at_its_steady_loss(
    tmp_path: Path,
) -> None:
    # V1 (an FCV filling T1) is Closed in [STATUS] and given its setting by a control at 0:00,
    # so EPANET's steady state runs it at 5 L/s. Before: TSNet kept it shut and J6 moved 32 m
    # (BWSN_Network_2's FCVs 14826 and 14828: junction 12501 moved 106 m)
    path = write(
        tmp_path,
        "control_at_start",
        junctions=" J5   0     0\n J6   0     0",
        tanks=" T1   0    10   0   40   10   0",
        pipes=" E    J2     J5     100     150       100        0          Open\n"
        " F    J6     T1     100     150       100        0          Open",
        options="\n[VALVES]\n V1   J5   J6   150   FCV   5   0\n\n[STATUS]\n V1  Closed\n\n"
        "[CONTROLS]\n LINK V1 5 AT TIME 0:00:00\n",
    )
    state = network.steady_state(network.load_network(path))
    assert state.flows["V1"] == pytest.approx(0.005, rel=1e-3)
    result = burst(path, "C")
    assert moved(result) < 0.01
    assert drop(result, "J3") > 0.5


def test_a_model_that_delivers_none_of_its_demand_is_refused_naming_a_junction(
    tmp_path: Path,
) -> None:
    # pipes 0.0001 mm wide (hanoi-exeter's design template): EPANET's pressure-driven steady
    # state delivers nothing. Before: "junction ... moved 940 m", the symptom
    path = write(tmp_path, "template")
    text = path.read_text(encoding="utf-8").replace("300     300", "300     0.0001")
    path.write_text(text, encoding="utf-8")
    with pytest.raises(NetworkError, match=r"template\.inp:\d+: EPANET's steady state delivers"):
        burst(path, "D")
