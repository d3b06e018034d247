"""A burst's size as engineers give it: a flow in L/s, and the emitter coefficient it takes.

TSNet's burst is an emitter at the junction that splits the pipe: it draws ``q = C sqrt(p)``
(m³/s, ``p`` the pressure head there in m, ``C`` the coefficient in m³/s per m^½; TSNet's
exponent is 0.5 whatever the INP's emitter exponent, and WNTR reads every INP in SI units, so a
coefficient means the same on a network in GPM as in LPS). A flow ``Q`` therefore maps to
``C = Q / sqrt(p0)`` at the burst point's pressure before the burst, ``p0``: the network's
steady heads at the pipe's end nodes interpolated linearly along it (before the burst the flow
is the same all along the pipe, so its head loss is linear in length) minus the split
junction's elevation (:func:`~burstloc.sim.signatures.epanet_inplace.split_elevation`). ``Q`` is
the burst's *nominal* flow: once it opens the pressure there falls, and it draws less.

:func:`burst_sizes` gives each pipe's pressure, coefficient and nominal flow, for a coefficient
or a flow, and with ``check`` the lowest junction pressure of the network once the burst has
opened (EPANET's pressure-driven steady state with the emitter, one project edited in place:
:class:`~burstloc.sim.signatures.epanet_inplace.InPlaceSplitter`): a burst that takes a
junction below zero pressure is larger than the network can feed.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from burstloc.constants import BURST_FLOW, BURST_SHARE
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.network import Network
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import BurstScenario

__all__ = [
    "DEFAULT_BURST",
    "BurstFlow",
    "BurstSize",
    "burst_point_pressure",
    "burst_sizes",
    "coeff_for_flow",
    "describe_sizes",
    "sized_scenarios",
    "with_size",
]


@dataclass(frozen=True)
class BurstSize:
    """One burst's size: ``pipe`` split at ``position``; ``pressure`` (m) at the burst point
    before the burst; the emitter ``coeff`` (m³/s per m^½) and the ``flow`` (m³/s) it draws at
    that pressure; with a check, the lowest junction pressure (m) once it has opened, that
    junction, and how many junctions it takes below zero pressure that were at or above it
    before (else ``None``)."""

    pipe: str
    position: float
    pressure: float
    coeff: float
    flow: float
    lowest_pressure: float | None = None
    lowest_junction: str | None = None
    below_zero: int | None = None

    @property
    def flow_lps(self) -> float:
        """The nominal flow in L/s."""
        return 1000.0 * self.flow


@dataclass(frozen=True)
class BurstFlow:
    """Bursts sized by their flow: ``flow`` (m³/s) on every network, or ``share`` of the
    network's demand (the junctions' demand at the steady state the burst opens from; 0.05 is
    5 %), at most ``cap`` (m³/s) when given. Exactly one of ``flow`` and ``share``.

    Raises:
        ConfigError: neither or both of ``flow`` and ``share``, a flow or cap that is not a
            positive number, a share not in (0, 1].
    """

    flow: float | None = None
    share: float | None = None
    cap: float | None = None

    def __post_init__(self) -> None:
        if (self.flow is None) == (self.share is None):
            raise ConfigError("size the burst by a flow or by a share of the demand: one of them")
        for name, value in (("flow", self.flow), ("cap", self.cap)):
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ConfigError(f"the burst {name} must be a positive number, got {value}")
        if self.share is not None and not (math.isfinite(self.share) and 0 < self.share <= 1):
            raise ConfigError(
                f"the burst's share of the demand must be in (0, 1], got {self.share}"
            )

    def of(self, demand: float) -> float:
        """The flow (m³/s) on a network whose junctions draw ``demand`` (m³/s).

        Raises:
            ConfigError: sized by a share of a network that draws no water.
        """
        if self.flow is not None:
            return self.flow
        if not demand > 0:
            raise ConfigError(
                "the network draws no water at its steady state: size the burst by its flow "
                "(--burst-flow) or its coefficient (--burst-coeff)"
            )
        flow = float(self.share) * demand  # type: ignore[arg-type]
        return flow if self.cap is None else min(flow, self.cap)

    def describe(self) -> str:
        """How the flow is chosen, in words (printed and recorded)."""
        if self.flow is not None:
            return f"{1000 * self.flow:g} L/s"
        cap = "" if self.cap is None else f", at most {1000 * self.cap:g} L/s"
        return f"{100 * float(self.share):g} % of the network's demand{cap}"  # type: ignore[arg-type]


DEFAULT_BURST = BurstFlow(share=BURST_SHARE, cap=BURST_FLOW)
"""The commands' default burst: :data:`~burstloc.constants.BURST_SHARE` of the network's demand,
at most :data:`~burstloc.constants.BURST_FLOW`."""


def coeff_for_flow(flow: float, pressure: float) -> float:
    """The emitter coefficient (m³/s per m^½) that draws ``flow`` (m³/s) at ``pressure`` (m).

    Raises:
        ConfigError: a flow that is not a positive finite number, or a pressure that is not
            positive (no flow comes out of a pipe without pressure).
    """
    if not (math.isfinite(flow) and flow > 0):
        raise ConfigError(f"the burst flow must be a positive number, got {flow}")
    if not (math.isfinite(pressure) and pressure > 0):
        raise ConfigError(
            f"the burst point has no positive pressure ({pressure:.3g} m) to size a burst by flow"
        )
    return flow / math.sqrt(pressure)


def burst_point_pressure(wn: Any, heads: dict[str, float], pipe: str, position: float) -> float:
    """The pressure head (m) at ``position`` along ``pipe`` (fraction from its INP start node)
    before the burst, from the steady ``heads`` of the WNTR model ``wn`` (module docstring).

    Raises:
        NetworkError: ``pipe`` is not a pipe of ``wn``.
        ConfigError: ``position`` not strictly between 0 and 1.
    """
    from burstloc.sim.signatures.epanet_inplace import split_elevation

    if pipe not in set(wn.pipe_name_list):
        raise NetworkError(f"unknown pipe {pipe!r}")
    if not 0.0 < position < 1.0:
        raise ConfigError(f"position must be strictly between 0 and 1, got {position!r}")
    link = wn.get_link(pipe)
    start, end = heads[link.start_node_name], heads[link.end_node_name]
    return start + (end - start) * position - split_elevation(link, position)


def burst_sizes(
    wn: Any,
    pipes: Sequence[str],
    position: float,
    *,
    coeff: float | None = None,
    flow: float | None = None,
    check: bool = False,
    engine: str = "PDD",
) -> list[BurstSize]:
    """Each pipe's burst at ``position``, sized by the emitter coefficient ``coeff`` (m³/s per
    m^½) or by the nominal ``flow`` (m³/s), exactly one of them; with ``check`` the lowest
    junction pressure once it has opened (module docstring). ``wn``: the WNTR model.

    Raises:
        ConfigError: neither or both of ``coeff`` and ``flow``, a bad value, a burst point
            without pressure to size by flow.
        NetworkError: an unknown pipe; EPANET cannot solve the network.
    """
    from burstloc._diagnostics import capture_diagnostics
    from burstloc.network import steady_state
    from burstloc.sim.signatures.epanet_inplace import InPlaceSplitter

    if (coeff is None) == (flow is None):
        raise ConfigError("size the burst by its emitter coefficient or by its flow: one of them")
    if coeff is not None and not (math.isfinite(coeff) and coeff > 0):
        raise ConfigError(f"the burst coefficient must be a positive number, got {coeff}")
    heads = steady_state(wn, engine).heads
    sizes = []
    for pipe in pipes:
        pressure = burst_point_pressure(wn, heads, pipe, position)
        c = coeff_for_flow(flow, pressure) if flow is not None else float(coeff)  # type: ignore[arg-type]
        sizes.append(_size(pipe, position, pressure, c))
    if not check:
        return sizes
    junctions = list(wn.junction_name_list)
    elevation = np.array([wn.get_node(j).elevation for j in junctions])
    before = np.array([heads[j] for j in junctions]) - elevation >= 0.0
    checked = []
    with capture_diagnostics(), InPlaceSplitter(wn, engine) as splitter:
        for size in sizes:
            pressures = splitter.split_heads(size.pipe, position, size.coeff, junctions) - elevation
            low = int(pressures.argmin())
            checked.append(
                replace(
                    size,
                    lowest_pressure=float(pressures[low]),
                    lowest_junction=junctions[low],
                    below_zero=int(np.count_nonzero(before & (pressures < 0.0))),
                )
            )
    return checked


def sized_scenarios(
    scenarios: Sequence[BurstScenario],
    flow: float | BurstFlow | None = None,
    network: Network | None = None,
) -> tuple[list[BurstScenario], list[BurstSize]]:
    """The bursts ``scenarios`` with their sizes: with ``flow`` (m³/s, or a :class:`BurstFlow`:
    a share of each network's demand) each one's coefficient set to draw that flow at its burst
    point's pressure before it opens; without, their own coefficients and the flows those draw
    there. The network's steady state is solved once per network file (its engine the first
    scenario's), on ``network`` (the loaded network the scenarios burst) or, for a scenario of
    another file, that file read once (:func:`~burstloc.network.as_network`).

    Raises:
        ConfigError: a bad flow, a burst point without pressure to size by flow, a share of a
            network that draws no water.
        NetworkError: an unknown pipe; EPANET cannot solve the network.
    """
    from burstloc.network import as_network, steady_state

    sizing = BurstFlow(flow=flow) if isinstance(flow, (int, float)) else flow
    out: list[BurstScenario] = []
    sizes: list[BurstSize] = []
    solved: dict[tuple[str, str], tuple[Any, dict[str, float], float]] = {}
    for s in scenarios:
        if (s.network, s.engine) not in solved:
            if network is not None and os.fspath(network.path) == os.fspath(s.network):
                wn = network.model
            else:
                wn = as_network(s.network).model
            state = steady_state(wn, s.engine)
            demand = sum(q for q in state.demands.values() if q > 0)
            solved[(s.network, s.engine)] = (wn, state.heads, demand)
        wn, heads, demand = solved[(s.network, s.engine)]
        pressure = burst_point_pressure(wn, heads, s.pipe, s.position)
        coeff = s.burst_coeff if sizing is None else coeff_for_flow(sizing.of(demand), pressure)
        sizes.append(_size(s.pipe, s.position, pressure, coeff))
        out.append(s if sizing is None else replace(s, burst_coeff=coeff))
    return out, sizes


def _size(pipe: str, position: float, pressure: float, coeff: float) -> BurstSize:
    """The size of a burst of coefficient ``coeff`` at a point of ``pressure`` (m)."""
    return BurstSize(pipe, position, pressure, coeff, coeff * math.sqrt(max(pressure, 0.0)))


def with_size(
    result: ScenarioResult, size: BurstSize, sizing: BurstFlow | None = None
) -> ScenarioResult:
    """``result`` with its burst's nominal flow (``burst_flow_lps``, L/s), the burst point's
    pressure before it opened (``burst_pressure_m``, m) and, sized by a :class:`BurstFlow`, how
    the flow was chosen (``burst_sizing``) in its metadata."""
    meta = {
        **result.metadata,
        "burst_flow_lps": round(size.flow_lps, 6),
        "burst_pressure_m": round(size.pressure, 6),
    }
    if sizing is not None:
        meta["burst_sizing"] = sizing.describe()
    return replace(result, metadata=meta)


def describe_sizes(sizes: Sequence[BurstSize], sizing: BurstFlow | None = None) -> str:
    """What the bursts draw, in one line: one burst's flow, pressure and coefficient, or the
    range of several, and how the flow was chosen when ``sizing`` is given (``burstloc
    simulate`` prints it)."""
    chosen = "" if sizing is None or sizing.share is None else f" ({sizing.describe()})"
    if len(sizes) == 1:
        (size,) = sizes
        return (
            f"burst on {size.pipe}: {size.flow_lps:.3g} L/s{chosen} at the burst point's "
            f"{size.pressure:.1f} m of pressure head before it opens (emitter coefficient "
            f"{size.coeff:.3g} m^3/s/m^0.5)"
        )
    flows = sorted(s.flow_lps for s in sizes)
    coeffs = sorted(s.coeff for s in sizes)
    return (
        f"{len(sizes)} bursts: {flows[0]:.3g}-{flows[-1]:.3g} L/s (median "
        f"{flows[len(flows) // 2]:.3g}){chosen} at their burst points' pressure before they "
        f"open (emitter coefficients {coeffs[0]:.3g}-{coeffs[-1]:.3g} m^3/s/m^0.5)"
    )
