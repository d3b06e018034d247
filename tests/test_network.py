"""burstloc.network and networks/paper15.inp: loading, flow directions, splitting pipes."""

from __future__ import annotations

import hashlib
import importlib.util
import os
import pickle
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from burstloc import inp, network, network_file
from burstloc.exceptions import ConfigError, NetworkError
from conftest import PAPER15, REPO, TINY_INP, TNET1, write_tiny

# The paper's table of the extended network (and its result tables): pipe -> (start, end) in
# steady-state flow direction, length m, diameter mm, Hazen-Williams C (None: Tnet1's figures).
PAPER_TABLE: dict[str, tuple[str, str, float | None, float | None, float | None]] = {
    "P1": ("R1", "N3", None, None, None),
    "P2": ("N3", "N4", None, None, None),
    "P3": ("N3", "N2", None, None, None),
    "P4": ("N4", "N6", None, None, None),
    "P5": ("N4", "N2", None, None, None),
    "P6": ("N2", "N5", None, None, None),
    "P7": ("N5", "N7", None, None, None),
    "P8": ("N6", "N5", None, None, None),
    "P9": ("N2", "N6", None, None, None),
    "1": ("N7", "4", 750, 500, 100),
    "2": ("5", "8", 700, 500, 110),
    "3": ("1", "2", 600, 500, 120),
    "4": ("N3", "1", 650, 450, 120),
    "5": ("2", "3", 450, 450, 100),
    "6": ("3", "4", 350, 350, 130),
    "7": ("4", "5", 350, 200, 130),
    "8": ("N2", "2", 850, 500, 100),
    "9": ("N5", "3", 700, 500, 110),
    "11": ("6", "7", 400, 200, 100),
    "12": ("N6", "6", 450, 500, 120),
    "13": ("7", "N8", 900, 500, 110),
    "14": ("N8", "8", 500, 350, 120),
    "15": ("N7", "7", 800, 600, 100),
    "16": ("N7", "N8", 900, 400, 110),
    "17": ("1", "N2", 800, 300, 130),
}
NEW_DEMANDS_LPS = {"1": 15, "2": 10, "3": 20, "4": 20, "5": 8, "6": 2, "7": 8, "8": 15}


@pytest.fixture(scope="module")
def wn():  # type: ignore[no-untyped-def]
    return network.load_network(PAPER15)


@pytest.fixture(scope="module")
def graph(wn):  # type: ignore[no-untyped-def]
    return network.flow_direction_graph(wn)


# --- paper15.inp -----------------------------------------------------------------------------


@pytest.mark.parametrize("pipe", list(PAPER_TABLE))
def test_paper15_steady_state_flows_as_the_paper_table(graph, pipe: str) -> None:
    start, end = PAPER_TABLE[pipe][:2]
    assert network.pipe_endpoints(graph, pipe) == (start, end)
    assert graph.edges[start, end, pipe]["flow"] > 1e-4  # a real flow (> 0.1 L/s), not a tie


def test_paper15_has_the_papers_elements(wn) -> None:  # type: ignore[no-untyped-def]
    assert sorted(wn.pipe_name_list) == sorted(PAPER_TABLE)
    assert wn.num_junctions == 15 and wn.reservoir_name_list == ["R1"]
    assert wn.num_valves == 0 and wn.num_pumps == 0 and wn.num_tanks == 0


@pytest.mark.parametrize("pipe", [p for p, row in PAPER_TABLE.items() if row[2] is not None])
def test_paper15_new_pipe_figures(wn, pipe: str) -> None:  # type: ignore[no-untyped-def]
    start, end, length, diameter, c = PAPER_TABLE[pipe]
    link = wn.get_link(pipe)
    assert (link.start_node_name, link.end_node_name) == (start, end)
    assert link.length == pytest.approx(length)
    assert link.diameter == pytest.approx(diameter / 1000)
    assert link.roughness == pytest.approx(c)


def test_paper15_new_junctions(wn) -> None:  # type: ignore[no-untyped-def]
    for name, demand in NEW_DEMANDS_LPS.items():
        junction = wn.get_node(name)
        assert junction.elevation == 0
        assert junction.base_demand == pytest.approx(demand / 1000)
        assert junction.coordinates is not None


