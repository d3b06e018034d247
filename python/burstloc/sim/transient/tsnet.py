"""The TSNet driver: simulate a :class:`~burstloc.sim.scenarios.scenario.BurstScenario`.

:func:`simulate_burst` splits the pipe with a new junction (:func:`burstloc.network.split_pipe`),
places TSNet's burst there, solves the initial steady state (pressure-driven demand, as the
paper does) and runs the MOC transient simulation: TSNet's model, solved by burstloc's
vectorized solver (:mod:`burstloc.sim.transient.moc`, the default: TSNet's heads, 20-70x faster) or
by TSNet's own ``MOCSimulator`` (``solver="tsnet"``). Results are cached on disk by content
(:mod:`burstloc.sim.scenarios.cache`); :func:`simulate_many` sweeps scenarios over local processes
or a
Dask cluster (:mod:`burstloc.sim.scenarios.sweep`). What does not depend on the burst pipe (the
network,
its steady state, its transient-ready model) is made once per process
(:mod:`burstloc.sim.transient.intact`).
TSNet prints progress, warns on every time step and writes EPANET scratch files into the
working directory. Here its output is captured into the metadata (``warnings``,
``tsnet_messages``, ``negative_pressure_nodes``) and it runs inside a temporary directory: the
working directory is changed for the duration of a simulation, under a process-wide lock, so
simulations in one process run one at a time (TSNet is pure Python, threads would not help).
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc import network
from burstloc._diagnostics import capture_diagnostics
from burstloc.constants import PRESSURE_NOISE
from burstloc.exceptions import ConfigError, NetworkError, SimulationError
from burstloc.sim.scenarios.cache import DiskCache, file_sha256, package_versions
from burstloc.sim.scenarios.perturb import perturb_model
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import SCHEMA, BurstScenario
from burstloc.sim.scenarios.sweep import SweepReport, sweep
from burstloc.sim.transient import _tsnet_compat, moc
from burstloc.sim.transient._tsnet_results import results_by_name
from burstloc.sim.transient.intact import intact
from burstloc.sim.transient.steady import check_steady_start
from burstloc.sim.transient.tsnet_elements import check_steady_state, hold_valves
from burstloc.sim.transient.tsnet_ready import pipe_speeds, prepare_for_tsnet, transient_model

__all__ = [
    "TransientSettings",
    "cached",
    "from_cache",
    "isolated_run",
    "resolve_cache",
    "run_transient",
    "scenario_result",
    "simulate_burst",
    "simulate_many",
    "transient_model",
]


#: TSNet fails on fewer time steps than this.
MIN_STEPS = 10


_TSNET_LOCK = threading.Lock()


def resolve_cache(cache: DiskCache | bool | None) -> DiskCache | None:
    """The cache a ``cache`` argument means: ``True`` the default one, ``False``/``None`` none."""
    if cache is True:
        return DiskCache()
    if cache is False or cache is None:
        return None
    if isinstance(cache, DiskCache):
        return cache
    raise ConfigError(f"cache must be a DiskCache, True or False, got {cache!r}")


def from_cache(store: DiskCache, key: str, scenario: Any) -> ScenarioResult | None:
    """The cached result of ``scenario`` (anything with a ``network``), or ``None``."""
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
        cache: ``True`` = the default :class:`~burstloc.sim.scenarios.cache.DiskCache`; a
        ``DiskCache``;
            ``False``/``None`` = always simulate, store nothing.

    Raises:
        NetworkError: missing or malformed network file, unknown or closed pipe.
        ConfigError: ``time_step`` above TSNet's stability limit for this network, or a
            ``duration`` shorter than TSNet's minimum of 10 time steps.
        SimulationError: TSNet failed, or produced non-finite heads.
        UnsteadyStartError: a junction's head moved more than
            :data:`~burstloc.sim.transient.steady.STEADY_TOLERANCE` before the burst (nothing is
            cached).
        SimulatorMissingError: the simulator (the ``sim`` extra) is not installed.
    """
    return cached(scenario, None, cache, _simulate)


