"""burstloc.sim.scenarios.perturb: a perturbed truth, its draws, and its simulation by TSNet."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.network import load_network
from burstloc.sim.scenarios.perturb import (
    TruthPerturbation,
    clock_offsets,
    perturb_roughness,
    pipe_wave_speeds,
    shift_clocks,
    silence,
)
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst

SHORT = {"burst_start": 0.5, "duration": 3.0}


# --- the perturbation and its draws ----------------------------------------------------------


@pytest.mark.parametrize(
    ("fields", "message"),
    [
        ({"wave_speed_spread": 1.0}, "--truth-wave-speed-spread must be in [0, 1), got 1.0"),
        ({"wave_speed_spread": -0.1}, "--truth-wave-speed-spread must be a finite number"),
        ({"roughness_spread": 1.5}, "--truth-roughness-spread must be in [0, 1), got 1.5"),
        ({"clock_offset": -0.005}, "--truth-clock-offset must be a finite number"),
        ({"clock_offset": float("nan")}, "--truth-clock-offset must be a finite number"),
        ({"silent_meter": -1.0}, "--truth-silent-meter must be a finite number"),
        ({"seed": -1}, "--truth-seed must be a whole number >= 0, got -1"),
        ({"seed": 1.5}, "--truth-seed must be a whole number >= 0, got 1.5"),
    ],
)
def test_bad_values_name_their_option(fields: dict[str, float], message: str) -> None:
    with pytest.raises(ConfigError) as error:
        TruthPerturbation(**fields)  # type: ignore[arg-type]
    assert message in str(error.value)


def test_off_by_default_and_only_the_simulated_part_is_simulated() -> None:
    assert not TruthPerturbation().active and TruthPerturbation().describe() == "none"
    heard_only = TruthPerturbation(clock_offset=0.005, silent_meter=2.0, seed=3)
    assert heard_only.active and heard_only.heard and heard_only.simulated() is None
    both = TruthPerturbation(wave_speed_spread=0.15, clock_offset=0.005, seed=3)
    assert both.simulated() == TruthPerturbation(wave_speed_spread=0.15, seed=3)
    assert both.to_dict() == {
        "wave_speed_spread": 0.15,
        "roughness_spread": 0.0,
        "clock_offset": 0.005,
        "silent_meter": None,
        "seed": 3,
    }
    assert both.describe() == (
        "wave speeds ±15 % per pipe, meter clocks off by N(0, (5 ms)²) (seed 3)"
    )


def test_draws_are_per_name_in_range_and_seeded() -> None:
    truth = TruthPerturbation(wave_speed_spread=0.15, clock_offset=0.005, seed=7)
    pipes = [f"P{i}" for i in range(200)]
    speeds = pipe_wave_speeds(truth, 1200.0, pipes)
    values = np.array(list(speeds.values()))
    assert values.min() >= 1020.0 and values.max() <= 1380.0 and values.std() > 50.0
    # one pipe's draw does not depend on the others drawn with it
    assert pipe_wave_speeds(truth, 1200.0, ["P5"])["P5"] == speeds["P5"]
    assert pipe_wave_speeds(truth, 1200.0, ["P5_2"], {"P5_2": "P5"})["P5_2"] == speeds["P5"]
    other = pipe_wave_speeds(TruthPerturbation(wave_speed_spread=0.15, seed=8), 1200.0, pipes)
    assert other != speeds
    offsets = clock_offsets(truth, pipes)
    assert clock_offsets(truth, pipes[::-1])[::-1].tolist() == offsets.tolist()
    assert 0.003 < offsets.std() < 0.007 and np.all(offsets != 0)
    assert not clock_offsets(TruthPerturbation(), pipes).any()
    assert pipe_wave_speeds(TruthPerturbation(roughness_spread=0.3), 1200.0, pipes) == {}


def test_roughness_is_multiplied_per_pipe(paper15: Path) -> None:
    wn = load_network(paper15)
    before = {name: float(pipe.roughness) for name, pipe in wn.pipes()}
    factors = perturb_roughness(TruthPerturbation(roughness_spread=0.3, seed=1), wn)
    assert set(factors) == set(before)
    for name, pipe in wn.pipes():
        assert 0.7 <= factors[name] <= 1.3
        assert float(pipe.roughness) == pytest.approx(before[name] * factors[name])
    assert len(set(factors.values())) == len(factors)


def test_clocks_shift_each_column_and_silence_blanks_one() -> None:
    time = np.arange(0.0, 1.0, 0.01)
    heads = np.column_stack([time, 2 * time])
    shifted = shift_clocks(time, heads, np.array([0.0, 0.05]))
    assert shifted[:, 0].tolist() == heads[:, 0].tolist()
    # column 1 read 0.05 s late: its value at t is the head at t + 0.05 (held at the end)
    np.testing.assert_allclose(shifted[:-5, 1], 2 * (time[:-5] + 0.05))
    early = shift_clocks(time, heads, np.array([0.0, -0.05]))
    assert early[0, 1] == 0.0  # before the start: the initial steady state
    quiet = silence(time, heads, 1, 0.505)  # between two simulated instants
    assert np.isnan(quiet[50:, 1]).all() and not np.isnan(quiet[:50]).any()  # from t = 0.5
    assert not np.isnan(quiet[:, 0]).any() and not np.isnan(heads).any()


# --- the simulated truth ---------------------------------------------------------------------


def test_the_scenario_keeps_only_the_simulated_part_and_is_keyed_apart(paper15: Path) -> None:
    plain = BurstScenario(paper15, "P7", **SHORT)
    heard = BurstScenario(paper15, "P7", **SHORT, truth=TruthPerturbation(clock_offset=0.005))
    assert heard.truth is None and heard.cache_key() == plain.cache_key()
    assert "truth" not in plain.parameters()
    spread = BurstScenario(paper15, "P7", **SHORT, truth=TruthPerturbation(wave_speed_spread=0.1))
    again = BurstScenario(
        paper15, "P7", **SHORT, truth=TruthPerturbation(wave_speed_spread=0.1, silent_meter=1.0)
    )
    reseeded = BurstScenario(
        paper15, "P7", **SHORT, truth=TruthPerturbation(wave_speed_spread=0.1, seed=1)
    )
    keys = {plain.cache_key(), spread.cache_key(), reseeded.cache_key()}
    assert len(keys) == 3 and again.cache_key() == spread.cache_key()
    with pytest.raises(ConfigError, match="truth must be a TruthPerturbation"):
        BurstScenario(paper15, "P7", truth={"wave_speed_spread": 0.1})  # type: ignore[arg-type]


def _slow_seed(spread: float, pipe: str) -> int:
    """A seed whose draw makes ``pipe`` at least 10 % slower than the model."""
    return next(
        seed
        for seed in range(100)
        if pipe_wave_speeds(TruthPerturbation(wave_speed_spread=spread, seed=seed), 1.0, [pipe])[
            pipe
        ]
        < 0.9
    )


def _arrival(result: ScenarioResult, junction: str) -> float:
    """When the head at ``junction`` first moves 5 cm from its steady value."""
    j = result.junctions.index(junction)
    moved = np.abs(result.heads[:, j] - result.heads[0, j]) > 0.05
    return float(result.time[np.argmax(moved)])


def test_a_slower_pipe_in_the_truth_brings_the_wave_later(paper15: Path) -> None:
    # P7 (N5 - N7, 1000 m) bursts mid-pipe: the wave reaches N7 along its second half only
    fine = {**SHORT, "time_step": 0.02}
    plain = simulate_burst(BurstScenario(paper15, "P7", **fine), cache=False)
    truth = TruthPerturbation(wave_speed_spread=0.15, seed=_slow_seed(0.15, "P7"))
    slow = simulate_burst(BurstScenario(paper15, "P7", **fine, truth=truth), cache=False)
    assert slow.metadata["truth"] == truth.simulated().to_dict()  # type: ignore[union-attr]
    # 500 m at 1200 m/s: 0.42 s; at <= 1080 m/s: >= 0.46 s (two steps later, at least)
    assert _arrival(slow, "N7") >= _arrival(plain, "N7") + 0.03
    assert _arrival(plain, "N7") == pytest.approx(0.5 + 500 / 1200, abs=0.03)
    # at the speed drawn for P7 (both halves), not the model's: the solver runs each pipe's own
    drawn = pipe_wave_speeds(truth, 1200.0, ["P7"])["P7"]
    assert _arrival(slow, "N7") == pytest.approx(0.5 + 500 / drawn, abs=0.03)


def test_the_perturbed_truth_differs_and_the_same_seed_repeats_it(paper15: Path) -> None:
    truth = TruthPerturbation(wave_speed_spread=0.15, roughness_spread=0.3, seed=4)
    plain = simulate_burst(BurstScenario(paper15, "P3", **SHORT), cache=False)
    first = simulate_burst(BurstScenario(paper15, "P3", **SHORT, truth=truth), cache=False)
    second = simulate_burst(BurstScenario(paper15, "P3", **SHORT, truth=truth), cache=False)
    assert first.time.tolist() == second.time.tolist()
    assert first.heads.tolist() == second.heads.tolist()
    n = min(plain.time.size, first.time.size)
    # the roughness moves the steady state, the wave speeds the transient
    assert np.abs(first.heads[0] - plain.heads[0]).max() > 0.01
    assert np.abs(first.heads[:n] - plain.heads[:n]).max() > 0.1
