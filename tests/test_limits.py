"""Sizes no machine can hold are configuration errors, and restored state is validated."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from burstloc import ConfigError, Cusum, DetectorBank, InputError, Shewhart
from snapshot_frame import payload, seal


@pytest.mark.parametrize(
    ("make", "name"),
    [
        (lambda: Shewhart(window=10**12, threshold=0.5), "window"),
        (lambda: Shewhart(window=2**62, threshold=0.5), "window"),
        (lambda: DetectorBank("cusum", 10**12, threshold=0.5), "channels"),
        # The ring of window x channels samples: the window asks for it; the per-channel sums
        # (allocated first) name the channels.
        (lambda: DetectorBank("shewhart", 3, window=10**12, threshold=0.5), "window"),
        (lambda: DetectorBank("shewhart", 10**6, window=10**7, threshold=0.5), "window"),
        (lambda: DetectorBank("shewhart", 10**12, window=10, threshold=0.5), "channels"),
        (lambda: DetectorBank("shewhart", 3, window=2**62, threshold=0.5), "window"),
        # Past a 64-bit integer: still a configuration error, not an OverflowError.
        (lambda: Shewhart(window=2**63, threshold=0.5), "window"),
        (lambda: DetectorBank("cusum", 2**70, threshold=0.5), "channels"),
        (lambda: DetectorBank("shewhart", 2, window=2**64, threshold=0.5), "window"),
    ],
)
def test_huge_sizes_are_config_errors_not_aborts(make, name: str) -> None:
    """Each size parameter of each detector and bank: a configuration error naming it."""
    with pytest.raises(ConfigError, match=rf"parameter `{name}` = \d+:"):
        make()


def _replace_float(snapshot: bytes, old: float, new: float) -> bytes:
    """The snapshot with its one CBOR float64 ``old`` (0xfb + 8 big-endian bytes) replaced,
    sealed with a valid checksum (the state validation is what lies behind it)."""
    encoded = b"\xfb" + struct.pack(">d", old)
    cbor = payload(snapshot)
    assert cbor.count(encoded) == 1
    return seal(cbor.replace(encoded, b"\xfb" + struct.pack(">d", new)))


def test_restore_rejects_a_non_finite_previous_value() -> None:
    det = Cusum(threshold=0.5, drift=0.01)
    det.update_many(np.array([200.0, 200.1, 200.05]))
    edited = _replace_float(det.snapshot(), 200.05, float("nan"))
    with pytest.raises(InputError, match="`x_prev` = NaN: must be a sample"):
        Cusum.restore(edited)
    # The same edit with a finite value restores, and the detector runs on.
    moved = Cusum.restore(_replace_float(det.snapshot(), 200.05, 150.0))
    assert moved.update(151.0) is not None


def test_restore_rejects_a_non_finite_window_sample() -> None:
    det = Shewhart(window=4, threshold=0.5)
    det.update_many(np.array([1.1, 2.2, 3.3, 4.4, 5.5]))
    edited = _replace_float(det.snapshot(), 3.3, float("inf"))
    with pytest.raises(InputError, match=r"`ring`\[2\] = inf: must be a sample"):
        Shewhart.restore(edited)


def test_restore_rejects_a_real_sum_above_the_threshold() -> None:
    bank = DetectorBank("cusum", 1, threshold=0.5, drift=0.01)
    bank.run(np.array([[1.0], [1.3]]))
    edited = _replace_float(bank.snapshot(), 1.3 - 1.0, 0.75)  # gp_real
    with pytest.raises(InputError, match="threshold"):
        DetectorBank.restore(edited)


def _floats(data: bytes) -> list[tuple[int, int, str]]:
    """``(start, end, field)`` of every float item of the CBOR ``data`` (``field``: the last map
    key on its path): a minimal reader of the snapshot envelope's major types."""
    found: list[tuple[int, int, str]] = []

    def item(i: int, key: str) -> tuple[int, str | None]:
        major, info = data[i] >> 5, data[i] & 31
        i += 1
        if info >= 24:
            n = 1 << (info - 24)
            if major == 7:
                if info >= 25:  # float16, float32, float64
                    found.append((i - 1, i + n, key))
                return i + n, None
            arg, i = int.from_bytes(data[i : i + n], "big"), i + n
        else:
            arg = info
        if major in (2, 3):
            return i + arg, data[i : i + arg].decode() if major == 3 else None
        if major == 4:
            for _ in range(arg):
                i, _ = item(i, key)
        elif major == 5:
            for _ in range(arg):
                i, name = item(i, key)
                i, _ = item(i, name or key)
        elif major == 6:
            return item(i, key)
        return i, None

    end, _ = item(0, "")
    assert end == len(data)
    return found


def _fed(kind: str) -> Cusum | Shewhart | DetectorBank:
    x = 200.0 + 0.01 * np.sin(np.arange(1500.0)) + np.where(np.arange(1500) > 700, -1.0, 0.0)
    if kind == "cusum":
        det: Cusum | Shewhart = Cusum(threshold=0.5, drift=0.01)
    elif kind == "shewhart":
        det = Shewhart(window=6, threshold=0.3)
    else:
        extra = {"drift": 0.01} if kind == "bank_cusum" else {"window": 6}
        bank = DetectorBank(kind.removeprefix("bank_"), 2, threshold=0.5, **extra)
        bank.run(np.stack([x, x - 3.0], axis=1))
        return bank
    det.update_many(x)
    return det


@pytest.mark.parametrize("kind", ["cusum", "shewhart", "bank_cusum", "bank_shewhart"])
def test_a_non_finite_value_in_any_float_field_is_refused_by_name(kind: str) -> None:
    """Through the binding: every float of the snapshot (configs, sums, compensations, samples,
    rings) replaced in turn by NaN, +inf and -inf, the snapshot sealed with a valid checksum;
    each restore refused, naming the field."""
    det = _fed(kind)
    snapshot = det.snapshot()
    cbor = payload(snapshot)
    floats = _floats(cbor)
    fields = {name for _, _, name in floats}
    want = {
        "cusum": {"threshold", "drift", "x_prev", "gp", "gn", "gp_real", "gn_real", "x_tap"},
        "shewhart": {"sigma", "threshold", "reference", "s1", "c1", "s2", "c2", "ring"},
    }[kind.removeprefix("bank_")]
    assert want <= fields, fields
    for start, end, name in floats:
        for bad in (float("nan"), float("inf"), float("-inf")):
            edited = seal(cbor[:start] + b"\xfb" + struct.pack(">d", bad) + cbor[end:])
            with pytest.raises(InputError, match=f"`{name}`"):
                type(det).restore(edited)
    assert type(det).restore(snapshot).snapshot() == snapshot
