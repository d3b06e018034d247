"""burstloc.sim.transient.tsnet: burst scenarios on split pipes, TSNet output, sweeps, bad input."""

from __future__ import annotations

import contextlib
import json
import math
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from burstloc import inp, network
from burstloc.exceptions import ConfigError, NetworkError, SimulationError
from burstloc.sim.scenarios.cache import DiskCache
from burstloc.sim.scenarios.result import ScenarioResult, output_path
from burstloc.sim.scenarios.scenario import BurstScenario, burst_scenarios
from burstloc.sim.transient.time_step import expected_time_step
from burstloc.sim.transient.tsnet import simulate_burst, simulate_many
from burstloc.wave_speeds import WaveSpeeds
from conftest import write_tiny

SHORT = {"burst_start": 0.5, "duration": 3.0}


@pytest.fixture(scope="module")
def pipe7(tmp_path_factory: pytest.TempPathFactory, paper15: Path) -> ScenarioResult:
    """A 3 s burst in the middle of paper15's pipe 7 (4 -> 5)."""
    store = DiskCache(tmp_path_factory.mktemp("cache"))
    return simulate_burst(BurstScenario(paper15, "7", **SHORT), cache=store)


# --- one scenario ----------------------------------------------------------------------------


def test_meters_are_the_original_junctions(pipe7: ScenarioResult, paper15: Path) -> None:
    wn = network.load_network(paper15)
    assert pipe7.junctions == network.junction_names(wn)
    assert pipe7.metadata["burst_node"] not in pipe7.junctions
    assert pipe7.heads.shape == (pipe7.time.size, 15)


def test_time_is_tsnets_grid(pipe7: ScenarioResult) -> None:
    dt = pipe7.time_step
    assert 0 < dt < 0.2  # fine enough for the paper's 0.2 s capture interval
    np.testing.assert_allclose(pipe7.time, np.arange(pipe7.time.size) * dt)
    assert pipe7.time.size == int(3.0 / dt)
    assert pipe7.metadata["time_step"] == dt


def test_metadata_names_the_true_pipe_in_flow_direction(pipe7: ScenarioResult) -> None:
    meta = pipe7.metadata
    assert pipe7.pipe == "7" and pipe7.true_endpoints == ("4", "5")
    assert meta["split_pipes"][0] == "7" and meta["position"] == 0.5
    assert meta["burst_start"] == 0.5 and meta["duration"] == 3.0
    assert meta["wave_speed"] == 1200.0 and meta["engine"] == "PDD"
    assert set(meta["versions"]) == {"burstloc", "tsnet", "wntr", "numpy"}
    assert meta["capture_interval"] is None
    json.dumps(meta)  # plain JSON


def test_pressure_is_steady_before_the_burst_and_drops_after(pipe7: ScenarioResult) -> None:
    before = pipe7.heads[pipe7.time < 0.5]
    assert np.ptp(before, axis=0).max() < 1e-3  # the PDD initial state is the MOC's steady state
    # Node 4, an end of pipe 7, loses several metres once the wave from mid-pipe arrives
    # (175 m at 1200 m/s: 0.15 s after the burst starts).
    col = pipe7.junctions.index("4")
    after = pipe7.heads[pipe7.time > 0.5 + 0.2, col]
    assert after.min() < before[0, col] - 5
    # The reservoir-fed side barely moves in the first instants: farthest junctions react later.
    first_drop = {
        j: pipe7.time[np.argmax(pipe7.heads[:, i] < before[0, i] - 0.5)]
        for i, j in enumerate(pipe7.junctions)
    }
    assert first_drop["4"] <= min(first_drop.values()) + 1e-9


