"""Water distribution networks: load an INP file, its flow-direction graph, split a pipe.

* :func:`read_network` (:mod:`burstloc.network_file`, named here too) reads an EPANET INP file
  once into a :class:`Network` (path, fingerprint, pipes, junctions, WNTR's model); the CLI and
  the public API read the network at their edge and pass it down (:func:`as_network`);
  :func:`load_network` is a model the caller may change (a copy).
* :func:`steady_state` is THE steady-state solver (heads and flows of one EPANET run, solved as
  TSNet's ``Initializer`` solves it: WNTR's EPANET simulator, pressure-driven demand by default,
  demand-driven where EPANET cannot solve it pressure-driven, said by a
  :class:`~burstloc.exceptions.DemandDrivenWarning`; what EPANET warns is captured, never
  printed; EPANET runs in a temporary working directory, where its scratch files go). The
  flow-direction graph and the burst signatures (:mod:`burstloc.sim.signatures.compute`) both use
  it.
* :func:`flow_direction_graph` is the paper's directed graph (section IV.B): one edge per link,
  keyed by the link's name (parallel links are edges of their own), pointing downstream in the
  steady state.
* :func:`split_pipe` cuts a pipe into two at a fraction of its length with a new junction
  between them, where a burst can then be placed (TSNet bursts only at junctions).

This module never imports TSNet: the live path (stream, detectors, localize) uses it. WNTR is
imported on first use. The INP file read as text (structure checks, pipe IDs, fingerprint)
is :mod:`burstloc.inp`.
"""

from __future__ import annotations

import contextlib
import math
import os
import tempfile
import threading
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from burstloc._diagnostics import capture_diagnostics
from burstloc.exceptions import (
    ConfigError,
    DemandDrivenWarning,
    NetworkError,
)
from burstloc.network_file import (
    Network,
    NetworkSource,
    as_network,
    identify,
    import_wntr,
    load_network,
    read_network,
)

if TYPE_CHECKING:
    import networkx as nx
    from wntr.network import WaterNetworkModel

__all__ = [
    "Network",
    "NetworkSource",
    "SplitPipe",
    "SteadyState",
    "as_network",
    "closed_pipes",
    "epanet_workdir",
    "flow_direction_graph",
    "identify",
    "junction_names",
    "load_network",
    "pipe_endpoints",
    "pipe_names",
    "read_network",
    "require_pipe",
    "split_pipe",
    "steady_state",
    "steady_state_flows",
    "warn_demand_driven",
]


def junction_names(wn: WaterNetworkModel) -> list[str]:
    """Return the network's junction names in INP order (the meters of a burst scenario)."""
    return list(wn.junction_name_list)


def pipe_names(wn: WaterNetworkModel) -> list[str]:
    """Return the network's pipe names in INP order."""
    return list(wn.pipe_name_list)


def closed_pipes(wn: WaterNetworkModel) -> list[str]:
    """The pipes whose initial status is Closed (no water flows in them: nothing to burst)."""
    return [name for name, pipe in wn.pipes() if pipe.initial_status.name == "Closed"]


def _source(wn: WaterNetworkModel) -> str:
    name = getattr(wn, "name", None)
    return f" in {name}" if name else ""


def require_pipe(wn: WaterNetworkModel, pipe: str, *, open_only: bool = False) -> Any:
    """Return the WNTR pipe named ``pipe``.

    Raises:
        NetworkError: no pipe has that name (a valve or pump is not a pipe), or, with
            ``open_only``, the pipe is closed in the network file.
    """
    if pipe not in wn.pipe_name_list:
        kind = "a valve or pump, not a pipe" if pipe in wn.link_name_list else "no such pipe"
        raise NetworkError(f"unknown pipe {pipe!r}{_source(wn)}: {kind}")
    link = wn.get_link(pipe)
    if open_only and link.initial_status.name == "Closed":
        raise NetworkError(
            f"pipe {pipe!r}{_source(wn)} is closed (its initial status): no water reaches a "
            "burst on it; choose an open pipe"
        )
    return link


