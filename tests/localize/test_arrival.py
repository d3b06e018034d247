"""The arrival localizer: wave travel from a point on a pipe explains the meters' alarm starts.

The localizers on the tiny network are built offline from the network file
(:func:`burstloc.sim.model.prepare.arrival_localizer`); the live path builds them from a stored
model
(tests/localize/test_model.py)."""

from __future__ import annotations

import math
from pathlib import Path

import networkx as nx
import numpy as np
import pytest

from alarm_evidence import arrival_evidence
from burstloc.exceptions import ConfigError, InputError, NetworkError
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.evidence import (
    BurstEvidence,
)
from burstloc.localize.pipes import PipeGeometry
from burstloc.network import load_network
from burstloc.sim.model.prepare import arrival_localizer, length_graph

A = 1000.0  # wave speed used by these tests, m/s


def _true_arrivals(
    loc: ArrivalLocalizer, network: Path, pipe: str, fraction: float, t0: float
) -> dict[str, float]:
    """Arrival time at every meter of a burst at ``fraction`` along ``pipe`` (INP direction)."""
    wn = load_network(network)
    graph = length_graph(wn)
    link = wn.get_link(pipe)
    u, v, length = link.start_node_name, link.end_node_name, link.length
    du = nx.single_source_dijkstra_path_length(graph, u, weight="length")
    dv = nx.single_source_dijkstra_path_length(graph, v, weight="length")
    return {
        m: t0 + min(fraction * length + du[m], (1 - fraction) * length + dv[m]) / A
        for m in loc.meters
    }


@pytest.mark.parametrize(("pipe", "fraction"), [("B", 0.5), ("C", 0.3), ("D", 0.6), ("E", 0.7)])
def test_true_pipe_ranks_first_at_a_fine_capture_interval(
    tiny_network: Path, pipe: str, fraction: float
) -> None:
    loc = arrival_localizer(tiny_network, wave_speed=A)
    arrivals = _true_arrivals(loc, tiny_network, pipe, fraction, t0=1.0037)
    ranking = loc.rank(arrival_evidence(arrivals, dt=0.01))
    assert ranking.best is not None and ranking.best.pipe == pipe
    assert len(ranking) == 5


def test_exact_arrivals_fit_with_zero_misfit(tiny_network: Path) -> None:
    loc = arrival_localizer(tiny_network, wave_speed=A, positions=[0.5])
    arrivals = _true_arrivals(loc, tiny_network, "D", 0.5, t0=2.0)
    misfit = loc.misfit(arrival_evidence(arrivals, dt=0.001))
    d = [p.pipe for p in loc.pipes].index("D")
    assert misfit[d] < 0.001
    assert np.all(np.delete(misfit, d) > 0.005)


def test_amplitudes_break_ties_at_coarse_intervals(tiny_network: Path) -> None:
    loc = arrival_localizer(tiny_network, wave_speed=A)
    arrivals = _true_arrivals(loc, tiny_network, "E", 0.5, t0=1.0)
    # at a 10 s capture interval every alarm lands in one tick: timing cannot tell pipes apart
    amps = {"J1": -0.5, "J2": -0.6, "J3": -1.5, "J4": -2.0}
    ranking = loc.rank(arrival_evidence(arrivals, dt=10.0, amplitudes=amps))
    assert ranking.best is not None and ranking.best.pipe == "E"  # J3 and J4: the largest drops
    scores = ranking.scores()
    assert scores["E"] > scores["C"] > scores["A"]


def test_pipes_follow_the_flow_direction(tiny_network: Path) -> None:
    loc = arrival_localizer(tiny_network)
    ends = {p.pipe: (p.start, p.end) for p in loc.pipes}
    assert ends["A"] == ("R1", "J1")
    assert ends["E"] == ("J3", "J4")
    assert loc.pipe_travel == pytest.approx(200.0 / 1200.0)


