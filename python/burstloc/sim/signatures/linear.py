"""Burst signatures from one factorization of the linearized steady state (large networks).

:func:`burstloc.sim.signatures.compute.compute_signatures` solves EPANET once per pipe: exact, but
on a
network of fifteen thousand pipes nine signature sets are over a hundred thousand steady states.
Here the steady state is solved once and linearized about its solution. Unknowns are the head
changes at the junctions and the flow changes in the links; equations are

* at each junction, the mass balance: ``sum(out dQ) - sum(in dQ) + dd/dp * dh = -w`` (``w``: an
  extra withdrawal there, ``dd/dp``: how its pressure-driven demand or emitter answers);
* for each link ``s -> e``, its head-loss law: ``dh_s - dh_e = r dQ`` with ``r = d(headloss)/dQ``
  at the steady flow (pipes: Hazen-Williams, Darcy-Weisbach or Chezy-Manning friction plus minor
  loss, never below the laminar gradient; pumps: minus the slope of the head curve at their speed,
  or ``gain / Q`` for a pump given by its power; open valves: ``2 |headloss| / |Q|``), or the
  link's active state (closed or an active flow control: ``dQ = 0``; an active pressure-reducing
  valve holds its downstream head, ``dh_e = 0``; a sustaining valve its upstream head; a
  breaker its head loss). Tanks and reservoirs hold their heads.

The matrix is factorized once (SuperLU); one transposed solve per meter gives that meter's head
response ``Z[m, k]`` to a unit withdrawal at every junction ``k``. A burst at ``f`` along the
pipe ``a -> b`` (from its INP start node, as the exact signatures split it) withdraws ``q`` from
a point inside the pipe, which for the rest of the network is ``(1 - f) q`` at ``a`` and ``f q``
at ``b`` (eliminating the split junction from the linear equations), so its signature at ``m`` is
``q ((1 - f) Z[m, a] + f Z[m, b])`` with ``q = C sqrt(p)`` (``C``: the reference burst's emitter
coefficient, ``p``: the steady pressure interpolated at the point). A closed pipe has no
signature; a check valve held shut draws the whole burst from its start node (the part of the
pipe after the burst stays shut). Every pipe at every position costs a few multiplications.

The signature localizer fits a free scale per pipe, so what matters is each signature's shape;
it is exact for a vanishing burst and the reference burst is moderate.
:mod:`benches/bench_linear_signatures.py` measures the agreement with the exact signatures
(and the time of both) on the shipped networks and L-TOWN.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import NetworkError
from burstloc.network import SteadyState

__all__ = ["LinearResponse", "anchored", "burst_signatures", "linear_response"]

GRAVITY = 9.81
"""m/s²."""

VISCOSITY = 1.1e-6
"""Kinematic viscosity of water (m²/s), as EPANET's default."""

MIN_GRADIENT = 1e-3
"""Smallest head-loss gradient (s/m²) of a pump or an open valve: a link with no loss at its
steady flow is stiff, not a short circuit that leaves a loop's flow undetermined."""

ISOLATED_LEAK = 1e-9
"""Demand gradient (m²/s) added at every junction, so that a group of junctions cut off from
every tank and reservoir (behind closed links) keeps the matrix regular; such a group is heard by
no meter outside it."""

_HW = 10.667
_CM = 10.29


class LinearResponse:
    """The head response at ``meters`` to a unit withdrawal at each junction (module docstring).

    ``drop[m, k]`` is the head drop (m) at ``meters[m]`` per m³/s withdrawn at node ``k`` of
    ``nodes`` (every node of the network; a tank or reservoir withdraws without effect: 0).
    """

    def __init__(self, meters: Sequence[str], nodes: Sequence[str], drop: NDArray[np.float64]):
        self.meters = tuple(meters)
        self.nodes = tuple(nodes)
        self.index = {name: i for i, name in enumerate(self.nodes)}
        self.drop = drop


