"""Pumps and valves for the vectorized MOC solver: TSNet's own boundary functions, per step.

A network has few pumps and valves; their pipe ends are solved each step by the very functions
TSNet's ``MOCSimulator`` calls (``tsnet.simulation.solver``: ``pump_node``, ``valve_node``,
``source_pump``), with the arguments it builds (the pump curve scaled by its operation rule, the
valve's loss from its opening), so they behave as in TSNet. A valve leading nowhere holds a flow
(TSNet's ``valve_end``): :func:`valve_end_velocity` gives it per step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["PUMP", "SOURCE", "VALVE", "ElementEnd", "G", "between", "source", "valve_end_velocity"]

#: TSNet's gravitational acceleration, m/s².
G = 9.8


#: :attr:`ElementEnd.kind` of a valve between pipes, a pump between pipes, a source pump.
VALVE, PUMP, SOURCE = 0, 1, 2


@dataclass
class ElementEnd:
    """A pipe end at a pump or valve, solved by TSNet's own function each step.

    ``solve(H, V, ts)`` returns the end's ``(head, velocity)`` from the previous step's flat
    arrays; ``index`` is the end's point in the flat arrays. The rest describes the same
    computation for the Rust time loop (:mod:`burstloc.sim.transient.moc_rust`): ``kind``
    (:data:`VALVE`,
    :data:`PUMP`, :data:`SOURCE`), whether the end is its pipe's start, TSNet's characteristics
    ``C1`` and ``C2`` as ``(point, pipe, sign)``, the pipe end on the pump's suction side, the
    sump's head (a source pump) and ``parameter(ts)``: the valve's inverse loss coefficient (in
    the first of three places) or the pump curve's ``a, b, c`` at step ``ts``, which ``varies``
    only for a pump or valve operated during the event.
    """

    index: int
    solve: Callable[[np.ndarray, np.ndarray, int], tuple[float, float]]
    kind: int
    at_start: bool
    link1: tuple[int, int, float]
    link2: tuple[int, int, float]
    parameter: Callable[[int], tuple[float, float, float]]
    varies: bool
    suction: bool = False
    sump: float = 0.0


def _pump_curve(pump: Any) -> Callable[[int], Any]:
    """The pump's curve coefficients at step ``ts`` (scaled by its speed when operated)."""
    from tsnet.utils import calc_parabola_vertex

    if not getattr(pump, "operating", False):
        return lambda ts: pump.curve_coef
    points = pump.get_pump_curve().points
    rule = pump.operation_rule

    def curve(ts: int) -> Any:
        po = rule[ts]
        return calc_parabola_vertex([(i * po, j * po**2) for (i, j) in points])

    return curve


def _valve_loss(valve: Any) -> Callable[[int], Any]:
    """The valve's inverse loss coefficient at step ``ts`` (TSNet's ``valve_curve``)."""
    from tsnet.utils import valve_curve

    if getattr(valve, "operating", False):
        rule, coeff = valve.operation_rule, valve.valve_coeff
        return lambda ts: valve_curve(rule[ts] * 100, coeff)
    status = valve.initial_status.name
    fixed = (
        valve_curve(100, valve.valve_coeff)
        if status == "Open"
        else valve_curve(0, valve.valve_coeff)
        if status == "Closed"
        else 0
    )
    return lambda ts: fixed


