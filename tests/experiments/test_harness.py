"""burstloc.experiments.harness: clocks, captured readings with history and noise, the paper's and
the ranking localizers' attempts, and the tally evaluate and the study both count with."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, InputError, NetworkError
from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.evaluate import RunResult, evaluate
from burstloc.experiments.harness import (
    Attempt,
    Clock,
    Tally,
    capture_readings,
    locate_burst,
    readings_at_offset,
)
from burstloc.experiments.ranking import RankingSetup, locate_ranked, rank_attempts
from burstloc.experiments.runs import RunSpec
from burstloc.localize.detection import DetectorConfig, Mode
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.sensors import SensorModel
from synthetic_bursts import small_graph, synthetic

CUSUM = DetectorConfig("cusum", 0.3)


def test_clock_validation_and_offsets() -> None:
    with pytest.raises(ConfigError, match="phase"):
        Clock(0.2, 0.2)
    with pytest.raises(ConfigError, match="capture interval"):
        Clock(0.0)
    with pytest.raises(ConfigError, match="history"):
        Clock(0.2, 0.0, -1)
    assert Clock.at_offset(0.2, 0.0, 10) == Clock(0.2, 0.0, 10)
    # 0.45 s earlier: three ticks fall in [-0.45, 0), the first simulated one at 0.15 s
    moved = Clock.at_offset(0.2, 0.45, 10)
    assert moved.history == 13 and moved.phase == pytest.approx(0.15)
    # a whole interval earlier is one more tick of history, same phase
    assert Clock.at_offset(2.0, 2.0, 4) == Clock(2.0, 0.0, 5)


def test_history_prepends_the_steady_state_at_the_capture_interval() -> None:
    r = synthetic("pB", {"B": (3.0, 0.2)})
    t, v = capture_readings(r, Clock(2.0, 0.5, 3))
    np.testing.assert_allclose(t, [-5.5, -3.5, -1.5, 0.5, 2.5, 4.5, 6.5], atol=1e-12)
    np.testing.assert_array_equal(v[:3], np.tile(r.heads[0], (3, 1)))
    np.testing.assert_array_equal(v[3], r.heads[0])  # 0.5 s: before the burst
    assert v[4, 1] == r.heads[0, 1] - 3.0  # 2.5 s: after it reached B at 2.2 s


def test_readings_of_a_subset_of_meters_with_noise() -> None:
    r = synthetic("pB", {"B": (3.0, 0.2), "C": (1.0, 0.4)})
    clock = Clock(0.2, 0.1, 11)
    t_all, v_all = capture_readings(r, clock)
    t, v = capture_readings(r, clock, meters=["A", "C"])
    np.testing.assert_array_equal(t, t_all)
    np.testing.assert_array_equal(v, v_all[:, [0, 2]])
    sensor = SensorModel(noise_sigma=0.05, seed=3)
    _, noisy = capture_readings(r, clock, meters=["A", "C"], sensor=sensor, noise_key="x")
    _, again = capture_readings(r, clock, meters=["A", "C"], sensor=sensor, noise_key="x")
    _, other = capture_readings(r, clock, meters=["A", "C"], sensor=sensor, noise_key="y")
    np.testing.assert_array_equal(noisy, again)  # same key, same noise
    assert not np.array_equal(noisy, other)
    # every reading is noisy, the steady history included, by about sigma
    assert np.all(noisy[:11] != v[:11])
    assert 0.02 < float(np.std(noisy - v)) < 0.08
    with pytest.raises(NetworkError, match="Z"):
        capture_readings(r, clock, meters=["A", "Z"])


def test_evaluate_readings_are_the_harness_at_an_offset() -> None:
    r = synthetic("pB", {"B": (3.0, 0.2)})
    spec = RunSpec(CUSUM, 0.2, 5, meter_model="interval-averaged")
    t, v = readings_at_offset(r, spec, 0.45)
    t2, v2 = capture_readings(r, Clock.at_offset(0.2, 0.45, 10), "interval-averaged")
    np.testing.assert_array_equal(t, t2)
    np.testing.assert_array_equal(v, v2)
    # the 2 x 5 warm-up and the 3 ticks in [-0.45, 0) carry the steady state
    assert t[0] == pytest.approx(-0.45 - 2.0)
    assert np.count_nonzero(t < 0) == 13
    np.testing.assert_array_equal(v[:13], np.tile(r.heads[0], (13, 1)))


def test_tally_counts_hits_misses_and_times() -> None:
    g = small_graph()
    spec = RunSpec(CUSUM, 0.2, 5)
    hit = synthetic("pB", {"B": (3.0, 0.2), "A": (1.0, 0.2)})
    wrong = synthetic("pC", {"B": (3.0, 0.2), "A": (1.0, 0.2)})
    miss = synthetic("pD", {})
    attempts = [locate_burst(r, g, spec, o) for r in (hit, wrong, miss) for o in (0.0, 0.1)]
    tally = Tally.of(attempts)
    assert (tally.attempts, tally.top1, tally.top3, tally.not_located) == (6, 2, 2, 2)
    assert tally.top1_fraction == pytest.approx(2 / 6)
    located = [a.time_to_localize for a in attempts if a.located]
    assert len(tally.times) == 4
    assert tally.median_time() == pytest.approx(float(np.median(located)))
    assert Tally().median_time() is None
    # evaluate's run counts with the same tally
    rr = RunResult(
        spec,
        ["pB", "pC", "pD"],
        {"pB": ("A", "B"), "pC": ("A", "C"), "pD": ("B", "C")},
        [0.0, 0.1],
        {"pB": attempts[0:2], "pC": attempts[2:4], "pD": attempts[4:6]},
    )
    assert rr.tally() == tally
    assert rr.to_json()["top1"] == pytest.approx(float(np.mean(rr.phase_accuracies())))


def _answer(attempt: Attempt) -> tuple[object, ...]:
    """What an attempt decided: when, and every pipe in rank order with its score."""
    ranking = attempt.ranking
    assert ranking is not None
    return attempt.decided_at, [(p.pipe, p.score) for p in ranking]


@pytest.fixture(scope="module")
def tiny_burst(tiny: Path) -> tuple[ScenarioResult, RankingSetup]:
    ev = evaluate(
        tiny,
        [RunSpec(CUSUM, 0.2, 5)],
        pipes=["C"],
        phases=1,
        scenario=paper.ScenarioConfig(burst_start=2.0, duration=160.0),
        workers=1,
        progress=False,
    )
    result = ev.results["C"]
    config = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01)
    return result, RankingSetup.build(tiny, list(result.junctions), (0.2,), config)


def test_one_bank_pass_serves_every_localizer(
    tiny_burst: tuple[ScenarioResult, RankingSetup],
) -> None:
    result, setup = tiny_burst
    readings = capture_readings(result, Clock(0.2, 0.0, 11))
    ranked = rank_attempts(
        result,
        readings,
        setup,
        detector="cusum",
        capture_interval=0.2,
        localizers=["fused", "arrival", "signature"],
        offset=0.0,
    )
    assert list(ranked) == ["fused", "arrival", "signature"]  # the caller's order
    for name, attempt in ranked.items():
        assert attempt.located and attempt.ranking is not None, name
        assert attempt.in_top(3), name  # noise-free, every meter: the burst pipe is near the top
    # The fused answer reusing the signature's ranking is the fused answer alone.
    alone = rank_attempts(
        result, readings, setup, detector="cusum", capture_interval=0.2, localizers=["fused"]
    )["fused"]
    assert _answer(alone) == _answer(ranked["fused"])
    # locate_ranked is the same pass for one run at an offset
    spec = RunSpec(CUSUM, 0.2, 5, Mode.STREAM, localizer="arrival")
    one = locate_ranked(result, spec, setup, 0.0)
    at_offset = rank_attempts(
        result,
        readings_at_offset(result, spec, 0.0),
        setup,
        detector="cusum",
        capture_interval=0.2,
        localizers=["arrival"],
    )["arrival"]
    assert _answer(one) == _answer(at_offset) == _answer(ranked["arrival"])


def test_steady_readings_are_not_located(
    tiny_burst: tuple[ScenarioResult, RankingSetup],
) -> None:
    result, setup = tiny_burst
    times, values = capture_readings(result, Clock(0.2, 0.0, 11))
    before = times < float(result.metadata["burst_start"])
    ranked = rank_attempts(
        result,
        (times[before], values[before]),
        setup,
        detector="shewhart",
        capture_interval=0.2,
        localizers=["arrival", "fused"],
        offset=0.1,
    )
    for attempt in ranked.values():
        assert attempt == Attempt("C", 0.1, 2.0, None)
        assert not attempt.located and attempt.time_to_localize is None
    with pytest.raises(InputError, match="columns"):
        rank_attempts(
            result,
            (times, values[:, :2]),
            setup,
            detector="cusum",
            capture_interval=0.2,
            localizers=["arrival"],
        )


def test_a_meter_that_sends_nothing_is_named_to_the_monitor_as_filled(
    tiny_burst: tuple[ScenarioResult, RankingSetup],
) -> None:
    # NaN = no reading (a silent meter of a perturbed truth): the monitor gets the step with
    # the meter named in ``filled``, as from the live feed, and still decides on the others;
    # before, every step with a NaN was refused and skipped, and nothing was decided
    result, setup = tiny_burst
    times, values = capture_readings(result, Clock(0.2, 0.0, 11))
    burst = float(result.metadata["burst_start"])
    quiet = values.copy()
    quiet[times >= burst, 0] = np.nan
    ranked = rank_attempts(
        result,
        (times, quiet),
        setup,
        detector="cusum",
        capture_interval=0.2,
        localizers=["arrival"],
    )["arrival"]
    assert ranked.located and ranked.decided_at is not None and ranked.decided_at > burst
