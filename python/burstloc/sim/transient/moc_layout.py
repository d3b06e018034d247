"""TSNet's transient model as flat arrays, for the vectorized MOC solver
(:mod:`burstloc.sim.transient.moc`).

TSNet (0.3.1) discretizes every pipe into ``n`` reaches of ``n + 1`` points and, at each time
step, loops over its pipes in Python: the interior points from the two characteristics, each
pipe end from the boundary its topology (``tsnet.network.topology``) assigns. :func:`layout`
reads a model TSNet has initialized (``tsnet.simulation.Initializer``: discretization, adjusted
wave speeds, EPANET's steady state, demand coefficients, pump curves, the event's controls) and
lays it out once, as TSNet's solver would dispatch it, so that a time step is a few array
operations over the whole network:

* every pipe's points in one flat array (pipe ``p`` at ``offset[p] .. offset[p] + n[p]``);
* the interior points with their pipe's constants;
* the pipe ends at junctions (TSNet's ``add_leakage``: every pipe meeting there, its sign and
  the point next to the junction; the burst's emitter and the demand), at dead ends
  (``dead_end``), at reservoirs and tanks ending one pipe (``rev_end``) and at valves leading
  nowhere (``valve_end``: a fixed flow);
* the few pipe ends at pumps and valves between two pipes, and pumps drawing from a reservoir
  (``pump_node``, ``valve_node``, ``source_pump``), which keep TSNet's own functions.

Only what TSNet leaves unsimulated is refused (:class:`~burstloc.exceptions.SimulationError`
naming the pipe): surge tanks and air chambers (burstloc never adds them), a pipe end TSNet
leaves at zero head (a pipe joining two boundaries) and a pump at a branch (TSNet stops there;
:func:`burstloc.sim.transient.tsnet_ready.add_connectors` prevents both).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from burstloc.exceptions import ConfigError, SimulationError
from burstloc.sim.transient import moc_elements
from burstloc.sim.transient.moc_elements import ElementEnd, G

_BOUNDARY_NODES = ("Reservoir", "Tank")

__all__ = ["Layout", "dot_order", "layout"]


@dataclass
class _Group:
    """Pipe ends of one kind, as parallel lists: ``out`` the end's point, ``near`` the point
    next to it in the same pipe, ``pipe`` the pipe's index, ``node`` the node's index (junctions
    and dead ends), ``value`` per kind (a junction end: its pipe's sign there, -1 at the pipe's
    start, +1 at its end; a reservoir or tank: its head; a dead end: its floor, see
    :func:`_floor`), ``series`` a valve end's velocity per step."""

    out: list[int] = field(default_factory=list)
    near: list[int] = field(default_factory=list)
    pipe: list[int] = field(default_factory=list)
    node: list[int] = field(default_factory=list)
    value: list[float] = field(default_factory=list)
    series: list[Any] = field(default_factory=list)


@dataclass
class Layout:
    """A TSNet model laid out for :func:`burstloc.sim.transient.moc.solve` (built by
    :func:`layout`).

    Arrays per pipe (``ga`` = g/a, ``gadt`` = g/a·dt, ``cf`` = f·dt/2/D as TSNet groups it,
    ``cf2`` = f·dt/(2D) as its dead end does, ``area`` as TSNet's junction computes it,
    ``area_dead`` as its dead end does), the flat initial state (``H0``, ``V0``), the groups of
    ends, and ``record``: for every node, the point whose head TSNet reports as the node's.
    """

    dt: float
    steps: int
    pipes: list[Any]
    offset: np.ndarray
    n: np.ndarray
    ga: np.ndarray
    ag: np.ndarray
    gadt: np.ndarray
    theta: np.ndarray
    cf: np.ndarray
    cf2: np.ndarray
    area: np.ndarray
    area_dead: np.ndarray
    H0: np.ndarray
    V0: np.ndarray
    nodes: list[Any]
    emitter: np.ndarray
    demand: np.ndarray
    elevation: np.ndarray
    junction: _Group
    junction_b: np.ndarray
    contributions: dict[str, list[Any]]
    dead_start: _Group
    dead_end: _Group
    rev_start: _Group
    rev_end: _Group
    valve_start: _Group
    valve_end: _Group
    elements: list[ElementEnd]
    record: np.ndarray
    record_nodes: list[Any]


