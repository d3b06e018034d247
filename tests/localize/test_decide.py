"""When and what the ranking localizers answer (burstloc.localize.decide), on the line network."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.decide import Decision, RankingLocalizers, decision_time, rank_alarms
from burstloc.localize.evidence import IndexedAlarm, RankedPipe, Ranking, evidence_at
from burstloc.localize.fused import FusedLocalizer, decisive, quantisation_margin
from line_network import METERS, WAVE, line_arrival, line_signature
from line_network import line_calibration as _calibration

# signature rows: p01 and p12 differ only at m0 / m2, p23 is far from both
MATRIX = np.array([[1.0, 1.0, 0.4, 0.2], [0.6, 1.0, 0.9, 0.4], [0.1, 0.3, 1.0, 1.0]])
BURST = 10.0


def _burst(x: float, drop: np.ndarray, dt: float = 0.05, until: float = 80.0) -> tuple:
    """Readings and alarms of a burst at ``x`` metres along the line (a step at wave arrival)."""
    t = np.arange(0.0, until + 1e-9, dt)
    arrive = [BURST + abs(x - 600.0 * i) / WAVE for i in range(len(METERS))]
    readings = np.stack(
        [np.where(t < a, 50.0, 50.0 - d) for a, d in zip(arrive, drop, strict=True)], axis=1
    )
    alarms = []
    for channel, a in enumerate(arrive):
        index = int(np.searchsorted(t, a))
        alarms.append(IndexedAlarm(channel, index, index - 1, -float(drop[channel])))
    return t, readings, alarms


def _localizers(**fused_options: float) -> RankingLocalizers:
    arrival, signature = line_arrival(), line_signature(MATRIX)
    return RankingLocalizers(
        arrival, signature, FusedLocalizer(arrival, signature, **fused_options)
    )


def _decide(
    name: str,
    x: float,
    drop: np.ndarray,
    localizers: RankingLocalizers | None = None,
    dt: float = 0.05,
) -> tuple:
    t, readings, alarms = _burst(x, drop, dt)
    decision = rank_alarms(
        name,
        localizers or _localizers(),
        METERS,
        t,
        readings,
        alarms,
        _calibration(dt),
        "instantaneous",
    )
    return decision, t, alarms


def test_fused_answers_early_when_arrivals_are_decisive() -> None:
    # a burst mid-way along p12 whose drop looks like p01's: arrivals must decide, early
    decision, t, alarms = _decide("fused", 900.0, 0.5 * MATRIX[0])
    first = min(float(t[a.index]) for a in alarms)
    assert not decision.waited
    assert decision.time == pytest.approx(first + 1.0)
    assert decision.ranking.best is not None and decision.ranking.best.pipe == "p12"


def test_fused_waits_for_the_signature_near_a_junction() -> None:
    # 5 m from m1 on p12, readings every 0.2 s: p01 and p12 explain the arrivals equally well
    # (their candidate points nearest m1 are 60 m from it); the drop is p12's
    decision, t, alarms = _decide("fused", 605.0, 0.5 * MATRIX[1], dt=0.2)
    onset = min(float(t[a.start]) for a in alarms)
    assert decision.waited
    assert decision.time == pytest.approx(onset + 60.0)
    assert decision.ranking.best is not None and decision.ranking.best.pipe == "p12"
    # the same burst 5 m on the other side of m1 is p01's
    other, _, _ = _decide("fused", 595.0, 0.5 * MATRIX[0], dt=0.2)
    assert other.waited and other.ranking.best is not None and other.ranking.best.pipe == "p01"


def test_a_zero_margin_never_waits() -> None:
    decision, t, alarms = _decide("fused", 605.0, 0.5 * MATRIX[1], _localizers(margin=0.0), 0.2)
    assert not decision.waited
    assert decision.time == pytest.approx(min(float(t[a.index]) for a in alarms) + 1.0)


def test_arrival_and_signature_answer_at_their_own_delays() -> None:
    drop = 0.5 * MATRIX[2]
    arrival, t, alarms = _decide("arrival", 1500.0, drop)
    assert arrival.time == pytest.approx(min(float(t[a.index]) for a in alarms) + 1.0)
    signature, _, _ = _decide("signature", 1500.0, drop)
    assert signature.time == pytest.approx(min(float(t[a.start]) for a in alarms) + 60.0)
    for d in (arrival, signature):
        assert not d.waited and d.ranking.best is not None and d.ranking.best.pipe == "p23"


def test_the_decision_is_capped_at_the_last_reading() -> None:
    t, readings, alarms = _burst(900.0, 0.5 * MATRIX[1], until=40.0)
    decision = rank_alarms(
        "signature", _localizers(), METERS, t, readings, alarms, _calibration(), "instantaneous"
    )
    assert decision.time == pytest.approx(float(t[-1]))


def test_no_alarm_is_an_input_error() -> None:
    with pytest.raises(InputError, match="no alarm"):
        decision_time("fused", [], np.arange(3.0), _calibration())


def test_quantisation_margin() -> None:
    assert quantisation_margin(15) == pytest.approx(2 / math.sqrt(12 * 15))
    assert quantisation_margin(1) > quantisation_margin(4)
    with pytest.raises(ConfigError):
        quantisation_margin(0)
    assert _localizers()["fused"].margin == pytest.approx(quantisation_margin(len(METERS)))
    with pytest.raises(ConfigError):
        _localizers(margin=-1.0)


@pytest.mark.parametrize(("x", "row", "dt"), [(605.0, 1, 0.2), (1500.0, 2, 2.0)])
def test_fused_reuses_the_signature_ranking_of_the_same_readings(
    x: float, row: int, dt: float
) -> None:
    # waiting near a junction at 0.2 s, and answering at the signature's time at 2 s: in both
    # the fused localizer looks at the signatures when the signature localizer does
    localizers = _localizers()
    t, readings, alarms = _burst(x, 0.5 * MATRIX[row], dt)
    cal = _calibration(dt)

    def decide(name: str, **shared: object) -> object:
        return rank_alarms(
            name, localizers, METERS, t, readings, alarms, cal, "instantaneous", **shared
        )

    signature = decide("signature")
    alone = decide("fused")
    shared = decide("fused", signature_ranking=signature.ranking)
    assert list(shared.ranking) == list(alone.ranking)
    assert (shared.time, shared.waited) == (alone.time, alone.waited)
    assert alone.time == pytest.approx(signature.time)
    # the ranking passed in is the one used (a reversed one changes the answer)
    reversed_ranking = Ranking(
        RankedPipe(p.pipe, p.start, p.end, score=-p.score) for p in signature.ranking
    )
    swapped = decide("fused", signature_ranking=reversed_ranking)
    assert [(p.pipe, p.score) for p in swapped.ranking] != [
        (p.pipe, p.score) for p in alone.ranking
    ]


def test_ranking_localizers_read_by_name() -> None:
    localizers = _localizers()
    assert list(localizers) == ["arrival", "signature", "fused"] and len(localizers) == 3
    assert localizers["arrival"] is localizers.arrival
    assert localizers["fused"] is localizers.fused and localizers.get("paper") is None
    with pytest.raises(KeyError):
        localizers["paper"]
    # a plain mapping works too, but its "fused" must be a FusedLocalizer
    t, readings, alarms = _burst(300.0, MATRIX[0])
    plain = {"arrival": localizers.arrival, "fused": localizers.arrival}
    with pytest.raises(ConfigError, match="'fused' localizer must be a FusedLocalizer"):
        rank_alarms("arrival", plain, METERS, t, readings, alarms, _calibration(), "instantaneous")


def test_a_decision_knows_its_first_alarm_and_prints_as_json() -> None:
    decision, t, alarms = _decide("arrival", 300.0, MATRIX[0])
    first = min(float(t[a.index]) for a in alarms)
    assert decision.first_alarm == first
    assert decision.first_alarm <= decision.time
    assert decision.pipe == decision.ranking[0].pipe == "p01"
    doc = decision.to_json(top=2)
    assert list(doc) == ["time", "first_alarm", "waited", "position", "region", "pipes"]
    assert (doc["time"], doc["first_alarm"], doc["waited"]) == (decision.time, first, False)
    # the burst is 300 m from m0 along p01; alarms are stamped to 0.05 s = 60 m of travel
    assert doc["position"]["from"] == "m0"
    assert abs(doc["position"]["metres"] - 300.0) <= 30.0 + 1.0
    assert doc["position"]["low"] <= 300.0 <= doc["position"]["high"]
    assert doc["pipes"] == [  # scores to 1e-6, without float noise (0.049999999999964476)
        {"pipe": r.pipe, "start": r.start, "end": r.end, "score": round(r.score, 6)}
        for r in decision.ranking.top(2)
    ]
    assert [p["score"] for p in doc["pipes"]] == [0.05, -4.513351]
    assert Decision(Ranking([]), 1.0, 0.5).pipe is None
    fused, _, _ = _decide("fused", 1100.0, MATRIX[1])
    assert fused.position is not None and fused.position.pipe == fused.pipe == "p12"
    assert abs(fused.position.metres - 500.0) <= 31.0
    signature, _, _ = _decide("signature", 300.0, MATRIX[0])
    assert signature.position is None and signature.to_json()["position"] is None


def test_a_late_fused_answer_takes_its_position_from_the_arrivals_at_their_time() -> None:
    # With every pipe crossed in 10 ms the arrivals time none at 0.05 s: the fused localizer
    # answers at the signature's time (60 s). The burst is 100 m along p01: m3's wave comes
    # 1.33 s after the first alarm; at 60 s it would count as silent (no wave before 59.9 s)
    # had its alarm been left out, and no point would fit. The position comes from the
    # arrivals at their horizon (1.4 s), m3's included.
    localizers = _localizers(tau=0.01)
    localizers.fused.longest_travel = 0.01
    assert not localizers.fused.resolves(0.05)
    decision, _, _ = _decide("fused", 100.0, MATRIX[0], localizers)
    assert decision.time > 50.0 and decision.pipe == "p01"
    at = decision.position
    assert at is not None and at.pipe == "p01" and at.start == "m0"
    assert abs(at.metres - 100.0) <= 31.0
    assert at.low <= 100.0 <= at.high and at.high - at.low < 300.0


def _two_meter_arrival() -> ArrivalLocalizer:
    """The line's arrival localizer with meters at its two ends only (m0, m3)."""
    full = line_arrival()
    ends = [0, 3]
    distances = {f"m{i}": np.array([abs(600.0 * i - 600.0 * j) for j in ends]) for i in range(4)}
    return ArrivalLocalizer(full.pipes, ("m0", "m3"), distances, wave_speed=WAVE)