def linear_response(
    wn: Any, state: SteadyState, meters: Sequence[str], engine: str = "PDD"
) -> LinearResponse:
    """Factorize the steady state ``state`` of ``wn`` linearized (module docstring) and solve it
    once per meter; ``engine`` is the demand model ``state`` was solved with (``"PDD"``
    pressure-driven, ``"DD"`` demand-driven: only emitters answer the pressure).

    Raises:
        NetworkError: the linearized equations are singular (the model's steady state is not a
            solution EPANET could have found).
    """
    from scipy.sparse import csc_matrix
    from scipy.sparse.linalg import splu

    junctions = list(wn.junction_name_list)
    jindex = {name: i for i, name in enumerate(junctions)}
    n_j, links = len(junctions), list(wn.link_name_list)
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []

    def put(row: int, col: int, value: float) -> None:
        rows.append(row)
        cols.append(col)
        vals.append(value)

    for j, name in enumerate(junctions):
        gradient = _demand_gradient(wn, wn.get_node(name), state.heads[name], engine)
        put(j, j, gradient + ISOLATED_LEAK)
    for i, name in enumerate(links):
        link = wn.get_link(name)
        row, col = n_j + i, n_j + i
        s, e = jindex.get(link.start_node_name, -1), jindex.get(link.end_node_name, -1)
        if s >= 0:
            put(s, col, 1.0)  # the flow leaves its start node
        if e >= 0:
            put(e, col, -1.0)
        law = _link_law(wn, link, state)
        if law == "fixed-flow" or (law == "hold-end" and e < 0) or (law == "hold-start" and s < 0):
            put(row, col, 1.0)
        elif law == "hold-end":
            put(row, e, 1.0)
        elif law == "hold-start":
            put(row, s, 1.0)
        else:  # a gradient: dh_s - dh_e - r dQ = 0 (a breaker: r = 0)
            if s >= 0:
                put(row, s, 1.0)
            if e >= 0:
                put(row, e, -1.0)
            put(row, col, -float(law))
    size = n_j + len(links)
    matrix = csc_matrix((vals, (rows, cols)), shape=(size, size))
    try:
        lu = splu(matrix)
    except RuntimeError as exc:  # SuperLU: "Factor is exactly singular"
        raise NetworkError(f"the linearized steady state is singular: {exc}") from exc
    meter_rows = [jindex[m] for m in meters]
    rhs = np.zeros((size, len(meter_rows)))
    rhs[meter_rows, np.arange(len(meter_rows))] = 1.0
    y = lu.solve(rhs, trans="T")  # row m of the inverse: dh_m per unit injection
    nodes = list(wn.node_name_list)
    drop = np.zeros((len(meter_rows), len(nodes)))
    where = np.array([jindex.get(n, -1) for n in nodes])
    junction_cols = np.flatnonzero(where >= 0)
    # a withdrawal w enters the balance as -w: the head change is -y[k], the drop y[k]
    drop[:, junction_cols] = y[where[junction_cols], :].T
    if not np.all(np.isfinite(drop)):
        raise NetworkError("the linearized steady state is singular (non-finite response)")
    return LinearResponse(meters, nodes, drop)


def burst_signatures(
    wn: Any,
    state: SteadyState,
    response: LinearResponse,
    pipes: Sequence[str],
    position: float,
    burst_coeff: float,
) -> NDArray[np.float64]:
    """The (pipes x meters) signature matrix of a reference burst of emitter coefficient
    ``burst_coeff`` at ``position`` along every pipe of ``pipes`` (module docstring)."""
    from burstloc.sim.signatures.epanet_inplace import split_elevation

    f = float(position)
    starts = np.array([response.index[wn.get_link(p).start_node_name] for p in pipes], dtype=int)
    ends = np.array([response.index[wn.get_link(p).end_node_name] for p in pipes], dtype=int)
    heads = np.array([state.heads[n] for n in response.nodes])
    point_head = (1 - f) * heads[starts] + f * heads[ends]
    elevation = np.array([split_elevation(wn.get_link(p), f) for p in pipes])
    exponent = float(wn.options.hydraulic.emitter_exponent)
    flow = burst_coeff * np.maximum(point_head - elevation, 0.0) ** exponent
    share = np.full(len(pipes), f)  # the part of the burst drawn through the pipe's end
    for i, p in enumerate(pipes):
        if p in state.closed:
            link = wn.get_link(p)
            if link.check_valve:  # held shut: the burst opens the part from its start
                share[i] = 0.0
            else:  # a burst inside a closed pipe is cut off
                flow[i] = 0.0
    shape = (1 - share) * response.drop[:, starts] + share * response.drop[:, ends]
    return np.asarray((shape * flow[None, :]).T, dtype=np.float64)


def anchored(
    exact_middle: NDArray[np.float64],
    linear_middle: NDArray[np.float64],
    linear: NDArray[np.float64],
) -> NDArray[np.float64]:
    """The hybrid signatures at a position (pipes x meters): the exact mid-pipe drop plus the
    linearized change from mid-pipe to the position (``linear - linear_middle``), scaled per
    pipe by the ratio of the exact to the linearized mid-pipe drop."""
    size = np.linalg.norm(linear_middle, axis=1, keepdims=True)
    scale = np.linalg.norm(exact_middle, axis=1, keepdims=True) / np.where(size > 0, size, 1.0)
    return np.asarray(exact_middle + scale * (linear - linear_middle), dtype=np.float64)


