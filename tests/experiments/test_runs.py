"""burstloc.experiments.runs: run specifications, the paper's runs, clock offsets, durations."""

from __future__ import annotations

import pytest

from burstloc.exceptions import ConfigError
from burstloc.experiments import paper
from burstloc.experiments.runs import RunSpec, paper_runs, phase_offsets, required_duration
from burstloc.localize.detection import DetectorConfig, Mode

CUSUM = DetectorConfig("cusum", 0.3)


def test_run_spec_validation_and_params() -> None:
    spec = RunSpec(CUSUM, 0.2, 5)
    assert spec.params() == {
        "threshold": 0.3,
        "drift": 0.0,
        "localization_interval": 5,
        "mode": "window",
    }
    assert spec.paper_run() == paper.TABLE_I[0]
    assert RunSpec(CUSUM, 0.2, 6).paper_run() is None
    with pytest.raises(ConfigError, match=r"capture interval \(s\) must be .* in \(0, 3600\]"):
        RunSpec(CUSUM, 0.0, 5)
    with pytest.raises(ConfigError, match=r"localization_interval must be .* \[1, 100000\]"):
        RunSpec(CUSUM, 0.2, 0)
    with pytest.raises(ConfigError, match=r"localization_interval must be .* got 1844"):
        RunSpec(CUSUM, 0.2, 2**64)
    with pytest.raises(ValueError):
        RunSpec(CUSUM, 0.2, 5, mode="guess")  # type: ignore[arg-type]


def test_paper_runs_follow_tables_i_and_ii() -> None:
    runs = paper_runs()
    assert [
        (r.detector.kind, r.capture_interval, r.detector.threshold, r.localization_interval)
        for r in runs
    ] == [
        (p.detector, p.capture_interval, p.threshold, p.localization_interval)
        for p in paper.PAPER_RUNS
    ]
    assert [r.label for r in runs] == [p.scenario for p in paper.PAPER_RUNS]
    assert all(r.mode is Mode(paper.DEFAULT_MODE) for r in runs)
    both = paper_runs(["shewhart"], [0.2], ["window", "stream"], sigma=3.0)
    assert [(r.mode, r.detector.effective_sigma) for r in both] == [
        (Mode.WINDOW, 3.0),
        (Mode.STREAM, 3.0),
    ]
    with pytest.raises(ConfigError, match="unknown detector"):
        paper_runs(["ewma"])
    with pytest.raises(ConfigError, match="not one of the paper's"):
        paper_runs(["cusum"], [1.0])
    assert paper_runs(["cusum"], [1.0], threshold=1.0, localization_interval=3)[0].label is None
    with pytest.raises(ConfigError, match="Shewhart chart only"):
        paper_runs(["cusum"], sigma=2.0)
    with pytest.raises(ConfigError, match="CUSUM only"):
        paper_runs(["shewhart"], drift=0.1)


def test_phase_offsets_and_required_duration() -> None:
    spec = RunSpec(CUSUM, 0.2, 5)
    assert phase_offsets(spec, 5) == pytest.approx([0.0, 0.04, 0.08, 0.12, 0.16])
    assert phase_offsets(spec, 2, "window") == pytest.approx([0.0, 0.5])
    with pytest.raises(ConfigError, match="phases"):
        phase_offsets(spec, 0)
    with pytest.raises(ConfigError, match=r"phases must be an integer in \[1, 1000\], got 1844"):
        phase_offsets(spec, 2**64)  # refused, not a list of 2**64 offsets
    with pytest.raises(ConfigError, match="phase span"):
        phase_offsets(spec, 2, "day")
    ten = RunSpec(CUSUM, 10.0, 10)
    assert required_duration(ten, 10.0) == 220.0  # the paper's coarsest run, whatever the phase
    # the arrival localizer looks until its horizon after the first alarm: a network whose wave
    # travels 6 s (L-TOWN's bound) needs more than 2 x 5 readings at 0.2 s after the burst
    arrival = RunSpec(CUSUM, 0.2, 5, localizer="arrival")
    assert required_duration(arrival, 10.0) == pytest.approx(12.2)
    assert required_duration(arrival, 10.0, travel=6.0) == pytest.approx(22.4)
