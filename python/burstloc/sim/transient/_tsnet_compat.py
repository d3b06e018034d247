"""TSNet 0.3.1 on numpy 2 and current WNTR: small patches, applied before every run.

TSNet 0.3.1 (its last release) was written against numpy 1 and WNTR 1.3. Three of its
functions leave 1-element arrays where numbers belong, and numpy 2 refuses to convert them
to scalars; one relies on WNTR accepting a zero pipe roughness:

* ``tsnet.network.discretize.cal_N`` returns the reaches per pipe as an ``(n, 1)`` array, so
  ``int(Ndis[i])`` in ``discretization`` fails. Patched: the same numbers as a flat array.
* ``tsnet.network.discretize.adjust_wavev`` computes the time step and each pipe's adjusted
  wave speed through ``(1, 1)`` matrix products, so ``tm.time_step`` and every ``pipe.wavev``
  are 1-element arrays; ``'%.5f' % tm.time_step`` in ``set_time`` and the MOC solver's
  element assignments then fail. Patched: TSNet's own function runs unchanged, then these
  values are stored as the NumPy float64 scalars they hold (the same bits).
* ``tsnet.simulation.solver.add_leakage`` (every junction: demand, emitter, burst) returns the
  node's velocity as a 1-element array, which ``tsnet.simulation.single`` stores into an
  element of its velocity array; numpy 2 refuses. Patched (where ``single`` calls it): the
  same value as a float64 scalar.
* ``tsnet.simulation.initialize.cal_roughness_coef`` sets the roughness of a pipe without
  steady flow to 0 (no friction); WNTR >= 1.4 rejects a roughness <= 0. Patched: that case
  stores the 0 past WNTR's check, exactly as TSNet meant. And it replaces a Darcy-Weisbach
  factor above 0.08 by 0.03, so the pipe loses a fraction of EPANET's head and the network
  moves before any event (a Hazen-Williams pipe at low velocity: over half of KY14's pipes,
  KY13's; a pipe with a large minor loss: BWSN_Network_1). Patched: the pipe keeps the factor
  of its steady head loss; every other case runs TSNet's code.

Two more make TSNet's valve and pump operations run (they failed on every WNTR we install):

* ``TransientModel.valve_opening`` and ``TransientModel.pump_start_up`` set ``link.status``
  (to close the link before it opens), but in WNTR (1.3.2 as in 1.5) a link's ``status`` is a
  read-only property: "use initial_status". Patched: TSNet's own code, with the status set
  through ``initial_status`` (what WNTR's EPANET writer and TSNet's solver read).
* ``tsnet.simulation.initialize.pump_operation_points`` replaces the design point nearest to
  each pump's initial operating point with that point. A stopped pump (a start-up: no initial
  flow) has no operating point: the head across it is not a pump head, and the refit would
  bend the curve through it (lowering the shut-off head). Patched: a stopped pump's curve is
  fitted through its operating point at full speed, as ``pump_start_up`` computed it
  (``nominal_flow``, ``nominal_pump_head``); running pumps keep TSNet's code. And a starting
  pump's speed is kept at 0.01 % or more, as TSNet's ``pumpclosing`` keeps a tripped one (at
  zero speed its scaled curve is three identical points: no parabola, a division by zero).
  A pump curve of more than three points (EPANET's multi-point curve, e.g. Anytown's five),
  which TSNet refused, keeps three of them, its first, middle and last, before TSNet's refit
  (which replaces the one nearest the operating point with that point, so the transient starts
  from EPANET's steady state).
  Where that refit rises at the operating point (a pump near shut-off, whose shut-off point is
  the one replaced: MICROPOLIS's well pumps), the pump would feed waves back amplified and the
  network drifts before any event: the curve becomes ``H = H_s - K Q^2`` through the operating
  point with the slope of the design curve there.

And one makes a network with a junction below atmospheric pressure at the start simulate:

* ``tsnet.simulation.initialize.cal_demand_coef`` divides each end node's demand by the square
  root of its pressure; a junction without demand at a negative pressure (EPANET's Net3: junction
  10, behind the closed Lake pump) gets ``0 / sqrt(-0.45)``, NaN, and every head of the network
  turns NaN within a few steps. Patched: a node without demand has coefficient 0, as TSNet gives
  it at any positive pressure, and so has one below zero pressure that EPANET's pressure-driven
  steady state delivers nothing (its demand there is numerical residue, 1e-8 m³/s: KY15,
  exnet-3); every other case runs TSNet's code.
* ``tsnet.simulation.solver.dead_end`` solves a dead end's head from ``Q = k sqrt(p)`` with
  ``sqrt(p)`` as the unknown; without demand (``k = 0``) below atmospheric pressure it has no
  root, and TSNet holds the head at the elevation (zero pressure, its floor): junction 10
  jumped 0.45 m at the first step. Patched (where ``single`` calls it): a dead end without
  demand that *starts* below atmospheric pressure has its floor at that starting pressure
  instead; above it, the head is TSNet's own expression continued below zero pressure,
  ``elevation - cq`` (its root ``elevation + (sqrt(-cq))**2`` where ``cq <= 0``), the closed
  end's characteristic. Every other dead end, and any with a root, runs TSNet's code.

Nothing else changes: on the pinned stack (numpy 1.26, WNTR 1.3.2) the patched TSNet gives
bit-identical heads wherever no junction without demand starts below atmospheric pressure
(``tests/sim/test_tsnet_compat.py`` checks this, checks numpy 2 against heads stored from the
pinned stack, and shows each of the last two patches needed where one does). TSNet is
MIT-licensed; the thresholds below are TSNet's.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np

from burstloc.constants import PRESSURE_NOISE
from burstloc.exceptions import SimulatorMissingError
from burstloc.network_file import import_wntr

__all__ = ["applied", "load"]

#: TSNet's thresholds in ``cal_roughness_coef``: below either, the pipe has no friction.
_V_TOL = 1e-5
_H_TOL = 1e-3
#: TSNet's gravity (m/s²) and its cap on a Darcy-Weisbach friction factor in
#: ``cal_roughness_coef`` (above it TSNet warns and takes 0.03).
_G = 9.8
_MAX_FRICTION = 0.08

#: TSNet's ``pumpclosing`` keeps a "closed" pump at this speed (its curve scaled by zero speed
#: is three identical points, which no parabola fits); ``pumpopening`` did not: now it does.
_MIN_SPEED = 1e-4

#: Below this demand (m³/s) a node below zero pressure delivers none (EPANET's pressure-driven
#: demand there is numerical residue, a few 1e-8 m³/s).
_NO_DEMAND = 1e-6

#: Below this flow (m³/s) a pump has no operating point: it is stopped.
_Q_TOL = 1e-9

_ORIGINALS: dict[str, Callable[..., Any]] = {}


def applied() -> bool:
    """Whether :func:`load` has patched TSNet in this process."""
    return bool(_ORIGINALS)


def load() -> ModuleType:
    """Import TSNet, patched (once per process), and return it.

    Raises:
        SimulatorMissingError: TSNet is not installed (it comes with the ``sim`` extra).
    """
    import_wntr()  # TSNet imports WNTR: imported first, without its import-time noise
    try:
        import tsnet
        from tsnet.network import discretize, model
        from tsnet.simulation import initialize, single
    except ImportError as exc:
        raise SimulatorMissingError(exc) from exc
    if not _ORIGINALS:
        _ORIGINALS["cal_N"] = discretize.cal_N
        _ORIGINALS["adjust_wavev"] = discretize.adjust_wavev
        _ORIGINALS["cal_roughness_coef"] = initialize.cal_roughness_coef
        _ORIGINALS["cal_demand_coef"] = initialize.cal_demand_coef
        initialize.cal_demand_coef = _cal_demand_coef
        _ORIGINALS["add_leakage"] = single.add_leakage
        _ORIGINALS["dead_end"] = single.dead_end
        single.dead_end = _dead_end
        discretize.cal_N = _cal_n
        discretize.adjust_wavev = _adjust_wavev
        initialize.cal_roughness_coef = _cal_roughness_coef
        single.add_leakage = _add_leakage
        _ORIGINALS["pump_operation_points"] = initialize.pump_operation_points
        initialize.pump_operation_points = _pump_operation_points
        _ORIGINALS["valve_opening"] = model.TransientModel.valve_opening
        _ORIGINALS["pump_start_up"] = model.TransientModel.pump_start_up
        model.TransientModel.valve_opening = _valve_opening
        model.TransientModel.pump_start_up = _pump_start_up
    return tsnet


def _scalar(value: Any) -> np.float64:
    """A 1-element array (or a number) as the float64 scalar it holds."""
    return np.float64(np.asarray(value, dtype=np.float64).item())


def _cal_n(tm: Any, dt: float) -> np.ndarray:
    """TSNet's ``cal_N`` as a flat array (``int(N[i])`` needs a scalar under numpy 2)."""
    return np.asarray(_ORIGINALS["cal_N"](tm, dt)).ravel()


