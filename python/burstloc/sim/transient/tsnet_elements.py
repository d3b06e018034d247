"""Pumps given by their power and valves EPANET controls, as TSNet can simulate them.

TSNet 0.3.1 knows a pump only by its head curve (``get_pump_curve``) and a valve only by its
opening (a gate valve's loss at 100 % or 0 % open); EPANET knows two more kinds of element:

* **A pump given by its power** (``POWER`` in [PUMPS]: a constant power ``P`` adding the head
  ``H = P / (rho g Q)``; the Kentucky networks KY1, KY3, KY10, ...) stopped TSNet
  ("'PowerPump' object has no attribute 'get_pump_curve'"). :func:`settle_pumps_and_check_valves`
  (called by :func:`burstloc.sim.transient.tsnet_ready.prepare_for_tsnet`) turns each into a head
  pump whose
  curve agrees with the constant-power hyperbola at EPANET's operating point ``(Q0, H0)`` in head
  and slope (``dH/dQ = -H0 / Q0``): the parabola ``H = 1.5 H0 - H0 Q^2 / (2 Q0^2)`` through
  ``(0, 1.5 H0)``, ``(Q0, H0)`` and ``(sqrt(3) Q0, 0)``. The steady state is unchanged (the
  curve passes through the operating point) and a small transient sees the pump respond as the
  constant-power pump does to first order.
* **A pump or a check-valve pipe EPANET gives no flow at the start** (a pump a control stops at
  the start, a check valve held shut by the heads: MICROPOLIS's 52 of 54), **and a pipe EPANET
  reports closed** (at a full or empty tank, which EPANET shuts rather than overfill or drain:
  KY11's tanks T-24 and T-4; or by a control at the start) TSNet would run as open (it holds a
  tank's head): :func:`settle_pumps_and_check_valves` makes each a closed valve, which TSNet
  keeps shut.
* **A valve EPANET controls** (PRV, PSV, PBV, FCV, TCV or GPV with status ``Active``: EPANET sets
  its loss to hold a pressure or flow) TSNet takes as closed (only ``Open`` and ``Closed`` have a
  loss in its MOC): L-TOWN's PRVs moved junction n336 by 114 m within 0.044 s, before any burst.
  And an ``Open`` valve it gives a fully open gate valve's loss (``V^2 / (10 g)``), not EPANET's
  (a TCV's setting, a minor loss): MICROPOLIS's 200 TCVs moved its heads by metres.
  :func:`hold_valves` (called once TSNet's initializer has EPANET's steady state) gives each such
  valve the fixed loss it has in that state, ``dH0 = V^2 / (2 g K)`` (``V`` the velocity of the
  pipe after the valve, TSNet's valve equation), so the transient starts where EPANET's state
  is and the valve then acts as a fixed loss: over the seconds a burst is localized in, a
  pressure-reducing valve's pilot does not move. A valve EPANET gives no flow is closed; a
  valve an event operates (``burstloc simulate --event``) and a ``Closed`` one EPANET gives no
  flow keep TSNet's own model; a ``Closed`` one a control sets at the start (so EPANET runs it:
  BWSN_Network_2's FCVs filling its tanks) is held like an active one.

:func:`check_steady_state` refuses, before any of this, a model whose steady state serves no
water: a junction with a demand below absolute vacuum (anytown-exeter: -30.5 m; KY15: -49 m),
or none of the demand delivered (hanoi-exeter, whose pipes are 0.0001 mm wide), naming the
junction and its line.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass
from typing import Any

from burstloc import network
from burstloc.constants import VACUUM_HEAD
from burstloc.exceptions import NetworkError
from burstloc.inp import node_line
from burstloc.network import _fresh_name
from burstloc.sim.transient.moc_elements import G

__all__ = [
    "HeldValve",
    "PowerPumpCurve",
    "check_steady_state",
    "hold_valves",
    "settle_pumps_and_check_valves",
]

#: Below this flow (m³/s) a pump, valve or check-valve pipe is taken as carrying none at the
#: start: EPANET gives a link it closes a flow of 1e-6 ft³/s (2.8e-8 m³/s), not zero.
NO_FLOW = 1e-6
#: The largest inverse loss coefficient a held valve gets (TSNet's fully open gate valve has 5):
#: a valve EPANET gives (almost) no loss loses ``V^2 / (2 g 1e4)``, 0.005 mm at 1 m/s.
MAX_INVERSE_LOSS = 1e4


#: A steady state delivering less than this share of the demand asked at the start delivers none.
MIN_DELIVERED = 0.01


def check_steady_state(wn: Any, state: network.SteadyState, path: str) -> None:
    """Refuse a model (INP file ``path``, WNTR model ``wn``) whose EPANET steady state
    ``state`` serves no water: a junction with a demand below absolute vacuum
    (:data:`~burstloc.constants.VACUUM_HEAD`: consumers at a pressure no water has), or none
    of the demand delivered. (A junction without demand may start below atmospheric pressure,
    as Net3's junction 10 behind its closed pump: the transient holds it there.)

    Raises:
        NetworkError: naming the junction (the lowest; the one short of the most demand), its
            line in ``path`` and the figures.
    """
    multiplier = wn.options.hydraulic.demand_multiplier
    asked = {
        name: float(j.demand_timeseries_list.at(0.0, multiplier=multiplier))
        for name, j in wn.junctions()
    }
    pressures = {name: state.heads[name] - float(wn.get_node(name).elevation) for name in asked}
    served = [name for name, q in asked.items() if q > 0]
    if not served:
        return
    lowest = min(served, key=pressures.__getitem__)
    if pressures[lowest] < VACUUM_HEAD:
        below = sum(pressures[name] < VACUUM_HEAD for name in served)
        raise NetworkError(
            f"{_where(path, lowest)}: junction {lowest!r} (demand {asked[lowest]:.3g} m³/s) is "
            f"at {pressures[lowest]:.3g} m pressure head in EPANET's steady state, below "
            f"absolute vacuum ({VACUUM_HEAD:g} m; {below} junction(s) with a demand below it): "
            "the model is at fault there"
        )
    wanted = sum(asked[name] for name in served)
    got = sum(max(state.demands.get(name, 0.0), 0.0) for name in served)
    if state.demands and got < MIN_DELIVERED * wanted:
        short = max(served, key=lambda n: asked[n] - state.demands.get(n, 0.0))
        raise NetworkError(
            f"{_where(path, short)}: EPANET's steady state delivers {got:.3g} of the "
            f"{wanted:.3g} m³/s the junctions ask (junction {short!r}: "
            f"{state.demands.get(short, 0.0):.3g} of {asked[short]:.3g} m³/s, pressure head "
            f"{pressures[short]:.3g} m): the model carries no water to burst"
        )


def _where(path: str, node: str) -> str:
    """``path:line`` of the node's definition (``path`` alone when not found)."""
    line = node_line(path, node)
    return path if line is None else f"{path}:{line}"


@dataclass(frozen=True)
class PowerPumpCurve:
    """A pump given by ``power`` (W) as a head pump: ``curve`` (the new curve's name) through
    EPANET's operating point ``flow`` (m³/s) and ``head`` (m); ``removed`` when EPANET gave it no
    flow at the start."""

    pump: str
    power: float
    flow: float
    head: float
    curve: str


def settle_pumps_and_check_valves(
    wn: Any, keep: Collection[str] = (), engine: str = "PDD"
) -> tuple[list[str], list[PowerPumpCurve]]:
    """Give ``wn`` (changed in place) EPANET's state at the start where TSNet would not: the
    pumps and the check-valve pipes that carry no flow in it (stopped by a control at the start,
    or a check valve held shut: TSNet would run them) and the pipes it reports closed (at a full
    or empty tank, by a control), except ``keep``, become closed valves
    of the same name (TSNet keeps a closed valve shut; removed, they could cut a part of the
    network off its sources), and every power pump becomes a head pump with the equivalent
    curve at its operating point (see the module's description). Return the links closed and
    the power pumps' curves.

    Raises:
        NetworkError: a power pump whose steady state has it run backwards or add no head.
    """
    checks = [name for name, pipe in wn.pipes() if pipe.check_valve]
    if not (wn.num_pumps or checks or wn.num_tanks or wn.control_name_list):
        return [], []
    state = network.steady_state(wn, engine)
    shut = [name for name in wn.pipe_name_list if name in state.closed]  # tanks, controls
    at_rest = [
        name
        for name in dict.fromkeys([*wn.pump_name_list, *checks, *shut])
        if (abs(state.flows[name]) < NO_FLOW or name in state.closed) and name not in keep
    ]
    for name in at_rest:
        _close(wn, name)
    curves = [
        _power_curve(wn, name, state) for name, pump in wn.pumps() if pump.pump_type == "POWER"
    ]
    return at_rest, curves


def _close(wn: Any, name: str) -> None:
    """Replace the link ``name`` by a closed valve (TCV) of the same name between its nodes."""
    link = wn.get_link(name)
    start, end = link.start_node_name, link.end_node_name
    diameter = float(getattr(link, "diameter", 0.0) or 0.0)
    if diameter <= 0:  # a pump: as wide as the widest pipe at its nodes
        pipes = [
            wn.get_link(n)
            for node in (start, end)
            for n in wn.get_links_for_node(node)
            if wn.get_link(n).link_type == "Pipe"
        ]
        diameter = max((float(p.diameter) for p in pipes), default=0.3)
    wn.remove_link(name, with_control=True)
    for subset in ("_pumps", "_head_pumps", "_power_pumps", "_pipes"):
        # WNTR 1.3's registry stops half-way for a pump with no speed pattern (a KeyError it
        # swallows): the pump stays listed under its type, and wn.pumps() then fails
        getattr(wn._link_reg, subset).discard(name)
    wn.add_valve(
        name,
        start,
        end,
        diameter=diameter,
        valve_type="TCV",
        minor_loss=0.0,
        initial_setting=0.0,
        initial_status="Closed",
    )


def _power_curve(wn: Any, name: str, state: network.SteadyState) -> PowerPumpCurve:
    """Make the power pump ``name`` a head pump through its operating point in ``state``."""
    from wntr.network.elements import HeadPump

    pump = wn.get_link(name)
    flow = state.flows[name]
    head = state.heads[pump.end_node_name] - state.heads[pump.start_node_name]
    power = float(pump.power)
    if flow <= 0 or head <= 0:
        raise NetworkError(
            f"pump {name!r} (power {power:g} W) runs at {flow:.4g} m³/s and {head:.4g} m in "
            "EPANET's steady state: a pump must lift water forwards"
        )
    curve = _fresh_name(f"{name}_P", set(wn.curve_name_list), "POWERCURVE")
    wn.add_curve(curve, "HEAD", [(0.0, 1.5 * head), (flow, head), (math.sqrt(3.0) * flow, 0.0)])
    registry = wn._link_reg  # WNTR files each pump under its type
    pump.__class__ = HeadPump  # same object: the controls naming it keep working
    pump._pump_curve_name = None  # a head pump's own attribute
    pump.pump_curve_name = curve
    pump.base_speed = 1.0
    registry._power_pumps.discard(name)
    registry._head_pumps.add(name)
    return PowerPumpCurve(name, power, flow, head, curve)


@dataclass(frozen=True)
class HeldValve:
    """An active valve held at its steady state: ``loss`` (m) at ``flow`` (m³/s), TSNet's inverse
    loss coefficient ``inverse_loss`` (0: closed)."""

    valve: str
    valve_type: str
    flow: float
    loss: float
    inverse_loss: float


def _pipe_area(tm: Any, node: str, valve: str) -> float | None:
    """Cross-section (m²) of the one pipe beyond ``valve`` at ``node`` (None: not one pipe)."""
    pipes = [
        tm.get_link(name)
        for name in tm.get_links_for_node(node)
        if name != valve and tm.get_link(name).link_type == "Pipe"
    ]
    if len(pipes) != 1:
        return None
    return math.pi * float(pipes[0].diameter) ** 2 / 4.0


def hold_valves(tm: Any) -> list[HeldValve]:
    """Give every valve of TSNet's model ``tm`` (after its initializer) that is active or open,
    or closed but given a flow in EPANET's steady state (a control at the start sets it:
    BWSN_Network_2's FCVs filling its tanks, which TSNet shut and moved a junction by 106 m), and
    that no event operates, the fixed loss it has in EPANET's steady state; return them."""
    from wntr.network.base import LinkStatus

    held = []
    for name, valve in tm.valves():
        flow = float(valve.initial_flow)
        shut = valve.initial_status.name == "Closed"
        if getattr(valve, "operating", False) or (shut and abs(flow) < NO_FLOW):
            continue
        start, end = valve.start_node, valve.end_node
        loss = float(start.initial_head) - float(end.initial_head)
        area = _pipe_area(tm, end.name if flow >= 0 else start.name, name)
        if area is None:  # a valve at the network's edge: TSNet holds its flow (valve_end)
            if shut:  # ... if open
                valve.initial_status = LinkStatus.Open
            continue
        velocity = abs(flow) / area
        if abs(flow) < NO_FLOW:
            inverse = 0.0
        elif loss * math.copysign(1.0, flow) <= 0:
            inverse = MAX_INVERSE_LOSS
        else:
            inverse = min(velocity**2 / (2 * G * abs(loss)), MAX_INVERSE_LOSS)
        valve.valve_coeff = [[100.0, 0.0], [inverse, 0.0]]
        valve.initial_status = LinkStatus.Open if inverse > 0 else LinkStatus.Closed
        held.append(HeldValve(name, valve.valve_type, flow, loss, inverse))
    return held
