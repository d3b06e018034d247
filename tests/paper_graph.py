"""The upstream part of the paper's network as a flow-direction graph, and change helpers,
shared by the tests of the paper's rules and of its real-time loop."""

from __future__ import annotations

import networkx as nx

from burstloc.localize.evidence import Change


def tnet1_like() -> nx.DiGraph:
    """The upstream part of the paper's network, edges in flow direction.

    R1 -> N3 -> {N4, N2};  N4 -> {N2, N6};  N2 -> {N6, N5};  N6 -> N5
    """
    g = nx.DiGraph()
    for pipe, u, v in [
        ("P1", "R1", "N3"),
        ("P2", "N3", "N4"),
        ("P3", "N3", "N2"),
        ("P5", "N4", "N2"),
        ("P4", "N4", "N6"),
        ("P9", "N2", "N6"),
        ("P6", "N2", "N5"),
        ("P8", "N6", "N5"),
    ]:
        g.add_edge(u, v, pipe=pipe, flow=1.0)
    return g


METERS = ("N2", "N3", "N4", "N5", "N6")


def changes(**amps: float | tuple[float, float]) -> dict[str, list[Change]]:
    """``node=amplitude`` or ``node=(amplitude, start_time)``; every meter present."""
    out: dict[str, list[Change]] = {m: [] for m in METERS}
    for node, a in amps.items():
        amp, start = a if isinstance(a, tuple) else (a, 1.0)
        out[node] = [Change(node, start, amp)]
    return out


MEANS = {"N2": 150.0, "N3": 180.0, "N4": 160.0, "N5": 140.0, "N6": 145.0}
