"""A network as TSNet needs it: closed pipes and pumps out, a single pipe at each side of a pump
or valve.

TSNet 0.3.1 simulates a pipe whose status is Closed as an open one (a boundary valve modelled as
a closed pipe; Net3's pump bypass 330), and a pump that is not being operated by its curve
whatever its status (Net3's Lake pump 10, Closed at the start): the water EPANET kept out flows
from the first time step. :func:`prepare_for_tsnet` removes them first (with any control that
names them, and a reservoir or tank left with no link): EPANET gives them no flow. An event's
own asset is kept (TSNet's pump start-up opens a closed pump itself). Closed valves TSNet
models as closed.

TSNet 0.3.1 models a pump or a valve as the boundary between the pipe before it and the pipe
after it (``tsnet.network.topology``): at each end it takes *one* adjacent link. A pump that
discharges into a junction where several pipes meet (Anytown's pump 82 into junction 20, three
pipes) or a valve next to another valve is then simulated with the wrong pipes attached, and
the "steady" network jumps by metres at the first time step
(:class:`~burstloc.exceptions.UnsteadyStartError`).

:func:`add_connectors` (then called by :func:`prepare_for_tsnet`) mends this: where a pump's
or valve's end node is a junction that does not join exactly one other link, a pipe, the link
is moved to a new junction (same elevation, no demand) joined to the old node by a short
connector pipe. The connector is
as long as the network's shortest pipe, so TSNet's time step does not shrink, and copies the
widest pipe at the node (diameter and roughness), so its head loss is small; EPANET's steady
state is recomputed with it, so the transient starts steady. Reservoirs and tanks at a pump's
or valve's end need nothing. The meters stay the original junctions; the simulation's metadata
lists the connectors (``connectors``) and the removed links (``removed_closed_links``).

TSNet holds a tank's or reservoir's head only where it ends a single pipe (``rev_end``); one
joined by several links it solves as a junction (``add_leakage``): a tank then takes a
pressure-dependent "demand", its EPANET net inflow scaled by the square root of its depth (the
head of a 15 m wide tank moved 6.3 m within 9 s of a small network's burst), and a reservoir, which
has no elevation, stops TSNet ("'Reservoir' object has no attribute 'elevation'").
:func:`add_connectors` gives such a tank or reservoir one connector pipe first: its links move
to a new junction (the tank's elevation; a reservoir's lowest neighbour's) at the connector's
far end. (No network shipped or fetched has one.)

A supply junction (a negative demand at the start: water entering, as Net2's pump station at
junction 1) is, for EPANET, a fixed inflow. TSNet 0.3.1 scales every junction's demand with the
square root of its pressure during the transient (``Q = k sqrt(p)``, ``k`` from the steady
state), a negative ``k`` included: the inflow then falls as the pressure falls, a negative
resistance that reflects every pressure wave reaching it *amplified* (by ``(R + B) / (R - B)``,
``R = 2 sqrt(p) / |k|``, ``B = a / (g A)`` the pipe's impedance; 2.6 at Net2's junction 1). Any
burst then grows without bound: on Net2 junction 1's pressure fell until TSNet's dead-end
equation had no real root ("no real solution (dead end)"), after which TSNet holds its head
constant, downstream heads swung by over 100 m and most junctions were reported at negative
pressure. :func:`add_supply_boundaries` (called by :func:`prepare_for_tsnet`) gives TSNet
EPANET's meaning instead: the demands move to a new junction (same elevation) joined to the
supply junction by an open valve (TCV, no loss, as wide as the widest pipe there). TSNet takes
a valve with nothing beyond it as the network's edge and holds its steady flow (``valve_end``):
a fixed inflow. The supply junction stays a meter (its head is what is measured), EPANET's
steady state is unchanged (the valve loses no head), and the metadata lists the supplies
(``supply_boundaries``).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

from burstloc import network, skeleton
from burstloc.network import _fresh_name
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet_elements import PowerPumpCurve, settle_pumps_and_check_valves

#: EPANET's trials for the steady state TSNet starts from (see :func:`prepare_for_tsnet`).
STEADY_TRIALS = 1000
#: EPANET's convergence criterion (relative flow change) for that state at most (its default).
STEADY_ACCURACY = 0.001

__all__ = [
    "Connector",
    "SupplyBoundary",
    "TsnetPreparation",
    "add_connectors",
    "add_supply_boundaries",
    "pipe_speeds",
    "prepare_for_tsnet",
    "supply_junctions",
    "transient_model",
    "turn_dead_ends_from_sources",
]


@dataclass(frozen=True)
class Connector:
    """A connector pipe: ``link`` (a pump or valve; or, where ``node`` is a tank or reservoir,
    ``link`` is ``node`` and stands for all its links) now ends at ``junction`` instead of
    ``node``, and ``pipe`` (``length`` m, ``diameter`` m) joins ``junction`` to ``node``."""

    link: str
    node: str
    junction: str
    pipe: str
    length: float
    diameter: float


def _needs_connector(
    wn: Any, link_name: str, node_name: str, edges: Collection[str], side: str
) -> bool:
    node = wn.get_node(node_name)
    if node.node_type != "Junction" or node_name in edges:
        return False  # a reservoir, a tank or a supply's source is a boundary TSNet handles
    others = [name for name in wn.get_links_for_node(node_name) if name != link_name]
    if len(others) != 1 or wn.get_link(others[0]).link_type != "Pipe":
        return True
    # TSNet's valve and pump equations take the pipe at the link's start to end there and the
    # pipe at its end to start there (pipe -> valve -> pipe); a pipe the other way round is
    # solved with the wrong characteristic (L-TOWN's PRV-2: 0.5 m before any burst; KY13's
    # Pump-3: 62 m); and they have no demand at the link's nodes (L-TOWN's PRV-3 at n229: 0.27 m)
    if any(demand.base_value != 0 for demand in node.demand_timeseries_list):
        return True
    pipe = wn.get_link(others[0])
    return bool(
        pipe.end_node_name != node_name if side == "start" else pipe.start_node_name != node_name
    )


def _template(wn: Any, node_name: str) -> Any:
    """The widest pipe at the node, else the widest pipe of the network."""
    at_node = [wn.get_link(n) for n in wn.get_links_for_node(node_name)]
    pipes = [link for link in at_node if link.link_type == "Pipe"]
    pool = pipes or [pipe for _, pipe in wn.pipes()]
    return max(pool, key=lambda pipe: pipe.diameter)


def _elevation(wn: Any, node_name: str) -> float:
    """A node's elevation; a reservoir's (it has none): the lowest of its neighbours'."""
    node = wn.get_node(node_name)
    if node.node_type != "Reservoir":
        return float(node.elevation)
    ends: set[str] = set()
    for name in wn.get_links_for_node(node_name):
        link = wn.get_link(name)
        ends.update((link.start_node_name, link.end_node_name))
    levels = [float(wn.get_node(n).elevation) for n in ends if hasattr(wn.get_node(n), "elevation")]
    return min(levels, default=0.0)