def dot_order(products: list[float]) -> float:
    """``products`` summed as ``np.dot`` sums a strided column with OpenBLAS (TSNet's junction
    sums, measured on every length up to eight): four partial sums, term ``i`` of each full
    block of four into sum ``i % 4``, the remaining terms into the first, then ``(s0 + s1) +
    (s2 + s3)``."""
    acc = [0.0, 0.0, 0.0, 0.0]
    blocked = len(products) - len(products) % 4
    for i, value in enumerate(products):
        acc[i % 4 if i < blocked else 0] += value
    return (acc[0] + acc[1]) + (acc[2] + acc[3])


def _near(offset: int, n: int, sign: int) -> int:
    """The point TSNet reads for a pipe meeting a node: next to its end (sign +1: the pipe ends
    there, TSNet's index -2) or next to its start (sign -1: index 1)."""
    return offset + n - 1 if sign > 0 else offset + 1


class _Builder:
    def __init__(self, tm: Any) -> None:
        from tsnet.network import topology

        self.tm = tm
        self.pipes = [pipe for _, pipe in tm.pipes()]
        for index, pipe in enumerate(self.pipes):
            if int(pipe.id) != index + 1:
                raise SimulationError(f"TSNet numbered pipe {pipe.name!r} out of order")
        self.links1, self.links2, self.utype, self.dtype = topology(tm)
        self.n = np.array([int(p.number_of_segments) for p in self.pipes], dtype=np.int64)
        self.offset = np.concatenate([[0], np.cumsum(self.n + 1)[:-1]]).astype(np.int64)
        self.node_index: dict[str, int] = {}
        self.nodes: list[Any] = []
        self.dt = float(tm.time_step)

    def node(self, node: Any) -> int:
        if node.name not in self.node_index:
            self.node_index[node.name] = len(self.nodes)
            self.nodes.append(node)
        return self.node_index[node.name]

    def near(self, link: int) -> int:
        q = abs(link) - 1
        return _near(int(self.offset[q]), int(self.n[q]), int(np.sign(link)))

    def refuse(self, pn: int, what: str) -> SimulationError:
        return SimulationError(
            f"the vectorized solver cannot simulate pipe {self.pipes[pn].name!r}: {what} "
            "(TSNet leaves it unsimulated or stops there)"
        )


def _floor(node: Any) -> float:
    """A dead end's lowest head without demand: its start if below its elevation (see
    :mod:`burstloc.sim.transient._tsnet_compat`), else its elevation (TSNet's zero pressure)."""
    return float(min(node.elevation, node.initial_head))


def _pipe_constants(pipes: list[Any], dt: float) -> dict[str, np.ndarray]:
    """Each pipe's constants, computed in TSNet's own order of operations."""
    out: dict[str, list[float]] = {
        k: [] for k in ("ga", "ag", "gadt", "theta", "cf", "cf2", "area", "area_dead")
    }
    for pipe in pipes:
        f, d, a = float(pipe.roughness), float(pipe.diameter), float(pipe.wavev)
        ga = G / a
        out["ga"].append(ga)
        out["ag"].append(a / G)
        out["gadt"].append(ga * dt)
        out["theta"].append(float(pipe.theta))
        out["cf"].append(f * dt / 2.0 / d)
        out["cf2"].append(f * dt / (2.0 * d))
        out["area"].append(np.pi * d**2.0 / 4.0)
        out["area_dead"].append(np.pi / 4.0 * d**2.0)
    return {k: np.array(v, dtype=np.float64) for k, v in out.items()}


