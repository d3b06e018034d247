"""Burst signatures from the hydraulic model: offline, once per network (WNTR/EPANET).

A pipe's *signature* at a position ``x`` along it is the vector of steady-state head drops at the
meters caused by a reference burst (an emitter) at ``x``: what the signature localizer
(:class:`burstloc.localize.signature.SignatureLocalizer`) matches the observed lasting drop to.
:func:`compute_signatures` runs one EPANET steady state (pressure-driven demand, the engine TSNet
initialises from) for the base state and one per pipe, in one EPANET project edited in place
(:mod:`burstloc.sim.signatures.epanet_inplace`);
:func:`cached_signatures` / :func:`cached_signature_sets` keep the result on disk (one
``.npz`` file per position in burstloc's cache directory). On large networks
:func:`linear_signature_sets` takes them from one factorization of the linearized steady state
(:mod:`burstloc.sim.signatures.linear`), alone or anchored on an exact mid-pipe drop per pipe.

Only ``burstloc calibrate`` and the experiments call this: the stored configuration carries the
signatures (:class:`burstloc.localize.model.LocalizationModel`), so the live path never runs it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from functools import partial
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from burstloc._diagnostics import capture_diagnostics
from burstloc.constants import (
    CANDIDATE_POSITIONS,
    EXACT_SIGNATURES_UP_TO,
    HYBRID_SIGNATURES_UP_TO,
)
from burstloc.exceptions import ConfigError, InputError, SimulationError
from burstloc.inp import check_meters
from burstloc.localize.signature import SIGNATURE_FORMAT, SignatureSet
from burstloc.network import Network, NetworkSource, SteadyState, as_network, steady_state
from burstloc.sim.scenarios.cache import cache_key, default_cache_dir, drop_corrupt
from burstloc.sim.signatures.epanet_inplace import InPlaceSplitter

__all__ = [
    "DEFAULT_BURST_COEFF",
    "SIGNATURE_METHODS",
    "DemandModel",
    "SignatureMethod",
    "cached_signature_sets",
    "cached_signatures",
    "compute_signatures",
    "linear_signature_sets",
    "signature_method",
]

DEFAULT_BURST_COEFF = 0.01
"""Emitter coefficient (m^3/s per m^0.5, TSNet's burst coefficient unit) of the reference burst.

Only the shape of a signature matters (the fit has a free scale); the reference burst is kept
moderate so that the drop stays in the near-linear range of the network's response."""

DemandModel = Literal["pdd", "emitter"]
"""How consumer demands respond to the burst's pressure drop in the steady-state runs: WNTR's
pressure-driven demand (``"pdd"``, TSNet's initialiser) or TSNet's transient demand law
``q = c * sqrt(p)`` (``"emitter"``, each demand becomes an emitter fitted at the base state)."""

SignatureMethod = Literal["auto", "epanet", "hybrid", "linear"]
"""How the signatures are computed: ``"epanet"`` one EPANET steady state per pipe and position
(exact, for the reference burst), ``"linear"`` one factorization of the linearized steady state
(:mod:`burstloc.sim.signatures.linear`: exact for a small burst, the shape of a large one
approximated; seconds on any network), ``"hybrid"`` the exact mid-pipe drop and the linearized
change along the pipe (:func:`linear_signature_sets`), ``"auto"`` by size
(:func:`signature_method`)."""

SIGNATURE_METHODS = ("auto", "epanet", "hybrid", "linear")


def compute_signatures(
    network: NetworkSource,
    meters: Sequence[str] | None = None,
    *,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    position: float = 0.5,
    demand_model: DemandModel = "pdd",
) -> SignatureSet:
    """Burst signatures of every pipe of ``network`` at ``meters`` (default: every junction).

    One EPANET steady-state run for the base state and one per pipe with the pipe split at
    ``position`` and an emitter of coefficient ``burst_coeff`` at the new junction, all in one
    EPANET project edited in place (:class:`burstloc.sim.signatures.epanet_inplace.InPlaceSplitter`:
    no copy
    of the model per pipe). Pipe end nodes are oriented in the base state's flow direction (a
    pipe with negative flow is reversed); ``baseline`` holds :func:`burstloc.network.steady_state`'s
    heads.

    Raises:
        ConfigError: a bad ``burst_coeff``, ``position`` or ``demand_model``.
        NetworkError: missing or malformed network, or a meter that is not a junction.
        InputError: no meter.
    """
    _check_params(burst_coeff, [position], demand_model)
    read = as_network(network)
    wn, state, meter_list = _base_state(read, meters, demand_model)
    matrix = _split_matrix(wn, meter_list, position, burst_coeff)
    return _signature_set(read, wn, state, meter_list, matrix, burst_coeff, position, demand_model)


def linear_signature_sets(
    network: NetworkSource,
    meters: Sequence[str] | None = None,
    *,
    positions: Sequence[float] = CANDIDATE_POSITIONS,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    demand_model: DemandModel = "pdd",
    method: Literal["linear", "hybrid"] = "linear",
    workers: int | None = None,
) -> tuple[SignatureSet, ...]:
    """:func:`compute_signatures`' sets at every position of ``positions`` from one
    factorization of the linearized steady state (:mod:`burstloc.sim.signatures.linear`).

    ``"linear"``: one EPANET run and one sparse solve per meter, however many pipes.
    ``"hybrid"``: also one EPANET steady state per pipe at mid-pipe (:func:`compute_signatures`
    at 0.5: the reference burst's own drop, its non-linear part included); at another position
    ``x`` that drop plus the linearized change from mid-pipe to ``x``, scaled by the ratio of the
    exact to the linearized mid-pipe drop (a ninth of the exact method's EPANET runs, shared
    among ``workers`` local processes, default one per CPU). ``params`` record the method.

    Raises:
        ConfigError: a bad ``burst_coeff``, position, ``demand_model``, method or ``workers``,
            or no position.
        NetworkError: missing or malformed network, a meter that is not a junction, or a
            singular linearized steady state.
        InputError: no meter.
        SimulationError: EPANET failed on a pipe (hybrid).
    """
    from burstloc.sim.signatures.linear import anchored, burst_signatures, linear_response

    _check_params(burst_coeff, positions, demand_model)
    if method not in ("linear", "hybrid"):
        raise ConfigError(f"unknown linearized signature method {method!r}")
    read = as_network(network)
    wn, state, meter_list = _base_state(read, meters, demand_model)
    pipes = list(wn.pipe_name_list)
    with capture_diagnostics():  # e.g. SciPy's fit of a pump curve, kept off the terminal
        response = linear_response(wn, state, meter_list)
        matrices = [
            burst_signatures(wn, state, response, pipes, float(x), burst_coeff) for x in positions
        ]
        if method == "hybrid":
            exact = _split_matrix_parallel(
                read.path, pipes, meter_list, burst_coeff, demand_model, workers
            )
            middle = burst_signatures(wn, state, response, pipes, 0.5, burst_coeff)
            matrices = [anchored(exact, middle, m) for m in matrices]
    return tuple(
        _signature_set(
            read,
            wn,
            state,
            meter_list,
            matrix,
            burst_coeff,
            float(x),
            demand_model,
            method=method,
        )
        for x, matrix in zip(positions, matrices, strict=True)
    )


def signature_method(method: SignatureMethod, pipes: int) -> Literal["epanet", "hybrid", "linear"]:
    """The method ``method`` stands for on a network of ``pipes`` pipes: ``"auto"`` is
    ``"epanet"`` up to :data:`~burstloc.constants.EXACT_SIGNATURES_UP_TO` pipes, ``"hybrid"``
    up to :data:`~burstloc.constants.HYBRID_SIGNATURES_UP_TO`, ``"linear"`` above.

    Raises:
        ConfigError: an unknown method.
    """
    if method == "auto":
        if pipes <= EXACT_SIGNATURES_UP_TO:
            return "epanet"
        return "hybrid" if pipes <= HYBRID_SIGNATURES_UP_TO else "linear"
    if method not in ("epanet", "hybrid", "linear"):
        raise ConfigError(f"unknown signature method {method!r}; use one of {SIGNATURE_METHODS}")
    return method


def _split_matrix(
    wn: Any,
    meters: list[str],
    position: float,
    burst_coeff: float,
    pipes: Sequence[str] | None = None,
) -> NDArray[np.float64]:
    """The (pipes x meters) head drops of the reference burst at ``position`` along each of
    ``pipes`` (default: every pipe), one EPANET steady state each in one project edited in
    place."""
    pipes = list(wn.pipe_name_list if pipes is None else pipes)
    matrix = np.empty((len(pipes), len(meters)), dtype=np.float64)
    with capture_diagnostics(), InPlaceSplitter(wn) as splitter:
        intact = splitter.heads(meters)
        for i, pipe in enumerate(pipes):
            matrix[i] = intact - splitter.split_heads(pipe, position, burst_coeff, meters)
    return matrix


def _check_params(burst_coeff: float, positions: Sequence[float], demand_model: str) -> None:
    """ConfigError for a bad burst coefficient, position or demand model."""
    if not (math.isfinite(burst_coeff) and burst_coeff > 0):
        raise ConfigError(f"burst_coeff must be > 0, got {burst_coeff}")
    if not positions:
        raise ConfigError("at least one signature position is needed")
    for position in positions:
        if not 0.0 < position < 1.0:
            raise ConfigError(f"position must be strictly between 0 and 1, got {position}")
    if demand_model not in ("pdd", "emitter"):
        raise ConfigError(f"unknown demand model {demand_model!r}; use 'pdd' or 'emitter'")


def _base_state(
    network: Network, meters: Sequence[str] | None, demand_model: str
) -> tuple[Any, SteadyState, list[str]]:
    """The network's WNTR model (:func:`_model`), its steady state, and the checked meters
    (default: every junction)."""
    wn = _model(network, demand_model)
    junctions = list(wn.junction_name_list)
    meter_list = check_meters(junctions if meters is None else meters, junctions, network.path)
    if not meter_list:
        raise InputError("at least one meter is needed")
    return wn, steady_state(wn), list(meter_list)


def _model(network: NetworkSource, demand_model: str) -> Any:
    """A copy of the network's WNTR model (the splitter edits it), its demands turned into
    emitters for ``"emitter"`` (each fitted at the base state)."""
    wn = as_network(network).editable()
    if demand_model == "emitter":
        base = steady_state(wn).heads
        for name in wn.junction_name_list:
            node = wn.get_node(name)
            q0 = sum(ts.base_value for ts in node.demand_timeseries_list)
            pressure = base[name] - node.elevation
            if q0 > 0 and pressure > 0:
                node.emitter_coefficient = q0 / math.sqrt(pressure)
            for ts in node.demand_timeseries_list:
                ts.base_value = 0.0
    return wn


def _split_matrix_parallel(
    network: str,
    pipes: list[str],
    meters: list[str],
    burst_coeff: float,
    demand_model: str,
    workers: int | None,
) -> NDArray[np.float64]:
    """:func:`_split_matrix` at mid-pipe over ``workers`` local processes (default: one per
    CPU), the pipes in contiguous chunks, each worker with its own EPANET project: the same
    numbers as one process (every run starts from scratch)."""
    from burstloc.sim.scenarios.sweep import sweep

    count = max(1, min(workers or os.cpu_count() or 1, len(pipes)))
    chunks = [list(c) for c in np.array_split(np.array(pipes, dtype=object), 2 * count) if len(c)]
    task = partial(_split_chunk, network, tuple(meters), burst_coeff, demand_model)
    report = sweep(task, chunks, workers=count, progress=False, label=lambda c: f"pipes {c[0]}..")
    if report.failures:
        raise SimulationError("; ".join(report.failure_lines()))
    return np.vstack([r for r in report.results if r is not None])


def _split_chunk(
    network: str, meters: tuple[str, ...], burst_coeff: float, demand_model: str, pipes: list[str]
) -> NDArray[np.float64]:
    """A worker's part of :func:`_split_matrix_parallel`."""
    return _split_matrix(_model(network, demand_model), list(meters), 0.5, burst_coeff, pipes)


def _signature_set(
    network: Network,
    wn: Any,
    state: SteadyState,
    meters: list[str],
    matrix: NDArray[np.float64],
    burst_coeff: float,
    position: float,
    demand_model: str,
    method: str | None = None,
) -> SignatureSet:
    """A :class:`SignatureSet` of ``matrix`` (pipes x meters), pipe ends in the steady flow
    direction (a pipe with negative flow reversed)."""
    endpoints: dict[str, tuple[str, str]] = {}
    for pipe in wn.pipe_name_list:
        link = wn.get_link(pipe)
        a, b = link.start_node_name, link.end_node_name
        endpoints[pipe] = (b, a) if state.flows[pipe] < 0 else (a, b)
    params: dict[str, Any] = {
        "burst_coeff": burst_coeff,
        "position": position,
        "demand_model": demand_model,
    }
    if method is not None:
        params["method"] = method
    return SignatureSet(
        network_hash=network.hash,
        meters=tuple(meters),
        pipes=tuple(wn.pipe_name_list),
        endpoints=endpoints,
        matrix=matrix,
        baseline=np.array([state.heads[m] for m in meters]),
        params=params,
    )


def cached_signatures(
    network: NetworkSource,
    meters: Sequence[str] | None = None,
    *,
    cache_dir: str | os.PathLike[str] | None = None,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    position: float = 0.5,
    demand_model: DemandModel = "pdd",
) -> SignatureSet:
    """:func:`compute_signatures` for every junction, cached on disk, restricted to ``meters``.

    The cache key covers the network file's bytes, the parameters and the package versions
    (:func:`burstloc.sim.scenarios.cache.cache_key`), so an edited network file is recomputed. The
    default
    folder is ``signatures/`` in burstloc's cache directory (``$BURSTLOC_CACHE_DIR``).
    """
    read = as_network(network)
    key = cache_key(
        SIGNATURE_FORMAT,
        {"burst_coeff": burst_coeff, "position": position, "demand_model": demand_model},
        files=[read],
    )
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir() / "signatures"
    path = folder / f"{Path(read.path).stem}-{key[:24]}.npz"
    full: SignatureSet | None = None
    if path.exists():
        try:
            full = SignatureSet.load(path)
        except InputError as exc:
            drop_corrupt(path, str(exc))  # reported, deleted, recomputed
            full = None
    if full is None:
        full = compute_signatures(
            read, burst_coeff=burst_coeff, position=position, demand_model=demand_model
        )
        full.save(path)
    return full if meters is None else full.for_meters(meters)


def cached_signature_sets(
    network: NetworkSource,
    meters: Sequence[str] | None = None,
    *,
    positions: Sequence[float] = CANDIDATE_POSITIONS,
    cache_dir: str | os.PathLike[str] | None = None,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    demand_model: DemandModel = "pdd",
    method: SignatureMethod = "auto",
    workers: int | None = None,
) -> tuple[SignatureSet, ...]:
    """The signature sets at every position of ``positions`` (one set each, same order) by
    ``method`` (:func:`signature_method`): :func:`cached_signatures` for ``"epanet"``,
    :func:`linear_signature_sets` (not cached; the hybrid's EPANET runs over ``workers``
    processes) for ``"hybrid"`` and ``"linear"``.

    Raises:
        ConfigError: no position, a position outside (0, 1), an unknown method.
    """
    if not positions:
        raise ConfigError("at least one signature position is needed")
    read = as_network(network)
    chosen = signature_method(method, len(read.pipes))
    if chosen != "epanet":
        return linear_signature_sets(
            read,
            meters,
            positions=positions,
            burst_coeff=burst_coeff,
            demand_model=demand_model,
            method=chosen,
            workers=workers,
        )
    return tuple(
        cached_signatures(
            read,
            meters,
            cache_dir=cache_dir,
            burst_coeff=burst_coeff,
            position=float(x),
            demand_model=demand_model,
        )
        for x in positions
    )
