"""The vectorized MOC solver's time loop in Rust (``burstloc._core.moc_run``, crate ``moc-core``).

:func:`burstloc.sim.transient.moc.solve` runs TSNet's transient either as NumPy array operations per
time
step or, by default, here: the :class:`~burstloc.sim.transient.moc_layout.Layout` is handed to Rust
as
flat arrays once and the whole time loop runs there, pumps and valves between pipes included
(TSNet's ``valve_node``, ``pump_node`` and ``source_pump``, ported with their order of
operations), without the Python interpreter between steps. Every expression keeps the NumPy
loop's order of operations, squares are the C library's ``pow`` and a junction's sum keeps
``np.dot``'s order, so the heads are the NumPy loop's to the last bit
(``tests/sim/test_moc_rust.py``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from burstloc.sim.transient.moc_layout import Layout

__all__ = ["Run", "run"]


@dataclass(frozen=True)
class Run:
    """What the Rust time loop returns: ``heads`` (steps x recorded nodes), per junction end
    and per dead end (start ends first, then end ends, as in the layout) the number of steps
    its equation had no real root, and per pump or valve ``element_warnings`` (no real root,
    reverse flow stopped by a pump's check valve, negative head gain bypassed)."""

    heads: np.ndarray
    junction_failed: np.ndarray
    dead_failed: np.ndarray
    element_warnings: np.ndarray


def _ints(rows: list[list[int]], width: int) -> np.ndarray:
    return np.asarray(rows, dtype=np.int64).reshape(len(rows), width)


def _floats(rows: Any, width: int) -> np.ndarray:
    values = np.asarray(rows, dtype=np.float64)
    return values.reshape(len(values), width) if width else values.reshape(-1)


def _series(columns: list[np.ndarray], steps: int) -> np.ndarray:
    """Per-step series as a ``(steps, len(columns))`` matrix."""
    if not columns:
        return np.zeros((steps, 0))
    return np.column_stack([np.asarray(c, dtype=np.float64)[:steps] for c in columns])


def _lanes(end: np.ndarray, slot: np.ndarray) -> np.ndarray:
    """Each junction-sum entry's ``np.dot`` lane (see
    :func:`burstloc.sim.transient.moc_layout.dot_order`):
    ``slot % 4`` within the full blocks of four, else the first lane."""
    degree = np.bincount(end, minlength=1)
    blocked = (4 * (degree // 4))[end]
    return np.where(slot < blocked, slot % 4, 0)


def run(lay: Layout) -> Run:
    """Run the transient of ``lay`` in Rust.

    Raises:
        burstloc.InputError: the layout's arrays do not fit together (a bug, not bad input).
    """
    from burstloc._core import moc_run

    steps = lay.steps
    junction, c = lay.junction, lay.contributions
    cend = np.asarray(c["end"], dtype=np.int64)
    cslot = np.asarray(c["slot"], dtype=np.int64)
    contributions = _ints(
        [
            [e, i, p, lane]
            for e, i, p, lane in zip(cend, c["index"], c["pipe"], _lanes(cend, cslot), strict=True)
        ],
        4,
    )
    dead = [
        [o, n, p, node, flag]
        for group, flag in ((lay.dead_start, 1), (lay.dead_end, 0))
        for o, n, p, node in zip(group.out, group.near, group.pipe, group.node, strict=True)
    ]
    floors = [*lay.dead_start.value, *lay.dead_end.value]
    reservoirs = [
        (o, n, p, value, side)
        for group, side in ((lay.rev_start, 1.0), (lay.rev_end, -1.0))
        for o, n, p, value in zip(group.out, group.near, group.pipe, group.value, strict=True)
    ]
    valves = [
        (o, n, p, side, series)
        for group, side in ((lay.valve_start, 1.0), (lay.valve_end, -1.0))
        for o, n, p, series in zip(group.out, group.near, group.pipe, group.series, strict=True)
    ]
    elements = lay.elements
    element_series = np.zeros((steps, 3 * len(elements)))
    for k, element in enumerate(elements):
        if element.varies:
            element_series[:, 3 * k : 3 * k + 3] = [element.parameter(ts) for ts in range(steps)]
        else:
            element_series[:, 3 * k : 3 * k + 3] = element.parameter(0)
    bursts = [
        (i, x.burst_coeff) for i, x in enumerate(lay.nodes) if getattr(x, "burst_status", False)
    ]
    pulses = [
        (i, x.pulse_coeff) for i, x in enumerate(lay.nodes) if getattr(x, "pulse_status", False)
    ]
    heads, junction_failed, dead_failed, element_warnings = moc_run(
        steps=steps,
        pipe_points=np.column_stack([lay.offset, lay.n]).astype(np.int64),
        pipes=np.column_stack(
            [lay.ga, lay.ag, lay.gadt, lay.theta, lay.cf, lay.cf2, lay.area, lay.area_dead]
        ),
        h0=np.ascontiguousarray(lay.H0, dtype=np.float64),
        v0=np.ascontiguousarray(lay.V0, dtype=np.float64),
        nodes=np.column_stack([lay.emitter, lay.demand, lay.elevation]).reshape(-1, 3),
        junctions=_ints(
            [
                [o, n, p, node]
                for o, n, p, node in zip(
                    junction.out, junction.near, junction.pipe, junction.node, strict=True
                )
            ],
            4,
        ),
        junction_values=_floats(
            [[s, b] for s, b in zip(junction.value, lay.junction_b, strict=True)], 2
        ),
        contributions=contributions,
        contribution_signs=_floats(c["sign"], 0),
        dead_ends=_ints(dead, 5),
        dead_floors=_floats(floors, 0),
        reservoirs=_ints([list(r[:3]) for r in reservoirs], 3),
        reservoir_values=_floats([r[3:] for r in reservoirs], 2),
        valve_ends=_ints([list(v[:3]) for v in valves], 3),
        valve_sides=_floats([v[3] for v in valves], 0),
        valve_series=_series([v[4] for v in valves], steps),
        elements=_ints(
            [
                [e.kind, e.index, int(e.at_start), *e.link1[:2], *e.link2[:2], int(e.suction)]
                for e in elements
            ],
            8,
        ),
        element_values=_floats([[e.link1[2], e.link2[2], e.sump] for e in elements], 3),
        element_series=element_series,
        bursts=np.array([i for i, _ in bursts], dtype=np.int64),
        burst_series=_series([s for _, s in bursts], steps),
        pulses=np.array([i for i, _ in pulses], dtype=np.int64),
        pulse_series=_series([s for _, s in pulses], steps),
        record=np.ascontiguousarray(lay.record, dtype=np.int64),
    )
    return Run(heads, junction_failed, dead_failed, element_warnings)
