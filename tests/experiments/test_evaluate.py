"""Scoring bursts: runs, phases, attempts, aggregates, and a short real simulated sweep."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.experiments import paper
from burstloc.experiments.evaluate import RunResult, evaluate
from burstloc.experiments.harness import locate_burst, readings_at_offset
from burstloc.experiments.runs import RunSpec
from burstloc.localize.detection import DetectorConfig, Mode
from conftest import PAPER15, write_tiny
from synthetic_bursts import small_graph, synthetic

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())
CUSUM = DetectorConfig("cusum", 0.3)


def test_capture_offsets_move_the_clock_earlier_with_steady_warm_up() -> None:
    r = synthetic("pB", {"B": (3.0, 0.2)})
    spec = RunSpec(CUSUM, 0.2, 5)
    t0, v0 = readings_at_offset(r, spec, 0.0)
    # 2 x 5 warm-up readings of the steady state, then the simulation from t = 0
    np.testing.assert_allclose(t0[:11], np.arange(-10, 1) * 0.2, atol=1e-12)
    np.testing.assert_array_equal(v0[:10], np.tile(r.heads[0], (10, 1)))
    t1, v1 = readings_at_offset(r, spec, 0.45)
    assert t1[0] == pytest.approx(-0.45 - 2.0)  # the whole grid moved 0.45 s earlier
    np.testing.assert_allclose(np.diff(t1), 0.2)
    first_simulated = int(np.searchsorted(t1, 0.0))
    assert t1[first_simulated] == pytest.approx(0.15)
    np.testing.assert_array_equal(v1[:first_simulated], np.tile(r.heads[0], (13, 1)))
    burst = int(np.searchsorted(t1, 2.2 - 1e-9))  # sample-and-hold of the drop at 2.2 s
    assert v1[burst, 1] == r.heads[0, 1] - 3.0 and v1[burst - 1, 1] == r.heads[0, 1]


def test_locate_burst_names_the_pipe_and_times_the_decision() -> None:
    r = synthetic("pB", {"B": (3.0, 0.2), "A": (1.0, 0.2)})
    a = locate_burst(r, small_graph(), RunSpec(CUSUM, 0.2, 5))
    assert a.located and a.correct and a.predicted == ("A", "B")
    assert a.localization is not None and a.localization.trigger_node == "B"
    # ticks 0, 0.2, ...; the drop is seen at 2.2; windows end at 0.8, 1.8, 2.8
    assert a.time_to_localize == pytest.approx(0.8)
    wrong = locate_burst(
        synthetic("pC", {"B": (3.0, 0.2), "A": (1.0, 0.2)}), small_graph(), RunSpec(CUSUM, 0.2, 5)
    )
    assert wrong.located and not wrong.correct


def test_nothing_detected_is_not_located() -> None:
    a = locate_burst(synthetic("pB", {}), small_graph(), RunSpec(CUSUM, 0.2, 5, Mode.STREAM))
    assert not a.located and not a.correct
    assert a.predicted is None and a.time_to_localize is None


def test_run_result_aggregates() -> None:
    g = small_graph()
    spec = RunSpec(CUSUM, 0.2, 5)
    hit = synthetic("pB", {"B": (3.0, 0.2), "A": (1.0, 0.2)})
    miss = synthetic("pC", {})
    offsets = [0.0, 0.1]
    attempts = {
        "pB": [locate_burst(hit, g, spec, o) for o in offsets],
        "pC": [locate_burst(miss, g, spec, o) for o in offsets],
    }
    rr = RunResult(spec, ["pB", "pC"], {"pB": ("A", "B"), "pC": ("A", "C")}, offsets, attempts)
    assert (rr.correct, rr.total, rr.accuracy) == (1, 2, 0.5)
    assert rr.phase_accuracies() == [0.5, 0.5]
    ttl = [a.time_to_localize for a in attempts["pB"]]
    assert rr.median_time_to_localize() == pytest.approx(float(np.median(ttl)))
    doc = rr.to_json()
    assert doc["pipes"][1]["predicted"] is None and doc["pipes"][1]["rule"] is None
    assert doc["paper"]["scenario"] == "S_C1" and doc["paper"]["correct_in_table"] == 22


@pytest.fixture(scope="module")
def short_evaluation():
    """Two real bursts on the paper's network, simulated briefly (cached for the session)."""
    runs = [
        RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, Mode.WINDOW, "S_C1"),
        RunSpec(DetectorConfig("shewhart", 1.5), 0.2, 5, Mode.STREAM, "S_S1"),
    ]
    scenario = paper.ScenarioConfig(burst_start=2.0)
    return evaluate(
        PAPER15, runs, pipes=["P4", "12"], phases=2, scenario=scenario, workers=1, progress=False
    )