def _connect(wn: Any, node_name: str, moved: list[str], name: str, length: float) -> Connector:
    """Move the ends of the links ``moved`` at ``node_name`` to a new junction (``name``, no
    demand) joined to the node by a connector pipe (``length``, the widest pipe at the node)."""
    node = wn.get_node(node_name)
    template = _template(wn, node_name)
    junction = _fresh_name(name, set(wn.node_name_list), "CJ")
    pipe = _fresh_name(f"{name}P", set(wn.link_name_list), "CP")
    wn.add_junction(
        junction,
        base_demand=0.0,
        elevation=_elevation(wn, node_name),
        coordinates=node.coordinates,
    )
    starts = []
    for link_name in moved:
        link = wn.get_link(link_name)
        for side in ("start", "end"):
            if getattr(link, f"{side}_node_name") == node_name:
                setattr(link, f"{side}_node", wn.get_node(junction))
                starts.append(side == "start")
    start, end = (node_name, junction) if all(starts) else (junction, node_name)
    wn.add_pipe(
        pipe,
        start,
        end,
        length=length,
        diameter=template.diameter,
        roughness=template.roughness,
        minor_loss=0.0,
    )
    link = moved[0] if len(moved) == 1 else node_name
    return Connector(link, node_name, junction, pipe, length, float(template.diameter))


def add_connectors(wn: Any, edges: Collection[str] = ()) -> list[Connector]:
    """Add a connector pipe wherever a tank or reservoir of ``wn`` (changed in place) is joined
    by more than one link (its links then meet at the connector's far end), then wherever a pump
    or valve does not meet a single pipe at a junction end (a pipe ending at its start,
    starting at its end, at a junction without demand), except at the junctions ``edges`` (a
    supply's source, the network's edge on purpose); return what was added (empty: nothing
    needed)."""
    length = min(float(pipe.length) for _, pipe in wn.pipes())
    added: list[Connector] = []
    for name in [*wn.tank_name_list, *wn.reservoir_name_list]:
        links = list(wn.get_links_for_node(name))
        if len(links) > 1:
            added.append(_connect(wn, name, links, f"{name}_C", length))
    for link_name in [name for name, _ in wn.pumps()] + [name for name, _ in wn.valves()]:
        for side in ("start", "end"):
            node_name = getattr(wn.get_link(link_name), f"{side}_node_name")
            if _needs_connector(wn, link_name, node_name, edges, side):
                name = f"{link_name}_{side[0].upper()}"
                added.append(_connect(wn, node_name, [link_name], name, length))
    return added


