"""burstloc.experiments.truth: what the meters hear of a perturbed truth (clocks, a silent
meter), read by the harness's capture code, on a real simulated burst."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.experiments.harness import Clock, capture_readings
from burstloc.experiments.truth import Hearing
from burstloc.network import load_network
from burstloc.sim.scenarios.perturb import TruthPerturbation, clock_offsets
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst


@pytest.fixture(scope="module")
def pipe_p7(paper15: Path) -> ScenarioResult:
    """paper15's P7 (N5 - N7, 1000 m) burst mid-pipe at 0.5 s, simulated at a 0.02 s step."""
    scenario = BurstScenario(paper15, "P7", burst_start=0.5, duration=3.0, time_step=0.02)
    return simulate_burst(scenario, cache=False)


def _first_move(times: np.ndarray, column: np.ndarray) -> float:
    return float(times[np.argmax(np.abs(column - column[0]) > 0.05)])


def test_exact_hearing_is_the_result_itself(pipe_p7: ScenarioResult, paper15: Path) -> None:
    hear = Hearing(TruthPerturbation(wave_speed_spread=0.1), load_network(paper15))
    assert hear(pipe_p7) is pipe_p7


def test_clock_offsets_shift_each_meters_readings(pipe_p7: ScenarioResult, paper15: Path) -> None:
    truth = TruthPerturbation(clock_offset=0.1, seed=2)
    offsets = clock_offsets(truth, pipe_p7.junctions)
    heard = Hearing(truth, load_network(paper15))(pipe_p7)
    assert heard.heads.shape == pipe_p7.heads.shape and heard.time is pipe_p7.time
    clock = Clock(0.025, 0.0, 4)  # the capture every meter uses, at 0.025 s
    times, plain = capture_readings(pipe_p7, clock)
    _, shifted = capture_readings(heard, clock)
    assert times.tolist() == capture_readings(heard, clock)[0].tolist()
    for meter in ("N5", "N7"):
        j = pipe_p7.junctions.index(meter)
        assert abs(offsets[j]) > 0.03  # seed 2 sets both clocks well off
        # a clock ahead (offset > 0) reads later heads at each tick: the wave seems earlier
        moved = _first_move(times, shifted[:, j]) - _first_move(times, plain[:, j])
        assert moved == pytest.approx(-offsets[j], abs=0.025 + pipe_p7.time_step)


def test_the_meter_nearest_the_burst_sends_nothing_after_s(
    pipe_p7: ScenarioResult, paper15: Path
) -> None:
    wn = load_network(paper15)
    hear = Hearing(TruthPerturbation(silent_meter=0.3), wn)
    heard = hear(pipe_p7)
    # the burst point is 500 m from both ends of P7: the nearer by name, N5
    assert hear.silent == {"P7": "N5"}
    times, values = capture_readings(heard, Clock(0.2, 0.0, 5))
    j = heard.junctions.index("N5")
    after = times >= 0.5 + 0.3 - 1e-9
    assert after.any() and np.isnan(values[after, j]).all()
    assert np.isfinite(values[~after, j]).all()
    others = np.delete(values, j, axis=1)
    assert np.isfinite(others).all()
    # only metered junctions fall silent: with N5 and N7 unmetered, the nearest metered one
    metered = [m for m in pipe_p7.junctions if m not in ("N5", "N7")]
    far = Hearing(TruthPerturbation(silent_meter=0.3), wn, metered)
    far(pipe_p7)
    assert far.silent["P7"] in metered
