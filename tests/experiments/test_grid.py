"""burstloc.experiments.grid: the study's one-factor-at-a-time points, settings and bursts."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from burstloc.exceptions import ConfigError
from burstloc.experiments.grid import (
    DEFAULT_LEVELS,
    Factors,
    StudyPoint,
    StudySettings,
    point_scenarios,
    study_grid,
    study_time_step,
)
from burstloc.wave_speeds import WaveSpeeds


def test_grid_varies_one_factor_at_a_time_on_the_first_network() -> None:
    points = study_grid(["a.inp", "b.inp", "c.inp"])
    defaults = [p for p in points if p.factor == "default"]
    assert [p.network for p in defaults] == ["a.inp", "b.inp", "c.inp"]
    assert all(p.factors == Factors() for p in defaults)
    varied = [p for p in points if p.factor != "default"]
    assert {p.network for p in varied} == {"a.inp"}
    expected = sum(len(v) - 1 for v in DEFAULT_LEVELS.values())
    assert len(varied) == expected
    for p in varied:
        changed = {k for k, v in vars(p.factors).items() if v != getattr(Factors(), k)}
        assert changed == {p.factor}
    assert StudyPoint("x/paper15.inp", "noise_sigma", Factors(noise_sigma=0.05)).label == (
        "paper15: noise_sigma=0.05"
    )


def test_grid_refuses_unknown_factors_and_no_network() -> None:
    with pytest.raises(ConfigError, match="unknown study factor"):
        study_grid(["a.inp"], {"colour": (1, 2)})
    with pytest.raises(ConfigError, match="at least one network"):
        study_grid([])


def test_bad_settings_and_factors_are_refused() -> None:
    with pytest.raises(ConfigError, match="detectors"):
        StudySettings(detectors=("ewma",))
    with pytest.raises(ConfigError, match="meter_models"):
        StudySettings(meter_models=("peak",))
    with pytest.raises(ConfigError, match="phases"):
        StudySettings(phases=0)
    with pytest.raises(ConfigError, match="meter_fraction"):
        Factors(meter_fraction=0.0)
    with pytest.raises(ConfigError, match="noise_sigma"):
        Factors(noise_sigma=-0.1)


def test_scenarios_carry_the_factors_and_settings(tiny_network: Path) -> None:
    point = StudyPoint(str(tiny_network), "friction", Factors(friction="unsteady", position=0.3))
    settings = StudySettings(pipes=("B", "C"), duration=50.0, time_step=0.05)
    scenarios = point_scenarios(point, settings)
    assert [s.pipe for s in scenarios] == ["B", "C"]
    assert {(s.friction, s.position, s.duration, s.time_step) for s in scenarios} == {
        ("unsteady", 0.3, 50.0, 0.05)
    }
    assert {s.wave_speeds for s in scenarios} == {None}
    slow = WaveSpeeds((("D", 250.0),), source="speeds.csv")
    timed = point_scenarios(point, replace(settings, wave_speeds=slow))
    assert {s.wave_speeds for s in timed} == {slow}  # simulated at D's speed
    assert timed[0].cache_key() != scenarios[0].cache_key()


def test_the_settings_record_the_wave_speeds_only_when_given() -> None:
    assert "wave_speeds" not in StudySettings().to_json()
    slow = WaveSpeeds((("D", 250.0),), source="speeds.csv")
    assert StudySettings(wave_speeds=slow).to_json()["wave_speeds"] == {
        "pipes": {"D": 250.0},
        "diameters": [],
    }
    with pytest.raises(ConfigError, match="wave_speeds must be WaveSpeeds"):
        StudySettings(wave_speeds={"D": 250.0})  # type: ignore[arg-type]


def test_time_step_rule_keeps_tsnets_step_unless_coarser_than_the_finest_capture(
    tiny_network: Path,
) -> None:
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.time_step import expected_time_step

    scenario = BurstScenario(str(tiny_network), "B")
    tsnet_step = expected_time_step(scenario)
    coarse = StudySettings(capture_intervals=(2 * tsnet_step, 10.0))
    fine = StudySettings(capture_intervals=(0.5 * tsnet_step, 10.0))
    assert study_time_step(scenario, coarse) is None
    assert study_time_step(scenario, fine) == pytest.approx(0.25 * tsnet_step)
    given = StudySettings(capture_intervals=(0.5 * tsnet_step,), time_step=0.001)
    assert study_time_step(scenario, given) == 0.001
    point = StudyPoint(str(tiny_network), "default")
    assert {s.time_step for s in point_scenarios(point, fine)} == {0.25 * tsnet_step}