def test_evaluate_short_real_sweep(short_evaluation) -> None:
    ev = short_evaluation
    assert ev.scenario["duration"] == 5.0  # 2 s onset + (2 x 5 + 1) x 0.2 s, rounded up
    doc = ev.to_json()
    jsonschema.validate(doc, SCHEMA)
    for run in doc["runs"]:
        assert run["total"] == 2
        assert [p["pipe"] for p in run["pipes"]] == ["P4", "12"]
        for p in run["pipes"]:
            assert " - ".join(p["true"]) == paper.TRUE_PIPES[p["pipe"]]
            if p["predicted"] is not None:
                assert p["correct"] == (p["predicted_pipe"] == p["pipe"])
                assert 0 < p["time_to_localize_s"] < 2 * 5 * 0.2 + 0.2
        assert run["accuracy_phase_min"] <= run["accuracy_phase_mean"]
        assert run["accuracy_phase_mean"] <= run["accuracy_phase_max"]
        assert run["correct"] == sum(p["correct"] for p in run["pipes"])


def test_negative_pressure_warning_names_the_burst_point_as_a_user_knows_it(
    tmp_path: Path,
) -> None:
    # A large, instant burst on the tiny network's pipe B: TSNet's solver reports negative
    # pressure at the junction it inserted on B (named "B_B" inside the simulation) and at J1-J3
    # (TSNet names a pipe's start node when its end is below zero: J2 after B_B -> J2).
    runs = [RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, Mode.WINDOW, "S_C1")]
    scenario = paper.ScenarioConfig(
        burst_start=0.2, opening_time=0.0, burst_coeff=0.02, solver="tsnet"
    )
    tiny = write_tiny(tmp_path / "tiny.inp")
    ev = evaluate(tiny, runs, pipes=["B"], phases=1, scenario=scenario, workers=1, progress=False)
    meta = ev.results["B"].metadata
    assert meta["burst_node"] in meta["negative_pressure_nodes"]
    [warning] = [w for w in ev.warnings if "negative pressure" in w]
    assert warning.startswith("burst on pipe B: negative pressure at ")
    places = warning.removeprefix("burst on pipe B: negative pressure at ").split(", ")
    assert "the burst point on pipe B" in places and "J1" in places
    assert "B_B" not in warning


def test_evaluate_rejects_bad_input_clearly(short_evaluation) -> None:
    runs = [RunSpec(CUSUM, 0.2, 5)]
    scenario = paper.ScenarioConfig(burst_start=2.0)
    with pytest.raises(NetworkError, match="unknown pipe"):
        evaluate(PAPER15, runs, pipes=["P99"], scenario=scenario, progress=False)
    with pytest.raises(NetworkError, match="not found"):
        evaluate("nowhere.inp", runs, scenario=scenario, progress=False)
    with pytest.raises(ConfigError, match="no runs"):
        evaluate(PAPER15, [], scenario=scenario, progress=False)
    with pytest.raises(ConfigError, match="needs"):
        evaluate(
            PAPER15,
            [RunSpec(CUSUM, 2.0, 10)],
            pipes=["P4"],
            scenario=paper.ScenarioConfig(burst_start=2.0, duration=5.0),
            progress=False,
        )
    # a simulation at a requested 0.09 s cannot provide readings every 0.01 s (by default the
    # time step would follow the capture interval: 0.005 s)
    fine = [RunSpec(CUSUM, 0.01, 100)]
    with pytest.raises(ConfigError, match="finer than the simulation time step"):
        evaluate(
            PAPER15,
            fine,
            pipes=["P4"],
            scenario=paper.ScenarioConfig(burst_start=2.0, duration=5.0),
            progress=False,
            time_step=0.09,
        )


def test_every_pipe_leaves_out_a_closed_pipe_and_says_so(tmp_path: Path) -> None:
    # pipe D (J2 - J3) closed in the file: no water reaches a burst on it
    tiny = write_tiny(tmp_path / "tiny.inp")
    text = tiny.read_text(encoding="utf-8")
    closed = tiny.with_name("closed.inp")
    closed.write_text(
        text.replace(
            " D    J2     J3     150     150       100        0          Open",
            " D    J2     J3     150     150       100        0          Closed",
        ),
        encoding="utf-8",
    )
    assert "Closed" in closed.read_text(encoding="utf-8")
    runs = [RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, Mode.WINDOW, "S_C1")]
    scenario = paper.ScenarioConfig(burst_start=0.2, opening_time=0.0, burst_coeff=0.02)
    ev = evaluate(closed, runs, phases=1, scenario=scenario, workers=1, progress=False)
    assert sorted(ev.results) == ["A", "B", "C", "E"]
    assert "1 pipe(s) closed in the network file, not burst: D" in ev.warnings
    with pytest.raises(NetworkError, match=r"pipe 'D' .* is closed"):
        evaluate(closed, runs, pipes=["D"], phases=1, scenario=scenario, progress=False)
