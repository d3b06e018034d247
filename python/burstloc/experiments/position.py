"""Position errors in metres: where a burst really was, where it was placed, how far apart.

The ranking localizers name a pipe and, from the arrival fit, a position on it
(:class:`burstloc.localize.pipes.PipePosition`: metres from the pipe's flow-direction start
node, with an interval). ``burstloc evaluate`` scores that position against the simulated burst's
(:func:`true_point`: the scenario's fraction of the pipe from its INP start node) as a *network
distance* (:class:`NetworkDistance`): the shortest path along the pipes between the two points,
the measure the field uses (a burst named on the wrong side of a junction is as far away as the
water has to travel, not as the crow flies). :class:`PositionErrors` summarises a run: mean and
90th percentile of the error over every attempt that gave a position, and how often the true
point lay inside the reported interval (counted only when the named pipe is the burst pipe).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import networkx as nx
import numpy as np

from burstloc._validate import attributes
from burstloc.exceptions import NetworkError
from burstloc.sim.model.prepare import length_graph

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

    from burstloc.experiments.harness import Attempt
    from burstloc.localize.pipes import PipePosition
    from burstloc.sim.scenarios.result import ScenarioResult

__all__ = [
    "NetworkDistance",
    "PipePoint",
    "PositionErrors",
    "PositionOutcome",
    "PositionScorer",
    "estimated_point",
    "score_position",
    "true_point",
    "wave_travel",
]


@dataclass(frozen=True)
class PipePoint:
    """A point on a pipe: ``metres`` along ``pipe`` from its end node ``node``."""

    pipe: str
    node: str
    metres: float


def true_point(result: ScenarioResult, wn: WaterNetworkModel) -> PipePoint:
    """Where a simulated burst opened: metres from the burst pipe's flow-direction start node.

    Raises:
        NetworkError: the result's pipe is not a pipe of ``wn``.
    """
    if result.pipe not in wn.pipe_name_list:
        raise NetworkError(f"pipe {result.pipe!r} is not a pipe of the network")
    link = wn.get_link(result.pipe)
    fraction = float(result.metadata["position"])
    start = result.true_endpoints[0]
    along = fraction if start == link.start_node_name else 1.0 - fraction
    return PipePoint(result.pipe, start, along * float(link.length))


def estimated_point(position: PipePosition) -> PipePoint:
    """The point a localizer's :class:`~burstloc.localize.pipes.PipePosition` names."""
    return PipePoint(position.pipe, position.start, position.metres)


def wave_travel(wn: WaterNetworkModel, wave_speed: float) -> float:
    """A bound (s) on the wave's travel between any two connected nodes of ``wn``: twice the
    longest path length (m) from one node, over ``wave_speed`` (m/s)."""
    graph = length_graph(wn)
    if graph.number_of_nodes() == 0:
        return 0.0
    source = next(iter(graph.nodes))
    reach = nx.single_source_dijkstra_path_length(graph, source, weight="length")
    return 2.0 * max(reach.values()) / wave_speed


class NetworkDistance:
    """Shortest path lengths (m) along the pipes between points on pipes of one network.

    Valves and pumps count as length 0 (:func:`burstloc.sim.model.prepare.length_graph`). Path
    lengths from a node are computed once and kept. With ``stretch`` (pipes of their own wave
    speed: :meth:`burstloc.wave_speeds.WaveSpeeds.stretch`) they are metres of wave travel at
    the model's wave speed, as the localizers time them.
    """

    def __init__(self, wn: WaterNetworkModel, stretch: Mapping[str, float] | None = None) -> None:
        self._graph = length_graph(wn, stretch)
        self._stretch = dict(stretch or {})
        self._ends = {
            p: (wn.get_link(p).start_node_name, wn.get_link(p).end_node_name, wn.get_link(p).length)
            for p in wn.pipe_name_list
        }
        self._from: dict[str, dict[str, float]] = {}

    def _node(self, node: str) -> dict[str, float]:
        if node not in self._from:
            self._from[node] = nx.single_source_dijkstra_path_length(
                self._graph, node, weight="length"
            )
        return self._from[node]

    def _legs(self, point: PipePoint) -> list[tuple[str, float]]:
        """The point's two end nodes with the length along the pipe to each."""
        if point.pipe not in self._ends:
            raise NetworkError(f"pipe {point.pipe!r} is not a pipe of the network")
        start, end, length = self._ends[point.pipe]
        if point.node not in (start, end):
            raise NetworkError(f"node {point.node!r} is not an end of pipe {point.pipe!r}")
        other = end if point.node == start else start
        k = self._stretch.get(point.pipe, 1.0)
        return [(point.node, k * point.metres), (other, k * (float(length) - point.metres))]

    def between_nodes(self, a: str, b: str) -> float:
        """Network distance (m) from node ``a`` to node ``b`` (``inf`` without a path)."""
        return float(self._node(a).get(b, math.inf))

    def to_node(self, point: PipePoint, node: str) -> float:
        """Network distance (m) from ``point`` to the node ``node`` (``inf`` without a path)."""
        return min(to + self._node(end).get(node, math.inf) for end, to in self._legs(point))

    def between(self, a: PipePoint, b: PipePoint) -> float:
        """Network distance (m) from ``a`` to ``b`` (``inf`` when no path joins them)."""
        legs_a, legs_b = self._legs(a), self._legs(b)
        best = math.inf
        if a.pipe == b.pipe:
            best = abs(dict(legs_a)[a.node] - dict(legs_b)[a.node])
        for node_a, to_a in legs_a:
            reach = self._node(node_a)
            for node_b, to_b in legs_b:
                best = min(best, to_a + reach.get(node_b, math.inf) + to_b)
        return best


