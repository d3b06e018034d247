"""Prepare the localization model offline: the network facts the ranking localizers need.

:func:`prepare_model` loads the network with WNTR, solves its steady state once for the flow
directions (:func:`burstloc.network.flow_direction_graph`), measures the shortest path lengths
from every pipe's end nodes to the meters (:func:`arrival_geometry`) and takes the burst
signatures (:func:`burstloc.sim.signatures.compute.cached_signature_sets`). The result, a
:class:`burstloc.localize.model.LocalizationModel`, is stored in the configuration that
``burstloc calibrate`` writes; the live monitor only reads it.

:func:`arrival_localizer` and :func:`ranking_localizers` are conveniences for the experiments,
which work from network files: they prepare (signatures cached on disk) and build at once.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import networkx as nx
import numpy as np
from numpy.typing import NDArray

from burstloc.constants import CANDIDATE_POSITIONS, WAVE_SPEED
from burstloc.inp import check_meters
from burstloc.localize.arrival import ArrivalLocalizer
from burstloc.localize.decide import RankingLocalizers
from burstloc.localize.model import LocalizationModel
from burstloc.localize.pipes import PipeGeometry
from burstloc.network import Network, NetworkSource, as_network, flow_direction_graph
from burstloc.sim.signatures.compute import SignatureMethod, cached_signature_sets
from burstloc.wave_speeds import WaveSpeeds, stretch_of

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

__all__ = [
    "arrival_geometry",
    "arrival_localizer",
    "connectors",
    "length_graph",
    "pipe_geometry",
    "prepare_model",
    "ranking_localizers",
    "travel_time_spread",
    "wave_fronts",
]


def length_graph(wn: WaterNetworkModel, stretch: Mapping[str, float] | None = None) -> nx.Graph:
    """Undirected graph of a WNTR model weighted by link length (m).

    Pipes weigh their length; valves and pumps, which have none, weigh 0 (the wave passes them).
    With ``stretch`` (pipe -> metres of wave travel at the model's wave speed per metre of pipe,
    :meth:`burstloc.wave_speeds.WaveSpeeds.stretch`), a pipe weighs its length times its stretch:
    path lengths are then travel times times the model's wave speed.
    Parallel links keep the shortest: edge attributes ``length``, ``link`` (the first shortest
    link in INP order) and ``links`` (every link of that shortest length, which a wave front
    crosses side by side: :func:`wave_fronts`).
    """
    graph = nx.Graph()
    graph.add_nodes_from(wn.node_name_list)
    stretch = stretch or {}
    for name in wn.link_name_list:
        link = wn.get_link(name)
        length = float(getattr(link, "length", 0.0) or 0.0) * stretch.get(name, 1.0)
        u, v = link.start_node_name, link.end_node_name
        if graph.has_edge(u, v):
            edge = graph[u][v]
            if edge["length"] == length:
                edge["links"] = (*edge["links"], name)
            if edge["length"] <= length:
                continue
        graph.add_edge(u, v, length=length, link=name, links=(name,))
    return graph


def travel_time_spread(
    graph: nx.Graph, meters: Sequence[str], wave_speed: float = WAVE_SPEED
) -> float:
    """Largest wave travel time (s) between two meters: how long arrivals keep coming in."""
    best = 0.0
    for m in meters:
        lengths = nx.single_source_dijkstra_path_length(graph, m, weight="length")
        best = max(best, max(float(lengths.get(o, 0.0)) for o in meters))
    return best / wave_speed


def _model_of(network: NetworkSource | WaterNetworkModel) -> WaterNetworkModel:
    """The WNTR model (read only) of a network, an INP file or a WNTR model."""
    if isinstance(network, (Network, str, os.PathLike)):
        return as_network(network).model
    return network


def _meters_of(wn: WaterNetworkModel, meters: Sequence[str] | None) -> list[str]:
    junctions = list(wn.junction_name_list)
    return check_meters(
        junctions if meters is None else meters, junctions, wn.name or "the network"
    )


def pipe_geometry(
    wn: WaterNetworkModel, stretch: Mapping[str, float] | None = None
) -> list[PipeGeometry]:
    """Every pipe's flow-direction end nodes, length (m) and ``stretch`` (:func:`length_graph`;
    1 where not given), in the network's pipe order.

    One EPANET steady state (:func:`burstloc.network.flow_direction_graph`, pressure-driven).
    """
    by_pipe = flow_direction_graph(wn).graph["edges_by_pipe"]
    stretch = stretch or {}
    return [
        PipeGeometry(
            p,
            str(by_pipe[p][0]),
            str(by_pipe[p][1]),
            float(wn.get_link(p).length),
            float(stretch.get(p, 1.0)),
        )
        for p in wn.pipe_name_list
    ]


def connectors(wn: WaterNetworkModel) -> list[tuple[str, str, float]]:
    """The network's links that are not pipes (valves, pumps) as ``(start, end, 0.0)``: where
    the pipes meet across them, at no length, as in :func:`length_graph`
    (:attr:`burstloc.localize.model.LocalizationModel.connectors`)."""
    pipes = set(wn.pipe_name_list)
    return [
        (str(link.start_node_name), str(link.end_node_name), 0.0)
        for name, link in wn.links()
        if name not in pipes
    ]


def arrival_geometry(
    network: NetworkSource | WaterNetworkModel,
    meters: Sequence[str] | None = None,
    stretch: Mapping[str, float] | None = None,
) -> tuple[list[PipeGeometry], dict[str, NDArray[np.float64]]]:
    """Every pipe's flow-direction end nodes and length, and the shortest path lengths (m) from
    those end nodes to each of ``meters`` (default: every junction; ``inf`` without a path);
    with ``stretch`` (pipes of their own wave speed, :func:`length_graph`) the paths are
    weighted by travel time (metres at the model's wave speed).

    One EPANET steady state (:func:`burstloc.network.flow_direction_graph`, pressure-driven).

    Raises:
        NetworkError: missing or malformed network, or a meter that is not a junction.
    """
    wn = _model_of(network)
    meter_list = _meters_of(wn, meters)
    graph = length_graph(wn, stretch)
    pipes = pipe_geometry(wn, stretch)
    per_meter = {
        m: nx.single_source_dijkstra_path_length(graph, m, weight="length") for m in meter_list
    }
    nodes = dict.fromkeys(n for p in pipes for n in (p.start, p.end))  # pipe order: reproducible
    node_distances = {
        n: np.array([float(per_meter[m].get(n, math.inf)) for m in meter_list]) for n in nodes
    }
    return pipes, node_distances


def _link_area(link: Any) -> float:
    """Cross-section (m^2) a wave front crosses in ``link``: 0 when it is closed; a pump, which
    has no diameter, passes the wave (it gets the largest area, :func:`wave_fronts`)."""
    if getattr(link, "initial_status", None) is not None and link.initial_status.name == "Closed":
        return 0.0
    diameter = getattr(link, "diameter", None)
    if diameter is None:
        return math.inf
    return math.pi * float(diameter) ** 2 / 4.0


def wave_fronts(
    wn: WaterNetworkModel,
    meters: Sequence[str],
    pipes: Sequence[PipeGeometry],
    stretch: Mapping[str, float] | None = None,
) -> dict[str, NDArray[np.float64]]:
    """Per pipe, the head step at each meter, relative to the step a burst on the pipe starts,
    of the first wave front to reach it (``fronts[pipe][j]`` for ``meters[j]``).

    The front travels along the shortest path (the one the arrival localizer times, on
    :func:`length_graph`), frictionless; at each node ``k`` it enters from link ``q`` a share
    ``2 A_q / sum(A)`` passes (the junction transmission coefficient of pipes of one wave speed:
    ``A`` the cross-sections of the links at ``k``; 2 at a dead end, where the front doubles); a
    reservoir or tank holds its head (0: nothing passes it), a closed link carries nothing and a
    pump passes the front whole; parallel links of one length carry it side by side (their
    shares add). The front at meter ``m`` for a burst on ``p`` comes through, of
    ``p``'s two end nodes, the one nearer ``m`` (the first front; the larger on a tie): the
    product of the shares along the path, the end node's own share of a front coming from ``p``
    included. Friction, demands, fronts along other paths and the reflections that follow are
    left out: this is the *shape* the arrival localizer compares between meters, not a head in
    metres (:func:`burstloc.localize.windows.silence_counts`). ``stretch``: pipes of their own
    wave speed (:func:`length_graph`); the first front then takes the quickest path.
    """
    graph = length_graph(wn, stretch)
    areas = {name: _link_area(wn.get_link(name)) for name in wn.link_name_list}
    finite = [a for a in areas.values() if math.isfinite(a)]
    widest = max(finite, default=1.0)
    areas = {name: (widest if math.isinf(a) else a) for name, a in areas.items()}
    total: dict[str, float] = {n: 0.0 for n in wn.node_name_list}
    for name in wn.link_name_list:
        link = wn.get_link(name)
        total[link.start_node_name] += areas[name]
        total[link.end_node_name] += areas[name]
    fixed = set(wn.reservoir_name_list) | set(wn.tank_name_list)

    def share(node: str, link: str) -> float:
        if node in fixed or total[node] <= 0:
            return 0.0
        return 2.0 * areas[link] / total[node]

    ends = dict.fromkeys(n for p in pipes for n in (p.start, p.end))
    reach = {n: np.zeros(len(meters)) for n in ends}  # front at meter j of a unit step at n
    far = {n: np.full(len(meters), math.inf) for n in ends}  # and its path length (m)
    for j, meter in enumerate(meters):
        preds, dist = nx.dijkstra_predecessor_and_distance(graph, meter, weight="length")
        front = {meter: 1.0}
        for node in dist:  # in the order Dijkstra settled them: a node's first pred is done
            if node != meter:
                front[node] = max(
                    sum(share(toward, link) for link in graph[node][toward]["links"])
                    * front[toward]
                    for toward in preds[node]
                    if toward in front  # across a 0-length link (pump, valve) ties go both ways
                )
        for n in ends:
            reach[n][j] = front.get(n, 0.0)
            far[n][j] = dist.get(n, math.inf)
    fronts = {}
    for p in pipes:
        start = share(p.start, p.pipe) * reach[p.start]
        end = share(p.end, p.pipe) * reach[p.end]
        # the first front comes through the nearer end (from the pipe's middle); a tie, either
        nearer = np.where(far[p.start] < far[p.end], start, end)
        fronts[p.pipe] = np.where(far[p.start] == far[p.end], np.maximum(start, end), nearer)
    return fronts


def arrival_localizer(
    network: NetworkSource | WaterNetworkModel,
    meters: Sequence[str] | None = None,
    *,
    wave_speed: float = WAVE_SPEED,
    wave_speeds: WaveSpeeds | None = None,
    positions: Iterable[float] = CANDIDATE_POSITIONS,
    **options: Any,
) -> ArrivalLocalizer:
    """An :class:`~burstloc.localize.arrival.ArrivalLocalizer` for ``meters`` (default: every
    junction) of an INP path or a WNTR model, from :func:`arrival_geometry`; ``wave_speeds``:
    pipes of their own speed (the rest run at ``wave_speed``); ``options`` are the
    localizer's other keyword arguments (``amplitude_weight``, ``decision_delay``, ``silence``).

    Raises:
        NetworkError: missing or malformed network, a meter that is not a junction, or wave
            speeds of pipes it does not have.
        ConfigError: a bad wave speed, position or option.
    """
    wn = _model_of(network)
    meter_list = _meters_of(wn, meters)
    stretch = stretch_of(wave_speeds, wn, wave_speed)
    pipes, node_distances = arrival_geometry(wn, meter_list, stretch)
    options.setdefault("fronts", wave_fronts(wn, meter_list, pipes, stretch))
    options.setdefault("connectors", connectors(wn))
    return ArrivalLocalizer(
        pipes, meter_list, node_distances, wave_speed=wave_speed, positions=positions, **options
    )


def prepare_model(
    network: NetworkSource,
    meters: Sequence[str] | None = None,
    *,
    wave_speed: float = WAVE_SPEED,
    wave_speeds: WaveSpeeds | None = None,
    positions: Sequence[float] = CANDIDATE_POSITIONS,
    cache_dir: str | os.PathLike[str] | None = None,
    signatures: SignatureMethod = "auto",
    workers: int | None = None,
) -> LocalizationModel:
    """The :class:`~burstloc.localize.model.LocalizationModel` of ``meters`` (default: every
    junction) on ``network`` (a :class:`~burstloc.network.Network` or its INP file; module
    docstring). ``wave_speeds``: pipes of their own speed (the rest run at ``wave_speed``): the
    paths are timed at each pipe's speed. ``cache_dir``: where the signatures are cached;
    ``signatures``: how they are computed (:data:`burstloc.sim.signatures.compute.SignatureMethod`;
    ``workers``: the local processes of the hybrid method's EPANET runs).

    Raises:
        NetworkError: missing or malformed network, a meter that is not a junction, or wave
            speeds of pipes it does not have.
    """
    read = as_network(network)
    model = read.model
    meter_list = _meters_of(model, meters)
    stretch = stretch_of(wave_speeds, model, wave_speed)
    pipes, node_distances = arrival_geometry(model, meter_list, stretch)
    return LocalizationModel(
        network_hash=read.hash,
        meters=tuple(meter_list),
        pipes=tuple(pipes),
        node_distances=node_distances,
        signature_sets=cached_signature_sets(
            read,
            meter_list,
            positions=positions,
            cache_dir=cache_dir,
            method=signatures,
            workers=workers,
        ),
        wave_speed=wave_speed,
        fronts=wave_fronts(model, meter_list, pipes, stretch),
        connectors=connectors(model),
    )


def ranking_localizers(network: NetworkSource, meters: Sequence[str]) -> RankingLocalizers:
    """The ranking localizers of ``meters`` on ``network`` (``arrival``, ``signature``,
    ``fused``), built from :func:`prepare_model` (the signatures cached on disk).

    Raises:
        NetworkError: missing or malformed network, or a meter that is not a junction.
    """
    return RankingLocalizers.from_model(prepare_model(network, meters))
