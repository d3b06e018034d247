"""The fused localizer: arrival and signature rankings weighted by the capture interval."""

from __future__ import annotations

import math

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import BurstEvidence, MeterAlarm, RankedPipe, Ranking
from burstloc.localize.fused import FusedLocalizer, arrival_loglik, signature_loglik
from burstloc.localize.pipes import PipeGeometry
from line_network import METERS, WAVE, line_arrival, line_signature


def _evidence(dt: float, burst_pipe: int, drop: np.ndarray, until: float) -> BurstEvidence:
    """A burst at the middle of pipe ``burst_pipe`` at t = 10 s; alarms from wave travel."""
    x = 600.0 * burst_pipe + 300.0
    arrive = {m: 10.0 + abs(x - 600.0 * i) / WAVE for i, m in enumerate(METERS)}
    alarms = {m: MeterAlarm(m, math.floor(a / dt - 1e-9) * dt, -1.0) for m, a in arrive.items()}
    t = np.arange(0.0, until + 1e-9, dt)
    readings = np.where((t <= 10.0)[:, None], 50.0, 50.0 - drop[None, :])
    return BurstEvidence(
        meters=METERS,
        times=t,
        readings=readings,
        onset=min(a.start for a in alarms.values()),
        capture_interval=dt,
        alarms=alarms,
    )


def test_weights_follow_the_capture_interval() -> None:
    fused = FusedLocalizer(line_arrival(), line_signature(np.eye(3, 4) + 0.1))
    assert fused.tau == pytest.approx(0.5)
    w_fine, w_coarse = fused.weights(0.2)[0], fused.weights(2.0)[0]
    assert w_fine == pytest.approx(math.exp(-0.4))
    assert w_fine > 0.5 > w_coarse
    assert sum(fused.weights(5.0)) == pytest.approx(1.0)
    assert fused.decision_delay(0.2) == fused.arrival.decision_delay
    assert fused.decision_delay(5.0) == 60.0
    with pytest.raises(InputError):
        fused.weights(0.0)
    with pytest.raises(ConfigError):
        FusedLocalizer(line_arrival(), line_signature(np.eye(3, 4)), tau=-1.0)


def test_where_meters_are_few_the_weights_follow_the_wave_to_the_nearest_meter() -> None:
    # 20 pipes of 50 m in a line, metered at its two ends only: a burst is placed between the
    # two meters, not told from its 50 m neighbour, so tau is the travel to the nearer meter
    nodes = [f"n{i}" for i in range(21)]
    ends = ("n0", "n20")
    distances = {n: np.array([50.0 * i, 50.0 * (20 - i)]) for i, n in enumerate(nodes)}
    names = [f"q{i}" for i in range(20)]
    names[12] = "p12"  # one pipe the signature localizer knows
    pipes = [PipeGeometry(names[i], nodes[i], nodes[i + 1], 50.0) for i in range(20)]
    sparse = ArrivalLocalizer(pipes, ends, distances, wave_speed=WAVE)
    assert sparse.pipe_travel == pytest.approx(50.0 / WAVE)
    middles = sorted(min(50.0 * i + 25.0, 1000.0 - 50.0 * i - 25.0) for i in range(20))
    assert sparse.meter_travel == pytest.approx(float(np.median(middles)) / WAVE)
    signature = line_signature(np.eye(3, 4) + 0.1)
    assert FusedLocalizer(sparse, signature).tau == pytest.approx(sparse.meter_travel)
    assert FusedLocalizer(sparse, signature, tau=0.1).tau == 0.1
    # metered at every junction, the pipe's own travel time decides, as before
    assert FusedLocalizer(line_arrival(), signature).tau == pytest.approx(600.0 / WAVE)


def test_arrivals_decide_at_fine_intervals_signatures_at_coarse() -> None:
    # signatures barely separate p12 from p01 (nearly equal columns) and favour p01 slightly;
    # arrivals point at p12 clearly when the capture interval resolves them
    matrix = np.array([[1.0, 1.0, 0.5, 0.2], [1.0, 1.02, 0.55, 0.2], [0.1, 0.3, 1.0, 1.0]])
    fused = FusedLocalizer(line_arrival(), line_signature(matrix))
    drop = 0.5 * matrix[0]
    fine = fused.rank(_evidence(0.05, burst_pipe=1, drop=drop, until=80.0))
    assert fine.best is not None and fine.best.pipe == "p12"
    coarse = fused.rank(_evidence(5.0, burst_pipe=1, drop=drop, until=80.0))
    assert coarse.best is not None and coarse.best.pipe == "p01"
    # signature alone would say p01 at any interval
    sig_only = fused.signature.rank(_evidence(0.05, burst_pipe=1, drop=drop, until=80.0))
    assert sig_only.best is not None and sig_only.best.pipe == "p01"


