"""The search region (burstloc.localize.region) on the line network: four meters 600 m apart."""

from __future__ import annotations

import math

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.evidence import BurstEvidence, MeterAlarm, RankedPipe, Ranking
from burstloc.localize.region import DropFit, RegionGrid, grid_of, posterior
from burstloc.localize.timing_error import TAIL_DOF, timing_scale
from line_network import METERS, WAVE, line_arrival

PIPE_OF = {0: "p01", 1: "p12", 2: "p23"}


def _evidence(
    x: float,
    dt: float,
    heard: tuple[str, ...] = METERS,
    jitter: np.ndarray | None = None,
    until: float = 4.0,
) -> BurstEvidence:
    """A burst at ``x`` m along the line at t = 1 s: each heard meter's alarm starts at the last
    capture tick before its wave (plus ``jitter`` s); the others read and stay silent."""
    alarms = {}
    for i, m in enumerate(METERS):
        if m in heard:
            arrive = 1.0 + abs(x - 600.0 * i) / WAVE + (0.0 if jitter is None else jitter[i])
            alarms[m] = MeterAlarm(m, math.floor(arrive / dt - 1e-9) * dt, -1.0)
    t = np.arange(0.0, until, dt)
    return BurstEvidence(
        meters=METERS,
        times=t,
        readings=np.zeros((t.size, len(METERS))),
        onset=min(a.start for a in alarms.values()),
        capture_interval=dt,
        alarms=alarms,
    )


