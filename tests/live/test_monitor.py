"""burstloc.live.monitor: the live loop of the ranking localizers (calibrated bank, bounded
history)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from live_feed import Collected

from burstloc.cli import main
from burstloc.exceptions import ConfigError, InputError
from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.evaluate import evaluate
from burstloc.experiments.harness import readings_at_offset
from burstloc.experiments.runs import RunSpec
from burstloc.live.monitor import BurstMonitor
from burstloc.live.windows import readings_of
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.config import Calibration
from burstloc.localize.decide import arrival_horizon
from burstloc.localize.detection import DetectorConfig
from burstloc.readings import Step
from burstloc.sim.scenarios.sensors import SensorModel
from conftest import write_tiny

SHORT = paper.ScenarioConfig(burst_start=2.0)


@pytest.fixture(scope="module")
def config(tiny: Path) -> Calibration:
    return calibrate(tiny, capture_intervals=(0.2, 2.0), noise_sigma=0.01)


def _evaluate(
    tiny: Path, config: Calibration, intervals: tuple[float, ...], noise: float | None = 0.0
):
    """``evaluate``'s answers (the batch reference) for bursts on two pipes (noiseless unless
    ``noise`` says otherwise: ``None`` is evaluate's default, the calibrated noise)."""
    runs = [
        RunSpec(DetectorConfig("cusum", 0.3), ci, 5, localizer=name)
        for ci in intervals
        for name in ("arrival", "fused")
    ]
    return evaluate(
        tiny,
        runs,
        pipes=["B", "C"],
        phases=1,
        scenario=SHORT,
        config=config,
        workers=1,
        progress=False,
        noise=noise,
    )


@pytest.fixture(scope="module")
def batch(tiny: Path, config: Calibration):
    """``evaluate``'s answers at 0.2 and 2 s."""
    return _evaluate(tiny, config, (0.2, 2.0))


def _steps(result, spec: RunSpec) -> list[Step]:
    times, values = readings_at_offset(result, spec, 0.0)
    return [Step(float(t), v) for t, v in zip(times, values, strict=True)]


def test_the_live_loop_decides_what_evaluate_decides(tiny: Path, config: Calibration, batch):
    for run in batch.runs:
        spec = run.spec
        for pipe in run.pipes:
            expected = run.attempts[pipe][0]
            assert expected.ranking is not None
            monitor = BurstMonitor(
                tiny, config, capture_interval=spec.capture_interval, localizer=spec.localizer
            )
            records = monitor.run(_steps(batch.results[pipe], spec))
            decisions = [d for d in records if not d.transient]  # the answers
            assert decisions, (spec, pipe)
            live = decisions[0]
            assert live.pipe == expected.predicted_pipe
            assert [r.pipe for r in live.ranking] == [r.pipe for r in expected.ranking]
            assert math.isclose(live.time, expected.decided_at, abs_tol=1e-9)
            assert live.first_alarm <= live.time
            doc = live.to_json()
            assert [p["pipe"] for p in doc["pipes"]] == [r.pipe for r in expected.ranking.top(3)]


@pytest.mark.parametrize("noise", [None, 0.05])
def test_the_live_loop_decides_what_evaluate_decides_under_noise(
    tiny: Path, config: Calibration, noise: float | None
):
    # evaluate's own noise (None: each meter's calibrated sigma, 0.01 m; 0.05 m: five times
    # what the bank was calibrated for, so that meters alarm alone before the burst), and the
    # same noisy readings, reading by reading, through the live loop (reading stream, health,
    # monitor): every attempt's decision, or its absence, is the same.
    names = ("arrival", "signature", "fused")
    runs = [RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer=name) for name in names]
    ev = evaluate(
        tiny, runs, phases=3, scenario=SHORT, config=config, workers=1, progress=False, noise=noise
    )
    assert ev.scenario["noise"]["ranking"] == (noise if noise is not None else config.noise_sigma)
    sensor = SensorModel(
        noise_sigma=noise or 0.0, meter_sigma=None if noise else config.noise_sigma
    )
    compared = 0
    for run in ev.runs:
        for pipe in run.pipes:
            for offset, expected in zip(run.offsets, run.attempts[pipe], strict=True):
                result = ev.results[pipe]
                times, values = readings_at_offset(
                    result, run.spec, offset, config.meters, sensor=sensor
                )
                exact, _ = readings_at_offset(result, run.spec, offset, config.meters)
                assert np.array_equal(times, exact)
                steps = [Step(float(t), v) for t, v in zip(times, values, strict=True)]
                monitor = BurstMonitor(
                    tiny, config, capture_interval=0.2, localizer=run.spec.localizer
                )
                decided = Collected(monitor).run(readings_of(steps, monitor.meters)).decisions
                if expected.decision is None:
                    assert decided == [], (run.spec.localizer, pipe, offset)
                    continue
                live = decided[0]
                assert live["pipes"][0]["pipe"] == expected.predicted_pipe
                assert expected.ranking is not None
                top = [r.pipe for r in expected.ranking.top(3)]
                assert [p["pipe"] for p in live["pipes"]] == top, (run.spec.localizer, pipe)
                # the reading stream puts each step on the capture grid (k x 0.2 s): a clock
                # offset moves the stamp by less than half an interval, never the step
                assert expected.decided_at is not None
                assert abs(live["time"] - expected.decided_at) < 0.1 + 1e-9
                compared += 1
    assert compared >= len(ev.runs[0].pipes) * 3  # most attempts decided