def cached(
    scenario: Any,
    key: str | None,
    cache: DiskCache | bool | None,
    simulate: Callable[[Any], ScenarioResult],
) -> ScenarioResult:
    """``simulate(scenario)``, or its cached result under ``key`` (default
    ``scenario.cache_key()``; ``cache`` as for :func:`simulate_burst`)."""
    store = resolve_cache(cache)
    if store is None:
        return simulate(scenario)
    key = scenario.cache_key() if key is None else key
    hit = from_cache(store, key, scenario)
    if hit is not None:
        return hit
    result = simulate(scenario)
    store.put(key, result.to_arrays())
    return result


@contextlib.contextmanager
def isolated_run() -> Iterator[str]:
    """Hold the TSNet lock and work in a fresh temporary directory (TSNet writes into cwd, and
    EPANET its scratch files: :func:`burstloc.network.epanet_workdir`)."""
    with _TSNET_LOCK, network.epanet_workdir("burstloc-tsnet-") as tmp:
        yield tmp


def _simulate(scenario: BurstScenario) -> ScenarioResult:
    started = time.perf_counter()
    source = os.path.abspath(scenario.network)  # before isolated_run changes directory
    with isolated_run() as tmp, capture_diagnostics() as diag:
        kept = intact(source)  # the steps that do not depend on the pipe: once per process
        wn = kept.wn
        network.require_pipe(wn, scenario.pipe, open_only=True)
        steady = kept.steady(scenario.engine)
        check_steady_state(wn, steady.state, scenario.network)
        flows = steady.state.flows
        true_start, true_end = network.pipe_endpoints(steady.graph, scenario.pipe)
        meters = scenario.recorded_junctions(network.junction_names(wn))
        model, pipe, position, shortened = kept.transient_model(scenario)
        split = network.split_pipe(model, pipe, position)  # a copy: the truth may perturb it
        truth, aliases = scenario.truth, {split.second_pipe: pipe}
        speeds = pipe_speeds(scenario, kept.wn, split.network.pipe_name_list, shortened, aliases)
        drawn = perturb_model(truth, split.network, scenario.wave_speed, aliases) if truth else {}
        for p, a in drawn.items():  # the truth's draw about each pipe's own speed
            speeds[p] = speeds.get(p, scenario.wave_speed) * a / scenario.wave_speed
        prepared = prepare_for_tsnet(split.network, engine=scenario.engine)
        where = f"pipe {scenario.pipe!r} of {scenario.network}"

        def burst(tm: Any) -> None:
            tm.add_burst(
                split.burst_node, scenario.burst_start, scenario.opening_time, scenario.burst_coeff
            )

        transient = run_transient(
            split.network,
            meters,
            os.path.join(tmp, "scenario.inp"),
            replace(TransientSettings.of(scenario), pipe_speeds=speeds or None),
            burst,
            where=f"{where} split at {scenario.position:g}",
        )
    specific = {
        "true_start": true_start,
        "true_end": true_end,
        "steady_flow_m3s": abs(flows[scenario.pipe]),
        "burst_node": split.burst_node,
        "split_pipes": [split.pipe, split.second_pipe],
        **({} if shortened is None else {"transient_model": shortened.summary()}),
    }
    run = (prepared, started, diag, SCHEMA)
    return scenario_result(scenario, scenario.burst_start, (*transient, meters), run, specific)


