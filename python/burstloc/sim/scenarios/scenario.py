"""Burst scenarios: what to simulate.

A :class:`BurstScenario` names a network file, a pipe and where along it the burst opens, when
it starts, how long it takes to open fully and how large it ends (TSNet's emitter
coefficient); :mod:`burstloc.sim.transient.tsnet` simulates it into a
:class:`~burstloc.sim.scenarios.result.ScenarioResult` (every original junction's head over
time, or the ``recorded`` ones').
The defaults (see ``networks/README.md`` for the reasoning):

========================  =========  ==================================================
``burst_start``           10 s       a steady stretch before the burst at every capture
                                     interval of the paper (0.2 to 10 s)
``opening_time``          1 s        TSNet's documented burst example (``tc = 1``)
``burst_coeff``           0.01       TSNet's documented burst example, m³/s/m^½
``wave_speed``            1200 m/s   TSNet's default, as in the paper
``duration``              220 s      2 x 10 readings after the burst at a 10 s capture
                                     interval (the paper's coarsest, with localization
                                     interval 10), whatever the capture phase
``time_step``             None       TSNet's largest stable step, as in the paper
``engine``                "PDD"      the paper's pressure-driven initial steady state
``solver``                vectorized burstloc's vectorized MOC solver
(:mod:`burstloc.sim.transient.moc`):
                                     TSNet's model and heads, a 20-70x faster solve
========================  =========  ==================================================
"""

from __future__ import annotations

import math
import os
from collections import Counter
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from burstloc import inp
from burstloc.constants import SCENARIO_DURATION, WAVE_SPEED
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.network import Network, NetworkSource
from burstloc.sim.scenarios.cache import network_cache_key
from burstloc.sim.scenarios.perturb import TruthPerturbation
from burstloc.wave_speeds import WaveSpeeds

__all__ = [
    "DEFAULT_BURST_COEFF",
    "DEFAULT_BURST_START",
    "DEFAULT_OPENING_TIME",
    "FRICTION_MODELS",
    "SOLVERS",
    "BurstScenario",
    "burst_scenarios",
    "check_solver",
]


DEFAULT_BURST_START = 10.0


DEFAULT_OPENING_TIME = 1.0


DEFAULT_BURST_COEFF = 0.01


#: Cache namespace; bump when a change changes what a scenario simulates (2: supply junctions
# : are fixed inflows, :func:`burstloc.sim.transient.tsnet_ready.add_supply_boundaries`; 3: every
# pipe keeps
#: the friction factor of its steady head loss above TSNet's cap, pipes EPANET closes become
#: closed valves, EPANET's steady state solved to at least 1000 trials: Anytown's bursts change).
SCHEMA = "burst-scenario/3"


_ENGINES = ("PDD", "DD")


#: TSNet's friction models (``MOCSimulator(friction=...)``); "steady" is TSNet's default.
FRICTION_MODELS = ("steady", "quasi-steady", "unsteady")


# : The transient solvers: burstloc's vectorized MOC solver (:mod:`burstloc.sim.transient.moc`,
# steady
#: friction; its time loop in Rust), the same solver's time loop as NumPy array operations
#: (``"numpy"``: the same heads to the bit, slower; kept to measure and check the Rust loop)
#: and TSNet's own ``MOCSimulator`` (every friction model; the reference).
SOLVERS = ("vectorized", "numpy", "tsnet")


def check_solver(solver: Any, friction: str) -> None:
    """Refuse an unknown solver, or the vectorized one with a friction model it lacks.

    Raises:
        ConfigError: naming the solver or the friction model.
    """
    if solver not in SOLVERS:
        raise ConfigError(f"solver must be one of {SOLVERS}, got {solver!r}")
    if solver in ("vectorized", "numpy") and friction != "steady":
        raise ConfigError(
            f"the {solver} solver models steady friction only; friction {friction!r} "
            "needs solver 'tsnet'"
        )


def _number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    return number


def _junction_names(names: Any) -> tuple[str, ...]:
    """``recorded`` as a tuple of distinct, non-empty junction names.

    Raises:
        ConfigError: not a non-empty sequence of distinct non-empty strings (named).
    """
    if isinstance(names, str) or not isinstance(names, (list, tuple)) or not names:
        raise ConfigError(f"recorded must be a non-empty list of junction names, got {names!r}")
    bad = [n for n in names if not isinstance(n, str) or not n]
    if bad:
        raise ConfigError(f"recorded must name junctions by non-empty strings, got {bad[0]!r}")
    twice = sorted(n for n, count in Counter(names).items() if count > 1)
    if twice:
        raise ConfigError(f"recorded names junction(s) more than once: {', '.join(twice)}")
    return tuple(names)


