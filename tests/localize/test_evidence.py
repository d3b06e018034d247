"""burstloc.localize.evidence: rankings and the evidence built from a detector bank's alarms."""

from __future__ import annotations

import numpy as np
import pytest

from burstloc import _core
from burstloc.exceptions import InputError
from burstloc.localize.evidence import (
    RankedPipe,
    Ranking,
    evidence_from_alarms,
)


def test_evidence_from_a_real_detector_bank() -> None:
    # three meters see a 1 m drop at readings 12, 14 and 17 (0.1 s apart), one stays flat
    t = np.arange(40) * 0.1
    x = np.full((40, 4), 50.0)
    for j, k in enumerate((12, 14, 17)):
        x[k:, j] -= 1.0
    alarms = _core.DetectorBank("cusum", 4, threshold=0.5, drift=0.001).run(x)
    meters = ["a", "b", "c", "d"]
    ev = evidence_from_alarms(meters, t, x, alarms, capture_interval=0.1, decision_time=2.0)
    assert set(ev.alarms) == {"a", "b", "c"}
    assert ev.alarms["a"].start == pytest.approx(1.1)  # the last flat reading
    assert ev.alarms["c"].start == pytest.approx(1.6)
    assert ev.alarms["b"].amplitude == pytest.approx(-1.0)
    assert ev.onset == pytest.approx(1.1)
    assert ev.decision_time == pytest.approx(2.0)
    shew = _core.DetectorBank("shewhart", 4, window=10, threshold=0.5, sigma=2.0).run(x)
    ev2 = evidence_from_alarms(meters, t, x, shew, capture_interval=0.1)
    assert ev2.alarms["a"].start == pytest.approx(1.1)  # flagged reading 12 -> change after 11
    with pytest.raises(InputError, match="no alarm"):
        evidence_from_alarms(meters, t, x, alarms, capture_interval=0.1, decision_time=1.0)


def test_ranking_orders_and_validates() -> None:
    r = Ranking(
        [
            RankedPipe("b", "1", "2", -1.0),
            RankedPipe("a", "2", "3", -1.0),
            RankedPipe("c", "", "", 0),
        ]
    )
    assert [p.pipe for p in r] == ["c", "a", "b"]  # ties by name
    assert r.rank_of("b") == 3 and r.rank_of("z") is None
    assert r.in_top("a", 2) and not r.in_top("b", 2)
    assert r.to_records(1) == [{"pipe": "c", "start": "", "end": "", "score": 0, "rank": 1}]
    with pytest.raises(InputError):
        r.top(0)
    with pytest.raises(InputError, match="NaN"):
        Ranking([RankedPipe("a", "1", "2", float("nan"))])
    with pytest.raises(InputError, match="twice"):
        Ranking([RankedPipe("a", "1", "2", 0.0), RankedPipe("a", "1", "2", 1.0)])