def test_the_horizon_is_the_longest_spread_of_arrivals_at_the_meters() -> None:
    # the candidate points nearest the line's ends (60 m from m0 or m3) reach the other end
    # 1,680 m of travel later; meters between the ends change nothing
    assert _two_meter_arrival().horizon == pytest.approx((1800.0 - 120.0) / WAVE)
    assert line_arrival().horizon == pytest.approx((1800.0 - 120.0) / WAVE)


def _two_meter_burst(dt: float = 0.05, until: float = 80.0) -> tuple:
    """A burst 700 m along the line (p12) as its two end meters (m0, m3) read it: times,
    readings and alarms."""
    t, readings, every = _burst(700.0, np.full(4, 0.5), dt=dt, until=until)
    keep = [0, 3]
    alarms = [
        IndexedAlarm(keep.index(a.channel), a.index, a.start, a.amplitude)
        for a in every
        if a.channel in keep
    ]
    return t, readings[:, keep], alarms


def test_with_few_meters_the_arrivals_are_looked_at_again_until_decisive() -> None:
    # 700 m along the line (p12), meters at its ends: m0 hears the wave at 0.58 s, m3 at 0.92 s.
    # At the first look (0.1 s after the first alarm) only m0 has: p01 and p12 fit alike.
    arrival = _two_meter_arrival()
    t, readings, alarms = _two_meter_burst()
    cal = replace(_calibration(), arrival_decision_delay=0.1)
    first = min(float(t[a.index]) for a in alarms)
    meters = ("m0", "m3")

    def decide(until: float, resume: float | None = None, provisional: bool = True) -> Decision:
        n = int(np.searchsorted(t, until + 1e-9, side="right"))  # the readings so far
        seen = [a for a in alarms if a.index < n]
        return rank_alarms(
            "arrival",
            {"arrival": arrival},
            meters,
            t[:n],
            readings[:n],
            seen,
            cal,
            "instantaneous",
            resume=resume,
            provisional=provisional,
        )

    early = evidence_at(first + 0.1, meters, t, readings, alarms, cal, "instantaneous")
    assert not decisive(arrival.rank(early), quantisation_margin(2))
    decision = decide(float(t[-1]))
    assert decision.pipe == "p12" and decision.look_again is None
    assert first + 0.1 < decision.time <= first + arrival.horizon + 1e-9
    # live, with readings up to the first look only, the answer says when to look again
    provisional = decide(first + 0.1)
    assert provisional.look_again == pytest.approx(first + 0.15)
    # resumed at each look_again, as the live monitor does, the looks reach the same answer
    # at the same time, one look per call
    step = provisional
    calls = 0
    while step.look_again is not None:
        calls += 1
        step = decide(step.look_again, resume=step.look_again)
    assert (step.pipe, step.look_again) == (decision.pipe, None)
    assert step.time == pytest.approx(decision.time, abs=1e-9)  # the same reading
    assert step.position == decision.position
    assert calls == round((decision.time - (first + 0.1)) / cal.capture_interval)
    # a provisional answer carries its region and named point, unless the caller discards it
    # (the live monitor): then the looks alone, and the same final answer
    assert provisional.posterior is not None and provisional.position is not None
    bare = decide(first + 0.1, provisional=False)
    assert bare.look_again == provisional.look_again and bare.time == provisional.time
    assert list(bare.ranking) == list(provisional.ranking)
    assert bare.posterior is None and bare.position is None
    while bare.look_again is not None:
        bare = decide(bare.look_again, resume=bare.look_again, provisional=False)
    assert (bare.pipe, bare.time, bare.position) == (step.pipe, step.time, step.position)
    assert bare.posterior is not None and bare.region == step.region


