"""Burst scenarios simulated with TSNet: one pipe burst -> every junction's pressure head.

A :class:`BurstScenario` names a network file, a pipe and where along it the burst opens, when
it starts, how long it takes to open fully and how large it ends (TSNet's emitter
coefficient). :func:`simulate_burst` splits the pipe with a new junction
(:func:`burstloc.network.split_pipe`), places TSNet's burst there, solves the initial steady
state (pressure-driven demand, as the paper does) and runs TSNet's MOC transient simulation.
The result holds the pressure head of every *original* junction (the meters; the burst
junction is left out) on TSNet's time grid, with the scenario's metadata.

Results are cached on disk by content (:mod:`burstloc.cache`); :func:`simulate_many` sweeps
scenarios over local processes or a Dask cluster (:mod:`burstloc.sweep`).

TSNet prints progress, warns on every time step and writes EPANET scratch files into the
working directory. Here its output is captured into the metadata (``warnings``,
``tsnet_messages``, ``negative_pressure_nodes``) and it runs inside a temporary directory: the
working directory is changed for the duration of a simulation, under a process-wide lock, so
simulations in one process run one at a time (TSNet is pure Python, threads would not help).

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
========================  =========  ==================================================
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc import capture, network
from burstloc._diagnostics import capture_diagnostics
from burstloc.cache import DiskCache, atomic_write_npz, cache_key, file_sha256, package_versions
from burstloc.exceptions import ConfigError, NetworkError, SimulationError
from burstloc.sweep import SweepReport, sweep

__all__ = [
    "DEFAULT_BURST_COEFF",
    "DEFAULT_BURST_START",
    "DEFAULT_DURATION",
    "DEFAULT_OPENING_TIME",
    "DEFAULT_WAVE_SPEED",
    "BurstScenario",
    "ScenarioResult",
    "burst_scenarios",
    "expected_time_step",
    "output_path",
    "simulate_burst",
    "simulate_many",
]

DEFAULT_BURST_START = 10.0
DEFAULT_OPENING_TIME = 1.0
DEFAULT_BURST_COEFF = 0.01
DEFAULT_WAVE_SPEED = 1200.0
DEFAULT_DURATION = 220.0

#: Cache namespace; bump when a change to this module changes what a scenario simulates.
SCHEMA = "burst-scenario/1"

#: TSNet fails on fewer time steps than this.
MIN_STEPS = 10

_TSNET_LOCK = threading.Lock()
_ENGINES = ("PDD", "DD")
#: TSNet's friction models (``MOCSimulator(friction=...)``); "steady" is TSNet's default.
FRICTION_MODELS = ("steady", "quasi-steady", "unsteady")


def _number(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    return number


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
        wave_speed: pressure wave speed in every pipe, m/s, > 0.
        duration: simulated time, s, > ``burst_start``.
        engine: initial steady state: ``"PDD"`` (pressure-driven) or ``"DD"``.
        time_step: TSNet's requested time step, s; ``None`` = TSNet's largest stable step.
            TSNet adjusts it (wave-speed adjustment), see :attr:`ScenarioResult.time_step`.
        friction: TSNet's friction model, one of :data:`FRICTION_MODELS` (default ``"steady"``,
            TSNet's own default and what every scenario used before this field existed).

    Raises:
        ConfigError: a parameter is out of range (the message names it and its value).
    """

    network: str
    pipe: str
    position: float = 0.5
    burst_start: float = DEFAULT_BURST_START
    opening_time: float = DEFAULT_OPENING_TIME
    burst_coeff: float = DEFAULT_BURST_COEFF
    wave_speed: float = DEFAULT_WAVE_SPEED
    duration: float = DEFAULT_DURATION
    engine: str = "PDD"
    time_step: float | None = None
    friction: str = "steady"

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
        if self.time_step is not None:
            put("time_step", _number("time_step", self.time_step))
            if self.time_step <= 0:  # type: ignore[operator]
                raise ConfigError(f"time_step must be > 0 s, got {self.time_step}")

    def parameters(self) -> dict[str, Any]:
        """Every field except the network path (the cache hashes the file's bytes instead).

        The default friction model is left out, so scenarios cached before the field existed
        keep their keys.
        """
        params = asdict(self)
        del params["network"]
        if params["friction"] == "steady":
            del params["friction"]
        return params

    def cache_key(self) -> str:
        """The scenario's content-addressed cache key.

        Raises:
            NetworkError: the network file does not exist.
        """
        try:
            return cache_key(SCHEMA, self.parameters(), [self.network])
        except FileNotFoundError:
            raise NetworkError(f"network file not found: {self.network}") from None