def test_the_live_loop_looks_again_at_the_arrivals_as_evaluate_does(
    tiny: Path, config: Calibration
):
    # the first look at the first alarm itself: one meter has heard the wave, and the answer
    # comes at a later look (rank_alarms' look_again), live as in evaluate
    eager = replace(
        config,
        intervals=tuple(replace(i, arrival_decision_delay=0.0) for i in config.intervals),
    )
    ev = _evaluate(tiny, eager, (0.2,))
    later = 0
    for run in ev.runs:
        for pipe in run.pipes:
            expected = run.attempts[pipe][0]
            monitor = BurstMonitor(tiny, eager, capture_interval=0.2, localizer=run.spec.localizer)
            records = monitor.run(_steps(ev.results[pipe], run.spec))
            live = next(d for d in records if not d.transient)
            assert live.pipe == expected.predicted_pipe
            assert math.isclose(live.time, expected.decided_at, abs_tol=1e-9)
            later += live.time > live.first_alarm + 1e-9
    assert later > 0


def test_raw_readings_go_through_the_reading_stream(tiny: Path, config: Calibration, batch):
    run = batch.runs[0]  # arrival at 0.2 s
    steps = _steps(batch.results["C"], run.spec)
    reference = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    expected = next(reference.run(steps))
    monitor = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    readings = list(readings_of(steps, monitor.meters))
    readings[0], readings[1] = readings[1], readings[0]  # out of order within a step is fine
    decided = Collected(monitor).run(readings).decisions
    assert decided and decided[0]["pipes"][0]["pipe"] == expected.pipe
    assert decided[0]["time"] == pytest.approx(expected.time)


def test_one_decision_per_burst_thanks_to_the_holdoff(tiny: Path, config: Calibration, batch):
    steps = _steps(batch.results["B"], batch.runs[0].spec)
    monitor = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    decisions, holding = [], []
    for step in steps:
        decided = monitor.push(step)
        if decided is not None:
            decisions.append(decided)
        holding.append(monitor.holding_off)
    assert len(decisions) == 1 and decisions[0].time < SHORT.burst_start + 1.0
    decided_at = decisions[0].time
    assert [h for s, h in zip(steps, holding, strict=True) if s.timestamp < decided_at] == [
        False
    ] * sum(s.timestamp < decided_at for s in steps)
    assert all(
        h == (s.timestamp < decided_at + monitor.holdoff - 1e-9)
        for s, h in zip(steps, holding, strict=True)
        if s.timestamp >= decided_at
    )
    # Without a hold-off the ringing network is "located" again and again.
    eager = BurstMonitor(
        tiny, config, capture_interval=0.2, localizer="arrival", holdoff=0.0, rearm=0
    )
    assert len(list(eager.run(steps))) > 1
    # Re-arming (alarm-free steps before an alarm counts again) alone already prevents that.
    rearmed = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival", holdoff=0.0)
    assert len(list(rearmed.run(steps))) == 1
    with pytest.raises(ConfigError, match="holdoff"):
        BurstMonitor(tiny, config, capture_interval=0.2, holdoff=-1.0)


def test_a_quiet_feed_decides_nothing_and_history_is_bounded(tiny: Path, config: Calibration):
    monitor = BurstMonitor(tiny, config, capture_interval=2.0, localizer="signature")
    level = np.linspace(50.0, 60.0, len(monitor.meters))
    steps = [Step(2.0 * k, level) for k in range(2_000)]
    assert list(monitor.run(steps)) == [] and not monitor.pending
    cal = config.for_interval(2.0)
    assert len(monitor._times) < (60 + cal.decision_delay) / 2.0 + 2 * cal.localization_interval + 5