def _adjust_wavev(tm: Any) -> Any:
    """TSNet's ``adjust_wavev``, then its time step and wave speeds as float64 scalars."""
    tm = _ORIGINALS["adjust_wavev"](tm)
    tm.time_step = _scalar(tm.time_step)
    for _, pipe in tm.pipes():
        pipe.wavev = _scalar(pipe.wavev)
    return tm


def _cal_roughness_coef(pipe: Any, velocity: Any, head_loss: Any) -> Any:
    """TSNet's ``cal_roughness_coef``; a pipe without steady flow gets roughness 0 past WNTR;
    a pipe with a minor loss keeps the friction factor of its steady head loss above TSNet's
    cap of 0.08 (which sets 0.03 instead: BWSN_Network_1's pump suction main, minor loss 800,
    then lost a fraction of EPANET's head and its pump moved 22 m before any burst)."""
    if abs(velocity) >= _V_TOL and head_loss >= _H_TOL:
        factor = head_loss / (pipe.length / pipe.diameter) / (velocity**2 / 2 / _G)
        if factor > _MAX_FRICTION:
            pipe.roughness = factor
            pipe.roughness_height = max(
                10 ** (-1 / 1.8 / np.sqrt(factor)) - 6.9 / pipe.initial_Re, 0
            )
            return pipe
        return _ORIGINALS["cal_roughness_coef"](pipe, velocity, head_loss)
    pipe._roughness = 0  # TSNet's "no friction"; WNTR >= 1.4's setter refuses 0
    pipe.roughness_height = 0
    return pipe


