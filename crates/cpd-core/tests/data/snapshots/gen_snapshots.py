"""Generate the snapshot-interop fixtures shared by the Rust and Python tests.

Run from the repository root:

    .venv/bin/python crates/cpd-core/tests/data/snapshots/gen_snapshots.py

It writes, next to this file:

* ``trace.json``: a seeded 3-channel head trace (one drop on channel 1 and one rise on
  channel 2 after both cuts), the detector configurations and two cut points;
* ``py_*.cbor``: snapshots written by the Python package (``burstloc``) after feeding the
  trace up to ``py_cut``: ``Cusum`` and ``Shewhart`` on channel 1, a CUSUM and a Shewhart
  ``DetectorBank`` on all three channels.

Format-1 snapshots (the bare CBOR map ``{format: 1, kind, state}``, no checksum: what the Python
package wrote before snapshot format 2) are not stored: the tests make them from the ``py_*.cbor``
payloads, byte for byte what that package wrote (checked against its files when format 2 came).

The ``rust_*.cbor`` files are written by the Rust test ``tests/snapshot_interop.rs`` with
``CPD_WRITE_SNAPSHOTS=1 cargo test -p cpd-core --features snapshot --test snapshot_interop``
(after feeding the trace up to ``rust_cut``). Rust decodes the ``py_*`` files and Python
(``tests/test_snapshot_interop.py``) decodes the ``rust_*`` files; both sides then check that
the restored detector equals one fed the same samples and raises the same alarms afterwards.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import burstloc

HERE = Path(__file__).resolve().parent
STEPS, CHANNELS = 600, 3
PY_CUT, RUST_CUT = 350, 420
CONFIG = {
    "cusum": {"threshold": 0.3, "drift": 0.01},
    # sigma left to its default (the threshold): the paper's single parameter.
    "shewhart": {"window": 50, "threshold": 0.2},
}


def trace() -> np.ndarray:
    rng = np.random.default_rng(20261123)
    x = 200.0 + rng.normal(0.0, 0.05, (STEPS, CHANNELS)) - 15.0 * np.arange(CHANNELS)
    x[500:, 1] -= 1.5  # a burst seen by meter 1
    x[540:, 2] += 0.8  # a valve closing near meter 2
    return x


def detectors() -> dict[str, object]:
    c, s = CONFIG["cusum"], CONFIG["shewhart"]
    return {
        "cusum": burstloc.Cusum(c["threshold"], c["drift"]),
        "shewhart": burstloc.Shewhart(s["window"], s["threshold"]),
        "bank_cusum": burstloc.DetectorBank("cusum", CHANNELS, **c),
        "bank_shewhart": burstloc.DetectorBank("shewhart", CHANNELS, **s),
    }


def main() -> None:
    x = trace()
    (HERE / "trace.json").write_text(
        json.dumps(
            {
                "channels": CHANNELS,
                "py_cut": PY_CUT,
                "rust_cut": RUST_CUT,
                "config": CONFIG,
                "rows": x.tolist(),
            }
        )
        + "\n"
    )
    for name, det in detectors().items():
        if name.startswith("bank"):
            det.run(x[:PY_CUT])
        else:
            det.update_many(np.ascontiguousarray(x[:PY_CUT, 1]))
        (HERE / f"py_{name}.cbor").write_bytes(det.snapshot())


if __name__ == "__main__":
    main()
