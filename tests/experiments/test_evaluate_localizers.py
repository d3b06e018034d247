"""burstloc.experiments.evaluate with the ranking localizers: calibrated bank, top-k,
--config."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import jsonschema
import numpy as np
import pytest

from burstloc.cli import main
from burstloc.exceptions import ConfigError
from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.evaluate import evaluate
from burstloc.experiments.runs import RunSpec
from burstloc.localize.config import Calibration
from burstloc.localize.decide import decision_time
from burstloc.localize.detection import DetectorConfig
from conftest import write_tiny

SCHEMA = json.loads((Path(__file__).parents[1] / "evaluate_schema.json").read_text())
SHORT = paper.ScenarioConfig(burst_start=2.0)


@pytest.fixture(scope="module")
def tiny_config(tiny: Path) -> Calibration:
    return calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)


def test_runspec_refuses_unknown_localizer_and_meter_model() -> None:
    with pytest.raises(ConfigError, match="localizer"):
        RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="magic")
    with pytest.raises(ConfigError, match="meter model"):
        RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, meter_model="peak")
    # The paper's figures belong to its rules only.
    assert RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5).paper_run() is not None
    assert RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival").paper_run() is None


def test_decision_time_per_localizer() -> None:
    times = np.arange(10) * 2.0
    alarms = [SimpleNamespace(index=5, start=3), SimpleNamespace(index=6, start=6)]
    cal = SimpleNamespace(capture_interval=2.0, arrival_decision_delay=1.5, decision_delay=150.0)
    assert decision_time("arrival", alarms, times, cal) == 10.0 + 1.5  # first alarm + delay
    # A start equal to the alarm reading (Shewhart) counts from the reading before it.
    assert decision_time("signature", alarms, times, cal) == 6.0 + 150.0  # onset + delay
    # a fused localizer whose arrivals can time the wave along some pipe below 1 s intervals
    fused = SimpleNamespace(resolves=lambda dt: dt < 1)
    assert decision_time("fused", alarms, times, cal, fused) == 156.0
    fast = SimpleNamespace(capture_interval=0.2, arrival_decision_delay=0.5, decision_delay=150.0)
    assert decision_time("fused", alarms, times, fast, fused) == 10.5


def test_ranking_localizers_report_top_k(tiny: Path, tiny_config: Calibration) -> None:
    runs = [
        RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival"),
        RunSpec(
            DetectorConfig("shewhart", 1.5),
            0.2,
            5,
            localizer="arrival",
            meter_model="interval-averaged",
        ),
    ]
    ev = evaluate(
        tiny,
        runs,
        pipes=["B", "C"],
        phases=2,
        scenario=SHORT,
        config=tiny_config,
        workers=1,
        progress=False,
    )
    doc = ev.to_json()
    jsonschema.validate(doc, SCHEMA)
    for run, spec in zip(doc["runs"], runs, strict=True):
        assert run["localizer"] == "arrival" and run["meter_model"] == spec.meter_model
        assert 0.0 <= run["top1"] <= run["top3"] <= 1.0
        assert run["top1"] == run["accuracy_phase_mean"]
        for pipe in run["pipes"]:
            # Every burst is detected and ranked within a second of the burst.
            assert pipe["predicted_pipe"] is not None and pipe["rule"] == "arrival"
            assert 0.0 < pipe["time_to_localize_s"] < 1.0
            assert pipe["top3"] >= pipe["correct"]
    result = ev.runs[0]
    for p in result.pipes:
        for a in result.attempts[p]:
            assert a.ranking is not None and len(a.ranking) == 5  # every pipe of the network
            assert a.correct == (a.ranking.rank_of(p) == 1)


def test_a_configuration_for_another_network_is_refused(
    tiny_config: Calibration, tmp_path: Path
) -> None:
    other = write_tiny(tmp_path / "other.inp", head=70.0)
    spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival")
    with pytest.raises(
        ConfigError, match=r"was calibrated for network .*tiny\.inp.*not for .*other\.inp"
    ):
        evaluate(
            other,
            [spec],
            pipes=["B"],
            phases=1,
            scenario=SHORT,
            config=tiny_config,
            workers=1,
            progress=False,
        )


def test_cli_evaluate_with_localizer_and_config(
    tiny: Path, tiny_config: Calibration, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    config = tiny_config.save(tmp_path / "tiny.json")
    out = tmp_path / "run.json"
    argv = [
        "evaluate",
        str(tiny),
        "--detector",
        "cusum",
        "--capture-interval",
        "0.2",
        "--localizer",
        "arrival",
        "--meter-model",
        "both",
        "--config",
        str(config),
        "--pipes",
        "C",
        "--phases",
        "1",
        "--json",
        str(out),
        "--quiet",
        "--workers",
        "1",
        "--plot",
        str(tmp_path / "plots"),
    ]
    assert main(argv) == 0
    assert any(p.suffix == ".png" for p in (tmp_path / "plots").iterdir())
    doc = json.loads(out.read_text())
    jsonschema.validate(doc, SCHEMA)
    assert [r["meter_model"] for r in doc["runs"]] == ["instantaneous", "interval-averaged"]
    assert "top-1 / top-3" in capsys.readouterr().out
    argv[argv.index("--config") + 1] = str(tmp_path / "missing.json")
    assert main(argv) == 2
    assert "cannot read configuration" in capsys.readouterr().err
