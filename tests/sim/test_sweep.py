"""burstloc.sim.scenarios.sweep: map a function over items serially, in processes, or on Dask."""

from __future__ import annotations

import math
import operator
import weakref
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError
from burstloc.sim.scenarios import sweep as sweep_mod
from burstloc.sim.scenarios.sweep import sweep

# math.sqrt fails on negative numbers: a picklable function with a natural per-item failure.
ITEMS = [4.0, -1.0, 9.0, 16.0, -4.0, 25.0]


def _check(report, labelled: bool = False) -> None:  # type: ignore[no-untyped-def]
    assert report.items == ITEMS
    assert report.results == [2.0, None, 3.0, 4.0, None, 5.0]
    assert [f.index for f in report.failures] == [1, 4]
    assert [f.item for f in report.failures] == [-1.0, -4.0]
    assert all(f.error_type == "ValueError" for f in report.failures)
    assert all("math domain error" in f.message for f in report.failures)
    assert all("ValueError" in f.traceback for f in report.failures)
    assert not report.ok
    assert report.succeeded() == [(4.0, 2.0), (9.0, 3.0), (16.0, 4.0), (25.0, 5.0)]
    if labelled:
        assert str(report.failures[0]) == "x=-1.0: ValueError: math domain error"


@pytest.mark.parametrize("workers", [1, 2])
def test_failures_are_reported_and_the_rest_complete(workers: int) -> None:
    seen: list[tuple[int, float, float]] = []
    report = sweep(
        math.sqrt,
        ITEMS,
        workers=workers,
        progress=False,
        label=lambda x: f"x={x}",
        on_result=lambda i, item, result: seen.append((i, item, result)),
    )
    _check(report, labelled=True)
    assert sorted(seen) == [(0, 4.0, 2.0), (2, 9.0, 3.0), (3, 16.0, 4.0), (5, 25.0, 5.0)]


@pytest.mark.parametrize("workers", [1, 2])
def test_results_not_kept_are_let_go_once_handed_over(workers: int) -> None:
    """With keep=False each result lives only as long as ``on_result`` keeps it (a sweep of
    large results holds one at a time; worker processes' futures held every one before)."""
    handed: list[weakref.ref[np.ndarray]] = []
    alive_before: list[int] = []

    def on_result(i: int, item: int, result: np.ndarray) -> None:
        alive_before.append(sum(ref() is not None for ref in handed))
        handed.append(weakref.ref(result))

    report = sweep(np.zeros, [10, 20, 30, 40, 50], workers=workers, progress=False,
                   on_result=on_result, keep=False)  # fmt: skip
    assert report.results == [None] * 5 and report.ok
    assert alive_before == [0] * 5


def test_empty_and_single_item_sweeps() -> None:
    empty = sweep(math.sqrt, [], progress=False)
    assert empty.ok and empty.results == [] and empty.items == []
    single = sweep(operator.neg, [3], workers=4, progress=False)
    assert single.ok and single.results == [-3]


def test_progress_bar_counts_every_item(capsys: pytest.CaptureFixture[str]) -> None:
    sweep(math.sqrt, ITEMS, workers=1, progress=True, desc="roots")
    err = capsys.readouterr().err
    assert "roots" in err and "6/6" in err


@pytest.mark.parametrize("workers", [0, -1, 1.5, "2"])
def test_bad_worker_count(workers: object) -> None:
    with pytest.raises(ConfigError, match="workers"):
        sweep(math.sqrt, ITEMS, workers=workers, progress=False)  # type: ignore[arg-type]


def test_dask_local_cluster_runs_items_and_reports_failures(dask_scheduler: str) -> None:
    _check(sweep(math.sqrt, ITEMS, scheduler=dask_scheduler, progress=False))


def test_unreachable_scheduler_is_a_config_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sweep_mod, "DASK_CONNECT_TIMEOUT", 1.0)
    with pytest.raises(ConfigError, match=r"tcp://127\.0\.0\.1:9"):
        sweep(math.sqrt, ITEMS, scheduler="tcp://127.0.0.1:9", progress=False)


def test_the_same_failure_of_many_items_is_one_line() -> None:
    # A network that cannot be simulated fails every pipe with the same error: said once, with
    # how many items and which; a different error keeps its own line.
    items = [-1.0, -2.0, -3.0, -4.0, -5.0, -6.0, -7.0, 4.0, "x"]
    report = sweep(math.sqrt, items, workers=1, progress=False, label=lambda x: f"x={x}")
    lines = report.failure_lines()
    assert lines == [
        "7 of 9 (x=-1.0, x=-2.0, x=-3.0, x=-4.0, x=-5.0 and 2 more): ValueError: math domain error",
        "x=x: TypeError: must be real number, not str",
    ]


def test_workers_run_ahead_of_the_results_taken_by_one_item_each(tmp_path: Path) -> None:
    """An item starts only once submitted: at most one per worker, and QUEUED more, beyond the
    results already handed over (a slow parent does not hold every result made meanwhile)."""
    files = [tmp_path / f"item{i}" for i in range(12)]
    taken: list[int] = []

    def on_result(i: int, item: Path, result: None) -> None:
        taken.append(i)
        started = sum(f.exists() for f in files)  # each item creates its file
        assert started <= 2 + sweep_mod.QUEUED + len(taken) - 1

    report = sweep(Path.touch, files, workers=2, progress=False, on_result=on_result)
    assert report.ok and sorted(taken) == list(range(12))