def scenario_result(
    scenario: Any,
    onset: float,
    transient: tuple[NDArray[np.float64], NDArray[np.float64], float, list[str]],
    run: tuple[Any, float, Any, str],
    specific: dict[str, Any],
) -> ScenarioResult:
    """A simulation's result, its start checked steady up to ``onset``
    (:func:`~burstloc.sim.transient.steady.check_steady_start`), and the metadata every
    simulation records: the scenario's network (and its fingerprint), parameters and solver,
    what is ``specific`` to its kind, the steady start, how the model was made ready for TSNet,
    the time step, samples and seconds, TSNet's captured output, versions and the schema.

    Args:
        transient: the times, heads, time step and meters of the run.
        run: how the model was made ready for TSNet, when the simulation started
            (``time.perf_counter()``), TSNet's captured output and the schema.

    Raises:
        UnsteadyStartError: the heads moved before ``onset``.
    """
    steps, heads, dt, meters = transient
    prepared, started, diag, schema = run
    start = check_steady_start(steps, heads, meters, onset, scenario.network)
    meta = {
        "network": scenario.network,
        "network_sha256": file_sha256(scenario.network),
        **scenario.parameters(),
        "solver": scenario.solver,
        **specific,
        "steady_start": start.as_metadata(),
        **prepared.as_metadata(),
        "time_step": dt,
        "samples": int(steps.size),
        "head": "pressure head, m (hydraulic head - elevation)",
        "warnings": diag.warnings,
        "negative_pressure_nodes": diag.negative_pressure_nodes(),
        "tsnet_messages": diag.messages,
        "versions": package_versions(),
        "simulation_seconds": round(time.perf_counter() - started, 3),
        "capture_interval": None,
        "capture_phase": None,
        "cache": "miss",
        "schema": schema,
    }
    return ScenarioResult(steps, heads, meters, dt, meta)


@dataclass(frozen=True)
class TransientSettings:
    """How a transient runs: wave speed (m/s), duration (s), requested time step (s, ``None`` =
    TSNet's largest), initial steady state engine, friction model and solver
    (:data:`~burstloc.sim.scenarios.scenario.SOLVERS`); ``pipe_speeds``, the wave speed (m/s)
    of the pipes it names in place of ``wave_speed`` (a perturbed truth,
    :mod:`burstloc.sim.scenarios.perturb`; TSNet discretises with each pipe's own)."""

    wave_speed: float
    duration: float
    time_step: float | None
    engine: str
    friction: str
    solver: str = "vectorized"
    pipe_speeds: Mapping[str, float] | None = None

    @classmethod
    def of(cls, scenario: Any) -> TransientSettings:
        """The settings of a scenario (anything with these five fields)."""
        return cls(
            scenario.wave_speed,
            scenario.duration,
            scenario.time_step,
            scenario.engine,
            scenario.friction,
            scenario.solver,
        )