def _demand_gradient(wn: Any, node: Any, head: float, engine: str) -> float:
    """d(demand + emitter outflow)/d(head) (m²/s) of a junction at its steady head: EPANET
    2.2's pressure-driven demand and the emitter law ``q = C p^gamma``."""
    hyd = wn.options.hydraulic
    pressure = head - float(node.elevation)
    gradient = 0.0
    if engine.upper() == "PDD":
        full = float(node.demand_timeseries_list.at(0, multiplier=hyd.demand_multiplier))
        p_min = float(hyd.minimum_pressure)
        span = max(float(hyd.required_pressure) - p_min, 0.1)  # EPANET raises it to 0.1 m
        x = (pressure - p_min) / span
        if full > 0 and 0.0 < x < 1.0:
            e = float(hyd.pressure_exponent)
            gradient += full / (e * span) * x ** (1.0 / e - 1.0)
    coeff = float(getattr(node, "emitter_coefficient", None) or 0.0)
    if coeff > 0 and pressure > 0:
        gamma = float(hyd.emitter_exponent)
        gradient += gamma * coeff * pressure ** (gamma - 1.0)
    return gradient


def _link_law(wn: Any, link: Any, state: SteadyState) -> float | str:
    """A link's linearized law at the steady state: its head-loss gradient ``r`` (s/m²), or
    ``"fixed-flow"``, ``"hold-end"``, ``"hold-start"`` (module docstring)."""
    name = link.name
    if name in state.closed:
        return "fixed-flow"
    flow = abs(state.flows[name])
    loss = abs(state.heads[link.start_node_name] - state.heads[link.end_node_name])
    kind = link.link_type
    if kind == "Pipe":
        return _pipe_gradient(wn, link, flow)
    if kind == "Pump":
        return max(_pump_gradient(link, flow, loss), MIN_GRADIENT)
    valve = str(link.valve_type).upper()
    if name in state.active:
        if valve == "FCV":
            return "fixed-flow"
        if valve == "PRV":
            return "hold-end"
        if valve == "PSV":
            return "hold-start"
        if valve == "PBV":
            return 0.0
    return max(2 * loss / flow, MIN_GRADIENT) if flow > 1e-9 else MIN_GRADIENT


def _pipe_gradient(wn: Any, pipe: Any, flow: float) -> float:
    """d(headloss)/dQ (s/m²) of a pipe at ``flow`` (m³/s): friction by the network's formula
    plus minor loss, never below the laminar (Hagen-Poiseuille) gradient."""
    d, length, rough = float(pipe.diameter), float(pipe.length), float(pipe.roughness)
    area = math.pi * d * d / 4
    laminar = 128 * VISCOSITY * length / (GRAVITY * math.pi * d**4)
    minor = 2 * float(pipe.minor_loss) / (2 * GRAVITY * area * area) * flow
    formula = str(wn.options.hydraulic.headloss).upper()
    if formula == "H-W":
        friction = 1.852 * _HW * rough**-1.852 * d**-4.871 * length * flow**0.852
    elif formula == "C-M":
        friction = 2 * _CM * rough**2 * length * d ** (-16.0 / 3.0) * flow
    else:  # D-W: the derivative of Swamee-Jain's friction law, numerically
        step = max(flow * 1e-4, 1e-9)
        hi = _darcy_loss(flow + step, d, length, rough)
        friction = (hi - _darcy_loss(flow - step, d, length, rough)) / (2 * step)
    return max(friction + minor, laminar)


def _darcy_loss(flow: float, d: float, length: float, rough: float) -> float:
    """Darcy-Weisbach friction loss (m) at ``flow`` (m³/s): 64/Re when laminar, Swamee-Jain
    above (EPANET 2.2's transitional interpolation left out: the gradient is floored anyway)."""
    flow = abs(flow)
    if flow <= 0:
        return 0.0
    area = math.pi * d * d / 4
    velocity = flow / area
    reynolds = velocity * d / VISCOSITY
    if reynolds < 2000:
        factor = 64 / reynolds
    else:
        factor = 0.25 / math.log10(rough / (3.7 * d) + 5.74 / reynolds**0.9) ** 2
    return factor * length / d * velocity * velocity / (2 * GRAVITY)


def _pump_gradient(pump: Any, flow: float, gain: float) -> float:
    """Minus the slope (s/m²) of a pump's head curve at ``flow`` and its speed at the start;
    ``gain / flow`` for a pump given by its power (``gain * flow`` constant)."""
    if pump.pump_type != "HEAD":
        return gain / flow if flow > 1e-9 else 0.0
    speed = float(pump.speed_timeseries.at(0)) or 1.0
    points = list(pump.get_pump_curve().points)
    q = flow / speed
    if len(points) > 3:  # EPANET interpolates a multi-point curve linearly
        qs = np.array([p[0] for p in points])
        hs = np.array([p[1] for p in points])
        k = int(np.clip(np.searchsorted(qs, q) - 1, 0, len(qs) - 2))
        slope = (hs[k + 1] - hs[k]) / (qs[k + 1] - qs[k]) if qs[k + 1] > qs[k] else 0.0
    else:
        _, b, c = pump.get_head_curve_coefficients()
        slope = -b * c * q ** (c - 1) if q > 0 or c >= 1 else 0.0
    return -speed * float(slope)