@dataclass(frozen=True, eq=False)
class ScenarioResult:
    """A simulated burst: pressure heads of the meters over time, and what produced them.

    Attributes:
        time: times, s, shape ``(T,)`` (TSNet's grid, or capture ticks after :meth:`resample`).
        heads: pressure head (hydraulic head minus elevation), m, shape ``(T, M)``.
        junctions: the ``M`` meter junctions (the network's original junctions, INP order).
        time_step: TSNet's time step, s.
        metadata: the scenario's parameters, ``pipe``, ``true_start``/``true_end`` (the pipe's
            ends in steady-state flow direction), ``burst_node``, ``time_step``, captured
            ``warnings``/``tsnet_messages``/``negative_pressure_nodes``, ``versions``,
            ``capture_interval``/``capture_phase`` (``None`` on the simulation grid), ...
    """

    time: NDArray[np.float64]
    heads: NDArray[np.float64]
    junctions: list[str]
    time_step: float
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def pipe(self) -> str:
        """The burst pipe."""
        return str(self.metadata["pipe"])

    @property
    def true_endpoints(self) -> tuple[str, str]:
        """The burst pipe's ``(start, end)`` in steady-state flow direction."""
        return str(self.metadata["true_start"]), str(self.metadata["true_end"])

    def resample(self, capture_interval: float, phase: float = 0.0) -> ScenarioResult:
        """Return the readings meters would transmit every ``capture_interval`` seconds.

        See :func:`burstloc.capture.resample` (sample-and-hold; an error if the interval is
        finer than the time step).
        """
        ticks, samples = capture.resample(self.time, self.heads, capture_interval, phase)
        meta = {**self.metadata, "capture_interval": float(capture_interval)}
        meta["capture_phase"] = float(phase)
        return replace(self, time=ticks, heads=samples, metadata=meta)

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The NPZ layout: ``time``, ``heads``, ``junctions`` (str), ``metadata`` (JSON str)."""
        meta = {**self.metadata, "time_step": self.time_step}
        return {
            "time": np.asarray(self.time, dtype=np.float64),
            "heads": np.asarray(self.heads, dtype=np.float64),
            "junctions": np.asarray(self.junctions, dtype=np.str_),
            "metadata": np.asarray(json.dumps(meta, sort_keys=True)),
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> ScenarioResult:
        """Inverse of :meth:`to_arrays`."""
        meta = json.loads(str(arrays["metadata"][()]))
        return cls(
            time=np.asarray(arrays["time"], dtype=np.float64),
            heads=np.asarray(arrays["heads"], dtype=np.float64),
            junctions=[str(j) for j in arrays["junctions"]],
            time_step=float(meta["time_step"]),
            metadata=meta,
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the result as an NPZ file (atomically); readable with plain NumPy."""
        return atomic_write_npz(path, self.to_arrays())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> ScenarioResult:
        """Read a result written by :meth:`save`."""
        with np.load(path, allow_pickle=False) as data:
            return cls.from_arrays({name: data[name] for name in data.files})


def _resolve_cache(cache: DiskCache | bool | None) -> DiskCache | None:
    if cache is True:
        return DiskCache()
    if cache is False or cache is None:
        return None
    if isinstance(cache, DiskCache):
        return cache
    raise ConfigError(f"cache must be a DiskCache, True or False, got {cache!r}")


def _from_cache(store: DiskCache, key: str, scenario: BurstScenario) -> ScenarioResult | None:
    arrays = store.get(key)
    if arrays is None:
        return None
    try:
        result = ScenarioResult.from_arrays(arrays)
    except (KeyError, ValueError):
        return None
    result.metadata["network"] = scenario.network
    result.metadata["cache"] = "hit"
    return result


def simulate_burst(
    scenario: BurstScenario, cache: DiskCache | bool | None = True
) -> ScenarioResult:
    """Simulate one burst (or load it from the cache).

    Args:
        scenario: what to simulate.
        cache: ``True`` = the default :class:`~burstloc.cache.DiskCache`; a ``DiskCache``;
            ``False``/``None`` = always simulate, store nothing.

    Raises:
        NetworkError: missing or malformed network file, unknown pipe.
        ConfigError: ``time_step`` above TSNet's stability limit for this network, or a
            ``duration`` shorter than TSNet's minimum of 10 time steps.
        SimulationError: TSNet failed, or produced non-finite heads.
    """
    store = _resolve_cache(cache)
    if store is None:
        return _simulate(scenario)
    key = scenario.cache_key()
    hit = _from_cache(store, key, scenario)
    if hit is not None:
        return hit
    result = _simulate(scenario)
    store.put(key, result.to_arrays())
    return result