def test_bad_steps_are_refused_by_name_and_leave_the_monitor_as_it_was(
    tiny: Path, config: Calibration, batch
) -> None:
    steps = _steps(batch.results["B"], batch.runs[0].spec)
    split = next(k for k, s in enumerate(steps) if s.timestamp > SHORT.burst_start) + 2
    clean = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    fed = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    for s in steps[:split]:
        clean.push(s)
        fed.push(s)
    m = len(fed.meters)
    nan = steps[split].values.copy()
    nan[1] = np.nan
    huge = steps[split].values.copy()
    huge[2] = -1e150  # finite, but beyond what a detector takes
    bad = [
        (Step(steps[split].timestamp, nan), f"non-finite reading nan from meter {fed.meters[1]!r}"),
        (
            Step(steps[split].timestamp, huge),
            f"out-of-range reading -1e\\+150 from meter {fed.meters[2]!r}",
        ),
        (Step(steps[split].timestamp, np.ones(m + 1)), f"values for {m} meters"),
        (Step(steps[split - 1].timestamp, steps[split].values), "is not after the previous"),
        (Step(math.inf, steps[split].values), "not finite"),
    ]
    for step, message in bad:
        with pytest.raises(InputError, match=message):
            fed.push(step)
    rest_clean = list(clean.run(steps[split:]))
    rest_fed = list(fed.run(steps[split:]))
    assert [d.to_json() for d in rest_fed] == [d.to_json() for d in rest_clean]
    assert rest_fed


def test_the_monitor_keeps_a_step_s_values_and_never_writes_them(
    tiny: Path, config: Calibration, batch
) -> None:
    """The step's own array is read, not copied (module ``live.history``) and not written: a
    value filled for an excluded meter is filled in a copy, and the caller's array keeps its
    NaN; what the monitor decides is what it decides from copies."""
    steps = _steps(batch.results["B"], batch.runs[0].spec)
    gap = [
        Step(s.timestamp, np.where(np.arange(s.values.size) == 1, np.nan, s.values)) for s in steps
    ]
    kept = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    copied = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival")
    for m in (kept, copied):
        m.exclude(kept.meters[1])
    from_kept = [d.to_json() for d in kept.run(gap)]
    from_copies = [d.to_json() for d in copied.run(Step(s.timestamp, s.values.copy()) for s in gap)]
    assert all(np.isnan(s.values[1]) for s in gap)
    assert from_kept == from_copies and from_kept


def test_configuration_checks(tiny: Path, config: Calibration, tmp_path: Path) -> None:
    other = write_tiny(tmp_path / "other.inp", head=70.0)
    with pytest.raises(ConfigError, match=r"calibrated for network .*tiny\.inp"):
        BurstMonitor(other, config, capture_interval=0.2)
    with pytest.raises(ConfigError, match="no calibration for a 5 s capture interval"):
        BurstMonitor(tiny, config, capture_interval=5.0)
    with pytest.raises(ConfigError, match="localizer must be one of"):
        BurstMonitor(tiny, config, capture_interval=0.2, localizer="paper")
    with pytest.raises(ConfigError, match="meter model must be one of"):
        BurstMonitor(tiny, config, capture_interval=0.2, meter_model="peak")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="unknown detector"):
        BurstMonitor(tiny, config, capture_interval=0.2, detector="ewma")