def between(builder: Any, pn: int, at_start: bool, links: list[int], index: int) -> ElementEnd:
    """Pipe ``pn``'s end at a pump or valve joining it to the pipe(s) ``links``."""
    from tsnet.simulation.solver import pump_node, valve_node

    tm, pipes = builder.tm, builder.pipes
    pipe = pipes[pn]
    kind, name = builder.utype[pn] if at_start else builder.dtype[pn]
    link = tm.links[name]
    others = [pipes[abs(i) - 1] for i in links]
    near = [builder.near(i) for i in links]
    signs = np.sign(links)
    zeros = [0.0] * len(links)
    dt = builder.dt
    lo, n = int(builder.offset[pn]), int(builder.n[pn])
    if kind == "Pump":
        curve = _pump_curve(link)
        node = pipe.start_node if at_start else pipe.end_node
        side = "s" if node.name == link.start_node.name else "d"

        def pump(ts: int) -> Any:
            return [curve(ts), side]

        parameter: Callable[[int], Any] = pump
        function: Callable[..., Any] = pump_node
    else:
        parameter = _valve_loss(link)
        function = valve_node

    first = (near[0], abs(links[0]) - 1, float(signs[0]))
    if at_start:  # TSNet's C1 from the first pipe joined, C2 from this pipe's start
        link1, link2 = first, (lo + 1, pn, -1.0)
    else:  # C1 from this pipe's end, C2 from the first pipe joined
        link1, link2 = (lo + n - 1, pn, 1.0), first

    if at_start:

        def solve(H: np.ndarray, V: np.ndarray, ts: int) -> tuple[float, float]:
            head, velocity = function(
                parameter(ts),
                others,
                pipe,
                [H[i] for i in near],
                [V[i] for i in near],
                H[lo + 1],
                V[lo + 1],
                dt,
                G,
                0,
                signs,
                [-1],
                "steady",
                zeros,
                0.0,
                zeros,
                0.0,
            )
            return float(head), float(velocity)
    else:

        def solve(H: np.ndarray, V: np.ndarray, ts: int) -> tuple[float, float]:
            head, velocity = function(
                parameter(ts),
                pipe,
                others,
                H[lo + n - 1],
                V[lo + n - 1],
                [H[i] for i in near],
                [V[i] for i in near],
                dt,
                G,
                n,
                [1],
                signs,
                "steady",
                0.0,
                zeros,
                0.0,
                zeros,
            )
            return float(head), float(velocity)

    return ElementEnd(
        index,
        solve,
        kind=PUMP if kind == "Pump" else VALVE,
        at_start=at_start,
        link1=link1,
        link2=link2,
        parameter=_numbers(parameter),
        varies=bool(getattr(link, "operating", False)),
        suction=kind == "Pump" and side == "s",
    )


def source(builder: Any, pn: int, index: int) -> ElementEnd:
    """Pipe ``pn``'s start at a pump drawing from a reservoir or tank (TSNet's source pump)."""
    from tsnet.simulation.solver import source_pump

    pipe = builder.pipes[pn]
    pump = builder.tm.links[builder.utype[pn][1]]
    sump = pump.start_node.initial_head
    curve = _pump_curve(pump)
    dt, lo = builder.dt, int(builder.offset[pn])

    def solve(H: np.ndarray, V: np.ndarray, ts: int) -> tuple[float, float]:
        head, velocity = source_pump(
            [sump, curve(ts)], pipe, H[lo + 1], V[lo + 1], dt, G, [-1], "steady", 0.0, 0.0
        )
        return float(head), float(velocity)

    own = (lo + 1, pn, -1.0)
    return ElementEnd(
        index,
        solve,
        kind=SOURCE,
        at_start=True,
        link1=own,
        link2=own,
        parameter=_numbers(curve),
        varies=bool(getattr(pump, "operating", False)),
        sump=float(sump),
    )


def _numbers(parameter: Callable[[int], Any]) -> Callable[[int], tuple[float, float, float]]:
    """A pump's ``[curve, side]``, its curve ``(a, b, c)`` or a valve's inverse loss, at step
    ``ts``, as three floats (the valve's first, then zeros)."""

    def numbers(ts: int) -> tuple[float, float, float]:
        value = parameter(ts)
        if isinstance(value, list):  # a pump between pipes: [curve, side]
            value = value[0]
        if np.ndim(value) == 0:
            return (float(value), 0.0, 0.0)
        a, b, c = (float(x) for x in value)
        return (a, b, c)

    return numbers


def valve_end_velocity(builder: Any, pn: int, at_start: bool, point: int) -> np.ndarray:
    """The velocity TSNet holds at pipe ``pn``'s end at a valve leading nowhere, per step: the
    steady velocity scaled by the valve's operation rule, the steady velocity if the valve is
    open, else 0."""
    pipe = builder.pipes[pn]
    name = builder.utype[pn][1] if at_start else builder.dtype[pn][1]
    valve = builder.tm.links[name]
    steps = int(builder.tm.simulation_period / builder.tm.time_step)
    steady = np.float64(pipe.initial_velocity[point])
    if getattr(valve, "operating", False):
        return steady * np.asarray(valve.operation_rule, dtype=np.float64)[:steps]
    if valve.initial_status.name == "Open":
        return np.full(steps, steady)
    return np.zeros(steps)