def layout(tm: Any, friction: str = "steady") -> Layout:
    """Lay out a TSNet model initialized by ``tsnet.simulation.Initializer``.

    Raises:
        ConfigError: a friction model other than TSNet's ``steady``.
        SimulationError: an element TSNet leaves unsimulated (see the module's docstring).
    """
    if friction != "steady":
        raise ConfigError(
            f"the vectorized solver models steady friction only, got {friction!r}; "
            "use the TSNet solver for other friction models"
        )
    b = _Builder(tm)
    steps = int(tm.simulation_period / tm.time_step)
    const = _pipe_constants(b.pipes, b.dt)
    size = int(b.offset[-1] + b.n[-1] + 1)
    H0 = np.empty(size)
    V0 = np.empty(size)
    for pn, pipe in enumerate(b.pipes):
        lo, hi = int(b.offset[pn]), int(b.offset[pn] + b.n[pn] + 1)
        H0[lo:hi] = np.asarray(pipe.initial_head, dtype=np.float64)
        V0[lo:hi] = np.asarray(pipe.initial_velocity, dtype=np.float64)
        H0[lo], H0[hi - 1] = float(pipe.start_node_head[0]), float(pipe.end_node_head[0])
    groups = {k: _Group() for k in ("junction", "ds", "de", "rs", "re", "vs", "ve")}
    contributions: dict[str, list[Any]] = {
        "end": [],
        "index": [],
        "pipe": [],
        "sign": [],
        "slot": [],
    }
    junction_b: list[float] = []
    elements: list[ElementEnd] = []

    def junction(pn: int, at_start: bool, links: list[int]) -> None:
        pipe = b.pipes[pn]
        node = pipe.start_node if at_start else pipe.end_node
        if node.transient_node_type in ("SurgeTank", "Chamber"):
            raise b.refuse(pn, f"{node.transient_node_type} at node {node.name!r}")
        if not hasattr(node, "elevation"):
            raise b.refuse(pn, f"reservoir {node.name!r} joined by several links")
        if any(abs(i) > len(b.pipes) for i in links):
            raise b.refuse(pn, f"a pump or valve at a branch ({node.name!r})")
        e = len(groups["junction"].out)
        lo, n = int(b.offset[pn]), int(b.n[pn])
        g = groups["junction"]
        g.out.append(lo if at_start else lo + n)
        g.near.append(lo + 1 if at_start else lo + n - 1)
        g.pipe.append(pn)
        g.node.append(b.node(node))
        g.value.append(-1.0 if at_start else 1.0)  # the own pipe's sign
        for slot, i in enumerate(links):
            contributions["end"].append(e)
            contributions["index"].append(b.near(i))
            contributions["pipe"].append(abs(i) - 1)
            contributions["sign"].append(float(np.sign(i)))
            contributions["slot"].append(slot)
        q = [abs(i) - 1 for i in links]
        nb = dot_order([float(const["ga"][x] * const["area"][x]) for x in q])
        own = float(const["ga"][pn] * const["area"][pn])
        block = 1 - float(node.block_per)
        junction_b.append(nb + block * own if at_start else own + block * nb)

    def end_group(
        key: str, pn: int, at_start: bool, node: int = -1, value: float = 0.0, series: Any = None
    ) -> None:
        lo, n = int(b.offset[pn]), int(b.n[pn])
        g = groups[key]
        g.out.append(lo if at_start else lo + n)
        g.near.append(lo + 1 if at_start else lo + n - 1)
        g.pipe.append(pn)
        g.node.append(node)
        g.value.append(value)
        g.series.append(series)

    for pn, pipe in enumerate(b.pipes):
        l1, l2 = b.links1[pn], b.links2[pn]
        u, d = b.utype[pn][0], b.dtype[pn][0]
        start_open = bool(l1) and l1 != ["End"]
        end_open = bool(l2) and l2 != ["End"]
        lo, n = int(b.offset[pn]), int(b.n[pn])
        if start_open:  # TSNet's inner_pipe or right_boundary: the start joins links
            if u == "Pipe":
                junction(pn, True, l1)
            elif u in ("Pump", "Valve"):
                elements.append(moc_elements.between(b, pn, True, l1, lo))
            else:
                raise b.refuse(pn, f"a {u} at its start")
        else:  # TSNet's left_boundary
            if u in _BOUNDARY_NODES:
                end_group("rs", pn, True, value=float(pipe.initial_head[0]))
            elif u == "Valve":
                velocity = moc_elements.valve_end_velocity(b, pn, True, 0)
                end_group("vs", pn, True, series=velocity)
            elif u == "Junction":
                end_group(
                    "ds", pn, True, node=b.node(pipe.start_node), value=_floor(pipe.start_node)
                )
            elif u == "Pump":
                elements.append(moc_elements.source(b, pn, lo))
            else:
                raise b.refuse(pn, f"a {u} at its start")
        if start_open and end_open:  # inner_pipe's end
            if d == "Pipe":
                junction(pn, False, l2)
            elif d in ("Pump", "Valve"):
                elements.append(moc_elements.between(b, pn, False, l2, lo + n))
            else:
                raise b.refuse(pn, f"a {d} at its end")
        elif not start_open:  # left_boundary's end
            if d == "Pipe":
                junction(pn, False, l2)
            elif d == "Pump" and end_open:
                elements.append(moc_elements.between(b, pn, False, l2, lo + n))
            elif d == "Valve" and not end_open:  # TSNet never sets this end's flow: closed
                end_group("ve", pn, False, series=np.zeros(steps))
            elif d == "Valve":
                elements.append(moc_elements.between(b, pn, False, l2, lo + n))
            elif d == "Junction":
                end_group("de", pn, False, node=b.node(pipe.end_node), value=_floor(pipe.end_node))
            else:
                raise b.refuse(pn, f"a {d} at its end with nothing at its start")
        else:  # right_boundary's end
            if d in _BOUNDARY_NODES:
                end_group("re", pn, False, value=float(pipe.initial_head[-1]))
            elif d == "Valve":
                velocity = moc_elements.valve_end_velocity(b, pn, False, -1)
                end_group("ve", pn, False, series=velocity)
            elif d == "Junction":
                end_group("de", pn, False, node=b.node(pipe.end_node), value=_floor(pipe.end_node))
            else:
                raise b.refuse(pn, f"a {d} at its end")

    record_nodes: list[Any] = []
    record: list[int] = []
    seen: set[str] = set()
    for pn, pipe in enumerate(b.pipes):
        for node, point in (
            (pipe.start_node, b.offset[pn]),
            (pipe.end_node, b.offset[pn] + b.n[pn]),
        ):
            if node.name not in seen:
                seen.add(node.name)
                record_nodes.append(node)
                record.append(int(point))
    for node in record_nodes:
        if node.transient_node_type == "Junction":
            b.node(node)
    return Layout(
        dt=b.dt,
        steps=steps,
        pipes=b.pipes,
        offset=b.offset,
        n=b.n,
        **const,
        H0=H0,
        V0=V0,
        nodes=b.nodes,
        emitter=np.array([float(getattr(x, "emitter_coeff", 0.0)) for x in b.nodes]),
        demand=np.array([float(getattr(x, "demand_coeff", 0.0)) for x in b.nodes]),
        elevation=np.array([float(getattr(x, "elevation", np.nan)) for x in b.nodes]),
        junction=groups["junction"],
        junction_b=np.array(junction_b, dtype=np.float64),
        contributions=contributions,
        dead_start=groups["ds"],
        dead_end=groups["de"],
        rev_start=groups["rs"],
        rev_end=groups["re"],
        valve_start=groups["vs"],
        valve_end=groups["ve"],
        elements=elements,
        record=np.array(record, dtype=np.int64),
        record_nodes=record_nodes,
    )
