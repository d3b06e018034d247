"""burstloc.localize.classify: burst, other event or unsure, from synthetic lasting changes."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.classify import (
    ClassifierConfig,
    EventClassifier,
    Operation,
    read_operations,
)
from burstloc.localize.evidence import BurstEvidence, MeterAlarm
from burstloc.localize.signature import SignatureLocalizer, SignatureSet

METERS = ("A", "B", "C", "D")
SIGNATURES = SignatureSet(
    network_hash="sha256:" + "0" * 64,
    meters=METERS,
    pipes=("p", "q"),
    endpoints={"p": ("A", "B"), "q": ("C", "D")},
    matrix=np.array([[4.0, 3.0, 1.0, 0.5], [0.5, 1.0, 3.0, 4.0]]),
    baseline=np.full(4, 50.0),
    params={},
)
CONFIG = ClassifierConfig(
    max_residual=0.2, min_scale=0.25, rise_tolerance=0.05, asset_nodes={"D": "PU1"}
)


def evidence(change: np.ndarray, first: str = "A") -> BurstEvidence:
    """Readings that step by ``-change`` (a drop is positive) at t = 10 s, seen until 160 s."""
    times = np.arange(0.0, 161.0)
    readings = np.tile(50.0, (times.size, 4))
    readings[times > 10] -= change
    alarms = {m: MeterAlarm(m, 10.0 if m == first else 11.0, -1.0) for m in METERS}
    return BurstEvidence(METERS, times, readings, onset=10.0, capture_interval=1.0, alarms=alarms)


def classify(change: list[float], *, first: str = "A", ops: list[Operation] | None = None) -> str:
    classifier = EventClassifier(CONFIG, SignatureLocalizer(SIGNATURES), ops or [])
    return classifier.classify(evidence(np.array(change), first)).label


def test_a_drop_that_fits_a_signature_is_a_burst() -> None:
    assert classify([4.0, 3.0, 1.0, 0.5]) == "burst"
    assert classify([0.5, 1.0, 3.0, 4.0], first="C") == "burst"


def test_a_rise_everywhere_is_another_event() -> None:
    assert classify([-1.0, -1.0, -0.5, -0.5]) == "other"


def test_heads_rising_on_one_side_and_falling_on_the_other_is_another_event() -> None:
    assert classify([1.0, 1.0, -1.0, -1.0]) == "other"


def test_the_reason_for_a_split_names_only_what_the_classifier_knows() -> None:
    def reason(config: ClassifierConfig, first: str) -> str:
        classifier = EventClassifier(config, SignatureLocalizer(SIGNATURES))
        kind = classifier.classify(evidence(np.array([1.0, 1.0, -1.0, -1.0]), first))
        assert kind.label == "other"
        return kind.reason

    split = "an operation splitting the network (one side rose, the other fell)"
    # No asset beside the first meter nor on both sides (PU1 is at D only): no valve is named.
    assert reason(CONFIG, "A") == f"heads rose at C, D and fell at A, B: {split}"
    # The transient started beside PU1.
    assert reason(CONFIG, "D") == (
        f"heads rose at C, D and fell at A, B, the transient starting at D, beside link PU1: "
        f"{split}"
    )
    # V1 joins B (fell) and C (rose): its operation, wherever the transient started.
    between = replace(CONFIG, asset_nodes={"B": "V1", "C": "V1", "D": "PU1"})
    assert reason(between, "D") == (
        "heads rose at C, D and fell at A, B, on either side of link V1: an operation of V1"
    )


def test_a_transient_starting_at_an_asset_node_and_pointing_there_is_another_event() -> None:
    assert classify([0.5, 1.0, 3.0, 4.0], first="D") == "other"  # pipe q ends at D
    assert classify([4.0, 3.0, 1.0, 0.5], first="D") == "burst"  # pipe p does not


def test_a_small_drop_is_unsure() -> None:
    assert classify([0.4, 0.3, 0.1, 0.05]) == "unsure"


def test_a_drop_that_fits_no_burst_is_unsure() -> None:
    assert classify([4.0, 0.0, 4.0, 0.0]) == "unsure"


def test_a_declared_operation_explains_a_burst_like_drop() -> None:
    near = [Operation("N8", 20.0, "demand on")]
    assert classify([4.0, 3.0, 1.0, 0.5], ops=near) == "other"
    far = [Operation("N8", 500.0, "demand on")]
    assert classify([4.0, 3.0, 1.0, 0.5], ops=far) == "burst"


def test_the_config_round_trips_and_refuses_bad_fields(tmp_path: Path) -> None:
    path = CONFIG.save(tmp_path / "classifier.json")
    assert ClassifierConfig.load(path) == CONFIG
    with pytest.raises(ConfigError, match="max_residual"):
        ClassifierConfig(max_residual=-1.0, min_scale=0.1, rise_tolerance=0.1)
    path.write_text(path.read_text().replace('"min_scale": 0.25', '"min_scale": "x"'))
    with pytest.raises(ConfigError, match="min_scale"):
        ClassifierConfig.load(path)


def test_operations_are_read_from_csv(tmp_path: Path) -> None:
    good = tmp_path / "ops.csv"
    good.write_text("asset,time,action\nV16,12.5,close\nPU1,40,start\n")
    assert read_operations(good) == [
        Operation("V16", 12.5, "close"),
        Operation("PU1", 40.0, "start"),
    ]
    bad = tmp_path / "bad.csv"
    bad.write_text("asset,time,action\nV16,soon,close\n")
    with pytest.raises(InputError, match="line 2"):
        read_operations(bad)
    with pytest.raises(InputError, match="columns"):
        (tmp_path / "cols.csv").write_text("asset,when\nV16,1\n")
        read_operations(tmp_path / "cols.csv")


def test_a_drop_beyond_the_tolerance_at_one_meter_only_is_unsure() -> None:
    classifier = EventClassifier(CONFIG, SignatureLocalizer(SIGNATURES))
    kind = classifier.classify(evidence(np.array([2.0, 0.04, 0.0, 0.0])))
    assert kind.label == "unsure" and "small, local" in kind.reason
    assert kind.evidence["falling"] == 1


def test_thresholds_per_capture_interval(tmp_path: Path) -> None:
    strict = {"max_residual": 0.01, "min_scale": 0.25, "rise_tolerance": 0.05}
    config = ClassifierConfig(
        max_residual=0.2, min_scale=0.25, rise_tolerance=0.05, intervals={"1": strict}
    )
    assert config.thresholds(1.0) == (0.01, 0.25, 0.05)
    assert config.thresholds(2.0) == (0.2, 0.25, 0.05)
    assert ClassifierConfig.load(config.save(tmp_path / "c.json")) == config
    classifier = EventClassifier(config, SignatureLocalizer(SIGNATURES))
    noisy = np.array([4.0, 3.0, 1.0, 0.5]) + np.array([0.1, -0.1, 0.1, 0.0])
    assert classifier.classify(evidence(noisy)).label == "unsure"  # at 1 s: too far from a fit
    with pytest.raises(ConfigError, match=r"intervals\.1"):
        ClassifierConfig(0.2, 0.25, 0.05, intervals={"1": {"max_residual": 0.1}})
