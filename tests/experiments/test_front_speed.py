"""The speed at which the meters hear bursts' fronts, fitted on real simulations of the paper's
network, stored per capture interval and used by whatever builds the arrival localizer."""

from __future__ import annotations

import json
import re
from dataclasses import replace
from pathlib import Path

import pytest

from burstloc.cli import main
from burstloc.exceptions import ConfigError
from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.front_speed import simulate_front_bursts, speeds_of, with_front_speeds
from burstloc.experiments.ranking import RankingSetup
from burstloc.live.monitor import BurstMonitor
from burstloc.localize.config import Calibration
from burstloc.network import Network, read_network


@pytest.fixture(scope="module")
def network(paper15: Path) -> Network:
    return read_network(paper15)


@pytest.fixture(scope="module")
def config(network: Network) -> Calibration:
    return calibrate(network, capture_intervals=[0.01, 0.2], noise_sigma=0.01)


@pytest.mark.parametrize(("truth", "low", "high"), [(1200.0, 1120.0, 1300.0), (1000, 930, 1080)])
def test_the_fit_finds_the_speed_the_bursts_travel_at(
    network: Network, config: Calibration, truth: float, low: float, high: float
) -> None:
    scenario = replace(paper.SCENARIO, wave_speed=truth)  # the model assumes 1 200 m/s
    heard = simulate_front_bursts(network, config, bursts=6, seed=1, scenario=scenario, workers=1)
    fits = speeds_of(config, heard)
    assert [f.capture_interval for f in fits] == [0.01, 0.2]
    for f in fits:
        assert f.bursts == 6 and f.heard == 6 and f.fit.arrivals >= 60
        assert low <= f.fit.wave_speed <= high, (f.capture_interval, f.fit.wave_speed)
        assert f.factor(1200.0) == pytest.approx(min(1.0, f.fit.wave_speed / 1200.0))
    fitted = with_front_speeds(config, fits)
    for f, item in zip(fits, fitted.intervals, strict=True):
        assert item.front_factor == pytest.approx(min(1.0, f.fit.wave_speed / 1200.0))
        assert fitted.model_at(f.capture_interval).wave_speed == pytest.approx(
            1200.0 * item.front_factor
        )
    assert fitted.provenance["front_speeds"]["0.2"]["bursts"] == 6
    assert fitted.model is config.model  # the model keeps the wave's own speed


def test_a_fit_faster_than_the_wave_leaves_the_wave_speed(network: Network) -> None:
    # two meters far apart: one difference of arrivals per burst, which the paths' shapes decide
    two = calibrate(network, capture_intervals=[0.2], noise_sigma=0.01, meters=["1", "8"])
    (fit,) = speeds_of(two, simulate_front_bursts(network, two, bursts=8, seed=1, workers=1))
    assert fit.fit.wave_speed > 1200.0 and fit.factor(1200.0) == 1.0
    fitted = with_front_speeds(two, [fit])
    assert fitted.intervals[0].front_factor == 1.0
    assert fitted.model_at(0.2).wave_speed == 1200.0


def test_too_few_bursts_are_refused(network: Network, config: Calibration) -> None:
    with pytest.raises(ConfigError, match="at least 2 simulated bursts"):
        simulate_front_bursts(network, config, bursts=1)


def _slower(config: Calibration, factor: float) -> Calibration:
    intervals = tuple(replace(item, front_factor=factor) for item in config.intervals)
    return replace(config, intervals=intervals)


def test_the_factor_is_stored_and_an_older_file_reads_as_the_wave_speed(
    config: Calibration, tmp_path: Path
) -> None:
    slower = _slower(config, 0.85)
    loaded = Calibration.load(slower.save(tmp_path / "c.json"))
    assert [i.front_factor for i in loaded.intervals] == [0.85, 0.85]
    assert loaded.model_at(0.2).wave_speed == pytest.approx(0.85 * config.model.wave_speed)
    assert loaded.model_at(0.2).wave_speed_tolerance == config.model.wave_speed_tolerance
    assert any("fronts heard at 1020 m/s" in line for line in loaded.summary())
    data = json.loads((tmp_path / "c.json").read_text(encoding="utf-8"))
    for item in data["intervals"]:
        del item["front_speed_factor"]
    (tmp_path / "old.json").write_text(json.dumps(data), encoding="utf-8")
    old = Calibration.load(tmp_path / "old.json")
    assert all(i.front_factor == 1.0 for i in old.intervals)
    assert old.model_at(0.2) is old.model
    data["intervals"][1]["front_speed_factor"] = 7
    (tmp_path / "bad.json").write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ConfigError, match=r"intervals\[1\]\.front_speed_factor"):
        Calibration.load(tmp_path / "bad.json")


def test_the_monitor_and_the_evaluation_time_paths_at_the_fronts_speed(
    network: Network, config: Calibration
) -> None:
    slower = _slower(config, 0.85)
    speed = 0.85 * config.model.wave_speed
    monitor = BurstMonitor(network, slower, capture_interval=0.2)
    assert monitor.localizers["arrival"].wave_speed == pytest.approx(speed)  # type: ignore[attr-defined]
    setup = RankingSetup.build(network, list(slower.meters), [0.2], slower)
    assert setup.localizers_at(0.2).arrival.wave_speed == pytest.approx(speed)
    assert setup.localizers_at(0.2) is setup.localizers_at(0.2)  # built once
    plain = RankingSetup.build(network, list(config.meters), [0.2], config)
    assert plain.localizers_at(0.2) is plain.localizers


def test_calibrate_fits_the_fronts_and_known_events_still_find_the_wave(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "c.json"
    args = ["calibrate", str(paper15), "--out", str(out), "--capture-interval", "0.2"]
    assert main([*args, "--front-bursts", "4", "--front-seed", "2", "--workers", "1"]) == 0
    said = capsys.readouterr().out
    found = re.search(r"fronts at 0.2 s: heard at (\d+) m/s \(([\d.]+) x 1200 m/s\)", said)
    assert found is not None, said
    config = Calibration.load(out)
    assert config.for_interval(0.2).front_factor == pytest.approx(float(found.group(2)), abs=1e-3)
    assert config.provenance["front_speeds"]["0.2"]["bursts"] == 4
    assert "fronts heard at" in said
    # the regions' timing error fitted on the same bursts, printed and stored
    spread = re.search(r"regions at 0.2 s: timing error x([\d.]+), the 95% regions holding", said)
    assert spread is not None, said
    assert config.for_interval(0.2).timing_factor == float(spread.group(1))
    assert config.provenance["region_timing"]["0.2"]["bursts"] == 4
    assert main([*args, "--front-bursts", "1"]) == 2
    assert "at least 2 simulated bursts" in capsys.readouterr().err