def test_paper15_keeps_tnet1_figures(wn) -> None:  # type: ignore[no-untyped-def]
    if not TNET1.is_file():
        pytest.skip(f"TSNet's Tnet1.inp is not at {TNET1}")
    tnet1 = network.load_network(TNET1)
    for pipe in (f"P{i}" for i in range(1, 10)):
        ours, theirs = wn.get_link(pipe), tnet1.get_link(pipe)
        assert (ours.start_node_name, ours.end_node_name) == (
            theirs.start_node_name,
            theirs.end_node_name,
        )
        assert (ours.length, ours.diameter, ours.roughness) == pytest.approx(
            (theirs.length, theirs.diameter, theirs.roughness)
        )
    for node in ("N2", "N3", "N4", "N5", "N6", "N7", "N8"):
        assert wn.get_node(node).base_demand == pytest.approx(tnet1.get_node(node).base_demand)
        assert wn.get_node(node).elevation == tnet1.get_node(node).elevation
    assert wn.get_node("R1").base_head == tnet1.get_node("R1").base_head


def test_paper15_is_what_the_builder_writes() -> None:
    if not TNET1.is_file():
        pytest.skip(f"TSNet's Tnet1.inp is not at {TNET1}")
    spec = importlib.util.spec_from_file_location(
        "build_paper15", REPO / "networks" / "build_paper15.py"
    )
    assert spec is not None and spec.loader is not None
    builder = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(builder)
    assert builder.build(TNET1) == PAPER15.read_text(encoding="utf-8")


def test_paper15_assets_is_what_the_builder_writes() -> None:
    spec = importlib.util.spec_from_file_location(
        "build_paper15_assets", REPO / "networks" / "build_paper15_assets.py"
    )
    assert spec is not None and spec.loader is not None
    builder = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(builder)
    assets = REPO / "networks" / "paper15_assets.inp"
    assert builder.build(PAPER15) == assets.read_text(encoding="utf-8")


def test_paper15_assets_has_the_valve_and_the_pump_and_clear_flows() -> None:
    wn = network.load_network(REPO / "networks" / "paper15_assets.inp")
    assert list(wn.valve_name_list) == ["V16"] and list(wn.pump_name_list) == ["PU1"]
    assert len(network.junction_names(wn)) == 18 and len(network.pipe_names(wn)) == 27
    flows = network.steady_state_flows(wn, "PDD")
    assert min(abs(flows[p]) for p in network.pipe_names(wn)) > 3e-3  # m³/s: no ambiguous pipe
    assert flows["18"] > 0.015  # the pump delivers into junction 8


# --- loading and errors ----------------------------------------------------------------------


def test_pipe_names_in_file_lists_pipes_in_order() -> None:
    assert inp.pipe_names_in_file(PAPER15) == list(PAPER_TABLE)


def test_missing_file_is_a_network_error(tmp_path: Path) -> None:
    missing = tmp_path / "nope.inp"
    with pytest.raises(NetworkError, match=r"nope\.inp"):
        network.load_network(missing)


def _broken(tmp_path: Path, old: str, new: str) -> Path:
    assert old in TINY_INP
    path = tmp_path / "broken.inp"
    path.write_text(TINY_INP.replace(old, new).format(head=60), encoding="utf-8")
    return path


