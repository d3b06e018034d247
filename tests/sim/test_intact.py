"""burstloc.sim.transient.intact: what does not depend on the burst pipe is made once per process,
and a
burst simulated with it warm is bit for bit the burst of a fresh process (real TSNet runs)."""

from __future__ import annotations

import contextlib
import logging
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from burstloc import _diagnostics
from burstloc._diagnostics import capture_diagnostics, recording
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient import intact, tsnet_run
from burstloc.sim.transient.time_step import capture_time_step, expected_time_step
from burstloc.sim.transient.tsnet import simulate_burst
from conftest import write_tiny

#: Short bursts on transient-ready models (the evaluation's scenario, shorter).
SHORT = {"burst_start": 0.5, "duration": 3.0, "min_pipe_length": 30.0}


def comparable(result: ScenarioResult) -> dict[str, Any]:
    """A result's metadata without what differs between any two runs (the run's own time and
    its temporary directory's name)."""
    meta = {k: v for k, v in result.metadata.items() if k != "simulation_seconds"}
    return {k: re.sub(r"burstloc-tsnet-[^/\\]*", "TMP", repr(v)) for k, v in meta.items()}


def fresh(scenario: BurstScenario) -> ScenarioResult:
    """The burst simulated with nothing kept in the process."""
    intact.clear()
    return simulate_burst(scenario, cache=False)


@pytest.mark.parametrize("solver", ["vectorized", "tsnet"])
def test_a_burst_after_another_is_bit_for_bit_a_fresh_one(paper15: Path, solver: str) -> None:
    first = BurstScenario(paper15, "7", solver=solver, **SHORT)
    second = BurstScenario(paper15, "3", solver=solver, **SHORT)
    alone = fresh(second)
    fresh(first)  # the network, its steady state and transient-ready model now kept
    assert intact.intact(paper15).wn is intact.intact(paper15).wn
    warm = simulate_burst(second, cache=False)
    assert warm.heads.tobytes() == alone.heads.tobytes()
    assert warm.time.tobytes() == alone.time.tobytes()
    assert comparable(warm) == comparable(alone)
    again = simulate_burst(first, cache=False)  # and the first again, all of it kept
    assert again.heads.tobytes() == fresh(first).heads.tobytes()


def test_an_edited_file_is_read_afresh(tmp_path: Path) -> None:
    path = write_tiny(tmp_path / "tiny.inp", head=60.0)
    scenario = BurstScenario(path, "C", burst_start=0.5, duration=3.0)
    intact.clear()
    before = simulate_burst(scenario, cache=False)
    write_tiny(path, head=70.0)  # same path, new content
    after = simulate_burst(scenario, cache=False)
    assert not np.array_equal(after.heads, before.heads)
    assert after.heads.tobytes() == fresh(scenario).heads.tobytes()


def test_networks_kept_are_the_last_few(tmp_path: Path, paper15: Path) -> None:
    intact.clear()
    paths = [write_tiny(tmp_path / f"tiny{i}.inp", head=60.0 + i) for i in range(3)]
    kept = [intact.intact(p) for p in paths]
    assert intact.intact(paths[-1]) is kept[-1]
    assert intact.intact(paths[0]) is not kept[0]  # dropped: more than NETWORKS since
    assert len(intact._KEPT) == intact.NETWORKS


def test_the_capture_rule_is_the_expected_steps(paper15: Path) -> None:
    """capture_time_step sees TSNet's step below an interval without preparing the model, as
    expected_time_step, which prepares it, would decide."""
    for pipe in ("1", "7", "12"):
        scenario = BurstScenario(paper15, pipe, min_pipe_length=30.0)
        expected = expected_time_step(scenario)
        for interval in (expected / 2, expected, expected * 1.001, expected * 3, 1.0):
            rule = None if expected <= interval else interval / 2
            assert capture_time_step(scenario, interval) == rule, (pipe, interval)


def _noisy() -> None:
    """Print, log, warn, and run a capture block that does the same inside."""
    print("outside")
    logging.getLogger("wntr").warning("logged outside")
    warnings.warn("warned outside", UserWarning, stacklevel=1)
    with capture_diagnostics():
        print("inside")
        logging.getLogger("wntr").warning("logged inside")
        warnings.warn("warned inside", UserWarning, stacklevel=1)


def test_a_replayed_recording_is_what_the_block_gave() -> None:
    with capture_diagnostics() as direct:
        print("before")
        _noisy()
        print("after")
    with capture_diagnostics() as recorded:
        print("before")
        with recording():
            _noisy()
        print("after")
    with pytest.warns(UserWarning, match="warned outside"), recording() as record:
        _noisy()  # no capture block: it reaches the terminal, as without the recording
    with capture_diagnostics() as replayed:
        print("before")
        record.replay()
        print("after")
    assert direct.messages == recorded.messages == replayed.messages
    assert direct.warnings == recorded.warnings == replayed.warnings
    assert direct.messages.count("wntr WARNING: logged inside") == 2  # both blocks log it
    assert not _diagnostics._RECORDING


@pytest.mark.parametrize("solver", ["vectorized", "tsnet"])
def test_the_initializer_reads_by_name_the_numbers_pandas_gives(
    paper15: Path, solver: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    scenario = BurstScenario(paper15, "7", solver=solver, **SHORT)
    by_name = simulate_burst(scenario, cache=False)
    monkeypatch.setattr(tsnet_run, "results_by_name", contextlib.nullcontext)
    through_pandas = simulate_burst(scenario, cache=False)
    assert by_name.heads.tobytes() == through_pandas.heads.tobytes()
    assert comparable(by_name) == comparable(through_pandas)