@dataclass(frozen=True)
class PositionOutcome:
    """One attempt's position against the true point: the network distance ``error`` (m),
    whether the interval held the true point (``inside``, ``None`` when another pipe was named)
    and the interval's ``width`` (m); all ``None`` when the attempt gave no position."""

    error: float | None = None
    inside: bool | None = None
    width: float | None = None


@dataclass(frozen=True)
class PositionErrors:
    """Position errors (m) of a run's attempts: ``count`` attempts gave a position (of
    ``attempts``), with ``mean`` and ``p90`` errors and the intervals' ``mean_width`` (``None``
    without any), and ``interval_hits`` of the ``on_pipe`` positions on the burst pipe held the
    true point inside their interval."""

    attempts: int
    count: int
    mean: float | None
    p90: float | None
    mean_width: float | None
    on_pipe: int
    interval_hits: int

    @classmethod
    def of(cls, outcomes: Iterable[PositionOutcome]) -> PositionErrors:
        """Summarise the outcomes of a run's attempts."""
        items = list(outcomes)
        located = [o for o in items if o.error is not None]
        errors = np.array([o.error for o in located], dtype=np.float64)
        widths = np.array([o.width for o in located], dtype=np.float64)
        flags = [o.inside for o in located if o.inside is not None]
        return cls(
            attempts=len(items),
            count=int(errors.size),
            mean=float(errors.mean()) if errors.size else None,
            p90=float(np.percentile(errors, 90)) if errors.size else None,
            mean_width=float(widths.mean()) if widths.size else None,
            on_pipe=len(flags),
            interval_hits=sum(flags),
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready record (``tests/evaluate_schema.json``, ``position_error_m``)."""
        names = ("attempts", "count", "mean", "p90", "mean_width", "on_pipe", "interval_hits")
        return attributes(self, *names)


def score_position(
    distance: NetworkDistance, truth: PipePoint, position: PipePosition | None
) -> PositionOutcome:
    """One attempt's position against the true point (:class:`PositionOutcome`)."""
    if position is None:
        return PositionOutcome()
    error = distance.between(truth, estimated_point(position))
    width = position.high - position.low
    if position.pipe != truth.pipe:
        return PositionOutcome(error, None, width)
    along = truth.metres if truth.node == position.start else position.length - truth.metres
    inside = bool(position.low - 1e-6 <= along <= position.high + 1e-6)
    return PositionOutcome(error, inside, width)


class PositionScorer:
    """The true burst points of simulated bursts on one network, and the scoring of attempts'
    positions against them (:func:`score_position`)."""

    def __init__(self, wn: WaterNetworkModel, results: Mapping[str, ScenarioResult]) -> None:
        self.distance = NetworkDistance(wn)
        self.points = {p: true_point(r, wn) for p, r in results.items()}
        """Pipe -> where its burst opened."""

    def error(self, truth: PipePoint, position: PipePosition | None) -> float | None:
        """Network distance (m) from a named ``position`` to ``truth`` (``None`` without one)."""
        return score_position(self.distance, truth, position).error

    def score(self, attempts: Mapping[str, Sequence[Attempt]]) -> dict[str, list[PositionOutcome]]:
        """Per pipe, the outcome of each attempt (``attempts[pipe][k]``)."""
        return {
            p: [
                score_position(
                    self.distance,
                    self.points[p],
                    None if a.decision is None else a.decision.position,
                )
                for a in runs
            ]
            for p, runs in attempts.items()
        }
