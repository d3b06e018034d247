"""The non-burst events ``burstloc evaluate --events`` operates on a network.

Every valve and pump operated (:data:`VALVE_EVENTS`, :data:`PUMP_EVENTS`) and demand steps at the
largest consumers (:data:`DEMAND_JUNCTIONS`), as
:class:`burstloc.sim.events.operations.EventScenario`
values, and the junctions beside each valve and pump (:func:`asset_nodes`: where the classifier
expects an operation's wave to be heard first).
"""

from __future__ import annotations

from burstloc.network import NetworkSource
from burstloc.sim.events.operations import EventScenario

__all__ = [
    "DEMAND_JUNCTIONS",
    "PUMP_EVENTS",
    "VALVE_EVENTS",
    "asset_nodes",
    "default_events",
]

#: The operations of each valve and pump: (kind, keyword arguments): fast (1-2 s) and slow
#: (10-30 s), full and partial (to 30 % open).
VALVE_EVENTS: tuple[tuple[str, dict[str, float]], ...] = (
    ("valve-closure", {"operation_time": 1.0}),
    ("valve-closure", {"operation_time": 30.0}),
    ("valve-closure", {"operation_time": 1.0, "setting": 0.3}),
    ("valve-closure", {"operation_time": 30.0, "setting": 0.3}),
    ("valve-opening", {"operation_time": 1.0, "setting": 1.0}),
    ("valve-opening", {"operation_time": 30.0, "setting": 1.0}),
    ("valve-opening", {"operation_time": 1.0, "setting": 0.3}),
)
PUMP_EVENTS: tuple[tuple[str, dict[str, float]], ...] = (
    ("pump-trip", {"operation_time": 1.0}),
    ("pump-trip", {"operation_time": 10.0}),
    ("pump-start", {"operation_time": 2.0}),
    ("pump-start", {"operation_time": 10.0}),
)
#: Demand steps at the junctions of largest base demand: this many junctions, each doubling
#: its demand in 1 s and adding a quarter of it in 5 s; the largest also halves in 1 s.
DEMAND_JUNCTIONS = 4


def default_events(
    network: NetworkSource, duration: float, solver: str = "vectorized"
) -> list[EventScenario]:
    """The events of the evaluation on ``network``: :data:`VALVE_EVENTS` on every valve,
    :data:`PUMP_EVENTS` on every pump, demand steps at :data:`DEMAND_JUNCTIONS` junctions
    (simulated by ``solver``)."""
    from burstloc import network as netmod

    read = netmod.as_network(network)
    path, wn = read.path, read.model
    out: list[tuple[str, str, dict[str, float]]] = []
    for valve in wn.valve_name_list:
        out += [(kind, valve, kw) for kind, kw in VALVE_EVENTS]
    for pump in wn.pump_name_list:
        out += [(kind, pump, kw) for kind, kw in PUMP_EVENTS]
    demands = {j: float(wn.get_node(j).base_demand) for j in netmod.junction_names(wn)}
    largest = sorted((j for j in demands if demands[j] > 0), key=lambda j: -demands[j])
    for j in largest[:DEMAND_JUNCTIONS]:
        out.append(("demand-step", j, {"demand_change": demands[j]}))
        out.append(("demand-step", j, {"demand_change": demands[j] / 4, "operation_time": 5.0}))
    if largest:
        out.append(("demand-step", largest[0], {"demand_change": -demands[largest[0]] / 2}))
    return [
        EventScenario(path, kind, asset, duration=duration, solver=solver, **kw)  # type: ignore[arg-type]
        for kind, asset, kw in out
    ]


def asset_nodes(network: NetworkSource) -> dict[str, str]:
    """Junction -> the valve or pump it is an end of."""
    from burstloc import network as netmod

    wn = netmod.as_network(network).model
    junctions = set(netmod.junction_names(wn))
    out: dict[str, str] = {}
    for name in list(wn.valve_name_list) + list(wn.pump_name_list):
        link = wn.get_link(name)
        for node in (link.start_node_name, link.end_node_name):
            if node in junctions:
                out[node] = name
    return out
