"""Snapshots cross the language boundary: Rust-written snapshots restore in Python.

The fixtures live in ``crates/cpd-core/tests/data/snapshots`` (see ``gen_snapshots.py``
there): ``rust_*.cbor`` are written by the Rust test ``tests/snapshot_interop.rs`` (which also
decodes the Python-written ``py_*.cbor``). Each restored detector must equal one fed the same
samples here, and raise the same alarms afterwards.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from burstloc import Cusum, DetectorBank, Shewhart

DATA = Path(__file__).resolve().parents[1] / "crates" / "cpd-core" / "tests" / "data" / "snapshots"
TRACE = json.loads((DATA / "trace.json").read_text())
ROWS = np.array(TRACE["rows"])
CONFIG = TRACE["config"]
CHANNELS = TRACE["channels"]


def fresh(name: str) -> Cusum | Shewhart | DetectorBank:
    c, s = CONFIG["cusum"], CONFIG["shewhart"]
    return {
        "cusum": lambda: Cusum(c["threshold"], c["drift"]),
        "shewhart": lambda: Shewhart(s["window"], s["threshold"]),
        "bank_cusum": lambda: DetectorBank("cusum", CHANNELS, **c),
        "bank_shewhart": lambda: DetectorBank("shewhart", CHANNELS, **s),
    }[name]()


def feed(det: Cusum | Shewhart | DetectorBank, rows: np.ndarray) -> list:
    if isinstance(det, DetectorBank):
        return det.run(rows)
    return det.update_many(np.ascontiguousarray(rows[:, 1]))


@pytest.mark.parametrize("name", ["cusum", "shewhart", "bank_cusum", "bank_shewhart"])
@pytest.mark.parametrize(("writer", "cut"), [("rust", "rust_cut"), ("py", "py_cut")])
def test_snapshot_fixture_restores_and_continues(name: str, writer: str, cut: str) -> None:
    k = TRACE[cut]
    never_stopped = fresh(name)
    feed(never_stopped, ROWS[:k])
    restored = type(never_stopped).restore((DATA / f"{writer}_{name}.cbor").read_bytes())
    assert restored.snapshot() == never_stopped.snapshot()
    expected = feed(never_stopped, ROWS[k:])
    assert expected, "the trace's tail holds changes, so alarms are compared"
    assert feed(restored, ROWS[k:]) == expected
    assert restored.snapshot() == never_stopped.snapshot()