def _line_of(path: Path, text: str) -> int:
    """The line of the first occurrence of ``text`` (the last one for a ``'...$'`` marker)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    hits = [i for i, line in enumerate(lines, start=1) if text.rstrip("$") in line]
    return hits[-1] if text.endswith("$") else hits[0]


@pytest.mark.parametrize(
    ("old", "new", "marker", "words"),
    [
        (
            " B    J1     J2     200     200       100        0          Open",
            " B    J1     J2",
            " B    J1     J2",
            "at least 6 fields",
        ),
        ("200       100", "2x0       100", "2x0", "not a number: '2x0'"),
        (" C    J1     J3", " C    J1     J9", " C    J1     J9", "unknown node 'J9'"),
        (" J3   0      5", " J2   0      5", " J2   0      5$", "duplicate ID 'J2'"),
        ("[PIPES]", "[PIPEZ]", "[PIPEZ]", "unknown INP section"),
        ("150       100        0          Open", "150 100 0 Shut", " D ", "unknown status"),
    ],
)
def test_malformed_inp_names_file_and_line(
    tmp_path: Path, old: str, new: str, marker: str, words: str
) -> None:
    path = _broken(tmp_path, old, new)
    with pytest.raises(NetworkError) as info:
        network.load_network(path)
    message = str(info.value)
    assert f"{path}:{_line_of(path, marker)}:" in message
    assert words in message


def test_malformed_option_is_reported_by_file(tmp_path: Path) -> None:
    path = _broken(tmp_path, " Units              LPS", " Units              FURLONGS")
    with pytest.raises(NetworkError, match=str(path)):
        network.load_network(path)


def test_require_pipe_names_unknown_pipe(wn) -> None:  # type: ignore[no-untyped-def]
    assert network.require_pipe(wn, "7").name == "7"
    with pytest.raises(NetworkError, match="'10'"):
        network.require_pipe(wn, "10")


def test_pipe_endpoints_unknown_pipe(graph) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(NetworkError, match="'P10'"):
        network.pipe_endpoints(graph, "P10")


def test_junction_names_are_the_meters_in_inp_order(wn) -> None:  # type: ignore[no-untyped-def]
    names = network.junction_names(wn)
    assert names == list(wn.junction_name_list)
    assert len(names) == 15 and "R1" not in names


# --- the flow-direction graph ----------------------------------------------------------------


def test_graph_turns_reverse_flow_pipes_around(wn, graph) -> None:  # type: ignore[no-untyped-def]
    # P6 is written N5 -> N2 in the INP but carries flow N2 -> N5.
    link = wn.get_link("P6")
    assert (link.start_node_name, link.end_node_name) == ("N5", "N2")
    flows = network.steady_state_flows(wn)
    assert flows["P6"] < 0
    assert graph.has_edge("N2", "N5") and not graph.has_edge("N5", "N2")
    assert graph.edges["N2", "N5", "P6"]["pipe"] == "P6"
    assert graph.edges["N2", "N5", "P6"]["flow"] == pytest.approx(-flows["P6"])


def test_graph_has_one_edge_per_link_and_mass_balance(wn, graph) -> None:  # type: ignore[no-untyped-def]
    assert graph.number_of_edges() == wn.num_links
    assert set(graph.nodes) == set(wn.node_name_list)
    # Every junction: inflow - outflow = its demand (demand-driven at these pressures).
    for name in network.junction_names(wn):
        inflow = sum(d["flow"] for _, _, d in graph.in_edges(name, data=True))
        outflow = sum(d["flow"] for _, _, d in graph.out_edges(name, data=True))
        assert inflow - outflow == pytest.approx(wn.get_node(name).base_demand, abs=2e-5)


def test_graph_keeps_inp_orientation_for_a_closed_pipe(tmp_path: Path) -> None:
    path = _broken(
        tmp_path,
        " D    J2     J3     150     150       100        0          Open",
        " D    J3     J2     150     150       100        0          Closed",
    )
    g = network.flow_direction_graph(network.load_network(path))
    assert network.pipe_endpoints(g, "D") == ("J3", "J2")
    assert g.edges["J3", "J2", "D"]["flow"] == 0


def test_parallel_links_are_edges_of_their_own(tmp_path: Path) -> None:
    # F runs beside B (J1 -> J2): each keeps its name, flow and end nodes; before, a DiGraph
    # refused the network ("parallel links are not supported")
    path = _broken(
        tmp_path, " E    J3     J4", " F    J1     J2     210     200       100\n E    J3     J4"
    )
    wn = network.load_network(path)
    flows = network.steady_state_flows(wn)
    g = network.flow_direction_graph(wn, flows)
    assert g.number_of_edges() == wn.num_links == 6
    assert network.pipe_endpoints(g, "B") == network.pipe_endpoints(g, "F") == ("J1", "J2")
    assert set(g["J1"]["J2"]) == {"B", "F"}
    for link in ("B", "F"):
        assert g.edges["J1", "J2", link]["flow"] == pytest.approx(abs(flows[link]))
    assert flows["B"] > flows["F"] > 0  # the shorter main carries more


def test_bad_engine_is_a_config_error(wn) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError, match="'XX'"):
        network.steady_state_flows(wn, "XX")


def test_one_steady_state_gives_heads_and_flows(wn, recwarn, capfd) -> None:  # type: ignore[no-untyped-def]
    hydraulic, times = wn.options.hydraulic, wn.options.time
    before = (hydraulic.demand_model, times.duration)
    state = network.steady_state(wn)
    assert (hydraulic.demand_model, times.duration) == before  # the model is left as it was
    assert set(state.heads) == set(wn.node_name_list)
    assert set(state.flows) == set(wn.link_name_list)
    assert state.flows == network.steady_state_flows(wn)
    assert state.heads["R1"] == pytest.approx(wn.get_node("R1").base_head)
    # the head drops along the flow: every pipe's upstream end is the higher one
    for name in wn.pipe_name_list:
        link = wn.get_link(name)
        up, down = link.start_node_name, link.end_node_name
        if state.flows[name] < 0:
            up, down = down, up
        assert state.heads[up] >= state.heads[down] - 1e-6, name
    # demand-driven solves too, and nothing EPANET says reaches the user
    assert network.steady_state(wn, "DD").flows["P1"] == pytest.approx(state.flows["P1"], rel=1e-3)
    assert not [w for w in recwarn if "EPANET" in str(w.message).upper()]
    assert capfd.readouterr() == ("", "")


# --- split_pipe ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    return network.load_network(write_tiny(tmp_path_factory.mktemp("tiny") / "tiny.inp"))


@given(fraction=st.floats(min_value=1e-3, max_value=1 - 1e-3))
def test_split_pipe_cuts_at_the_fraction(tiny, fraction: float) -> None:  # type: ignore[no-untyped-def]
    split = network.split_pipe(tiny, "B", fraction)
    wn2 = split.network
    first, second = wn2.get_link("B"), wn2.get_link(split.second_pipe)
    assert (first.start_node_name, first.end_node_name) == ("J1", split.burst_node)
    assert (second.start_node_name, second.end_node_name) == (split.burst_node, "J2")
    assert first.length == pytest.approx(200 * fraction)
    assert second.length == pytest.approx(200 * (1 - fraction))
    assert (second.diameter, second.roughness) == (first.diameter, first.roughness)
    assert wn2.get_node(split.burst_node).base_demand == 0
    assert split.pipe == "B" and split.fraction == fraction
    # The original network is untouched.
    assert tiny.get_link("B").length == 200 and split.burst_node not in tiny.node_name_list


def test_split_pipe_names_do_not_collide(tiny) -> None:  # type: ignore[no-untyped-def]
    first = network.split_pipe(tiny, "B")
    again = network.split_pipe(first.network, "B")
    assert again.burst_node != first.burst_node
    assert again.second_pipe != first.second_pipe


@pytest.mark.parametrize("fraction", [0.0, 1.0, -0.1, 1.5, float("nan")])
def test_split_pipe_rejects_positions_outside_0_1(tiny, fraction: float) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError, match="position"):
        network.split_pipe(tiny, "B", fraction)


def test_split_pipe_unknown_pipe(tiny) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(NetworkError, match="'Z'"):
        network.split_pipe(tiny, "Z")


def test_network_module_does_not_import_tsnet() -> None:
    code = (
        "import sys; from burstloc import network as n; "
        f"g = n.flow_direction_graph(n.load_network({str(PAPER15)!r})); "
        "assert 'tsnet' not in sys.modules, 'tsnet imported'; "
        "assert 'burstloc.sim.transient.tsnet' not in sys.modules; print('ok')"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


#: A junction with a demand and no way to any source: EPANET cannot solve it demand-driven.
ISLAND_INP = """\
[JUNCTIONS]
 J1 0 5
 J2 0 5
 J3 0 5