@dataclass(frozen=True)
class BurstScenario:
    """One burst: where, when, how large, and how to simulate it.

    Attributes:
        network: path of the EPANET INP file.
        pipe: the pipe that bursts.
        position: where along the pipe, as a fraction of its length from its INP start node,
            strictly between 0 and 1.
        burst_start: when the burst begins to open, s (>= 0).
        opening_time: how long it takes to open fully, s (>= 0; 0 = instantly).
        burst_coeff: the burst's final emitter coefficient, m³/s per m^½ of pressure head
            (TSNet's ``final_burst_coeff``), > 0.
        wave_speed: pressure wave speed in every pipe, m/s, > 0 (but those ``wave_speeds``
            gives).
        wave_speeds: ``None`` (default), or :class:`~burstloc.wave_speeds.WaveSpeeds`: pipes
            (or diameter classes) of their own wave speed; through a transient-ready model
            each merged pipe keeps its pieces' travel time.
        duration: simulated time, s, > ``burst_start``.
        engine: initial steady state: ``"PDD"`` (pressure-driven) or ``"DD"``.
        time_step: TSNet's requested time step, s; ``None`` = TSNet's largest stable step.
            TSNet adjusts it (wave-speed adjustment), see :attr:`ScenarioResult.time_step`.
        friction: TSNet's friction model, one of :data:`FRICTION_MODELS` (default ``"steady"``,
            TSNet's own default and what every scenario used before this field existed).
        min_pipe_length: ``None`` (default) simulates the network as it is; a length (m, > 0)
            simulates its transient-ready model (:func:`burstloc.skeleton.prepare_transient_model`
            keeping every junction): pipes shorter than this are lengthened to it, so TSNet's
            step is at least ``min_pipe_length / (2 wave_speed)``. The burst pipe and meters
            keep their original names.
        solver: the transient solver, one of :data:`SOLVERS` (default ``"vectorized"``; its
            heads are TSNet's, see :mod:`burstloc.sim.transient.moc`; ``"tsnet"`` for the other
            friction
            models).
        truth: ``None`` (default) simulates the network as the model has it; a
            :class:`~burstloc.sim.scenarios.perturb.TruthPerturbation` simulates a perturbed
            truth (per-pipe wave speeds and roughness; only that part is kept: clock offsets
            and a silent meter are applied when the meters read the result).
        recorded: ``None`` (default): the result holds the head of every original junction; a
            tuple of junction names (e.g. the meters): only theirs, in that order. A whole
            network's heads at a fine step are hundreds of MB per burst (L-TOWN at 5 ms: 190
            MB); its 33 meters', 8 MB. The steady start is then checked at those junctions;
            negative pressure is still reported wherever the solver found it.

    Raises:
        ConfigError: a parameter is out of range (the message names it and its value).
    """

    network: str
    pipe: str
    position: float = 0.5
    burst_start: float = DEFAULT_BURST_START
    opening_time: float = DEFAULT_OPENING_TIME
    burst_coeff: float = DEFAULT_BURST_COEFF
    wave_speed: float = WAVE_SPEED
    duration: float = SCENARIO_DURATION
    engine: str = "PDD"
    time_step: float | None = None
    friction: str = "steady"
    min_pipe_length: float | None = None
    solver: str = "vectorized"
    truth: TruthPerturbation | None = None
    wave_speeds: WaveSpeeds | None = None
    recorded: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        def put(name: str, value: Any) -> None:
            object.__setattr__(self, name, value)

        put("network", os.fspath(self.network))
        if not isinstance(self.pipe, str) or not self.pipe:
            raise ConfigError(f"pipe must be a non-empty string, got {self.pipe!r}")
        for name in ("position", "burst_start", "opening_time", "burst_coeff"):
            put(name, _number(name, getattr(self, name)))
        put("wave_speed", _number("wave_speed", self.wave_speed))
        put("duration", _number("duration", self.duration))
        if not 0 < self.position < 1:
            raise ConfigError(f"position must be strictly between 0 and 1, got {self.position}")
        if self.burst_start < 0:
            raise ConfigError(f"burst_start must be >= 0 s, got {self.burst_start}")
        if self.opening_time < 0:
            raise ConfigError(f"opening_time must be >= 0 s, got {self.opening_time}")
        if self.burst_coeff <= 0:
            raise ConfigError(f"burst_coeff must be > 0, got {self.burst_coeff}")
        if self.wave_speed <= 0:
            raise ConfigError(f"wave_speed must be > 0 m/s, got {self.wave_speed}")
        if self.duration <= self.burst_start:
            raise ConfigError(
                f"duration ({self.duration} s) must be longer than burst_start "
                f"({self.burst_start} s)"
            )
        engine = str(self.engine).upper()
        if engine not in _ENGINES:
            raise ConfigError(f"engine must be 'PDD' or 'DD', got {self.engine!r}")
        put("engine", engine)
        if self.friction not in FRICTION_MODELS:
            raise ConfigError(f"friction must be one of {FRICTION_MODELS}, got {self.friction!r}")
        check_solver(self.solver, self.friction)
        if self.time_step is not None:
            put("time_step", _number("time_step", self.time_step))
            if self.time_step <= 0:  # type: ignore[operator]
                raise ConfigError(f"time_step must be > 0 s, got {self.time_step}")
        if self.min_pipe_length is not None:
            put("min_pipe_length", _number("min_pipe_length", self.min_pipe_length))
            if self.min_pipe_length <= 0:  # type: ignore[operator]
                raise ConfigError(f"min_pipe_length must be > 0 m, got {self.min_pipe_length}")
        if self.wave_speeds is not None:
            if not isinstance(self.wave_speeds, WaveSpeeds):
                raise ConfigError(f"wave_speeds must be WaveSpeeds, got {self.wave_speeds!r}")
            put("wave_speeds", self.wave_speeds or None)
        if self.truth is not None:
            if not isinstance(self.truth, TruthPerturbation):
                raise ConfigError(f"truth must be a TruthPerturbation, got {self.truth!r}")
            put("truth", self.truth.simulated())
        if self.recorded is not None:
            put("recorded", _junction_names(self.recorded))

    def parameters(self) -> dict[str, Any]:
        """Every field except the network path (the cache hashes the file's bytes instead).

        The default friction model, ``min_pipe_length=None``, the ``"tsnet"`` solver,
        ``truth=None`` and ``recorded=None`` are left out, so scenarios cached before those
        fields existed keep their keys (TSNet's results); a perturbed truth is keyed by its
        simulated part, wave speeds per pipe by their values.
        """
        params = asdict(self)
        del params["network"]
        if params["friction"] == "steady":
            del params["friction"]
        if params["min_pipe_length"] is None:
            del params["min_pipe_length"]
        if params["solver"] == "tsnet":
            del params["solver"]
        if params["truth"] is None:
            del params["truth"]
        if params["recorded"] is None:
            del params["recorded"]
        else:
            params["recorded"] = list(params["recorded"])
        if self.wave_speeds is None:
            del params["wave_speeds"]
        else:  # keyed by the speeds, not by the file they came from
            params["wave_speeds"] = self.wave_speeds.to_json()
        return params

    def recorded_junctions(self, junctions: Sequence[str]) -> list[str]:
        """The junctions whose heads the result holds: ``recorded``, or every one of
        ``junctions`` (the network's original junctions).

        Raises:
            NetworkError: ``recorded`` names a node that is not one of ``junctions``.
        """
        if self.recorded is None:
            return list(junctions)
        known = set(junctions)
        unknown = [n for n in self.recorded if n not in known]
        if unknown:
            raise NetworkError(
                f"recorded names {len(unknown)} node(s) that are not junctions of "
                f"{self.network}: {', '.join(unknown[:5])}{', ...' if len(unknown) > 5 else ''}"
            )
        return list(self.recorded)

    def cache_key(self) -> str:
        """The scenario's content-addressed cache key.

        Raises:
            NetworkError: the network file does not exist.
        """
        return network_cache_key(SCHEMA, self.parameters(), self.network)


def burst_scenarios(
    network: NetworkSource, pipes: Sequence[str] | None = None, **parameters: Any
) -> list[BurstScenario]:
    """Return one scenario per pipe (all pipes of the network when ``pipes`` is ``None``); a
    scenario names the network's file.

    ``parameters`` are :class:`BurstScenario` fields (``position``, ``duration``, ...).

    Raises:
        NetworkError: missing or malformed file, or a pipe the file does not have.
        ConfigError: a bad parameter.
    """
    if isinstance(network, Network):
        path, known = network.path, list(network.pipes)
    else:
        path, known = os.fspath(network), inp.pipe_names_in_file(network)
    chosen = inp.choose_pipes(known, pipes, path)
    return [BurstScenario(path, pipe, **parameters) for pipe in chosen]
