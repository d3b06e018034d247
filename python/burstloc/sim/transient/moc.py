"""burstloc's vectorized MOC solver: TSNet's transient model, a time step in array operations.

TSNet's ``MOCSimulator`` loops over pipes in Python at every time step; on a network of a
hundred pipes a step costs milliseconds, and a network with short pipes needs tens of thousands
of steps (EPANET's Net3: 1.8 CPU s per simulated second on its transient-ready model). This
solver takes the model TSNet has initialized (discretization, wave speeds, EPANET's steady
state, demand coefficients, pump curves, the event's controls: everything but the time loop)
and runs the same equations over the whole network at once
(:mod:`burstloc.sim.transient.moc_layout`):
interior points, junctions (pressure-dependent demand and the burst's emitter, ``Q = k
sqrt(p)``), dead ends, reservoirs and tanks, valves leading nowhere; pumps and valves between
pipes keep TSNet's own functions (:mod:`burstloc.sim.transient.moc_elements`). The time loop runs in
Rust by
default (:mod:`burstloc.sim.transient.moc_rust`, the same expressions, pumps and valves ported: the
same
heads to the bit, 15-20 times faster on L-TOWN); ``kernel="numpy"`` (solver ``"numpy"``) runs
it here as NumPy array operations per step. Every expression keeps
TSNet's order of operations, down to the order in which ``np.dot`` adds a junction's pipes
(:func:`~burstloc.sim.transient.moc_layout.dot_order`, as OpenBLAS does with NumPy 1.26) and the C
library's ``pow`` for squares: there the heads are TSNet's to the last bit. Where NumPy's BLAS
adds in another order (NumPy 2) they differ by micrometres to millimetres: TSNet's junction
equation is ill-conditioned at a junction without demand, and TSNet itself differs by as much
between the two stacks (``tests/sim/test_moc.py``, ``benches/bench_moc.py``).

:func:`solve` leaves its results where TSNet's solver does (each node's ``head`` series,
``tm.simulation_timestamps``), and reports what TSNet warns of through :mod:`warnings`, once
per node with a count: negative pressure at a junction (one that starts below atmospheric
pressure in EPANET's steady state is said so instead), and a junction or dead-end equation
without a real root.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np

from burstloc.exceptions import ConfigError
from burstloc.sim.transient import moc_rust
from burstloc.sim.transient.moc_layout import Layout, layout

__all__ = ["solve"]

#: TSNet's tolerance: a quadratic's discriminant above ``-ROOT_TOLERANCE`` counts as zero.
ROOT_TOLERANCE = 1.0e-7


class _Ends:
    """One group of pipe ends with their pipes' constants gathered (see :class:`Layout`)."""

    def __init__(self, lay: Layout, group: Any) -> None:
        p = np.asarray(group.pipe, dtype=np.int64)
        self.out = np.asarray(group.out, dtype=np.int64)
        self.near = np.asarray(group.near, dtype=np.int64)
        self.node = np.asarray(group.node, dtype=np.int64)
        self.value = np.asarray(group.value, dtype=np.float64)
        velocities = [v for v in group.series if v is not None]  # valve ends: per step
        self.series = np.column_stack(velocities) if velocities else np.zeros((0, 0))
        self.ga, self.ag, self.gadt = lay.ga[p], lay.ag[p], lay.gadt[p]
        self.theta, self.cf, self.cf2 = lay.theta[p], lay.cf[p], lay.cf2[p]
        self.area, self.area_dead = lay.area[p], lay.area_dead[p]
        self.size = self.out.size
        self.failed = np.zeros(self.size, dtype=np.int64)


_POW = np.frompyfunc(lambda value: math.pow(value, 2.0), 1, 1)


def _squared(values: np.ndarray) -> np.ndarray:
    """``values ** 2`` as TSNet's scalar arithmetic computes it (the C library's ``pow``, which
    differs from the exact square in the last place for about one value in a thousand; NumPy's
    array square does not call it)."""
    return np.asarray(_POW(values), dtype=np.float64)


def _interior(lay: Layout) -> tuple[np.ndarray, ...]:
    """Every pipe's interior points and their pipes' constants."""
    points = [np.arange(o + 1, o + n) for o, n in zip(lay.offset, lay.n, strict=True)]
    idx = np.concatenate(points) if points else np.zeros(0, dtype=np.int64)
    p = np.repeat(np.arange(lay.n.size), lay.n - 1)
    return idx, lay.ga[p], lay.gadt[p], lay.theta[p], lay.cf[p], lay.ga[p] + lay.ga[p]


