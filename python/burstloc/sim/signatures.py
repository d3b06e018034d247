"""Burst signatures from the hydraulic model: offline, once per network (WNTR/EPANET).

A pipe's *signature* at a position ``x`` along it is the vector of steady-state head drops at the
meters caused by a reference burst (an emitter) at ``x``: what the signature localizer
(:class:`burstloc.localize.signature.SignatureLocalizer`) matches the observed lasting drop to.
:func:`compute_signatures` runs one EPANET steady state (pressure-driven demand, the engine TSNet
initialises from) for the base state and one per pipe, in one EPANET project edited in place
(:mod:`burstloc.sim.epanet_inplace`);
:func:`cached_signatures` / :func:`cached_signature_sets` keep the result on disk (one
``.npz`` file per position in burstloc's cache directory).

Only ``burstloc calibrate`` and the experiments call this: the stored configuration carries the
signatures (:class:`burstloc.localize.model.LocalizationModel`), so the live path never runs it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import numpy as np

from burstloc._diagnostics import capture_diagnostics
from burstloc.constants import CANDIDATE_POSITIONS
from burstloc.exceptions import ConfigError, InputError
from burstloc.inp import check_meters, network_hash
from burstloc.localize.signature import SIGNATURE_FORMAT, SignatureSet
from burstloc.network import load_network, steady_state
from burstloc.sim.cache import cache_key, default_cache_dir, drop_corrupt
from burstloc.sim.epanet_inplace import InPlaceSplitter

__all__ = [
    "DEFAULT_BURST_COEFF",
    "DemandModel",
    "cached_signature_sets",
    "cached_signatures",
    "compute_signatures",
]

DEFAULT_BURST_COEFF = 0.01
"""Emitter coefficient (m^3/s per m^0.5, TSNet's burst coefficient unit) of the reference burst.

Only the shape of a signature matters (the fit has a free scale); the reference burst is kept
moderate so that the drop stays in the near-linear range of the network's response."""

DemandModel = Literal["pdd", "emitter"]
"""How consumer demands respond to the burst's pressure drop in the steady-state runs: WNTR's
pressure-driven demand (``"pdd"``, TSNet's initialiser) or TSNet's transient demand law
``q = c * sqrt(p)`` (``"emitter"``, each demand becomes an emitter fitted at the base state)."""


def compute_signatures(
    network: str | os.PathLike[str],
    meters: Sequence[str] | None = None,
    *,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    position: float = 0.5,
    demand_model: DemandModel = "pdd",
) -> SignatureSet:
    """Burst signatures of every pipe of ``network`` at ``meters`` (default: every junction).

    One EPANET steady-state run for the base state and one per pipe with the pipe split at
    ``position`` and an emitter of coefficient ``burst_coeff`` at the new junction, all in one
    EPANET project edited in place (:class:`burstloc.sim.epanet_inplace.InPlaceSplitter`: no copy
    of the model per pipe). Pipe end nodes are oriented in the base state's flow direction (a
    pipe with negative flow is reversed); ``baseline`` holds :func:`burstloc.network.steady_state`'s
    heads.

    Raises:
        ConfigError: a bad ``burst_coeff``, ``position`` or ``demand_model``.
        NetworkError: missing or malformed network, or a meter that is not a junction.
        InputError: no meter.
    """
    if not (math.isfinite(burst_coeff) and burst_coeff > 0):
        raise ConfigError(f"burst_coeff must be > 0, got {burst_coeff}")
    if not 0.0 < position < 1.0:
        raise ConfigError(f"position must be strictly between 0 and 1, got {position}")
    if demand_model not in ("pdd", "emitter"):
        raise ConfigError(f"unknown demand model {demand_model!r}; use 'pdd' or 'emitter'")
    wn = load_network(network)
    junctions = list(wn.junction_name_list)
    meter_list = check_meters(junctions if meters is None else meters, junctions, network)
    if not meter_list:
        raise InputError("at least one meter is needed")
    if demand_model == "emitter":
        base = steady_state(wn).heads
        for name in junctions:
            node = wn.get_node(name)
            q0 = sum(ts.base_value for ts in node.demand_timeseries_list)
            pressure = base[name] - node.elevation
            if q0 > 0 and pressure > 0:
                node.emitter_coefficient = q0 / math.sqrt(pressure)
            for ts in node.demand_timeseries_list:
                ts.base_value = 0.0
    state = steady_state(wn)
    pipes = list(wn.pipe_name_list)
    endpoints: dict[str, tuple[str, str]] = {}
    for pipe in pipes:
        link = wn.get_link(pipe)
        a, b = link.start_node_name, link.end_node_name
        endpoints[pipe] = (b, a) if state.flows[pipe] < 0 else (a, b)
    matrix = np.empty((len(pipes), len(meter_list)), dtype=np.float64)
    with capture_diagnostics(), InPlaceSplitter(wn) as splitter:
        intact = splitter.heads(meter_list)
        for i, pipe in enumerate(pipes):
            matrix[i] = intact - splitter.split_heads(pipe, position, burst_coeff, meter_list)
    return SignatureSet(
        network_hash=network_hash(network),
        meters=tuple(meter_list),
        pipes=tuple(pipes),
        endpoints=endpoints,
        matrix=matrix,
        baseline=np.array([state.heads[m] for m in meter_list]),
        params={"burst_coeff": burst_coeff, "position": position, "demand_model": demand_model},
    )


def cached_signatures(
    network: str | os.PathLike[str],
    meters: Sequence[str] | None = None,
    *,
    cache_dir: str | os.PathLike[str] | None = None,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    position: float = 0.5,
    demand_model: DemandModel = "pdd",
) -> SignatureSet:
    """:func:`compute_signatures` for every junction, cached on disk, restricted to ``meters``.

    The cache key covers the network file's bytes, the parameters and the package versions
    (:func:`burstloc.sim.cache.cache_key`), so an edited network file is recomputed. The default
    folder is ``signatures/`` in burstloc's cache directory (``$BURSTLOC_CACHE_DIR``).
    """
    key = cache_key(
        SIGNATURE_FORMAT,
        {"burst_coeff": burst_coeff, "position": position, "demand_model": demand_model},
        files=[network],
    )
    folder = Path(cache_dir) if cache_dir is not None else default_cache_dir() / "signatures"
    path = folder / f"{Path(network).stem}-{key[:24]}.npz"
    full: SignatureSet | None = None
    if path.exists():
        try:
            full = SignatureSet.load(path)
        except InputError as exc:
            drop_corrupt(path, str(exc))  # reported, deleted, recomputed
            full = None
    if full is None:
        full = compute_signatures(
            network, burst_coeff=burst_coeff, position=position, demand_model=demand_model
        )
        full.save(path)
    return full if meters is None else full.for_meters(meters)


def cached_signature_sets(
    network: str | os.PathLike[str],
    meters: Sequence[str] | None = None,
    *,
    positions: Sequence[float] = CANDIDATE_POSITIONS,
    cache_dir: str | os.PathLike[str] | None = None,
    burst_coeff: float = DEFAULT_BURST_COEFF,
    demand_model: DemandModel = "pdd",
) -> tuple[SignatureSet, ...]:
    """:func:`cached_signatures` at every position of ``positions`` (one set each, same order).

    Raises:
        ConfigError: no position, or a position outside (0, 1).
    """
    if not positions:
        raise ConfigError("at least one signature position is needed")
    return tuple(
        cached_signatures(
            network,
            meters,
            cache_dir=cache_dir,
            burst_coeff=burst_coeff,
            position=float(x),
            demand_model=demand_model,
        )
        for x in positions
    )