def _cal_demand_coef(demand: Any, pipe: Any, hs: Any, he: Any, t0: float = 0.0) -> Any:
    """TSNet's ``cal_demand_coef``; a node without demand gets coefficient 0 whatever its
    pressure (TSNet: ``0 / sqrt(p)``, NaN below atmospheric pressure), and so does a node at
    zero pressure within :data:`~burstloc.constants.PRESSURE_NOISE` (TSNet: ``q / sqrt(0)``,
    infinite, or NaN a micrometre below) and one below zero pressure that EPANET's
    pressure-driven steady state delivers no demand (TSNet: NaN; KY15, exnet-3)."""
    with np.errstate(invalid="ignore", divide="ignore"):  # q / sqrt(p <= 0), mended below
        pipe = _ORIGINALS["cal_demand_coef"](demand, pipe, hs, he, t0)
    if _no_demand(demand[0], hs):
        pipe.start_node.demand_coeff = 0.0
    if _no_demand(demand[1], he):
        pipe.end_node.demand_coeff = 0.0
    return pipe


def _no_demand(demand: Any, pressure: Any) -> bool:
    """Whether a node's demand coefficient is 0: no demand, zero pressure (within
    :data:`~burstloc.constants.PRESSURE_NOISE`), or below zero pressure with no demand delivered
    (EPANET's pressure-driven demand there: a few 1e-8 m³/s of numerical residue)."""
    return bool(
        demand == 0
        or -PRESSURE_NOISE <= pressure <= 0
        or (pressure < 0 and abs(demand) < _NO_DEMAND)
    )


def _dead_end(
    linkp: Any,
    H1: Any,
    V1: Any,
    elev: Any,
    nn: int,
    a: Any,
    g: Any,
    f: Any,
    D: Any,
    dt: Any,
    KD: Any,
    friction: Any,
    dVdx1: Any,
    dVdt1: Any,
) -> tuple[Any, Any]:
    """TSNet's ``dead_end``; a dead end without demand that starts below atmospheric pressure
    keeps the closed end's head ``elevation - cq`` (not below its start) where TSNet has no
    root, instead of the elevation."""
    from tsnet.simulation.solver import cal_friction

    args = (linkp, H1, V1, elev, nn, a, g, f, D, dt, KD, friction, dVdx1, dVdt1)
    node = linkp.start_node if nn == 0 else linkp.end_node
    if node.demand_coeff + node.emitter_coeff != 0:
        return _ORIGINALS["dead_end"](*args)
    J = cal_friction(friction, f, D, V1, KD, dt, dVdt1, dVdx1, a, g)
    if nn == 0:
        cq = a / g * V1 - a / g * J - H1 - g / a * dt * V1 * linkp.theta + elev
    else:
        cq = -a / g * V1 + a / g * J - H1 - g / a * dt * V1 * linkp.theta + elev
    floor = min(elev, node.initial_head)
    if cq <= 0 or floor >= elev:  # a root, or a dead end that starts above zero pressure
        return _ORIGINALS["dead_end"](*args)
    HP = max(elev - cq, floor)
    loss = f * dt / (2.0 * D) * V1 * abs(V1)
    if nn == 0:
        VP = V1 - g / a * H1 - loss + g / a * HP - g / a * dt * V1 * linkp.theta
    else:
        VP = V1 + g / a * H1 - loss - g / a * HP + g / a * dt * V1 * linkp.theta
    return HP, VP


def _add_leakage(*args: Any, **kwargs: Any) -> tuple[Any, np.float64]:
    """TSNet's ``add_leakage``, its velocity (a 1-element array) as a float64 scalar."""
    head, velocity = _ORIGINALS["add_leakage"](*args, **kwargs)
    return head, _scalar(velocity)


def _set_status(link: Any, status: Any) -> None:
    """Set a WNTR link's status the way WNTR allows (its ``status`` is read-only)."""
    link.initial_status = status
    link._user_status = status


