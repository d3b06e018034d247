"""Transient-ready models (burstloc.skeleton): short pipes merged or lengthened, nothing lost.

Two small INP networks: one with every kind of element next to short pipes (written here; the
structure checks), and tests/connector_network.py's, with a 0.3 m connector between two branch
junctions and a 0.5 m one in series (EPANET steady states here; its TSNet runs are in
tests/sim/test_short_pipes.py).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from burstloc import network, skeleton
from burstloc.exceptions import ConfigError, NetworkError
from connector_network import CONNECTOR_INP, METERS

#: Every element beside a short pipe: a pump and a valve between short pipes, a tank at the
#: end of one, a check-valve pipe, a pipe named by a control, a junction with an emitter.
ELEMENTS_INP = """\
[JUNCTIONS]
 A  0  0
 B  0  1
 C  0  0
 D  0  1
 E  0  0
 F  0  1
 G  0  0
 H  0  1

[RESERVOIRS]
 R  10

[TANKS]
;ID Elev InitLvl MinLvl MaxLvl Diam MinVol
 T  20   5       0      10     10   0

[PIPES]
 S1  R  A  2    300  120  0  Open
 L1  B  C  400  300  120  0  Open
 S2  C  D  1    300  120  0  CV
 L2  D  E  400  300  120  0  Open
 S3  E  T  1.5  300  120  0  Open
 S4  E  F  2    300  120  0  Open
 L3  F  G  400  300  120  0  Open
 S5  G  H  1    300  120  0  Open
 L4  H  E  400  300  120  0  Open

[PUMPS]
 PU  A  B  HEAD CURVE1

[VALVES]
 V1  D  F  300  PRV  30  0

[CURVES]
 CURVE1  50  40

[EMITTERS]
 G  0.1

[CONTROLS]
 LINK S4 CLOSED AT TIME 5

[OPTIONS]
 Units     LPS
 Headloss  H-W

