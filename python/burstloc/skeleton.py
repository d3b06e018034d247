"""Transient-ready models: no pipe shorter than a length that would dictate TSNet's time step.

TSNet's time step is at most ``min L / (2 a)`` over every pipe (its Courant limit; each pipe
needs two reaches), and the work per simulated second grows with ``1 / dt²`` (more steps,
each over more reaches). Real network models hold short connector pipes: EPANET's Net3 has two
of 0.3 m, a step of 0.13 ms. :func:`prepare_transient_model` returns a copy of the model in
which every pipe is at least ``min_length`` long, so the step is at least
``min_length / (2 a)``, by two documented operations:

1. **Series merge** (as WNTR's ``wntr.morph.skeletonize`` merges pipes in series, but chosen
   by length, not diameter): a short pipe ``P`` (``u``-``m``) whose end ``m`` is a junction
   joining only ``P`` and one other pipe ``Q`` (``m``-``w``) becomes part of ``Q``: one pipe
   ``u``-``w`` named ``Q``, of length ``L_P + L_Q`` (wave travel times along the path are
   kept), with the diameter that keeps the steady head loss of the two pipes at a common flow
   (Hazen-Williams exponent 4.871, Darcy-Weisbach 5 at a fixed friction factor,
   Chezy-Manning 16/3; ``Q``'s roughness) and the minor loss coefficient that keeps their minor
   losses. ``m``'s demand moves to ``u``, at most ``min_length`` away. Only junctions are
   removed, and only those not in ``keep`` (the meters), without an emitter, not named by a
   control; only open pipes without a check valve, not named by a control, are merged; a
   merge that would make a loop or a second link between two nodes is not made.
2. **Lengthening**: a short pipe that cannot be merged (both ends are branch points, tanks,
   reservoirs, pumps, valves or meters) is lengthened to ``min_length``, its diameter widened
   to keep its steady head loss (and its minor loss). The wave then takes ``min_length / a``
   to cross it instead of ``L / a``: at most ``min_length / a`` of delay on a path through
   it. TSNet itself changes every pipe's wave speed to fit its step (up to half a step per
   pipe); this is the same kind of change, made visibly, on the pipes that force it.

Pumps, valves, tanks, reservoirs and kept junctions are never removed. Every original pipe
stays carried by exactly one model pipe (:class:`PipePiece`: which pipe, and which stretch of
it), so a burst on an original pipe is placed in the model (:meth:`PreparedNetwork.locate`) and
a model pipe is reported as the original pipes it carries (:meth:`PreparedNetwork.originals`).

This module works on WNTR models only (no TSNet): a base module, usable from every layer.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from burstloc.exceptions import ConfigError, NetworkError

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

__all__ = [
    "HEADLOSS_EXPONENTS",
    "PipePiece",
    "PreparedNetwork",
    "courant_time_step",
    "prepare_transient_model",
    "shortest_pipe",
]

#: The diameter exponent of each EPANET head loss formula (head loss ∝ L / D^e at a flow).
HEADLOSS_EXPONENTS = {"H-W": 4.871, "D-W": 5.0, "C-M": 16.0 / 3.0}

#: The roughness exponent of each formula (head loss ∝ r^k: Hazen-Williams C^-1.852,
#: Manning n^2; Darcy-Weisbach at a fixed friction factor: 0).
_ROUGHNESS_EXPONENTS = {"H-W": -1.852, "D-W": 0.0, "C-M": 2.0}


@dataclass(frozen=True)
class PipePiece:
    """Where an original pipe is in the prepared model.

    Attributes:
        pipe: the model pipe that carries it.
        start: the fraction of the model pipe's length (from the model pipe's INP start node)
            at which the original pipe's INP start node lies.
        end: the same for the original pipe's end node (``end < start``: the original pipe runs
            the other way).
    """

    pipe: str
    start: float
    end: float

    def at(self, position: float) -> float:
        """The model pipe's fraction at ``position`` (a fraction of the original pipe)."""
        return self.start + position * (self.end - self.start)

    def covers(self, fraction: float) -> bool:
        """Whether the model pipe's ``fraction`` lies on this piece (ends included)."""
        low, high = sorted((self.start, self.end))
        return low - 1e-12 <= fraction <= high + 1e-12