[RESERVOIRS]
 R1 50
[PIPES]
 P1 R1 J1 100 200 100 0 Open
 P2 J2 J3 100 200 100 0 Open
[OPTIONS]
 Units LPS
 Headloss H-W
[END]
"""


def test_a_steady_state_leaves_no_file_in_the_working_directory(
    wn, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:  # type: ignore[no-untyped-def]
    island = tmp_path / "island.inp"
    island.write_text(ISLAND_INP, encoding="utf-8")
    unsolvable = network.load_network(island)
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    network.steady_state(wn)
    network.steady_state(wn, "DD")
    # a failed solve: EPANET's scratch file ("en" and 6 characters) stayed here, before
    with pytest.raises(NetworkError, match=r"\(demand-driven\): \(Error 110\)"):
        network.steady_state(unsolvable, "DD")
    assert list(work.iterdir()) == []
    assert Path.cwd() == work


#: A network EPANET solves demand-driven only: its pressure law is illegal (the file says how).
DEMAND_DRIVEN_ONLY = REPO / "tests" / "demand_driven_only.inp"


def test_a_network_epanet_solves_only_demand_driven_is_solved_so_and_said(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    wntr = pytest.importorskip("wntr")
    monkeypatch.chdir(tmp_path)  # WNTR's own runs leave EPANET's scratch files here
    wn = network.load_network(DEMAND_DRIVEN_ONLY)
    # EPANET itself, through WNTR: pressure-driven it refuses the model, demand-driven it solves
    wn.options.hydraulic.demand_model = "PDD"
    with pytest.raises(wntr.epanet.exceptions.EpanetException, match="Error 200"):
        wntr.sim.EpanetSimulator(wn).run_sim(file_prefix=str(tmp_path / "pdd"))
    assert "PDA" in (tmp_path / "pdd.inp").read_text()  # (its report says Error 208, unflushed)
    wn.options.hydraulic.demand_model = "DD"
    solved = wntr.sim.EpanetSimulator(wn).run_sim(file_prefix=str(tmp_path / "dd"))
    wn.options.hydraulic.demand_model = "PDD"
    with pytest.warns(network.DemandDrivenWarning) as said:
        state = network.steady_state(wn)
    (warning,) = said
    assert str(warning.message) == (
        f"EPANET cannot solve {DEMAND_DRIVEN_ONLY} pressure-driven ((Error 200) one or more "
        "errors in input file): its steady state is solved demand-driven instead (every demand "
        "met in full, whatever the pressure)"
    )
    assert state.engine == "DD" and wn.options.hydraulic.demand_model == "PDA"  # as it was
    heads = solved.node["head"].iloc[0]
    assert state.heads == pytest.approx({n: float(heads[n]) for n in wn.node_name_list})
    assert network.steady_state(wn, "DD").engine == "DD"
    with pytest.raises(NetworkError, match="demand-driven either"):  # neither solves: said
        network.steady_state(network.load_network(_island(tmp_path)), "PDD")


def _island(folder: Path) -> Path:
    """The island network with the illegal pressure law too: neither engine solves it."""
    limits = " Demand Model PDA\n Minimum Pressure 30\n Required Pressure 20"
    text = ISLAND_INP.replace(" Headloss H-W", f" Headloss H-W\n{limits}")
    path = folder / "island_pda.inp"
    path.write_text(text, encoding="utf-8")
    return path


def _written_an_hour_ago(path: Path) -> Path:
    hour_ago = time.time() - 3600
    os.utime(path, (hour_ago, hour_ago))
    return path


def test_read_network_reads_the_file_once_and_keeps_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = _written_an_hour_ago(write_tiny(tmp_path / "tiny.inp"))
    reads: list[str] = []
    real = inp.read_bytes
    monkeypatch.setattr(inp, "read_bytes", lambda p: reads.append(str(p)) or real(p))
    monkeypatch.setattr(network_file, "read_bytes", inp.read_bytes)
    first = network.read_network(path)
    assert reads == [str(path)]  # structure checked, hashed and read by WNTR: one read
    assert first.hash == "sha256:" + hashlib.sha256(path.read_bytes()).hexdigest()
    assert first.path == str(path) and first.model.name == str(path)
    assert first.pipes == tuple(inp.pipe_names_in_file(path)) == ("A", "B", "C", "D", "E")
    assert first.junctions == ("J1", "J2", "J3", "J4")
    reads.clear()
    assert network.read_network(path) is first  # kept: nothing read
    assert inp.network_hash(path) == first.hash  # its fingerprint kept too
    assert network.as_network(first) is first
    assert reads == []
    again = network.read_network(os.path.relpath(path))  # another name of the same file
    assert again.model is first.model and again.path == os.path.relpath(path)
    assert reads == []


def test_a_file_written_again_is_read_again(tmp_path: Path) -> None:
    path = _written_an_hour_ago(write_tiny(tmp_path / "tiny.inp"))
    first = network.read_network(path)
    write_tiny(path, head=70.0)  # the same size, written again
    second = network.read_network(path)
    assert second.hash != first.hash
    assert second.model.get_node("R1").base_head == pytest.approx(70.0)
    assert first.model.get_node("R1").base_head == pytest.approx(60.0)


def test_a_file_written_just_before_it_was_read_is_hashed_again_not_parsed(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Written within the file system's timestamp granularity of the read, a file could be
    written again without changing its times or size: its bytes are compared."""
    path = write_tiny(tmp_path / "tiny.inp")
    first = network.read_network(path)
    reads: list[str] = []
    real = inp.read_bytes
    monkeypatch.setattr(inp, "read_bytes", lambda p: reads.append(str(p)) or real(p))
    assert network.read_network(path) is first
    assert reads == [str(path)]


def test_the_model_is_shared_and_an_editable_copy_is_the_callers(tmp_path: Path) -> None:
    path = _written_an_hour_ago(write_tiny(tmp_path / "tiny.inp"))
    read = network.read_network(path)
    mine = network.load_network(read)
    assert mine is not read.model
    mine.remove_link("E")
    assert "E" in read.model.pipe_name_list
    assert "E" in network.load_network(path).pipe_name_list


def test_a_pickled_network_is_read_again_from_its_file(tmp_path: Path) -> None:
    path = _written_an_hour_ago(write_tiny(tmp_path / "tiny.inp"))
    read = network.read_network(path)
    sent = pickle.dumps(read)
    assert len(sent) < 1000  # the path and the hash, not the model
    assert pickle.loads(sent) is read  # this process read it already
    write_tiny(path, head=70.0)
    with pytest.raises(NetworkError, match="changed"):
        pickle.loads(sent)
