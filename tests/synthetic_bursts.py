"""Synthetic 'simulations' of a burst on a three-junction network, for the experiments' tests.

No simulator: heads on a 0.05 s grid, each meter dropping by a given amount after a given delay.
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from burstloc.sim.scenarios.result import ScenarioResult

#: The junctions of :func:`synthetic` and :func:`small_graph` (fed from reservoir R1).
METERS = ("A", "B", "C")

#: Where each node is drawn (plots).
POSITIONS = {"R1": (0.0, 0.0), "A": (1.0, 0.0), "B": (2.0, 1.0), "C": (2.0, -1.0)}


def small_graph() -> nx.DiGraph:
    """The flow-direction graph: pA R1->A, pB A->B, pC A->C, pD B->C; nodes carry ``pos``."""
    g = nx.DiGraph()
    for node, pos in POSITIONS.items():
        g.add_node(node, pos=pos)
    for pipe, u, v in [("pA", "R1", "A"), ("pB", "A", "B"), ("pC", "A", "C"), ("pD", "B", "C")]:
        g.add_edge(u, v, pipe=pipe)
    return g


def synthetic(
    pipe: str, drops: dict[str, tuple[float, float]], burst_start: float = 2.0
) -> ScenarioResult:
    """A burst on ``pipe`` over 8 s: meter -> (drop in m, arrival delay in s after the burst)."""
    time = np.arange(0, 8.0 + 1e-9, 0.05)
    heads = np.tile([100.0, 98.0, 97.0], (time.size, 1))
    for j, m in enumerate(METERS):
        drop, delay = drops.get(m, (0.0, 0.0))
        heads[time >= burst_start + delay, j] -= drop
    meta = {"pipe": pipe, "burst_start": burst_start, "true_start": "A", "true_end": "B"}
    return ScenarioResult(time, heads, list(METERS), 0.05, meta)
