"""Type stubs for ``burstloc._core``, the Rust extension module (crates/cpd-py)."""

from collections.abc import Iterable, Sequence
from typing import Any, Final, Literal, final

import numpy as np
import numpy.typing as npt
from typing_extensions import Self

from burstloc.readings import Step

__all__ = [
    "Alarm",
    "ConfigError",
    "Cusum",
    "DetectorBank",
    "InputError",
    "Shewhart",
    "__version__",
    "detect_cusum",
    "detect_shewhart",
    "feed_lines",
    "moc_run",
]

__version__: Final[str]

_FloatArray = npt.NDArray[np.float64]
_IndexArray = npt.NDArray[np.int64]

class ConfigError(ValueError):
    """A detector was configured with an invalid parameter."""

class InputError(ValueError):
    """A detector was fed invalid input; its state is unchanged (also: steps of readings that
    do not fit their meters)."""

@final
class Alarm:
    """A detected change (immutable)."""

    @property
    def index(self) -> int: ...
    @property
    def start(self) -> int: ...
    @property
    def direction(self) -> Literal["rise", "drop"]: ...
    @property
    def amplitude(self) -> float: ...
    @property
    def channel(self) -> int | None: ...
    def __new__(
        cls,
        index: int,
        start: int,
        direction: Literal["rise", "drop"],
        amplitude: float,
        channel: int | None = None,
    ) -> Self: ...
    def __eq__(self, other: object, /) -> bool: ...
    def __ne__(self, other: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __reduce__(self) -> tuple[Any, ...]: ...

class _Snapshots:
    """Stub-only: the snapshot methods every detector class has (pickle, copy)."""

    def snapshot(self) -> bytes:
        """The configuration and full state as bytes (format 2: version, length, CBOR payload,
        CRC-32C)."""
    @classmethod
    def restore(cls, state: bytes) -> Self:
        """An object in exactly the state captured by ``snapshot()`` (or a format-1 snapshot).

        Raises:
            InputError: altered, truncated or extended bytes (checksum or length mismatch), an
                unknown format version, another kind, or an invalid state; named.
        """
    def __reduce__(self) -> tuple[Any, ...]: ...
    def __copy__(self) -> Self: ...
    def __deepcopy__(self, memo: Any, /) -> Self: ...

class _Streaming(_Snapshots):
    """Stub-only: the methods of a single-channel streaming detector."""

    @property
    def samples_seen(self) -> int: ...
    def update(self, x: float) -> Alarm | None: ...
    def update_many(self, x: _FloatArray) -> list[Alarm]: ...
    def reset(self) -> None: ...

@final
class Cusum(_Streaming):
    """Two-sided CUSUM change detector (TSNet's ``detect_cusum``, online form)."""

    def __new__(cls, threshold: float, drift: float = 0.0) -> Self: ...
    @property
    def threshold(self) -> float: ...
    @property
    def drift(self) -> float: ...
    @property
    def gp(self) -> float: ...
    @property
    def gn(self) -> float: ...
    @property
    def gp_real(self) -> float: ...
    @property
    def gn_real(self) -> float: ...

@final
class Shewhart(_Streaming):
    """Shewhart control chart over a sliding window (the paper's Algorithm 2, streaming)."""

    def __new__(cls, window: int, threshold: float, sigma: float | None = None) -> Self: ...
    @property
    def window(self) -> int: ...
    @property
    def sigma(self) -> float: ...
    @property
    def threshold(self) -> float: ...

@final
class DetectorBank(_Snapshots):
    """One detector per channel (sensor), advanced one time step at a time."""

    def __new__(
        cls,
        kind: Literal["cusum", "shewhart"],
        channels: int,
        *,
        threshold: float,
        drift: float | None = None,
        window: int | None = None,
        sigma: float | None = None,
    ) -> Self: ...
    @property
    def kind(self) -> Literal["cusum", "shewhart"]: ...
    @property
    def channels(self) -> int: ...
    @property
    def steps_seen(self) -> int: ...
    def step(self, readings: _FloatArray) -> list[Alarm]: ...
    def run(self, matrix: _FloatArray) -> list[Alarm]: ...
    def reset(self) -> None: ...

def detect_cusum(
    time: Any,
    x: _FloatArray,
    threshold: float,
    drift: float,
    ending: bool = True,
) -> tuple[_IndexArray, _IndexArray, _FloatArray]:
    """TSNet's ``detect_cusum(time, x, threshold, drift, show=False, ending=ending)``."""

def detect_shewhart(
    x: _FloatArray, sigma: float, threshold: float
) -> tuple[_IndexArray, _FloatArray]:
    """The paper's Algorithm 2 over the whole of ``x``."""

def feed_lines(steps: Iterable[Step], meters: Sequence[str]) -> bytes:
    """The lines ``timestamp,meter,value`` of ``steps`` (columns ``meters``), every number as
    ``repr`` writes it, filled values and values that are not finite left out; made without the
    GIL (``burstloc.incidents.kept``)."""

_UIntArray = npt.NDArray[np.uint64]

def moc_run(
    *,
    steps: int,
    pipe_points: _IndexArray,
    pipes: _FloatArray,
    h0: _FloatArray,
    v0: _FloatArray,
    nodes: _FloatArray,
    junctions: _IndexArray,
    junction_values: _FloatArray,
    contributions: _IndexArray,
    contribution_signs: _FloatArray,
    dead_ends: _IndexArray,
    dead_floors: _FloatArray,
    reservoirs: _IndexArray,
    reservoir_values: _FloatArray,
    valve_ends: _IndexArray,
    valve_sides: _FloatArray,
    valve_series: _FloatArray,
    elements: _IndexArray,
    element_values: _FloatArray,
    element_series: _FloatArray,
    bursts: _IndexArray,
    burst_series: _FloatArray,
    pulses: _IndexArray,
    pulse_series: _FloatArray,
    record: _IndexArray,
) -> tuple[_FloatArray, _UIntArray, _UIntArray, _UIntArray]:
    """TSNet's MOC time loop over a network laid out as arrays
    (``burstloc.sim.transient.moc_rust``):
    ``(heads, junction_failed, dead_failed, element_warnings)``."""