@dataclass(frozen=True)
class SupplyBoundary:
    """A supply junction given to TSNet as a fixed inflow: ``inflow`` (m³/s, EPANET's at the
    start) enters ``junction`` through ``valve`` (an open TCV) from ``source`` (a new junction,
    same elevation), which now holds the junction's demands."""

    junction: str
    source: str
    valve: str
    inflow: float


def supply_junctions(wn: Any) -> dict[str, float]:
    """The junctions of ``wn`` with a negative demand at time 0 (patterns and the demand
    multiplier applied, as EPANET's steady state at the start): name -> inflow (m³/s, > 0)."""
    multiplier = wn.options.hydraulic.demand_multiplier
    found = {}
    for name, junction in wn.junctions():
        demand = float(junction.demand_timeseries_list.at(0.0, multiplier=multiplier))
        if demand < 0.0 and wn.get_links_for_node(name):
            found[name] = -demand
    return found


def add_supply_boundaries(wn: Any, keep: Collection[str] = ()) -> list[SupplyBoundary]:
    """Give every supply junction of ``wn`` (changed in place; :func:`supply_junctions`) except
    those in ``keep`` a fixed inflow TSNet holds: its demands move to a new junction joined to
    it by an open valve (see the module's description); return what was added."""
    added = []
    for name, inflow in supply_junctions(wn).items():
        if name in keep:
            continue
        junction = wn.get_node(name)
        source = _fresh_name(f"{name}_S", set(wn.node_name_list), "SUPPLY")
        valve = _fresh_name(f"{name}_SV", set(wn.link_name_list), "SUPPLYV")
        wn.add_junction(
            source, base_demand=0.0, elevation=junction.elevation, coordinates=junction.coordinates
        )
        demands = wn.get_node(source).demand_timeseries_list
        demands.clear()
        for demand in junction.demand_timeseries_list:
            demands.append((demand.base_value, demand.pattern, demand.category))
        junction.demand_timeseries_list.clear()
        wn.add_valve(
            valve,
            source,
            name,
            diameter=_template(wn, name).diameter,
            valve_type="TCV",
            minor_loss=0.0,
            initial_setting=0.0,
            initial_status="Open",
        )
        added.append(SupplyBoundary(name, source, valve, inflow))
    return added


@dataclass(frozen=True)
class TsnetPreparation:
    """What :func:`prepare_for_tsnet` changed: the closed links removed, the supplies made
    fixed inflows, the connectors added, the power pumps given curves, the pumps and check-valve
    pipes at rest made closed valves."""

    removed_closed_links: list[str]
    connectors: list[Connector]
    supply_boundaries: list[SupplyBoundary]
    power_pumps: list[PowerPumpCurve] = field(default_factory=list)
    closed_at_rest: list[str] = field(default_factory=list)
    turned_pipes: list[str] = field(default_factory=list)

    def as_metadata(self) -> dict[str, Any]:
        """The records stored in a simulation's metadata."""
        return {
            "removed_closed_links": list(self.removed_closed_links),
            "connectors": [asdict(c) for c in self.connectors],
            "supply_boundaries": [asdict(s) for s in self.supply_boundaries],
            **({"power_pumps": [asdict(p) for p in self.power_pumps]} if self.power_pumps else {}),
            **({"closed_at_rest": list(self.closed_at_rest)} if self.closed_at_rest else {}),
            **({"turned_pipes": list(self.turned_pipes)} if self.turned_pipes else {}),
        }


def remove_closed_links(wn: Any, keep: Collection[str] = ()) -> list[str]:
    """Remove the pipes and pumps of ``wn`` (changed in place) whose initial status is Closed,
    except those in ``keep``, with any control that names them and any reservoir or tank they
    leave unconnected; return the links' names."""
    closed = [
        name
        for name, link in [*wn.pipes(), *wn.pumps()]
        if link.initial_status.name == "Closed" and name not in keep
    ]
    for name in closed:
        link = wn.get_link(name)
        ends = (link.start_node_name, link.end_node_name)
        wn.remove_link(name, with_control=True)
        for node in ends:
            if wn.get_node(node).node_type != "Junction" and not wn.get_links_for_node(node):
                if wn.options.quality.trace_node == node:  # water quality plays no part here
                    wn.options.quality.parameter = "NONE"
                    wn.options.quality.trace_node = None
                wn.remove_node(node, with_control=True)
    return closed