def test_meters_subset_and_missing_alarms(tiny_network: Path) -> None:
    loc = arrival_localizer(tiny_network, ["J2", "J4"], wave_speed=A)
    arrivals = _true_arrivals(loc, tiny_network, "E", 0.5, t0=0.5)
    ranking = loc.rank(arrival_evidence({"J4": arrivals["J4"]}, dt=0.01, amplitudes={"J4": -1}))
    assert ranking.best is not None
    assert ranking.rank_of("E") is not None
    with pytest.raises(InputError, match="no meter"):
        loc.rank(arrival_evidence({"J1": 1.0}, dt=0.01))


def test_bad_configuration_is_refused(tiny_network: Path) -> None:
    with pytest.raises(ConfigError):
        arrival_localizer(tiny_network, wave_speed=0.0)
    with pytest.raises(ConfigError):
        arrival_localizer(tiny_network, positions=[1.5])
    with pytest.raises(NetworkError, match="R1"):
        arrival_localizer(tiny_network, ["R1"])
    with pytest.raises(ConfigError, match="no distances"):
        ArrivalLocalizer([PipeGeometry("x", "a", "b", 10.0)], ["m"], {"a": np.zeros(1)})


def _line_evidence(loc: ArrivalLocalizer, where: float, dt: float, t0: float) -> BurstEvidence:
    """Alarm starts of a burst ``where`` metres along the line m0 - m1 - m2 - m3 (600 m apart)."""
    spots = {m: 600.0 * i for i, m in enumerate(loc.meters)}
    return arrival_evidence({m: t0 + abs(where - x) / loc.wave_speed for m, x in spots.items()}, dt)


@pytest.mark.parametrize(("where", "dt"), [(700.0, 0.01), (1130.0, 0.01), (900.0, 0.2)])
def test_position_is_the_burst_point_within_one_capture_step(where: float, dt: float) -> None:
    from line_network import line_arrival

    loc = line_arrival()
    evidence = _line_evidence(loc, where, dt, t0=1.0013)
    pipe = loc.rank(evidence).best
    assert pipe is not None and pipe.pipe == "p12"
    at = loc.position(evidence, "p12")
    assert (at.pipe, at.start, at.end, at.length) == ("p12", "m1", "m2", 600.0)
    # one capture step of timing error is wave speed x dt metres of travel (both ways: half)
    step = loc.wave_speed * dt
    assert abs(at.metres - (where - 600.0)) <= step / 2 + 1.0
    assert at.low <= where - 600.0 <= at.high
    assert at.high - at.low <= 2 * step + 2.0
    record = at.to_json()
    assert record["from"] == "m1" and record["metres"] == at.metres


def test_position_interval_is_the_whole_pipe_when_meters_are_beyond_one_end() -> None:
    # Meters only at m2 and m3: every point of p01 reaches them through m1, so the arrivals
    # cannot tell p01's points apart.
    distances = {
        "m0": np.array([1200.0, 1800.0]),
        "m1": np.array([600.0, 1200.0]),
        "m2": np.array([0.0, 600.0]),
    }
    pipes = [PipeGeometry("p01", "m0", "m1", 600.0), PipeGeometry("p12", "m1", "m2", 600.0)]
    loc = ArrivalLocalizer(pipes, ("m2", "m3"), distances, wave_speed=1200.0)
    evidence = arrival_evidence({"m2": 1.5, "m3": 2.0}, 0.01)
    at = loc.position(evidence, "p01")
    assert (at.low, at.high) == (0.0, 600.0)
    assert at.metres == pytest.approx(300.0)
    with pytest.raises(InputError, match="not a candidate"):
        loc.position(evidence, "nope")


def test_position_tolerance_is_the_quantisation_noise_of_the_rms() -> None:
    from burstloc.localize.arrival import position_tolerance

    assert position_tolerance(3) == pytest.approx(1 / 6)  # 1 / sqrt(12 x 3)
    assert position_tolerance(12) < position_tolerance(3)
    with pytest.raises(InputError, match="at least one alarm"):
        position_tolerance(0)


