"""Sizes no machine can hold are configuration errors, and restored state is validated."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from burstloc import ConfigError, Cusum, DetectorBank, InputError, Shewhart


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Shewhart(window=10**12, threshold=0.5), "window"),
        (lambda: Shewhart(window=2**62, threshold=0.5), "window"),
        (lambda: DetectorBank("cusum", 10**12, threshold=0.5), "channels"),
        (lambda: DetectorBank("shewhart", 10**6, window=10**7, threshold=0.5), "channels"),
        (lambda: DetectorBank("shewhart", 10**12, window=10, threshold=0.5), "channels"),
        # Past a 64-bit integer: still a configuration error, not an OverflowError.
        (lambda: Shewhart(window=2**63, threshold=0.5), "window"),
        (lambda: DetectorBank("cusum", 2**70, threshold=0.5), "channels"),
        (lambda: DetectorBank("shewhart", 2, window=2**64, threshold=0.5), "window"),
    ],
)
def test_huge_sizes_are_config_errors_not_aborts(make, name: str) -> None:
    with pytest.raises(ConfigError, match=name):
        make()


def _replace_float(snapshot: bytes, old: float, new: float) -> bytes:
    """The snapshot with its one CBOR float64 ``old`` (0xfb + 8 big-endian bytes) replaced."""
    encoded = b"\xfb" + struct.pack(">d", old)
    assert snapshot.count(encoded) == 1
    return snapshot.replace(encoded, b"\xfb" + struct.pack(">d", new))


def test_restore_rejects_a_non_finite_previous_value() -> None:
    det = Cusum(threshold=0.5, drift=0.01)
    det.update_many(np.array([200.0, 200.1, 200.05]))
    edited = _replace_float(det.snapshot(), 200.05, float("nan"))
    with pytest.raises(InputError, match="non-finite"):
        Cusum.restore(edited)
    # The same edit with a finite value restores, and the detector runs on.
    moved = Cusum.restore(_replace_float(det.snapshot(), 200.05, 150.0))
    assert moved.update(151.0) is not None


def test_restore_rejects_a_non_finite_window_sample() -> None:
    det = Shewhart(window=4, threshold=0.5)
    det.update_many(np.array([1.1, 2.2, 3.3, 4.4, 5.5]))
    edited = _replace_float(det.snapshot(), 3.3, float("inf"))
    with pytest.raises(InputError, match="non-finite"):
        Shewhart.restore(edited)


def test_restore_rejects_a_real_sum_above_the_threshold() -> None:
    bank = DetectorBank("cusum", 1, threshold=0.5, drift=0.01)
    bank.run(np.array([[1.0], [1.3]]))
    edited = _replace_float(bank.snapshot(), 1.3 - 1.0, 0.75)  # gp_real
    with pytest.raises(InputError, match="threshold"):
        DetectorBank.restore(edited)
