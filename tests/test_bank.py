"""``DetectorBank``: N channels stepped together equal N independent detectors."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from burstloc import Alarm, ConfigError, Cusum, DetectorBank, InputError, Shewhart
from signals import pressure_signals


def examples(n: int) -> settings:
    """Hypothesis settings for ``n`` examples of possibly long signals (no deadline)."""
    return settings(
        max_examples=n,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


CONFIGS = {
    "cusum": {"threshold": 1.5, "drift": 0.02},
    "shewhart": {"window": 25, "threshold": 0.8, "sigma": 2.5},
}


def single(kind: str) -> Cusum | Shewhart:
    return Cusum(**CONFIGS[kind]) if kind == "cusum" else Shewhart(**CONFIGS[kind])


@st.composite
def traces(draw: st.DrawFn, max_steps: int = 400, max_channels: int = 8) -> np.ndarray:
    """A (T, N) matrix of pressure-like columns with unit-ish amplitudes."""
    steps = draw(st.integers(min_value=1, max_value=max_steps))
    channels = draw(st.integers(min_value=1, max_value=max_channels))
    columns = []
    for _ in range(channels):
        x = draw(pressure_signals(min_size=steps, max_size=steps))
        spread = float(np.ptp(x))
        columns.append((x - x.mean()) / spread * 5.0 if spread > 0 else x * 0.0)
    return np.column_stack(columns)


def independent(kind: str, matrix: np.ndarray) -> list[Alarm]:
    """The alarms of one single-channel detector per column, in (step, channel) order."""
    found = []
    for channel in range(matrix.shape[1]):
        for a in single(kind).update_many(np.ascontiguousarray(matrix[:, channel])):
            found.append(Alarm(a.index, a.start, a.direction, a.amplitude, channel=channel))
    return sorted(found, key=lambda a: (a.index, a.channel))


@examples(60)
@given(matrix=traces(), kind=st.sampled_from(["cusum", "shewhart"]))
def test_bank_equals_independent_detectors(matrix: np.ndarray, kind: str) -> None:
    expected = independent(kind, matrix)
    stepped = DetectorBank(kind, matrix.shape[1], **CONFIGS[kind])
    alarms = [a for row in matrix for a in stepped.step(row)]
    assert alarms == expected
    assert stepped.steps_seen == matrix.shape[0]
    ran = DetectorBank(kind, matrix.shape[1], **CONFIGS[kind])
    assert ran.run(matrix) == expected
    assert ran.snapshot() == stepped.snapshot()
    fortran = DetectorBank(kind, matrix.shape[1], **CONFIGS[kind])
    assert fortran.run(np.asfortranarray(matrix)) == expected


@examples(30)
@given(matrix=traces(max_steps=200), kind=st.sampled_from(["cusum", "shewhart"]), data=st.data())
def test_bank_snapshots_continue_identically(
    matrix: np.ndarray, kind: str, data: st.DataObject
) -> None:
    cut = data.draw(st.integers(0, matrix.shape[0]))
    bank = DetectorBank(kind, matrix.shape[1], **CONFIGS[kind])
    bank.run(matrix[:cut])
    restored = [
        pickle.loads(pickle.dumps(bank)),
        copy.deepcopy(bank),
        DetectorBank.restore(bank.snapshot()),
    ]
    expected = bank.run(matrix[cut:])
    for clone in restored:
        assert (clone.kind, clone.channels) == (kind, matrix.shape[1])
        assert clone.run(matrix[cut:]) == expected
        assert clone.snapshot() == bank.snapshot()


def test_bank_properties_and_reset() -> None:
    bank = DetectorBank("cusum", 3, threshold=1.0)
    assert (bank.kind, bank.channels, bank.steps_seen) == ("cusum", 3, 0)
    assert repr(bank) == "DetectorBank('cusum', channels=3, threshold=1.0, drift=0.0)"
    bank.step(np.array([1.0, 2.0, 3.0]))
    alarms = bank.step(np.array([1.0, 0.0, 5.0]))
    assert [(a.channel, a.direction, a.index, a.start) for a in alarms] == [
        (1, "drop", 1, 0),
        (2, "rise", 1, 0),
    ]
    bank.reset()
    assert bank.snapshot() == DetectorBank("cusum", 3, threshold=1.0).snapshot()
    shewhart = DetectorBank("shewhart", 2, window=10, threshold=0.5)
    assert (
        repr(shewhart)
        == "DetectorBank('shewhart', channels=2, window=10, threshold=0.5, sigma=0.5)"
    )


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "ewma", "channels": 2, "threshold": 1.0}, "kind"),
        ({"kind": "cusum", "channels": 0, "threshold": 1.0}, "channels"),
        ({"kind": "cusum", "channels": -3, "threshold": 1.0}, "channels"),
        ({"kind": "cusum", "channels": 2, "threshold": -1.0}, "threshold"),
        ({"kind": "cusum", "channels": 2, "threshold": 1.0, "window": 5}, "window"),
        ({"kind": "shewhart", "channels": 2, "threshold": 1.0}, "window"),
        ({"kind": "shewhart", "channels": 2, "threshold": 1.0, "window": 1}, "window"),
        ({"kind": "shewhart", "channels": 2, "threshold": 1.0, "window": 5, "drift": 1.0}, "drift"),
    ],
)
def test_bad_bank_configuration_raises_config_error(kwargs: dict, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        DetectorBank(**kwargs)


@pytest.mark.parametrize("kind", ["cusum", "shewhart"])
def test_bad_readings_raise_and_change_nothing(kind: str) -> None:
    rng = np.random.default_rng(5)
    matrix = rng.normal(50.0, 0.2, (60, 4))
    matrix[40:, 2] -= 3.0
    bank = DetectorBank(kind, 4, **CONFIGS[kind])
    twin = DetectorBank(kind, 4, **CONFIGS[kind])
    bank.run(matrix[:30])
    twin.run(matrix[:30])
    nan_row = matrix[30].copy()
    nan_row[3] = np.nan
    inf_matrix = matrix[30:].copy()
    inf_matrix[5, 1] = np.inf
    bad_calls = [
        (lambda: bank.step(nan_row), "channel 3"),
        (lambda: bank.step(matrix[30, :3].copy()), "expected 4"),
        (lambda: bank.step(matrix[30].astype(np.float32)), "float32"),
        (lambda: bank.step(matrix[30:32]), "shape"),
        (lambda: bank.step(list(matrix[30])), "list"),
        (lambda: bank.run(inf_matrix), "row 5, channel 1"),
        (lambda: bank.run(matrix[30:, :3]), "one column per channel"),
        (lambda: bank.run(matrix[30]), "2-D"),
    ]
    for call, message in bad_calls:
        before = bank.snapshot()
        with pytest.raises(InputError, match=message):
            call()
        assert bank.snapshot() == before
    assert bank.run(matrix[30:]) == twin.run(matrix[30:])