def test_tsnet_output_is_captured_not_printed(
    tiny_network: Path,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    work = tmp_path / "cwd"
    work.mkdir()
    monkeypatch.chdir(work)
    with _no_warnings():
        result = simulate_burst(
            BurstScenario(tiny_network, "B", burst_start=0.2, duration=1.5), cache=False
        )
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""
    assert list(work.iterdir()) == []  # EPANET's temp.inp/.rpt/.bin went elsewhere
    assert all(isinstance(w, str) for w in result.metadata["warnings"])


@contextlib.contextmanager
def _no_warnings() -> Iterator[None]:
    """Fail if a warning escapes to the caller."""
    with warnings.catch_warnings(record=True) as log:
        warnings.simplefilter("always")
        yield
    assert [str(w.message) for w in log] == []


def test_negative_pressures_are_reported_in_metadata(tmp_path: Path) -> None:
    # A large, instant burst on small pipes: the down-surge empties the pipes near it.
    inp = write_tiny(tmp_path / "tiny.inp", head=60)
    scenario = BurstScenario(
        inp, "B", burst_start=0.2, opening_time=0.0, burst_coeff=0.01, duration=2.0
    )
    result = simulate_burst(scenario, cache=False)
    assert result.heads.min() < 0
    nodes = result.metadata["negative_pressure_nodes"]
    assert nodes and set(nodes) <= {"J1", "J2", "J3", "J4", result.metadata["burst_node"]}
    assert any("Negative pressure" in w for w in result.metadata["warnings"])


def test_position_moves_the_burst_junction(tiny_network: Path) -> None:
    near = simulate_burst(
        BurstScenario(tiny_network, "B", position=0.1, burst_start=0.2, duration=1.5), cache=False
    )
    far = simulate_burst(
        BurstScenario(tiny_network, "B", position=0.9, burst_start=0.2, duration=1.5), cache=False
    )
    j1, j2 = near.junctions.index("J1"), near.junctions.index("J2")

    def arrival(result: ScenarioResult, col: int) -> float:
        base = result.heads[0, col]
        return float(result.time[np.argmax(result.heads[:, col] < base - 0.5)])

    # Near J1 (10% along J1 -> J2), the wave reaches J1 before J2; near J2 it is the other way.
    assert arrival(near, j1) < arrival(near, j2)
    assert arrival(far, j2) < arrival(far, j1)


def test_friction_model_reaches_tsnet_and_the_cache_key(tiny_network: Path) -> None:
    steady = BurstScenario(tiny_network, "B", burst_start=0.2, duration=3.0)
    unsteady = BurstScenario(
        tiny_network, "B", burst_start=0.2, duration=3.0, friction="unsteady", solver="tsnet"
    )
    # The default is left out of the key: scenarios cached before the field keep their keys.
    assert "friction" not in steady.parameters()
    assert unsteady.parameters()["friction"] == "unsteady"
    assert steady.cache_key() != unsteady.cache_key()
    a = simulate_burst(steady, cache=False)
    b = simulate_burst(unsteady, cache=False)
    assert a.heads.shape == b.heads.shape
    np.testing.assert_array_equal(a.heads[0], b.heads[0])  # same steady state
    assert float(np.max(np.abs(a.heads - b.heads))) > 1e-3  # different transient damping
    assert b.metadata["friction"] == "unsteady"


@pytest.mark.parametrize(
    ("pipe", "position", "time_step", "speeds"),
    [
        ("B", 0.5, None, None),
        ("E", 0.1, None, None),  # a half shorter than every pipe: the connectors shorten too
        ("C", 0.7, 0.004, None),
        ("D", 0.3, None, WaveSpeeds((("D", 400.0), ("A", 900.0)))),
        ("B", 0.5, None, WaveSpeeds(diameters=((1.0, 500.0),))),
    ],
)
def test_expected_time_step_is_tsnets(
    tiny_network: Path,
    pipe: str,
    position: float,
    time_step: float | None,
    speeds: WaveSpeeds | None,
) -> None:
    scenario = BurstScenario(
        tiny_network,
        pipe,
        position=position,
        burst_start=0.2,
        duration=1.5,
        time_step=time_step,
        wave_speeds=speeds,
    )
    result = simulate_burst(scenario, cache=False)
    assert expected_time_step(scenario) == pytest.approx(result.time_step, rel=1e-12)


def test_expected_time_step_names_an_unknown_pipe(tiny_network: Path) -> None:
    with pytest.raises(NetworkError, match="ZZ"):
        expected_time_step(BurstScenario(tiny_network, "ZZ"))


def test_resample_keeps_metadata_and_checks_the_interval(pipe7: ScenarioResult) -> None:
    readings = pipe7.resample(0.2)
    assert (
        readings.metadata["capture_interval"] == 0.2 and readings.metadata["capture_phase"] == 0.0
    )
    np.testing.assert_allclose(np.diff(readings.time), 0.2)
    assert readings.junctions == pipe7.junctions and readings.time_step == pipe7.time_step
    with pytest.raises(ConfigError, match="finer than the simulation time step"):
        pipe7.resample(pipe7.time_step / 2)


def test_npz_is_readable_with_plain_numpy(pipe7: ScenarioResult, tmp_path: Path) -> None:
    path = pipe7.save(output_path(tmp_path, pipe7))
    assert path.name == "paper15_pipe-7.npz"
    with np.load(path, allow_pickle=False) as data:
        assert sorted(data.files) == ["heads", "junctions", "metadata", "time"]
        np.testing.assert_array_equal(data["heads"], pipe7.heads)
        assert list(data["junctions"]) == pipe7.junctions
        meta = json.loads(str(data["metadata"]))
    assert meta["pipe"] == "7" and meta["time_step"] == pipe7.time_step
    again = ScenarioResult.load(path)
    np.testing.assert_array_equal(again.time, pipe7.time)
    assert again.metadata == pipe7.metadata | {"time_step": pipe7.time_step}


# --- bad input -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        ("position", 0.0, "position"),
        ("position", 1.0, "position"),
        ("position", -0.2, "position"),
        ("position", math.nan, "position"),
        ("duration", 10.0, "duration (10.0 s) must be longer than burst_start (10.0 s)"),
        ("duration", 5.0, "duration"),
        ("burst_coeff", 0.0, "burst_coeff must be > 0, got 0.0"),
        ("burst_coeff", -0.01, "-0.01"),
        ("wave_speed", 0.0, "wave_speed must be > 0 m/s, got 0.0"),
        ("wave_speed", -1200, "-1200"),
        ("burst_start", -1.0, "burst_start"),
        ("opening_time", -1.0, "opening_time"),
        ("time_step", 0.0, "time_step"),
        ("engine", "EPANET", "'EPANET'"),
        ("burst_coeff", "big", "'big'"),
        ("burst_coeff", True, "True"),
        ("friction", "laminar", "'laminar'"),
    ],
)
def test_bad_parameters_are_config_errors(
    paper15: Path, field: str, value: object, words: str
) -> None:
    with pytest.raises(ConfigError) as info:
        BurstScenario(paper15, "7", **{field: value})  # type: ignore[arg-type]
    assert words in str(info.value)


