"""The streaming detectors ``Cusum`` and ``Shewhart`` against the pure-Python oracle.

Checks that streaming alarms equal the paper's algorithms (``reference.py``), that per-sample
and batch feeding agree, that snapshots (pickle, copy) continue exactly where they stopped,
and that bad input raises the documented exception and changes nothing.
"""

from __future__ import annotations

import copy
import math
import pickle
import re
import struct
import subprocess
import sys
from importlib.metadata import version
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import burstloc
from burstloc import Alarm, ConfigError, Cusum, InputError, Shewhart
from burstloc.constants import MAX_SAMPLE
from reference import RefAlarm, amplitude_tolerance, cusum_online, shewhart_streaming
from signals import build_signal, cusum_parameters, pressure_signals
from snapshot_frame import payload, seal

ROOT = Path(__file__).resolve().parents[1]


def examples(n: int) -> settings:
    """Hypothesis settings for ``n`` examples of possibly long signals (no deadline)."""
    return settings(
        max_examples=n,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )


def as_ref(alarms: list[Alarm]) -> list[RefAlarm]:
    return [RefAlarm(a.index, a.start, a.direction, a.amplitude) for a in alarms]


def feed(detector: Cusum | Shewhart, x: np.ndarray) -> list[Alarm]:
    """Per-sample feeding, the way a live loop calls the detector."""
    return [a for v in x.tolist() if (a := detector.update(v)) is not None]


def burst_trace(n: int = 400, at: int = 250, seed: int = 3) -> np.ndarray:
    return build_signal(n, 50.0, 1.0, [("flat", at, 0.0), ("step", n - at, -4.0)], 0.01, seed)


# --- CUSUM -------------------------------------------------------------------------------


@examples(150)
@given(data=st.data())
def test_cusum_streaming_equals_the_online_pass(data: st.DataObject) -> None:
    x = data.draw(pressure_signals(max_size=5_000))
    threshold, drift = data.draw(cusum_parameters(x))
    expected = cusum_online(x.tolist(), threshold, drift)
    one_by_one = Cusum(threshold=threshold, drift=drift)
    assert as_ref(feed(one_by_one, x)) == expected
    batch = Cusum(threshold=threshold, drift=drift)
    assert as_ref(batch.update_many(x)) == expected
    assert one_by_one.snapshot() == batch.snapshot()
    assert batch.samples_seen == x.size


@examples(60)
@given(data=st.data())
def test_cusum_chunked_feeding_equals_one_shot(data: st.DataObject) -> None:
    x = data.draw(pressure_signals(max_size=3_000))
    threshold, drift = data.draw(cusum_parameters(x))
    cuts = sorted(data.draw(st.lists(st.integers(0, x.size), max_size=6)))
    chunked = Cusum(threshold, drift)
    alarms = []
    for lo, hi in zip([0, *cuts], [*cuts, x.size], strict=True):
        alarms += chunked.update_many(x[lo:hi])
    assert alarms == Cusum(threshold, drift).update_many(x)


def test_cusum_reports_a_burst() -> None:
    x = burst_trace()
    alarms = Cusum(threshold=2.0, drift=0.05).update_many(x)
    assert [(a.index, a.start, a.direction) for a in alarms] == [(250, 249, "drop")]
    assert alarms[0].amplitude == pytest.approx(x[250] - x[249])
    assert alarms[0].channel is None


def test_cusum_state_properties_follow_the_sums() -> None:
    det = Cusum(threshold=10.0, drift=0.5)
    assert (det.threshold, det.drift, det.samples_seen) == (10.0, 0.5, 0)
    det.update(1.0)
    det.update(3.0)  # s = 2: gp = 1.5, gp_real = 2; gn < 0 resets
    assert (det.gp, det.gp_real, det.gn, det.gn_real) == (1.5, 2.0, 0.0, 0.0)
    det.update(2.0)  # s = -1: gp = 0, gp_real = 1; gn = 0.5, gn_real = 1
    assert (det.gp, det.gp_real, det.gn, det.gn_real) == (0.0, 1.0, 0.5, 1.0)
    assert det.samples_seen == 3
    assert repr(det) == "Cusum(threshold=10.0, drift=0.5)"