def _write_csv(path: Path, steps: list[Step], meters: tuple[str, ...]) -> Path:
    lines = ["timestamp,meter,value"]
    lines += [f"{r.timestamp!r},{r.meter},{r.value!r}" for r in readings_of(steps, meters)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_cli_monitor_prints_one_json_line_per_burst(
    tiny: Path, config: Calibration, batch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    steps = _steps(batch.results["C"], batch.runs[0].spec)
    expected = batch.runs[0].attempts["C"][0]
    cfg = config.save(tmp_path / "tiny.json")
    csv = _write_csv(tmp_path / "feed.csv", steps, config.meters)
    argv = ["monitor", str(tiny), "--config", str(cfg), "--capture-interval", "0.2"]
    assert main([*argv, "--localizer", "arrival", "--readings", str(csv)]) == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    decisions = [r for r in records if r["type"] == "decision"]
    assert len(decisions) == 1 and {r["type"] for r in records} == {"decision", "health"}
    doc = decisions[0]
    assert doc["pipes"][0]["pipe"] == expected.predicted_pipe
    assert doc["time"] == pytest.approx(expected.decided_at)
    assert doc["meters"] == list(config.meters) and doc["excluded"] == []
    assert doc["health"]["type"] == "health"

    # bad lines are reported and skipped: the loop goes on
    bad = tmp_path / "bad.csv"
    bad.write_text("timestamp,meter,value\n0.0,J1,50.0\n0.0,J2\n0.0,nowhere,50.0\n")
    assert main([*argv, "--readings", str(bad)]) == 0
    err = capsys.readouterr().err
    assert "line 3: want 'timestamp,meter,value'" in err
    assert "unknown meter 'nowhere'" in err
    assert main([*argv, "--readings", str(tmp_path / "missing.csv")]) == 2
    assert "cannot read readings" in capsys.readouterr().err


#: What the live loop must never import: the simulator, the experiments, WNTR (and EPANET in it),
#: TSNet.
FORBIDDEN = ("burstloc.sim", "burstloc.experiments", "wntr", "tsnet")


def test_the_live_loop_does_not_import_the_simulator() -> None:
    code = (
        "import sys; import burstloc.live.monitor, burstloc.localize.decide, "
        "burstloc.localize.config, burstloc.localize.model; "
        "bad = sorted(m for m in sys.modules "
        f"if any(m == f or m.startswith(f + '.') for f in {FORBIDDEN!r})); "
        "assert not bad, bad; print('ok')"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_the_monitor_never_loads_the_network(
    tiny: Path, config: Calibration, batch, monkeypatch: pytest.MonkeyPatch
) -> None:
    import burstloc.network

    def boom(*args: object, **kwargs: object) -> None:
        raise AssertionError("the live loop loaded or solved the network")

    for name in ("load_network", "steady_state", "flow_direction_graph"):
        monkeypatch.setattr(burstloc.network, name, boom)
    spec = batch.runs[1].spec  # fused at 0.2 s
    monitor = BurstMonitor(tiny, config, capture_interval=0.2, localizer="fused")
    decided = list(monitor.run(_steps(batch.results["C"], spec)))
    assert decided and decided[0].pipe == batch.runs[1].attempts["C"][0].predicted_pipe


@pytest.fixture(scope="module")
def long_burst(tiny: Path):
    """A burst on pipe B that lasts past the signature's decision time (classification)."""
    from burstloc.sim.scenarios.scenario import BurstScenario
    from burstloc.sim.transient.tsnet import simulate_burst

    return simulate_burst(BurstScenario(tiny, "B", burst_start=2.0, duration=175.0))


def test_classified_decisions_are_bursts_or_events(tiny: Path, config: Calibration, long_burst):
    from burstloc.localize.classify import ClassifierConfig, Operation

    spec = RunSpec(DetectorConfig("cusum", 0.3), 2.0, 5, localizer="fused")
    loose = ClassifierConfig(max_residual=1.0, min_scale=0.0, rise_tolerance=0.05)
    steps = _steps(long_burst, spec)
    monitor = BurstMonitor(tiny, config, capture_interval=2.0, classify=loose)
    decisions = [d for d in monitor.run(steps) if not d.transient]
    assert decisions and decisions[0].is_burst
    doc = decisions[0].to_json()
    assert doc["type"] == "decision" and doc["burst"] is True
    assert doc["classification"]["class"] == "burst"
    assert (
        decisions[0].time >= decisions[0].first_alarm + config.for_interval(2.0).decision_delay - 2
    )

    # the same change mirrored: every head rises (as a pump start does): an event, not a burst
    base = steps[0].values
    mirrored = [Step(s.timestamp, 2 * base - s.values) for s in steps]
    monitor = BurstMonitor(tiny, config, capture_interval=2.0, classify=loose)
    events = [d for d in monitor.run(mirrored) if not d.transient]
    assert events and not events[0].is_burst
    doc = events[0].to_json()
    assert doc["type"] == "event" and doc["classification"]["class"] == "other"

    # declared: the burst at 2 s explained by an operation (a demand switched on)
    declared = [Operation("J3", 2.0, "demand on")]
    monitor = BurstMonitor(tiny, config, capture_interval=2.0, classify=loose, operations=declared)
    explained = [d for d in monitor.run(steps) if not d.transient]
    assert explained and explained[0].to_json()["classification"]["reason"].startswith("declared")


def test_a_classified_alarm_is_located_at_once_and_classified_later(
    tiny: Path, config: Calibration, long_burst
) -> None:
    """With a classifier the localizer's early answer is given at once as a transient record
    (here the arrival localizer's, which answers without waiting), the classification later."""
    from burstloc.localize.classify import ClassifierConfig

    spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival")
    loose = ClassifierConfig(max_residual=1.0, min_scale=0.0, rise_tolerance=0.05)
    steps = _steps(long_burst, spec)
    plain = list(BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival").run(steps))
    monitor = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival", classify=loose)
    records = list(monitor.run(steps))
    assert [r.transient for r in records[:2]] == [True, False]
    early, final = records[0], records[1]
    # the early record is the unclassified monitor's answer, at the same time
    assert plain and not plain[0].waited
    assert [r.pipe for r in early.ranking] == [r.pipe for r in plain[0].ranking]
    assert final.pipe == early.pipe  # the same alarms, the same arrival ranking
    assert early.time == plain[0].time < final.time
    arrival = monitor.localizers["arrival"]
    assert isinstance(arrival, ArrivalLocalizer)  # it answers by its looks' horizon at the latest
    assert early.time - early.first_alarm <= arrival_horizon(arrival, monitor.calibration) + 0.2
    assert not early.is_burst and final.is_burst
    doc = early.to_json()
    assert doc["type"] == "transient" and doc["burst"] is None and "classification" not in doc
    assert math.isclose(doc["classify_at"], final.time, abs_tol=0.2 + 1e-9)
    assert final.to_json()["type"] == "decision"
    # one early record per alarm, even over a restart in between
    from burstloc.live.monitor_state import monitor_state, restore_monitor

    # cut after the reading that gave the early record (the first at or after its look)
    cut = next(k for k, s in enumerate(steps) if s.timestamp >= early.time - 1e-9) + 1
    first = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival", classify=loose)
    before = list(first.run(steps[:cut]))
    again = BurstMonitor(tiny, config, capture_interval=0.2, localizer="arrival", classify=loose)
    restore_monitor(again, json.loads(json.dumps(monitor_state(first))))
    after = list(again.run(steps[cut:]))
    assert [r.transient for r in before] == [True]
    assert [r.transient for r in after[:1]] == [False] and after[0].time == final.time


def test_a_classified_decision_without_a_silent_meter(tiny: Path, config: Calibration, long_burst):
    from burstloc.localize.classify import ClassifierConfig

    spec = RunSpec(DetectorConfig("cusum", 0.3), 2.0, 5, localizer="fused")
    loose = ClassifierConfig(max_residual=1.0, min_scale=0.0, rise_tolerance=0.05)
    monitor = BurstMonitor(tiny, config, capture_interval=2.0, classify=loose)
    monitor.exclude("J4")
    records = list(monitor.run(_steps(long_burst, spec)))
    assert records[0].transient and records[0].meters == ("J1", "J2", "J3")  # the early answer
    decisions = [d for d in records if not d.transient]
    assert decisions and decisions[0].meters == ("J1", "J2", "J3")
    assert decisions[0].decision.classification is not None
    assert decisions[0].decision.classification.evidence["falling"] <= 3  # J4 left out


def test_the_fused_localizer_answers_early_at_a_coarse_interval(
    tiny: Path, config: Calibration, long_burst
) -> None:
    """At 2 s the arrivals cannot time the wave along the tiny network's pipes, so the fused
    localizer answers with the lasting drop; before it, at the arrival horizon, it gives an
    early record: the arrivals' search region, its centre as the named point (inside it), and
    when the answer is due."""
    from burstloc.localize.decide import arrival_horizon, fused_of

    spec = RunSpec(DetectorConfig("cusum", 0.3), 2.0, 5, localizer="fused")
    monitor = BurstMonitor(tiny, config, capture_interval=2.0)
    fused = fused_of(monitor.localizers)
    assert fused is not None and not fused.resolves(2.0)
    records = list(monitor.run(_steps(long_burst, spec)))
    assert [r.transient for r in records[:2]] == [True, False]
    early, final = records[0], records[1]
    horizon = arrival_horizon(fused.arrival, config.for_interval(2.0))
    assert early.time - early.first_alarm <= horizon + 2.0 + 1e-9  # seconds, not minutes
    assert final.time - final.first_alarm >= config.for_interval(2.0).decision_delay - 2.0
    region, at = early.decision.region, early.decision.position
    assert region is not None and at is not None
    assert at.pipe == early.pipe  # the named point's pipe leads the ranking
    assert region.contains(at.pipe, at.start, at.metres, at.length)
    doc = early.to_json()
    assert doc["type"] == "transient" and doc["answer_at"] == pytest.approx(final.time, abs=2.0)
    assert doc["region"]["length_m"] > 0 and doc["position"]["pipe"] == at.pipe
    # the wait it carries: from the burst's onset (before the first alarm) to the answer
    assert doc["wait_s"] == config.for_interval(2.0).decision_delay
    assert doc["answer_at"] - doc["wait_s"] <= doc["first_alarm"]
