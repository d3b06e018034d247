"""Meter placement and scores timed at each pipe's wave speed (burstloc.sim.placement with
``wave_speeds``): a pipe at 400 m/s takes as long as three times its length at 1200 m/s."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.localize.pipes import PipeGeometry
from burstloc.network import load_network, read_network
from burstloc.sim.model.prepare import arrival_geometry
from burstloc.sim.placement.arrival import arrival_separation
from burstloc.sim.placement.methods import MeterSet, meter_scores, place_meters, score_meters
from burstloc.sim.placement.scaled import Scaling
from burstloc.wave_speeds import WaveSpeeds, read_wave_speeds

METERS = ("N4", "N7", "1", "8")  # paper15's arrival placement of four
SLOW = WaveSpeeds((("P7", 400.0), ("P8", 400.0)))  # two PE mains among iron ones


def test_a_burst_point_crosses_its_own_pipe_at_the_pipe_s_speed() -> None:
    # meters at a and b, 600 m of pipe apart at a third of 1200 m/s: 1800 m of travel
    distances = {
        "a": np.array([0.0, 1800.0]),
        "b": np.array([1800.0, 0.0]),
        "c": np.array([1810.0, 10.0]),
    }
    slow = [PipeGeometry("p", "a", "b", 600.0, 3.0), PipeGeometry("q", "b", "c", 10.0)]
    long = [PipeGeometry("p", "a", "b", 1800.0), PipeGeometry("q", "b", "c", 10.0)]
    for resolution in (0.2, 1.0, 2.0):
        told = arrival_separation(slow, distances, resolution=resolution)
        assert told == arrival_separation(long, distances, resolution=resolution)
    # at one speed along the pipe, the points of p would sit a third as far apart in time
    short = [PipeGeometry("p", "a", "b", 600.0), PipeGeometry("q", "b", "c", 10.0)]
    assert arrival_separation(short, distances, resolution=1.0) != arrival_separation(
        slow, distances, resolution=1.0
    )


def test_a_slow_pipe_counts_as_three_times_its_length(paper15: Path) -> None:
    network = read_network(paper15)
    longer = load_network(paper15)  # the same network with P7 and P8 three times as long
    for pipe in ("P7", "P8"):
        longer.get_link(pipe).length *= 3
    pipes, distances = arrival_geometry(longer, list(METERS))
    same, _ = arrival_geometry(network, list(METERS))
    assert [(p.start, p.end) for p in pipes] == [(p.start, p.end) for p in same]  # same flows
    (slow,) = meter_scores(network, METERS, scores=("separation",), wave_speeds=SLOW)
    assert slow == pytest.approx(arrival_separation(pipes, distances))
    (uniform,) = meter_scores(network, METERS, scores=("separation",))
    assert slow < uniform  # 0.51 against 0.63: the slow mains lengthen paths alike


def test_every_pipe_at_a_third_of_the_speed_is_the_slower_speed(
    paper15: Path, tmp_path: Path
) -> None:
    # a diameter class that holds every pipe: the whole network at 400 m/s
    speeds_file = tmp_path / "plastic.json"
    speeds_file.write_text(json.dumps({"diameters": [{"up_to_mm": 2000, "wave_speed": 400}]}))
    plastic = read_wave_speeds(speeds_file)
    network = read_network(paper15)
    at_400 = score_meters(network, METERS, wave_speed=400.0)
    timed = score_meters(network, METERS, wave_speeds=plastic)  # the others at 1200 m/s
    assert timed.ambiguous == pytest.approx(at_400.ambiguous)
    # three times the travel time: a capture interval tells three times finer points apart
    assert timed.ambiguous < 0.5 * score_meters(network, METERS).ambiguous
    for method in ("arrival", "region"):
        placed = place_meters(network, 4, method=method, wave_speeds=plastic)
        assert placed.meters == place_meters(network, 4, method=method, wave_speed=400.0).meters
        assert placed.wave_speeds is not None
        assert placed.wave_speeds.to_json() == plastic.to_json()
        if method == "arrival":  # N3 N4 N7 8, not N4 N7 1 8 as at 1200 m/s
            assert placed.meters != place_meters(network, 4, method=method).meters
    # the reduced problem of a large network spreads its candidates by travel time too
    small = Scaling(above=10, candidates=12, pipes=20, points=100)
    for method in ("arrival", "region"):
        scaled = place_meters(network, 3, method=method, scaling=small, wave_speeds=plastic)
        alike = place_meters(network, 3, method=method, scaling=small, wave_speed=400.0)
        assert scaled.meters == alike.meters
        assert scaled.meters != place_meters(network, 3, method=method, scaling=small).meters


def test_the_meter_file_records_the_speeds_only_when_they_timed_the_paths(
    paper15: Path, tmp_path: Path
) -> None:
    placed = place_meters(paper15, 4, method="region", wave_speeds=SLOW)
    doc = json.loads(placed.save(tmp_path / "m.json").read_text())
    assert doc["wave_speeds"] == {"pipes": {"P7": 400.0, "P8": 400.0}, "diameters": []}
    assert MeterSet.load(tmp_path / "m.json") == placed
    plain = place_meters(paper15, 4, method="region")
    assert "wave_speeds" not in plain.to_json()
    # steady-state signatures take no wave speed: a coverage placement records none
    assert place_meters(paper15, 2, method="coverage", wave_speeds=SLOW).wave_speeds is None
    bad = {**doc, "wave_speeds": {"pipes": {"P7": 5}}}
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(ConfigError, match=r"meter file .*bad\.json.*pipes\.P7"):
        MeterSet.load(tmp_path / "bad.json")