def test_cusum_reset_equals_a_fresh_detector() -> None:
    x = burst_trace()
    det = Cusum(2.0, 0.05)
    det.update_many(x[:300])
    det.reset()
    assert det.snapshot() == Cusum(2.0, 0.05).snapshot()
    assert det.update_many(x) == Cusum(2.0, 0.05).update_many(x)


# --- Shewhart ----------------------------------------------------------------------------


@examples(100)
@given(
    x=pressure_signals(max_size=1_500),
    window=st.integers(min_value=2, max_value=80),
    sigma=st.floats(min_value=0.5, max_value=4.0),
    threshold_fraction=st.floats(min_value=1e-6, max_value=0.3),
)
def test_shewhart_streaming_equals_algorithm_2_on_each_trailing_window(
    x: np.ndarray, window: int, sigma: float, threshold_fraction: float
) -> None:
    threshold = threshold_fraction * (float(np.ptp(x)) or 1.0)
    det = Shewhart(window=window, threshold=threshold, sigma=sigma)
    alarms = {a.index: a for a in feed(det, x)}
    decisions = shewhart_streaming(x, window, sigma, threshold)
    assert sorted(alarms) == [d.index for d in decisions if d.alarm]
    tol = amplitude_tolerance(x)
    for d in decisions:
        if d.alarm:
            alarm = alarms[d.index]
            assert alarm.start == alarm.index
            assert alarm.amplitude == pytest.approx(d.deviation, rel=1e-9, abs=tol)
            assert alarm.direction == ("rise" if d.deviation > 0 else "drop")
    batch = Shewhart(window=window, threshold=threshold, sigma=sigma)
    assert batch.update_many(x) == list(alarms.values())
    assert batch.snapshot() == det.snapshot()


def test_shewhart_reports_the_burst_samples() -> None:
    x = burst_trace()
    det = Shewhart(window=50, threshold=1.0)
    assert (det.window, det.threshold, det.sigma) == (50, 1.0, 1.0)
    alarms = det.update_many(x)
    assert alarms and alarms[0].index == 250 and alarms[0].direction == "drop"
    assert alarms[0].amplitude < -1.0
    assert repr(det) == "Shewhart(window=50, threshold=1.0, sigma=1.0)"


def test_shewhart_is_silent_until_the_window_is_full() -> None:
    det = Shewhart(window=5, threshold=0.1, sigma=0.5)
    assert [det.update(v) for v in (0.0, 0.0, 0.0, 0.0)] == [None] * 4
    alarm = det.update(10.0)
    assert alarm == Alarm(4, 4, "rise", 8.0)


# --- Alarm -------------------------------------------------------------------------------


def test_alarm_is_immutable_comparable_and_readable() -> None:
    a = Alarm(12, 10, "drop", -0.5)
    assert (a.index, a.start, a.direction, a.amplitude, a.channel) == (12, 10, "drop", -0.5, None)
    assert repr(a) == "Alarm(index=12, start=10, direction='drop', amplitude=-0.5)"
    b = Alarm(12, 10, "drop", -0.5, channel=3)
    assert repr(b) == "Alarm(index=12, start=10, direction='drop', amplitude=-0.5, channel=3)"
    assert a == Alarm(12, 10, "drop", -0.5) and a != b
    assert hash(a) == hash(Alarm(12, 10, "drop", -0.5))
    assert hash(Alarm(1, 1, "rise", 0.0)) == hash(Alarm(1, 1, "rise", -0.0))
    with pytest.raises(AttributeError):
        a.index = 3  # type: ignore[misc]
    for alarm in (a, b):
        assert pickle.loads(pickle.dumps(alarm)) == alarm
        assert copy.deepcopy(alarm) == alarm
    with pytest.raises(InputError, match="direction"):
        Alarm(1, 1, "sideways", 0.0)  # type: ignore[arg-type]


# --- Snapshots: pickle and copy ----------------------------------------------------------


def _detectors(x: np.ndarray) -> list[Cusum | Shewhart]:
    return [Cusum(threshold=2.0, drift=0.05), Shewhart(window=30, threshold=1.0, sigma=3.0)]