def _valve_opening(tm: Any, name: str, rule: Any, curve: Any = None) -> None:
    """TSNet's ``valve_opening``: the valve starts closed, then opens by ``rule``."""
    from tsnet.network.control import valveopening
    from wntr.network.elements import LinkStatus

    valve = tm.get_link(name)
    if valve.link_type.lower() != "valve":
        raise RuntimeError("The name of valve to operate is not associated with a vale")
    _set_status(valve, LinkStatus.Closed)
    valve.operating = True
    valve.operation_rule = valveopening(tm.time_step, tm.simulation_period, rule)
    valve.valve_coeff = None if curve is None else [[p for p, _ in curve], [k for _, k in curve]]


def _pump_start_up(tm: Any, name: str, rule: Any) -> None:
    """TSNet's ``pump_start_up``: the pump's full-speed operating point from EPANET (pump open),
    then the pump starts closed and opens by ``rule``."""
    import wntr
    from tsnet.network.control import pumpopening
    from wntr.network.elements import LinkStatus

    pump = tm.get_link(name)
    if pump.link_type.lower() != "pump":
        raise RuntimeError("The name of pump to operate is not associated with a pump")
    _set_status(pump, LinkStatus.Open)
    results = wntr.sim.EpanetSimulator(tm).run_sim()
    pump.nominal_flow = float(results.link["flowrate"].loc[0, name])
    heads = results.node["head"].loc[0]
    pump.nominal_pump_head = abs(float(heads[pump.end_node_name] - heads[pump.start_node_name]))
    _set_status(pump, LinkStatus.Closed)
    pump.operating = True
    speed = pumpopening(tm.time_step, tm.simulation_period, rule)
    pump.operation_rule = np.maximum(speed, _MIN_SPEED)


def _pump_operation_points(tm: Any) -> Any:
    """TSNet's ``pump_operation_points``; a stopped pump's curve goes through its full-speed
    operating point (``nominal_flow``, ``nominal_pump_head``) instead of a zero-flow point."""
    from tsnet.utils import calc_parabola_vertex

    for _, pump in tm.pumps():
        point = (pump.initial_flow, abs(pump.end_node.initial_head - pump.start_node.initial_head))
        if abs(pump.initial_flow) < _Q_TOL and hasattr(pump, "nominal_flow"):
            point = (pump.nominal_flow, pump.nominal_pump_head)
        points = pump.get_pump_curve().points
        if len(points) == 1:
            (flow, head) = points[0]
            points.append((0.0, 1.33 * head))
            points.append((2 * flow, 0.0))
        elif len(points) > 3:
            # a multi-point curve: its shut-off, middle and last points (TSNet refused it)
            points[:] = [points[0], points[len(points) // 2], points[-1]]
        elif len(points) != 3:
            raise Exception("TSNet only support one-point or three-point pump curve.")
        design = list(points)
        dist = [np.sqrt((q - point[0]) ** 2 + (h - point[1]) ** 2) for q, h in points]
        points.remove(points[dist.index(min(dist))])
        points.append(point)
        pump.curve_coef = calc_parabola_vertex(points)
        if _slope(pump.curve_coef, point[0]) >= 0:
            _falling_curve(pump, point, design)
    return tm


def _falling_curve(pump: Any, point: tuple[float, float], design: list[Any]) -> None:
    """Give ``pump`` (whose refit curve rises at its operating point ``point``, where it would
    feed every pressure wave back amplified: a pump near shut-off whose shut-off point TSNet
    replaced, as MICROPOLIS's well pumps) the parabola ``H = H_s - K Q^2`` through ``point``
    with the slope of its ``design`` curve there (the chord of the two design points around
    the flow); a design curve that does not fall there keeps TSNet's refit."""
    from tsnet.utils import calc_parabola_vertex

    flow, head = point
    ordered = sorted(design)
    i = next((k for k in range(1, len(ordered) - 1) if flow < ordered[k][0]), len(ordered) - 1)
    (q1, h1), (q2, h2) = ordered[i - 1], ordered[i]
    slope = (h2 - h1) / (q2 - q1) if q2 > q1 else 0.0
    if slope >= 0 or flow <= 0:
        return
    k = -slope / (2.0 * flow)
    shutoff = head + k * flow**2
    points = pump.get_pump_curve().points
    points[:] = [(0.0, shutoff), (flow, head), (2.0 * flow, shutoff - 4.0 * k * flow**2)]
    pump.curve_coef = calc_parabola_vertex(points)


def _slope(coefficients: Any, flow: float) -> float:
    """``dH/dQ`` at ``flow`` of the parabola ``H = a Q^2 + b Q + c`` (``(a, b, c)``)."""
    a, b, _ = coefficients
    return float(2 * a * flow + b)