@dataclass(frozen=True)
class PreparedNetwork:
    """A transient-ready copy of a network and how it maps to the original.

    Attributes:
        network: the prepared WNTR model (the original is unchanged).
        pieces: every original pipe's :class:`PipePiece`.
        moved_demands: each removed junction -> the junction that took its demand.
        lengthened: each lengthened model pipe -> its length before lengthening (m).
        min_length: the shortest pipe length asked for (m).
    """

    network: WaterNetworkModel
    pieces: dict[str, PipePiece]
    moved_demands: dict[str, str]
    lengthened: dict[str, float]
    min_length: float

    def locate(self, pipe: str, position: float) -> tuple[str, float]:
        """The model pipe and fraction along it of ``position`` on the original ``pipe``.

        Raises:
            NetworkError: ``pipe`` is not a pipe of the original network.
        """
        piece = self._piece(pipe)
        return piece.pipe, piece.at(position)

    def originals(self, model_pipe: str) -> list[str]:
        """The original pipes ``model_pipe`` carries, in order along it (from its start)."""
        found = [(min(p.start, p.end), o) for o, p in self.pieces.items() if p.pipe == model_pipe]
        return [name for _, name in sorted(found)]

    def original_at(self, model_pipe: str, fraction: float) -> tuple[str, float]:
        """The original pipe at ``fraction`` of ``model_pipe``, and the fraction along it.

        Raises:
            NetworkError: ``model_pipe`` carries no original pipe, or ``fraction`` is outside
                ``[0, 1]``.
        """
        if not 0.0 <= fraction <= 1.0:
            raise NetworkError(f"fraction must be within [0, 1], got {fraction!r}")
        for name in self.originals(model_pipe):
            piece = self.pieces[name]
            if piece.covers(fraction):
                span = piece.end - piece.start
                return name, min(1.0, max(0.0, (fraction - piece.start) / span))
        raise NetworkError(f"model pipe {model_pipe!r} carries no original pipe")

    def wave_speeds(self, speeds: Mapping[str, float]) -> dict[str, float]:
        """The model pipes' wave speeds (m/s) from the original pipes' ``speeds``: a merged
        pipe the one that keeps its pieces' travel time (``1 / sum(share / a)``, the shares of
        its length), a lengthened pipe its original's. Model pipes carrying no original pipe in
        ``speeds`` are left out."""
        slowness: dict[str, float] = {}
        for name, piece in self.pieces.items():
            if name not in speeds:
                continue
            share = abs(piece.end - piece.start)
            slowness[piece.pipe] = slowness.get(piece.pipe, 0.0) + share / speeds[name]
        return {pipe: 1.0 / s for pipe, s in slowness.items() if s > 0}

    def summary(self) -> dict[str, Any]:
        """What was done, as JSON: merged pipes (original -> model pipe), moved demands,
        lengthened pipes (model pipe -> original length, m) and the length asked for."""
        return {
            "min_pipe_length": self.min_length,
            "merged": {o: p.pipe for o, p in sorted(self.pieces.items()) if p.pipe != o},
            "moved_demands": dict(sorted(self.moved_demands.items())),
            "lengthened": dict(sorted(self.lengthened.items())),
        }

    def _piece(self, pipe: str) -> PipePiece:
        try:
            return self.pieces[pipe]
        except KeyError:
            raise NetworkError(
                f"unknown pipe {pipe!r}: not a pipe of the original network"
            ) from None


def shortest_pipe(wn: WaterNetworkModel) -> tuple[str, float]:
    """The shortest pipe of ``wn`` and its length (m).

    Raises:
        NetworkError: the network has no pipe.
    """
    lengths = {p: float(wn.get_link(p).length) for p in wn.pipe_name_list}
    if not lengths:
        raise NetworkError("the network has no pipe")
    name = min(lengths, key=lambda p: (lengths[p], p))
    return name, lengths[name]