def test_at_high_rates_the_arrivals_are_looked_at_every_few_readings() -> None:
    # at 100 Hz a look every reading would fit the whole network 100 times a second: the looks
    # come every look_interval (5 readings), each on a reading, and resumed as live they reach
    # the same answer at the same look
    from burstloc.localize.looks import LOOK_INTERVAL, look_interval

    assert look_interval(0.2) == 0.2 and look_interval(0.05) == 0.05
    assert look_interval(0.01) == pytest.approx(5 * 0.01)
    assert look_interval(0.004) == pytest.approx(12 * 0.004)  # 48 ms, on a reading
    dt = 0.01
    arrival = _two_meter_arrival()
    t, readings, alarms = _two_meter_burst(dt, until=20.0)
    cal = replace(_calibration(dt), arrival_decision_delay=0.1)
    first = min(float(t[a.index]) for a in alarms)
    meters = ("m0", "m3")

    def decide(until: float, resume: float | None = None) -> Decision:
        n = int(np.searchsorted(t, until + 1e-9, side="right"))
        seen = [a for a in alarms if a.index < n]
        return rank_alarms(
            "arrival", {"arrival": arrival}, meters, t[:n], readings[:n], seen, cal,
            "instantaneous", resume=resume, provisional=False,
        )  # fmt: skip

    decision = decide(float(t[-1]))
    assert decision.pipe == "p12" and decision.look_again is None
    step = decide(first + 0.1)
    looks = [step.time]
    while step.look_again is not None:
        assert step.look_again == pytest.approx(looks[-1] + LOOK_INTERVAL)
        step = decide(step.look_again, resume=step.look_again)
        looks.append(step.time)
    assert step.pipe == decision.pipe
    assert step.time == pytest.approx(decision.time, abs=1e-9)  # the same reading
    assert step.position == decision.position
    gaps = np.diff(looks)
    assert len(looks) > 2 and np.allclose(gaps, LOOK_INTERVAL)
    # every look on a reading
    assert all(np.min(np.abs(t - x)) < 1e-9 for x in looks)