@contextlib.contextmanager
def _isolated_run() -> Iterator[str]:
    """Hold the TSNet lock and work in a fresh temporary directory (TSNet writes into cwd)."""
    with _TSNET_LOCK, tempfile.TemporaryDirectory(prefix="burstloc-tsnet-") as tmp:
        previous = os.getcwd()
        os.chdir(tmp)
        try:
            yield tmp
        finally:
            os.chdir(previous)


def _simulate(scenario: BurstScenario) -> ScenarioResult:
    started = time.perf_counter()
    source = os.path.abspath(scenario.network)  # before _isolated_run changes directory
    with _isolated_run() as tmp, capture_diagnostics() as diag:
        wn = network.load_network(source)
        network.require_pipe(wn, scenario.pipe)
        flows = network.steady_state_flows(wn, scenario.engine)
        graph = network.flow_direction_graph(wn, flows)
        true_start, true_end = network.pipe_endpoints(graph, scenario.pipe)
        split = network.split_pipe(wn, scenario.pipe, scenario.position)
        meters = network.junction_names(wn)
        elevation = np.array([wn.get_node(j).elevation for j in meters], dtype=np.float64)
        tm = _run_tsnet(scenario, split, os.path.join(tmp, "scenario.inp"))
        steps = np.asarray(tm.simulation_timestamps, dtype=np.float64)
        heads = np.column_stack([np.asarray(tm.get_node(j).head, np.float64) for j in meters])
        dt = float(tm.time_step)
    elapsed = time.perf_counter() - started

    heads = heads - elevation
    if heads.shape[0] != steps.size or not np.all(np.isfinite(heads)):
        raise SimulationError(
            f"TSNet produced non-finite or misshapen heads for pipe {scenario.pipe!r} of "
            f"{scenario.network}"
        )
    meta: dict[str, Any] = {
        "network": scenario.network,
        "network_sha256": file_sha256(scenario.network),
        **scenario.parameters(),
        "true_start": true_start,
        "true_end": true_end,
        "steady_flow_m3s": abs(flows[scenario.pipe]),
        "burst_node": split.burst_node,
        "split_pipes": [split.pipe, split.second_pipe],
        "time_step": dt,
        "samples": int(steps.size),
        "head": "pressure head, m (hydraulic head - elevation)",
        "warnings": diag.warnings,
        "negative_pressure_nodes": diag.negative_pressure_nodes(),
        "tsnet_messages": diag.messages,
        "versions": package_versions(),
        "simulation_seconds": round(elapsed, 3),
        "capture_interval": None,
        "capture_phase": None,
        "cache": "miss",
        "schema": SCHEMA,
    }
    return ScenarioResult(steps, heads, meters, dt, meta)


def expected_time_step(scenario: BurstScenario) -> float:
    """The time step (s) TSNet will use for ``scenario``, without running TSNet.

    TSNet's discretisation is arithmetic on the pipe lengths of the split network: each pipe
    gets ``N = floor(L / (a dt))`` reaches for the requested step ``dt`` (default: the Courant
    limit ``min L / (2 a)``), and the step becomes ``sum(phi^2) / sum(phi)`` with
    ``phi = L / (a N)`` (its wave-speed adjustment). This reproduces it, so a caller can choose
    ``time_step`` before simulating (e.g. finer than a capture interval).

    Raises:
        NetworkError: the network or pipe cannot be read.
    """
    wn = network.load_network(scenario.network)
    link = network.require_pipe(wn, scenario.pipe)
    lengths = [float(wn.get_link(p).length) for p in network.pipe_names(wn) if p != scenario.pipe]
    lengths += [scenario.position * link.length, (1.0 - scenario.position) * link.length]
    travel = np.array(lengths) / scenario.wave_speed
    dt = float(travel.min() / 2.0) if scenario.time_step is None else float(scenario.time_step)
    reaches = np.floor(travel / dt)
    if np.any(reaches < 1):
        return dt  # TSNet refuses such a step; _run_tsnet reports it
    phi = travel / reaches
    return float(np.sum(phi**2) / np.sum(phi))


