"""A perturbed truth: the network the meters hear differs from the model the localizer keeps.

A utility's model is never exact. :class:`TruthPerturbation` says how the *truth* (the
simulated transients the meters hear) departs from the model:

* ``wave_speed_spread`` F: each pipe's wave speed drawn uniformly in ``a (1 ± F)``
  (:func:`pipe_wave_speeds`; TSNet then discretises with each pipe's own speed);
* ``roughness_spread`` F: each pipe's roughness multiplied by a draw of ``U(1 - F, 1 + F)``
  (:func:`perturb_roughness`, on a copy of the WNTR model before it is written for TSNet);
* ``clock_offset`` S: each meter's clock off by a draw of ``N(0, S²)`` s: its readings are
  taken at shifted instants (:func:`shift_clocks`, on the simulated timeline before capture);
* ``silent_meter`` S: one meter sends nothing from S s after the burst starts
  (:func:`silence`: NaN, the monitor's "no reading", :class:`burstloc.readings.Step`'s
  ``filled``).

Every draw comes from a generator seeded by ``(seed, what, name)``: a pipe's or a meter's
draw does not depend on which other pipes or meters there are, so one burst's truth does not
depend on which other bursts are evaluated, and the same seed gives the same truth. The first
two change what is simulated (:meth:`TruthPerturbation.simulated`, part of the scenario's
cache key); the last two are applied when the meters read the simulation.

Pure NumPy (and a WNTR model passed in): no simulator import.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc._validate import FieldError, check_number
from burstloc.exceptions import ConfigError
from burstloc.sim.scenarios.sensors import _stream_id

__all__ = [
    "TruthPerturbation",
    "clock_offsets",
    "perturb_roughness",
    "pipe_wave_speeds",
    "shift_clocks",
    "silence",
]

#: The option each field is set by, as the command line names it (for the errors).
OPTIONS = {
    "wave_speed_spread": "--truth-wave-speed-spread",
    "roughness_spread": "--truth-roughness-spread",
    "clock_offset": "--truth-clock-offset",
    "silent_meter": "--truth-silent-meter",
    "seed": "--truth-seed",
}


@dataclass(frozen=True)
class TruthPerturbation:
    """How the simulated truth departs from the model (every part off by default).

    Attributes:
        wave_speed_spread: F in ``[0, 1)``: each pipe's wave speed uniform in ``a (1 ± F)``.
        roughness_spread: F in ``[0, 1)``: each pipe's roughness times ``U(1 - F, 1 + F)``.
        clock_offset: S >= 0 (s): each meter's clock off by a draw of ``N(0, S²)``.
        silent_meter: ``None``, or S >= 0 (s): the metered junction nearest the burst sends
            nothing from S s after the burst starts.
        seed: seeds every draw (>= 0).

    Raises:
        ConfigError: a value out of range, naming its command-line option.
    """

    wave_speed_spread: float = 0.0
    roughness_spread: float = 0.0
    clock_offset: float = 0.0
    silent_meter: float | None = None
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("wave_speed_spread", "roughness_spread", "clock_offset", "silent_meter"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _number(name, getattr(self, name)))
        for name in ("wave_speed_spread", "roughness_spread"):
            if getattr(self, name) >= 1.0:
                raise ConfigError(f"{OPTIONS[name]} must be in [0, 1), got {getattr(self, name)}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"{OPTIONS['seed']} must be a whole number >= 0, got {self.seed!r}")

    @property
    def active(self) -> bool:
        """Whether the truth differs from the model at all."""
        return self.simulated() is not None or self.heard

    @property
    def heard(self) -> bool:
        """Whether the meters' reading of the simulation is perturbed (clocks, silence)."""
        return self.clock_offset > 0 or self.silent_meter is not None

    def simulated(self) -> TruthPerturbation | None:
        """The part that changes what is simulated (wave speeds, roughness, their seed), or
        ``None`` when nothing simulated changes: what a scenario and its cache key carry."""
        if self.wave_speed_spread == 0 and self.roughness_spread == 0:
            return None
        return replace(self, clock_offset=0.0, silent_meter=None)

    def to_dict(self) -> dict[str, Any]:
        """The fields, for metadata and JSON."""
        return asdict(self)

    def describe(self) -> str:
        """One line for a user, e.g. "wave speeds ±15 % per pipe, clocks off by N(0, 5 ms)"."""
        parts = []
        if self.wave_speed_spread:
            parts.append(f"wave speeds ±{100 * self.wave_speed_spread:g} % per pipe")
        if self.roughness_spread:
            parts.append(f"roughness ±{100 * self.roughness_spread:g} % per pipe")
        if self.clock_offset:
            parts.append(f"meter clocks off by N(0, ({1000 * self.clock_offset:g} ms)²)")
        if self.silent_meter is not None:
            parts.append(
                f"the meter nearest each burst silent {self.silent_meter:g} s after it starts"
            )
        return ", ".join(parts) + f" (seed {self.seed})" if parts else "none"