def _characteristic(
    sign: Any, V: np.ndarray, H: np.ndarray, ga: Any, gadt: Any, theta: Any, cf: Any
) -> np.ndarray:
    """TSNet's ``cal_Cs``: ``s V + g/a H - s J + g/a dt V theta`` (steady friction ``J``)."""
    J = cf * V * np.abs(V)
    return sign * V + ga * H - sign * J + gadt * V * theta


def _lanes(
    end: np.ndarray, slot: np.ndarray, size: int
) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """The junction sums' order (:func:`~burstloc.sim.transient.moc_layout.dot_order`), per slot of
    the
    junctions' pipe lists: ``(lane, entries, ends)``."""
    degree = np.bincount(end, minlength=size)
    blocked = (4 * (degree // 4))[end]
    lanes = np.where(slot < blocked, slot % 4, 0)
    order = []
    for s in range(int(slot.max(initial=-1)) + 1):
        for lane in range(4):
            entries = np.flatnonzero((slot == s) & (lanes == lane))
            if entries.size:
                order.append((lane, entries, end[entries]))
    return order


def _dot_sums(
    products: np.ndarray, order: list[tuple[int, np.ndarray, np.ndarray]], size: int
) -> np.ndarray:
    """Per junction end, the sum of its entries' ``products`` in ``np.dot``'s order."""
    acc = np.zeros((4, size))
    for lane, entries, ends in order:
        acc[lane, ends] += products[entries]
    return (acc[0] + acc[1]) + (acc[2] + acc[3])


def _dead_ends(
    e: _Ends, H: np.ndarray, V: np.ndarray, k: np.ndarray, elev: np.ndarray, start: bool
) -> tuple[np.ndarray, np.ndarray]:
    """TSNet's ``dead_end``: a junction ending one pipe, its demand ``k sqrt(p)``."""
    V1, H1 = V[e.near], H[e.near]
    J = e.cf * V1 * np.abs(V1)
    if start:
        bq = -e.ag * k / e.area_dead
        cq = e.ag * V1 - e.ag * J - H1 - e.gadt * V1 * e.theta + elev
    else:
        bq = e.ag * k / e.area_dead
        cq = -e.ag * V1 + e.ag * J - H1 - e.gadt * V1 * e.theta + elev
    delta = _squared(bq) - 4.0 * cq
    ok = delta >= 0
    # no demand, started below atmospheric pressure, no root: the closed end (_tsnet_compat)
    closed = (k == 0) & (cq > 0) & (e.value < elev)
    root = np.sqrt(np.where(ok, delta, 0.0))
    e.failed += (delta <= -ROOT_TOLERANCE) & ~closed
    x = np.where(ok, (-bq - root) / 2 if start else (-bq + root) / 2, (-bq) / 2)
    HP = np.where(closed, np.maximum(elev - cq, e.value), _squared(x) + elev)
    friction = e.cf2 * V1 * np.abs(V1)
    if start:
        VP = V1 - e.ga * H1 - friction + e.ga * HP - e.gadt * V1 * e.theta
    else:
        VP = V1 + e.ga * H1 - friction - e.ga * HP + e.gadt * V1 * e.theta
    return HP, VP


#: The time loops :func:`solve` can run: ``"rust"`` (:mod:`burstloc.sim.transient.moc_rust`, the
#: default) or ``"numpy"`` (array operations per step, here); their heads are equal to the bit.
KERNELS = ("rust", "numpy")


def solve(
    tm: Any, friction: str = "steady", kernel: str = "rust", first: Sequence[str] = ()
) -> Any:
    """Run the transient of a TSNet model initialized by ``tsnet.simulation.Initializer``;
    return ``tm`` with every node's ``head`` series and ``simulation_timestamps`` set, and
    ``burstloc_heads``: the heads matrix (steps x nodes) those series are columns of and its
    nodes' names, the nodes named in ``first`` (those TSNet simulates) in its first columns in
    that order, so that a caller reads them without a copy.

    Raises:
        ConfigError: a friction model other than ``steady``, a kernel not in :data:`KERNELS`.
        SimulationError: an element TSNet leaves unsimulated (named).
    """
    if kernel not in KERNELS:
        raise ConfigError(f"unknown MOC kernel {kernel!r}; expected one of {KERNELS}")
    lay = layout(tm, friction)
    columns = _record_first(lay, first)
    junction = _Ends(lay, lay.junction)
    dead = [(_Ends(lay, lay.dead_start), True), (_Ends(lay, lay.dead_end), False)]
    if kernel == "rust":
        result = moc_rust.run(lay)
        heads = result.heads
        junction.failed[:] = result.junction_failed
        split = dead[0][0].size
        dead[0][0].failed[:] = result.dead_failed[:split]
        dead[1][0].failed[:] = result.dead_failed[split:]
        _element_warnings(result.element_warnings)
    else:
        heads = _numpy_loop(lay, junction, dead)
    _report(lay, heads, junction, dead, columns)
    for column, node in enumerate(lay.record_nodes):
        node._head = heads[:, column]
    tm.burstloc_heads = (heads, [node.name for node in lay.record_nodes])
    tm.simulation_timestamps = list(np.arange(lay.steps) * lay.dt)
    return tm


def _record_first(lay: Layout, first: Sequence[str]) -> list[tuple[int, Any]]:
    """Reorder the recorded nodes: those named in ``first`` first, in that order. Returns the
    nodes in their layout order with their new columns (the order warnings are given in)."""
    names = {node.name: i for i, node in enumerate(lay.record_nodes)}
    head = [names[name] for name in first if name in names]
    chosen = set(head)
    order = head + [i for i in range(len(lay.record_nodes)) if i not in chosen]
    column = {old: new for new, old in enumerate(order)}
    columns = [(column[i], node) for i, node in enumerate(lay.record_nodes)]
    lay.record = lay.record[order]
    lay.record_nodes = [lay.record_nodes[i] for i in order]
    return columns


#: TSNet's warnings from a pump or valve, in the order of ``moc_rust.Run.element_warnings``.
_ELEMENT_WARNINGS = (
    "The quadratic equation has no real solution (pump or valve)",
    "Reverse flow stopped by check valve!",
    "Negative head gain activates by-pass!",
)


def _element_warnings(counts: np.ndarray) -> None:
    """Warn once of each of TSNet's pump and valve warnings, with the number of steps."""
    for message, count in zip(
        _ELEMENT_WARNINGS, np.sum(counts, axis=0, dtype=np.int64), strict=True
    ):
        if count:
            warnings.warn(f"{message} ({int(count)} pipe-end time steps)", stacklevel=3)


def _numpy_loop(lay: Layout, junction: _Ends, dead: list[tuple[_Ends, bool]]) -> np.ndarray:
    """The time loop as array operations per step: the heads (steps x recorded nodes)."""
    interior, iga, igadt, itheta, icf, iga2 = _interior(lay)
    c = lay.contributions
    cend = np.asarray(c["end"], dtype=np.int64)
    cidx = np.asarray(c["index"], dtype=np.int64)
    cp = np.asarray(c["pipe"], dtype=np.int64)
    csign = np.asarray(c["sign"], dtype=np.float64)
    cga, cgadt, ctheta, ccf, carea = (
        lay.ga[cp],
        lay.gadt[cp],
        lay.theta[cp],
        lay.cf[cp],
        lay.area[cp],
    )
    lanes = _lanes(cend, np.asarray(c["slot"], dtype=np.int64), junction.size)
    at_start = junction.value < 0
    jb, jb2 = lay.junction_b, _squared(lay.junction_b)
    jelev = lay.elevation[junction.node]
    rev = [(_Ends(lay, lay.rev_start), 1.0), (_Ends(lay, lay.rev_end), -1.0)]
    valves = [(_Ends(lay, lay.valve_start), 1.0), (_Ends(lay, lay.valve_end), -1.0)]
    emitter, demand = lay.emitter.copy(), lay.demand.copy()
    bursts = [
        (i, x.burst_coeff) for i, x in enumerate(lay.nodes) if getattr(x, "burst_status", False)
    ]
    pulses = [
        (i, demand[i], x.pulse_coeff)
        for i, x in enumerate(lay.nodes)
        if getattr(x, "pulse_status", False)
    ]
    H, V = lay.H0.copy(), lay.V0.copy()
    HN, VN = np.empty_like(H), np.empty_like(V)
    heads = np.empty((lay.steps, lay.record.size))
    heads[0] = H[lay.record]
    for ts in range(1, lay.steps):
        for i, series in bursts:
            emitter[i] = series[ts]
        for i, base, pulse in pulses:
            demand[i] = base * (1.0 + pulse[ts])
        k = emitter + demand
        # interior points (TSNet's inner_node_steady)
        C0 = _characteristic(1.0, V[interior - 1], H[interior - 1], iga, igadt, itheta, icf)
        C1 = _characteristic(-1.0, V[interior + 1], H[interior + 1], iga, igadt, itheta, icf)
        HP = (C0 + C1) / iga2
        HN[interior] = HP
        VN[interior] = -C1 + iga * HP
        # junctions (TSNet's add_leakage)
        if junction.size:
            Cc = _characteristic(csign, V[cidx], H[cidx], cga, cgadt, ctheta, ccf)
            nb = _dot_sums(Cc * carea, lanes, junction.size)
            near = junction.near
            Co = _characteristic(
                junction.value,
                V[near],
                H[near],
                junction.ga,
                junction.gadt,
                junction.theta,
                junction.cf,
            )
            a = nb + Co * junction.area
            kj = k[junction.node]
            k2 = _squared(kj)
            b1 = -2 * a * jb - k2
            c1 = _squared(a) + k2 * jelev
            delta = _squared(b1) - 4 * jb2 * c1
            ok = delta >= 0
            junction.failed += delta <= -ROOT_TOLERANCE
            HP = np.where(
                ok, (-b1 - np.sqrt(np.where(ok, delta, 0.0))) / (2 * jb2), (-b1) / (2 * jb2)
            )
            HN[junction.out] = HP
            VN[junction.out] = np.where(at_start, -Co + junction.ga * HP, Co - junction.ga * HP)
        for e, start in dead:
            if e.size:
                HN[e.out], VN[e.out] = _dead_ends(e, H, V, k[e.node], lay.elevation[e.node], start)
        for e, side in rev:  # a reservoir or tank holds its head (TSNet's rev_end)
            if e.size:
                V1, H1 = V[e.near], H[e.near]
                J = e.cf * V1 * np.abs(V1)
                HN[e.out] = e.value
                VN[e.out] = V1 + side * (e.ga * (e.value - H1)) - J
        for e, side in valves:  # a valve leading nowhere holds a flow (TSNet's valve_end)
            if e.size:
                V1, H1 = V[e.near], H[e.near]
                Vb = e.series[ts]
                J = e.cf * Vb * np.abs(Vb)
                HN[e.out] = H1 + side * (e.ag * (Vb - V1)) + side * (e.ag * J)
                VN[e.out] = Vb
        for element in lay.elements:
            HN[element.index], VN[element.index] = element.solve(H, V, ts)
        heads[ts] = HN[lay.record]
        H, HN = HN, H
        V, VN = VN, V
    return heads


def _report(
    lay: Layout,
    heads: np.ndarray,
    junction: _Ends,
    dead: list[tuple[_Ends, bool]],
    columns: list[tuple[int, Any]],
) -> None:
    """Warn, once per node with a count, of negative pressure and of equations without a root
    (``columns``: each node's column in ``heads``, in the layout's order of the nodes)."""
    for column, node in columns:
        if node.transient_node_type != "Junction":
            continue
        pressure = heads[:, column] - node.elevation
        if pressure[0] <= 0:  # EPANET's steady state put it there: not the event's doing
            warnings.warn(
                f"Node {node.name} starts below atmospheric pressure: {pressure[0]:.3g} m in "
                f"EPANET's steady state (lowest {pressure.min():.3g} m during the simulation)",
                stacklevel=2,
            )
            continue
        low = int(np.count_nonzero(pressure <= 0))
        if low:
            warnings.warn(
                f"Negative pressure on node {node.name}. ({low} of {lay.steps} time steps)",
                stacklevel=2,
            )
    failed: dict[str, int] = {}
    for e in [junction, *(g for g, _ in dead)]:
        for node, count in zip(e.node, e.failed, strict=True):
            if count:
                name = lay.nodes[int(node)].name
                failed[name] = failed.get(name, 0) + int(count)
    for name, count in failed.items():
        warnings.warn(
            f"The head equation at node {name} had no real solution at {count} pipe-end "
            "time steps (TSNet's 'no real solution'); the results might not be accurate.",
            stacklevel=2,
        )