@given(position=st.one_of(st.floats(max_value=0.0), st.floats(min_value=1.0)))
def test_positions_outside_the_pipe_are_refused(position: float) -> None:
    with pytest.raises(ConfigError, match="position"):
        BurstScenario("any.inp", "7", position=position)


def test_unknown_pipe_is_a_network_error(paper15: Path) -> None:
    with pytest.raises(NetworkError, match="'10'"):
        simulate_burst(BurstScenario(paper15, "10", **SHORT), cache=False)
    with pytest.raises(NetworkError, match=r"\['10', 'P0'\]"):
        burst_scenarios(paper15, ["7", "10", "P0"])


def test_missing_or_malformed_network(tmp_path: Path) -> None:
    with pytest.raises(NetworkError, match=r"missing\.inp"):
        simulate_burst(BurstScenario(tmp_path / "missing.inp", "7"), cache=True)
    bad = tmp_path / "bad.inp"
    bad.write_text("[JUNCTIONS]\n J1 zero 5\n", encoding="utf-8")
    with pytest.raises(NetworkError, match=f"{bad}:2:"):
        simulate_burst(BurstScenario(bad, "A"), cache=False)


def test_time_step_above_the_stability_limit(tiny_network: Path) -> None:
    with pytest.raises(ConfigError, match="time_step 1 s exceeds TSNet's stability limit"):
        simulate_burst(
            BurstScenario(tiny_network, "B", time_step=1.0, burst_start=0.2, duration=30),
            cache=False,
        )


def test_too_short_a_simulation(tiny_network: Path) -> None:
    with pytest.raises(ConfigError, match="TSNet needs at least 10"):
        simulate_burst(
            BurstScenario(tiny_network, "B", burst_start=0.01, duration=0.1), cache=False
        )


# --- sweeps ----------------------------------------------------------------------------------


def test_burst_scenarios_default_to_every_pipe(paper15: Path) -> None:
    scenarios = burst_scenarios(paper15, duration=100.0)
    assert [s.pipe for s in scenarios] == inp.pipe_names_in_file(paper15)
    assert len(scenarios) == 25 and all(s.duration == 100.0 for s in scenarios)


