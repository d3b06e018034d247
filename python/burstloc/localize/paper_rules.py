"""The paper's pipe-burst localization rules (section IV.B, "Pipe burst localization").

Given the changes the detectors found in one window (per meter: start, amplitude) and the
steady-state flow-direction graph (every edge points downstream, edge attribute ``pipe``), the
rules name one pipe:

0. **Trigger node**: among the nodes that alarmed, the one with the largest absolute change
   amplitude (a node's amplitude is its largest ``|amplitude|`` in the window). Ties go to the
   earliest change start, then to the meter order.
1. **Two alarms** (:attr:`Rule.TWO_ALARMS`): if exactly two nodes alarmed and the other one is
   a *neighbour* of the trigger node, the burst pipe is trigger -> neighbour. Neighbours are
   NetworkX's ``DiGraph.neighbors``, i.e. the downstream successors (the paper lists them next
   to the predecessors). Had "neighbour" meant any adjacent node, the outcome would be the same
   pipe: an alarmed predecessor is picked by rule 2 or 3 below.
2. **Single predecessor** (:attr:`Rule.SINGLE_PREDECESSOR`): if the trigger node has exactly
   one predecessor, the pipe is predecessor -> trigger. The predecessor may be a node without a
   meter (N3's only predecessor is the reservoir R1, giving pipe P1).
3. **Alarmed predecessor** (:attr:`Rule.ALARMED_PREDECESSOR`): the alarmed predecessor with the
   largest absolute amplitude (ties: earliest start, then meter order).
4. **Lowest mean pressure** (:attr:`Rule.LOWEST_MEAN_PRESSURE`): the predecessor with the
   lowest mean pressure over the concatenated window (ties: meter order). Predecessors without
   a meter have no readings and are not candidates.

The rules name a pair of nodes; when parallel links join them (the flow-direction graph is a
``MultiDiGraph`` keyed by link name) the pipe named is a pipe before a valve or pump, then the one
with the larger steady flow: the meters cannot tell parallel links apart.

If nothing alarmed, or the trigger node has no predecessor (or several, none metered, none
alarmed), the window decides nothing: :func:`locate` returns ``None``, never a guess.

:class:`burstloc.live.paper_locator.BurstLocator` wires a reading stream, a window detector
(:mod:`burstloc.localize.detection`) and these rules into the real-time loop. Nothing here imports
the simulator.
"""

from __future__ import annotations

import math
from collections.abc import (
    Hashable,
    Iterable,
    Mapping,
    Sequence,
)
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, Protocol

import networkx as nx

from burstloc._validate import attributes
from burstloc.exceptions import NetworkError
from burstloc.localize.evidence import Change
from burstloc.readings import Window

__all__ = [
    "Localization",
    "Rule",
    "WindowDetector",
    "WindowOutcome",
    "locate",
    "node_amplitudes",
    "trigger_node",
]


class Rule(str, Enum):
    """The rule of paper IV.B that decided a localization."""

    TWO_ALARMS = "two_alarms"
    SINGLE_PREDECESSOR = "single_predecessor"
    ALARMED_PREDECESSOR = "alarmed_predecessor"
    LOWEST_MEAN_PRESSURE = "lowest_mean_pressure"


