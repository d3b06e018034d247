"""A scenario's ``recorded`` junctions: the result holds their heads only, the same to the bit
as the whole network's columns, in its own array (the solver's matrix is let go), with the
negative pressure the solver found anywhere; bad names are refused before anything runs."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst
from conftest import write_tiny


def burst(tmp_path: Path) -> BurstScenario:
    """A burst opening at once, large enough to draw the burst point below zero."""
    network = write_tiny(tmp_path / "tiny.inp", head=40.0)
    return BurstScenario(
        network, "E", burst_start=0.5, duration=3.0, burst_coeff=30.0, opening_time=0.0
    )


def test_the_recorded_junctions_are_the_whole_networks_columns(tmp_path: Path) -> None:
    scenario = burst(tmp_path)
    whole = simulate_burst(scenario, cache=False)
    some = simulate_burst(replace(scenario, recorded=("J4", "J1")), cache=False)
    assert whole.junctions == ["J1", "J2", "J3", "J4"]
    assert some.junctions == ["J4", "J1"]
    assert np.ptp(some.heads) > 1.0  # a transient, not a constant
    np.testing.assert_array_equal(some.heads, whole.heads[:, [3, 0]])
    np.testing.assert_array_equal(some.time, whole.time)
    assert some.heads.base is None  # not a view keeping the solver's matrix alive
    assert whole.heads.base is not None  # (the whole network's is one: no copy of it)
    # negative pressure is found where it was, at a node neither records (the burst point)
    assert whole.metadata["negative_pressure_nodes"] == ["E_B"]
    assert some.metadata["negative_pressure_nodes"] == ["E_B"]
    assert some.metadata["recorded"] == ["J4", "J1"]
    assert "recorded" not in whole.metadata


def test_recorded_is_part_of_the_cache_key_and_absent_by_default(tmp_path: Path) -> None:
    scenario = burst(tmp_path)
    assert "recorded" not in scenario.parameters()  # earlier caches keep their keys
    some = replace(scenario, recorded=["J2"])
    assert some.recorded == ("J2",)
    assert some.parameters()["recorded"] == ["J2"]
    keys = {scenario.cache_key(), some.cache_key(), replace(scenario, recorded=("J3",)).cache_key()}
    assert len(keys) == 3


@pytest.mark.parametrize(
    ("recorded", "message"),
    [
        ((), "recorded must be a non-empty list of junction names, got ()"),
        ("J1", "recorded must be a non-empty list of junction names, got 'J1'"),
        (("J1", ""), "recorded must name junctions by non-empty strings, got ''"),
        (("J1", 3), "recorded must name junctions by non-empty strings, got 3"),
        (("J2", "J1", "J2"), "recorded names junction\\(s\\) more than once: J2"),
    ],
)
def test_bad_recorded_junctions_are_refused(tmp_path: Path, recorded: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        replace(burst(tmp_path), recorded=recorded)


def test_a_recorded_node_that_is_not_a_junction_is_named(tmp_path: Path) -> None:
    scenario = replace(burst(tmp_path), recorded=("J1", "R1", "X9"))
    with pytest.raises(NetworkError, match=r"2 node\(s\) that are not junctions of .*: R1, X9"):
        simulate_burst(scenario, cache=False)
