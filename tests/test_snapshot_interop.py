"""Snapshots cross the language boundary: Rust-written snapshots restore in Python, old ones
still restore, and altered ones are refused.

The fixtures live in ``crates/cpd-core/tests/data/snapshots`` (see ``gen_snapshots.py``
there): ``rust_*.cbor`` are written by the Rust test ``tests/snapshot_interop.rs`` (which also
decodes the Python-written ``py_*.cbor``); format-1 snapshots (no checksum, what the package
wrote before format 2) are made from the ``py_*.cbor`` payloads (``snapshot_frame.format1_of``).
Each restored detector must
equal one fed the same samples here, and raise the same alarms afterwards.

Through the binding, every byte offset of a snapshot of each kind is altered in turn (the
8-byte patterns of NaN and +-inf, both byte orders; each bit flipped; the byte deleted; a zero
byte inserted), and the snapshot truncated to every shorter length and extended: each restore
raises ``InputError`` naming the problem, and the detector it was taken from is untouched.
"""

from __future__ import annotations

import json
import struct
from collections import Counter
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from burstloc import Cusum, DetectorBank, InputError, Shewhart
from snapshot_frame import crc32c, format1_of

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
@pytest.mark.parametrize(
    ("writer", "cut"), [("rust", "rust_cut"), ("py", "py_cut"), ("format1", "py_cut")]
)
def test_snapshot_fixture_restores_and_continues(name: str, writer: str, cut: str) -> None:
    k = TRACE[cut]
    never_stopped = fresh(name)
    feed(never_stopped, ROWS[:k])
    if writer == "format1":  # before format 2: made from the package's format-2 fixture
        stored = format1_of((DATA / f"py_{name}.cbor").read_bytes())
    else:
        stored = (DATA / f"{writer}_{name}.cbor").read_bytes()
    restored = type(never_stopped).restore(stored)
    assert restored.snapshot() == never_stopped.snapshot()
    expected = feed(never_stopped, ROWS[k:])
    assert expected, "the trace's tail holds changes, so alarms are compared"
    assert feed(restored, ROWS[k:]) == expected
    assert restored.snapshot() == never_stopped.snapshot()


def test_snapshots_end_with_the_crc32c_of_their_bytes() -> None:
    """The frame, checked against a pure-Python CRC-32C (the catalogue's check value first)."""
    assert crc32c(b"123456789") == 0xE3069283
    for name in ["cusum", "shewhart", "bank_cusum", "bank_shewhart"]:
        det = fresh(name)
        feed(det, ROWS[:100])
        snap = det.snapshot()
        assert snap[:5] == b"CPDS\x02"
        assert struct.unpack("<Q", snap[5:13])[0] == len(snap)
        assert struct.unpack("<I", snap[-4:])[0] == crc32c(snap[:-4])
        # A format-1 fixture restores, and is written back in format 2.
        old = format1_of((DATA / f"py_{name}.cbor").read_bytes())
        assert old.startswith(b"\xa3\x66format\x01")
        assert type(det).restore(old).snapshot() == (DATA / f"py_{name}.cbor").read_bytes()


_PATTERNS = [
    struct.pack(order + "d", x)
    for order in "><"
    for x in (float("nan"), float("inf"), -float("inf"))
]


def _altered(snap: bytes) -> Iterator[bytes]:
    """Every alteration of ``snap``: per byte offset the six float patterns, eight bit flips, the
    byte deleted, a zero byte inserted; every truncation; 1 to 8 zero bytes and a copy appended."""
    n = len(snap)
    for at in range(n):
        for p in _PATTERNS:
            yield snap[:at] + p[: n - at] + snap[at + 8 :]
        for bit in range(8):
            yield snap[:at] + bytes([snap[at] ^ (1 << bit)]) + snap[at + 1 :]
        yield snap[:at] + snap[at + 1 :]
        yield snap[:at] + b"\x00" + snap[at:]
        yield snap[:at]
    yield snap + b"\x00"
    yield from (snap + b"\x00" * k for k in range(1, 9))
    yield snap + snap


_PROBLEMS = ("checksum mismatch", "truncated", "after its end", "not a snapshot")


@pytest.mark.parametrize(
    "make",
    [
        lambda: Cusum(0.5, 0.01),
        lambda: Shewhart(37, 0.2),
        lambda: DetectorBank("cusum", 3, threshold=0.5, drift=0.01),
        lambda: DetectorBank("shewhart", 3, window=37, threshold=0.2),
    ],
    ids=["cusum", "shewhart_w37", "bank_cusum", "bank_shewhart_w37"],
)
def test_every_altered_snapshot_is_refused_through_the_binding(
    make: Callable[[], Cusum | Shewhart | DetectorBank],
) -> None:
    det = make()
    if isinstance(det, DetectorBank):
        det.run(ROWS[:240])
    else:
        det.update_many(np.ascontiguousarray(ROWS[:240, 1]))
    snap = det.snapshot()
    tried: Counter[str] = Counter()
    for altered in _altered(snap):
        if altered == snap:
            continue
        with pytest.raises(InputError) as refused:
            type(det).restore(altered)
        message = str(refused.value)
        problem = next((p for p in _PROBLEMS if p in message), None)
        assert problem is not None, message
        assert message.startswith("unreadable "), message
        tried[problem] += 1
    assert sum(tried.values()) > 16 * len(snap), tried
    assert tried["checksum mismatch"] > 14 * (len(snap) - 17), tried
    # The detector the snapshot was taken from is as it was, and restores from it.
    assert det.snapshot() == snap
    assert type(det).restore(snap).snapshot() == snap