def _truth(x: float) -> tuple[str, str, float, float]:
    """(pipe, its start node, metres from it, pipe length) of the point ``x`` m along the line."""
    k = min(int(x // 600.0), 2)
    return PIPE_OF[k], f"m{k}", x - 600.0 * k, 600.0


def test_the_grid_cuts_every_pipe_into_short_segments_end_to_end() -> None:
    arrival = line_arrival()
    grid = RegionGrid(arrival, step=25.0)
    assert len(grid) == 3 * 24 and grid_of(arrival) is grid_of(arrival)
    for k in range(3):
        mine = grid.pipe == k
        assert grid.low[mine][0] == 0.0 and grid.high[mine][-1] == pytest.approx(600.0)
        assert np.allclose(grid.high[mine][:-1], grid.low[mine][1:])
    assert grid.length.sum() == pytest.approx(1800.0) and grid.length.max() <= 25.0
    # the middle of p12's first segment is 612.5 m along the line
    assert grid.dist[24] == pytest.approx([612.5, 12.5, 587.5, 1187.5])
    with pytest.raises(ConfigError, match="grid step"):
        RegionGrid(arrival, step=0.0)


def test_the_region_holds_the_burst_and_says_how_much_main_that_is() -> None:
    arrival = line_arrival()
    post = posterior(arrival, _evidence(900.0, 0.05))
    assert post.probability.sum() == pytest.approx(1.0)
    region = post.region()
    assert region.confidence == 0.95 and region.probability >= 0.95
    assert region.contains(*_truth(900.0))
    assert region.pipes[0][0] == "p12" and region.pipes[0][1] > 0.95
    # alarms stamped to 0.05 s: 60 m of wave travel, and a little model error around it
    assert 50.0 <= region.length <= 300.0
    assert region.length == pytest.approx(sum(s.length for s in region.stretches))
    doc = region.to_json()
    assert list(doc) == [
        "confidence",
        "probability",
        "length_m",
        "pipe_count",
        "stretches",
        "pipes",
    ]
    assert doc["pipe_count"] == 1 and doc["stretches"][0]["pipe"] == "p12"
    assert doc["stretches"][0]["low"] <= 300.0 <= doc["stretches"][0]["high"]


def test_regions_of_lower_confidence_are_shorter_and_inside() -> None:
    post = posterior(line_arrival(), _evidence(250.0, 0.2, heard=("m0", "m1", "m2")))
    low, mid, high = post.region(0.5), post.region(0.8), post.region(0.95)
    assert low.length <= mid.length <= high.length
    assert low.probability >= 0.5 and mid.probability >= 0.8 and high.probability >= 0.95
    for s in low.stretches:
        assert high.contains(s.pipe, s.start, 0.5 * (s.low + s.high), 600.0)
    with pytest.raises(ConfigError, match="confidence"):
        post.region(0.0)
    with pytest.raises(ConfigError, match="confidence"):
        post.region(1.5)


def test_the_region_narrows_as_more_meters_hear_the_wave() -> None:
    arrival = line_arrival()
    truth = _truth(700.0)
    lengths = []
    for heard in (("m1",), ("m1", "m2"), METERS):
        region = posterior(arrival, _evidence(700.0, 0.05, heard=heard, until=1.2)).region()
        assert region.contains(*truth)
        lengths.append(region.length)
    assert lengths[0] > lengths[1] > lengths[2]


def test_the_lasting_drop_tells_the_pipes_at_a_junction_apart() -> None:
    # 5 m from m1 on p12, readings every 0.2 s: the arrivals cannot tell p01 from p12
    arrival = line_arrival()
    evidence = _evidence(605.0, 0.2)
    alone = posterior(arrival, evidence).pipe_probabilities()
    assert min(alone["p01"], alone["p12"]) > 0.2
    drop = Ranking(
        [
            RankedPipe("p12", "m1", "m2", -0.01),
            RankedPipe("p01", "m0", "m1", -0.2),
            RankedPipe("p23", "m2", "m3", -0.4),
        ]
    )
    both = posterior(arrival, evidence, drop=DropFit(drop, meters=4, size=0.5))
    assert both.pipe_probabilities()["p12"] > 0.95
    assert both.region().length < posterior(arrival, evidence).region().length
    assert both.region().contains(*_truth(605.0))
    # the same residuals from two meters (one degree of freedom) say much less
    two = posterior(arrival, evidence, drop=DropFit(drop, meters=2, size=0.5))
    assert 0.5 < two.pipe_probabilities()["p12"] < both.pipe_probabilities()["p12"]
    # counted at a fused localizer's signature weight of a quarter, it says less again
    weighed = posterior(arrival, evidence, drop=DropFit(drop, meters=4, size=0.5, weight=0.25))
    assert 0.5 < weighed.pipe_probabilities()["p12"] < both.pipe_probabilities()["p12"]
    assert posterior(arrival, evidence, drop=DropFit(drop, 4, 0.5, 0.0)).pipe_probabilities() == (
        pytest.approx(alone)
    )


def test_the_stated_probability_is_honest_under_the_timing_error_it_assumes() -> None:
    # bursts anywhere on the line, alarm starts off by the Student-t error the region assumes
    arrival = line_arrival()
    rng = np.random.default_rng(7)
    for dt in (0.05, 0.2):
        scale = timing_scale(dt)
        hits = {0.5: 0, 0.8: 0, 0.95: 0}
        trials = 300
        for _ in range(trials):
            x = float(rng.uniform(0.0, 1800.0))
            jitter = np.abs(scale * rng.standard_t(TAIL_DOF, size=len(METERS)))
            post = posterior(arrival, _evidence(x, dt, jitter=jitter))
            for level in hits:
                hits[level] += post.region(level).contains(*_truth(x))
        for level, count in hits.items():
            assert count / trials >= level - 0.05, (dt, level, count)


def test_a_region_needs_evidence_that_places_the_burst() -> None:
    arrival = line_arrival()
    with pytest.raises(InputError, match="arrivals or a lasting drop"):
        posterior(arrival, None)
    quiet = BurstEvidence(
        meters=("x",), times=np.arange(3.0), readings=np.zeros((3, 1)), onset=0.0,
        capture_interval=1.0, alarms={"x": MeterAlarm("x", 0.0, -1.0)},
    )  # fmt: skip
    with pytest.raises(InputError, match="no meter of the arrival model has alarmed"):
        posterior(arrival, quiet)


def test_a_wave_slower_than_the_model_s_stays_in_the_region_with_a_tolerance() -> None:
    """Every travel time 1/0.85 of the model's (the mains' wave speed 15 % below the model's):
    100 m along the line, the region with no tolerance still holds the burst, because the
    alarms' misfits at the best point widen the timing error (it is longer than the region of
    arrivals as the model says); with the default tolerance (5 % of each travel time) it holds
    it, and so does a wider one, neither shorter than the region of arrivals as the model says."""
    from burstloc.constants import WAVE_SPEED_TOLERANCE
    from burstloc.localize.arrival import ArrivalLocalizer

    def arrival(tolerance: float) -> ArrivalLocalizer:
        line = line_arrival()
        nodes = {p.start for p in line.pipes} | {p.end for p in line.pipes}
        d_start, d_end = line.end_distances
        distances = {p.start: d_start[i] for i, p in enumerate(line.pipes)}
        distances |= {p.end: d_end[i] for i, p in enumerate(line.pipes)}
        assert set(distances) == nodes
        return ArrivalLocalizer(
            line.pipes, METERS, distances, wave_speed=WAVE, wave_speed_tolerance=tolerance
        )

    x = 100.0
    late = np.array([abs(x - 600.0 * i) / WAVE * (1 / 0.85 - 1) for i in range(len(METERS))])
    evidence = _evidence(x, 0.01, jitter=late)
    exact = posterior(arrival(0.0), evidence).region()
    tolerant = posterior(arrival(WAVE_SPEED_TOLERANCE), evidence).region()
    wide = posterior(arrival(0.15), evidence).region()
    as_said = posterior(arrival(0.0), _evidence(x, 0.01)).region()
    assert exact.contains(*_truth(x)) and as_said.contains(*_truth(x))
    assert as_said.length < exact.length
    assert tolerant.contains(*_truth(x)) and wide.contains(*_truth(x))
    assert as_said.length <= min(tolerant.length, wide.length)
    # with arrivals as the model says, the tolerance still holds the burst
    assert posterior(arrival(0.15), _evidence(x, 0.01)).region().contains(*_truth(x))


def test_the_misfits_own_scale_trims_the_outliers_and_counts_the_fit() -> None:
    from burstloc.localize.timing_error import (
        FIT_PARAMETERS,
        STATED_DOF,
        misfit_scale,
        widened_scale,
    )

    # 10 misfits: the largest (an outlier) left out, the RMS of the 9 others over 9 - 3 dof
    gaps = np.array([0.0, 0.01, -0.02, 0.0, 0.03, 0.0, 0.01, -0.01, 0.0, 5.0])
    kept = np.sort(np.abs(gaps))[:9]
    assert FIT_PARAMETERS == 3
    shown, dof = misfit_scale(gaps)
    assert dof == 6 and shown == pytest.approx(np.sqrt(np.sum(kept**2) / 6))
    assert misfit_scale(np.zeros(12)) == (0.0, 8)  # every alarm in its window (one trimmed)
    assert misfit_scale(np.array([0.3, 0.4, 0.5])) == (0.0, 0)  # the fit leaves no freedom
    # pooled with the stated scale: never below it, towards the misfits as they count more
    assert widened_scale(0.03, 0.0, 9) == 0.03
    few, many = widened_scale(0.03, 0.3, 1), widened_scale(0.03, 0.3, 40)
    assert few == pytest.approx(np.sqrt((STATED_DOF * 0.03**2 + 0.3**2) / (STATED_DOF + 1)))
    assert 0.03 < few < many < 0.3
