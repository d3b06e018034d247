"""Travel times learnt from known events: the wave speed, the clocks and what is left."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import BurstEvidence, MeterAlarm
from burstloc.localize.model import LocalizationModel
from burstloc.localize.travel_fit import EventArrivals, fit_travel_times, robust_slowness

METERS = tuple(f"m{k}" for k in range(8))


def _events(
    speed: float,
    offsets: dict[str, float],
    dt: float,
    *,
    count: int = 3,
    seed: int = 0,
    meters: tuple[str, ...] = METERS,
) -> list[EventArrivals]:
    """``count`` events at random places, each meter's onset the reading before its arrival
    (the event at a random time within a reading, clocks off by ``offsets``)."""
    rng = np.random.default_rng(seed)
    found = []
    for e in range(count):
        t0 = 10.0 + rng.uniform(0, dt)
        distances = {m: float(rng.uniform(100, 3000)) for m in meters}
        onsets = {
            m: math.floor((t0 + d / speed + offsets.get(m, 0.0)) / dt) * dt
            for m, d in distances.items()
        }
        found.append(EventArrivals(f"e{e}", t0, distances, onsets, dt))
    return found


def test_a_wrong_wave_speed_is_corrected_from_three_events() -> None:
    events = _events(1000.0, {}, 0.01)
    fit = fit_travel_times(
        events, METERS, wave_speed=1150.0, wave_speed_tolerance=0.05, clock_tolerance=0.0
    )
    assert fit.wave_speed == pytest.approx(1000.0, rel=0.01)  # from 1 150 (15 % off)
    assert fit.arrivals == 3 * len(METERS) and fit.dropped == 0
    assert fit.clock_offsets == {m: 0.0 for m in METERS}  # a tolerance of 0: not fitted
    # arrivals known to a reading: what is left is rounding, stated at the floor
    assert fit.wave_speed_tolerance == pytest.approx(0.02)
    assert fit.rms < 0.01


def test_bursts_found_later_teach_the_speed_from_their_arrivals_differences() -> None:
    # the time recorded is the first meter's change, not the burst's: up to seconds off
    exact = _events(1000.0, {}, 0.01, seed=5)
    first = [min(e.onsets.values()) for e in exact]
    found = [replace(e, time=t, time_known=False) for e, t in zip(exact, first, strict=True)]
    options = {"wave_speed": 1150.0, "wave_speed_tolerance": 0.05, "clock_tolerance": 0.0}
    fit = fit_travel_times(found, METERS, **options)
    assert fit.wave_speed == pytest.approx(1000.0, rel=0.02)
    # taken as the burst's time, the first change makes every wave look far too fast
    taken = [replace(e, time_known=True) for e in found]
    assert fit_travel_times(taken, METERS, **options).wave_speed > 1300.0
    # an event of unknown time heard at one distance says nothing; the others still speak
    lone = replace(found[0], name="lone", onsets={"m0": found[0].onsets["m0"]})
    assert fit_travel_times([*found, lone], METERS, **options).arrivals == fit.arrivals


def test_an_event_heard_late_at_most_meters_does_not_move_the_speed() -> None:
    # two events heard on time; a third whose front most meters missed, heard a larger wave
    # 0.4-7 s later (as L-TOWN's meters heard a 10 L/s burst on p8 at 0.05 s)
    events = _events(1100.0, {}, 0.05, count=3, seed=7)
    rng = np.random.default_rng(1)
    late = {m: t + float(rng.uniform(0.4, 7.0)) for m, t in list(events[2].onsets.items())[2:]}
    events[2] = replace(events[2], onsets={**events[2].onsets, **late})
    options = {"wave_speed": 1200.0, "wave_speed_tolerance": 0.05, "clock_tolerance": 0.0}
    fit = fit_travel_times(events, METERS, **options)
    assert fit.wave_speed == pytest.approx(1100.0, rel=0.03)
    assert fit.dropped >= len(late) and fit.arrivals >= 2 * len(METERS)
    assert fit.wave_speed_tolerance < 0.05  # what is left is the readings' rounding
    on_time = fit_travel_times(events[:2], METERS, **options)
    assert fit.wave_speed == pytest.approx(on_time.wave_speed, rel=0.01)
    # the same when its time is not known (a burst found later)
    found = [replace(e, time=min(e.onsets.values()), time_known=False) for e in events]
    assert fit_travel_times(found, METERS, **options).wave_speed == pytest.approx(1100, rel=0.03)


def test_the_robust_start_is_the_median_slope_within_events() -> None:
    distance = np.array([100.0, 200.0, 300.0, 100.0, 400.0])
    travel = np.array([0.1, 0.2, 5.0, 0.1, 0.4])  # one late arrival
    event = np.array([0, 0, 0, 1, 1])
    unknown, known, equal = np.zeros(5, dtype=bool), np.ones(5, dtype=bool), np.ones(5)
    assert robust_slowness(travel, distance, event, unknown, equal) == pytest.approx(0.001)
    # a known time adds each arrival's slope from the event itself
    assert robust_slowness(travel, distance, event, known, equal) == pytest.approx(0.001)
    one = np.zeros(1, dtype=bool)
    assert math.isnan(robust_slowness(travel[:1], distance[:1], event[:1], one, equal[:1]))


def test_clock_offsets_are_fitted_within_their_tolerance() -> None:
    offsets = {"m2": 0.030, "m5": -0.020}
    events = _events(1200.0, offsets, 0.001, count=4, seed=3)
    fit = fit_travel_times(
        events, METERS, wave_speed=1200.0, wave_speed_tolerance=0.05, clock_tolerance=0.05
    )
    assert fit.wave_speed == pytest.approx(1200.0, rel=0.01)
    assert fit.clock_offsets["m2"] == pytest.approx(0.030, abs=0.004)
    assert fit.clock_offsets["m5"] == pytest.approx(-0.020, abs=0.004)
    assert abs(fit.clock_offsets["m0"]) < 0.004
    # the same arrivals without offsets fitted: the clocks' error is left as travel-time error
    fixed = fit_travel_times(
        events, METERS, wave_speed=1200.0, wave_speed_tolerance=0.05, clock_tolerance=0.0
    )
    assert fixed.rms > 10 * fit.rms


def test_an_alarm_on_something_else_is_dropped() -> None:
    events = _events(1000.0, {}, 0.01)
    wrong = dict(events[0].onsets, m3=events[0].onsets["m3"] + 2.0)  # heard a reflection
    events[0] = EventArrivals("e0", events[0].time, events[0].distances, wrong, 0.01)
    fit = fit_travel_times(
        events, METERS, wave_speed=1200.0, wave_speed_tolerance=0.05, clock_tolerance=0.0
    )
    assert fit.dropped == 1 and fit.wave_speed == pytest.approx(1000.0, rel=0.01)


def test_events_that_cannot_tell_a_speed_are_refused() -> None:
    kw = {"wave_speed": 1200.0, "wave_speed_tolerance": 0.05, "clock_tolerance": 0.0}
    with pytest.raises(ConfigError, match="no known event"):
        fit_travel_times([], METERS, **kw)
    one = EventArrivals("e", 10.0, {"m0": 500.0, "m1": 500.0}, {"m0": 10.4, "m1": 10.4}, 0.1)
    with pytest.raises(ConfigError, match="2 arrival"):
        fit_travel_times([one], METERS, **kw)
    backwards = EventArrivals(
        "e",
        10.0,
        {m: 100.0 * (k + 1) for k, m in enumerate(METERS)},
        {m: 9.5 for m in METERS},
        0.01,
    )  # fmt: skip  (heard before it happened: the time is wrong)
    with pytest.raises(ConfigError, match="no finite"):
        fit_travel_times([backwards], METERS, **kw)
    stranger = EventArrivals("e", 10.0, {"zz": 1.0}, {"zz": 10.0}, 0.1)
    with pytest.raises(ConfigError, match="'zz' is not a meter"):
        fit_travel_times([stranger], METERS, **kw)


def _model(**changes: object) -> LocalizationModel:
    from test_model import _line_model

    return _line_model(**changes)


def test_a_fit_is_stored_in_the_model_and_read_back() -> None:
    model = _model()
    events = _events(1000.0, {}, 0.01, meters=model.meters)
    fit = fit_travel_times(
        events, model.meters, wave_speed=1200.0, wave_speed_tolerance=0.05, clock_tolerance=0.01
    )
    fitted = fit.apply(model)
    assert fitted.wave_speed == fit.wave_speed
    assert fitted.wave_speed_tolerance == fit.wave_speed_tolerance
    assert set(fitted.clock_offsets or {}) == set(model.meters)
    back = LocalizationModel.from_json(json.loads(json.dumps(fitted.to_json())))
    assert back == fitted and back.clock_offsets == fitted.clock_offsets
    assert "clock_offsets_s" not in model.to_json()  # none known: none stored
    with pytest.raises(ConfigError, match="'zz' is not a meter"):
        _model(clock_offsets={"zz": 0.1})
    with pytest.raises(ConfigError, match=r"clock_offsets_s\.m0"):
        _model(clock_offsets={"m0": math.nan})


def test_the_arrival_localizer_takes_each_meters_offset_off_its_alarm() -> None:
    from test_model import METERS as LINE
    from test_model import WAVE

    model = _model()
    late = {"m2": 0.2}  # m2's clock runs 0.2 s late
    dt, t0, where = 0.01, 10.0, 750.0  # 150 m along p12
    arrive = {m: t0 + abs(where - 600.0 * i) / WAVE for i, m in enumerate(LINE)}
    alarms = {
        m: MeterAlarm(m, math.floor((a + late.get(m, 0.0)) / dt) * dt, -1.0)
        for m, a in arrive.items()
    }
    t = np.arange(0.0, 20.0, dt)
    evidence = BurstEvidence(
        LINE, t, np.zeros((t.size, len(LINE))), onset=10.0, capture_interval=dt, alarms=alarms
    )

    def localizer(offsets: dict[str, float] | None) -> ArrivalLocalizer:
        return ArrivalLocalizer(
            model.pipes, model.meters, model.node_distances, wave_speed=WAVE,
            clock_offsets=offsets,
        )  # fmt: skip

    told, untold = localizer(late), localizer(None)
    assert told.misfit(evidence).min() < 0.5 * untold.misfit(evidence).min()
    assert told.position(evidence, "p12").metres == pytest.approx(150.0, abs=10.0)
    assert abs(untold.position(evidence, "p12").metres - 150.0) > 30.0