def run_transient(
    wn: Any,
    meters: Sequence[str],
    inp: str,
    settings: TransientSettings,
    operate: Callable[[Any], None],
    *,
    where: str,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Write ``wn`` to ``inp``, run TSNet on it with ``operate(tm)`` setting up the event, and
    return ``(times, pressure heads of meters (T, M), time step)``. Call inside
    :func:`isolated_run` (TSNet writes into the working directory).

    Raises:
        ConfigError: a time step above TSNet's limit, or too few time steps.
        SimulationError: TSNet failed or produced non-finite heads.
    """
    tm = _run_tsnet(wn, inp, settings, operate, where, meters)
    steps = np.asarray(tm.simulation_timestamps, dtype=np.float64)
    solved = getattr(tm, "burstloc_heads", None)  # burstloc's solvers: the meters come first
    if solved is not None and solved[1][: len(meters)] == list(meters):
        heads = solved[0][:, : len(meters)]  # a view: no copy of the largest array
        if 2 * len(meters) < solved[0].shape[1]:  # a copy, so that the matrix can go
            heads = np.ascontiguousarray(heads)
    else:
        heads = np.column_stack([np.asarray(tm.get_node(j).head, np.float64) for j in meters])
    elevation = np.array([wn.get_node(j).elevation for j in meters], dtype=np.float64)
    if heads.shape[0] != steps.size:
        raise SimulationError(f"the transient simulation produced misshapen heads for {where}")
    broken = [j for j, ok in zip(meters, np.isfinite(heads).all(axis=0), strict=True) if not ok]
    if broken:
        raise SimulationError(
            f"the transient simulation produced non-finite heads for {where} at "
            f"{len(broken)} junction(s) ({', '.join(broken[:5])}"
            f"{', ...' if len(broken) > 5 else ''}){_negative(tm)}"
        )
    heads -= elevation  # (in the solver's matrix, once nothing reads its heads any more)
    return steps, heads, float(tm.time_step)


def _negative(tm: Any) -> str:
    """The junctions of TSNet's model with a negative initial pressure, as a message's end."""
    low = {
        name: float(node.head[0] - node.elevation)
        for name, node in tm.junctions()
        if node.head is not None and node.head[0] - node.elevation < -PRESSURE_NOISE
    }
    if not low:
        return ""
    named = ", ".join(f"{name!r} {p:.3g} m" for name, p in list(low.items())[:5])
    return f"; it cannot start from a negative pressure (EPANET's steady state): {named}"


def _run_tsnet(
    wn: Any,
    inp: str,
    settings: TransientSettings,
    operate: Callable[[Any], None],
    where: str,
    meters: Sequence[str] = (),
) -> Any:
    tsnet = _tsnet_compat.load()
    import wntr  # loaded with the network (burstloc.network), so known to be installed
    from tsnet.network.discretize import max_time_step

    # TSNet's Initializer sets this too; setting it first writes the INP's pressure-driven
    # demand options (required pressure, ...) into the file instead of WNTR's defaults.
    wn.options.hydraulic.demand_model = settings.engine
    wntr.network.write_inpfile(wn, inp, units=wn.options.hydraulic.inpfile_units)
    try:
        tm = tsnet.network.TransientModel(inp)
        tm.set_wavespeed(settings.wave_speed)
        if settings.pipe_speeds:  # those still pipes once prepared for TSNet
            pipes = set(tm.pipe_name_list)
            named = [p for p in settings.pipe_speeds if p in pipes]
            tm.set_wavespeed([settings.pipe_speeds[p] for p in named], pipes=named)
    except Exception as exc:
        raise SimulationError(f"TSNet could not load {where}: {exc}") from exc
    if settings.time_step is not None:
        limit = float(max_time_step(tm))
        if settings.time_step > limit:
            raise ConfigError(
                f"time_step {settings.time_step:g} s exceeds TSNet's stability limit "
                f"{limit:.5g} s for {where}"
            )
    try:
        tm.set_time(settings.duration, settings.time_step)
    except Exception as exc:
        raise SimulationError(f"TSNet could not discretize {where}: {exc}") from exc
    steps = int(settings.duration / tm.time_step)
    if steps < MIN_STEPS:  # TSNet's progress report divides by steps // 10
        raise ConfigError(
            f"duration {settings.duration:g} s is only {steps} time steps of "
            f"{tm.time_step:.5g} s; TSNet needs at least {MIN_STEPS}"
        )
    try:
        operate(tm)
        tm = _initialize(tsnet, tm, settings, where)
        hold_valves(tm)
        if settings.solver in ("vectorized", "numpy"):
            kernel = "rust" if settings.solver == "vectorized" else "numpy"
            return moc.solve(tm, settings.friction, kernel, first=meters)
        return tsnet.simulation.MOCSimulator(tm, results_obj="no", friction=settings.friction)
    except SimulationError as exc:
        raise SimulationError(f"{exc} ({where})") from exc
    except Exception as exc:
        raise SimulationError(f"TSNet failed for {where}: {type(exc).__name__}: {exc}") from exc


def _initialize(tsnet: Any, tm: Any, settings: TransientSettings, where: str = "") -> Any:
    """TSNet's ``Initializer``, its EPANET run over no duration: it reads EPANET's state at the
    start only, and the extended-period run it makes of the model's own duration solves the
    same first step and then every later one (L-TOWN's week at 5 min: 2 016 steps, 0.8 s per
    burst); the duration is restored before the transient runs. Where EPANET cannot solve the
    model pressure-driven it is solved demand-driven, as :func:`burstloc.network.steady_state`
    does (a :class:`~burstloc.exceptions.DemandDrivenWarning`, kept in the scenario's
    ``warnings``). For burstloc's own solvers it
    also runs over a period of two steps: it allocates six result series per pipe and two per
    node over the whole period, which only TSNet's solver fills (about 1 GB on L-TOWN's 32 554
    steps); burstloc's reads their first value, and the period is restored too. It reads EPANET's
    results by name (:func:`burstloc.sim.transient._tsnet_results.results_by_name`)."""
    times = tm.options.time
    duration, period = times.duration, tm.simulation_period
    times.duration = 0
    if settings.solver != "tsnet":
        tm.simulation_period = 2 * tm.time_step
    try:
        with results_by_name():
            try:
                return tsnet.simulation.Initializer(tm, 0.0, settings.engine)
            except Exception as exc:  # EPANET cannot solve it pressure-driven: demand-driven
                if settings.engine.upper() != "PDD" or type(exc).__name__ != "EpanetException":
                    raise
                network.warn_demand_driven(where or "the transient model", exc)
                return tsnet.simulation.Initializer(tm, 0.0, "DD")
    finally:
        times.duration, tm.simulation_period = duration, period


def _simulate_uncached(scenario: BurstScenario) -> ScenarioResult:
    """Worker task: simulate without touching the cache (the parent process stores)."""
    return simulate_burst(scenario, cache=False)


def _key_or_none(scenario: BurstScenario) -> str | None:
    """The cache key, or None when it cannot be made (a missing file fails in the sweep)."""
    try:
        return scenario.cache_key()
    except NetworkError:
        return None


def simulate_many(
    scenarios: Sequence[BurstScenario],
    *,
    cache: DiskCache | bool | None = True,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    shrink: Callable[[BurstScenario, ScenarioResult], ScenarioResult] | None = None,
) -> SweepReport[BurstScenario, ScenarioResult]:
    """Simulate many scenarios: cached ones load here, the rest run in parallel.

    ``shrink(scenario, result)``, if given, is applied here to each result as it is loaded or
    arrives (after it is cached): the report holds what it returns, so a caller can consume
    each result at once and keep a small part of it.

    Uncached scenarios run in local worker processes (``workers``, default the CPU count) or,
    with ``scheduler`` (a Dask scheduler address), on that cluster; each result is stored in
    the cache as soon as it arrives. A failing scenario is reported in the returned
    :class:`~burstloc.sim.scenarios.sweep.SweepReport` with its pipe and error; the others complete.
    Dask workers read the network file at the scenario's path: on a cluster, give a path all
    workers can read (a shared file system).
    """
    store = resolve_cache(cache)
    todo = list(scenarios)
    keys = [_key_or_none(s) if store is not None else None for s in todo]
    results: list[ScenarioResult | None] = []
    for s, key in zip(todo, keys, strict=True):
        cached = from_cache(store, key, s) if store is not None and key is not None else None
        results.append(cached if cached is None or shrink is None else shrink(s, cached))
    missing = [i for i, result in enumerate(results) if result is None]
    if missing:
        _tsnet_compat.load()  # no simulator: one error here, not one failure per scenario

    def store_result(sub: int, scenario: BurstScenario, result: ScenarioResult) -> None:
        index = missing[sub]
        key = keys[index]
        if store is not None and key is not None:
            store.put(key, result.to_arrays())
        results[index] = result if shrink is None else shrink(scenario, result)

    report = sweep(
        _simulate_uncached,
        [todo[i] for i in missing],
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        desc="simulating bursts",
        label=_label,
        on_result=store_result,
        keep=False,  # held in ``results`` (shrunk)
    )
    failures = [replace(f, index=missing[f.index]) for f in report.failures]
    return SweepReport(todo, results, failures)


def _label(scenario: BurstScenario) -> str:
    return f"pipe {scenario.pipe} of {scenario.network}"