def test_horizon_spans_the_reachable_meters_only() -> None:
    # m9 is cut off (no path): it does not stretch the horizon. From p01's point nearest m0
    # (10 % along) the wave travels 60 m to m0 and 1,140 m to m2: 1,080 m apart.
    inf = math.inf
    distances = {
        "m0": np.array([0.0, 1200.0, inf]),
        "m1": np.array([600.0, 600.0, inf]),
        "m2": np.array([1200.0, 0.0, inf]),
    }
    pipes = [PipeGeometry("p01", "m0", "m1", 600.0), PipeGeometry("p12", "m1", "m2", 600.0)]
    loc = ArrivalLocalizer(pipes, ("m0", "m2", "m9"), distances, wave_speed=1200.0)
    assert loc.horizon == pytest.approx(1080.0 / 1200.0)
    alone = ArrivalLocalizer(pipes, ("m9",), {n: np.array([inf]) for n in distances})
    assert alone.horizon == 0.0


def test_silence_counts_where_the_front_is_at_least_an_alarmed_meters() -> None:
    from burstloc.localize.windows import silence_counts

    fronts = np.array(
        [
            [1.0, 0.5, 0.2, 0.6, 0.1],  # weakest alarmed front 0.5: meters 3 (0.6) count, 4 not
            [0.0, 0.3, 0.3, 0.2, 0.9],  # meter 0 gets no front: it says nothing of the size
            [0.0, 0.0, 0.1, 0.2, 0.3],  # no front at any alarm: every silence counts, as before
        ]
    )
    heard = silence_counts(fronts, [0, 1], [2, 3, 4])
    assert heard.tolist() == [[False, True, False], [True, False, True], [True, True, True]]
    # the burst's size cancels: scaling a candidate's fronts changes nothing
    np.testing.assert_array_equal(silence_counts(fronts * 7.5, [0, 1], [2, 3, 4]), heard)


def _silent_too(evidence: BurstEvidence, silent: list[str]) -> BurstEvidence:
    """``evidence`` with ``silent`` meters that read (flat) but never alarmed."""
    meters = evidence.meters + tuple(silent)
    readings = np.zeros((evidence.times.size, len(meters)))
    return BurstEvidence(
        meters=meters,
        times=evidence.times,
        readings=readings,
        onset=evidence.onset,
        capture_interval=evidence.capture_interval,
        alarms=evidence.alarms,
    )


def test_a_meter_too_weakly_reached_to_alarm_does_not_count_against_the_true_pipe(
    tiny_network: Path,
) -> None:
    # A burst on E (J3 - J4, J4 a dead end): J4 and J3 alarm; J1 and J2, reached 0.4 s later
    # through the 200 mm pipes, stay silent to the decision time at 5 s. Their fronts (J3's
    # share of E's front times J1's or J2's share) are weaker than J3's: their silence says
    # nothing, and E fits its alarms exactly. Counting them as "not reached" costs E misfit.
    meters = ["J1", "J2", "J3", "J4"]
    loc = arrival_localizer(tiny_network, meters, wave_speed=A)
    blind = arrival_localizer(tiny_network, meters, wave_speed=A, fronts=None)
    arrivals = _true_arrivals(loc, tiny_network, "E", 0.5, t0=1.0037)
    seen = {m: arrivals[m] for m in ("J3", "J4")}
    evidence = _silent_too(arrival_evidence(seen, dt=0.01), ["J1", "J2"])
    assert evidence.decision_time > max(arrivals.values()) + 1.0
    e = [p.pipe for p in loc.pipes].index("E")
    assert loc.misfit(evidence)[e] == pytest.approx(0.0, abs=1e-6)
    assert blind.misfit(evidence)[e] > 0.05
    best = loc.rank(evidence).best
    assert best is not None and best.pipe == "E"


def test_a_meter_that_should_have_heard_the_wave_still_counts(tiny_network: Path) -> None:
    # A burst on C (J1 - J3): J1 and J3 alarm. J4 lies beyond J3 at a dead end (the front
    # doubles there) and J2 beyond the 200/150 mm pipes: both fronts are at least J1's, so
    # their silence to 5 s says the wave has not come, against C, with or without the fronts.
    meters = ["J1", "J2", "J3", "J4"]
    loc = arrival_localizer(tiny_network, meters, wave_speed=A)
    blind = arrival_localizer(tiny_network, meters, wave_speed=A, fronts=None)
    arrivals = _true_arrivals(loc, tiny_network, "C", 0.5, t0=1.0037)
    evidence = _silent_too(
        arrival_evidence({m: arrivals[m] for m in ("J1", "J3")}, dt=0.01), ["J2", "J4"]
    )
    c = [p.pipe for p in loc.pipes].index("C")
    assert loc.misfit(evidence)[c] > 0.05
    assert loc.misfit(evidence)[c] == pytest.approx(blind.misfit(evidence)[c])