[END]
"""


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture
def connectors(tmp_path: Path) -> Path:
    return _write(tmp_path, "connectors.inp", CONNECTOR_INP)


def test_no_pipe_stays_shorter_than_asked_and_the_step_grows(connectors: Path) -> None:
    wn = network.load_network(connectors)
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=METERS)
    assert skeleton.shortest_pipe(wn) == ("C1", 0.3)
    assert skeleton.shortest_pipe(prepared.network)[1] >= 20.0
    before = skeleton.courant_time_step(wn, 1200.0)
    after = skeleton.courant_time_step(prepared.network, 1200.0)
    assert before == pytest.approx(0.3 / 2400)
    assert after >= 20.0 / 2400 > 60 * before
    assert wn.get_link("C1").length == 0.3  # the original is left alone


def test_series_connector_merges_branch_connector_lengthens(connectors: Path) -> None:
    wn = network.load_network(connectors)
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=METERS)
    model = prepared.network
    # C2 (J4-J5) merged into P5 at J5 (two pipes, no meter): one pipe J4-J6 named P5
    assert "C2" not in model.link_name_list and "J5" not in model.node_name_list
    merged = model.get_link("P5")
    assert (merged.start_node_name, merged.end_node_name) == ("J4", "J6")
    assert merged.length == pytest.approx(35.5)
    assert prepared.pieces["C2"] == skeleton.PipePiece("P5", 0.0, pytest.approx(0.5 / 35.5))
    assert prepared.pieces["P5"].start == pytest.approx(0.5 / 35.5)
    assert prepared.originals("P5") == ["C2", "P5"]
    # C1 (J1-J2): J1 is a meter, J2 joins three pipes: lengthened, diameter widened
    assert prepared.lengthened == {"C1": pytest.approx(0.3)}
    c1 = model.get_link("C1")
    assert c1.length == 20.0
    assert c1.diameter == pytest.approx(0.3 * (20.0 / 0.3) ** (1 / 4.871))
    assert prepared.summary()["merged"] == {"C2": "P5"}
    assert prepared.moved_demands == {}  # J5 had none


def test_a_merged_pipe_keeps_its_pieces_travel_time(connectors: Path) -> None:
    wn = network.load_network(connectors)
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=METERS)
    given = {p: 1200.0 for p in wn.pipe_name_list} | {"C2": 300.0, "C1": 400.0}
    speeds = prepared.wave_speeds(given)
    # P5 carries C2 (0.5 m at 300 m/s) and the old P5 (35 m at 1200 m/s)
    assert speeds["P5"] * (0.5 / 300.0 + 35.0 / 1200.0) == pytest.approx(35.5)
    assert speeds["C1"] == 400.0  # lengthened: its own speed
    assert "C2" not in speeds  # merged away
    assert set(speeds) == set(prepared.network.pipe_name_list)


def test_every_original_pipe_is_carried_and_located(connectors: Path) -> None:
    wn = network.load_network(connectors)
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=METERS)
    assert set(prepared.pieces) == set(wn.pipe_name_list)
    model_pipes = set(prepared.network.pipe_name_list)
    for original in wn.pipe_name_list:
        pipe, fraction = prepared.locate(original, 0.25)
        assert pipe in model_pipes and 0.0 < fraction < 1.0
        assert original in prepared.originals(pipe)
        back, position = prepared.original_at(pipe, fraction)
        assert (back, position) == (original, pytest.approx(0.25))
    with pytest.raises(NetworkError, match="unknown pipe 'nope'"):
        prepared.locate("nope", 0.5)


def test_steady_heads_at_the_meters_stay_within_a_centimetre(connectors: Path) -> None:
    wn = network.load_network(connectors)
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=METERS)
    before = network.steady_state(wn).heads
    after = network.steady_state(prepared.network).heads
    for meter in METERS:
        assert after[meter] == pytest.approx(before[meter], abs=0.01)
    assert before["J6"] < 59.0  # there is head loss to keep


def test_demand_of_a_removed_junction_moves_to_the_connector_end(tmp_path: Path) -> None:
    path = _write(tmp_path, "demand.inp", CONNECTOR_INP.replace(" J5  0     0", " J5  0     1 "))
    wn = network.load_network(path)
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=["J1", "J3", "J6"])
    assert prepared.moved_demands == {"J5": "J4"}
    demand = sum(d.base_value for d in prepared.network.get_node("J4").demand_timeseries_list)
    assert demand == pytest.approx(0.016)  # 15 + 1 L/s


def test_pumps_valves_tanks_reservoirs_and_guarded_pipes_are_kept(tmp_path: Path) -> None:
    wn = network.load_network(_write(tmp_path, "elements.inp", ELEMENTS_INP))
    prepared = skeleton.prepare_transient_model(wn, 50.0, keep=["H"])
    model = prepared.network
    assert set(model.pump_name_list) == {"PU"} and set(model.valve_name_list) == {"V1"}
    assert set(model.tank_name_list) == {"T"} and set(model.reservoir_name_list) == {"R"}
    pump = model.get_link("PU")
    assert (pump.start_node_name, pump.end_node_name) == ("A", "B")
    # S1 ends at the reservoir and the pump, S3 at the tank, S2 is a check valve, S4 is named
    # by a control, S5 joins the emitter junction G to the kept junction H: each is
    # lengthened, none merged away
    assert set(prepared.lengthened) == {"S1", "S2", "S3", "S4", "S5"}
    assert model.get_link("S2").check_valve
    assert {p.pipe for p in prepared.pieces.values()} == set(model.pipe_name_list)
    assert skeleton.shortest_pipe(model)[1] >= 50.0
    assert len(model.control_name_list) == 1


def test_bad_arguments_are_named(connectors: Path) -> None:
    wn = network.load_network(connectors)
    for bad in (0.0, -1.0, float("nan"), True):
        with pytest.raises(ConfigError, match="min_pipe_length"):
            skeleton.prepare_transient_model(wn, bad)  # type: ignore[arg-type]
    with pytest.raises(NetworkError, match=r"\['R1'\] are not junctions"):
        skeleton.prepare_transient_model(wn, 10.0, keep=["R1"])
    prepared = skeleton.prepare_transient_model(wn, 10.0)
    with pytest.raises(NetworkError, match="within"):
        prepared.original_at("P1", 1.5)


def test_a_network_without_short_pipes_is_unchanged(connectors: Path) -> None:
    wn = network.load_network(connectors)
    prepared = skeleton.prepare_transient_model(wn, 0.1)
    assert prepared.summary()["merged"] == {} and prepared.lengthened == {}
    assert sorted(prepared.network.pipe_name_list) == sorted(wn.pipe_name_list)


# WNTR reads [OPTIONS] after [PIPES] and warns that roughness units do not follow the formula
@pytest.mark.filterwarnings("ignore:Changing the headloss formula")
@pytest.mark.parametrize(
    ("formula", "roughness"), [("H-W", None), ("D-W", "0.1"), ("C-M", "0.012")]
)
def test_each_head_loss_formula_keeps_the_steady_heads(
    tmp_path: Path, formula: str, roughness: str | None
) -> None:
    text = CONNECTOR_INP.replace("Headloss  H-W", f"Headloss  {formula}")
    if roughness is not None:  # the same roughness in every pipe, in the formula's own unit
        text = "\n".join(
            " ".join([*line.split()[:5], roughness, *line.split()[6:]])
            if line.split()[:1] and line.split()[0] in {"P1", "C1", "P2", "P3", "P4", "C2", "P5"}
            else line
            for line in text.splitlines()
        )
    wn = network.load_network(_write(tmp_path, "formula.inp", text))
    prepared = skeleton.prepare_transient_model(wn, 20.0, keep=METERS)
    assert prepared.lengthened and prepared.summary()["merged"] == {"C2": "P5"}
    before = network.steady_state(wn).heads
    after = network.steady_state(prepared.network).heads
    loss = max(60.0 - before[m] for m in METERS)
    assert loss > 0.5
    for meter in METERS:
        assert after[meter] == pytest.approx(before[meter], abs=0.02 * loss)