def _number(name: str, value: Any) -> float:
    """``value`` as a finite number >= 0, else a :class:`ConfigError` naming its option."""
    try:
        return check_number(value, OPTIONS[name], low=0.0)
    except FieldError as exc:
        raise ConfigError(f"{exc.field} {exc.detail}") from None


def _draw(seed: int, what: str, name: str) -> np.random.Generator:
    """The generator of one draw: seeded by ``(seed, what, name)`` only."""
    return np.random.default_rng([seed, _stream_id(f"{what}/{name}")])


def _factor(truth: TruthPerturbation, what: str, spread: float, name: str) -> float:
    return float(_draw(truth.seed, what, name).uniform(1.0 - spread, 1.0 + spread))


def pipe_wave_speeds(
    truth: TruthPerturbation,
    wave_speed: float,
    pipes: Iterable[str],
    aliases: Mapping[str, str] | None = None,
) -> dict[str, float]:
    """Each pipe's wave speed (m/s) in the truth: ``wave_speed`` times its draw of
    ``U(1 - F, 1 + F)``. A pipe named in ``aliases`` draws as the pipe it maps to (the second
    half of a split burst pipe draws as the burst pipe). Empty without a wave-speed spread."""
    spread = truth.wave_speed_spread
    if spread == 0:
        return {}
    aliases = aliases or {}
    return {p: wave_speed * _factor(truth, "wave-speed", spread, aliases.get(p, p)) for p in pipes}


def perturb_roughness(
    truth: TruthPerturbation, wn: Any, aliases: Mapping[str, str] | None = None
) -> dict[str, float]:
    """Multiply each pipe's roughness of the WNTR model ``wn`` (changed in place: pass a copy)
    by its draw of ``U(1 - F, 1 + F)``; return the factors by pipe (empty without a roughness
    spread). ``aliases`` as for :func:`pipe_wave_speeds`."""
    spread = truth.roughness_spread
    if spread == 0:
        return {}
    aliases = aliases or {}
    factors = {}
    for name, pipe in wn.pipes():
        factors[name] = _factor(truth, "roughness", spread, aliases.get(name, name))
        pipe.roughness = float(pipe.roughness) * factors[name]
    return factors


def clock_offsets(truth: TruthPerturbation, meters: Sequence[str]) -> NDArray[np.float64]:
    """Each meter's clock offset (s), a draw of ``N(0, S²)`` per meter (zeros without one)."""
    if truth.clock_offset == 0:
        return np.zeros(len(meters))
    return np.array(
        [truth.clock_offset * _draw(truth.seed, "clock", m).standard_normal() for m in meters]
    )


def shift_clocks(
    time: NDArray[np.float64], heads: NDArray[np.float64], offsets: NDArray[np.float64]
) -> NDArray[np.float64]:
    """The timeline as meters with clocks off by ``offsets`` (s, one per column) read it:
    column ``j`` at time ``t`` holds the head at ``t + offsets[j]`` (linear between simulated
    points; before the start the initial steady state, after the end the last value). The
    capture code (:func:`burstloc.sim.scenarios.capture.capture`) then samples it as ever."""
    shifted = np.array(heads, dtype=np.float64, copy=True)
    for j in np.flatnonzero(offsets):
        shifted[:, j] = np.interp(time + offsets[j], time, heads[:, j])
    return shifted


def silence(
    time: NDArray[np.float64], heads: NDArray[np.float64], column: int, after: float
) -> NDArray[np.float64]:
    """``heads`` with column ``column`` NaN (no reading) from ``after`` (s) on: from the
    simulated instant a reading at ``after`` samples (the last at or before it), so every
    reading from ``after`` on is missing, whatever the capture clock."""
    out = np.array(heads, dtype=np.float64, copy=True)
    first = max(int(np.searchsorted(time, after + 1e-9, side="right")) - 1, 0)
    out[first:, column] = np.nan
    return out


def perturb_model(
    truth: TruthPerturbation, wn: Any, wave_speed: float, aliases: Mapping[str, str]
) -> dict[str, float]:
    """Perturb the WNTR model ``wn`` of a burst's truth (a copy: changed in place) and return
    its pipes' wave speeds (m/s; empty without a wave-speed spread): :func:`perturb_roughness`,
    :func:`pipe_wave_speeds`."""
    perturb_roughness(truth, wn, aliases)
    return pipe_wave_speeds(truth, wave_speed, wn.pipe_name_list, aliases)