def test_fit_windows_finds_the_least_squares_burst_time() -> None:
    """Each point's burst time is the least of its squared window misfit (checked against a
    fine scan of the objective), alarms and silent meters alike; a point that explains no
    alarm is not placed and misfits nothing."""
    from burstloc.localize.windows import fit_windows, window_misfit

    rng = np.random.default_rng(7)
    points, meters, alarmed, dt = 60, 12, 5, 0.01
    start = rng.uniform(9.0, 10.0, (points, meters))
    lo = start.copy()
    hi = start + dt
    hi[:, alarmed:] = np.inf  # silent meters: not reached before lo
    lo[:, -3:] = -np.inf  # meters that say nothing
    hi[:, -3:] = np.inf
    lo[0, :alarmed], hi[0, :alarmed] = -np.inf, np.inf  # no alarm explained
    gap, placed = fit_windows(lo, hi, alarmed, dt)
    assert not placed[0] and placed[1:].all()
    assert np.all(gap[0] == 0.0)
    scan = np.linspace(8.9, 10.1, 120_001)  # 10 us steps
    for i in range(1, points):
        cost = (window_misfit(lo[i][None, :], hi[i][None, :], scan[:, None]) ** 2).sum(axis=1)
        found = float((gap[i] ** 2).sum())
        assert found <= cost.min() + 1e-9
        assert found == pytest.approx(cost.min(), abs=1e-6)


def test_an_alarm_on_a_rise_bounds_the_first_front_and_does_not_time_it() -> None:
    """A burst's first front is a drop; a far meter whose first front was too weak to alarm on
    alarms later on a rise (a reflection). Its alarm says only that the front came no later:
    on the line m0 - m1 - m2 - m3, a burst 700 m along with m3's alarm 0.4 s late is placed
    where it is when that alarm is a rise, and pulled away from m3 when it is a drop."""
    from burstloc.localize.evidence import against_front
    from line_network import line_arrival

    loc = line_arrival()
    where, dt = 700.0, 0.01
    spots = {m: 600.0 * i for i, m in enumerate(loc.meters)}
    arrivals = {m: 1.0013 + abs(where - x) / loc.wave_speed for m, x in spots.items()}
    arrivals["m3"] += 0.4
    rise = arrival_evidence(arrivals, dt, amplitudes={"m3": 0.08})
    drop = arrival_evidence(arrivals, dt)
    assert against_front(rise, list(loc.meters)).tolist() == [False, False, False, True]
    assert not against_front(drop, list(loc.meters)).any()
    bounded, timed = loc.position(rise, "p12"), loc.position(drop, "p12")
    step = loc.wave_speed * dt
    assert abs(bounded.metres - (where - 600.0)) <= step / 2 + 1.0
    assert abs(timed.metres - (where - 600.0)) > 2 * step
    # at a coarse interval a reading holds the front and what follows: a rise is timed as a drop
    coarse = {m: 1.0013 + abs(where - x) / loc.wave_speed for m, x in spots.items()}
    rise_coarse = arrival_evidence(coarse, 0.2, amplitudes={"m3": 0.08})
    assert loc.position(rise_coarse, "p12") == loc.position(arrival_evidence(coarse, 0.2), "p12")
    # the bound still counts: an alarm on a rise before the front could reach its meter misfits
    early = dict(arrivals, m3=arrivals["m3"] - 0.4 - 0.3)
    assert (
        loc.misfit(arrival_evidence(early, dt, amplitudes={"m3": 0.08}))[
            [p.pipe for p in loc.pipes].index("p12")
        ]
        > loc.misfit(rise)[[p.pipe for p in loc.pipes].index("p12")]
    )
