"""burstloc.river: the detectors speak River's drift-detector protocol and pass River's checks."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
from river.checks import common
from river.drift import PageHinkley

import burstloc
from burstloc import ConfigError
from burstloc.river import (
    DATASETS,
    Cusum,
    Shewhart,
    compare_on_change_point_datasets,
    detections,
    score_detections,
)

#: River's own checks that apply to a drift detector: the others need a learning dataset, and
#: ``check_tags`` needs ``Estimator._tags``, which River's own drift detectors do not have.
RIVER_CHECKS = [
    common.check_repr,
    common.check_str,
    common.check_clone_same_class,
    common.check_clone_is_idempotent,
    common.check_init_has_default_params_for_tests,
    common.check_init_default_params_are_not_mutable,
    common.check_doc,
    common.check_clone_changes_memory_addresses,
    common.check_mutate_can_be_idempotent,
]

DETECTORS = [Cusum(), Cusum(threshold=0.3, drift=0.01), Shewhart(), Shewhart(20, 0.2, 3.0)]


@pytest.mark.parametrize("check", RIVER_CHECKS, ids=lambda c: c.__name__)
@pytest.mark.parametrize("detector", DETECTORS, ids=repr)
def test_river_checks(check, detector) -> None:
    check(detector)


def _heads(seed: int, n: int = 3_000) -> np.ndarray:
    rng = np.random.default_rng(seed)
    x = 200.0 + rng.normal(0.0, 0.05, n)
    x[n // 2 :] -= 1.0
    x[2 * n // 3 :] += 0.6
    return x


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_detections_are_the_core_alarms(seed: int) -> None:
    x = _heads(seed)
    pairs = [
        (Cusum(threshold=0.3, drift=0.01), burstloc.Cusum(0.3, 0.01)),
        (Shewhart(window=30, threshold=0.2, sigma=3.0), burstloc.Shewhart(30, 0.2, 3.0)),
    ]
    for adapter, core in pairs:
        expected = core.update_many(x)
        found = detections(adapter, x.tolist())
        assert found == [a.index for a in expected]
        assert found, "the trace's two steps are detected"
        assert adapter.last_alarm == expected[-1]


def test_reset_and_clone_start_afresh_and_clone_with_attributes_carries_on() -> None:
    x = _heads(7).tolist()
    for make in (lambda: Cusum(0.3, 0.01), lambda: Shewhart(30, 0.2, 3.0)):
        det = make()
        first = detections(det, x[:2_000])
        twin = det.clone(include_attributes=True)
        rest = detections(det, x[2_000:])
        assert detections(twin, x[2_000:]) == rest
        det._reset()
        assert not det.drift_detected and det.last_alarm is None
        assert detections(det, x[:2_000]) == first
        assert detections(det.clone(), x[:2_000]) == first


def test_repr_follows_river() -> None:
    # River's layout: the class name, then one parameter per line.
    assert repr(PageHinkley()).startswith("PageHinkley (\n  min_instances=30\n")
    assert repr(Cusum(threshold=0.3)) == "Cusum (\n  threshold=0.3\n  drift=0.\n)"
    assert repr(Shewhart()) == "Shewhart (\n  window=50\n  threshold=0.5\n  sigma=None\n)"


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Cusum(threshold=-1.0), "threshold"),
        (lambda: Cusum(drift=-1.0), "drift"),
        (lambda: Shewhart(window=1), "window"),
        (lambda: Shewhart(threshold=0.0), "threshold"),
    ],
)
def test_bad_parameters_are_config_errors(make, name: str) -> None:
    with pytest.raises(ConfigError, match=name):
        make()


def test_score_detections() -> None:
    # 8 -> first detection 10 (delay 2); 100 -> none within 5; 50 matches nothing.
    assert score_detections([10, 12, 50], [8, 100], margin=5) == (1, 2.0, 1)
    detected, delay, false_alarms = score_detections([], [8], margin=5)
    assert (detected, false_alarms) == (0, 0) and math.isnan(delay)


def test_comparison_covers_every_shipped_dataset_and_detector() -> None:
    rows = compare_on_change_point_datasets()
    assert {r.dataset for r in rows} == set(DATASETS)
    assert len({r.detector for r in rows}) == 3
    for r in rows:
        assert 0 <= r.detected <= r.change_points
        assert 0 <= r.false_alarms <= r.detections
        assert math.isnan(r.mean_delay) == (r.detected == 0)
    # Each detector finds some annotated change somewhere.
    for detector in {r.detector for r in rows}:
        assert sum(r.detected for r in rows if r.detector == detector) > 0


def test_burstloc_imports_without_river() -> None:
    code = (
        "import sys; sys.modules['river'] = None\n"
        "import burstloc\n"
        "try:\n    import burstloc.river\nexcept ImportError as e:\n    print(e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert "pip install 'burstloc[river]'" in out.stdout


def test_docstring_examples_run() -> None:
    import doctest

    import burstloc.river

    result = doctest.testmod(burstloc.river)
    assert result.attempted > 0 and result.failed == 0