def test_early_decision_uses_arrivals_alone() -> None:
    fused = FusedLocalizer(line_arrival(), line_signature(np.eye(3, 4) + 0.1))
    evidence = _evidence(0.05, burst_pipe=2, drop=np.zeros(4), until=11.0)
    ranking = fused.rank(evidence)
    arrival = fused.arrival.rank(evidence)
    assert [p.pipe for p in ranking] == [p.pipe for p in arrival]
    assert ranking.best is not None and ranking.best.pipe == "p23"


def test_nothing_to_go_on_is_an_error() -> None:
    fused = FusedLocalizer(line_arrival(), line_signature(np.eye(3, 4) + 0.1))
    t = np.arange(0.0, 5.0, 1.0)
    evidence = BurstEvidence(
        meters=METERS, times=t, readings=np.zeros((5, 4)), onset=2.0, capture_interval=1.0
    )
    with pytest.raises(InputError, match="neither"):
        fused.rank(evidence)


def test_logliks_are_zero_at_the_best_pipe() -> None:
    ranking = Ranking([RankedPipe("a", "x", "y", -0.002), RankedPipe("b", "y", "z", -0.004)])
    sig = signature_loglik(ranking)
    assert sig["a"] == 0.0
    assert sig["b"] == pytest.approx(-(0.004**2 - 0.002**2) / (2 * 0.002**2))
    arr = arrival_loglik(ranking)
    assert arr["a"] == 0.0 and arr["b"] == pytest.approx(-0.004)
    assert signature_loglik(Ranking([])) == {}


def test_the_arrivals_are_looked_at_early_while_the_longest_pipe_can_be_timed() -> None:
    # Pipes of 60, 60 and 3 000 m (median 60 m, 50 ms of wave travel): the median's weight at
    # 0.2 s is small, but a wave along the 3 km pipe (2.5 s) is timed at 0.2 s and even at 1 s;
    # at 4 s no pipe is.
    line = line_arrival()
    lengths = {"p01": 60.0, "p12": 60.0, "p23": 3000.0}
    pipes = [PipeGeometry(p.pipe, p.start, p.end, lengths[p.pipe]) for p in line.pipes]
    distances = {n: np.zeros(len(line.meters)) for n in line.meters}
    arrival = ArrivalLocalizer(pipes, line.meters, distances, wave_speed=line.wave_speed)
    fused = FusedLocalizer(arrival, line_signature(np.eye(3, 4) + 0.1))
    assert fused.weights(0.2)[0] < 0.5
    assert fused.longest_travel == pytest.approx(3000.0 / line.wave_speed)
    assert fused.resolves(0.2) and fused.resolves(1.0) and not fused.resolves(4.0)
    assert fused.decision_delay(0.2) == arrival.decision_delay
    assert fused.decision_delay(4.0) == 60.0
    with pytest.raises(InputError):
        fused.resolves(0.0)


def test_the_fused_score_is_zero_at_its_best_pipe_when_the_parts_disagree() -> None:
    """Arrivals at 0.2 s point at p12, the lasting drop at p01: the fused best pipe scores 0
    and every other pipe less, as each part's log-likelihood does."""
    matrix = np.array([[1.0, 1.0, 0.5, 0.2], [1.0, 1.02, 0.55, 0.2], [0.1, 0.3, 1.0, 1.0]])
    fused = FusedLocalizer(line_arrival(), line_signature(matrix))
    evidence = _evidence(0.2, burst_pipe=1, drop=0.5 * matrix[0], until=80.0)
    assert fused.arrival.rank(evidence).best.pipe != fused.signature.rank(evidence).best.pipe  # type: ignore[union-attr]
    ranking = fused.rank(evidence)
    scores = [p.score for p in ranking]
    assert scores[0] == 0.0 and all(s < 0.0 for s in scores[1:])