def courant_time_step(wn: WaterNetworkModel, wave_speed: float) -> float:
    """TSNet's largest time step for ``wn`` at ``wave_speed`` (m/s): ``min L / (2 a)``."""
    return shortest_pipe(wn)[1] / (2.0 * wave_speed)


def prepare_transient_model(
    wn: WaterNetworkModel, min_length: float, keep: Iterable[str] = ()
) -> PreparedNetwork:
    """A copy of ``wn`` without pipes shorter than ``min_length`` m (module docstring).

    Args:
        wn: the network (left unchanged).
        min_length: the shortest pipe length wanted, m (> 0); TSNet's step is then at least
            ``min_length / (2 a)``.
        keep: junctions that must stay (the meters); pumps, valves, tanks and reservoirs
            always stay.

    Raises:
        ConfigError: ``min_length`` is not a positive number.
        NetworkError: a name in ``keep`` is not a junction, or the head loss formula is unknown.
    """
    if isinstance(min_length, bool) or not isinstance(min_length, (int, float)):
        raise ConfigError(f"min_pipe_length must be a number, got {min_length!r}")
    if not (math.isfinite(min_length) and min_length > 0):
        raise ConfigError(f"min_pipe_length must be > 0 m, got {min_length!r}")
    kept = set(keep)
    unknown = sorted(kept - set(wn.junction_name_list))
    if unknown:
        raise NetworkError(f"kept node(s) {unknown} are not junctions of the network")
    formula = str(wn.options.hydraulic.headloss).upper()
    if formula not in HEADLOSS_EXPONENTS:
        raise NetworkError(f"unknown head loss formula {formula!r}")
    model = copy.deepcopy(wn)
    merger = _Merger(model, float(min_length), kept, formula)
    merger.merge_all()
    lengthened = merger.lengthen_rest()
    return PreparedNetwork(model, merger.pieces, merger.moved, lengthened, float(min_length))


