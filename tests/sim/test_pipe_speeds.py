"""Wave speeds per pipe, shared by the simulation and the localizers: paths timed at each pipe's
speed (burstloc.sim.model.prepare), bursts simulated so (burstloc.sim.transient.tsnet)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from alarm_evidence import arrival_evidence
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.model import LocalizationModel
from burstloc.network import load_network
from burstloc.sim.model.prepare import arrival_geometry, arrival_localizer, prepare_model
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst
from burstloc.wave_speeds import WaveSpeeds

FINE = {"burst_start": 0.5, "duration": 3.0, "time_step": 0.02}


def test_paths_are_timed_at_each_pipe_s_speed(tiny_network: Path) -> None:
    # J2 -> J4: via D (150 m) and E (180 m), 330 m; via B, C, E 630 m
    slow = WaveSpeeds((("D", 250.0),))  # D takes as long as 720 m at 1200 m/s
    wn = load_network(tiny_network)
    pipes, distances = arrival_geometry(wn, ["J2", "J4"], slow.stretch(wn, 1200.0))
    np.testing.assert_allclose(distances["J2"], [0.0, 630.0])  # the quicker path, via J1
    np.testing.assert_allclose(distances["J3"], [450.0, 180.0])  # J3-J1-J2 beats D's 720
    by = {p.pipe: p for p in pipes}
    assert by["D"].length == 150.0 and by["D"].travel == pytest.approx(720.0)
    assert by["B"].stretch == 1.0


def test_the_model_keeps_the_speeds_and_reads_them_back(tiny_network: Path) -> None:
    slow = WaveSpeeds((("D", 250.0),))
    model = prepare_model(tiny_network, ["J2", "J4"], wave_speeds=slow, signatures="epanet")
    again = LocalizationModel.from_json(model.to_json())
    assert {p.pipe: p.stretch for p in again.pipes}["D"] == pytest.approx(1200.0 / 250.0)
    assert again == model
    plain = prepare_model(tiny_network, ["J2", "J4"], signatures="epanet")
    assert "stretch" not in str(plain.to_json()["pipes"])  # files without speeds unchanged


def _arrivals(result: ScenarioResult) -> dict[str, float]:
    """When the head at each junction first moves 5 cm (junctions that never do left out)."""
    found = {}
    for j, name in enumerate(result.junctions):
        moved = np.abs(result.heads[:, j] - result.heads[0, j]) > 0.05
        if moved.any():
            found[name] = float(result.time[np.argmax(moved)])
    return found


def test_a_burst_on_a_slow_pipe_is_heard_late_and_placed_where_it_is(paper15: Path) -> None:
    # P7 (N5 - N7, 1000 m) bursts a quarter along from N5, P7 a PE main at 600 m/s
    slow = WaveSpeeds((("P7", 600.0),))
    scenario = BurstScenario(paper15, "P7", position=0.25, **FINE, wave_speeds=slow)
    result = simulate_burst(scenario, cache=False)
    assert result.metadata["wave_speeds"] == {"pipes": {"P7": 600.0}, "diameters": []}
    heard = _arrivals(result)
    assert heard["N5"] == pytest.approx(0.5 + 250 / 600, abs=0.03)
    assert heard["N7"] == pytest.approx(0.5 + 750 / 600, abs=0.03)
    # the same speeds read from another file are the same simulation; other speeds are not
    assert (
        BurstScenario(
            paper15, "P7", position=0.25, **FINE, wave_speeds=WaveSpeeds(slow.pipes, source="x.csv")
        ).cache_key()
        == scenario.cache_key()
    )
    assert BurstScenario(paper15, "P7", position=0.25, **FINE).cache_key() != scenario.cache_key()

    evidence = arrival_evidence(heard, 0.02, span=3.0)
    knows: ArrivalLocalizer = arrival_localizer(paper15, sorted(heard), wave_speeds=slow)
    assumes: ArrivalLocalizer = arrival_localizer(paper15, sorted(heard))
    start = knows.position(evidence, "P7")
    assert start.start == assumes.position(evidence, "P7").start
    true = 250.0 if start.start == "N5" else 750.0
    # timed at P7's speed: within a capture interval of wave travel at 600 m/s (12 m)
    assert abs(knows.position(evidence, "P7").metres - true) <= 20.0
    assert knows.position(evidence, "P7").low <= true <= knows.position(evidence, "P7").high
    # at one speed for every pipe the arrivals cannot fit P7's points (the burst pushed to an end)
    assert abs(assumes.position(evidence, "P7").metres - true) >= 150.0
    assert knows.rank(evidence).top(1)[0].pipe == "P7"