@dataclass(frozen=True)
class Localization:
    """The pipe the rules named, with how and when they named it.

    ``start_node -> end_node`` is the pipe in the steady-state flow direction; ``evidence``
    holds the changes of every alarmed node in the deciding window, ``means`` the mean reading
    per meter over that window (used by :attr:`Rule.LOWEST_MEAN_PRESSURE`).
    """

    pipe: str
    start_node: str
    end_node: str
    trigger_node: str
    rule: Rule
    decision_time: float
    evidence: Mapping[str, tuple[Change, ...]]
    means: Mapping[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """A JSON-ready summary."""
        return {
            **attributes(self, "pipe", "start_node", "end_node", "trigger_node"),
            "rule": self.rule.value,
            "decision_time": self.decision_time,
            "evidence": {
                n: [
                    {
                        "start_time": c.start_time,
                        "alarm_time": c.alarm_time,
                        "end_time": c.end_time,
                        "amplitude": c.amplitude,
                    }
                    for c in cs
                ]
                for n, cs in self.evidence.items()
            },
        }


def _rank(order: Sequence[str] | None, node: str) -> tuple[int, str]:
    if order is not None:
        try:
            return (order.index(node), node)
        except ValueError:
            pass
    return (len(order) if order is not None else 0, node)


def node_amplitudes(changes: Mapping[str, Sequence[Change]]) -> dict[str, float]:
    """The largest absolute change amplitude of every node that alarmed."""
    return {n: max(abs(c.amplitude) for c in cs) for n, cs in changes.items() if cs}


def _earliest(cs: Sequence[Change]) -> float:
    return min(c.start_time for c in cs)


def _strongest(
    nodes: Iterable[str], changes: Mapping[str, Sequence[Change]], order: Sequence[str] | None
) -> str:
    amps = node_amplitudes(changes)
    return min(nodes, key=lambda n: (-amps[n], _earliest(changes[n]), _rank(order, n)))


def trigger_node(
    changes: Mapping[str, Sequence[Change]], order: Sequence[str] | None = None
) -> str | None:
    """The alarmed node with the largest absolute amplitude (ties: earliest start, then order)."""
    alarmed = [n for n, cs in changes.items() if cs]
    if not alarmed:
        return None
    return _strongest(alarmed, changes, order)


def _pipe(graph: nx.DiGraph, u: Hashable, v: Hashable) -> str:
    """The link the rules name for the edge ``u -> v``; of parallel links (a ``MultiDiGraph``
    keyed by link name), a pipe before a valve or pump, then the larger steady flow, then the
    name."""
    data = graph.get_edge_data(u, v)
    if isinstance(graph, nx.MultiDiGraph) and data:
        data = data[
            min(
                data,
                key=lambda k: (
                    data[k].get("link_type", "pipe") != "pipe",
                    -float(data[k].get("flow", 0.0)),
                    str(k),
                ),
            )
        ]
    pipe = (data or {}).get("pipe")
    if pipe is None:
        raise NetworkError(f"edge {u} -> {v} of the flow-direction graph has no 'pipe' attribute")
    return str(pipe)


def locate(
    graph: nx.DiGraph,
    changes: Mapping[str, Sequence[Change]],
    means: Mapping[str, float],
    decision_time: float,
    *,
    order: Sequence[str] | None = None,
) -> Localization | None:
    """Apply the paper's rules to one window's changes; ``None`` when they decide nothing.

    ``changes`` maps each meter to the changes found in the window (meters without a change
    may be absent or map to an empty sequence); ``means`` maps meters to their mean reading
    over the concatenated window; ``order`` (the meter order) breaks ties deterministically.
    """
    alarmed = {n: tuple(cs) for n, cs in changes.items() if cs}
    for n in alarmed:
        if n not in graph:
            raise NetworkError(f"alarmed meter {n!r} is not a node of the flow-direction graph")
    node = trigger_node(alarmed, order)
    if node is None:
        return None

    def found(start: str, end: str, rule: Rule) -> Localization:
        return Localization(
            pipe=_pipe(graph, start, end),
            start_node=str(start),
            end_node=str(end),
            trigger_node=node,
            rule=rule,
            decision_time=float(decision_time),
            evidence=alarmed,
            means=dict(means),
        )

    preds = sorted(graph.predecessors(node), key=lambda n: _rank(order, str(n)))
    if len(alarmed) == 2:
        (other,) = (n for n in alarmed if n != node)
        if other in set(graph.neighbors(node)):
            return found(node, other, Rule.TWO_ALARMS)
    if len(preds) == 1:
        return found(preds[0], node, Rule.SINGLE_PREDECESSOR)
    alarmed_preds = [p for p in preds if p in alarmed]
    if alarmed_preds:
        return found(_strongest(alarmed_preds, alarmed, order), node, Rule.ALARMED_PREDECESSOR)
    metered = [p for p in preds if p in means and math.isfinite(means[p])]
    if metered:
        best = min(metered, key=lambda p: (means[p], _rank(order, str(p))))
        return found(best, node, Rule.LOWEST_MEAN_PRESSURE)
    return None


class WindowDetector(Protocol):
    """What the paper's real-time loop needs from a window detector
    (:mod:`burstloc.localize.detection`)."""

    def detect(self, window: Window) -> dict[str, list[Change]]:
        """The changes found in ``window``, per meter."""
        ...

    def reset(self) -> None:
        """Forget all state (a fresh detector)."""
        ...


@dataclass(frozen=True)
class WindowOutcome:
    """What one window produced: its changes and the localization (``None``: undecided)."""

    window: Window
    changes: dict[str, list[Change]]
    localization: Localization | None