class _Merger:
    """The series merges of :func:`prepare_transient_model`, shortest pipe first."""

    def __init__(self, wn: WaterNetworkModel, min_length: float, keep: set[str], formula: str):
        self.wn = wn
        self.min_length = min_length
        self.keep = keep
        self.exponent = HEADLOSS_EXPONENTS[formula]
        self.rough_exponent = _ROUGHNESS_EXPONENTS[formula]
        self.pieces = {p: PipePiece(p, 0.0, 1.0) for p in wn.pipe_name_list}
        self.moved: dict[str, str] = {}
        self.controlled = {obj.name for _, c in wn.controls() for obj in c.requires()}

    def merge_all(self) -> None:
        while True:
            short = sorted(
                (float(self.wn.get_link(p).length), p)
                for p in self.wn.pipe_name_list
                if self.wn.get_link(p).length < self.min_length
            )
            for _, name in short:
                if self._merge_one(name):
                    break
            else:
                return

    def lengthen_rest(self) -> dict[str, float]:
        lengthened: dict[str, float] = {}
        for name in self.wn.pipe_name_list:
            pipe = self.wn.get_link(name)
            if pipe.length < self.min_length:
                lengthened[name] = float(pipe.length)
                scale = (self.min_length / pipe.length) ** (1.0 / self.exponent)
                pipe.minor_loss = pipe.minor_loss * scale**4
                pipe.diameter = pipe.diameter * scale
                pipe.length = self.min_length
        return lengthened

    def _mergeable_pipe(self, name: str) -> bool:
        pipe = self.wn.get_link(name)
        return (
            pipe.link_type == "Pipe"
            and not pipe.check_valve
            and str(pipe.initial_status).upper() == "OPEN"
            and name not in self.controlled
        )

    def _partner(self, short: str, middle: str) -> str | None:
        """The other pipe at ``middle`` if ``short`` can merge into it there."""
        node = self.wn.get_node(middle)
        if node.node_type != "Junction" or middle in self.keep or middle in self.controlled:
            return None
        if node.emitter_coefficient or getattr(node, "leak", False):
            return None
        links = self.wn.get_links_for_node(middle)
        if len(links) != 2:
            return None
        other = links[0] if links[1] == short else links[1]
        if other == short or not self._mergeable_pipe(other):
            return None
        pipe = self.wn.get_link(short)
        far = pipe.end_node_name if pipe.start_node_name == middle else pipe.start_node_name
        partner = self.wn.get_link(other)
        beyond = (
            partner.end_node_name if partner.start_node_name == middle else partner.start_node_name
        )
        if far == beyond or set(self.wn.get_links_for_node(far)) & set(
            self.wn.get_links_for_node(beyond)
        ):
            return None  # a loop, or a second link between the same two nodes
        moves_demand = any(d.base_value for d in node.demand_timeseries_list)
        if moves_demand and self.wn.get_node(far).node_type != "Junction":
            return None
        return other

    def _merge_one(self, short: str) -> bool:
        if not self._mergeable_pipe(short):
            return False
        pipe = self.wn.get_link(short)
        options = []
        for middle in (pipe.start_node_name, pipe.end_node_name):
            other = self._partner(short, middle)
            if other is not None:
                ratio = abs(math.log(self.wn.get_link(other).diameter / pipe.diameter))
                options.append((ratio, -self.wn.get_link(other).length, other, middle))
        if not options:
            return False
        _, _, other, middle = min(options)
        self._merge(short, other, middle)
        return True

    def _merge(self, short_name: str, long_name: str, middle: str) -> None:
        wn = self.wn
        short, long = wn.get_link(short_name), wn.get_link(long_name)
        far = short.end_node_name if short.start_node_name == middle else short.start_node_name
        start = far if long.start_node_name == middle else long.start_node_name
        end = far if long.end_node_name == middle else long.end_node_name
        total = float(short.length + long.length)
        # positions (m from the new pipe's start) of each old pipe's INP start and end node
        at_middle = float(short.length if start == far else long.length)
        position = {start: 0.0, end: total, middle: at_middle}
        remap = {
            name: (position[link.start_node_name] / total, position[link.end_node_name] / total)
            for name, link in ((short_name, short), (long_name, long))
        }
        resistance = sum(self._resistance(p) for p in (short, long))
        rough = float(long.roughness)
        rough_factor = rough**self.rough_exponent if self.rough_exponent else 1.0
        diameter = (total * rough_factor / resistance) ** (1.0 / self.exponent)
        minor = diameter**4 * sum(p.minor_loss / p.diameter**4 for p in (short, long))
        node = wn.get_node(middle)
        demands = [(d.base_value, d.pattern_name, d.category) for d in node.demand_timeseries_list]
        wn.remove_link(short_name)
        wn.remove_link(long_name)
        wn.remove_node(middle)
        if any(base for base, _, _ in demands):
            target = wn.get_node(far)
            for base, pattern, category in demands:
                if base:
                    target.add_demand(base, pattern, category)
            self.moved[middle] = far
            for removed, to in list(self.moved.items()):
                if to == middle:
                    self.moved[removed] = far
        wn.add_pipe(long_name, start, end, total, diameter, rough, minor, "OPEN", False)
        for original, piece in self.pieces.items():
            if piece.pipe in remap:
                a, b = remap[piece.pipe]
                self.pieces[original] = PipePiece(
                    long_name, a + piece.start * (b - a), a + piece.end * (b - a)
                )

    def _resistance(self, pipe: Any) -> float:
        """The pipe's head loss factor ``L r^k / D^e`` (head loss at a flow, up to a constant)."""
        rough = float(pipe.roughness) ** self.rough_exponent if self.rough_exponent else 1.0
        return float(pipe.length) * rough / float(pipe.diameter) ** self.exponent
