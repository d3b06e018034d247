"""The burst driver: simulate a :class:`~burstloc.sim.scenarios.scenario.BurstScenario`.

:func:`simulate_burst` splits the pipe with a new junction (:func:`burstloc.network.split_pipe`),
places TSNet's burst there, and runs the transient (:mod:`burstloc.sim.transient.tsnet_run`:
the initial steady state, pressure-driven demand as the paper does, then the MOC by burstloc's
vectorized solver, TSNet's heads 20-70x faster, or by TSNet's own ``MOCSimulator``). Results
are cached on disk by content (:mod:`burstloc.sim.scenarios.cache`); :func:`simulate_many`
sweeps scenarios over local processes or a Dask cluster (:mod:`burstloc.sim.scenarios.sweep`).
What does not depend on the burst pipe (the network, its steady state, its transient-ready
model) is made once per process (:mod:`burstloc.sim.transient.intact`). TSNet's output is
captured into the metadata (``warnings``, ``tsnet_messages``, ``negative_pressure_nodes``).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc import network
from burstloc._diagnostics import capture_diagnostics
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.sim.scenarios.cache import DiskCache, file_sha256, package_versions
from burstloc.sim.scenarios.perturb import perturb_model
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import SCHEMA, BurstScenario
from burstloc.sim.scenarios.sweep import SweepReport, sweep
from burstloc.sim.transient import _tsnet_compat
from burstloc.sim.transient.intact import intact
from burstloc.sim.transient.steady import check_steady_start
from burstloc.sim.transient.tsnet_elements import check_steady_state
from burstloc.sim.transient.tsnet_ready import pipe_speeds, prepare_for_tsnet, transient_model
from burstloc.sim.transient.tsnet_run import TransientSettings, isolated_run, run_transient

__all__ = [
    "cached",
    "from_cache",
    "resolve_cache",
    "scenario_result",
    "simulate_burst",
    "simulate_many",
    "transient_model",
]


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