@examples(40)
@given(x=pressure_signals(min_size=10, max_size=2_000), data=st.data())
def test_snapshots_continue_identically(x: np.ndarray, data: st.DataObject) -> None:
    cut = data.draw(st.integers(0, x.size))
    protocol = data.draw(st.integers(0, pickle.HIGHEST_PROTOCOL))
    for never_stopped, det in zip(_detectors(x), _detectors(x), strict=True):
        never_stopped.update_many(x[:cut])
        det.update_many(x[:cut])
        clones = [
            pickle.loads(pickle.dumps(det, protocol=protocol)),
            copy.copy(det),
            copy.deepcopy(det),
            type(det).restore(det.snapshot()),
        ]
        expected = never_stopped.update_many(x[cut:])
        assert det.update_many(x[cut:]) == expected
        for clone in clones:
            assert type(clone) is type(det)
            assert clone.update_many(x[cut:]) == expected
            assert clone.snapshot() == never_stopped.snapshot()


def test_copies_are_independent() -> None:
    det = Cusum(1.0)
    det.update(0.0)
    twin = copy.copy(det)
    det.update(5.0)
    assert twin.samples_seen == 1 and det.samples_seen == 2


def test_restore_rejects_foreign_or_corrupt_snapshots() -> None:
    cusum = Cusum(0.1234567).snapshot()
    with pytest.raises(InputError, match="Cusum"):
        Shewhart.restore(cusum)
    with pytest.raises(InputError, match="snapshot"):
        Cusum.restore(b"not a snapshot")
    with pytest.raises(InputError, match="snapshot"):
        Cusum.restore(cusum[: len(cusum) // 2])
    # Behind a valid checksum, the core re-validates what it decodes: a negative threshold (a
    # CBOR float64 is 0xfb and eight big-endian bytes) is refused with the parameter named.
    threshold = b"\xfb" + struct.pack(">d", 0.1234567)
    cbor = payload(cusum)
    assert cbor.count(threshold) == 1
    negative = seal(cbor.replace(threshold, b"\xfb" + struct.pack(">d", -0.1234567)))
    with pytest.raises(InputError, match="threshold"):
        Cusum.restore(negative)
    # Without one, the same edit is refused before anything is decoded.
    with pytest.raises(InputError, match="checksum mismatch"):
        Cusum.restore(cusum.replace(threshold, b"\xfb" + struct.pack(">d", -0.1234567)))


def test_the_packages_max_sample_is_the_detectors() -> None:
    above = math.nextafter(MAX_SAMPLE, math.inf)
    for x, ok in ((MAX_SAMPLE, True), (-MAX_SAMPLE, True), (above, False), (-above, False)):
        for det in (Cusum(threshold=0.5), Shewhart(window=2, threshold=0.5)):
            if ok:
                det.update(x)
            else:
                with pytest.raises(InputError, match="out-of-range"):
                    det.update(x)
                assert det.samples_seen == 0


def test_samples_beyond_1e100_are_refused_and_window_sums_stay_finite() -> None:
    """Samples near 1e160 would overflow a window's sum of squares, leaving a state no snapshot
    check could tell from a corrupt one: they are refused like a NaN, the state unchanged. The
    largest samples taken keep every sum finite, through a snapshot and on."""
    det = Shewhart(window=5, threshold=1.0)
    det.update_many(np.array([1.0, 2.0]))
    before = det.snapshot()
    with pytest.raises(InputError, match=r"out-of-range .*sample 1e160 at index 2"):
        det.update(1e160)
    with pytest.raises(InputError, match=r"sample -1e160 at index 3"):
        det.update_many(np.array([1.0, -1e160]))
    assert det.snapshot() == before
    x = np.tile([1e100, -1e100, 1e100, 1.0, -1e100, 2.0, 1e100, -1e100], 200)
    det.update_many(x[:900])
    restored = pickle.loads(pickle.dumps(det))
    assert restored.snapshot() == det.snapshot()
    assert restored.update_many(x[900:]) == det.update_many(x[900:])


# --- Bad input ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Cusum(threshold=-1.0), "threshold"),
        (lambda: Cusum(threshold=0.0), "threshold"),
        (lambda: Cusum(threshold=float("nan")), "threshold"),
        (lambda: Cusum(threshold=1.0, drift=-0.1), "drift"),
        (lambda: Cusum(threshold=float("inf")), "threshold"),
        (lambda: Shewhart(window=1, threshold=1.0), "window"),
        (lambda: Shewhart(window=0, threshold=1.0), "window"),
        (lambda: Shewhart(window=-5, threshold=1.0), "window"),
        (lambda: Shewhart(window=10, threshold=-1.0), "threshold"),
        (lambda: Shewhart(window=10, threshold=1.0, sigma=-2.0), "sigma"),
    ],
)
def test_bad_parameters_raise_config_error(make, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        make()


def _bad_calls(det: Cusum | Shewhart):
    samples = np.linspace(50.0, 51.0, 20)
    with_nan = samples.copy()
    with_nan[7] = np.nan
    return [
        (lambda: det.update(float("nan")), InputError, "(?i)nan"),
        (lambda: det.update(float("inf")), InputError, "inf"),
        (lambda: det.update(float("-inf")), InputError, "inf"),
        (lambda: det.update_many(with_nan), InputError, "(?i)nan"),
        (lambda: det.update_many(samples.astype(np.float32)), InputError, "float32"),
        (lambda: det.update_many(samples.astype(np.int64)), InputError, "int64"),
        (lambda: det.update_many(samples.reshape(4, 5)), InputError, r"shape \[4, 5\]"),
        (lambda: det.update_many(samples.tolist()), InputError, "list"),
        (lambda: det.update("50.0"), TypeError, "str"),
    ]


@pytest.mark.parametrize("kind", ["cusum", "shewhart"])
def test_bad_input_raises_and_changes_nothing(kind: str) -> None:
    x = burst_trace()
    make = (
        (lambda: Cusum(threshold=2.0, drift=0.05))
        if kind == "cusum"
        else (lambda: Shewhart(window=20, threshold=1.0))
    )
    det, twin = make(), make()
    det.update_many(x[:200])
    twin.update_many(x[:200])
    for call, error, message in _bad_calls(det):
        before = det.snapshot()
        with pytest.raises(error, match=message):
            call()
        assert det.snapshot() == before
    assert det.update_many(x[200:]) == twin.update_many(x[200:])


def test_input_error_names_the_sample_index() -> None:
    det = Cusum(1.0)
    det.update_many(np.zeros(10))
    bad = np.zeros(5)
    bad[3] = np.inf
    with pytest.raises(InputError, match="13"):
        det.update_many(bad)
    with pytest.raises(InputError, match="10"):
        det.update(float("nan"))


def test_strided_and_readonly_arrays_are_accepted() -> None:
    x = burst_trace()
    expected = Cusum(2.0).update_many(x[::2].copy())
    assert Cusum(2.0).update_many(x[::2]) == expected
    frozen = x[::2].copy()
    frozen.flags.writeable = False
    assert Cusum(2.0).update_many(frozen) == expected


# --- Package -----------------------------------------------------------------------------


def test_exceptions_are_value_errors_that_pickle() -> None:
    from burstloc import exceptions

    assert issubclass(ConfigError, ValueError) and issubclass(InputError, ValueError)
    assert issubclass(exceptions.StreamError, InputError)
    assert issubclass(exceptions.NetworkError, ValueError)
    assert issubclass(exceptions.SimulationError, RuntimeError)
    assert exceptions.ConfigError is ConfigError
    try:
        Cusum(threshold=-1.0)
    except ConfigError as err:
        again = pickle.loads(pickle.dumps(err))
        assert type(again) is ConfigError and again.args == err.args


def test_version_comes_from_cargo() -> None:
    cargo = (ROOT / "Cargo.toml").read_text()
    package = cargo[cargo.index("[workspace.package]") :]
    match = re.search(r'^version\s*=\s*"([^"]+)"', package, re.MULTILINE)
    assert match and burstloc.__version__ == match.group(1)
    assert version("burstloc") == burstloc.__version__


def test_public_names() -> None:
    for name in burstloc.__all__:
        assert getattr(burstloc, name).__doc__ or name == "__version__", name
    assert Cusum.__module__ == "burstloc._core" and Cusum.__name__ == "Cusum"


def test_import_is_cheap() -> None:
    heavy = "{'tsnet', 'wntr', 'burstloc.sim.transient.tsnet'}"
    code = f"import sys, burstloc; print(sorted({heavy} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
