"""The search regions' timing error fitted on real simulations of the paper's network, so that
their stated probability holds on those bursts; stored per capture interval and used by every
search region built at it."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest

from burstloc.exceptions import ConfigError
from burstloc.experiments import paper
from burstloc.experiments.calibrate import calibrate
from burstloc.experiments.front_speed import FrontBurst, simulate_front_bursts
from burstloc.experiments.region_spread import (
    FACTORS,
    _look,
    allowed_misses,
    choose_factor,
    fit_timing_factors,
    with_timing_factors,
)
from burstloc.live.monitor import BurstMonitor
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.config import Calibration
from burstloc.localize.decide import RankingLocalizers
from burstloc.localize.region import posterior
from burstloc.network import Network, read_network


@pytest.fixture(scope="module")
def network(paper15: Path) -> Network:
    return read_network(paper15)


@pytest.fixture(scope="module")
def config(network: Network) -> Calibration:
    # four meters: the regions must place bursts between them, as a utility's few meters do
    return calibrate(
        network, capture_intervals=[0.2], noise_sigma=0.01, meters=["N4", "N8", "2", "7"]
    )


def _bursts(network: Network, config: Calibration, speed: float) -> dict[float, list[FrontBurst]]:
    scenario = replace(paper.SCENARIO, wave_speed=speed)  # the model assumes 1 200 m/s
    return simulate_front_bursts(network, config, bursts=10, seed=3, scenario=scenario, workers=1)


@pytest.fixture(scope="module")
def exact(network: Network, config: Calibration) -> dict[float, list[FrontBurst]]:
    return _bursts(network, config, 1200.0)


@pytest.fixture(scope="module")
def slow(network: Network, config: Calibration) -> dict[float, list[FrontBurst]]:
    return _bursts(network, config, 900.0)


def test_the_factor_widens_only_where_the_bursts_show_overconfidence() -> None:
    assert [allowed_misses(n, 0.95) for n in (0, 10, 24, 96, 200)] == [0, 1, 3, 8, 14]
    assert allowed_misses(10, 0.5) > allowed_misses(10, 0.8) > allowed_misses(10, 0.95)
    held = [1.0] * 21
    # 24 bursts, 3 outside at x1: chance for 95 % regions, left as stated
    assert choose_factor([*held, 1.3, 2.0, math.inf], 0.95) == 1.0
    # 4 outside: overconfident; the smallest factor leaving 3 outside
    assert choose_factor([*held[:20], 1.3, 1.3, 2.0, 2.5], 0.95) == 1.3
    assert choose_factor([*held[:18], 1.3, 1.3, 2.0, 2.5, 4.0, 4.0], 0.95) == 2.0
    # none holds enough: the largest
    assert choose_factor([math.inf] * 10, 0.95) == FACTORS[-1]
    assert choose_factor([], 0.95) == 1.0


def test_the_fit_on_simulated_bursts_follows_its_rule(
    config: Calibration, exact: dict[float, list[FrontBurst]], slow: dict[float, list[FrontBurst]]
) -> None:
    for bursts in (exact, slow):
        (fit,) = fit_timing_factors(config, bursts)
        assert fit.capture_interval == 0.2 and fit.bursts == 10 and fit.placed >= 8
        assert fit.factor == choose_factor(fit.needed, 0.95)
        assert all(n >= 1.0 for n in fit.needed)
        allowed = allowed_misses(fit.placed, 0.95)
        assert fit.placed - fit.held(fit.factor) <= allowed or fit.factor == FACTORS[-1]
    # each burst's factor is the smallest whose region holds it: at 50 % more need widening
    (half,) = fit_timing_factors(config, slow, confidence=0.5)
    (full,) = fit_timing_factors(config, slow)
    assert sum(n > 1.0 for n in half.needed) >= sum(n > 1.0 for n in full.needed)


def test_a_wider_timing_error_widens_the_region(
    config: Calibration, slow: dict[float, list[FrontBurst]]
) -> None:
    localizers = RankingLocalizers.from_model(config.model_at(0.2))
    burst = slow[0.2][0]
    evidence = _look(localizers, config.meters, burst, config.for_interval(0.2))
    assert evidence is not None
    lengths = [
        posterior(localizers.arrival, evidence, timing_factor=f).region().length
        for f in (1.0, 2.0, 5.0)
    ]
    assert lengths[0] <= lengths[1] <= lengths[2] and lengths[0] < lengths[2]


def test_the_factor_is_stored_used_and_checked(
    network: Network,
    config: Calibration,
    slow: dict[float, list[FrontBurst]],
    tmp_path: Path,
) -> None:
    (fit,) = fit_timing_factors(config, slow)
    fits = [replace(fit, factor=1.6)]  # as a network that needs it would fit
    fitted = with_timing_factors(config, fits)
    factor = 1.6
    assert fitted.provenance["region_timing"]["0.2"]["held"] == fits[0].held(factor)
    loaded = Calibration.load(fitted.save(tmp_path / "c.json"))
    assert loaded.for_interval(0.2).timing_factor == factor
    assert loaded.model_at(0.2).timing_factor == factor
    assert loaded.model.timing_factor == 1.0  # per interval, not the stored model's
    monitor = BurstMonitor(network, loaded, capture_interval=0.2)
    arrival = monitor.localizers["arrival"]
    assert isinstance(arrival, ArrivalLocalizer) and arrival.timing_factor == factor
    assert any(f"regions' timing error x{factor:.2f}" in line for line in loaded.summary())
    data = json.loads((tmp_path / "c.json").read_text(encoding="utf-8"))
    del data["intervals"][0]["region_timing_factor"]  # a file written before the fit existed
    (tmp_path / "old.json").write_text(json.dumps(data), encoding="utf-8")
    old = Calibration.load(tmp_path / "old.json")
    assert old.for_interval(0.2).timing_factor == 1.0 and old.model_at(0.2) is old.model
    data["intervals"][0]["region_timing_factor"] = 0.5
    (tmp_path / "bad.json").write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ConfigError, match=r"intervals\[0\]\.region_timing_factor"):
        Calibration.load(tmp_path / "bad.json")
    with pytest.raises(ConfigError, match="timing_factor must be >= 1"):
        ArrivalLocalizer(
            config.model.pipes, config.meters, config.model.node_distances, timing_factor=0.9
        )