def _run_tsnet(scenario: BurstScenario, split: network.SplitPipe, inp: str) -> Any:
    import tsnet
    import wntr
    from tsnet.network.discretize import max_time_step

    # TSNet's Initializer sets this too; setting it first writes the INP's pressure-driven
    # demand options (required pressure, ...) into the split file instead of WNTR's defaults.
    split.network.options.hydraulic.demand_model = scenario.engine
    wntr.network.write_inpfile(
        split.network, inp, units=split.network.options.hydraulic.inpfile_units
    )
    where = f"pipe {scenario.pipe!r} of {scenario.network}"
    try:
        tm = tsnet.network.TransientModel(inp)
        tm.set_wavespeed(scenario.wave_speed)
    except Exception as exc:
        raise SimulationError(f"TSNet could not load {where}: {exc}") from exc
    if scenario.time_step is not None:
        limit = float(max_time_step(tm))
        if scenario.time_step > limit:
            raise ConfigError(
                f"time_step {scenario.time_step:g} s exceeds TSNet's stability limit "
                f"{limit:.5g} s for {where} split at {scenario.position:g}"
            )
    try:
        tm.set_time(scenario.duration, scenario.time_step)
    except Exception as exc:
        raise SimulationError(f"TSNet could not discretize {where}: {exc}") from exc
    steps = int(scenario.duration / tm.time_step)
    if steps < MIN_STEPS:  # TSNet's progress report divides by steps // 10
        raise ConfigError(
            f"duration {scenario.duration:g} s is only {steps} time steps of "
            f"{tm.time_step:.5g} s; TSNet needs at least {MIN_STEPS}"
        )
    try:
        tm.add_burst(
            split.burst_node, scenario.burst_start, scenario.opening_time, scenario.burst_coeff
        )
        tm = tsnet.simulation.Initializer(tm, 0.0, scenario.engine)
        return tsnet.simulation.MOCSimulator(tm, results_obj="no", friction=scenario.friction)
    except Exception as exc:
        raise SimulationError(f"TSNet failed for {where}: {type(exc).__name__}: {exc}") from exc


def burst_scenarios(
    network_path: str | os.PathLike[str], pipes: Sequence[str] | None = None, **parameters: Any
) -> list[BurstScenario]:
    """Return one scenario per pipe (all pipes of the file when ``pipes`` is ``None``).

    ``parameters`` are :class:`BurstScenario` fields (``position``, ``duration``, ...).

    Raises:
        NetworkError: missing or malformed file, or a pipe the file does not have.
        ConfigError: a bad parameter.
    """
    known = network.pipe_names_in_file(network_path)
    chosen = list(known if pipes is None else pipes)
    unknown = [p for p in chosen if p not in known]
    if unknown:
        raise NetworkError(f"unknown pipe(s) {unknown} in {os.fspath(network_path)}")
    if not chosen:
        raise NetworkError(f"no pipes to burst in {os.fspath(network_path)}")
    return [BurstScenario(os.fspath(network_path), pipe, **parameters) for pipe in chosen]


def _simulate_uncached(scenario: BurstScenario) -> ScenarioResult:
    """Worker task: simulate without touching the cache (the parent process stores)."""
    return simulate_burst(scenario, cache=False)


def _key_or_none(scenario: BurstScenario) -> str | None:
    """The cache key, or None when it cannot be made (a missing file fails in the sweep)."""
    try:
        return scenario.cache_key()
    except NetworkError:
        return None


def _label(scenario: BurstScenario) -> str:
    return f"pipe {scenario.pipe} of {scenario.network}"


def simulate_many(
    scenarios: Sequence[BurstScenario],
    *,
    cache: DiskCache | bool | None = True,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
) -> SweepReport[BurstScenario, ScenarioResult]:
    """Simulate many scenarios: cached ones load here, the rest run in parallel.

    Uncached scenarios run in local worker processes (``workers``, default the CPU count) or,
    with ``scheduler`` (a Dask scheduler address), on that cluster; each result is stored in
    the cache as soon as it arrives. A failing scenario is reported in the returned
    :class:`~burstloc.sweep.SweepReport` with its pipe and error; the others complete.
    Dask workers read the network file at the scenario's path: on a cluster, give a path all
    workers can read (a shared file system).
    """
    store = _resolve_cache(cache)
    todo = list(scenarios)
    keys = [_key_or_none(s) if store is not None else None for s in todo]
    results: list[ScenarioResult | None] = [
        _from_cache(store, key, s) if store is not None and key is not None else None
        for s, key in zip(todo, keys, strict=True)
    ]
    missing = [i for i, result in enumerate(results) if result is None]

    def store_result(sub: int, scenario: BurstScenario, result: ScenarioResult) -> None:
        index = missing[sub]
        results[index] = result
        key = keys[index]
        if store is not None and key is not None:
            store.put(key, result.to_arrays())

    report = sweep(
        _simulate_uncached,
        [todo[i] for i in missing],
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="simulating bursts",
        label=_label,
        on_result=store_result,
    )
    failures = [replace(f, index=missing[f.index]) for f in report.failures]
    return SweepReport(todo, results, failures)


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


def output_path(directory: str | os.PathLike[str], result: ScenarioResult) -> Path:
    """Where the CLI writes a scenario: ``DIR/<network stem>_pipe-<pipe>.npz``."""
    stem = Path(str(result.metadata["network"])).stem
    return Path(directory) / f"{_UNSAFE.sub('_', stem)}_pipe-{_UNSAFE.sub('_', result.pipe)}.npz"
