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
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import asdict, dataclass
from typing import Any

from burstloc import network, skeleton
from burstloc.network import _fresh_name
from burstloc.sim.scenario import BurstScenario

__all__ = [
    "Connector",
    "TsnetPreparation",
    "add_connectors",
    "prepare_for_tsnet",
    "transient_model",
]


@dataclass(frozen=True)
class Connector:
    """A connector pipe: ``link`` (a pump or valve) now ends at ``junction`` instead of
    ``node``, and ``pipe`` (``length`` m, ``diameter`` m) joins ``junction`` to ``node``."""

    link: str
    node: str
    junction: str
    pipe: str
    length: float
    diameter: float

    def as_metadata(self) -> dict[str, Any]:
        """The record stored in a simulation's metadata."""
        return asdict(self)


def _needs_connector(wn: Any, link_name: str, node_name: str) -> bool:
    node = wn.get_node(node_name)
    if node.node_type != "Junction":
        return False  # a reservoir or tank is a boundary TSNet handles
    others = [name for name in wn.get_links_for_node(node_name) if name != link_name]
    return len(others) != 1 or wn.get_link(others[0]).link_type != "Pipe"


def _template(wn: Any, node_name: str) -> Any:
    """The widest pipe at the node, else the widest pipe of the network."""
    at_node = [wn.get_link(n) for n in wn.get_links_for_node(node_name)]
    pipes = [link for link in at_node if link.link_type == "Pipe"]
    pool = pipes or [pipe for _, pipe in wn.pipes()]
    return max(pool, key=lambda pipe: pipe.diameter)


def add_connectors(wn: Any) -> list[Connector]:
    """Add a connector pipe wherever a pump or valve of ``wn`` (changed in place) does not meet
    a single pipe at a junction end; return what was added (empty: nothing needed)."""
    length = min(float(pipe.length) for _, pipe in wn.pipes())
    added: list[Connector] = []
    links = [name for name, _ in wn.pumps()] + [name for name, _ in wn.valves()]
    for link_name in links:
        for side in ("start", "end"):
            link = wn.get_link(link_name)
            node_name = getattr(link, f"{side}_node_name")
            if not _needs_connector(wn, link_name, node_name):
                continue
            node = wn.get_node(node_name)
            template = _template(wn, node_name)
            junction = _fresh_name(f"{link_name}_{side[0].upper()}", set(wn.node_name_list), "CJ")
            pipe = _fresh_name(f"{link_name}_{side[0].upper()}P", set(wn.link_name_list), "CP")
            wn.add_junction(
                junction, base_demand=0.0, elevation=node.elevation, coordinates=node.coordinates
            )
            setattr(link, f"{side}_node", wn.get_node(junction))
            start, end = (node_name, junction) if side == "start" else (junction, node_name)
            wn.add_pipe(
                pipe,
                start,
                end,
                length=length,
                diameter=template.diameter,
                roughness=template.roughness,
                minor_loss=0.0,
            )
            added.append(
                Connector(link_name, node_name, junction, pipe, length, float(template.diameter))
            )
    return added


@dataclass(frozen=True)
class TsnetPreparation:
    """What :func:`prepare_for_tsnet` changed: the closed links removed, the connectors added."""

    removed_closed_links: list[str]
    connectors: list[Connector]

    def as_metadata(self) -> dict[str, Any]:
        """The records stored in a simulation's metadata."""
        return {
            "removed_closed_links": list(self.removed_closed_links),
            "connectors": [c.as_metadata() for c in self.connectors],
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


def prepare_for_tsnet(wn: Any, keep: Collection[str] = ()) -> TsnetPreparation:
    """Make ``wn`` (changed in place) a network TSNet simulates as EPANET solves it: closed
    pipes and pumps removed except ``keep`` (:func:`remove_closed_links`), then connectors
    (:func:`add_connectors`)."""
    removed = remove_closed_links(wn, keep)
    return TsnetPreparation(removed, add_connectors(wn))


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
