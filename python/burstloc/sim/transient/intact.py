"""What a burst's simulation needs of its network before the burst pipe matters, once per process.

Every burst of a sweep needs the same network (read once per process,
:func:`burstloc.network.read_network`; a :class:`~burstloc.network.Network` passed in is not
read at all), its steady state (the flow directions) and its transient-ready model
(:func:`~burstloc.sim.transient.tsnet_ready.transient_model`); none of it depends on the burst
pipe. :func:`intact` makes each once per process and keeps it, keyed by the file's path and
the SHA-256 of its bytes (an edited file is read afresh), for the last :data:`NETWORKS` files;
:class:`IntactNetwork` keeps its steady state per engine and its transient-ready model per
shortest pipe length. A burst's simulation copies the transient-ready model when it splits the
pipe (:func:`burstloc.network.split_pipe` copies): nothing kept is ever changed, and the heads
are bit for bit those of a fresh process.

What WNTR, EPANET and TSNet printed, logged and warned while the file was read or a step was
made is recorded with it and replayed into the caller's
:func:`~burstloc._diagnostics.capture_diagnostics` block each time it is used again
(:func:`burstloc._diagnostics.recording`): a scenario's metadata does not depend on what the
process read or simulated before. A step that fails (a missing file, a steady state EPANET
cannot solve) is not kept: it fails again, naming the problem, for each burst.
"""

from __future__ import annotations

import os
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

from burstloc import network, skeleton
from burstloc._diagnostics import Recording, recording

if TYPE_CHECKING:
    import networkx as nx
    from wntr.network import WaterNetworkModel

    from burstloc.sim.scenarios.scenario import BurstScenario

__all__ = ["NETWORKS", "IntactNetwork", "IntactSteady", "clear", "intact"]

#: Networks kept per process (the most recently used).
NETWORKS = 2

T = TypeVar("T")


@dataclass(frozen=True)
class IntactSteady:
    """A network's steady state at the start (:func:`burstloc.network.steady_state`) and its
    flow-direction graph (:func:`burstloc.network.flow_direction_graph`)."""

    state: network.SteadyState
    graph: nx.MultiDiGraph


def _made(make: Callable[[], T]) -> tuple[T, Recording]:
    """``make()`` and what it printed, logged and warned (which reached the caller too)."""
    with recording() as record:
        value = make()
    return value, record


@dataclass
class IntactNetwork:
    """An INP file's WNTR model (``wn``: never to be changed) and the steps made from it."""

    wn: WaterNetworkModel
    _steps: dict[tuple[Any, ...], tuple[Any, Recording]] = field(default_factory=dict)

    def step(self, key: tuple[Any, ...], make: Callable[[], T]) -> T:
        """``make()`` (a value made from ``wn`` only), made once for this network and ``key``;
        what it warned and printed is passed on each time."""
        if key not in self._steps:
            self._steps[key] = _made(make)
            return self._steps[key][0]  # type: ignore[no-any-return]
        value, record = self._steps[key]
        record.replay()
        return value  # type: ignore[no-any-return]

    def steady(self, engine: str = "PDD") -> IntactSteady:
        """The steady state with ``engine`` and its flow-direction graph (not to be changed).

        Raises:
            NetworkError: EPANET cannot solve it.
            ConfigError: an unknown ``engine``.
        """

        def make() -> IntactSteady:
            state = network.steady_state(self.wn, engine)
            return IntactSteady(state, network.flow_direction_graph(self.wn, state.flows))

        return self.step(("steady", engine), make)

    def transient_ready(
        self, min_pipe_length: float | None
    ) -> tuple[WaterNetworkModel, skeleton.PreparedNetwork | None]:
        """The transient-ready model (not to be changed: split a copy) and its preparation:
        ``wn`` itself without ``min_pipe_length``, else
        :func:`burstloc.skeleton.prepare_transient_model` keeping every junction.

        Raises:
            ConfigError: a bad ``min_pipe_length``.
        """

        def make() -> tuple[WaterNetworkModel, skeleton.PreparedNetwork | None]:
            if min_pipe_length is None:
                return self.wn, None
            prepared = skeleton.prepare_transient_model(
                self.wn, min_pipe_length, keep=network.junction_names(self.wn)
            )
            return prepared.network, prepared

        return self.step(("transient", min_pipe_length), make)

    def transient_model(
        self, scenario: BurstScenario
    ) -> tuple[WaterNetworkModel, str, float, skeleton.PreparedNetwork | None]:
        """:func:`burstloc.sim.transient.tsnet_ready.transient_model` of this network for
        ``scenario``
        (the model not to be changed: split a copy).

        Raises:
            ConfigError: a bad ``min_pipe_length``.
            NetworkError: the scenario's pipe is not a pipe of the network.
        """
        model, prepared = self.transient_ready(scenario.min_pipe_length)
        if prepared is None:
            return model, scenario.pipe, scenario.position, None
        pipe, position = prepared.locate(scenario.pipe, scenario.position)
        return model, pipe, position, prepared


#: (path as given, absolute path, SHA-256) -> the network, most recently used last.
_KEPT: OrderedDict[tuple[str, str, str], IntactNetwork] = OrderedDict()


def clear() -> None:
    """Forget every network kept in this process."""
    _KEPT.clear()


def intact(source: network.NetworkSource) -> IntactNetwork:
    """The network's steps, made once per process (:func:`burstloc.network.read_network` reads
    a file once per process) while the file's bytes are unchanged.

    Raises:
        NetworkError: the file is missing or malformed.
    """
    read = network.as_network(source, diagnostics=True)
    key = (read.path, os.path.abspath(read.path), read.hash)
    kept = _KEPT.get(key)
    if kept is not None:
        _KEPT.move_to_end(key)
        return kept
    kept = _KEPT[key] = IntactNetwork(read.model)
    while len(_KEPT) > NETWORKS:
        _KEPT.popitem(last=False)
    return kept