def prepare_for_tsnet(wn: Any, keep: Collection[str] = (), engine: str = "PDD") -> TsnetPreparation:
    """Make ``wn`` (changed in place) a network TSNet simulates as EPANET solves it: EPANET's
    steady state solved to at least :data:`STEADY_TRIALS` trials and an accuracy of
    :data:`STEADY_ACCURACY` (a model's looser options left KY15's pumps and valves switching
    when its 100 trials ran out, and exnet-3's accuracy of 0.1 left flows metres of head off
    balance: TSNet's transient started from that state and moved), closed
    pipes and pumps removed except ``keep`` (:func:`remove_closed_links`), the pumps and
    check-valve pipes EPANET's steady state (solved with ``engine``) gives no flow made closed
    valves, and pumps
    given by their power made head pumps at their operating point
    (:func:`burstloc.sim.transient.tsnet_elements.settle_pumps_and_check_valves`), supply junctions
    except
    ``keep`` made fixed inflows (:func:`add_supply_boundaries`), then connectors
    (:func:`add_connectors`), and pipes from a dead end to a tank or reservoir turned around
    (:func:`turn_dead_ends_from_sources`)."""
    hydraulic = wn.options.hydraulic
    hydraulic.trials = max(int(hydraulic.trials), STEADY_TRIALS)
    hydraulic.accuracy = min(float(hydraulic.accuracy), STEADY_ACCURACY)
    removed = remove_closed_links(wn, keep)
    at_rest, pumps = settle_pumps_and_check_valves(wn, keep, engine)
    supplies = add_supply_boundaries(wn, keep)
    connectors = add_connectors(wn, edges=[s.source for s in supplies])
    turned = turn_dead_ends_from_sources(wn)
    return TsnetPreparation(removed, connectors, supplies, pumps, at_rest, turned)


def turn_dead_ends_from_sources(wn: Any) -> list[str]:
    """Turn around (``wn`` changed in place) every pipe that runs from a dead end (a junction
    joining only it) to a tank or reservoir, and return their names: TSNet solves such a pipe
    only from the tank or reservoir to the dead end ("a Tank at its end with nothing at its
    start": Richmond_skeleton's pipe 1832, whose pump at junction 753 is closed). EPANET's
    steady state is the same, its flow's sign turned."""
    turned = []
    for name, pipe in wn.pipes():
        start, end = pipe.start_node, pipe.end_node
        if (
            not pipe.check_valve
            and start.node_type == "Junction"
            and end.node_type in ("Tank", "Reservoir")
            and list(wn.get_links_for_node(start.name)) == [name]
        ):
            pipe.start_node, pipe.end_node = end, start
            turned.append(name)
    return turned


def transient_model(
    wn: Any, scenario: BurstScenario
) -> tuple[Any, str, float, skeleton.PreparedNetwork | None]:
    """The model TSNet simulates for ``scenario`` and the burst's pipe and position in it:
    ``wn`` itself, or with ``scenario.min_pipe_length`` its transient-ready model keeping every
    junction (:func:`burstloc.skeleton.prepare_transient_model`), and that preparation."""
    if scenario.min_pipe_length is None:
        return wn, scenario.pipe, scenario.position, None
    prepared = skeleton.prepare_transient_model(
        wn, scenario.min_pipe_length, keep=network.junction_names(wn)
    )
    pipe, position = prepared.locate(scenario.pipe, scenario.position)
    return prepared.network, pipe, position, prepared


def pipe_speeds(
    scenario: BurstScenario,
    original: Any,
    pipes: Iterable[str],
    prepared: skeleton.PreparedNetwork | None,
    aliases: Mapping[str, str],
) -> dict[str, float]:
    """The wave speed (m/s) of each of the simulated model's ``pipes`` whose speed is not the
    scenario's: ``scenario.wave_speeds`` of the ``original`` network's pipes, carried through
    the transient-ready model (``prepared``: merged pipes keep their travel time) and the split
    burst pipe (``aliases``: a half -> the pipe it was cut from)."""
    if scenario.wave_speeds is None:
        return {}
    given = scenario.wave_speeds.of(original, scenario.wave_speed)
    by_model = given if prepared is None else prepared.wave_speeds(given)
    speeds = {p: by_model.get(aliases.get(p, p)) for p in pipes}
    return {p: a for p, a in speeds.items() if a is not None and a != scenario.wave_speed}