@dataclass(frozen=True)
class SteadyState:
    """A network's steady state at t = 0: ``heads`` per node (m), ``flows`` per link (m³/s,
    sign: INP orientation), ``closed``: the links EPANET reports closed (a closed status, a
    control at the start, a check valve held shut, a pipe at a full or empty tank), ``demands``
    per junction (m³/s delivered; pressure-driven: what the pressure allows), ``active``: the
    valves EPANET reports active (controlling their pressure or flow); ``engine``: the demand
    model EPANET solved it with, ``"PDD"`` or ``"DD"`` (``"DD"`` also where pressure-driven was
    asked for and EPANET could not solve it so: :func:`steady_state`)."""

    heads: dict[str, float]
    flows: dict[str, float]
    closed: frozenset[str] = frozenset()
    demands: dict[str, float] = field(default_factory=dict)
    active: frozenset[str] = frozenset()
    engine: str = "PDD"


_WORKDIR_LOCK = threading.RLock()


@contextlib.contextmanager
def epanet_workdir(prefix: str = "burstloc-epanet-") -> Iterator[str]:
    """Run EPANET in a fresh temporary directory: the working directory for the block (yielded),
    deleted after it with whatever EPANET left there.

    EPANET 2.2's toolkit creates its scratch files (``en`` and six random characters) in the
    working directory and deletes them only when its project is deleted, which WNTR's
    ``EpanetSimulator`` skips when the solver fails (``Error 110``): they stayed in whatever
    directory the caller ran from. The working directory is the process's: blocks are
    serialised (burstloc runs simulations in processes, not threads).
    """
    with _WORKDIR_LOCK, tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        previous = os.getcwd()
        os.chdir(tmp)
        try:
            yield tmp
        finally:
            os.chdir(previous)


def warn_demand_driven(name: str, error: object) -> None:
    """Say (:class:`~burstloc.exceptions.DemandDrivenWarning`) that EPANET cannot solve the
    network ``name`` pressure-driven (``error``: EPANET's) and that its steady state is solved
    demand-driven instead."""
    reason = str(error).replace(" %s", "")  # WNTR's message of EPANET's Error 200 keeps a %s
    warnings.warn(
        f"EPANET cannot solve {name} pressure-driven ({reason}): its steady state is solved "
        "demand-driven instead (every demand met in full, whatever the pressure)",
        DemandDrivenWarning,
        stacklevel=3,
    )


class _UnsolvedError(Exception):
    """EPANET's error (WNTR's ``EpanetException``) solving a steady state."""


