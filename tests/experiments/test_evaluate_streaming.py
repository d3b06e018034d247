"""``evaluate(..., keep_heads=False)`` scores each burst as its simulation arrives and keeps only
its first time step: the same evaluation (every run's JSON) as holding every burst's heads, for
the paper's rules and a ranking localizer (both meter models, two clock phases, several pipes),
from fresh simulations and from the cache. With meters and no run of the paper's rules, the
simulations record the meters' heads only, and the evaluation is again the same."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from burstloc.experiments import paper
from burstloc.experiments.evaluate import evaluate
from burstloc.experiments.runs import RunSpec
from burstloc.localize.detection import DetectorConfig, Mode
from burstloc.sim.scenarios.cache import DiskCache

SHORT = paper.ScenarioConfig(burst_start=2.0)
RUNS = [
    RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, Mode.WINDOW, "S_C1"),
    RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival"),
    RunSpec(
        DetectorConfig("shewhart", 1.5),
        0.2,
        5,
        localizer="fused",
        meter_model="interval-averaged",
    ),
]


def options(config: Any, **more: Any) -> dict[str, Any]:
    """What these evaluations share: three pipes, two phases, nothing cached; and ``more``."""
    shared = {"pipes": ["B", "C", "A"], "phases": 2, "scenario": SHORT, "config": config}
    return {**shared, "cache": False, "progress": False, **more}


def run(tiny: Path, config: Any, cache: Any, keep_heads: bool) -> Any:
    return evaluate(
        tiny,
        RUNS,
        pipes=["B", "C", "A"],
        phases=2,
        scenario=SHORT,
        config=config,
        cache=cache,
        workers=1,
        progress=False,
        keep_heads=keep_heads,
    )


@pytest.mark.parametrize("cached", [False, True], ids=["simulated", "from the cache"])
def test_streaming_gives_the_same_evaluation(
    tiny: Path, tiny_config: Any, tmp_path: Path, cached: bool
) -> None:
    cache: Any = DiskCache(tmp_path / "cache") if cached else False
    held = run(tiny, tiny_config, cache, keep_heads=True)
    streamed = run(tiny, tiny_config, cache, keep_heads=False)
    assert streamed.to_json() == held.to_json()
    assert [r.total for r in streamed.runs] == [3, 3, 3]
    for pipe, result in streamed.results.items():
        assert result.heads.shape == (1, len(held.results[pipe].junctions))
        assert result.heads.flags.owndata and result.time.flags.owndata  # not views of all
        assert (result.heads[0] == held.results[pipe].heads[0]).all()
        timing = ("cache", "simulation_seconds")  # how each run went, not what it produced
        same = {k: v for k, v in held.results[pipe].metadata.items() if k not in timing}
        assert {k: v for k, v in result.metadata.items() if k not in timing} == same


def test_with_meters_only_their_heads_are_simulated_and_scored_the_same(tiny: Path) -> None:
    from burstloc.experiments.calibrate import calibrate

    meters = ["J4", "J2", "J3"]
    config = calibrate(tiny, capture_intervals=(0.2,), noise_sigma=0.01, meters=meters)
    kwargs = options(config, workers=1, meters=meters)
    ranked = RUNS[1:]  # the paper's rules read every junction
    held = evaluate(tiny, ranked, keep_heads=True, **kwargs)
    streamed = evaluate(tiny, ranked, keep_heads=False, **kwargs)
    assert streamed.to_json() == held.to_json()
    for pipe, result in streamed.results.items():
        assert held.results[pipe].junctions == ["J1", "J2", "J3", "J4"]
        assert result.junctions == ["J4", "J2", "J3"]
        assert result.metadata["recorded"] == ["J4", "J2", "J3"]
        assert (result.heads[0] == held.results[pipe].heads[0, [3, 1, 2]]).all()
    # with the paper's rules every junction is simulated
    both = evaluate(tiny, RUNS, keep_heads=False, **kwargs)
    assert all(len(r.junctions) == 4 for r in both.results.values())


def test_a_dask_cluster_gives_the_same_evaluation_as_local_processes(
    tiny: Path, tiny_config: Any, dask_scheduler: str
) -> None:
    # each burst simulated on the cluster's workers, scored here as it arrives
    kwargs = options(tiny_config, keep_heads=False)
    local = evaluate(tiny, RUNS, workers=2, **kwargs)
    cluster = evaluate(tiny, RUNS, scheduler=dask_scheduler, **kwargs)
    assert cluster.to_json() == local.to_json()
    assert [r.total for r in cluster.runs] == [3, 3, 3]
    assert sorted(cluster.results) == ["A", "B", "C"]


def test_a_compact_attempt_keeps_the_best_pipes_and_refuses_deeper_questions(
    tiny: Path, tiny_config: Any
) -> None:
    from burstloc.exceptions import InputError

    held = run(tiny, tiny_config, False, keep_heads=True)
    ranked = [a for r in held.runs[1:] for tries in r.attempts.values() for a in tries]
    ranked = [a for a in ranked if a.ranking is not None and len(a.ranking) > 2]
    assert ranked
    for attempt in ranked:
        small = attempt.compact(2)
        assert small.ranking is not None and len(small.ranking) == 2
        assert [p.pipe for p in small.ranking] == [p.pipe for p in attempt.ranking.top(2)]
        assert (small.in_top(1), small.in_top(2)) == (attempt.in_top(1), attempt.in_top(2))
        assert small.decision is not None and attempt.decision is not None
        assert small.decision.posterior is attempt.decision.posterior  # regions still scored
        assert len(small.early) == len(attempt.early)
        with pytest.raises(InputError, match="kept its 2 best pipes, not 3"):
            small.in_top(3)