def test_simulate_many_reports_a_failure_and_completes_the_rest(
    tiny_network: Path, cache_dir: Path
) -> None:
    good = burst_scenarios(tiny_network, ["A", "C"], burst_start=0.2, duration=1.5)
    broken = BurstScenario(tiny_network, "B", burst_start=0.2, duration=30, time_step=1.0)
    scenarios = [good[0], broken, good[1]]
    store = DiskCache(cache_dir)
    report = simulate_many(scenarios, cache=store, workers=2, progress=False)
    assert [r is not None for r in report.results] == [True, False, True]
    assert [r.pipe for r in report.results if r is not None] == ["A", "C"]
    (failure,) = report.failures
    assert failure.index == 1 and failure.item == broken
    assert "pipe B" in str(failure) and failure.error_type == "ConfigError"
    assert "stability limit" in failure.message
    # The successes were cached as they arrived: a second sweep loads them.
    again = simulate_many(scenarios[::2], cache=store, workers=2, progress=False)
    assert again.ok and all(r is not None and r.metadata["cache"] == "hit" for r in again.results)
    np.testing.assert_array_equal(again.results[0].heads, report.results[0].heads)  # type: ignore[union-attr]


def test_simulate_many_missing_file_fails_early(tmp_path: Path, cache_dir: Path) -> None:
    report = simulate_many(
        [BurstScenario(tmp_path / "gone.inp", "A")], cache=DiskCache(cache_dir), progress=False
    )
    (failure,) = report.failures
    assert failure.error_type == "NetworkError" and "gone.inp" in failure.message


def test_simulate_many_on_a_dask_cluster(
    dask_scheduler: str, tiny_network: Path, cache_dir: Path
) -> None:
    scenarios = burst_scenarios(tiny_network, ["A", "B", "E"], burst_start=0.2, duration=1.5)
    report = simulate_many(
        scenarios, cache=DiskCache(cache_dir), scheduler=dask_scheduler, progress=False
    )
    assert report.ok
    local = simulate_burst(scenarios[1], cache=False)
    result = report.results[1]
    assert result is not None and result.pipe == "B"
    np.testing.assert_array_equal(result.heads, local.heads)  # same simulation, deterministic
    assert all(s.cache_key() in DiskCache(cache_dir) for s in scenarios)


def test_a_junction_below_atmospheric_pressure_at_the_start(tmp_path: Path) -> None:
    # J3, a dead end 80 m up, lies above the hydraulic grade (as Net3's junction 10 with its
    # pump closed). Without demand it simulates, held at its -20.5 m and reported; with a demand
    # (EPANET's demand-driven steady state keeps it) TSNet's start takes the square root of its
    # pressure, and the refusal names it.
    text = (
        "[JUNCTIONS]\n J1  0  10\n J2  0  10\n J3  80  {demand}\n\n[RESERVOIRS]\n R1  60\n\n"
        "[PIPES]\n A  R1  J1  300  250  100  0  Open\n B  J1  J2  300  250  100  0  Open\n"
        " C  J2  J3  300  150  100  0  Open\n\n[OPTIONS]\n Units  LPS\n Headloss  H-W\n\n[END]\n"
    )
    inp = tmp_path / "uphill.inp"
    inp.write_text(text.format(demand=0), encoding="utf-8")
    for solver in ("vectorized", "tsnet"):
        scenario = BurstScenario(inp, "B", burst_start=0.5, duration=1.5, solver=solver)
        result = simulate_burst(scenario, cache=False)
        j3 = result.heads[:, result.junctions.index("J3")]
        assert j3[0] == pytest.approx(-20.5, abs=0.1) and np.ptp(j3) < 0.01
        warned = result.metadata["negative_pressure_nodes"]
        if solver == "vectorized":  # said as where it starts, not as the burst's doing
            assert warned == []
            assert any("Node J3 starts below" in w for w in result.metadata["warnings"])
        else:  # TSNet warns at every step, naming the pipe's start node (J2) for its end (J3)
            assert warned == ["J2"]
    # with a demand 80 m up, J3's consumers are below absolute vacuum: a fault of the model
    inp.write_text(text.format(demand=1), encoding="utf-8")
    with pytest.raises(NetworkError, match=r"uphill\.inp:4: junction 'J3' .* -20\.\d m .*vacuum"):
        simulate_burst(
            BurstScenario(inp, "B", burst_start=0.5, duration=1.5, engine="DD"), cache=False
        )
    # 65 m up, -5.5 m: EPANET's demand-driven state still delivers its demand, which TSNet's
    # start cannot (the square root of its pressure); the refusal names it
    inp.write_text(text.format(demand=1).replace(" J3  80", " J3  65"), encoding="utf-8")
    with pytest.raises(SimulationError, match=r"negative pressure .*'J3' -5\.\d+ m"):
        simulate_burst(
            BurstScenario(inp, "B", burst_start=0.5, duration=1.5, engine="DD"), cache=False
        )