def steady_state(wn: WaterNetworkModel, engine: str = "PDD") -> SteadyState:
    """Solve the steady state at t = 0: heads and flows from one EPANET run.

    Solved as TSNet's ``Initializer`` does: WNTR's EPANET simulator with the given demand model
    (``"PDD"`` pressure-driven, ``"DD"`` demand-driven), first time step. Where EPANET cannot
    solve it pressure-driven (e.g. ``(Error 110) cannot solve network hydraulic equations``) but
    can demand-driven, it is solved demand-driven, said by a
    :class:`~burstloc.exceptions.DemandDrivenWarning` naming the network and EPANET's error, and
    recorded in the result's ``engine``. EPANET runs in a temporary working directory
    (:func:`epanet_workdir`: its scratch files never stay behind); what it warns (e.g. "REQUIRED
    PRESSURE raised to 0.1 m") is kept out of the terminal
    (:func:`burstloc._diagnostics.capture_diagnostics`, recorded in a scenario's metadata when
    :mod:`burstloc.sim.transient.tsnet` calls this). ``wn`` is left as it was (its demand model and
    duration are set for the run and restored).

    Raises:
        ConfigError: an unknown ``engine``.
        NetworkError: EPANET cannot solve it (its error code and message; pressure-driven, it
            cannot solve it demand-driven either).
    """
    wntr = import_wntr()

    solved = engine.upper()
    if solved not in ("PDD", "DD"):
        raise ConfigError(f"engine must be 'PDD' or 'DD', got {engine!r}")
    label = getattr(wn, "name", None) or "the network"
    try:
        results = _solve(wntr, wn, solved)
    except _UnsolvedError as exc:
        kind = "pressure-driven" if solved == "PDD" else "demand-driven"
        failed = f"EPANET cannot solve the steady state of {label} ({kind}): {exc}"
        if solved == "DD":
            raise NetworkError(failed) from exc.__cause__
        try:
            results = _solve(wntr, wn, "DD")
        except _UnsolvedError as again:
            raise NetworkError(f"{failed}; demand-driven either: {again}") from again.__cause__
        warn_demand_driven(label, exc)
        solved = "DD"
    heads = results.node["head"].iloc[0]
    flows = results.link["flowrate"].iloc[0]
    demands = results.node["demand"].iloc[0]
    status = results.link["status"].iloc[0]  # WNTR's LinkStatus: 0 closed, 1 open, 2 active
    return SteadyState(
        heads={name: float(heads[name]) for name in wn.node_name_list},
        flows={name: float(flows[name]) for name in wn.link_name_list},
        closed=frozenset(name for name in wn.link_name_list if status[name] == 0),
        demands={name: float(demands[name]) for name in wn.junction_name_list},
        active=frozenset(name for name in wn.link_name_list if status[name] == 2),
        engine=solved,
    )


def _solve(wntr: Any, wn: WaterNetworkModel, engine: str) -> Any:
    """WNTR's EPANET results of ``wn``'s first time step with ``engine``, run in
    :func:`epanet_workdir` (``wn``'s demand model and duration restored after).

    Raises:
        _UnsolvedError: EPANET's own error (WNTR's ``EpanetException``), with its code.
    """
    hydraulic, times = wn.options.hydraulic, wn.options.time
    saved = (hydraulic.demand_model, times.duration)
    hydraulic.demand_model, times.duration = engine, 0
    try:
        with epanet_workdir("burstloc-steady-") as tmp, capture_diagnostics():
            sim = wntr.sim.EpanetSimulator(wn)
            return sim.run_sim(file_prefix=os.path.join(tmp, "steady"))
    except Exception as exc:  # EPANET's own error (WNTR's EpanetException), with its code
        if type(exc).__name__ != "EpanetException":
            raise
        raise _UnsolvedError(str(exc).replace(" %s", "")) from exc  # WNTR's Error 200 has a %s
    finally:
        hydraulic.demand_model, times.duration = saved


def steady_state_flows(wn: WaterNetworkModel, engine: str = "PDD") -> dict[str, float]:
    """Each link's steady-state flow in m³/s (sign: INP orientation): :func:`steady_state`'s
    flows."""
    return steady_state(wn, engine).flows


