"""A network's drawing from its INP file: node coordinates, link vertices, kinds (no WNTR).

:func:`read_layout` reads the ``[JUNCTIONS]``, ``[RESERVOIRS]``, ``[TANKS]``, ``[PIPES]``,
``[PUMPS]``, ``[VALVES]``, ``[COORDINATES]`` and ``[VERTICES]`` sections with the same row
reader as :mod:`burstloc.inp` (the file's structure is checked as
:func:`burstloc.inp.pipe_names_in_file` checks it). A node without coordinates is placed at the
mean of its neighbours' (or at the origin when none has any), so every link can be drawn.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from burstloc.inp import _rows, pipe_names_in_file

__all__ = ["Layout", "drawn_lengths", "read_layout"]

Point = tuple[float, float]

_NODE_KINDS = {"[JUNCTIONS]": "junction", "[RESERVOIRS]": "reservoir", "[TANKS]": "tank"}
_LINK_KINDS = {"[PIPES]": "pipe", "[PUMPS]": "pump", "[VALVES]": "valve"}


@dataclass(frozen=True)
class Layout:
    """The drawing of a network: per node its kind and (x, y); per link its kind, end nodes and
    the vertices between them; ``lengths`` of the pipes (m, from the file)."""

    nodes: dict[str, tuple[str, float, float]]
    links: dict[str, tuple[str, str, str, list[tuple[float, float]]]]
    lengths: dict[str, float]

    def to_json(self) -> dict[str, Any]:
        """Compact JSON: ``nodes`` as parallel arrays (``names``, ``kinds``, ``x``, ``y``),
        ``links`` as parallel arrays (``names``, ``kinds``, ``from``/``to`` node indices,
        ``vertices`` as flat [x0, y0, x1, y1, ...] lists, ``length``: a pipe's length, else
        ``null``)."""
        names = list(self.nodes)
        index = {n: i for i, n in enumerate(names)}
        links = list(self.links)
        return {
            "nodes": {
                "names": names,
                "kinds": [self.nodes[n][0] for n in names],
                "x": [self.nodes[n][1] for n in names],
                "y": [self.nodes[n][2] for n in names],
            },
            "links": {
                "names": links,
                "kinds": [self.links[k][0] for k in links],
                "from": [index[self.links[k][1]] for k in links],
                "to": [index[self.links[k][2]] for k in links],
                "vertices": [[c for xy in self.links[k][3] for c in xy] for k in links],
                "length": [self.lengths.get(k) for k in links],
            },
        }

    def line(self, link: str) -> list[Point]:
        """The drawing of ``link`` from its INP start node to its end node (their coordinates
        and the vertices between)."""
        _, a, b, vertices = self.links[link]
        ends = (self.nodes[a][1:], self.nodes[b][1:])
        return [(float(x), float(y)) for x, y in (ends[0], *vertices, ends[1])]

    def nearest_pipe(self, x: float, y: float) -> tuple[str, float, float] | None:
        """The pipe whose drawing passes nearest the point ``(x, y)``: ``(pipe, fraction,
        distance)``, ``fraction`` the share of its drawn length from its INP start node to the
        point's projection (0..1), ``distance`` from the point to it in the drawing's units;
        ``None`` for a network without pipes. Ties go to the pipe listed first."""
        best: tuple[str, float, float] | None = None
        for pipe in self.lengths:
            line = self.line(pipe)
            along = drawn_lengths(line)
            for k, ((x0, y0), (x1, y1)) in enumerate(itertools.pairwise(line)):
                dx, dy = x1 - x0, y1 - y0
                span = dx * dx + dy * dy
                t = 0.0 if span == 0 else min(max(((x - x0) * dx + (y - y0) * dy) / span, 0.0), 1.0)
                gap = math.hypot(x - (x0 + t * dx), y - (y0 + t * dy))
                if best is None or gap < best[2]:
                    share = 0.0 if along[-1] == 0 else (along[k] + t * math.sqrt(span)) / along[-1]
                    best = (pipe, share, gap)
        return best


def drawn_lengths(line: Sequence[Point]) -> list[float]:
    """Cumulative drawn length at each point of ``line``."""
    out = [0.0]
    for (x0, y0), (x1, y1) in itertools.pairwise(line):
        out.append(out[-1] + math.hypot(x1 - x0, y1 - y0))
    return out


def read_layout(path: str | os.PathLike[str]) -> Layout:
    """The drawing of the network in the INP file ``path``.

    Raises:
        NetworkError: the file is missing or malformed (naming file and line).
    """
    path = Path(path)
    pipe_names_in_file(path)  # the structure checks (sections, fields, node references)
    kinds: dict[str, str] = {}
    coords: dict[str, tuple[float, float]] = {}
    links: dict[str, tuple[str, str, str, list[tuple[float, float]]]] = {}
    lengths: dict[str, float] = {}
    for row in _rows(path):
        f = row.fields
        if row.section in _NODE_KINDS:
            kinds[f[0]] = _NODE_KINDS[row.section]
        elif row.section in _LINK_KINDS:
            links[f[0]] = (_LINK_KINDS[row.section], f[1], f[2], [])
            if row.section == "[PIPES]":
                lengths[f[0]] = float(f[3])
        elif row.section == "[COORDINATES]":
            coords[f[0]] = (float(f[1]), float(f[2]))
        elif row.section == "[VERTICES]" and f[0] in links:
            links[f[0]][3].append((float(f[1]), float(f[2])))
    nodes = {n: (k, *coords[n]) for n, k in kinds.items() if n in coords}
    for n, k in kinds.items():
        if n not in nodes:
            near = [
                nodes[b if a == n else a][1:]
                for _, a, b, _ in links.values()
                if n in (a, b) and (b if a == n else a) in nodes
            ]
            x = sum(p[0] for p in near) / len(near) if near else 0.0
            y = sum(p[1] for p in near) / len(near) if near else 0.0
            nodes[n] = (k, x, y)
    return Layout({n: nodes[n] for n in kinds}, links, lengths)