def flow_direction_graph(
    wn: WaterNetworkModel, flows: dict[str, float] | None = None, engine: str = "PDD"
) -> nx.MultiDiGraph:
    """Return the paper's flow-direction graph (IV.B): every edge points downstream.

    As in the paper, link weights are the signs of the steady-state flows and WNTR's
    ``to_graph(link_weight=..., modify_direction=True)`` turns the links with negative weight
    around. The graph is a networkx ``MultiDiGraph`` keyed by link name, as WNTR's own: parallel
    links (two mains side by side, a pump beside its bypass, a valve beside a pipe) are edges of
    their own (``graph.edges[start, end, link]``). Edge attributes: ``pipe`` (the link name,
    pipes, valves and pumps alike), ``flow`` (|steady-state flow| in m³/s) and ``link_type``. A
    link with zero flow keeps its INP orientation. ``graph.graph["edges_by_pipe"]`` maps each
    link name to its ``(start, end)``.

    Args:
        wn: the network.
        flows: steady-state flows by link (m³/s, INP orientation); solved with ``engine`` when
            omitted (see :func:`steady_state_flows`).
        engine: ``"PDD"`` (the paper's) or ``"DD"``.
    """
    import networkx as nx
    import pandas as pd

    if flows is None:
        flows = steady_state_flows(wn, engine)
    sign = pd.Series({name: float(np.sign(flows[name])) for name in wn.link_name_list})
    multi = wn.to_graph(link_weight=sign, modify_direction=True)
    graph = nx.MultiDiGraph()
    graph.add_nodes_from(multi.nodes(data=True))
    by_pipe: dict[str, tuple[str, str]] = {}
    for start, end, name in multi.edges(keys=True):
        link = wn.get_link(name)
        graph.add_edge(
            start,
            end,
            key=name,
            pipe=name,
            flow=abs(flows[name]),
            link_type=link.link_type.lower(),
        )
        by_pipe[name] = (start, end)
    graph.graph["edges_by_pipe"] = by_pipe
    graph.graph["engine"] = engine.upper()
    return graph


def pipe_endpoints(graph: nx.MultiDiGraph, pipe: str) -> tuple[str, str]:
    """Return ``(start, end)`` of a pipe in steady-state flow direction.

    Raises:
        NetworkError: the graph has no link of that name.
    """
    try:
        return graph.graph["edges_by_pipe"][pipe]
    except KeyError:
        raise NetworkError(f"unknown pipe {pipe!r}: not in the flow-direction graph") from None


@dataclass(frozen=True)
class SplitPipe:
    """A network with one pipe cut in two by a new junction.

    Attributes:
        network: the new network (a copy; the original is unchanged).
        pipe: the original pipe's name; it now names the part from its INP start node to
            ``burst_node``.
        burst_node: the new junction (zero demand, elevation interpolated).
        second_pipe: the new pipe from ``burst_node`` to the original end node.
        fraction: where the junction sits, as a fraction of the length from the INP start node.
    """

    network: WaterNetworkModel
    pipe: str
    burst_node: str
    second_pipe: str
    fraction: float


def _fresh_name(base: str, taken: set[str], fallback: str) -> str:
    # EPANET IDs are at most 31 characters.
    candidate = base if len(base) <= 31 else fallback
    suffix = 0
    while candidate in taken:
        suffix += 1
        candidate = f"{fallback}{suffix}"
    return candidate


def split_pipe(wn: WaterNetworkModel, pipe: str, fraction: float = 0.5) -> SplitPipe:
    """Split ``pipe`` at ``fraction`` of its length (from its INP start node) with a junction.

    The original pipe keeps its name, diameter, roughness and status for the first part; a new
    pipe with the same properties runs from the new junction to the original end node (WNTR's
    ``split_pipe``). Names: junction ``"<pipe>_B"``, pipe ``"<pipe>_2"`` (or ``BURST``/``SPLIT``
    with a counter if taken or longer than EPANET's 31 characters).

    Raises:
        ConfigError: ``fraction`` is not strictly between 0 and 1.
        NetworkError: ``pipe`` is not a pipe of ``wn``.
    """
    wntr = import_wntr()

    if not (isinstance(fraction, (int, float)) and math.isfinite(fraction) and 0 < fraction < 1):
        raise ConfigError(f"position must be strictly between 0 and 1, got {fraction!r}")
    require_pipe(wn, pipe)
    burst_node = _fresh_name(f"{pipe}_B", set(wn.node_name_list), "BURST")
    second = _fresh_name(f"{pipe}_2", set(wn.link_name_list), "SPLIT")
    split = wntr.morph.split_pipe(
        wn, pipe, second, burst_node, add_pipe_at_end=True, split_at_point=float(fraction)
    )
    return SplitPipe(split, pipe, burst_node, second, float(fraction))
